"""
Detector calibration maps: flat field and dark current.

No real GONG flat or dark frame is publicly available (see the project's data
provenance notes), so gongsynth ships *synthetic* GONG-like defaults, built
deterministically from a fixed seed so that the camera and the reduction see
the same maps:

* `synthetic_flat`: a large-scale gradient (a linear tilt plus radial
  vignetting), soft-edged circular dust shadows (out-of-focus dust on a window
  near the focal plane) and ~1 % white pixel-response non-uniformity (PRNU);
  median-normalised.
* `synthetic_dark`: mean dark current per frame with a smooth amplifier-glow
  gradient and a sprinkling of hot pixels.

Both are illustrative, not measured.  Real maps can be read from FITS with
`read_flat` and `read_dark`.  `normalise_flat` and `prepare_dark` check and
bring any user map to the form the camera (and the reduction) use.
"""
import os

import astropy.units as u
import numpy as np
from astropy.io import fits

from gongsynth.planes import N_PLANES
from gongsynth.seeding import stage_generator
from gongsynth.validation import check_finite, check_quantity

__all__ = ["synthetic_flat", "synthetic_dark", "read_flat", "read_dark", "normalise_flat",
           "prepare_dark", "DEFAULT_MAP_SEED"]

#: Seed of the default synthetic flat and dark (fixed, so every stage sees the same maps).
DEFAULT_MAP_SEED = 20190601


def _shape2(shape, name="shape"):
    try:
        ny, nx = (int(s) for s in shape)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a pair of positive ints (ny, nx), got {shape!r}") from None
    if ny < 1 or nx < 1:
        raise ValueError(f"{name} must be a pair of positive ints (ny, nx), got {shape!r}")
    return ny, nx


def synthetic_flat(shape=(860, 860), *, seed=DEFAULT_MAP_SEED, tilt=0.03, vignetting=0.04,
                   dust_density=40.0, dust_depth=(0.01, 0.05), dust_radius=(3.0, 12.0), prnu=0.01):
    """
    A synthetic GONG-like flat field (gain map), median-normalised.

    flat = (1 + tilt·(x̂ cos α + ŷ sin α) − vignetting·r̂²) × Π(1 − dust) × (1 + prnu·N(0, 1)),
    with x̂, ŷ ∈ [−1, 1] across the detector, r̂ the distance from the centre
    in units of the half diagonal, and each dust shadow a soft-edged disc
    d / (1 + (r/R)⁸).

    Parameters
    ----------
    shape : tuple of int
        (ny, nx) in pixels.
    seed : seed-like
        Seed of the dust positions, gradient direction and PRNU.
    tilt : float
        Peak-to-centre amplitude of the linear gradient (fraction).
    vignetting : float
        Fractional darkening in the corners.
    dust_density : float
        Mean number of dust shadows per million pixels (≈ 30 on 860 × 860).
    dust_depth : tuple of float
        Range of the shadows' central depths (fraction), drawn uniformly.
    dust_radius : tuple of float
        Range of the shadows' radii in pixels, drawn uniformly.
    prnu : float
        RMS pixel-to-pixel response non-uniformity (fraction).

    Returns
    -------
    `numpy.ndarray`
        float64, shape (ny, nx), strictly positive, median 1.

    Examples
    --------
    >>> f = synthetic_flat((64, 64))
    >>> f.shape, float(np.median(f))
    ((64, 64), 1.0)
    >>> bool(0.005 < np.std(f - np.roll(f, 1, axis=1)) / np.sqrt(2) < 0.02)
    True
    """
    ny, nx = _shape2(shape)
    for name, value in (("tilt", tilt), ("vignetting", vignetting), ("prnu", prnu),
                        ("dust_density", dust_density)):
        if not (np.isfinite(value) and 0 <= value < (1e6 if name == "dust_density" else 0.5)):
            raise ValueError(f"{name} must be a small non-negative number, got {value!r}")
    rng = stage_generator(seed, "synthetic-flat")
    y = np.linspace(-1, 1, ny)[:, None]
    x = np.linspace(-1, 1, nx)[None, :]
    alpha = rng.uniform(0, 2 * np.pi)
    flat = 1 + tilt * (x * np.cos(alpha) + y * np.sin(alpha)) - vignetting * (x**2 + y**2) / 2
    n_dust = rng.poisson(dust_density * ny * nx / 1e6)
    yy, xx = np.arange(ny)[:, None], np.arange(nx)[None, :]
    for _ in range(n_dust):
        cy, cx = rng.uniform(0, ny), rng.uniform(0, nx)
        radius = rng.uniform(*dust_radius)
        depth = rng.uniform(*dust_depth)
        # Work on a window around the shadow; (r/R)^8 is < 1e-8 beyond 10 R.
        h = int(np.ceil(10 * radius))
        sy = slice(max(int(cy) - h, 0), min(int(cy) + h + 1, ny))
        sx = slice(max(int(cx) - h, 0), min(int(cx) + h + 1, nx))
        r2 = ((yy[sy] - cy) ** 2 + (xx[:, sx] - cx) ** 2) / radius**2
        flat[sy, sx] *= 1 - depth / (1 + r2**4)
    flat = flat * (1 + prnu * rng.standard_normal((ny, nx)))
    if np.any(flat <= 0):  # only for absurd parameters
        raise ValueError("synthetic_flat parameters give non-positive pixels; reduce prnu or dust_depth")
    return flat / np.median(flat)


