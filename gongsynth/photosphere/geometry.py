"""
Viewing geometry of a photospheric column: the line of sight and the sky frame.

Local frame (CONTRACTS): x = west, y = north, z = up.  The unit vector toward
the observer is n = (sinθ cos a, sinθ sin a, cosθ) with θ = arccos μ and
a = ``los_azimuth``; a = -90° is a region north of disk centre on the central
meridian.  The sky frame (e1, e2, n) is right-handed with e1 the projection of
the local +x (west) onto the plane of the sky, so e1 = x, e2 = y at disk centre.
Stokes Q > 0 is linear polarisation along e1.
"""
from __future__ import annotations

import astropy.units as u
import numpy as np

from ..validation import check_quantity

__all__ = ["check_geometry", "los_basis"]


def check_geometry(mu, los_azimuth, shape):
    """
    Validate and broadcast a viewing geometry.

    Parameters
    ----------
    mu : float, array_like or dimensionless Quantity
        Cosine of the viewing angle, in (0, 1]; scalar or ``shape``.
    los_azimuth : `~astropy.units.Quantity`, angle
        Azimuth of the observer direction from +x toward +y; scalar or ``shape``.
    shape : tuple of int
        (ny, nx) of the columns.

    Returns
    -------
    mu : float or `numpy.ndarray`
        float64, scalar kept scalar.
    azimuth : float or `numpy.ndarray`
        In radians.

    Examples
    --------
    >>> import astropy.units as u
    >>> check_geometry(0.5, -90 * u.deg, (4, 4))
    (0.5, -1.5707963267948966)
    """
    if isinstance(mu, u.Quantity):
        mu = mu.to_value(u.one)
    mu_arr = np.asarray(mu, dtype=np.float64)
    if mu_arr.ndim and mu_arr.shape != tuple(shape):
        raise ValueError(f"mu must be a scalar or have shape (ny, nx) = {tuple(shape)}, got {mu_arr.shape}")
    if not np.isfinite(mu_arr).all() or mu_arr.min() <= 0 or mu_arr.max() > 1:
        raise ValueError(
            f"mu must be in (0, 1] (cos of the viewing angle), got values in "
            f"[{float(np.nanmin(mu_arr))}, {float(np.nanmax(mu_arr))}]"
        )
    check_quantity(los_azimuth, u.deg, "los_azimuth")
    az = np.asarray(los_azimuth.to_value(u.rad), dtype=np.float64)
    if az.ndim and az.shape != tuple(shape):
        raise ValueError(
            f"los_azimuth must be a scalar or have shape (ny, nx) = {tuple(shape)}, got {az.shape}")
    if not np.isfinite(az).all():
        raise ValueError("los_azimuth contains non-finite value(s)")
    return (float(mu_arr) if mu_arr.ndim == 0 else mu_arr), (float(az) if az.ndim == 0 else az)


def los_basis(mu, azimuth):
    """
    The line of sight n and sky axes e1, e2 in the local frame.

    Parameters
    ----------
    mu : float or `numpy.ndarray`
        Cosine of the viewing angle, in (0, 1].
    azimuth : float or `numpy.ndarray`
        los_azimuth in radians.

    Returns
    -------
    n, e1, e2 : tuple of three (x, y, z) tuples
        Components (floats or arrays broadcast like the inputs).

    Examples
    --------
    >>> import numpy as np
    >>> n, e1, e2 = los_basis(0.5, np.radians(-90))
    >>> np.round(n, 3).tolist(), np.round(e1, 3).tolist(), np.round(e2, 3).tolist()
    ([0.0, -0.866, 0.5], [1.0, 0.0, 0.0], [0.0, 0.5, 0.866])
    """
    mu = np.asarray(mu, dtype=np.float64)
    sin_t = np.sqrt(np.clip(1.0 - mu * mu, 0.0, 1.0))
    nx, ny, nz = sin_t * np.cos(azimuth), sin_t * np.sin(azimuth), mu + 0 * sin_t
    # e1 = normalised projection of +x onto the sky plane; e2 = n × e1.
    s = np.sqrt(np.clip(1.0 - nx * nx, 1e-300, None))
    e1 = ((1.0 - nx * nx) / s, -nx * ny / s, -nx * nz / s)
    e2 = (0.0 * s, nz / s, -ny / s)
    return (nx, ny, nz), e1, e2
