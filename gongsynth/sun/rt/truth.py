"""
The ground-truth line-of-sight field of a synthesised cube, as the paper's code takes it.

``"paper"`` (default): B·n along the ray at the height where the continuum
optical depth along the ray is 1, plus 175 km, averaged over ±75 km (51
samples); alternatives: ``"tau0.1"`` (τ_c = 0.1 along the ray), ``"core"``
(optical depth 1 at the line's rest wavelength along the ray), or a height
(`~astropy.units.Quantity`, length, on the atmosphere's z scale).  Heights are
vertical heights; each sample is taken on the ray at that height, so at μ < 1
it lies horizontally displaced (as the ray is).  Samples beyond the top or
bottom of the box take the end values.
"""
from __future__ import annotations

import math

import astropy.units as u
import numba as nb
import numpy as np

from gongsynth.threads import run_chunks

__all__ = ["TRUTH_CHOICES", "truth_definition", "los_field_at_depth"]

#: Named truth definitions: (optical depth scale, log10 τ, offset km, half width km, samples).
TRUTH_CHOICES = {"paper": ("continuum", 0.0, 175.0, 75.0, 51), "tau0.1": ("continuum", -1.0, 0.0, 0.0, 1),
                 "core": ("core", 0.0, 0.0, 0.0, 1)}


def truth_definition(truth):
    """
    Normalise the ``truth`` argument of `~gongsynth.rt.synthesize`.

    Parameters
    ----------
    truth : str or `~astropy.units.Quantity`
        One of `TRUTH_CHOICES` or a height.

    Returns
    -------
    tuple
        (scale, log τ, offset km, half width km, samples); scale is ``"continuum"``,
        ``"core"`` or ``"height"`` (then log τ holds the height in km).

    Examples
    --------
    >>> import astropy.units as u
    >>> truth_definition("paper")
    ('continuum', 0.0, 175.0, 75.0, 51)
    >>> truth_definition(200 * u.km)
    ('height', 200.0, 0.0, 0.0, 1)
    """
    if isinstance(truth, u.Quantity):
        if not truth.unit.is_equivalent(u.km) or truth.size != 1 or not np.isfinite(truth.value):
            raise ValueError(f"a truth height must be one finite length, got {truth}")
        return ("height", float(truth.to_value(u.km)), 0.0, 0.0, 1)
    if isinstance(truth, str) and truth in TRUTH_CHOICES:
        return TRUTH_CHOICES[truth]
    raise ValueError(f"truth must be one of {sorted(TRUTH_CHOICES)} or a height Quantity, got {truth!r}")


def los_field_at_depth(z, log_tau, bpar, level, fixed_height, offset, half_width, nsamp, out, height_out):
    """
    Mean B·n over heights z(τ = 10^level) + offset ± half_width along each ray.

    Parameters
    ----------
    z : (nz,) float64
        Heights (km), increasing.
    log_tau : (ncol, nz) float32
        log10 optical depth along each ray (decreasing upward).
    bpar : (ncol, nz) float64
        B·n along each ray (G).
    level : float
        log10 τ of the anchor (ignored when ``fixed_height`` is true).
    fixed_height : bool
        Use ``level`` as the anchor height in km instead.
    offset, half_width : float
        km.
    nsamp : int
        Samples (1: the anchor + offset only).
    out, height_out : (ncol,) float32
        Filled with the truth (G) and the anchor height (km).
    """
    run_chunks(_los_field_rays, bpar.shape[0], z, log_tau, bpar, level, fixed_height, offset, half_width,
               nsamp, out, height_out)


@nb.njit(cache=True, nogil=True)
def _los_field_rays(start, stop, z, log_tau, bpar, level, fixed_height, offset, half_width, nsamp, out,
                    height_out):
    """Rays ``start`` to ``stop`` of `los_field_at_depth`."""
    nz = bpar.shape[1]
    for p in range(start, stop):
        if fixed_height:
            z1 = level
        else:
            z1 = z[0]
            for k in range(nz - 1, 0, -1):
                if log_tau[p, k - 1] >= level:
                    t0 = log_tau[p, k - 1]
                    t1 = log_tau[p, k]
                    w = 0.0 if t0 == t1 else (t0 - level) / (t0 - t1)
                    z1 = z[k - 1] + w * (z[k] - z[k - 1])
                    break
        height_out[p] = z1
        acc = 0.0
        for s in range(nsamp):
            h = z1 + offset + (0.0 if nsamp == 1 else half_width * (2.0 * s / (nsamp - 1) - 1.0))
            if h <= z[0]:
                acc += bpar[p, 0]
            elif h >= z[nz - 1]:
                acc += bpar[p, nz - 1]
            else:
                lo = 0
                hi = nz - 1
                while hi - lo > 1:
                    mid = (lo + hi) // 2
                    if z[mid] <= h:
                        lo = mid
                    else:
                        hi = mid
                w = (h - z[lo]) / (z[hi] - z[lo])
                acc += bpar[p, lo] + w * (bpar[p, hi] - bpar[p, lo])
        out[p] = acc / nsamp
        if math.isnan(out[p]):
            out[p] = 0.0