def synthetic_dark(shape=(860, 860), *, level=30 * u.electron, seed=DEFAULT_MAP_SEED, glow=0.2,
                   hot_fraction=1e-3, hot_factor=10.0):
    """
    A synthetic dark-current map in electrons per frame.

    dark = level × (1 + glow·g(x, y)) with g a smooth amplifier-glow ramp that
    is 1 in one corner and falls off over a quarter of the detector (mean of
    g ≈ 0.1), and a fraction ``hot_fraction`` of hot pixels at ``hot_factor``
    times the level.

    Parameters
    ----------
    shape : tuple of int
        (ny, nx) in pixels.
    level : `~astropy.units.Quantity`
        Typical dark current per frame, electron (default 30 e⁻ ≈ 0.9 ADU per
        1/60 s frame: illustrative, not a measured GONG value).
    seed : seed-like
        Seed of the hot-pixel positions.
    glow : float
        Amplitude of the amplifier glow relative to ``level``.
    hot_fraction : float
        Fraction of hot pixels.
    hot_factor : float
        Dark current of a hot pixel in units of ``level``.

    Returns
    -------
    `~astropy.units.Quantity`
        float64, shape (ny, nx), electron per frame, non-negative.

    Examples
    --------
    >>> import astropy.units as u
    >>> d = synthetic_dark((32, 32), level=10 * u.electron)
    >>> d.unit, d.shape, bool(10 <= float(np.median(d.value)) < 12)
    (Unit("electron"), (32, 32), True)
    """
    ny, nx = _shape2(shape)
    check_quantity(level, u.electron, "level")
    lvl = float(level.to_value(u.electron))
    if not np.isfinite(lvl) or lvl < 0:
        raise ValueError(f"level must be finite and non-negative, got {level}")
    if not (0 <= hot_fraction <= 1) or hot_factor < 0 or glow < 0:
        raise ValueError("glow, hot_fraction (0-1) and hot_factor must be non-negative")
    rng = stage_generator(seed, "synthetic-dark")
    y = np.arange(ny)[:, None] / max(ny - 1, 1)
    x = np.arange(nx)[None, :] / max(nx - 1, 1)
    dark = lvl * (1 + glow * np.exp(-np.hypot(x, y) / 0.25))
    hot = rng.random((ny, nx)) < hot_fraction
    dark[hot] = lvl * hot_factor
    return dark * u.electron


def _read_image(path, name):
    """First image (primary or first extension with data) of a FITS file, and its header."""
    path = os.fspath(path)
    if not os.path.exists(path):
        raise FileNotFoundError(f"{name}: no such file {path!r}")
    with fits.open(path) as hdul:
        for hdu in hdul:
            if hdu.data is not None and hdu.is_image:
                return np.array(hdu.data, dtype=np.float64), hdu.header.copy()
    raise ValueError(f"{name}: {path!r} contains no image data")


def read_flat(path):
    """
    Read a flat field from FITS: the first image HDU, shape (ny, nx) or (6, ny, nx).

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    `numpy.ndarray`
        float64, not yet normalised (see `normalise_flat`).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from astropy.io import fits
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "flat.fits"
    >>> fits.PrimaryHDU(np.full((4, 5), 2.0)).writeto(path)
    >>> read_flat(path).shape
    (4, 5)
    """
    data, _ = _read_image(path, "flat")
    return data


