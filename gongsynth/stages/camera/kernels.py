"""
Numba kernels of the frame-by-frame camera engine and its samplers.

Random numbers come from one stream per pixel: pixel ``i`` (its index in the
full detector, row-major) gets its own xoshiro256** state, seeded by SplitMix64
hashing of (seed key, i).  Every variate of a pixel is a fixed function of its
own stream and its own means, so the result does not depend on which chunk,
block or thread processes it.

Pixels are processed in blocks of `LANES`, frame by frame, with the block's
states in structure-of-arrays form so that the common path vectorises across
pixels (AVX-512 where the CPU has it).  Each frame draws two 64-bit numbers
per pixel, r1 and r2 (a vector loop), looks up the two ziggurat layers' table
words (a scalar loop: vector gathers cost more than twice as much per element
on Zen 4), then runs the common path (a vector loop).  A pixel whose draws
leave the common path (a ziggurat
draw outside its layer's core, a Poisson draw that PD's steps I and S do
not settle on the coarse uniform, or a mean below `PD_MIN_LAM`; about 0.5 % of
pixel-frames at λ ≥ 1e4) is redone by the whole algorithm, which continues
from the same two draws on the same stream, right after them.

Samplers:

* Normal: Marsaglia & Tsang's ziggurat (2000) with 2048 layers on one 64-bit
  draw (layer: bits 0-10, sign: bit 11, 46-bit abscissa: bits 12-57), exact
  wedges and tail, one table word per layer (its width with a coarse core
  bound in the low mantissa bits: `gongsynth.stages.camera.ziggurat`); 0.23 %
  of draws fall outside their layer's core.  z1 (Poisson) comes from r1, z2
  (read noise) from r2.
* Poisson, mean λ ≥ `PD_MIN_LAM` (and λ = 0): Ahrens & Dieter's algorithm PD
  (1982, ACM TOMS 8, 163; the one R uses): g = λ + √λ z1, k = ⌊g⌋ is accepted
  at once if k ≥ L (step I) or after the cubic squeeze 6λ²u ≥ (λ − k)³ (step
  S); the rest is corrected exactly against the Poisson probabilities (steps
  Q, E, H; log k! by its Stirling series, |error| < 1e-12).  PD's uniform u
  has 52 bits: the top 12 are bits 58-63 of r1 and of r2 (unused by the
  ziggurat), the low 40 come from one more draw taken only when the top 12
  do not settle step S.  Since u ≥ u12/4096, D·u12/4096 ≥ (λ − k)³ implies
  D·u ≥ (λ − k)³ in floating point too (rounding is monotone), so the
  decision is the one the whole uniform would give: every variate is exactly
  PD's with a 52-bit uniform.
* Poisson, 0 < λ < `PD_MIN_LAM`: inversion of the cumulative distribution
  tabulated up to λ + 10√λ + 10 (the tail beyond holds < 1e-19 and is
  renormalised away), searched from a guide table, with a 52-bit uniform
  (top 12 bits from r1 and r2, the rest from one more draw).
"""
import math

import numpy as np
from numba import njit, prange

from gongsynth.stages.camera.ziggurat import COARSE_BITS, as_float64, ziggurat_tables

__all__ = ["frames_kernel", "sample_kernel", "LANES", "PD_MIN_LAM", "ZIGGURAT_R"]

_U = np.uint64
_GOLDEN = _U(0x9E3779B97F4A7C15)
_M1 = _U(0xBF58476D1CE4E5B9)
_M2 = _U(0x94D049BB133111EB)
_TO_UNIT52 = 1.0 / 4503599627370496.0  # 2**-52

#: Pixels per block of the vectorised frame loop (a multiple of 8).
LANES = 128
#: Means from this up (and 0) use algorithm PD, smaller ones inversion.
PD_MIN_LAM = 10.0
# Longest inversion table: λ + 10√λ + 10 < 51.7 for λ < 10.
TABLE_LEN = 52

# Rows of the per-block constants (N_CONST, n_planes, LANES).
_LAM, _SLAM, _BIGL, _D, _LOGLAM, _OMEGA, _C0, _C1, _C2, _C3, _CHAT, _M, _SLOT, _FRAC = range(14)
N_CONST = 14
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
def _draw(s):
    """(next 64-bit output, next state) of the state tuple ``s``."""
    r, s0, s1, s2, s3 = _step(s[0], s[1], s[2], s[3])
    return r, (s0, s1, s2, s3)


