r"""
The Faddeeva function w(z) = e^{−z²} erfc(−i z) for the line profiles: H = Re w, 2F = Im w.

`faddeeva` is Humlíček's (1982) W4, relative accuracy ~1e-4 (the reference
solver's).  `w_weideman` is Weideman's (1994, SIAM Journal on Numerical
Analysis 31, 1497, eq. 38-39) 16-term rational approximation, branch-free and
valid in the whole upper half plane (relative error < 5e-7 of |w(z)|, measured
against `scipy.special.wofz` for y ≥ 1e-5, |x| ≤ 60), by Estrin's scheme;
`faddeeva_fast` is it for one point (the core's optical depth).
`w_weideman32` is the same form in float32 arithmetic (relative error < 1e-6):
the fast solver's w(z), a loop over the wavelengths that the compiler
vectorises with eight lanes (``benchmarks/README.md``, "w(z) in float32").
`sigma_taylor` gives the σ components of a Zeeman triplet from w at the
π component's position (`sigma_taylor_vec`: for all wavelengths at once).
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

__all__ = ["faddeeva", "faddeeva_fast", "w_weideman", "w_weideman32", "sigma_taylor", "sigma_taylor_vec",
           "WEIDEMAN_N"]

#: Terms of Weideman's approximation (N in his eq. 38).
WEIDEMAN_N = 16


def _weideman_coefficients(n):
    """
    (L, a_0 … a_{N−1}) of Weideman (1994) eq. 38: w(z) ≈ 2 p(Z)/(L − i z)² + 1/(√π (L − i z)), p(Z) = Σ aₙ Zⁿ.

    Z = (L + i z)/(L − i z), L = √(N/√2) (his eq. 39); aₙ are the Fourier coefficients of
    e^{−t²}(L² + t²) in θ, t = L tan(θ/2), computed by the trapezoidal rule on 4N points (his §4).
    """
    m = 2 * n
    lam = math.sqrt(n / math.sqrt(2.0))
    theta = np.arange(-m + 1, m) * math.pi / m
    t = lam * np.tan(theta / 2.0)
    f = np.concatenate([[0.0], np.exp(-t * t) * (lam * lam + t * t)])
    a = np.fft.fft(np.fft.fftshift(f)).real / (2 * m)
    return lam, tuple(float(v) for v in a[1:n + 1])


_WL, _WA = _weideman_coefficients(WEIDEMAN_N)
_RSQPI = 1.0 / math.sqrt(math.pi)
_F32 = np.float32
_WL32, _WA32, _RSQPI32 = _F32(_WL), tuple(_F32(v) for v in _WA), _F32(_RSQPI)


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
def _cmul(ar, ai, br, bi):
    return ar * br - ai * bi, ar * bi + ai * br


@nb.njit(cache=True, inline="always")
def _weideman(x, y, lam, a, rsqpi, two, one):
    """Weideman's form in the precision of its constants (``lam`` = L, ``a``, 1/√π, 2, 1)."""
    lp = lam + y
    d = one / (lp * lp + x * x)
    rr = lp * d                            # 1/(L − i z) = rr + i ri
    ri = x * d
    zr = (lam * lam - y * y - x * x) * d   # Z = (L + i z)/(L − i z)
    zi = two * lam * x * d
    z2r, z2i = _cmul(zr, zi, zr, zi)
    z4r, z4i = _cmul(z2r, z2i, z2r, z2i)
    z8r, z8i = _cmul(z4r, z4i, z4r, z4i)
    # a₂ₖ + a₂ₖ₊₁ Z, then pairs of those with Z², Z⁴, Z⁸.
    tr, ti = _cmul(z2r, z2i, a[2] + a[3] * zr, a[3] * zi)
    r0r, r0i = a[0] + a[1] * zr + tr, a[1] * zi + ti
    tr, ti = _cmul(z2r, z2i, a[6] + a[7] * zr, a[7] * zi)
    r1r, r1i = a[4] + a[5] * zr + tr, a[5] * zi + ti
    tr, ti = _cmul(z2r, z2i, a[10] + a[11] * zr, a[11] * zi)
    r2r, r2i = a[8] + a[9] * zr + tr, a[9] * zi + ti
    tr, ti = _cmul(z2r, z2i, a[14] + a[15] * zr, a[15] * zi)
    r3r, r3i = a[12] + a[13] * zr + tr, a[13] * zi + ti
    tr, ti = _cmul(z4r, z4i, r1r, r1i)
    s0r, s0i = r0r + tr, r0i + ti
    tr, ti = _cmul(z4r, z4i, r3r, r3i)
    s1r, s1i = r2r + tr, r2i + ti
    tr, ti = _cmul(z8r, z8i, s1r, s1i)
    pr, pi_ = s0r + tr, s0i + ti
    sr, si = _cmul(rr, ri, rr, ri)
    qr, qi = _cmul(pr, pi_, sr, si)
    return two * qr + rsqpi * rr, two * qi + rsqpi * ri