def read_dark(path, unit=None):
    """
    Read a dark-current map (electrons per frame) from FITS.

    Parameters
    ----------
    path : str or path-like
        File whose first image HDU is the (ny, nx) dark map.
    unit : `~astropy.units.Unit`, optional
        Unit of the data if the header has no ``BUNIT`` (must be convertible
        to electron).

    Returns
    -------
    `~astropy.units.Quantity`
        In electron (per frame).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from astropy.io import fits
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "dark.fits"
    >>> fits.PrimaryHDU(np.full((4, 5), 30.0)).writeto(path)
    >>> read_dark(path, unit=u.electron)[0, 0]
    <Quantity 30. electron>
    """
    data, header = _read_image(path, "dark")
    bunit = header.get("BUNIT")
    if bunit:
        unit = u.Unit(bunit, parse_strict="raise")
    if unit is None:
        raise ValueError(f"dark file {os.fspath(path)!r} has no BUNIT; pass unit=u.electron")
    return check_quantity(data * u.Unit(unit), u.electron, "dark").to(u.electron)


def normalise_flat(flat, shape):
    """
    Check a flat field and normalise each plane by its median.

    Parameters
    ----------
    flat : array_like, dimensionless `~astropy.units.Quantity`, str or path-like
        Multiplicative gain map, shape (ny, nx) (the same for all planes) or
        (6, ny, nx); a path is read with `read_flat`.
    shape : tuple of int
        (ny, nx) of the detector.

    Returns
    -------
    `numpy.ndarray`
        float64, shape (6, ny, nx), every plane with median 1 (a read-only
        broadcast view when one map serves all planes).

    Raises
    ------
    ValueError
        On a wrong shape, non-finite values, or values ≤ 0.

    Examples
    --------
    >>> f = normalise_flat(np.full((4, 5), 2.0), (4, 5))
    >>> f.shape, float(f.max())
    ((6, 4, 5), 1.0)
    """
    ny, nx = _shape2(shape)
    if isinstance(flat, (str, os.PathLike)):
        flat = read_flat(flat)
    if isinstance(flat, u.Quantity):
        if not flat.unit.is_equivalent(u.one):
            raise u.UnitsError(f"flat must be dimensionless, got unit {flat.unit}")
        flat = flat.to_value(u.one)
    flat = np.asarray(flat, dtype=np.float64)
    if flat.shape not in ((ny, nx), (N_PLANES, ny, nx)):
        raise ValueError(f"flat must have shape {(ny, nx)} or {(N_PLANES, ny, nx)}, got {flat.shape}")
    check_finite(flat, "flat")
    bad = int(np.count_nonzero(flat <= 0))
    if bad:
        raise ValueError(f"flat must be strictly positive (it multiplies the signal and is "
                         f"divided out in the reduction); it has {bad} zero or negative pixel(s)")
    if flat.ndim == 2:
        return np.broadcast_to(flat / np.median(flat), (N_PLANES, ny, nx))
    return flat / np.median(flat.reshape(N_PLANES, -1), axis=1)[:, None, None]


def prepare_dark(dark, shape):
    """
    Check a dark-current map and broadcast it to the detector.

    Parameters
    ----------
    dark : `~astropy.units.Quantity`, str or path-like
        Electrons per frame, scalar or shape (ny, nx); a path is read with
        `read_dark`.
    shape : tuple of int
        (ny, nx) of the detector.

    Returns
    -------
    `~astropy.units.Quantity`
        float64, shape (ny, nx), electron (per frame).

    Raises
    ------
    TypeError, astropy.units.UnitsError, ValueError
        If ``dark`` is not in electrons, has the wrong shape, non-finite or
        negative values.

    Examples
    --------
    >>> import astropy.units as u
    >>> prepare_dark(5 * u.electron, (2, 3)).shape
    (2, 3)
    """
    ny, nx = _shape2(shape)
    if isinstance(dark, (str, os.PathLike)):
        dark = read_dark(dark)
    check_quantity(dark, u.electron, "dark")
    values = np.asarray(dark.to_value(u.electron), dtype=np.float64)
    if values.ndim != 0 and values.shape != (ny, nx):
        raise ValueError(f"dark must be a scalar or have shape {(ny, nx)}, got {values.shape}")
    check_finite(values, "dark")
    if np.any(values < 0):
        raise ValueError(f"dark must be non-negative (electrons per frame); "
                         f"{int(np.count_nonzero(values < 0))} pixel(s) are negative")
    return np.broadcast_to(values, (ny, nx)).copy() * u.electron
