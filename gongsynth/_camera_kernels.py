"""
Numba kernels of the frame-by-frame camera engine (private).

Random numbers come from a counter-free but *per-pixel* stream: pixel ``i``
(its index in the full detector, row-major) gets its own xoshiro256** state,
seeded by SplitMix64 hashing of (seed key, i).  A pixel's numbers therefore do
not depend on which chunk or thread processes it, and a pixel is always
processed by one thread from its first frame to its last.

Samplers:

* Poisson: Hörmann's PTRS transformed rejection (1993) for λ ≥ 10 (the
  algorithm numpy uses, exact), Knuth's multiplication method below.
* Normal: Marsaglia's polar method, the second value kept for the next call.
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
_LAM, _SLAM, _LOGLAM, _B, _A, _INVALPHA, _VR, _ENLAM = range(8)
N_CONST = 8


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


@njit(inline="always")
def _normal(s, spare):
    """Standard normal; ``spare[0]`` flags a stored value in ``spare[1]``."""
    if spare[0] != 0.0:
        spare[0] = 0.0
        return spare[1]
    while True:
        x = 2.0 * _uniform(s) - 1.0
        y = 2.0 * _uniform(s) - 1.0
        r2 = x * x + y * y
        if 0.0 < r2 < 1.0:
            break
    f = math.sqrt(-2.0 * math.log(r2) / r2)
    spare[0] = 1.0
    spare[1] = y * f
    return x * f


@njit(inline="always")
def _poisson_constants(lam, c):
    """Fill ``c`` (length N_CONST) with the sampler constants for mean ``lam``."""
    c[_LAM] = lam
    if lam >= 10.0:
        slam = math.sqrt(lam)
        b = 0.931 + 2.53 * slam
        c[_SLAM] = slam
        c[_LOGLAM] = math.log(lam)
        c[_B] = b
        c[_A] = -0.059 + 0.02483 * b
        c[_INVALPHA] = math.log(1.1239 + 1.1328 / (b - 3.4))  # stored as its log
        c[_VR] = 0.9277 - 3.6224 / (b - 2.0)
    else:
        c[_ENLAM] = math.exp(-lam)


@njit(inline="always")
def _poisson(s, c):
    """Exact Poisson variate with the constants ``c`` of `_poisson_constants`."""
    lam = c[_LAM]
    if lam >= 10.0:
        b = c[_B]
        a = c[_A]
        while True:
            u = _uniform(s) - 0.5
            v = _uniform(s)
            us = 0.5 - abs(u)
            k = float(math.floor((2.0 * a / us + b) * u + lam + 0.43))
            if us >= 0.07 and v <= c[_VR]:
                return k
            if k < 0 or (us < 0.013 and v > us):
                continue
            if (math.log(v) + c[_INVALPHA] - math.log(a / (us * us) + b)
                    <= -lam + k * c[_LOGLAM] - math.lgamma(k + 1.0)):
                return k
    if lam <= 0.0:
        return 0.0
    enlam = c[_ENLAM]
    k = 0.0
    prod = _uniform(s)
    while prod > enlam:
        k += 1.0
        prod *= _uniform(s)
    return k


@njit(parallel=True, cache=True)
def frames_kernel(lam, seg_start, seg_snap, plane, dither, inv_gain, sigma, key0, key1, first, out):
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
        Read noise, ADU.
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
        spare = np.zeros(2)
        const = np.zeros((n_planes, N_CONST))
        acc = np.zeros(n_planes, np.int64)
        for j in range(seg_snap.size):
            snap = seg_snap[j]
            for p in range(n_planes):
                _poisson_constants(lam[snap, p, i], const[p])
            for k in range(seg_start[j], seg_start[j + 1]):
                p = plane[k]
                x = _poisson(state, const[p]) * inv_gain + sigma * _normal(state, spare)
                acc[p] += np.int64(math.floor(x + 0.5)) + dither[k]
        for p in range(n_planes):
            out[p, i] = acc[p]


@njit(cache=True)
def poisson_kernel(lam, key0, key1, index):
    """Poisson variates of means ``lam`` (1-D) from stream ``index`` (for tests)."""
    state = np.empty(4, np.uint64)
    _seed(state, key0, key1, _U(index))
    c = np.zeros(N_CONST)
    out = np.empty(lam.size)
    for i in range(lam.size):
        _poisson_constants(lam[i], c)
        out[i] = _poisson(state, c)
    return out


@njit(cache=True)
def normal_kernel(n, key0, key1, index):
    """``n`` standard normal variates from stream ``index`` (for tests)."""
    state = np.empty(4, np.uint64)
    _seed(state, key0, key1, _U(index))
    spare = np.zeros(2)
    out = np.empty(n)
    for i in range(n):
        out[i] = _normal(state, spare)
    return out
