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
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

__all__ = ["faddeeva", "solve_columns", "TAU_BOTTOM", "TAU_TOP", "ZEEMAN_CM_PER_G"]

#: Continuum optical depth (along the ray) where the integration starts.
TAU_BOTTOM = 60.0
#: Largest optical depth (any wavelength) of the layers above the ray's top point that are left out.
TAU_TOP = 1e-6
#: e / (4π m_e c²), cm⁻¹ G⁻¹: Δλ_B = this × λ² g B.
ZEEMAN_CM_PER_G = 4.66864e-5
_C = 2.99792458e10


@nb.njit(cache=True, inline="always")
def faddeeva(x, y):
    """
    Re and Im of the Faddeeva function w(x + i y), y ≥ 0 (Humlíček 1982, algorithm W4).

    Relative accuracy ~1e-4 (tested against `scipy.special.wofz`).
    """
    t = complex(y, -x)
    s = abs(x) + y
    if s >= 15.0:
        w = t * 0.5641896 / (0.5 + t * t)
    elif s >= 5.5:
        u = t * t
        w = t * (1.410474 + u * 0.5641896) / (0.75 + u * (3.0 + u))
    elif y >= 0.195 * abs(x) - 0.176:
        w = ((16.4955 + t * (20.20933 + t * (11.96482 + t * (3.778987 + t * 0.5642236))))
             / (16.4955 + t * (38.82363 + t * (39.27121 + t * (21.69274 + t * (6.699398 + t))))))
    else:
        u = t * t
        w = np.exp(u) - t * (36183.31 - u * (3321.9905 - u * (1540.787 - u * (219.0313 - u * (
            35.76683 - u * (1.320522 - u * 0.56419)))))) / (32066.6 - u * (24322.84 - u * (
                9022.228 - u * (2186.181 - u * (364.2191 - u * (61.57037 - u * (1.841439 - u)))))))
    return w.real, w.imag


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
def _solve4(q, u, v, rq, ru, rv, al, b0, b1, b2, b3):
    """Solve (1 + al K') x = b for the LL04 structure of K' (Gaussian elimination, no pivoting)."""
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
    m11 = 1.0 - m10 * m01
    m12 -= m10 * m02
    m13 -= m10 * m03
    b1 -= m10 * b0
    m21 -= m20 * m01
    m22 = 1.0 - m20 * m02
    m23 -= m20 * m03
    b2 -= m20 * b0
    m31 -= m30 * m01
    m32 -= m30 * m02
    m33 = 1.0 - m30 * m03
    b3 -= m30 * b0
    p1 = 1.0 / m11
    f = m21 * p1
    m22 -= f * m12
    m23 -= f * m13
    b2 -= f * b1
    f = m31 * p1
    m32 -= f * m12
    m33 -= f * m13
    b3 -= f * b1
    p2 = 1.0 / m22
    f = m32 * p2
    m33 -= f * m23
    b3 -= f * b2
    x3 = b3 / m33
    x2 = (b2 - m23 * x3) * p2
    x1 = (b1 - m12 * x2 - m13 * x3) * p1
    x0 = b0 - m01 * x1 - m02 * x2 - m03 * x3
    return x0, x1, x2, x3


@nb.njit(parallel=True, cache=True)
def solve_columns(lam_cm, lam0, lande_g, core_index, ds, kc_all, kl_all, dop_all, damp_all, src_all, vlos,
                  bpar, b1, b2, out_i, out_q, out_u, out_v, log_tau_c, log_tau_core):
    """
    Emergent Stokes spectra of a block of rays.

    Parameters
    ----------
    lam_cm : (nλ,) float64
        Wavelengths (cm, the line's rest wavelength scale).
    lam0 : float
        Rest wavelength (cm).
    lande_g : float
        Effective Landé factor of the normal triplet.
    core_index : int
        Wavelength index whose optical depth is reported in ``log_tau_core``.
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
    ncol, nz = kc_all.shape
    nl = lam_cm.size
    for p in nb.prange(ncol):
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
