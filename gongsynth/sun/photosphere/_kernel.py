"""
Numba kernel of the Milne–Eddington (Unno–Rachkovsky) synthesis.

The Voigt and Faraday–Voigt functions are the real and imaginary parts of the
Faddeeva function w(v + i a), tabulated once per damping on a fine grid
(step 0.002 Doppler widths, linear interpolation: error < 2e-6 of the peak)
and continued by the asymptotic series beyond |v| = 40.
"""
import functools
import math

import numba as nb
import numpy as np
from scipy.special import wofz

__all__ = ["voigt_table", "voigt_lookup", "me_kernel", "me_project_kernel", "TABLE_VMAX", "TABLE_STEP"]

#: Half range and step of the Voigt table, in Doppler widths.
TABLE_VMAX = 40.0
TABLE_STEP = 0.002
_SQRT_PI = math.sqrt(math.pi)


@functools.lru_cache(maxsize=8)
def voigt_table(damping):
    """
    Re and Im of w(v + i a) on v = -TABLE_VMAX..TABLE_VMAX (step TABLE_STEP).

    Parameters
    ----------
    damping : float
        Voigt damping parameter a.

    Returns
    -------
    (`numpy.ndarray`, `numpy.ndarray`)
        The absorption (H, peak ≈ 1 for small a) and dispersion (Im w) profiles.
    """
    n = int(round(2 * TABLE_VMAX / TABLE_STEP)) + 1
    v = -TABLE_VMAX + TABLE_STEP * np.arange(n)
    w = wofz(v + 1j * float(damping))
    re, im = np.ascontiguousarray(w.real), np.ascontiguousarray(w.imag)
    re.flags.writeable = False
    im.flags.writeable = False
    return re, im


@nb.njit(inline="always", cache=True)
def voigt_lookup(v, a, tab_re, tab_im):
    """(Re w, Im w) at v + i a: table interpolation inside, asymptotic series outside."""
    x = (v + TABLE_VMAX) * (1.0 / TABLE_STEP)
    if x >= 0.0 and x < tab_re.size - 1:
        i = int(x)
        t = x - i
        return (tab_re[i] + t * (tab_re[i + 1] - tab_re[i]),
                tab_im[i] + t * (tab_im[i + 1] - tab_im[i]))
    z = complex(v, a)
    iz2 = 1.0 / (z * z)
    w = 1j / (_SQRT_PI * z) * (1.0 + iz2 * (0.5 + iz2 * (0.75 + 1.875 * iz2)))
    return w.real, w.imag


@nb.njit(inline="always", cache=True)
def _unno_rachkovsky(v, vb, c, fq, fu, b, s, eta0, damping, tab_re, tab_im):
    """(I, Q, U, V) at one wavelength of one column (see `me_kernel` for the inputs)."""
    hp, fp = voigt_lookup(v, damping, tab_re, tab_im)
    if vb != 0.0:
        hb, fb = voigt_lookup(v + vb, damping, tab_re, tab_im)
        hr, fr = voigt_lookup(v - vb, damping, tab_re, tab_im)
    else:
        hb, fb, hr, fr = hp, fp, hp, fp
    hs = 0.5 * (hb + hr)
    fs = 0.5 * (fb + fr)
    ei = 0.5 * eta0 * (hp * (1.0 - c * c) + hs * (1.0 + c * c))
    eq = 0.5 * eta0 * (hp - hs) * fq
    eu = 0.5 * eta0 * (hp - hs) * fu
    ev = 0.5 * eta0 * (hr - hb) * c
    rq = 0.5 * eta0 * (fp - fs) * fq
    ru = 0.5 * eta0 * (fp - fs) * fu
    rv = 0.5 * eta0 * (fr - fb) * c
    k = 1.0 + ei
    k2 = k * k
    r2 = rq * rq + ru * ru + rv * rv
    pi_ = eq * rq + eu * ru + ev * rv
    delta = k2 * (k2 - eq * eq - eu * eu - ev * ev + r2) - pi_ * pi_
    f = b / delta
    return (s * (1.0 + f * k * (k2 + r2)),
            -s * f * (k2 * eq + k * (ev * ru - eu * rv) + rq * pi_),
            -s * f * (k2 * eu + k * (eq * rv - ev * rq) + ru * pi_),
            -s * f * (k2 * ev + k * (eu * rq - eq * ru) + rv * pi_))


