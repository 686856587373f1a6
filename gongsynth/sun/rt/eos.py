r"""
Equation of state: electron density, hydrogen density, gas pressure and density in LTE.

The gas is the elements of `~gongsynth.sun.rt.atomic_data.ELEMENTS` in the
Asplund et al. (2009) proportions, each nucleus a free particle, each element
ionised once at most (Saha equation with the Kurucz partition functions):

.. math:: \frac{n_{\rm II}\, n_e}{n_{\rm I}} = \Phi(T) =
          2\,\frac{U_{\rm II}}{U_{\rm I}}\Big(\frac{2\pi m_e kT}{h^2}\Big)^{3/2} e^{-\chi/kT},
          \qquad n_e = n_{\rm H}\sum_m A_m \frac{\Phi_m}{n_e + \Phi_m}

solved per point by a safeguarded Newton iteration in ln n_e.  Left out (and so
documented): H⁻ and H₂ (H₂ binds < 1 % of hydrogen above 4000 K; H⁻ holds ~1e-7
of it), second ionisations (relevant only above ~10⁴ K, where Ni I has no
opacity), and the turbulent pressure.  Gas pressure is P = (n_H ΣA_m + n_e) kT.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from gongsynth.sun.rt.atomic_data import (
    ABUNDANCE,
    ATOMIC_MASS,
    ELEMENTS,
    IONISATION_EV,
    LOG_PARTITION,
    PF_CAP,
    PF_TEMPERATURE,
)
from gongsynth.threads import run_chunks

__all__ = ["K_BOLTZMANN", "AMU", "MEAN_MASS_PER_H", "PARTICLES_PER_H", "saha_phi", "electron_density",
           "solve_state", "hydrogen_ionised_fraction"]

#: Boltzmann constant (erg/K) and atomic mass unit (g), CODATA 2018.
K_BOLTZMANN = 1.380649e-16
AMU = 1.66053907e-24
_EV_K = 11604.518          # K per eV
_SAHA = 4.829389e15        # 2 (2π m_e k / h²)^{3/2}, cm⁻³ K^{-3/2}

#: Mass per hydrogen nucleus in amu, Σ A_m m_m.
MEAN_MASS_PER_H = float(sum(ABUNDANCE[e] * ATOMIC_MASS[e] for e in ELEMENTS))
#: Nuclei per hydrogen nucleus, Σ A_m.
PARTICLES_PER_H = float(sum(ABUNDANCE[e] for e in ELEMENTS))

_CHUNK = 1 << 20


def _log_u(species, ln_t):
    cap = math.log(PF_CAP.get(species, 20000.0))
    return np.interp(np.minimum(ln_t, cap), np.log(PF_TEMPERATURE), np.asarray(LOG_PARTITION[species]))


def saha_phi(element, temperature):
    """
    Saha factor Φ = n_II n_e / n_I of an element (cm⁻³).

    Parameters
    ----------
    element : str
        Element symbol, e.g. ``"Ni"``.
    temperature : `numpy.ndarray`
        Temperature (K).

    Returns
    -------
    `numpy.ndarray`
        Φ(T) in cm⁻³.

    Examples
    --------
    >>> f"{float(saha_phi('H', 6000.0)):.3e}"          # n_p n_e / n_HI at 6000 K
    '4.246e+09'
    """
    t = np.maximum(np.asarray(temperature, dtype=np.float64), 1000.0)
    ln_t = np.log(t)
    ratio = 10.0 ** (_log_u(element + "II", ln_t) - _log_u(element + "I", ln_t))
    return _SAHA * ratio * t ** 1.5 * np.exp(-IONISATION_EV[element] * _EV_K / t)


def hydrogen_ionised_fraction(temperature, electron_density):
    """
    n_p / n_H from the Saha equation at the given electron density.

    Parameters
    ----------
    temperature : `numpy.ndarray`
        K.
    electron_density : `numpy.ndarray`
        cm⁻³.

    Returns
    -------
    `numpy.ndarray`
    """
    phi = saha_phi("H", temperature)
    return phi / (phi + np.asarray(electron_density, dtype=np.float64))


@nb.njit(cache=True, nogil=True)
def _solve_ne(start, stop, phi, abund, nh_or_ntot, from_pressure, sum_a, out):
    """Newton in ln n_e, bracketed, at points ``start`` to ``stop``; phi (nel, n)."""
    nel = phi.shape[0]
    for p in range(start, stop):
        q = nh_or_ntot[p]
        hi = q if from_pressure else q * sum_a
        lo = hi * 1e-30
        x = math.log(hi * 1e-3)
        for _ in range(200):
            ne = math.exp(x)
            nh = (q - ne) / sum_a if from_pressure else q
            s = 0.0
            ds = 0.0
            for m in range(nel):
                den = ne + phi[m, p]
                s += abund[m] * phi[m, p] / den
                ds += abund[m] * phi[m, p] / (den * den)
            f = ne - nh * s
            if f > 0.0:
                hi = min(hi, ne)
            else:
                lo = max(lo, ne)
            fp = 1.0 + nh * ds + (s / sum_a if from_pressure else 0.0)
            step = f / (fp * ne)
            xn = x - step
            if not (math.log(lo) < xn < math.log(hi)):
                xn = 0.5 * (math.log(lo) + math.log(hi))
            if abs(xn - x) < 1e-11:
                x = xn
                break
            x = xn
        out[p] = math.exp(x)


def _saha_coefficients():
    """
    Coefficients of ln Φ_m = a + b ln T − c/T per element and `PF_TEMPERATURE` interval (`saha_phi`).

    `saha_phi` interpolates log U linearly in ln T between the table's nodes (held at the caps and
    above 20 000 K), so on each interval ln Φ is exactly that; the nodes are all multiples of 500 K, so
    the interval of T is ``_PHI_BIN[int(T / 500)]``.  Returns (a, b) of shape (intervals, elements),
    c of shape (elements,) and the bin table.
    """
    nodes = PF_TEMPERATURE[PF_TEMPERATURE <= 20000.0]
    ln_nodes = np.log(nodes)
    a = np.empty((nodes.size, len(ELEMENTS)))
    b = np.empty((nodes.size, len(ELEMENTS)))
    for m, el in enumerate(ELEMENTS):
        v = (_log_u(el + "II", ln_nodes) - _log_u(el + "I", ln_nodes)) * math.log(10.0)
        slope = np.diff(v) / np.diff(ln_nodes)
        b[:-1, m] = slope + 1.5
        a[:-1, m] = v[:-1] - slope * ln_nodes[:-1] + math.log(_SAHA)
        b[-1, m] = 1.5                                  # above 20 000 K: U held constant
        a[-1, m] = v[-1] + math.log(_SAHA)
    c = np.array([IONISATION_EV[el] * _EV_K for el in ELEMENTS])
    bins = np.searchsorted(nodes, 500.0 * np.arange(int(nodes[-1] // 500) + 1), side="right") - 1
    return a, b, c, bins.astype(np.int64)


_PHI_A, _PHI_B, _PHI_C, _PHI_BIN = _saha_coefficients()


@nb.njit(cache=True, inline="always")
def _saha_point(t, abund, phi_a, phi_b, phi_c, phi_bin, phi):
    """`saha_phi` of every element at one temperature into ``phi`` (the closed form per interval)."""
    t = max(t, 1000.0)
    k = int(min(t, 20000.0) * (1.0 / 500.0))
    i = phi_bin[min(k, phi_bin.size - 1)]
    lt = math.log(t)
    it = 1.0 / t
    for m in range(abund.size):
        phi[m] = math.exp(phi_a[i, m] + phi_b[i, m] * lt - phi_c[m] * it)


@nb.njit(cache=True, inline="always")
def _newton_ne(phi, abund, q, from_pressure, sum_a, x):
    """
    `_solve_ne`'s safeguarded Newton in ln n_e at one point, from the start ``x``; returns n_e.

    The bracket is kept in ln n_e (the current point exactly, not log(exp(x))) and a step below the
    tolerance ends the iteration before the bracket test: near the root rounding could otherwise
    put the last step just outside the bracket and restart by bisection from 10⁻³⁰ of the density.
    """
    lhi = math.log(q if from_pressure else q * sum_a)
    llo = lhi - 69.07755278982137                      # ln 1e-30
    if not (llo < x < lhi):
        x = lhi - 6.907755278982137                    # ln 1e-3: the reference start
    for _ in range(200):
        ne = math.exp(x)
        nh = (q - ne) / sum_a if from_pressure else q
        s = 0.0
        ds = 0.0
        for m in range(abund.size):
            r = 1.0 / (ne + phi[m])
            f = abund[m] * phi[m] * r
            s += f
            ds += f * r
        f = ne - nh * s
        if f > 0.0:
            lhi = min(lhi, x)
        else:
            llo = max(llo, x)
        fp = 1.0 + nh * ds + (s / sum_a if from_pressure else 0.0)
        xn = x - f / (fp * ne)
        if abs(xn - x) < 1e-11:
            return math.exp(xn)
        if not (llo < xn < lhi):
            xn = 0.5 * (llo + lhi)
        x = xn
    return math.exp(x)


#: The start table of the fast solver: ln n_e on a (ln T, ln q) grid (q = P/kT or n_H), per input kind.
_GUESS_LNT = (math.log(1000.0), math.log(1e5), 240)
_GUESS_LNQ = (math.log(1e2), math.log(1e24), 120)


@nb.njit(cache=True, nogil=True)
def _solve_ne_fast(start, stop, t, q, from_pressure, sum_a, abund, phi_a, phi_b, phi_c, phi_bin, guess, out):
    """
    n_e at points ``start`` to ``stop``: `saha_phi` in closed form, Newton from a bilinear start in ``guess``.

    The same equation and stopping rule as `_solve_ne` (|Δ ln n_e| < 1e-11), so the same n_e to
    ~1e-11; each point depends on its own data only.  ``guess`` empty: the reference start.
    """
    t0, t1, nt = _GUESS_LNT
    q0, q1, nq = _GUESS_LNQ
    phi = np.empty(abund.size)
    for p in range(start, stop):
        _saha_point(t[p], abund, phi_a, phi_b, phi_c, phi_bin, phi)
        x = 0.0
        if guess.size:
            ft = min(max((math.log(t[p]) - t0) / (t1 - t0) * (nt - 1), 0.0), nt - 1.000001)
            fq = min(max((math.log(q[p]) - q0) / (q1 - q0) * (nq - 1), 0.0), nq - 1.000001)
            it = int(ft)
            iq = int(fq)
            wt = ft - it
            wq = fq - iq
            x = ((1.0 - wt) * ((1.0 - wq) * guess[it, iq] + wq * guess[it, iq + 1])
                 + wt * ((1.0 - wq) * guess[it + 1, iq] + wq * guess[it + 1, iq + 1]))
        out[p] = _newton_ne(phi, abund, q[p], from_pressure, sum_a, x)


_GUESS = {}
#: Fewest points per thread's chunk.
_MIN_CHUNK = 1024


def _guess_table(from_pressure):
    """The start grid's ln n_e (built once per process by the fast solver from the reference start)."""
    if from_pressure not in _GUESS:
        lt = np.linspace(*_GUESS_LNT)
        lq = np.linspace(*_GUESS_LNQ)
        t, q = (np.ascontiguousarray(a.ravel()) for a in np.meshgrid(np.exp(lt), np.exp(lq), indexing="ij"))
        out = np.empty(t.size)
        run_chunks(_solve_ne_fast, t.size, t, q, from_pressure, PARTICLES_PER_H, _ABUND, _PHI_A, _PHI_B,
                   _PHI_C, _PHI_BIN, np.empty((0, 0)), out, min_chunk=_MIN_CHUNK)
        _GUESS[from_pressure] = np.log(out).reshape(lt.size, lq.size)
    return _GUESS[from_pressure]


