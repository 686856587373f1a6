"""
Numba kernels of the frame-by-frame camera engine and its samplers.

Random numbers come from one stream per pixel: pixel ``i`` (its index in the
full detector, row-major) gets its own xoshiro256** state, seeded by SplitMix64
hashing of (seed key, i).  Every variate of a pixel is a fixed function of its
own stream and its own means, so the result does not depend on which chunk,
block or thread processes it.

Pixels are processed in blocks of `LANES`, frame by frame, with the block's
states in structure-of-arrays form so that the common path vectorises across
pixels (`_fast_pass`).  Each frame draws two 64-bit numbers per pixel, r1 and
r2; a pixel whose draws leave the common path (a ziggurat draw outside its
layer's rectangle, a Poisson draw that needs more than PD's steps I and S, or
a mean that uses inversion) is finished by `_complete`, the whole algorithm,
which continues from the same two draws on the same stream.

Samplers:

* Normal: Marsaglia & Tsang's 128-layer ziggurat (2000) on one 64-bit draw
  (layer: bits 0-6, sign: bit 7, 52-bit abscissa: bits 8-59), exact wedges
  and tail.  z1 (Poisson) comes from r1, z2 (read noise) from r2.
* Poisson, mean λ ≥ `PD_MIN_LAM` (and λ = 0): Ahrens & Dieter's algorithm PD
  (1982, ACM TOMS 8, 163; the one R uses): g = λ + √λ z1, k = ⌊g⌋ is accepted
  at once if k ≥ L (step I) or after the cubic squeeze 6λ²u ≥ (λ − k)³ (step
  S); the rest is corrected exactly against the Poisson probabilities (steps
  Q, E, H; log k! by its Stirling series, |error| < 1e-12).  PD's uniform u
  has 52 bits: the top 8 are bits 60-63 of r1 and r2 (unused by the
  ziggurat), the low 44 come from one more draw taken only when the top 8 do
  not decide step S.  Since u ≥ u8/256, D·u8/256 ≥ (λ − k)³ implies
  D·u ≥ (λ − k)³ in floating point too (rounding is monotone), so the
  decision is the one the full uniform would give: the variate is exactly
  PD's with a 52-bit uniform.
* Poisson, 0 < λ < `PD_MIN_LAM`: inversion of the cumulative distribution
  tabulated up to λ + 10√λ + 10 (the tail beyond holds < 1e-19 and is
  renormalised away), searched from a guide table, with u from r1.
"""
import math

import numpy as np
from numba import njit, prange

__all__ = ["frames_kernel", "sample_kernel", "LANES", "PD_MIN_LAM"]

_U = np.uint64
_GOLDEN = _U(0x9E3779B97F4A7C15)
_M1 = _U(0xBF58476D1CE4E5B9)
_M2 = _U(0x94D049BB133111EB)
_TO_UNIT52 = 1.0 / 4503599627370496.0  # 2**-52

#: Pixels per block of the vectorised frame loop.
LANES = 64
#: Means from this up (and 0) use algorithm PD, smaller ones inversion.
PD_MIN_LAM = 10.0
# Longest inversion table: λ + 10√λ + 10 < 51.7 for λ < 10.
TABLE_LEN = 52

# Rows of the per-block constants (N_CONST, n_planes, LANES).
_LAM, _SLAM, _BIGL, _D, _LOGLAM, _OMEGA, _C0, _C1, _C2, _C3, _CHAT, _M, _SLOT = range(13)
N_CONST = 13
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
def _seed(st, lane, key0, key1, index):
    """xoshiro256** state of stream ``index`` into ``st[:, lane]`` (SplitMix64 of a hashed key)."""
    z = _mix64(key0 ^ _mix64(index + key1))
    for m in range(4):
        z += _GOLDEN
        st[m, lane] = _mix64(z)


@njit(inline="always")
def _step(s0, s1, s2, s3):
    """xoshiro256**: (output, next state) of state (s0, s1, s2, s3)."""
    result = _rotl(s1 * _U(5), 7) * _U(9)
    t = s1 << _U(17)
    s2 ^= s0
    s3 ^= s1
    s1 ^= s2
    s0 ^= s3
    s2 ^= t
    return result, s0, s1, s2, _rotl(s3, 45)


