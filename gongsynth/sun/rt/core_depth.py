"""
The optical depth at one wavelength along the solver's rays (the ``truth="core"`` height), and the
rays' point parameters that the solver (`~gongsynth.sun.rt.kernels`) shares.

`core_depth_rays` is a kernel of its own so that a run which does not ask for the core's optical
depth (the default) never compiles it, nor the scalar `~gongsynth.sun.rt.voigt.faddeeva_fast`
it calls (issue 26: a first run's compile).
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from gongsynth.sun.rt.voigt import faddeeva_fast

__all__ = ["core_depth_rays", "point_parameters", "ZEEMAN_CM_PER_G", "LIGHT_CM_PER_S"]

#: e / (4π m_e c²), cm⁻¹ G⁻¹: Δλ_B = this × λ² g B.
ZEEMAN_CM_PER_G = 4.66864e-5
#: The speed of light, cm/s.
LIGHT_CM_PER_S = 2.99792458e10


@nb.njit(cache=True, inline="always")
def point_parameters(lo, hi, lam0, lande_g, dop, vlos, kl, bpar, b1, b2, pt):
    """
    The parameters of points ``lo`` to ``hi`` of one ray, into ``pt[:, lo:hi]`` (9 rows): 1/Δλ_D,
    v_los and v_B in Doppler widths, κ_L/2, 1 − cos²γ, 1 + cos²γ, cos 2χ, sin 2χ, cos γ.

    Returns
    -------
    bool
        Whether any of these points has a field.
    """
    polar = False
    for k in range(lo, hi):
        rd = 1.0 / dop[k]
        pt[0, k] = rd
        pt[1, k] = lam0 * vlos[k] / LIGHT_CM_PER_S / dop[k]
        pt[3, k] = 0.5 * kl[k]
        bz, bx, by = bpar[k], b1[k], b2[k]
        b2sum = bz * bz + bx * bx + by * by
        cg = 1.0
        if b2sum > 0.0:
            polar = True
            bb_ = math.sqrt(b2sum)
            rb2 = 1.0 / b2sum
            pt[2, k] = ZEEMAN_CM_PER_G * lam0 * lam0 * lande_g * bb_ / dop[k]
            cg = bz / bb_
            pt[6, k] = (bx * bx - by * by) * rb2
            pt[7, k] = 2.0 * bx * by * rb2
        pt[4, k] = 1.0 - cg * cg
        pt[5, k] = 1.0 + cg * cg
        pt[8, k] = cg
    return polar


@nb.njit(cache=True)
def _fast_elements(v, a, vb, kc, h, c1, c2, cq, cu, cv):
    """(η_I, η_Q,U,V/η_I, ρ_Q,U,V/η_I) at one point; h = κ_L/2, c1,2 = 1 ∓ cos²γ, cv = cos γ."""
    hp, fp = faddeeva_fast(v, a)
    if vb == 0.0:
        return kc + h * (hp * c1 + hp * c2), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    hb, fb = faddeeva_fast(v + vb, a)
    hr, fr = faddeeva_fast(v - vb, a)
    hs = 0.5 * (hb + hr)
    fs = 0.5 * (fb + fr)
    ei = kc + h * (hp * c1 + hs * c2)
    g = h / ei
    t = g * (hp - hs)
    r = g * (fp - fs)
    return ei, t * cq, t * cu, g * (hr - hb) * cv, r * cq, r * cu, g * (fr - fb) * cv


@nb.njit(cache=True, nogil=True, error_model="numpy", fastmath={"contract"})
def core_depth_rays(start, stop, dl, lam0, lande_g, core_index, ds, kc_all, kl_all, dop_all, damp_all,
                     vlos_all, bpar_all, b1_all, b2_all, log_tau_core_all):
    """
    log10 of the optical depth at wavelength ``core_index`` along rays ``start`` to ``stop`` of
    `~gongsynth.sun.rt.kernels.solve_columns` (all points), into ``log_tau_core_all``.
    """
    nz = kc_all.shape[1]
    j = core_index
    for p in range(start, stop):
        kc, aa, log_tau_core = kc_all[p], damp_all[p], log_tau_core_all[p]
        pt = np.zeros((9, nz))
        point_parameters(0, nz, lam0, lande_g, dop_all[p], vlos_all[p], kl_all[p], bpar_all[p], b1_all[p],
                         b2_all[p], pt)
        tau = 0.0
        log_tau_core[nz - 1] = -12.0
        k = nz - 1
        en0 = _fast_elements(dl[j] * pt[0, k] - pt[1, k], aa[k], pt[2, k], kc[k], pt[3, k], pt[4, k],
                             pt[5, k], pt[6, k], pt[7, k], pt[8, k])[0]
        for k in range(nz - 2, -1, -1):
            ec0 = _fast_elements(dl[j] * pt[0, k] - pt[1, k], aa[k], pt[2, k], kc[k], pt[3, k], pt[4, k],
                                 pt[5, k], pt[6, k], pt[7, k], pt[8, k])[0]
            tau += 0.5 * (ec0 + en0) * ds[k]
            log_tau_core[k] = math.log10(max(tau, 1e-12))
            en0 = ec0
