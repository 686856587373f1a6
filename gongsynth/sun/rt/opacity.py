r"""
Continuum and line opacity in LTE (cgs), as numba point functions and numpy wrappers.

Continuum at wavelength λ (per cm, stimulated emission included):

* H⁻ bound-free and free-free: John (1988, A&A 193, 189) fits, with the H⁻
  population from the Saha equation (binding 0.754 eV);
* H I bound-free from levels n = 3..8 (hydrogenic cross-section, Gaunt factor 1;
  levels above 8 by Gray's integral) and H I free-free (Gaunt factor 1);
* Thomson scattering on electrons and Rayleigh scattering on H I (Dalgarno's
  fit as in Kurucz's ATLAS); scattering is counted as absorption with the LTE
  source function (S = B).

Metal bound-free opacity is left out (< 1 % at 617–677 nm in the photosphere).
The continuum is evaluated at the line's own rest wavelength.

Line (any `~gongsynth.sun.rt.atomic_data.LineData`): the lower-level
population from Saha–Boltzmann with the element's partition functions, the
integrated cross-section π e²/(m_e c²) λ₀² f, Doppler width from temperature
and microturbulence, Voigt damping from radiative, van der Waals and quadratic
Stark widths.  Van der Waals: Unsöld's formula exactly as RH and Lightweaver
compute it, or, where the line has Anstee–Barklem–O'Mara data (σ, α), the
ABO full width per perturber 2 (4/π)^{α/2} Γ(2 − α/2) v₀ σ (v̄/v₀)^{1−α}
(v₀ = 10 km/s, v̄ the mean H–atom relative speed; Anstee & O'Mara 1995,
Barklem, Piskunov & O'Mara 2000), times n_H I + 0.42 n_He as Barklem's
recipe adds helium.  `line_constants` packs what the kernels need into one array.
`tabulated_opacity` gives the same quantities from T and P_gas by interpolation in a
per-line (ln T, ln P) table (`opacity_table`), the equation of state included.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from gongsynth.sun.rt.atomic_data import ABUNDANCE, IONISATION_EV, PF_TEMPERATURE, get_line
from gongsynth.sun.rt.eos import solve_state
from gongsynth.threads import run_chunks

__all__ = ["line_constants", "point_opacity", "column_opacity", "continuum_opacity", "line_opacity",
           "opacity_table", "tabulated_opacity",
           "planck", "LC_SIZE"]

_H = 6.62607015e-27
_C = 2.99792458e10
_K = 1.380649e-16
_EV_K = 11604.518
_SAHA_HALF = 2.4146830e15            # (2π m_e k / h²)^{3/2}
_PI_RE = 8.85280e-13                 # π e² / (m_e c²), cm
_SQRT_PI = math.sqrt(math.pi)
_AMU = 1.66053907e-24

#: Length of the array returned by `line_constants`.
LC_SIZE = 16
_PF_LNT = np.linspace(math.log(1000.0), math.log(20000.0), 300)


def line_constants(line=None):
    """
    A line's constants in one float64 array (the kernels' input).

    Parameters
    ----------
    line : str or `~gongsynth.sun.rt.atomic_data.LineData`, optional
        A line name of `~gongsynth.sun.rt.atomic_data.LINES` or atomic data
        (default ``"Ni I 676.8"``).

    Returns
    -------
    constants : `numpy.ndarray`
        (LC_SIZE,): λ₀ (cm), gf/g_l·(π e²/m_e c²)λ₀², g_l, E_l (eV), abundance,
        χ (eV), mass (g), γ_rad, van der Waals and Stark coefficients, Landé g,
        λ₀ (nm), the van der Waals temperature exponent (0.3 Unsöld, (1 − α)/2 ABO).
    pf_table : `numpy.ndarray`
        (2, 300) log U of the neutral and the ion on a uniform ln T grid 1000–20 000 K.
    """
    line = get_line(line)
    lam = line.wavelength_nm * 1e-7
    # Unsöld van der Waals (RH / Lightweaver form, SI constants, result for n_HI in cm⁻³).
    q, eps4, a0, hp, ryd = 1.60217663e-19, 4 * math.pi * 8.8541878128e-12, 5.29177211e-11, 6.62607015e-34, \
        2.1798724e-18
    e_cont = line.ion_ground_cm * 1.98644586e-23
    e_up = line.upper_energy_cm * 1.98644586e-23
    e_lo = line.lower_energy_cm * 1.98644586e-23
    delta_r = (ryd / (e_cont - e_up)) ** 2 - (ryd / (e_cont - e_lo)) ** 2
    c625 = (2.5 * q * q / eps4 * 7.42e-41 / eps4 * 2 * math.pi * a0 ** 2 / hp * delta_r) ** 0.4
    mass = line.mass_amu
    vrel_h = (8.0 * 1.380649e-23 / (math.pi * 1.66053907e-27 * mass) * (1.0 + mass / 1.007975)) ** 0.3
    vrel_he = (8.0 * 1.380649e-23 / (math.pi * 1.66053907e-27 * mass) * (1.0 + mass / 4.002602)) ** 0.3
    vdw = 8.08 * line.vdw_enhancement * (vrel_h + ABUNDANCE["He"] * vrel_he) * c625 * 1e6   # n in cm⁻³
    vdw_exponent = 0.3
    if line.vdw_sigma is not None:
        # ABO: full width per H atom, SI → cm³ s⁻¹; v̄ = (8kT/πμ)^½ with μ the H–atom reduced mass.
        alpha = line.vdw_alpha
        v0 = 1e4
        vbar_t = 8.0 * 1.380649e-23 / (math.pi * 1.66053907e-27) * (1.0 / 1.007975 + 1.0 / mass)  # v̄²/T
        vdw = (2.0 * (4.0 / math.pi) ** (alpha / 2) * math.gamma(2.0 - alpha / 2) * v0
               * line.vdw_sigma * a0 ** 2 * (vbar_t ** 0.5 / v0) ** (1.0 - alpha)
               * (1.0 + 0.42 * ABUNDANCE["He"]) * 1e6)
        vdw_exponent = 0.5 * (1.0 - alpha)
    # Quadratic Stark (RH / Lightweaver).
    e_ryd = ryd / (1.0 + 9.1093837e-31 / (mass * 1.66053907e-27))
    n_l = math.sqrt(e_ryd / (e_cont - e_lo))
    n_u = math.sqrt(e_ryd / (e_cont - e_up))
    c4 = q * q / eps4 * a0 * (2 * math.pi * a0 ** 2 / hp) / 18.0 * (
        (n_u * (5 * n_u ** 2 + 1)) ** 2 - (n_l * (5 * n_l ** 2 + 1)) ** 2)
    cstark = 11.37 * (line.stark_enhancement * abs(c4)) ** (2.0 / 3.0)
    cm = (1.0 + mass / (9.1093837e-31 / 1.66053907e-27)) ** (1 / 6) + (1.0 + mass / 28.0) ** (1 / 6)
    stark = cstark * cm * (8.0 * 1.380649e-23 / (math.pi * 1.66053907e-27 * mass)) ** (1 / 6) * 1e6
    chi = IONISATION_EV[line.element] if line.partition_levels is None else line.ionisation_ev
    const = np.zeros(LC_SIZE)
    const[:13] = (lam, _PI_RE * lam * lam * line.oscillator_strength, line.g_lower, line.lower_energy_ev,
                  ABUNDANCE[line.element], chi, mass * _AMU, line.gamma_rad, vdw, stark, line.lande,
                  line.wavelength_nm, vdw_exponent)
    u1, u2 = line.partition_functions(np.exp(_PF_LNT))
    return const, np.ascontiguousarray(np.log(np.stack([u1, u2])))


@nb.njit(cache=True, inline="always")
def planck(lam_cm, t):
    """Planck function B_λ (erg s⁻¹ cm⁻² sr⁻¹ cm⁻¹) at λ (cm) and T (K)."""
    return 2.0 * _H * _C * _C / lam_cm ** 5 / math.expm1(_H * _C / (lam_cm * _K * t))


@nb.njit(cache=True)
def _continuum(lam_cm, t, ne, nh):
    """Continuum opacity (cm⁻¹) and the H I density at one point."""
    kt_ev = t / _EV_K
    t15 = t * math.sqrt(t)
    phi_h = _SAHA_HALF * t15 * math.exp(-13.5984 / kt_ev)        # U_HII/U_HI · 2 = 1
    n_hi = nh * ne / (ne + phi_h)
    n_p = nh - n_hi
    lam_um = lam_cm * 1e4
    stim = -math.expm1(-_H * _C / (lam_cm * _K * t))
    # H- bound-free (John 1988).
    kappa = 0.0
    if lam_um < 1.6419:
        x = 1.0 / lam_um - 1.0 / 1.6419
        s = math.sqrt(x)
        series = 152.519 + s * (49.534 + s * (-118.858 + s * (92.536 + s * (-34.194 + s * 4.982))))
        sigma = 1e-18 * lam_um ** 3 * x * s * series
        n_hm = n_hi * ne * 1.0353e-16 / t15 * math.exp(0.754195 / kt_ev)
        kappa += sigma * n_hm * stim
    # H- free-free (John 1988, λ > 0.3645 µm), per H I atom per unit electron pressure.
    theta = 5040.0 / t
    ff = 0.0
    a_ = (0.0, 2483.346, -3449.889, 2200.040, -696.271, 88.283)
    b_ = (0.0, 285.827, -1158.382, 2427.719, -1841.400, 444.517)
    c_ = (0.0, -2054.291, 8746.523, -13651.105, 8624.970, -1863.864)
    d_ = (0.0, 2827.776, -11485.632, 16755.524, -10051.530, 2095.288)
    e_ = (0.0, -1341.537, 5303.609, -7510.494, 4400.067, -901.788)
    f_ = (0.0, 208.952, -812.939, 1132.738, -655.020, 132.985)
    il = 1.0 / lam_um
    pw = theta                                  # θ^((n + 2)/2)
    st = math.sqrt(theta)
    for n in range(6):
        ff += pw * (lam_um * lam_um * a_[n] + b_[n] + il * (c_[n] + il * (d_[n] + il * (e_[n] + il * f_[n]))))
        pw *= st
    kappa += 1e-29 * ff * n_hi * ne * _K * t
    # H I bound-free from n = 3..8 plus the integral above 8 (Gray 2005, eq. 8.8), Gaunt factor 1.
    nu = _C / lam_cm
    e_ph = _H * nu / 1.602176634e-12
    sigma0 = 2.815e29 / nu ** 3
    hbf = 0.0
    for n in range(1, 9):
        if 13.5984 / (n * n) < e_ph:
            hbf += sigma0 / n ** 5 * 2.0 * n * n / 2.0 * math.exp(-13.5984 * (1.0 - 1.0 / (n * n)) / kt_ev)
    hbf += sigma0 * kt_ev / (2.0 * 13.5984) * (math.exp(-13.5984 * (1.0 - 1.0 / 81.0) / kt_ev)
                                               - math.exp(-13.5984 / kt_ev))
    kappa += hbf * n_hi * stim
    # H I free-free.
    kappa += 3.69e8 / (nu ** 3 * math.sqrt(t)) * ne * n_p * stim
    # Thomson and Rayleigh (Dalgarno) scattering.
    lam_a = lam_cm * 1e8
    l2 = 1.0 / (lam_a * lam_a)
    sig_r = l2 * l2 * (5.799e-13 + l2 * (1.422e-6 + l2 * 2.784))
    kappa += 6.6524587e-25 * ne + sig_r * n_hi
    return kappa, n_hi


@nb.njit(cache=True)
def point_opacity(t, ne, nh, vturb, const, pf_table):
    """
    Continuum opacity, line strength, Doppler width, damping and Planck function at one point.

    Parameters
    ----------
    t, ne, nh, vturb : float
        Temperature (K), electron and hydrogen densities (cm⁻³), microturbulence (cm/s).
    const, pf_table : `numpy.ndarray`
        From `line_constants`.

    Returns
    -------
    tuple of float
        κ_c (cm⁻¹), κ_L (cm⁻¹, line-centre opacity of an undamped line: multiply
        by H(a, v)), Δλ_D (cm), a, B_λ(λ₀).
    """
    lam = const[0]
    kc, n_hi = _continuum(lam, t, ne, nh)
    kt_ev = t / _EV_K
    x = (math.log(min(max(t, 1000.0), 20000.0)) - _PF_LNT[0]) / (_PF_LNT[1] - _PF_LNT[0])
    i = min(max(int(x), 0), _PF_LNT.size - 2)
    w = x - i
    ln_u1 = pf_table[0, i] * (1 - w) + pf_table[0, i + 1] * w
    ln_u2 = pf_table[1, i] * (1 - w) + pf_table[1, i + 1] * w
    phi = 2.0 * _SAHA_HALF * t * math.sqrt(t) * math.exp(ln_u2 - ln_u1 - const[5] / kt_ev)
    n_el = nh * const[4]
    n_neutral = n_el * ne / (ne + phi)
    n_low = n_neutral * const[2] * math.exp(-const[3] / kt_ev - ln_u1)
    stim = -math.expm1(-_H * _C / (lam * _K * t))
    lnt = math.log(t)
    gamma = const[7] + const[8] * math.exp(const[12] * lnt) * n_hi + const[9] * math.exp(lnt / 6.0) * ne
    return _finish(t, vturb, const, kc, const[1] * n_low * stim / _SQRT_PI, gamma, planck(lam, t))


@nb.njit(cache=True, inline="always")
def _finish(t, vturb, const, kc, k_dl, gamma, source):
    """`point_opacity`'s result from its microturbulence-free parts: κ_c, K = κ_L Δλ_D, Γ (s⁻¹), B_λ."""
    lam = const[0]
    dlam = lam / _C * math.sqrt(2.0 * _K * t / const[6] + vturb * vturb)
    dnu = _C * dlam / (lam * lam)
    return kc, k_dl / dlam, dlam, gamma / (4.0 * math.pi * dnu), source


