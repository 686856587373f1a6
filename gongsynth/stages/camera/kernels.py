"""
Numba kernels of the frame-by-frame camera engine and its samplers.

Random numbers come from one stream per pixel: pixel ``i`` (its index in the
full detector, row-major) gets its own xoshiro256** state, seeded by SplitMix64
hashing of (seed key, i).  A pixel's numbers therefore do not depend on which
chunk or thread processes it, and a pixel is always processed by one thread
from its first frame to its last.

Samplers:

* Poisson, mean λ ≤ 500: inversion of the cumulative distribution, tabulated
  once per pixel and plane up to λ + 10√λ + 10 (the tail beyond holds
  < 1e-19 and is renormalised away), searched from a guide table: one uniform
  and one or two comparisons per draw.
* Poisson, λ > 500: Ahrens & Dieter's algorithm PD (1982, ACM TOMS 8, 163; the
  one R uses): a normal deviate rounded down is accepted at once or after a
  cubic squeeze in > 99 % of cases, the rest is corrected exactly against the
  Poisson probabilities (log k! by its Stirling series, |error| < 1e-12).
* Normal: Marsaglia & Tsang's 128-layer ziggurat (2000) on 64-bit draws (layer,
  sign and 52-bit abscissa from disjoint bits), exact tail.
"""
import math

import numpy as np
from numba import njit, prange

__all__ = ["frames_kernel", "poisson_kernel", "normal_kernel"]

_U = np.uint64
_GOLDEN = _U(0x9E3779B97F4A7C15)
_M1 = _U(0xBF58476D1CE4E5B9)
_M2 = _U(0x94D049BB133111EB)
_TO_UNIT = 1.0 / 9007199254740992.0  # 2**-53

# Columns of the per-plane Poisson constants table.
_LAM, _SLAM, _LOGLAM, _BIGL, _D, _OMEGA, _C0, _C1, _C2, _C3, _CHAT, _M = range(12)
N_CONST = 12
# Means up to this use the tabulated inversion, above it algorithm PD.
TABLE_MAX_LAM = 500.0
# Longest table: λ + 10√λ + 10 at λ = TABLE_MAX_LAM is 733.6.
TABLE_LEN = 736
_INV_SQRT_2PI = 0.3989422804014327


@njit(inline="always")
def _mix64(z):
    z = (z ^ (z >> _U(30))) * _M1
    z = (z ^ (z >> _U(27))) * _M2
    return z ^ (z >> _U(31))


@njit(inline="always")
def _rotl(x, k):
    return (x << _U(k)) | (x >> _U(64 - k))


@njit(inline="always")
def _seed(state, key0, key1, index):
    """xoshiro256** state of stream ``index`` (SplitMix64 expansion of a hashed key)."""
    z = _mix64(key0 ^ _mix64(index + key1))
    for m in range(4):
        z += _GOLDEN
        state[m] = _mix64(z)


@njit(inline="always")
def _next(s):
    result = _rotl(s[1] * _U(5), 7) * _U(9)
    t = s[1] << _U(17)
    s[2] ^= s[0]
    s[3] ^= s[1]
    s[1] ^= s[2]
    s[0] ^= s[3]
    s[2] ^= t
    s[3] = _rotl(s[3], 45)
    return result


@njit(inline="always")
def _uniform(s):
    """Uniform double in the open interval (0, 1)."""
    return (np.float64(_next(s) >> _U(11)) + 0.5) * _TO_UNIT


def _ziggurat_tables(n=128, r=3.442619855899, v=9.91256303526217e-3):
    """Marsaglia & Tsang (2000) tables for the normal ziggurat on 52-bit integers."""
    m = 2.0**52
    k = np.zeros(n, np.uint64)
    w = np.zeros(n)
    f = np.zeros(n)
    d = t = r
    q = v / math.exp(-0.5 * d * d)
    k[0] = np.uint64((d / q) * m)
    k[1] = 0
    w[0] = q / m
    w[n - 1] = d / m
    f[0] = 1.0
    f[n - 1] = math.exp(-0.5 * d * d)
    for i in range(n - 2, 0, -1):
        d = math.sqrt(-2.0 * math.log(v / d + math.exp(-0.5 * d * d)))
        k[i + 1] = np.uint64((d / t) * m)
        t = d
        f[i] = math.exp(-0.5 * d * d)
        w[i] = d / m
    return k, w, f, r


_ZK, _ZW, _ZF, _ZR = _ziggurat_tables()
_ZMASK = _U(0xFFFFFFFFFFFFF)  # 52 bits


@njit(inline="always")
def _normal(s):
    """Standard normal variate (ziggurat: ~99 % of calls cost one 64-bit draw)."""
    r = _next(s)
    i = np.int64(r & _U(127))
    j = (r >> _U(8)) & _ZMASK
    if j < _ZK[i]:
        x = np.float64(j) * _ZW[i]
        return -x if (r >> _U(7)) & _U(1) else x
    return _normal_rare(s, r)