@nb.njit(cache=True, inline="always")
def w_weideman(x, y):
    """
    Re and Im of w(x + i y), y ≥ 0, by Weideman's (1994) 16-term rational approximation.

    Relative error < 5e-7 (of |w|; < 2e-7 of w(i y)) anywhere in the upper half plane; no branch, no
    table, one division: loops of it vectorise.  p(Z) by Estrin's scheme (pairs, then Z², Z⁴, Z⁸).

    Parameters
    ----------
    x, y : float
        The argument (y ≥ 0).

    Returns
    -------
    tuple of float
        Re w, Im w.

    Examples
    --------
    >>> round(w_weideman(0.0, 0.05)[0], 6)     # scipy.special.wofz(0.05j) = 0.9459900...
    0.94599
    """
    return _weideman(x, y, _WL, _WA, _RSQPI, 2.0, 1.0)


@nb.njit(cache=True, inline="always")
def w_weideman32(x, y):
    """
    `w_weideman` in float32 arithmetic: twice the SIMD lanes, relative error < 1e-6 of |w|.

    Parameters
    ----------
    x, y : numpy.float32
        The argument (y ≥ 0).  A float64 argument is rounded to float32 first.

    Returns
    -------
    tuple of numpy.float32
        Re w, Im w.

    Examples
    --------
    >>> round(float(w_weideman32(0.0, 0.05)[0]), 6)     # scipy.special.wofz(0.05j) = 0.9459900...
    0.94599
    """
    return _weideman(_F32(x), _F32(y), _WL32, _WA32, _RSQPI32, _F32(2.0), _F32(1.0))


@nb.njit(cache=True)
def faddeeva_fast(x, y):
    """
    Re and Im of w(x + i y), y ≥ 0, by `w_weideman` (relative error < 5e-7).

    Parameters
    ----------
    x, y : float
        Real and imaginary parts of the argument (y ≥ 0).

    Returns
    -------
    tuple of float
        Re w (the Voigt function H) and Im w (the Faraday–Voigt function, 2F).

    Examples
    --------
    >>> h, f = faddeeva_fast(0.0, 0.05)
    >>> round(h, 6)                 # scipy.special.wofz(0.05j) = 0.9459900...
    0.94599
    """
    return w_weideman(x, y)