def continuum_opacity(wavelength_nm, temperature, electron_density, hydrogen_density):
    """
    Continuum opacity (cm⁻¹) at one wavelength for arrays of points.

    Parameters
    ----------
    wavelength_nm : float
        Wavelength (nm), e.g. 500 for the τ₅₀₀ scale or 676.78.
    temperature, electron_density, hydrogen_density : array_like
        K, cm⁻³, cm⁻³.

    Returns
    -------
    `numpy.ndarray`
        κ_c in cm⁻¹.

    Examples
    --------
    >>> k = continuum_opacity(500.0, 6420.0, 6.6e13, 1.17e17)    # FAL-C near tau_500 = 1
    >>> 1e-8 < float(k) < 1e-6
    True
    """
    t, ne, nh = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in
                                      (temperature, electron_density, hydrogen_density)))
    out = np.empty(t.shape)
    flat = [np.ascontiguousarray(a.reshape(-1)) for a in (t, ne, nh)]
    run_chunks(_continuum_many, t.size, float(wavelength_nm) * 1e-7, *flat, out.reshape(-1), min_chunk=1024)
    return out


@nb.njit(cache=True, nogil=True)
def _continuum_many(start, stop, lam, t, ne, nh, out):
    for p in range(start, stop):
        out[p] = _continuum(lam, t[p], ne[p], nh[p])[0]