@njit(inline="always")
def _uniform(s):
    """(uniform double in the open interval (0, 1) on a 2**-52 grid, next state)."""
    r, s = _draw(s)
    return (np.float64(r >> _U(12)) + 0.5) * _TO_UNIT52, s


# 2048 layers: 0.23 % of draws fall outside their layer's core (0.43 % with 1024, 2.8 % with 128).
_ZBITS = 11
_ZABS = 46
_ZT, _ZF, _ZR = ziggurat_tables(1 << _ZBITS, _ZABS)
assert np.all(_ZT != 0)
#: Edge of the ziggurat's base strip: normal variates beyond it come from the exact tail.
ZIGGURAT_R = _ZR
_ZLAYER = _U((1 << _ZBITS) - 1)
_ZMASK = _U((1 << _ZABS) - 1)
_ZSHIFT = _U(_ZABS - COARSE_BITS)
_ZLOW = _U((1 << COARSE_BITS) - 1)
# Bits of a draw above layer, sign and abscissa: PD's coarse uniform takes them from r1 and r2.
_SPARE = 64 - _ZBITS - 1 - _ZABS
_COARSE = 2 * _SPARE
_TO_COARSE = 1.0 / (1 << _COARSE)
# Lowest set bit of a 64-bit word by de Bruijn multiplication.
_DEBRUIJN = _U(0x03F79D71B4CB0A89)
_DEBRUIJN_INDEX = np.zeros(64, np.int64)
for _b in range(64):
    _DEBRUIJN_INDEX[((1 << _b) * 0x03F79D71B4CB0A89 % 2**64) >> 58] = _b


@njit(inline="always")
def _rectangle(r, t):
    """(inside, x): the ziggurat's common case for draw ``r`` and its layer's table word ``t``."""
    j = (r >> _U(_ZBITS + 1)) & _ZMASK
    x = np.float64(j) * as_float64(t)
    x = -x if (r >> _U(_ZBITS)) & _U(1) else x
    return (j >> _ZSHIFT) < (t & _ZLOW), x


@njit(inline="always")
def _normal(s, r):
    """(standard normal variate from draw ``r``, state): continues state ``s`` if ``r`` is not enough."""
    while True:
        i = np.int64(r & _ZLAYER)
        t = _ZT[i]
        sign = (r >> _U(_ZBITS)) & _U(1)
        j = (r >> _U(_ZBITS + 1)) & _ZMASK
        x = np.float64(j) * as_float64(t)
        if (j >> _ZSHIFT) < (t & _ZLOW):
            return (-x if sign else x), s
        if i == 0:
            if x < _ZR:  # the base strip's core beyond its coarse bound
                return (-x if sign else x), s
            # Tail beyond r (Marsaglia 1964).
            while True:
                a, s = _uniform(s)
                b, s = _uniform(s)
                xt = -math.log(a) / _ZR
                if -2.0 * math.log(b) >= xt * xt:
                    break
            return (-(_ZR + xt) if sign else _ZR + xt), s
        a, s = _uniform(s)
        if _ZF[i] + a * (_ZF[i - 1] - _ZF[i]) < math.exp(-0.5 * x * x):
            return (-x if sign else x), s
        r, s = _draw(s)


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
def _poisson_constants(lam, c, p, lane, cdf, guide, slot, photon):
    """
    Fill ``c[:, p, lane]`` to draw Poisson variates of mean ``lam`` (``photon``) or to give ``lam`` itself.

    A mean below `PD_MIN_LAM` gets its cumulative distribution in ``cdf[slot]``
    and guide table in ``guide[slot]``; its L and D are NaN so that the
    common path of `_run_block` always leaves it to the whole algorithm.  λ = 0 runs
    through PD's constants, which give 0 on the common path.  Without
    ``photon`` the common path's ⌊λ + 0·z1⌋ + (λ − ⌊λ⌋) is λ exactly.
    """
    c[_LAM, p, lane] = lam
    c[_M, p, lane] = 0.0
    c[_FRAC, p, lane] = 0.0
    if not photon:
        c[_SLAM, p, lane] = 0.0
        c[_BIGL, p, lane] = -np.inf
        c[_D, p, lane] = 0.0
        c[_FRAC, p, lane] = lam - math.floor(lam)
        return
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
def _pk_fk(q, k):
    """Poisson probability p_k and discrete-normal probability f_k (algorithm PD; constants ``q``)."""
    lam = q[_LAM]
    pk = math.exp(-lam + k * q[_LOGLAM] - _log_factorial(k))
    x = (k + 0.5 - lam) / q[_SLAM]
    x *= x
    fk = q[_OMEGA] * math.exp(-0.5 * x) * (((q[_C3] * x + q[_C2]) * x + q[_C1]) * x + q[_C0])
    return pk, fk