_ABUND = np.array([ABUNDANCE[e] for e in ELEMENTS])


def electron_density(temperature, *, hydrogen_density=None, gas_pressure=None, reference=False):
    """
    LTE electron density from T and either the hydrogen density or the gas pressure.

    Parameters
    ----------
    temperature : array_like
        K.
    hydrogen_density : array_like, optional
        Total hydrogen nuclei per cm³.
    gas_pressure : array_like, optional
        dyn cm⁻² (give exactly one of the two).
    reference : bool, optional
        Solve as the first implementation did (Φ of each element by `saha_phi` on whole arrays, Newton
        from n_e = 10⁻³ of the particle density), kept to test the default against.  The default
        evaluates Φ in closed form per point and starts Newton from a tabulated n_e(T, q): the same
        equation and stopping rule, so the same n_e within ~1e-11, ~20× faster.

    Returns
    -------
    `numpy.ndarray`
        n_e in cm⁻³ (float64, the shape of ``temperature``).

    Examples
    --------
    >>> ne = electron_density(6000.0, gas_pressure=1.0e5)
    >>> f"{float(ne):.2e}"
    '2.88e+13'
    """
    if (hydrogen_density is None) == (gas_pressure is None):
        raise ValueError("give exactly one of hydrogen_density and gas_pressure")
    t = np.asarray(temperature, dtype=np.float64)
    from_pressure = gas_pressure is not None
    q = (np.asarray(gas_pressure, dtype=np.float64) / (K_BOLTZMANN * t) if from_pressure
         else np.asarray(hydrogen_density, dtype=np.float64))
    t, q = np.broadcast_arrays(t, q)
    shape = t.shape
    t, q = t.reshape(-1), q.reshape(-1)
    if not (np.isfinite(t).all() and np.isfinite(q).all() and (t > 0).all() and (q > 0).all()):
        raise ValueError("temperature and density/pressure must be finite and positive")
    out = np.empty(t.size)
    if not reference:
        run_chunks(_solve_ne_fast, t.size, np.ascontiguousarray(t), np.ascontiguousarray(q), from_pressure,
                   PARTICLES_PER_H, _ABUND, _PHI_A, _PHI_B, _PHI_C, _PHI_BIN, _guess_table(from_pressure),
                   out, min_chunk=_MIN_CHUNK)
        return out.reshape(shape)
    abund = _ABUND
    for start in range(0, t.size, _CHUNK):
        sl = slice(start, start + _CHUNK)
        phi = np.stack([saha_phi(e, t[sl]) for e in ELEMENTS])
        run_chunks(_solve_ne, phi.shape[1], phi, abund, np.ascontiguousarray(q[sl]), from_pressure,
                   PARTICLES_PER_H, out[sl], min_chunk=_MIN_CHUNK)
    return out.reshape(shape)