def line_opacity(temperature, electron_density, hydrogen_density, microturbulence=0.0, line=None):
    """
    Line-centre opacity scale, Doppler width and damping of a line for arrays of points.

    Parameters
    ----------
    temperature, electron_density, hydrogen_density : array_like
        K, cm⁻³, cm⁻³.
    microturbulence : array_like, optional
        km/s.
    line : str or `~gongsynth.sun.rt.atomic_data.LineData`, optional
        Default ``"Ni I 676.8"``.

    Returns
    -------
    dict
        ``kappa_continuum`` and ``kappa_line`` (cm⁻¹; the line's opacity is
        κ_L H(a, v)), ``doppler_width`` (pm), ``damping``, ``planck`` (cgs per cm).
    """
    const, pf = line_constants(line)
    arrays = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in
                                   (temperature, electron_density, hydrogen_density, microturbulence)))
    shape = arrays[0].shape
    flat = [np.ascontiguousarray(a.reshape(1, -1)) for a in arrays]
    out = np.empty((5, 1, flat[0].size))
    column_opacity(flat[0], flat[1], flat[2], flat[3] * 1e5, const, pf, *out)
    out = out.reshape((5,) + shape)
    return {"kappa_continuum": out[0], "kappa_line": out[1], "doppler_width": out[2] * 1e10,
            "damping": out[3], "planck": out[4]}


