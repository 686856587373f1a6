"""
Tables of the frames engine's normal sampler: a ziggurat with one 64-bit word per layer.

Marsaglia & Tsang's ziggurat (2000) covers the half-normal density
f(x) = exp(−x²/2) with n layers of equal area v: a base strip [0, X₀) × [0, f(r))
whose part beyond r stands for the tail, and n − 1 rectangles
[0, xᵢ) × [yᵢ, yᵢ₊₁) stacked on it.  A variate picks a layer uniformly and an
abscissa x uniformly across it; points left of the layer's *core* edge
f⁻¹(yᵢ₊₁) lie under the curve and are accepted at once, the others are
accepted if a uniform height under the layer falls below f(x) (the base
strip sends them to the exact tail instead).

The classic construction makes each width exactly xᵢ = f⁻¹(yᵢ), so that the
layers close at f(0) = 1.  Exactness needs less: equal areas, widths
xᵢ ≥ f⁻¹(yᵢ) (each layer covers the curve over its height) and, in the base
strip, X₀ f(r) = v.  That freedom lets each layer's width be rounded up to a
double whose 16 low mantissa bits are free: they hold a conservative coarse
core bound ``kc`` (the abscissa's top 16 bits below ``kc`` are inside the core),
so that the common case needs one table word per normal (one gather in the
vectorised loop) instead of a width and a bound.  Heights then follow the
widths (yᵢ₊₁ = yᵢ + v/xᵢ); r is chosen so that X₀ is itself such a double
and the stack just reaches 1 (the top layer may overshoot it slightly: its
points above the curve are rejected by the height test).

The kernels freeze these tables into numba's on-disk cache, which is keyed
on ``kernels.py``: change that file too (or clear the cache) when changing
this one.
"""
import math
import struct

import numpy as np
from numba import types
from numba.extending import intrinsic

__all__ = ["ziggurat_tables", "as_float64", "COARSE_BITS"]

#: Bits of the coarse core bound held in the low mantissa bits of each table word.
COARSE_BITS = 16
_LOW = (1 << COARSE_BITS) - 1


@intrinsic
def as_float64(typingctx, word):
    """
    The double whose bits are the 64-bit unsigned integer ``word`` (numba only).

    Parameters
    ----------
    word : uint64

    Returns
    -------
    float64
    """
    if word != types.uint64:
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], context.get_value_type(types.float64))

    return types.float64(types.uint64), codegen


def _bits(x):
    return struct.unpack("<Q", struct.pack("<d", x))[0]


def _double(b):
    return struct.unpack("<d", struct.pack("<Q", b))[0]


def _inverse(y):
    """f⁻¹(y) of the half-normal density f(x) = exp(−x²/2) (0 at and above f(0) = 1)."""
    return math.sqrt(-2.0 * math.log(y)) if y < 1.0 else 0.0


def _x0(r):
    """Width of the base strip whose part beyond r has the area of the tail: v / f(r)."""
    return r + math.sqrt(math.pi / 2) * math.erfc(r / math.sqrt(2)) * math.exp(0.5 * r * r)


def _bound(w, edge, shift):
    """Largest kc < 2**16 with fl(j w) < edge for every j < kc << shift (abscissa j)."""
    kc = min(int(edge / w / 2.0**shift), _LOW)
    while kc > 0 and ((kc << shift) - 1) * w >= edge:
        kc -= 1
    return kc


def _layer(y_lo, v, m, shift):
    """(word, y_hi, core edge) of a layer on height ``y_lo``; width f⁻¹(y_lo) rounded up."""
    need = _inverse(y_lo) * (1.0 + 2.0**-50)
    base = (_bits(need / m) + _LOW) & ~_LOW
    kc = 0
    for _ in range(3):  # the width depends on kc through its low bits; kc hardly on the width
        w = _double(base | kc)
        y_hi = y_lo + v / (w * m)
        edge = _inverse(y_hi)
        kc = _bound(_double(base | kc), edge, shift)
    word = base | kc
    w = _double(word)
    y_hi = y_lo + v / (w * m)
    edge = _inverse(y_hi)
    if kc and ((kc << shift) - 1) * w >= edge:  # pragma: no cover - guarded by construction
        raise RuntimeError("ziggurat core bound is not conservative")
    return word, y_hi, edge


