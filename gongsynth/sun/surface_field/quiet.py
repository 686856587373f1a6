"""
The quiet Sun's large-scale field: a stationary Gaussian field with the correlation of ADAPT's quiet band.

Away from active regions the radial field averaged over a degree is not
white from cell to cell: flux that active regions left behind and the
network's imbalance form unipolar patches several degrees across.  Measured
on the ADAPT-GONG synchronic map of 2017-07-20 (``shared/data/real/gong``, 12
realizations, |latitude| < 30°, each realization clipped at 5 robust σ about
its median so that active regions do not set the law;
``scripts/quiet_field_correlation.py``), the correlation of the 1° field is
0.89, 0.74, 0.55, 0.40, 0.27, 0.17 and 0.10 at 1, 2, 4, 6, 8, 10 and 12°
(the same along longitude and latitude within 0.04 out to 6°): close to
exp(−r / 6.5°), i.e. patches of ~80 Mm, while its robust width stays 2.9 G
at 1° and 2.8 G averaged over 5° (white cells would give 0.6 G there).

`quiet_field` draws such a field on the surface-field grid: white noise on
its equal-area cells smoothed by Gaussians of `QUIET_CORRELATION`'s widths
(their correlations' weights fitted to the measured correlation by
non-negative least squares, largest error 0.04 over 0-20°), each part
normalised to unit variance row by row and the parts added with their
weights, scaled to the requested standard deviation.  The smoothing is
along latitude on the sphere and along longitude in the local plane of each
row (the width in longitude is the width on the sphere over cos latitude):
exact at the equator, approximate within a few widths of the poles, where
the polar fields dominate.
"""
import math

import numpy as np

__all__ = ["QUIET_CORRELATION", "quiet_field"]

#: (correlation width σ_c in degrees, weight): the quiet field's correlation is
#: Σ weight · exp(−r² / 2σ_c²), fitted to the ADAPT band's (see the module docstring).
QUIET_CORRELATION = ((1.0, 0.218), (3.0, 0.230), (6.0, 0.460), (12.0, 0.092))

_MIN_COSLAT = 0.02     # longitude widths are capped near the poles (a row there is one small circle)


def _smoothed_unit_field(white, lat_grid, kernel_width):
    """White noise (ny, nx) smoothed by a Gaussian of ``kernel_width`` deg, unit variance in every row."""
    ny, nx = white.shape
    dlat = lat_grid[:, None] - lat_grid[None, :]
    along_lat = np.exp(-0.5 * (dlat / kernel_width) ** 2)               # (ny, ny): rows are equal-area
    field = along_lat @ white
    frequency = np.fft.rfftfreq(nx, d=360.0 / nx)                      # cycles per degree of longitude
    width_lon = kernel_width / np.maximum(np.cos(np.radians(lat_grid)), _MIN_COSLAT)
    transfer = np.exp(-2.0 * (math.pi * frequency[None, :] * width_lon[:, None]) ** 2)
    field = np.fft.irfft(np.fft.rfft(field, axis=1) * transfer, n=nx, axis=1)
    # The variance of row i is Σ_j w_ij² times the longitude filter's energy (the noise is iid).
    energy_lon = (transfer[:, :1] ** 2 + 2 * np.sum(transfer[:, 1:] ** 2, axis=1, keepdims=True)) / nx
    if nx % 2 == 0:
        energy_lon -= transfer[:, -1:] ** 2 / nx
    variance = np.sum(along_lat ** 2, axis=1, keepdims=True) * energy_lon
    return field / np.sqrt(variance)


def quiet_field(rng, lat_grid, shape, rms):
    """
    A seeded quiet-Sun large-scale field with ADAPT's correlation, on the surface-field grid.

    Parameters
    ----------
    rng : `numpy.random.Generator`
        Source of the white noise (one draw of ``(len(QUIET_CORRELATION), ny, nx)``).
    lat_grid : `numpy.ndarray`
        (ny,) cell-centre latitudes, deg (`gongsynth.sun.surface_field.maps.field_grid`).
    shape : (int, int)
        (ny, nx) of the grid.
    rms : float
        Standard deviation of the field, G.

    Returns
    -------
    `numpy.ndarray`
        (ny, nx) B_r in G.

    Examples
    --------
    >>> import numpy as np
    >>> from gongsynth.sun.surface_field.maps import field_grid
    >>> lon, lat = field_grid((360, 720))
    >>> b = quiet_field(np.random.default_rng(1), lat, (360, 720), 3.0)
    >>> equator = b[np.abs(lat) < 30]
    >>> bool(2.7 < equator.std() < 3.3)           # one draw of a correlated field: ±10 %
    True
    >>> lag = 12                                  # 6 deg of longitude
    >>> c = np.mean(equator * np.roll(equator, lag, axis=1)) / equator.var()
    >>> bool(0.3 < c < 0.55)                      # ADAPT: 0.40
    True
    """
    ny, nx = shape
    white = rng.standard_normal((len(QUIET_CORRELATION), ny, nx))
    out = np.zeros(shape)
    for part, (width, weight) in zip(white, QUIET_CORRELATION):
        # Gaussian-smoothed white noise of kernel width s has correlation width σ_c = √2 s.
        out += math.sqrt(weight) * _smoothed_unit_field(part, lat_grid, width / math.sqrt(2.0))
    return rms * out