def column_opacity(temp, ne, nh, vturb, const, pf_table, kc, kl, dop, damping, source):
    """
    Fill (ncol, nz) arrays with `point_opacity` at every point (vturb in cm/s).

    Parameters
    ----------
    temp, ne, nh, vturb : (ncol, nz) float64
        K, cm⁻³, cm⁻³, cm/s.
    const, pf_table : `numpy.ndarray`
        From `line_constants`.
    kc, kl, dop, damping, source : (ncol, nz) float64
        Output: κ_c, κ_L (cm⁻¹), Δλ_D (cm), a, B_λ.
    """
    run_chunks(_column_opacity_rows, temp.shape[0], temp, ne, nh, vturb, const, pf_table, kc, kl, dop,
               damping, source)


@nb.njit(cache=True, nogil=True)
def _column_opacity_rows(start, stop, temp, ne, nh, vturb, const, pf_table, kc, kl, dop, damping, source):
    """Columns ``start`` to ``stop`` of `column_opacity`."""
    nz = temp.shape[1]
    for p in range(start, stop):
        for k in range(nz):
            r = point_opacity(temp[p, k], ne[p, k], nh[p, k], vturb[p, k], const, pf_table)
            kc[p, k], kl[p, k], dop[p, k], damping[p, k], source[p, k] = r


