r"""
Inclined rays through the horizontally periodic box.

A ray toward the observer runs along n = (sinθ cos a, sinθ sin a, cosθ)
(θ = arccos μ, a the line-of-sight azimuth of `gongsynth.geometry`).  The ray
that is stored in output pixel (j, i) crosses the reference height z_ref at
the centre of that pixel, (x_i, y_j); at height z it is at

.. math:: (x, y) = (x_i, y_j) + (z - z_\mathrm{ref})\,\tan\theta\,(\cos a, \sin a),

wrapped periodically.  `synthesize` takes z_ref as the mean height of
τ_c = 1 at 676.8 nm (vertical), so the Stokes images and the truth are
registered with the atmosphere where the continuum forms, and the output stays
on the atmosphere's horizontal grid (pixel size unchanged): foreshortening is
left to the scene stage, which projects the surface grid onto the sky at the
latitude (no double foreshortening).  Every field is sampled at the grid's
heights by bilinear interpolation in x and y; along the ray the step is Δz/μ.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from gongsynth.threads import run_chunks

__all__ = ["ray_offsets", "rays_are_vertical", "sample_rays", "VERTICAL_TRAVEL"]

#: Rays that move less than this many pixels sideways across the whole box are read as
#: vertical columns: at disk centre the default date's B0 (-9e-5°) tilts them by ~1e-5 pixel,
#: for which the inclined path would synthesise a halo of rows and interpolate for nothing.
VERTICAL_TRAVEL = 1e-3


def rays_are_vertical(z_km, mu, pixel_km):
    """
    Whether rays at ``mu`` move less than `VERTICAL_TRAVEL` pixels sideways across the heights ``z_km``.

    Parameters
    ----------
    z_km : `numpy.ndarray`
        Heights (km).
    mu : float
        cos θ in (0, 1].
    pixel_km : float
        Pixel size (km).

    Returns
    -------
    bool

    Examples
    --------
    >>> import numpy as np
    >>> z = np.array([-500.0, 700.0])
    >>> rays_are_vertical(z, 1 - 1.2e-12, 96.0), rays_are_vertical(z, 0.99, 96.0)
    (True, False)
    """
    if mu >= 1:
        return True
    travel = float(np.ptp(np.asarray(z_km, dtype=np.float64))) * math.sqrt(1.0 - mu * mu) / mu / pixel_km
    return travel < VERTICAL_TRAVEL


def ray_offsets(z_km, z_ref_km, mu, azimuth_rad, pixel_km):
    """
    Horizontal offsets (pixels) of a ray at each height relative to where it crosses z_ref.

    Parameters
    ----------
    z_km : `numpy.ndarray`
        Heights (km).
    z_ref_km : float
        Reference height (km).
    mu : float
        cos θ in (0, 1].
    azimuth_rad : float
        Line-of-sight azimuth (rad).
    pixel_km : float
        Pixel size (km).

    Returns
    -------
    dx, dy : `numpy.ndarray`
        Offsets in pixels along x and y.

    Examples
    --------
    >>> import numpy as np
    >>> dx, dy = ray_offsets(np.array([0.0, 100.0]), 0.0, 0.5, 0.0, 10.0)
    >>> np.round(dx, 3).tolist(), np.round(dy, 3).tolist()
    ([0.0, 17.321], [0.0, 0.0])
    """
    tan_t = math.sqrt(max(0.0, 1.0 - mu * mu)) / mu
    shift = (np.asarray(z_km, dtype=np.float64) - z_ref_km) * tan_t / pixel_km
    return shift * math.cos(azimuth_rad), shift * math.sin(azimuth_rad)


def sample_rays(field, rows, dx, dy, out):
    """
    Sample a (nz, ny, nx) field along the rays of the given output rows.

    Parameters
    ----------
    field : (nz, ny, nx) float32 array
        Any strides (broadcast views are fine).
    rows : (nr,) int64
        Output rows.
    dx, dy : (nz,) float64
        Offsets from `ray_offsets`.
    out : (nr * nx, nz) float64
        Filled with the bilinearly interpolated values, ray points bottom to top.
    """
    if field.dtype != np.float32:
        raise TypeError(f"field must be float32 (an Atmosphere's stored array), got {field.dtype}")
    # Vertical rays (or whole-pixel shifts): plain copies.
    aligned = bool(np.all(dx == np.floor(dx)) and np.all(dy == np.floor(dy)))
    if not _sample_rays.signatures:
        # One specialisation for C-ordered, strided and broadcast (read-only) fields alike: each
        # further one would cost a first run another compile.
        _sample_rays.compile(_SIGNATURE)
        _sample_rays.disable_compile()
    run_chunks(_sample_rays, rows.size * field.shape[2], field, rows, dx, dy, aligned, out, min_chunk=256)


_SIGNATURE = (nb.int64, nb.int64, nb.types.Array(nb.float32, 3, "A", readonly=True), nb.int64[::1],
              nb.float64[::1], nb.float64[::1], nb.boolean, nb.float64[:, ::1])


@nb.njit(cache=True, nogil=True)
def _sample_rays(start, stop, field, rows, dx, dy, aligned, out):
    """Rays ``start`` to ``stop`` of `sample_rays`."""
    nz, ny, nx = field.shape
    # Per height: the whole-pixel offsets wrapped into the box and the weights, the same for every ray, so
    # the loop over rays needs no integer division (the modulo was most of its time).
    ox = np.empty(nz, dtype=np.int64)
    oy = np.empty(nz, dtype=np.int64)
    wxs = np.empty(nz)
    wys = np.empty(nz)
    for k in range(nz):
        fx0 = math.floor(dx[k])
        fy0 = math.floor(dy[k])
        wxs[k] = dx[k] - fx0
        wys[k] = dy[k] - fy0
        ox[k] = int(fx0) % nx
        oy[k] = int(fy0) % ny
    for q in range(start, stop):
        r = q // nx
        i = q - r * nx
        j = rows[r]
        for k in range(nz):
            x0 = i + ox[k]
            x0 = x0 - nx if x0 >= nx else x0
            y0 = j + oy[k]
            y0 = y0 - ny if y0 >= ny else y0
            if aligned:
                out[q, k] = field[k, y0, x0]
                continue
            wx = wxs[k]
            wy = wys[k]
            x1 = x0 + 1 if x0 + 1 < nx else 0
            y1 = y0 + 1 if y0 + 1 < ny else 0
            out[q, k] = ((1.0 - wy) * ((1.0 - wx) * field[k, y0, x0] + wx * field[k, y0, x1])
                         + wy * ((1.0 - wx) * field[k, y1, x0] + wx * field[k, y1, x1]))