@nb.njit(cache=True, inline="always")
def sigma_taylor(x, y, vb, wr, wi):
    """
    σ components from w(z) = wr + i wi by the Taylor series in ±vb (z = x + i y, small vb).

    Derivatives from w' = −2 z w + 2i/√π, w⁽ⁿ⁺¹⁾ = −2 z w⁽ⁿ⁾ − 2 n w⁽ⁿ⁻¹⁾; terms up to vb⁷
    (error ~(1.4 vb)⁸/√8! of w: < 1e-9 for vb ≤ 0.1; the kernels take it up to their `VB_TAYLOR`).

    Parameters
    ----------
    x, y : float
        z (y ≥ 0).
    vb : float
        Zeeman shift (Doppler widths).
    wr, wi : float
        w(z).

    Returns
    -------
    tuple of float
        Re and Im of [w(z + vb) + w(z − vb)]/2 and of w(z − vb) − w(z + vb).

    Examples
    --------
    >>> from gongsynth.sun.rt.voigt import faddeeva_fast
    >>> s = sigma_taylor(0.5, 0.05, 0.01, *faddeeva_fast(0.5, 0.05))
    >>> round(s[2], 6)      # Re[w(0.49 + 0.05i) - w(0.51 + 0.05i)] = 0.0140607 (scipy)
    0.014061
    """
    zr = -2.0 * x
    zi = -2.0 * y
    d0r, d0i = wr, wi
    d1r = zr * d0r - zi * d0i
    d1i = zr * d0i + zi * d0r + 1.1283791670955126
    er, ei_, odr, odi = d0r, d0i, vb * d1r, vb * d1i
    c = vb
    for n in range(1, 7):
        d2r = zr * d1r - zi * d1i - 2.0 * n * d0r
        d2i = zr * d1i + zi * d1r - 2.0 * n * d0i
        c *= vb * (1.0 / (n + 1))
        if n % 2 == 1:
            er += c * d2r
            ei_ += c * d2i
        else:
            odr += c * d2r
            odi += c * d2i
        d0r, d0i, d1r, d1i = d1r, d1i, d2r, d2i
    return er, ei_, -2.0 * odr, -2.0 * odi


@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})
def sigma_taylor_vec(xs, y, vb, hp, fp, hs, fs, hd, fd, work):
    """
    σ profiles of all wavelengths from the π ones by `sigma_taylor`'s series.

    vb ≤ the kernels' ``VB_TAYLOR``; the same recurrence, order by order over all wavelengths (loops
    the compiler vectorises), up to the first order N whose term's bound (1.4 vb)^N/√(N!) is below
    1e-9, at most 7 (`sigma_taylor`'s): N ≤ 4 below vb = 0.006, 5 below 0.018, 6 below 0.039.  From
    `w_weideman32`'s π profiles (|x| ≤ 15, vb ≤ 0.006) both results are within 2e-6 of their peaks
    for y ≤ 1 and 6e-6 at y = 3, in the wings too (fused multiply-add only, as in the kernels).
    ``xs``, ``hp``, ``fp``: x and w(x + i y) per wavelength; out: ``hs``, ``fs``, ``hd``, ``fd`` as
    `sigma_taylor`'s four results; ``work``: (4, nλ) scratch.
    """
    nl = xs.size
    order = 1
    bound = 1.4 * vb
    while order < 7 and bound > 1e-9:
        order += 1
        bound *= 1.4 * vb / math.sqrt(order)
    d0r, d0i, d1r, d1i = work[0], work[1], work[2], work[3]
    for j in range(nl):
        zr = -2.0 * xs[j]
        d0r[j] = hp[j]
        d0i[j] = fp[j]
        d1r[j] = zr * hp[j] + 2.0 * y * fp[j]
        d1i[j] = zr * fp[j] - 2.0 * y * hp[j] + 1.1283791670955126
        hs[j] = hp[j]
        fs[j] = fp[j]
        hd[j] = vb * d1r[j]
        fd[j] = vb * d1i[j]
    c = vb
    for n in range(1, order):
        c *= vb * (1.0 / (n + 1))
        even = n % 2 == 1
        for j in range(nl):
            zr = -2.0 * xs[j]
            d2r = zr * d1r[j] + 2.0 * y * d1i[j] - 2.0 * n * d0r[j]
            d2i = zr * d1i[j] - 2.0 * y * d1r[j] - 2.0 * n * d0i[j]
            d0r[j] = d1r[j]
            d0i[j] = d1i[j]
            d1r[j] = d2r
            d1i[j] = d2i
            if even:
                hs[j] += c * d2r
                fs[j] += c * d2i
            else:
                hd[j] += c * d2r
                fd[j] += c * d2i
    for j in range(nl):
        hd[j] *= -2.0
        fd[j] *= -2.0