#: `tabulated_opacity`'s grid: ln T steps of at most 1/`_TAB_SUB` of the line's partition-function grid
#: (`_PF_LNT`), with a node on each node of that grid and of the equation of state's partition functions
#: (`PF_TEMPERATURE`), over `_TAB_T` K; ln P every `_TAB_DLNP` over `_TAB_P` dyn cm⁻².
_TAB_SUB = 4
_TAB_T = (2000.0, 20000.0)
_TAB_P = (1e-2, 1e7)
_TAB_DLNP = 0.15
_TABLES = {}


def _tab_temperature_grid():
    """
    `opacity_table`'s ln T nodes, each cell's cubic stencil and Lagrange denominators, and the lookup.

    Between two kinks (a segment) the nodes are uniform, at least 4 of them; a cell's stencil is the 4
    nodes of its own segment nearest to it.  ``cell[b]`` is the last node at or below the b-th point of
    a uniform grid of step h (≤ every node spacing), from which the cell of any ln T is a few steps away.
    """
    h0 = _PF_LNT[1] - _PF_LNT[0]
    lo, hi = math.log(_TAB_T[0]), math.log(_TAB_T[1])
    kinks = np.union1d(_PF_LNT[(_PF_LNT > lo) & (_PF_LNT < hi)],
                       np.log(PF_TEMPERATURE[(PF_TEMPERATURE > _TAB_T[0]) & (PF_TEMPERATURE < _TAB_T[1])]))
    ends = np.concatenate([[lo], kinks[np.diff(np.concatenate([[lo], kinks])) > 1e-9], [hi]])
    nodes, start = [], []
    for s0, s1 in zip(ends[:-1], ends[1:]):
        n = max(3, math.ceil((s1 - s0) / h0 * _TAB_SUB))
        first = len(nodes)
        nodes.extend(s0 + (s1 - s0) * np.arange(n) / n)
        start.extend(min(max(first + c - 1, first), first + n - 3) for c in range(n))
    nodes.append(hi)
    nodes, start = np.array(nodes), np.array(start, dtype=np.int64)
    st = nodes[start[:, None] + np.arange(4)]
    den = np.ones((start.size, 4))
    for m in range(4):
        for n in range(4):
            if n != m:
                den[:, m] *= st[:, m] - st[:, n]
    h = np.diff(nodes).min()
    base = lo + h * np.arange(math.ceil((hi - lo) / h) + 1)
    cell = np.minimum(np.searchsorted(nodes, base, side="right") - 1, start.size - 1).astype(np.int64)
    return nodes, start, 1.0 / den, cell, lo, 1.0 / h