@njit(inline="always")
def _next(st, lane):
    """Next 64-bit output of the stream in ``st[:, lane]``."""
    s0 = st[0, lane]
    s1 = st[1, lane]
    s2 = st[2, lane]
    s3 = st[3, lane]
    result = _rotl(s1 * _U(5), 7) * _U(9)
    t = s1 << _U(17)
    s2 ^= s0
    s3 ^= s1
    s1 ^= s2
    s0 ^= s3
    s2 ^= t
    st[0, lane] = s0
    st[1, lane] = s1
    st[2, lane] = s2
    st[3, lane] = _rotl(s3, 45)
    return result


@njit(inline="always")
def _uniform(st, lane):
    """Uniform double in the open interval (0, 1), on a 2**-52 grid."""
    return (np.float64(_next(st, lane) >> _U(12)) + 0.5) * _TO_UNIT52


def _ziggurat_constants(n):
    """(r, v) of the n-layer normal ziggurat: base-strip edge and common layer area (bisection)."""
    def excess(r):
        v = r * math.exp(-0.5 * r * r) + math.sqrt(math.pi / 2) * math.erfc(r / math.sqrt(2))
        d = r
        for _ in range(n - 2):
            a = v / d + math.exp(-0.5 * d * d)
            if a >= 1.0:
                return 1.0, v  # the layers reach the top too early: r is too small
            d = math.sqrt(-2.0 * math.log(a))
        return v / d + math.exp(-0.5 * d * d) - 1.0, v

    lo, hi = 2.0, 6.0
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if excess(mid)[0] > 0 else (lo, mid)
    return lo, excess(lo)[1]


def _ziggurat_tables(n):
    """Marsaglia & Tsang (2000) tables for the n-layer normal ziggurat on 52-bit integers."""
    r, v = _ziggurat_constants(n)
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


# 1024 layers: 0.43 % of draws fall outside their layer's rectangle (2.8 % with 128).
_ZBITS = 10
_ZK, _ZW, _ZF, _ZR = _ziggurat_tables(1 << _ZBITS)
_ZLAYER = _U((1 << _ZBITS) - 1)
_ZMASK = _U(0xFFFFFFFFFFFFF)  # 52 bits


@njit(inline="always")
def _rectangle(r):
    """(inside, x): the ziggurat's common case for draw ``r``; x is the variate if inside."""
    i = r & _ZLAYER
    j = (r >> _U(_ZBITS + 1)) & _ZMASK
    x = np.float64(j) * _ZW[i]
    x = -x if (r >> _U(_ZBITS)) & _U(1) else x
    return j < _ZK[i], x


@njit(cache=True)
def _normal(st, lane, r):
    """Standard normal variate from draw ``r``, continuing stream ``lane`` if it needs more."""
    while True:
        i = np.int64(r & _ZLAYER)
        sign = (r >> _U(_ZBITS)) & _U(1)
        j = (r >> _U(_ZBITS + 1)) & _ZMASK
        x = np.float64(j) * _ZW[i]
        if j < _ZK[i]:
            return -x if sign else x
        if i == 0:
            # Tail beyond r (Marsaglia 1964).
            while True:
                xt = -math.log(_uniform(st, lane)) / _ZR
                yt = -math.log(_uniform(st, lane))
                if yt + yt >= xt * xt:
                    break
            return -(_ZR + xt) if sign else _ZR + xt
        if _ZF[i] + _uniform(st, lane) * (_ZF[i - 1] - _ZF[i]) < math.exp(-0.5 * x * x):
            return -x if sign else x
        r = _next(st, lane)


@njit(inline="always")
def _log_factorial(k):
    """Log k! (Stirling series beyond k = 9, |error| < 1e-12)."""
    if k < 9.0:
        return math.lgamma(k + 1.0)
    x = k + 1.0
    r = 1.0 / (x * x)
    series = (1.0 / 12.0 - r * (1.0 / 360.0 - r * (1.0 / 1260.0 - r / 1680.0))) / x
    return (x - 0.5) * math.log(x) - x + 0.9189385332046728 + series