@njit(cache=True)
def _normal_rare(s, r):
    """Wedge and tail of the ziggurat for a draw ``r`` outside its layer's rectangle.

    Kept out of line: its exp/log calls in the hot loop cost ~15 % of the kernel's time.
    """
    while True:
        i = np.int64(r & _U(127))
        sign = (r >> _U(7)) & _U(1)
        j = (r >> _U(8)) & _ZMASK
        x = np.float64(j) * _ZW[i]
        if j < _ZK[i]:
            return -x if sign else x
        if i == 0:
            # Tail beyond r (Marsaglia 1964).
            while True:
                xt = -math.log(_uniform(s)) / _ZR
                yt = -math.log(_uniform(s))
                if yt + yt >= xt * xt:
                    break
            return -(_ZR + xt) if sign else _ZR + xt
        if _ZF[i] + _uniform(s) * (_ZF[i - 1] - _ZF[i]) < math.exp(-0.5 * x * x):
            return -x if sign else x
        r = _next(s)


@njit(inline="always")
def _log_factorial(k):
    """Log k! (Stirling series beyond k = 9, |error| < 1e-12)."""
    if k < 9.0:
        return math.lgamma(k + 1.0)
    x = k + 1.0
    r = 1.0 / (x * x)
    series = (1.0 / 12.0 - r * (1.0 / 360.0 - r * (1.0 / 1260.0 - r / 1680.0))) / x
    return (x - 0.5) * math.log(x) - x + 0.9189385332046728 + series


@njit(inline="always")
def _poisson_constants(lam, c, p, cdf, guide, table_max):
    """
    Prepare row ``p`` of ``c`` (n, N_CONST) to draw Poisson variates of mean ``lam``.

    Means up to ``table_max`` get the cumulative distribution in ``cdf[p]`` and
    its guide table in ``guide[p]`` (length ``c[p, _M]``); larger ones the
    constants of algorithm PD.
    """
    c[p, _LAM] = lam
    c[p, _M] = 0.0
    if lam > table_max:
        slam = math.sqrt(lam)
        c[p, _SLAM] = slam
        c[p, _LOGLAM] = math.log(lam)
        # p_k ≥ f_k (the discretised normal) for every k ≥ L: immediate acceptance.
        c[p, _BIGL] = math.floor(lam - 1.1484)
        c[p, _D] = 6.0 * lam * lam
        # Hermite-corrected discrete normal probabilities f_k and the hat constant.
        b1 = 1.0 / (24.0 * lam)
        b2 = 0.3 * b1 * b1
        c3 = b1 * b2 / 7.0
        c[p, _OMEGA] = _INV_SQRT_2PI / slam
        c[p, _C3] = c3
        c[p, _C2] = b2 - 15.0 * c3
        c[p, _C1] = b1 - 6.0 * b2 + 45.0 * c3
        c[p, _C0] = 1.0 - b1 + 3.0 * b2 - 15.0 * c3
        c[p, _CHAT] = 0.1069 / lam
    elif lam > 0.0:
        m = min(int(lam + 10.0 * math.sqrt(lam) + 10.0), TABLE_LEN)
        pk = math.exp(-lam)
        total = 0.0
        for k in range(m):
            if k > 0:
                pk *= lam / k
            total += pk
            cdf[p, k] = total
        # Renormalise away the < 1e-20 tail beyond the table: cdf[m - 1] = 1 > any u.
        for k in range(m):
            cdf[p, k] /= total
        cdf[p, m - 1] = 1.0
        # guide[j] = smallest k with cdf[k] >= j / m: where the search for u in [j/m, (j+1)/m) starts.
        k = 0
        for j in range(m):
            while cdf[p, k] < j / m:
                k += 1
            guide[p, j] = k
        c[p, _M] = m


@njit(inline="always")
def _pk_fk(c, p, k):
    """Poisson probability p_k and discrete-normal probability f_k (algorithm PD)."""
    lam = c[p, _LAM]
    pk = math.exp(-lam + k * c[p, _LOGLAM] - _log_factorial(k))
    x = (k + 0.5 - lam) / c[p, _SLAM]
    x *= x
    fk = c[p, _OMEGA] * math.exp(-0.5 * x) * (((c[p, _C3] * x + c[p, _C2]) * x + c[p, _C1]) * x
                                              + c[p, _C0])
    return pk, fk


@njit(inline="always")
def _poisson(s, c, p, cdf, guide):
    """Exact Poisson variate with the constants in row ``p`` of ``c`` (`_poisson_constants`)."""
    m = c[p, _M]
    if m > 0.0:
        # Inversion: the smallest k with cdf[k] >= u, searched from the guide entry.
        u = _uniform(s)
        k = guide[p, min(np.int64(u * m), np.int64(m) - 1)]
        while cdf[p, k] < u:
            k += 1
        return np.float64(k)
    lam = c[p, _LAM]
    if lam <= 0.0:
        return 0.0
    # Step N: normal sample; steps I and S: immediate and squeeze acceptance.
    g = lam + c[p, _SLAM] * _normal(s)
    u = _uniform(s)  # drawn even when step I accepts: one predictable branch
    k = np.floor(g)
    diff = lam - k
    if (g >= 0.0) & ((k >= c[p, _BIGL]) | (c[p, _D] * u >= diff * diff * diff)):
        return k
    return _poisson_rare(s, c, p, g, u)