@njit(inline="always")
def _pd_rest(s, q, g, u):
    """(variate, state): steps Q, E and H of algorithm PD (< 3 % of draws at λ ≥ 30)."""
    if g >= 0.0:
        # Step Q: accept with probability p_k / f_k (u is reused, as in PD).
        k = np.floor(g)
        pk, fk = _pk_fk(q, k)
        if (1.0 - u) * fk <= pk:
            return k, s
    # Steps E and H: double-exponential hat for the excess p_k − f_k.
    while True:
        a, s = _uniform(s)
        b, s = _uniform(s)
        e = -math.log(a)
        v = 2.0 * b - 1.0
        t = 1.8 + e if v >= 0.0 else 1.8 - e
        if t > -0.6744:
            k = np.floor(q[_LAM] + q[_SLAM] * t)
            pk, fk = _pk_fk(q, k)
            if q[_CHAT] * abs(v) <= (pk - fk) * math.exp(e):
                return k, s


@njit(inline="always")
def _coarse(r1, r2):
    """PD's coarse uniform bits: the spare top bits of r1, then of r2 (an integer < 2**_COARSE)."""
    return ((r1 >> _U(64 - _SPARE)) << _U(_SPARE)) | (r2 >> _U(64 - _SPARE))


@njit(inline="always")
def _fine(coarse, r):
    """52-bit uniform in (0, 1) whose top bits are ``coarse``, the rest from draw ``r``."""
    return (np.float64((coarse << _U(52 - _COARSE)) | (r >> _U(12 + _COARSE))) + 0.5) * _TO_UNIT52


@njit(inline="always")
def _complete_pd(s, r1, r2, q, photon):
    """
    (electrons, read-noise normal, state) of one pixel-frame from its two draws, by the whole algorithm.

    ``q`` holds the pixel's constants (`_poisson_constants`; a mean that PD
    serves, or any mean if not ``photon``).  Further draws continue state
    ``s`` in a fixed order: the rest of z1, of z2, then the fine bits of the
    uniform and PD's steps E and H.
    """
    lam = q[_LAM]
    if not photon:
        z2, s = _normal(s, r2)
        return lam, z2, s
    z1, s = _normal(s, r1)
    z2, s = _normal(s, r2)
    # Step N: normal sample; steps I and S: immediate and squeeze acceptance, first
    # on the coarse uniform (a lower bound of u), then on the whole one.
    coarse = _coarse(r1, r2)
    g = lam + q[_SLAM] * z1
    k = np.floor(g)
    diff = lam - k
    cube = diff * diff * diff
    if (g >= 0.0) & ((k >= q[_BIGL]) | (q[_D] * (np.float64(coarse) * _TO_COARSE) >= cube)):
        return k, z2, s
    r, s = _draw(s)
    u = _fine(coarse, r)
    if (g >= 0.0) & (q[_D] * u >= cube):
        return k, z2, s
    k, s = _pd_rest(s, q, g, u)
    return k, z2, s


@njit(inline="always")
def _common(r1, r2, t1, t2, mean, slam, bigl, d, frac):
    """(accepted, electrons, read-noise normal): the common path of both samplers for draws r1, r2."""
    ok1, z1 = _rectangle(r1, t1)
    ok2, z2 = _rectangle(r2, t2)
    g = mean + slam * z1
    n = np.floor(g)
    diff = mean - n
    u = np.float64(_coarse(r1, r2)) * _TO_COARSE
    accept = ok1 & ok2 & (g >= 0.0) & ((n >= bigl) | (d * u >= diff * diff * diff))
    return accept, n + frac, z2