def opacity_table(const, pf_table):
    """
    A line's `point_opacity` parts without microturbulence on a (ln T, ln P_gas) grid, built once per process.

    The tabulated quantities (κ_c, κ_L Δλ_D, the damping rate Γ and B_λ, as logarithms) depend on the
    state (T, P) only, through n_e of `~gongsynth.sun.rt.eos.electron_density`.  They are smooth
    functions of ln T and ln P except at the nodes of the partition functions' piecewise-linear
    interpolation, in ln T: the line's (`line_constants`) and the equation of state's
    (`~gongsynth.sun.rt.atomic_data.PF_TEMPERATURE`).  The ln T grid has a node on each of them and
    interpolates cubically (Lagrange) inside each smooth piece only; in ln P it is cubic too
    (0.15 steps).  Interpolation error < 1e-5 of each quantity (tests/test_rt_speedpaths.py).

    Parameters
    ----------
    const, pf_table : `numpy.ndarray`
        From `line_constants`.

    Returns
    -------
    tuple
        The ln T grid of `_tab_temperature_grid`, (ln P₀, 1/Δ ln P, P nodes) and the (nT, nP, 4) table.
    """
    key = (const.tobytes(), pf_table.tobytes())
    if key not in _TABLES:
        tgrid = _tab_temperature_grid()
        nodes = tgrid[0]
        lnp = math.log(_TAB_P[0]) + _TAB_DLNP * np.arange(-1, math.ceil(math.log(_TAB_P[1] / _TAB_P[0])
                                                                          / _TAB_DLNP) + 3)
        t, p = (np.ascontiguousarray(a.reshape(1, -1)) for a in
                np.meshgrid(np.exp(nodes), np.exp(lnp), indexing="ij"))
        st = solve_state(t, gas_pressure=p)
        out = np.empty((5,) + t.shape)
        column_opacity(t, st["electron_density"], st["hydrogen_density"], np.zeros_like(t), const, pf_table,
                       *out)
        kc, kl, dlam, a, src = (x.reshape(nodes.size, lnp.size) for x in out)
        tab = np.log(np.stack([kc, kl * dlam, a * 4.0 * math.pi * _C * dlam / (const[0] ** 2), src], axis=-1))
        pgrid = np.array([lnp[0], 1.0 / _TAB_DLNP, lnp.size])
        _TABLES[key] = tgrid + (pgrid, np.ascontiguousarray(tab))
    return _TABLES[key]