@nb.njit(parallel=True, cache=True)
def me_kernel(vgrid, vshift, vzeeman, cosg, qfac, ufac, bmu, scale, eta0, damping,
              tab_re, tab_im, out_i, out_q, out_u, out_v):
    """
    Fill ``out_*`` (npix, nλ) float32 with the Unno–Rachkovsky Stokes spectra.

    Per column (npix,) float64 inputs: ``vshift`` Doppler shift and
    ``vzeeman`` Zeeman splitting in Doppler widths, ``cosg`` = cosγ (field to
    line of sight), ``qfac`` = sin²γ cos2χ, ``ufac`` = sin²γ sin2χ, ``bmu`` = βμ,
    ``scale`` = continuum / (1 + βμ).  ``vgrid`` = (λ - λ0)/Δλ_D.  The loop runs
    in parallel over columns, so a (1, N) strip of a full-disk scene is as
    fast as an N-column square.
    """
    for p in nb.prange(vshift.size):
        for j in range(vgrid.size):
            si, sq, su, sv = _unno_rachkovsky(vgrid[j] - vshift[p], vzeeman[p], cosg[p], qfac[p], ufac[p],
                                              bmu[p], scale[p], eta0, damping, tab_re, tab_im)
            out_i[p, j] = si
            out_q[p, j] = sq
            out_u[p, j] = su
            out_v[p, j] = sv


# Floating-point freedoms of the contraction kernel: fused multiply-adds and reordered
# sums (vectorised dot products), ~1e-15 relative; the spectra themselves as in me_kernel.
_PROJECT_FASTMATH = {"contract", "reassoc", "arcp", "nsz"}


@nb.njit(parallel=True, cache=True, fastmath=_PROJECT_FASTMATH)
def me_project_kernel(vgrid, vshift, vzeeman, cosg, qfac, ufac, bmu, scale, eta0, damping,
                      tab_re, tab_im, weights, out):
    """
    Fill ``out`` (n_out, npix) float64 with the Stokes spectra contracted with ``weights``.

    ``out[o, p] = Σ_j Σ_s weights[o, s, j] S_s(p, λ_j)`` with S = (I, Q, U, V) of
    column p as `me_kernel` computes them (in float64, held for one column
    only): e.g. the six channel integrals of the I±V analysis.  Inputs as in
    `me_kernel`; ``weights`` is (n_out, 4, nλ) float64.  Columns are
    independent, so the result does not depend on the number of threads.
    """
    n_out = weights.shape[0]
    nl = vgrid.size
    npix = vshift.size
    # Stokes parameters an output does not use (zero weights: Q and U of the I±V analysis) are
    # skipped; leaving out exact zeros does not change the sum.
    used = np.zeros((n_out, 4), dtype=np.bool_)
    for o in range(n_out):
        for s in range(4):
            for j in range(nl):
                if weights[o, s, j] != 0.0:
                    used[o, s] = True
    chunk = 64
    for c in nb.prange((npix + chunk - 1) // chunk):
        spectrum = np.empty((4, nl))
        for p in range(c * chunk, min(npix, (c + 1) * chunk)):
            for j in range(nl):
                si, sq, su, sv = _unno_rachkovsky(vgrid[j] - vshift[p], vzeeman[p], cosg[p], qfac[p],
                                                  ufac[p], bmu[p], scale[p], eta0, damping, tab_re, tab_im)
                spectrum[0, j] = si
                spectrum[1, j] = sq
                spectrum[2, j] = su
                spectrum[3, j] = sv
            for o in range(n_out):
                acc = 0.0
                for s in range(4):
                    if used[o, s]:
                        for j in range(nl):
                            acc += weights[o, s, j] * spectrum[s, j]
                out[o, p] = acc