@njit(cache=True, error_model="numpy")
def _run_block(lam, i0, lanes, seg_start, seg_snap, plane, inv_gain, sigma, photon, key0, key1, first,
               reference, acc, record):
    """
    Every frame of the block of pixels ``i0 .. i0 + lanes - 1`` of a chunk.

    Adds each frame's ADU, round(n / g + σ z), to ``acc`` (n_planes, LANES).
    ``record`` (n_frames, 2, LANES), unless empty, receives each frame's
    electrons n and read-noise normal z.  Lanes past ``lanes`` draw from
    streams of their own (mean 0) and are dropped by the caller.  The frame
    loop is written out here, with no array passed to a function inside it:
    numba's reference counting of array arguments would cost more than the
    samplers.
    """
    n_planes = lam.shape[1]
    st = np.empty((4, LANES), np.uint64)
    for lane in range(LANES):
        _seed(st, lane, key0, key1, _U(first + i0 + lane))
    c = np.zeros((N_CONST, n_planes, LANES))
    draws = np.empty((2, LANES), np.uint64)
    n_out = np.empty(LANES)
    z_out = np.empty(LANES)
    flags = np.zeros(LANES, np.uint8)
    tw = np.empty((2, LANES), np.uint64)
    words = flags.view(np.uint64)
    keep = record.shape[0] > 0
    for j in range(seg_snap.size):
        snap = seg_snap[j]
        small = 0
        for p in range(n_planes):
            for lane in range(lanes):
                small += (lam[snap, p, i0 + lane] > 0.0) & (lam[snap, p, i0 + lane] < PD_MIN_LAM)
        cdf = np.empty((small, TABLE_LEN))
        guide = np.empty((small, TABLE_LEN), np.int32)
        slot = 0
        for p in range(n_planes):
            for lane in range(LANES):
                _poisson_constants(lam[snap, p, i0 + lane] if lane < lanes else 0.0, c, p, lane, cdf, guide,
                                   slot, photon)
                slot += c[_M, p, lane] > 0.0
        for k in range(seg_start[j], seg_start[j + 1]):
            p = plane[k]
            # Two draws per pixel-frame, vectorised across the block.
            for lane in range(LANES):
                r1, s0, s1, s2, s3 = _step(st[0, lane], st[1, lane], st[2, lane], st[3, lane])
                r2, s0, s1, s2, s3 = _step(s0, s1, s2, s3)
                st[0, lane], st[1, lane], st[2, lane], st[3, lane] = s0, s1, s2, s3
                draws[0, lane] = r1
                draws[1, lane] = r2
            if reference:
                flags[:] = 1
            else:
                # The common path of every sampler, branch-free so that it vectorises
                # across the block; the pixels it cannot finish are flagged.  First the
                # layers' table words by scalar loads, four lanes a step: the early exit (never
                # taken: no word is 0) keeps this loop scalar, as vector gathers cost twice as much.
                for l4 in range(0, LANES, 4):
                    a = _ZT[draws[0, l4] & _ZLAYER]
                    if a == _U(0):
                        break
                    tw[0, l4] = a
                    tw[1, l4] = _ZT[draws[1, l4] & _ZLAYER]
                    tw[0, l4 + 1] = _ZT[draws[0, l4 + 1] & _ZLAYER]
                    tw[1, l4 + 1] = _ZT[draws[1, l4 + 1] & _ZLAYER]
                    tw[0, l4 + 2] = _ZT[draws[0, l4 + 2] & _ZLAYER]
                    tw[1, l4 + 2] = _ZT[draws[1, l4 + 2] & _ZLAYER]
                    tw[0, l4 + 3] = _ZT[draws[0, l4 + 3] & _ZLAYER]
                    tw[1, l4 + 3] = _ZT[draws[1, l4 + 3] & _ZLAYER]
                for lane in range(LANES):
                    accept, n, z2 = _common(draws[0, lane], draws[1, lane], tw[0, lane], tw[1, lane],
                                            c[_LAM, p, lane], c[_SLAM, p, lane], c[_BIGL, p, lane],
                                            c[_D, p, lane], c[_FRAC, p, lane])
                    adu = np.int64(math.floor(n * inv_gain + sigma * z2 + 0.5))
                    acc[p, lane] += adu if accept else 0
                    flags[lane] = np.uint8(0 if accept else 1)
                if keep:  # the variates themselves, for tests (stored here: a loop of their own is cheaper)
                    for lane in range(LANES):
                        _, n_out[lane], z_out[lane] = _common(
                            draws[0, lane], draws[1, lane], tw[0, lane], tw[1, lane], c[_LAM, p, lane],
                            c[_SLAM, p, lane], c[_BIGL, p, lane], c[_D, p, lane], c[_FRAC, p, lane])
            # The rest: the whole algorithm, continuing each pixel's stream.
            for w in range(LANES // 8):
                mask = words[w]
                while mask:
                    low = mask & (~mask + _U(1))
                    lane = w * 8 + (_DEBRUIJN_INDEX[(low * _DEBRUIJN) >> _U(58)] >> 3)
                    mask ^= low
                    s = (st[0, lane], st[1, lane], st[2, lane], st[3, lane])
                    r1 = draws[0, lane]
                    r2 = draws[1, lane]
                    m = c[_M, p, lane]
                    if photon and m > 0.0:
                        # Inversion: the smallest n with cdf[n] >= u, searched from the guide entry.
                        z, s = _normal(s, r2)
                        r, s = _draw(s)
                        u = _fine(_coarse(r1, r2), r)
                        row = np.int64(c[_SLOT, p, lane])
                        i = guide[row, min(np.int64(u * m), np.int64(m) - 1)]
                        while cdf[row, i] < u:
                            i += 1
                        n = np.float64(i)
                    else:
                        q = (c[0, p, lane], c[1, p, lane], c[2, p, lane], c[3, p, lane], c[4, p, lane],
                             c[5, p, lane], c[6, p, lane], c[7, p, lane], c[8, p, lane], c[9, p, lane],
                             c[10, p, lane])
                        n, z, s = _complete_pd(s, r1, r2, q, photon)
                    st[0, lane], st[1, lane], st[2, lane], st[3, lane] = s
                    n_out[lane] = n
                    z_out[lane] = z
                    acc[p, lane] += np.int64(math.floor(n * inv_gain + sigma * z + 0.5))
            if keep:
                for lane in range(LANES):
                    record[k, 0, lane] = n_out[lane]
                    record[k, 1, lane] = z_out[lane]


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
    none = np.empty((0, 2, LANES))
    # A bool variable, not the literal False: numba compiles a literal argument into a
    # specialisation of its own, and `_run_block` costs ~20 s of CPU per specialisation;
    # this way the engine and `sample_kernel` share one.
    reference = first < 0
    for b in prange((n_pix + LANES - 1) // LANES):
        i0 = b * LANES
        lanes = min(LANES, n_pix - i0)
        acc = np.zeros((n_planes, LANES), np.int64)
        _run_block(lam, i0, lanes, seg_start, seg_snap, plane, inv_gain, sigma, photon, key0, key1, first,
                   reference, acc, none)
        for p in range(n_planes):
            for lane in range(lanes):
                out[p, i0 + lane] = acc[p, lane] + dither_sum[p]


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
        Run the whole algorithm for every pixel-frame instead of the
        vectorised common path: the results must be the same bits.

    Returns
    -------
    electrons, normal : float64 (n_frames, n_pix)
        Poisson variates (λ itself if not ``photon``) and read-noise normal variates.
    """
    # Plain Python values as plain types: an omitted or literal flag would compile a
    # specialisation of its own (of this kernel and of `_run_block`, ~20 s of CPU each).
    return _sample_kernel(np.ascontiguousarray(lam, np.float64), int(n_frames), np.uint64(key0),
                          np.uint64(key1), int(first), bool(photon), bool(reference))


@njit(parallel=True, cache=True, error_model="numpy")
def _sample_kernel(lam, n_frames, key0, key1, first, photon, reference):
    """`sample_kernel`'s compiled body (every argument required, of one type)."""
    n_pix = lam.size
    means = lam.reshape(1, 1, n_pix)
    seg_start = np.array([0, n_frames], np.int64)
    seg_snap = np.zeros(1, np.int64)
    plane = np.zeros(n_frames, np.int64)
    electrons = np.empty((n_frames, n_pix))
    normal = np.empty((n_frames, n_pix))
    for b in prange((n_pix + LANES - 1) // LANES):
        i0 = b * LANES
        lanes = min(LANES, n_pix - i0)
        record = np.empty((n_frames, 2, LANES))
        _run_block(means, i0, lanes, seg_start, seg_snap, plane, 1.0, 0.0, photon, key0, key1, first,
                   reference, np.zeros((1, LANES), np.int64), record)
        for k in range(n_frames):
            for lane in range(lanes):
                electrons[k, i0 + lane] = record[k, 0, lane]
                normal[k, i0 + lane] = record[k, 1, lane]
    return electrons, normal