@njit(cache=True)
def _poisson_rare(s, c, p, g, u):
    """Steps Q, E and H of algorithm PD (< 1 % of calls at λ ≳ 1000); kept out of line."""
    lam = c[p, _LAM]
    if g >= 0.0:
        # Step Q: accept with probability p_k / f_k (u is reused, as in PD).
        k = np.floor(g)
        pk, fk = _pk_fk(c, p, k)
        if (1.0 - u) * fk <= pk:
            return k
    # Steps E and H: double-exponential hat for the excess p_k − f_k.
    while True:
        e = -math.log(_uniform(s))
        v = 2.0 * _uniform(s) - 1.0
        t = 1.8 + e if v >= 0.0 else 1.8 - e
        if t > -0.6744:
            k = np.floor(lam + c[p, _SLAM] * t)
            pk, fk = _pk_fk(c, p, k)
            if c[p, _CHAT] * abs(v) <= (pk - fk) * math.exp(e):
                return k


@njit(parallel=True, cache=True)
def frames_kernel(lam, seg_start, seg_snap, plane, dither, inv_gain, sigma, photon, key0, key1, first, out):
    """
    Accumulate every frame of every pixel of a chunk.

    Parameters
    ----------
    lam : float64 (n_snap, 6, n_pix)
        Mean electrons per frame (signal × flat + dark) of each snapshot.
    seg_start : int64 (n_seg + 1,)
        Frames ``seg_start[j] .. seg_start[j+1] - 1`` use snapshot ``seg_snap[j]``.
    seg_snap : int64 (n_seg,)
    plane : int64 (n_frames,)
        Plane of each frame.
    dither : int64 (n_frames,)
        Dither of each frame, ADU.
    inv_gain : float
        1 / gain, ADU per electron.
    sigma : float
        Read noise, ADU (0 for none: the normal variate is still drawn, so the
        stream is that of any other σ).
    photon : bool
        Draw the electrons of each frame from Poisson(λ); False uses λ itself
        (no photon or dark-current noise).
    key0, key1 : uint64
        Seed keys.
    first : int64
        Detector index of the chunk's first pixel.
    out : int64 (6, n_pix)
        Receives the accumulated sums Σ (round((P + read noise) / gain) + dither).
    """
    n_pix = lam.shape[2]
    n_planes = lam.shape[1]
    for i in prange(n_pix):
        state = np.empty(4, np.uint64)
        _seed(state, key0, key1, _U(first + i))
        const = np.zeros((n_planes, N_CONST))
        cdf = np.empty((n_planes, TABLE_LEN))
        guide = np.empty((n_planes, TABLE_LEN), np.int32)
        acc = np.zeros(n_planes, np.int64)
        for j in range(seg_snap.size):
            snap = seg_snap[j]
            if photon:
                for p in range(n_planes):
                    _poisson_constants(lam[snap, p, i], const, p, cdf, guide, TABLE_MAX_LAM)
            for k in range(seg_start[j], seg_start[j + 1]):
                p = plane[k]
                if photon:
                    n = _poisson(state, const, p, cdf, guide)
                else:
                    n = lam[snap, p, i]
                x = n * inv_gain + sigma * _normal(state)
                acc[p] += np.int64(math.floor(x + 0.5)) + dither[k]
        for p in range(n_planes):
            out[p, i] = acc[p]


@njit(cache=True)
def poisson_kernel(lam, key0, key1, index, table_max=TABLE_MAX_LAM):
    """
    Poisson variates of means ``lam`` (1-D) from stream ``index`` (for tests).

    ``table_max`` moves the switch from tabulated inversion to algorithm PD
    (PD is valid from λ = 10), so that both can be tested at any mean.
    """
    state = np.empty(4, np.uint64)
    _seed(state, key0, key1, _U(index))
    c = np.zeros((1, N_CONST))
    cdf = np.empty((1, TABLE_LEN))
    guide = np.empty((1, TABLE_LEN), np.int32)
    out = np.empty(lam.size)
    previous = -1.0
    for i in range(lam.size):
        if lam[i] != previous:
            _poisson_constants(lam[i], c, 0, cdf, guide, max(table_max, 10.0))
            previous = lam[i]
        out[i] = _poisson(state, c, 0, cdf, guide)
    return out


@njit(cache=True)
def normal_kernel(n, key0, key1, index):
    """``n`` standard normal variates from stream ``index`` (for tests)."""
    state = np.empty(4, np.uint64)
    _seed(state, key0, key1, _U(index))
    out = np.empty(n)
    for i in range(n):
        out[i] = _normal(state)
    return out