def tabulated_opacity(temp, pressure, vturb, const, pf_table, kc, kl, dop, damping, source):
    """
    `column_opacity` from T and P_gas by interpolation in `opacity_table` (direct outside the table).

    The same quantities as `column_opacity` with n_e and n_H from
    `~gongsynth.sun.rt.eos.solve_state` (T, P), within 1e-5 of each; points outside the
    table's 2000–20 000 K, 10⁻²–10⁷ dyn cm⁻² are computed directly.

    Parameters
    ----------
    temp, pressure, vturb : (ncol, nz) float64
        K, dyn cm⁻², cm/s.
    const, pf_table : `numpy.ndarray`
        From `line_constants`.
    kc, kl, dop, damping, source : (ncol, nz) float64
        Output: κ_c, κ_L (cm⁻¹), Δλ_D (cm), a, B_λ.
    """
    miss = np.empty(temp.shape, dtype=np.bool_)
    run_chunks(_tabulated_rows, temp.shape[0], temp, pressure, vturb, const, *opacity_table(const, pf_table),
               kc, kl, dop, damping, source, miss)
    if miss.any():
        t, p = temp[miss].reshape(1, -1), pressure[miss].reshape(1, -1)
        st = solve_state(t, gas_pressure=p)
        out = np.empty((5,) + t.shape)
        column_opacity(t, st["electron_density"], st["hydrogen_density"], vturb[miss].reshape(1, -1), const,
                       pf_table, *out)
        for dst, src in zip((kc, kl, dop, damping, source), out):
            dst[miss] = src[0]


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _tabulated_rows(start, stop, temp, pressure, vturb, const, nodes, stencil, inv_den, cell, lt0, inv_h,
                    pgrid, tab, kc, kl, dop, damping, source, miss):
    """Columns ``start`` to ``stop`` of `tabulated_opacity` (``miss`` marks the points outside the table)."""
    lp0, inv_hp, npres = pgrid[0], pgrid[1], pgrid[2]
    lt_hi = nodes[nodes.size - 1]
    nz = temp.shape[1]
    v = np.empty(4)
    for p in range(start, stop):
        for k in range(nz):
            t = temp[p, k]
            lt = math.log(t)
            fp = (math.log(pressure[p, k]) - lp0) * inv_hp
            out = not (lt0 <= lt < lt_hi and 1.0 <= fp < npres - 2.0)        # NaN too
            miss[p, k] = out
            if out:
                continue
            j = cell[int((lt - lt0) * inv_h)]
            while lt >= nodes[j + 1]:
                j += 1
            s = stencil[j]
            d0, d1, d2, d3 = lt - nodes[s], lt - nodes[s + 1], lt - nodes[s + 2], lt - nodes[s + 3]
            t0 = d1 * d2 * d3 * inv_den[j, 0]
            t1 = d0 * d2 * d3 * inv_den[j, 1]
            t2 = d0 * d1 * d3 * inv_den[j, 2]
            t3 = d0 * d1 * d2 * inv_den[j, 3]
            i = int(fp)
            w = fp - i
            # Cubic Lagrange weights of the pressure nodes i - 1 .. i + 2.
            wa = w * (w - 1.0)
            wb = (w + 1.0) * (w - 2.0)
            c0 = -wa * (w - 2.0) * (1.0 / 6.0)
            c1 = wb * (w - 1.0) * 0.5
            c2 = -wb * w * 0.5
            c3 = wa * (w + 1.0) * (1.0 / 6.0)
            for q in range(4):
                acc = 0.0
                for m, tm in ((0, t0), (1, t1), (2, t2), (3, t3)):
                    acc += tm * (c0 * tab[s + m, i - 1, q] + c1 * tab[s + m, i, q] + c2 * tab[s + m, i + 1, q]
                                 + c3 * tab[s + m, i + 2, q])
                v[q] = math.exp(acc)
            kc[p, k], kl[p, k], dop[p, k], damping[p, k], source[p, k] = _finish(t, vturb[p, k], const, v[0],
                                                                                 v[1], v[2], v[3])