@njit(cache=True)
def _poisson_constants(lam, c, p, lane, cdf, guide, slot):
    """
    Fill ``c[:, p, lane]`` to draw Poisson variates of mean ``lam``.

    A mean below `PD_MIN_LAM` gets its cumulative distribution in ``cdf[slot]``
    and guide table in ``guide[slot]``; its L and D are NaN so that the
    common path (`_fast_pass`) always leaves it to `_complete`.  λ = 0 runs
    through PD's constants, which give 0 on the common path.
    """
    c[_LAM, p, lane] = lam
    c[_M, p, lane] = 0.0
    if lam >= PD_MIN_LAM or lam <= 0.0:
        lam = max(lam, 0.0)
        slam = math.sqrt(lam)
        c[_SLAM, p, lane] = slam
        # p_k ≥ f_k (the discretised normal) for every k ≥ L: immediate acceptance.
        c[_BIGL, p, lane] = math.floor(lam - 1.1484)
        c[_D, p, lane] = 6.0 * lam * lam
        if lam > 0.0:
            c[_LOGLAM, p, lane] = math.log(lam)
            # Hermite-corrected discrete normal probabilities f_k and the hat constant.
            b1 = 1.0 / (24.0 * lam)
            b2 = 0.3 * b1 * b1
            c3 = b1 * b2 / 7.0
            c[_OMEGA, p, lane] = _INV_SQRT_2PI / slam
            c[_C3, p, lane] = c3
            c[_C2, p, lane] = b2 - 15.0 * c3
            c[_C1, p, lane] = b1 - 6.0 * b2 + 45.0 * c3
            c[_C0, p, lane] = 1.0 - b1 + 3.0 * b2 - 15.0 * c3
            c[_CHAT, p, lane] = 0.1069 / lam
        return
    c[_SLAM, p, lane] = 0.0
    c[_BIGL, p, lane] = np.nan
    c[_D, p, lane] = np.nan
    c[_SLOT, p, lane] = slot
    m = min(int(lam + 10.0 * math.sqrt(lam) + 10.0), TABLE_LEN)
    pk = math.exp(-lam)
    total = 0.0
    for k in range(m):
        if k > 0:
            pk *= lam / k
        total += pk
        cdf[slot, k] = total
    # Renormalise away the < 1e-19 tail beyond the table: cdf[m - 1] = 1 > any u.
    for k in range(m):
        cdf[slot, k] /= total
    cdf[slot, m - 1] = 1.0
    # guide[j] = smallest k with cdf[k] >= j / m: where the search for u in [j/m, (j+1)/m) starts.
    k = 0
    for j in range(m):
        while cdf[slot, k] < j / m:
            k += 1
        guide[slot, j] = k
    c[_M, p, lane] = m


@njit(inline="always")
def _pk_fk(c, p, lane, k):
    """Poisson probability p_k and discrete-normal probability f_k (algorithm PD)."""
    lam = c[_LAM, p, lane]
    pk = math.exp(-lam + k * c[_LOGLAM, p, lane] - _log_factorial(k))
    x = (k + 0.5 - lam) / c[_SLAM, p, lane]
    x *= x
    fk = c[_OMEGA, p, lane] * math.exp(-0.5 * x) * (
        ((c[_C3, p, lane] * x + c[_C2, p, lane]) * x + c[_C1, p, lane]) * x + c[_C0, p, lane])
    return pk, fk


@njit(inline="always")
def _unit(r):
    """Uniform double in (0, 1) from the top 52 bits of draw ``r``."""
    return (np.float64(r >> _U(12)) + 0.5) * _TO_UNIT52


@njit(cache=True)
def _pd_rest(st, lane, c, p, g, u):
    """Steps Q, E and H of algorithm PD (< 3 % of draws at λ ≥ 30)."""
    lam = c[_LAM, p, lane]
    if g >= 0.0:
        # Step Q: accept with probability p_k / f_k (u is reused, as in PD).
        k = np.floor(g)
        pk, fk = _pk_fk(c, p, lane, k)
        if (1.0 - u) * fk <= pk:
            return k
    # Steps E and H: double-exponential hat for the excess p_k − f_k.
    while True:
        e = -math.log(_uniform(st, lane))
        v = 2.0 * _uniform(st, lane) - 1.0
        t = 1.8 + e if v >= 0.0 else 1.8 - e
        if t > -0.6744:
            k = np.floor(lam + c[_SLAM, p, lane] * t)
            pk, fk = _pk_fk(c, p, lane, k)
            if c[_CHAT, p, lane] * abs(v) <= (pk - fk) * math.exp(e):
                return k