def solve_state(temperature, *, gas_pressure=None, density=None, electron_density_=None):
    """
    Complete the thermodynamic state: (P, ρ, n_e, n_H) from T and P or ρ (n_e optional).

    Parameters
    ----------
    temperature : array_like
        K.
    gas_pressure : array_like, optional
        dyn cm⁻².
    density : array_like, optional
        g cm⁻³ (at least one of P and ρ).
    electron_density_ : array_like, optional
        cm⁻³; when given it is kept and only the missing quantities are derived.

    Returns
    -------
    dict
        ``gas_pressure``, ``density``, ``electron_density``, ``hydrogen_density`` (float64, cgs).
    """
    t = np.asarray(temperature, dtype=np.float64)
    if gas_pressure is None and density is None:
        raise ValueError("the state needs the gas pressure or the density")
    if density is not None:
        nh = np.asarray(density, dtype=np.float64) / (AMU * MEAN_MASS_PER_H)
        ne = (electron_density(t, hydrogen_density=nh) if electron_density_ is None
              else np.asarray(electron_density_, dtype=np.float64))
        p = ((nh * PARTICLES_PER_H + ne) * K_BOLTZMANN * t if gas_pressure is None
             else np.asarray(gas_pressure, dtype=np.float64))
    else:
        p = np.asarray(gas_pressure, dtype=np.float64)
        ne = (electron_density(t, gas_pressure=p) if electron_density_ is None
              else np.asarray(electron_density_, dtype=np.float64))
        nh = (p / (K_BOLTZMANN * t) - ne) / PARTICLES_PER_H
        if (nh <= 0).any():
            raise ValueError("the electron density exceeds the particle density P/kT somewhere")
    rho = nh * AMU * MEAN_MASS_PER_H if density is None else np.asarray(density, dtype=np.float64)
    return {"gas_pressure": p, "density": rho, "electron_density": ne, "hydrogen_density": nh}
