r"""
Numba kernels: the Faddeeva function and the DELO-linear polarised formal solver.

Transfer equation along the ray (s toward the observer), Landi Degl'Innocenti &
Landolfi (2004) conventions:

.. math:: \frac{d\mathbf I}{ds} = -\mathbf K (\mathbf I - B\,\mathbf e_1)\ \text{in LTE},\qquad
          \mathbf K = \begin{pmatrix} \eta_I & \eta_Q & \eta_U & \eta_V\\ \eta_Q & \eta_I & \rho_V & -\rho_U\\
          \eta_U & -\rho_V & \eta_I & \rho_Q \\ \eta_V & \rho_U & -\rho_Q & \eta_I\end{pmatrix}

with the normal-triplet elements of `gongsynth.sun.photosphere.synthesize`
(π and σ± components with H and F = Re, Im of w(v + i a)).  In the optical
depth dτ = −η_I ds, dI/dτ = I − S_eff with S_eff = S' − K'I, K' = K/η_I − 1,
S' = B (1, η_Q, η_U, η_V)/η_I.  DELO-linear (Rees, Durrant & Murphy 1989)
interpolates S_eff linearly between grid points, which gives per step

.. math:: (1 + \alpha K'_c)\,\mathbf I_c = (e^{-\Delta\tau} - \beta K'_u)\,\mathbf I_u
          + \alpha S'_c + \beta S'_u

solved as a 4 × 4 system (its symmetric part is positive definite, so Gaussian
elimination needs no pivoting).  The ray starts at the deepest point where
τ_c ≤ `TAU_BOTTOM` with the diffusion approximation and ignores the top layers
above τ ≤ `TAU_TOP` at every wavelength.

`solve_columns` is the fast implementation: per ray (`_solve_rays`) it
advances all wavelengths together point by point in loops the compiler
vectorises, takes w(z) from Weideman's form in float32 (`_w_vec`,
`~gongsynth.sun.rt.voigt.w_weideman32`: relative error < 1e-6, eight SIMD
lanes, no branch), the σ profiles from the Taylor series in the Zeeman shift
when it is below `VB_TAYLOR` Doppler widths (where w(x − v_B) − w(x + v_B) of
two float32 values would lose the difference to rounding) and from w at x ± v_B
above it, and the scalar solve on rays with B = 0.  The σ series stays in
float64 (its recurrence cancels in the wings); the absorption-matrix elements,
Δτ, e^−Δτ, the DELO weights (from their series below Δτ = 0.3, where
1 − e^−Δτ would cancel in float32) and the 4 × 4 recursion are float32, within
2e-5 of the continuum of the float64 recursion (measured on the 3-D Sun's
rays).  The bottom point's incoming intensity (diffusion approximation) is taken from the first
step's Δτ, so the whole ray goes through the vectorised loops.  Its
only fast-math flag is fused multiply-add, so it gives the same bits for any
block size and thread count.  `solve_columns_reference` is the first, simple implementation of
the same equations, kept to test and benchmark the fast one against.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from gongsynth.sun.rt.core_depth import LIGHT_CM_PER_S as _C
from gongsynth.sun.rt.core_depth import ZEEMAN_CM_PER_G, core_depth_rays, point_parameters
from gongsynth.sun.rt.voigt import faddeeva, faddeeva_fast, sigma_taylor_vec, w_weideman32
from gongsynth.threads import run_chunks

__all__ = ["faddeeva", "faddeeva_fast", "solve_columns", "solve_columns_reference", "TAU_BOTTOM", "TAU_TOP",
           "VB_TAYLOR", "ZEEMAN_CM_PER_G"]

#: Continuum optical depth (along the ray) where the integration starts.
TAU_BOTTOM = 60.0
#: Largest optical depth (any wavelength) of the layers above the ray's top point that are left out.
TAU_TOP = 1e-6
#: Zeeman splitting (Doppler widths) up to which the σ profiles come from the Taylor series about π's
#: (order ≤ 4; above it the float32 difference w(x − v_B) − w(x + v_B) errs by < 6e-5 of its peak).
VB_TAYLOR = 0.006
#: Fast-math flags of the fast solver: only fused multiply-add (no reassociation, NaN and inf kept), so the
#: result is the same for any block size and thread count.
_CONTRACT = {"contract"}


@nb.njit(cache=True, inline="always")
def _delo_weights(dt):
    if dt < 1e-3:
        w0 = dt * (1.0 - dt * (0.5 - dt / 6.0))
        w1 = dt * dt * (0.5 - dt * (1.0 / 3.0 - dt * 0.125))
        e = 1.0 - w0
    else:
        e = math.exp(-dt)
        w0 = 1.0 - e
        w1 = w0 - dt * e
    beta = w1 / dt
    return e, w0 - beta, beta


@nb.njit(cache=True, inline="always")
def _elements(vj, k, kc, kl, dop, a, vs, vb, cg, fq, fu):
    """Absorption-matrix elements at one point and wavelength index vj (Doppler-width units)."""
    v = vj - vs
    hp, fp = faddeeva(v, a)
    if vb != 0.0:
        hb, fb = faddeeva(v + vb, a)
        hr, fr = faddeeva(v - vb, a)
    else:
        hb, fb, hr, fr = hp, fp, hp, fp
    hs = 0.5 * (hb + hr)
    fs = 0.5 * (fb + fr)
    h = 0.5 * kl
    ei = kc + h * (hp * (1.0 - cg * cg) + hs * (1.0 + cg * cg))
    inv = 1.0 / ei
    return (ei, h * (hp - hs) * fq * inv, h * (hp - hs) * fu * inv, h * (hr - hb) * cg * inv,
            h * (fp - fs) * fq * inv, h * (fp - fs) * fu * inv, h * (fr - fb) * cg * inv)


@nb.njit(cache=True, inline="always")
def _solve4(q, u, v, rq, ru, rv, al, b0, b1, b2, b3, one=1.0):
    """
    Solve (1 + al K') x = b for the LL04 structure of K' (Gaussian elimination, no pivoting).

    ``one``: 1 in the arithmetic's precision (`numpy.float32` keeps a float32 solve in float32).
    """
    m01 = al * q
    m02 = al * u
    m03 = al * v
    m10 = m01
    m12 = al * rv
    m13 = -al * ru
    m20 = m02
    m21 = -m12
    m23 = al * rq
    m30 = m03
    m31 = -m13
    m32 = -m23
    m11 = one - m10 * m01
    m12 -= m10 * m02
    m13 -= m10 * m03
    b1 -= m10 * b0
    m21 -= m20 * m01
    m22 = one - m20 * m02
    m23 -= m20 * m03
    b2 -= m20 * b0
    m31 -= m30 * m01
    m32 -= m30 * m02
    m33 = one - m30 * m03
    b3 -= m30 * b0
    p1 = one / m11
    f = m21 * p1
    m22 -= f * m12
    m23 -= f * m13
    b2 -= f * b1
    f = m31 * p1
    m32 -= f * m12
    m33 -= f * m13
    b3 -= f * b1
    p2 = one / m22
    f = m32 * p2
    m33 -= f * m23
    b3 -= f * b2
    x3 = b3 / m33
    x2 = (b2 - m23 * x3) * p2
    x1 = (b1 - m12 * x2 - m13 * x3) * p1
    x0 = b0 - m01 * x1 - m02 * x2 - m03 * x3
    return x0, x1, x2, x3


def solve_columns_reference(lam_cm, lam0, lande_g, core_index, ds, kc_all, kl_all, dop_all, damp_all, src_all,
                            vlos, bpar, b1, b2, out_i, out_q, out_u, out_v, log_tau_c, log_tau_core):
    """
    Emergent Stokes spectra of a block of rays: the simple reference path of `solve_columns`.

    The first version of the solver, kept to check the fast one against: wavelength
    by wavelength, Humlíček's W4 for the π and both σ components at every point,
    the full 4 × 4 solve even where B = 0.  Same arguments as `solve_columns`.
    """
    run_chunks(_reference_rays, kc_all.shape[0], lam_cm, lam0, lande_g, core_index, ds, kc_all, kl_all,
               dop_all, damp_all, src_all, vlos, bpar, b1, b2, out_i, out_q, out_u, out_v, log_tau_c,
               log_tau_core)


@nb.njit(cache=True, nogil=True)
def _reference_rays(start, stop, lam_cm, lam0, lande_g, core_index, ds, kc_all, kl_all, dop_all, damp_all,
                    src_all, vlos, bpar, b1, b2, out_i, out_q, out_u, out_v, log_tau_c, log_tau_core):
    """Rays ``start`` to ``stop`` of `solve_columns_reference`."""
    nz = kc_all.shape[1]
    nl = lam_cm.size
    for p in range(start, stop):
        kc = kc_all[p]
        kl = kl_all[p]
        dop = dop_all[p]
        aa = damp_all[p]
        bb = src_all[p]
        vs = np.empty(nz)
        vb = np.empty(nz)
        cg = np.empty(nz)
        fq = np.empty(nz)
        fu = np.empty(nz)
        kmax = np.empty(nz)
        for k in range(nz):
            kmax[k] = kc[k] + kl[k]
            vs[k] = lam0 * vlos[p, k] / _C / dop[k]
            bz, bx, by = bpar[p, k], b1[p, k], b2[p, k]
            b2sum = bz * bz + bx * bx + by * by
            if b2sum > 0.0:
                vb[k] = ZEEMAN_CM_PER_G * lam0 * lam0 * lande_g * math.sqrt(b2sum) / dop[k]
                cg[k] = bz / math.sqrt(b2sum)
                fq[k] = (bx * bx - by * by) / b2sum
                fu[k] = 2.0 * bx * by / b2sum
            else:
                vb[k] = 0.0
                cg[k] = 1.0
                fq[k] = 0.0
                fu[k] = 0.0
        # Continuum and core optical depths from the top; the range of points to integrate.
        tc = 0.0
        tm = 0.0
        log_tau_c[p, nz - 1] = -12.0
        kbot = 0
        ktop = nz - 1
        for k in range(nz - 2, -1, -1):
            tc += 0.5 * (kc[k] + kc[k + 1]) * ds[k]
            tm += 0.5 * (kmax[k] + kmax[k + 1]) * ds[k]
            log_tau_c[p, k] = math.log10(max(tc, 1e-12))
            if tm <= TAU_TOP:
                ktop = k
            if tc < TAU_BOTTOM:
                kbot = k
        kbot = max(kbot - 1, 0)
        ktop = max(ktop, kbot + 1)
        for j in range(nl):
            # Wavelength offset in Doppler widths is per point: v = (λ - λ0)/Δλ_D.
            dl = lam_cm[j] - lam0
            k = kbot
            eu = _elements(dl / dop[k], k, kc[k], kl[k], dop[k], aa[k], vs[k], vb[k], cg[k], fq[k], fu[k])
            en = _elements(dl / dop[k + 1], k + 1, kc[k + 1], kl[k + 1], dop[k + 1], aa[k + 1], vs[k + 1],
                           vb[k + 1], cg[k + 1], fq[k + 1], fu[k + 1])
            dt0 = 0.5 * (eu[0] + en[0]) * ds[k]
            i0 = bb[k] + (bb[k] - bb[k + 1]) / dt0
            i1 = 0.0
            i2 = 0.0
            i3 = 0.0
            tau = 0.0
            if j == core_index:
                for kk in range(nz):
                    log_tau_core[p, kk] = 30.0
            for k in range(kbot + 1, ktop + 1):
                ec = _elements(dl / dop[k], k, kc[k], kl[k], dop[k], aa[k], vs[k], vb[k], cg[k], fq[k],
                               fu[k])
                dt = 0.5 * (eu[0] + ec[0]) * ds[k - 1]
                e, al, be = _delo_weights(dt)
                bu = bb[k - 1]
                bc = bb[k]
                y0 = e * i0 - be * (eu[1] * i1 + eu[2] * i2 + eu[3] * i3) + al * bc + be * bu
                y1 = e * i1 - be * (eu[1] * i0 + eu[6] * i2 - eu[5] * i3) + al * bc * ec[1] + be * bu * eu[1]
                y2 = e * i2 - be * (eu[2] * i0 - eu[6] * i1 + eu[4] * i3) + al * bc * ec[2] + be * bu * eu[2]
                y3 = e * i3 - be * (eu[3] * i0 + eu[5] * i1 - eu[4] * i2) + al * bc * ec[3] + be * bu * eu[3]
                i0, i1, i2, i3 = _solve4(ec[1], ec[2], ec[3], ec[4], ec[5], ec[6], al, y0, y1, y2, y3)
                eu = ec
            out_i[p, j] = i0
            out_q[p, j] = i1
            out_u[p, j] = i2
            out_v[p, j] = i3
            if j == core_index:
                tau = 0.0
                log_tau_core[p, nz - 1] = -12.0
                en = _elements(dl / dop[nz - 1], nz - 1, kc[nz - 1], kl[nz - 1], dop[nz - 1], aa[nz - 1],
                               vs[nz - 1], vb[nz - 1], cg[nz - 1], fq[nz - 1], fu[nz - 1])
                for k in range(nz - 2, -1, -1):
                    ec = _elements(dl / dop[k], k, kc[k], kl[k], dop[k], aa[k], vs[k], vb[k], cg[k],
                                   fq[k], fu[k])
                    tau += 0.5 * (ec[0] + en[0]) * ds[k]
                    log_tau_core[p, k] = math.log10(max(tau, 1e-12))
                    en = ec


@nb.njit(cache=True, error_model="numpy", fastmath=_CONTRACT)
def _w_vec(dl, rd, shift, y, xs, wr, wi):
    """
    w(x + i y) of all wavelengths at one point, x = dl·rd − shift, into ``xs``, ``wr``, ``wi``.

    Weideman's form in float32 (`w_weideman32`, relative error < 1e-6 of |w|): one branch-free loop
    over the wavelengths that the compiler vectorises with eight lanes.
    """
    y32 = np.float32(y)
    for j in range(dl.size):
        x = dl[j] * rd - shift
        xs[j] = x
        wr[j], wi[j] = w_weideman32(np.float32(x), y32)


_F = np.float32
#: 2⁻ⁿ in float32 (n ≤ 126, the normal range) and 0 for n = 127: e^(−t) of `_exp_neg` underflows to 0.
_EXP2_NEG = np.append(np.ldexp(_F(1.0), -np.arange(127)), 0.0).astype(_F)
_EXP_TAYLOR = tuple(_F((-1.0) ** n / math.factorial(n)) for n in range(10))
_ZERO, _HALF, _ONE = _F(0.0), _F(0.5), _F(1.0)
_T_MAX = _F(89.0)                                  # e^(−t) < 2⁻¹²⁷ beyond: the table's 0
_LOG2E, _LN2_HI, _LN2_LO = _F(1.4426950408889634), _F(0.693145751953125), _F(1.4286068203094172e-06)
#: Optical-depth step below which the DELO weights come from their series (no cancellation in float32).
_DT_SERIES = _F(0.3)
# Series coefficients: w0 = 1 − e^(−Δτ) = Σ (−1)ⁿ⁺¹ Δτⁿ/n!, w1/Δτ = (1 − e^(−Δτ) − Δτ e^(−Δτ))/Δτ =
# Σ_{n≥2} (−1)ⁿ (n − 1) Δτⁿ⁻¹/n!, in float32 up to Δτ⁸ (relative error < 1e-8 at Δτ = 0.3).
_W0_SERIES = tuple(_F((-1.0) ** (n + 1) / math.factorial(n)) for n in range(1, 10))
_BETA_SERIES = tuple(_F((-1.0) ** n * (n - 1) / math.factorial(n)) for n in range(2, 11))


@nb.njit(cache=True, inline="always")
def _exp_neg(t):
    """
    e^(−t), t ≥ 0, in float32 without a library call (vectorisable): 2^(−n) e^(−r), r ∈ [0, ln 2),
    Taylor to r⁹ (relative error < 2e-7); 0 beyond t = 88 (float32 underflow), finite for any t.
    """
    t = min(max(t, _ZERO), _T_MAX)
    n = min(max(int(t * _LOG2E), 0), 127)               # in the table whatever t is (NaN included)
    fn = _F(n)
    r = (t - fn * _LN2_HI) - fn * _LN2_LO
    p = _EXP_TAYLOR[9]
    for m in range(8, -1, -1):
        p = p * r + _EXP_TAYLOR[m]
    return p * _EXP2_NEG[n]


@nb.njit(cache=True, inline="always")
def _weights(dt, ex):
    """
    `_delo_weights` in float32 with e^(−Δτ) given: (e, α, β), branch-free for vectorisation.

    Below `_DT_SERIES` w0 and β come from their series, where 1 − e and w0 − Δτ e would cancel.
    """
    p = _W0_SERIES[8]
    q = _BETA_SERIES[8]
    for m in range(7, -1, -1):
        p = p * dt + _W0_SERIES[m]
        q = q * dt + _BETA_SERIES[m]
    w0s = p * dt
    bes = q * dt
    small = dt < _DT_SERIES
    w0 = w0s if small else _ONE - ex
    e = _ONE - w0s if small else ex
    beta = bes if small else (w0 - dt * ex) / dt
    return e, w0 - beta, beta


@nb.njit(cache=True, inline="always")
def _diffusion(i0, i1, i2, i3, dt, bu, bc):
    """The incoming I at the bottom point by the diffusion approximation, B + dB/dτ (Q = U = V = 0)."""
    for j in range(i0.size):
        i0[j] = bu + (bu - bc) / dt[j]
        i1[j] = i2[j] = i3[j] = _ZERO


@nb.njit(cache=True, error_model="numpy", fastmath=_CONTRACT)
def _step(i0, i1, i2, i3, eu, ec, dt, ex, bu, bc):
    """One DELO-linear step of all wavelengths in float32 (4 × 4 solve; a loop the compiler vectorises)."""
    for j in range(i0.size):
        e, al, be = _weights(dt[j], ex[j])
        a0, a1, a2, a3 = i0[j], i1[j], i2[j], i3[j]
        u1, u2, u3, u4, u5, u6 = eu[1, j], eu[2, j], eu[3, j], eu[4, j], eu[5, j], eu[6, j]
        sc = al * bc
        su = be * bu
        y0 = e * a0 - be * (u1 * a1 + u2 * a2 + u3 * a3) + sc + su
        y1 = e * a1 - be * (u1 * a0 + u6 * a2 - u5 * a3) + sc * ec[1, j] + su * u1
        y2 = e * a2 - be * (u2 * a0 - u6 * a1 + u4 * a3) + sc * ec[2, j] + su * u2
        y3 = e * a3 - be * (u3 * a0 + u5 * a1 - u4 * a2) + sc * ec[3, j] + su * u3
        i0[j], i1[j], i2[j], i3[j] = _solve4(ec[1, j], ec[2, j], ec[3, j], ec[4, j], ec[5, j], ec[6, j], al,
                                             y0, y1, y2, y3, _ONE)


#: The wavelength loops' SIMD width (float32 lanes of AVX2): the solver's wavelength grid is padded to
#: a multiple of it, so that no loop ends in a scalar remainder.
_LANES = 8


def _padded(dl):
    """``dl`` extended to a multiple of `_LANES` values, continuing its last step (still increasing)."""
    pad = -dl.size % _LANES
    step = dl[-1] - dl[-2] if dl.size > 1 else 1e-10
    return np.concatenate([dl, dl[-1] + step * np.arange(1, pad + 1)])


def solve_columns(lam_cm, lam0, lande_g, core_index, ds, kc_all, kl_all, dop_all, damp_all, src_all, vlos,
                  bpar, b1, b2, out_i, out_q, out_u, out_v, log_tau_c, log_tau_core):
    """
    Emergent Stokes spectra of a block of rays.

    The DELO-linear solution of the module docstring over the same points as
    `solve_columns_reference`, computed faster (`_solve_rays`, one ray after
    another, chunks of rays on the threads of `~gongsynth.threads.run_chunks`):
    all wavelengths are advanced together point by point (independent work
    for the processor between the steps of one recursion),
    w(z) from Weideman's form in float32 over all wavelengths at once (`_w_vec`;
    the wavelengths padded to a multiple of the SIMD width, so that no loop ends
    in a scalar remainder: 56 for 51, ~10 % faster), and a ray
    with B = 0 at every integrated point takes the scalar solve (Q = U = V = 0
    exactly; I as the 4 × 4 solve gives it with zero off-diagonal elements).
    Each ray's result depends on that ray's data only (any block size, any threads).

    Parameters
    ----------
    lam_cm : (nλ,) float64
        Wavelengths (cm, the line's rest wavelength scale), increasing.
    lam0 : float
        Rest wavelength (cm).
    lande_g : float
        Effective Landé factor of the normal triplet.
    core_index : int
        Wavelength index whose optical depth is reported in ``log_tau_core``
        (negative: none, ``log_tau_core`` is left as it is).
    ds : (nz - 1,) float64
        Path length between consecutive ray points (cm), bottom to top.
    kc_all, kl_all, dop_all, damp_all, src_all : (ncol, nz) float64
        Continuum opacity and line-centre opacity scale (cm⁻¹), Doppler width
        (cm), damping and source function (see
        `~gongsynth.sun.rt.opacity.column_opacity`); points ordered bottom to top.
    vlos, bpar, b1, b2 : (ncol, nz) float64
        Velocity along the ray (cm/s, > 0 away from the observer) and the field
        along the line of sight and the sky axes e1, e2 (G).
    out_i, out_q, out_u, out_v : (ncol, nλ) float32
        Filled with the emergent spectra (units of the source function).
    log_tau_c, log_tau_core : (ncol, nz) float32
        Filled with log10 of the continuum and ``core_index`` optical depth along the ray.
    """
    if not np.all(np.diff(lam_cm) > 0):
        raise ValueError("lam_cm must be strictly increasing")
    dl = _padded(lam_cm - lam0)
    run_chunks(_solve_rays, kc_all.shape[0], dl, lam0, lande_g, ds, kc_all, kl_all, dop_all, damp_all,
               src_all, vlos, bpar, b1, b2, out_i, out_q, out_u, out_v, log_tau_c)
    if core_index >= 0:
        run_chunks(core_depth_rays, kc_all.shape[0], dl, lam0, lande_g, core_index, ds, kc_all, kl_all,
                   dop_all, damp_all, vlos, bpar, b1, b2, log_tau_core)


@nb.njit(cache=True, nogil=True, error_model="numpy", fastmath=_CONTRACT)
def _solve_rays(start, stop, dl, lam0, lande_g, ds, kc_all, kl_all, dop_all, damp_all, src_all,
                vlos_all, bpar_all, b1_all, b2_all, out_i, out_q, out_u, out_v, log_tau_c_all):
    """
    Rays ``start`` to ``stop`` of `solve_columns` (``dl`` = λ − λ₀), one after the other.

    The ray loop is in this kernel, not around a per-ray kernel: one compile (a caller of a
    compiled per-ray kernel re-optimised its inlined copy, ~2 s of CPU more on a first run).
    """
    nz = kc_all.shape[1]
    nl = dl.size
    for p in range(start, stop):
        kc, kl, dop_k, aa, bb = kc_all[p], kl_all[p], dop_all[p], damp_all[p], src_all[p]
        vlos, bpar, b1, b2 = vlos_all[p], bpar_all[p], b1_all[p], b2_all[p]
        log_tau_c = log_tau_c_all[p]
        tc = 0.0
        tm = 0.0
        log_tau_c[nz - 1] = -12.0
        kbot = 0
        ktop = nz - 1
        for k in range(nz - 2, -1, -1):
            tc += 0.5 * (kc[k] + kc[k + 1]) * ds[k]
            tm += 0.5 * ((kc[k] + kl[k]) + (kc[k + 1] + kl[k + 1])) * ds[k]
            log_tau_c[k] = math.log10(max(tc, 1e-12))
            if tm <= TAU_TOP:
                ktop = k
            if tc < TAU_BOTTOM:
                kbot = k
        kbot = max(kbot - 1, 0)
        ktop = max(ktop, kbot + 1)
        # The points' parameters, only where they are used: the integrated points.
        pt = np.zeros((9, nz))
        polar = point_parameters(kbot, ktop + 1, lam0, lande_g, dop_k, vlos, kl, bpar, b1, b2, pt)
        wk = np.zeros((9, nl))
        pr0, pr1, pr2, pr3, pr4, pr5, xs, wbr, wbi = (wk[0], wk[1], wk[2], wk[3], wk[4], wk[5], wk[6], wk[7],
                                                      wk[8])
        sw = np.empty((4, nl))        # scratch of sigma_taylor_vec
        # The DELO recursion and the absorption matrix in float32 (see the module docstring).
        wf = np.zeros((20, nl), dtype=np.float32)
        i0, i1, i2, i3, dt, ex = wf[0], wf[1], wf[2], wf[3], wf[4], wf[5]
        eu = wf[6:13]                 # elements at the point below
        ec = wf[13:20]                # and at the current point
        # The bottom point only gives the elements (eu); each later one a step from the point below.
        for k in range(kbot, ktop + 1):
            first = k == kbot
            dsk = _F(0.5 * ds[k - 1]) if not first else _ZERO
            bu = _F(bb[k - 1])
            bc = _F(bb[k])
            rd, vs, vb, ak = pt[0, k], pt[1, k], pt[2, k], aa[k]
            h, c1, c2, kck = _F(pt[3, k]), _F(pt[4, k]), _F(pt[5, k]), _F(kc[k])
            _w_vec(dl, rd, vs, ak, xs, pr0, pr1)
            if not polar:
                for j in range(nl):
                    ei = kck + h * (_F(pr0[j]) * (c1 + c2))
                    dt[j] = (eu[0, j] + ei) * dsk
                    eu[0, j] = ei
                if first:
                    continue
                if k == kbot + 1:
                    _diffusion(i0, i1, i2, i3, dt, bu, bc)
                for j in range(nl):
                    ex[j] = _exp_neg(dt[j])
                for j in range(nl):
                    # e I + α S_c + β S_u as I + α (S_c − I) + β (S_u − I) (α + β = 1 − e): no rounding of
                    # an e near 1 (thin steps), which in float32 would accumulate along the ray.
                    e, al, be = _weights(dt[j], ex[j])
                    a0 = i0[j]
                    i0[j] = a0 + (al * (bc - a0) + be * (bu - a0))
                continue
            cq, cu, cv = _F(pt[6, k]), _F(pt[7, k]), _F(pt[8, k])
            if vb == 0.0:
                for j in range(nl):
                    pr2[j] = pr0[j]
                    pr3[j] = pr1[j]
                    pr4[j] = 0.0
                    pr5[j] = 0.0
            elif vb <= VB_TAYLOR:
                sigma_taylor_vec(xs, ak, vb, pr0, pr1, pr2, pr3, pr4, pr5, sw)
            else:
                _w_vec(dl, rd, vs - vb, ak, pr4, pr2, pr3)           # w(x + vb)
                _w_vec(dl, rd, vs + vb, ak, pr4, wbr, wbi)           # w(x − vb)
                for j in range(nl):
                    hb, fb = pr2[j], pr3[j]
                    pr2[j] = 0.5 * (hb + wbr[j])
                    pr3[j] = 0.5 * (fb + wbi[j])
                    pr4[j] = wbr[j] - hb
                    pr5[j] = wbi[j] - fb
            for j in range(nl):
                hp, fp, hs = _F(pr0[j]), _F(pr1[j]), _F(pr2[j])
                ei = kck + h * (hp * c1 + hs * c2)
                g = h / ei
                t = g * (hp - hs)
                r = g * (fp - _F(pr3[j]))
                ec[0, j] = ei
                ec[1, j] = t * cq
                ec[2, j] = t * cu
                ec[3, j] = g * _F(pr4[j]) * cv
                ec[4, j] = r * cq
                ec[5, j] = r * cu
                ec[6, j] = g * _F(pr5[j]) * cv
                dt[j] = (eu[0, j] + ei) * dsk
            if not first:
                if k == kbot + 1:
                    _diffusion(i0, i1, i2, i3, dt, bu, bc)
                for j in range(nl):
                    ex[j] = _exp_neg(dt[j])
                _step(i0, i1, i2, i3, eu, ec, dt, ex, bu, bc)
            eu, ec = ec, eu
        for j in range(out_i.shape[1]):          # without the padding (`_padded`)
            out_i[p, j] = i0[j]
            out_q[p, j] = i1[j]
            out_u[p, j] = i2[j]
            out_v[p, j] = i3[j]