@njit(cache=True)
def _complete(st, lane, r1, r2, r3, c, p, cdf, guide, photon):
    """
    (electrons, read-noise normal) of one pixel-frame from its three draws, by the whole algorithm.

    Further draws continue the pixel's stream in a fixed order: the rest of
    z1 (PD means only), of z2, then PD's steps E and H.
    """
    lam = c[_LAM, p, lane]
    if not photon:
        return lam, _normal(st, lane, r2)
    u = _unit(r3)
    m = c[_M, p, lane]
    if m > 0.0:
        z2 = _normal(st, lane, r2)
        # Inversion: the smallest k with cdf[k] >= u, searched from the guide entry.
        slot = np.int64(c[_SLOT, p, lane])
        k = guide[slot, min(np.int64(u * m), np.int64(m) - 1)]
        while cdf[slot, k] < u:
            k += 1
        return np.float64(k), z2
    z1 = _normal(st, lane, r1)
    z2 = _normal(st, lane, r2)
    # Step N: normal sample; steps I and S: immediate and squeeze acceptance.
    g = lam + c[_SLAM, p, lane] * z1
    k = np.floor(g)
    diff = lam - k
    if (g >= 0.0) & ((k >= c[_BIGL, p, lane]) | (c[_D, p, lane] * u >= diff * diff * diff)):
        return k, z2
    return _pd_rest(st, lane, c, p, g, u), z2


@njit(inline="always")
def _fast_pass(st, c, p, photon, draws, n_out, z_out, flag):
    """
    One frame of a block: three draws per pixel and the common path of every sampler.

    Writes the draws, the electrons and read-noise normal of each pixel and
    whether `_complete` must redo it (``flag``, one byte per pixel); returns
    the number of such pixels.  Branch-free, so that it vectorises across the
    block.
    """
    lam = c[_LAM, p]
    slam = c[_SLAM, p]
    bigl = c[_BIGL, p]
    dd = c[_D, p]
    bad = 0
    for lane in range(st.shape[1]):
        # The state stays in registers for the three draws.
        r1, s0, s1, s2, s3 = _step(st[0, lane], st[1, lane], st[2, lane], st[3, lane])
        r2, s0, s1, s2, s3 = _step(s0, s1, s2, s3)
        r3, s0, s1, s2, s3 = _step(s0, s1, s2, s3)
        st[0, lane] = s0
        st[1, lane] = s1
        st[2, lane] = s2
        st[3, lane] = s3
        ok1, z1 = _rectangle(r1)
        ok2, z2 = _rectangle(r2)
        g = lam[lane] + slam[lane] * z1
        k = np.floor(g)
        diff = lam[lane] - k
        u = _unit(r3)
        accept = ok1 & (g >= 0.0) & ((k >= bigl[lane]) | (dd[lane] * u >= diff * diff * diff))
        accept = accept if photon else True
        draws[0, lane] = r1
        draws[1, lane] = r2
        draws[2, lane] = r3
        n_out[lane] = k if photon else lam[lane]
        z_out[lane] = z2
        f = np.uint8(not (accept & ok2))
        flag[lane] = f
        bad += f
    return bad


@njit(inline="always")
def _frame(st, c, p, cdf, guide, photon, reference, draws, n_out, z_out, flag):
    """Electrons and read-noise normal of one frame of a block into ``n_out``, ``z_out``."""
    if reference:
        for lane in range(st.shape[1]):
            r1 = _next(st, lane)
            r2 = _next(st, lane)
            r3 = _next(st, lane)
            n_out[lane], z_out[lane] = _complete(st, lane, r1, r2, r3, c, p, cdf, guide, photon)
        return
    if _fast_pass(st, c, p, photon, draws, n_out, z_out, flag):
        # Eight flags per word: skip the (mostly clean) words at once.
        words = flag.view(np.uint64)
        for w in range(words.size):
            if words[w]:
                for lane in range(8 * w, 8 * w + 8):
                    if flag[lane]:
                        n_out[lane], z_out[lane] = _complete(st, lane, draws[0, lane], draws[1, lane],
                                                             draws[2, lane], c, p, cdf, guide, photon)


@njit(inline="always")
def _block_start(key0, key1, first, n_planes):
    """Seeded states and the work arrays of one block starting at detector index ``first``."""
    st = np.empty((4, LANES), np.uint64)
    for lane in range(LANES):
        _seed(st, lane, key0, key1, _U(first + lane))
    return (st, np.zeros((N_CONST, n_planes, LANES)), np.empty((3, LANES), np.uint64),
            np.empty(LANES), np.empty(LANES), np.zeros(LANES, np.uint8))