def _stack(x0_word, n, bits, shift):
    """Layers over a base strip of width ``x0_word``: (words, heights, r), or ±1 if r is too small/large."""
    m = 2.0**bits
    x0 = _double(x0_word) * m
    lo, hi = 1.0, 8.0
    for _ in range(200):  # solve _x0(r) = x0 (increasing in r)
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _x0(mid) < x0 else (lo, mid)
    r = lo
    y = math.exp(-0.5 * r * r)
    v = x0 * y
    words = np.zeros(n, np.uint64)
    heights = np.zeros(n)
    words[0] = x0_word
    heights[n - 1] = y
    for i in range(n - 1, 0, -1):
        words[i], y_hi, _ = _layer(y, v, m, shift)
        if i > 1 and y_hi >= 1.0:
            return 1  # closes below the top layer: r too small
        heights[i - 1] = y_hi
        y = y_hi
    if y < 1.0:
        return -1  # short of f(0) = 1: r too large
    return words, heights, r


def ziggurat_tables(n, bits):
    """
    Packed ziggurat tables: one 64-bit word per layer and the layer heights.

    Parameters
    ----------
    n : int
        Layers (the base strip is layer 0, layer n − 1 sits on it, layer 1 is on top).
    bits : int
        Bits of the uniform abscissa j (x = j·w of the layer's word w; at most 52).

    Returns
    -------
    words : uint64 (n,)
        The double w = xᵢ / 2**bits (its width per abscissa step) whose 16 low
        mantissa bits are the coarse core bound kc: ``j >> (bits - 16) < kc``
        implies fl(j w) < the core edge (r for the base strip).
    heights : float64 (n,)
        ``heights[i]`` is the bottom of layer i ≥ 1 and ``heights[i - 1]`` its
        top (``heights[0]`` ≥ 1 is the top of layer 1).
    r : float
        Edge of the base strip; variates beyond it come from the exact tail.

    Examples
    --------
    >>> words, heights, r = ziggurat_tables(256, 46)
    >>> words.size, bool(heights[0] >= 1.0), round(r, 2)
    (256, True, 3.65)
    """
    shift = bits - COARSE_BITS
    m = 2.0**bits
    # The classic n-layer ziggurat: r by bisection on the closure at f(0) = 1.
    lo, hi = 2.0, 8.0
    for _ in range(100):
        r = 0.5 * (lo + hi)
        v = r * math.exp(-0.5 * r * r) + math.sqrt(math.pi / 2) * math.erfc(r / math.sqrt(2))
        d = r
        for _ in range(n - 2):
            a = v / d + math.exp(-0.5 * d * d)
            if a >= 1.0:
                break
            d = math.sqrt(-2.0 * math.log(a))
        closes_early = a >= 1.0 or v / d + math.exp(-0.5 * d * d) >= 1.0
        lo, hi = (r, hi) if closes_early else (lo, r)
    x0 = _x0(hi)
    kc0 = max(int(hi / x0 * 2.0**COARSE_BITS) - 1, 0)
    base = _bits(x0 / m) & ~_LOW
    step = 1
    while True:
        word = base | kc0
        found = _stack(word, n, bits, shift)
        if not isinstance(found, int):
            words, heights, r = found
            if ((kc0 << shift) - 1) * _double(word) < r:
                return words, heights, r
            found = -1
        # Rounding the widths up makes the layers lower: a narrower base strip (smaller r,
        # larger v) makes up for it.
        base += found * (step << COARSE_BITS)
        step *= 2