@njit(inline="always")
def _block_means(means, c, p, lanes, cdf, guide, used):
    """Constants of the block's ``means`` (first ``lanes`` real, the rest 0) in plane ``p``."""
    for lane in range(LANES):
        mean = means[lane] if lane < lanes else 0.0
        _poisson_constants(mean, c, p, lane, cdf, guide, used)
        if c[_M, p, lane] > 0.0:
            used += 1
    return used


@njit(inline="always")
def _count_small(means, lanes):
    n = 0
    for lane in range(lanes):
        n += (means[lane] > 0.0) & (means[lane] < PD_MIN_LAM)
    return n


@njit(parallel=True, cache=True, error_model="numpy")
def frames_kernel(lam, seg_start, seg_snap, plane, dither, inv_gain, sigma, photon, key0, key1, first, out):
    """
    Accumulate every frame of every pixel of a chunk.

    Parameters
    ----------
    lam : float64 (n_snap, n_planes, n_pix)
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
    out : int64 (n_planes, n_pix)
        Receives the accumulated sums Σ (round((P + read noise) / gain) + dither).
    """
    n_pix = lam.shape[2]
    n_planes = lam.shape[1]
    dither_sum = np.zeros(n_planes, np.int64)
    for k in range(plane.size):
        dither_sum[plane[k]] += dither[k]
    for b in prange((n_pix + LANES - 1) // LANES):
        i0 = b * LANES
        lanes = min(LANES, n_pix - i0)
        st, c, draws, n_out, z_out, flag = _block_start(key0, key1, first + i0, n_planes)
        acc = np.zeros((n_planes, LANES), np.int64)
        for j in range(seg_snap.size):
            snap = seg_snap[j]
            small = 0
            for p in range(n_planes):
                small += _count_small(lam[snap, p, i0:i0 + lanes], lanes)
            cdf = np.empty((small, TABLE_LEN))
            guide = np.empty((small, TABLE_LEN), np.int32)
            used = 0
            for p in range(n_planes):
                used = _block_means(lam[snap, p, i0:i0 + lanes], c, p, lanes, cdf, guide, used)
            for k in range(seg_start[j], seg_start[j + 1]):
                p = plane[k]
                _frame(st, c, p, cdf, guide, photon, False, draws, n_out, z_out, flag)
                for lane in range(LANES):
                    acc[p, lane] += np.int64(math.floor(n_out[lane] * inv_gain + sigma * z_out[lane] + 0.5))
        for p in range(n_planes):
            for lane in range(lanes):
                out[p, i0 + lane] = acc[p, lane] + dither_sum[p]


@njit(parallel=True, cache=True, error_model="numpy")
def sample_kernel(lam, n_frames, key0, key1, first, photon=True, reference=False):
    """
    The engine's variates themselves, for tests: ``n_frames`` frames of pixels of means ``lam``.

    Parameters
    ----------
    lam : float64 (n_pix,)
        Mean electrons of each pixel (one plane).
    n_frames : int
    key0, key1 : uint64
        Seed keys.
    first : int
        Detector index of the first pixel.
    photon : bool
        As in `frames_kernel`.
    reference : bool
        Run the whole algorithm (`_complete`) for every pixel-frame instead of
        the vectorised common path: the results must be the same bits.

    Returns
    -------
    electrons, normal : float64 (n_frames, n_pix)
        Poisson variates (λ itself if not ``photon``) and read-noise normal variates.
    """
    n_pix = lam.size
    electrons = np.empty((n_frames, n_pix))
    normal = np.empty((n_frames, n_pix))
    for b in prange((n_pix + LANES - 1) // LANES):
        i0 = b * LANES
        lanes = min(LANES, n_pix - i0)
        st, c, draws, n_out, z_out, flag = _block_start(key0, key1, first + i0, 1)
        small = _count_small(lam[i0:i0 + lanes], lanes)
        cdf = np.empty((small, TABLE_LEN))
        guide = np.empty((small, TABLE_LEN), np.int32)
        _block_means(lam[i0:i0 + lanes], c, 0, lanes, cdf, guide, 0)
        for k in range(n_frames):
            _frame(st, c, 0, cdf, guide, photon, reference, draws, n_out, z_out, flag)
            for lane in range(lanes):
                electrons[k, i0 + lane] = n_out[lane]
                normal[k, i0 + lane] = z_out[lane]
    return electrons, normal
