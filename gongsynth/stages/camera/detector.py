"""
Detector calibration maps: flat field and dark current.

No real GONG flat or dark frame is publicly available (see the project's data
provenance notes), so gongsynth ships *synthetic* GONG-like defaults, built
deterministically from a fixed seed so that the camera and the reduction see
the same maps (every knob, and the seed, is a `~gongsynth.GONGInstrument`
field):

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

from gongsynth import instruments
from gongsynth.seeding import stage_generator
from gongsynth.validation import check_finite, check_quantity

__all__ = ["synthetic_flat", "synthetic_dark", "read_flat", "read_dark", "normalise_flat",
           "prepare_dark"]


def _shape2(shape, name="shape"):
    try:
        ny, nx = (int(s) for s in shape)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a pair of positive ints (ny, nx), got {shape!r}") from None
    if ny < 1 or nx < 1:
        raise ValueError(f"{name} must be a pair of positive ints (ny, nx), got {shape!r}")
    return ny, nx


def _detector_shape(shape, inst):
    """``shape`` as (ny, nx), or the instrument's square detector when None."""
    if shape is None:
        return inst.detector_shape, inst.detector_shape
    return _shape2(shape)


def _number(value, default, unit):
    """A keyword override as a float, or the instrument's value in ``unit``."""
    value = default if value is None else value
    return float(u.Quantity(value, unit).to_value(unit)) if isinstance(value, u.Quantity) else value


def synthetic_flat(shape=None, *, instrument=None, seed=None, tilt=None, vignetting=None,
                   dust_density=None, dust_depth=None, dust_radius=None, prnu=None):
    """
    A synthetic GONG-like flat field (gain map), median-normalised.

    flat = (1 + tilt·(x̂ cos α + ŷ sin α) − vignetting·r̂²) × Π(1 − dust) × (1 + prnu·N(0, 1)),
    with x̂, ŷ ∈ [−1, 1] across the detector, r̂ the distance from the centre
    in units of the half diagonal, and each dust shadow a soft-edged disc
    d / (1 + (r/R)⁸).

    Every knob defaults to the instrument's value (`~gongsynth.GONGInstrument`
    fields ``detector_map_seed`` and ``flat_*``); a keyword overrides it.

    Parameters
    ----------
    shape : tuple of int, optional
        (ny, nx) in pixels; default the instrument's ``detector_shape`` square.
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
        Supplies the defaults below.
    seed : seed-like, optional
        Seed of the dust positions, gradient direction and PRNU
        (``detector_map_seed``, 20190601).
    tilt : float, optional
        Peak-to-centre amplitude of the linear gradient, fraction (``flat_tilt``, 0.03).
    vignetting : float, optional
        Fractional darkening in the corners (``flat_vignetting``, 0.04).
    dust_density : float, optional
        Mean number of dust shadows per million pixels (``flat_dust_density``,
        40, ≈ 30 on 860 × 860).
    dust_depth : tuple of float, optional
        Range of the shadows' central depths (fraction), drawn uniformly
        (``flat_dust_depth_min``, ``flat_dust_depth_max``: 0.01, 0.05).
    dust_radius : tuple of float, optional
        Range of the shadows' radii in pixels, drawn uniformly
        (``flat_dust_radius_min``, ``flat_dust_radius_max``: 3, 12).
    prnu : float, optional
        RMS pixel-to-pixel response non-uniformity, fraction (``flat_prnu``, 0.01).

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
    inst = instruments.get(instrument)
    ny, nx = _detector_shape(shape, inst)
    knobs = inst.detector_maps  # the synthetic maps' parameters
    seed = knobs.detector_map_seed if seed is None else seed
    tilt = _number(tilt, knobs.flat_tilt, u.one)
    vignetting = _number(vignetting, knobs.flat_vignetting, u.one)
    dust_density = _number(dust_density, knobs.flat_dust_density, 1 / u.Mpix)
    prnu = _number(prnu, knobs.flat_prnu, u.one)
    if dust_depth is None:
        dust_depth = (knobs.flat_dust_depth_min, knobs.flat_dust_depth_max)
    if dust_radius is None:
        dust_radius = (knobs.flat_dust_radius_min, knobs.flat_dust_radius_max)
    dust_depth = tuple(_number(d, None, u.one) for d in dust_depth)
    dust_radius = tuple(_number(r, None, u.pix) for r in dust_radius)
    for name, value in (("tilt", tilt), ("vignetting", vignetting), ("prnu", prnu),
                        ("dust_density", dust_density)):
        if not (np.isfinite(value) and 0 <= value < (1e6 if name == "dust_density" else 0.5)):
            raise ValueError(f"{name} must be a small non-negative number, got {value!r}")
    for name, (low, high), top in (("dust_depth", dust_depth, 1.0), ("dust_radius", dust_radius, np.inf)):
        if not (np.isfinite(low) and np.isfinite(high) and 0 <= low <= high < top):
            raise ValueError(f"{name} must be an ordered (min, max) pair of non-negative numbers"
                             f"{' below 1' if top == 1 else ''}, got {(low, high)!r}")
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


def synthetic_dark(shape=None, *, instrument=None, level=None, seed=None, glow=None, glow_length=None,
                   hot_fraction=None, hot_factor=None):
    """
    A synthetic dark-current map in electrons per frame.

    dark = level × (1 + glow·exp(−ρ / glow_length)) with ρ the distance from
    one corner in units of the detector side (an amplifier-glow ramp, mean
    ≈ 0.1 of ``glow`` for the default length), and a fraction
    ``hot_fraction`` of hot pixels at ``hot_factor`` times the level.

    Every knob defaults to the instrument's value (`~gongsynth.GONGInstrument`
    fields ``detector_map_seed`` and ``dark_*``); a keyword overrides it.

    Parameters
    ----------
    shape : tuple of int, optional
        (ny, nx) in pixels; default the instrument's ``detector_shape`` square.
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
        Supplies the defaults below.
    level : `~astropy.units.Quantity`, optional
        Typical dark current per frame, electron (``dark_level``, 30 e⁻ ≈ 0.9
        ADU per 1/60 s frame: illustrative, not a measured GONG value).
    seed : seed-like, optional
        Seed of the hot-pixel positions (``detector_map_seed``).
    glow : float, optional
        Amplitude of the amplifier glow relative to ``level`` (``dark_glow``, 0.2).
    glow_length : float, optional
        e-folding length of the glow in units of the detector side
        (``dark_glow_length``, 0.25).
    hot_fraction : float, optional
        Fraction of hot pixels (``dark_hot_fraction``, 0.001).
    hot_factor : float, optional
        Dark current of a hot pixel in units of ``level`` (``dark_hot_factor``, 10).

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
    inst = instruments.get(instrument)
    ny, nx = _detector_shape(shape, inst)
    knobs = inst.detector_maps  # the synthetic maps' parameters
    level = knobs.dark_level if level is None else level
    seed = knobs.detector_map_seed if seed is None else seed
    glow = _number(glow, knobs.dark_glow, u.one)
    glow_length = _number(glow_length, knobs.dark_glow_length, u.one)
    hot_fraction = _number(hot_fraction, knobs.dark_hot_fraction, u.one)
    hot_factor = _number(hot_factor, knobs.dark_hot_factor, u.one)
    check_quantity(level, u.electron, "level")
    lvl = float(level.to_value(u.electron))
    if not np.isfinite(lvl) or lvl < 0:
        raise ValueError(f"level must be finite and non-negative, got {level}")
    if not (0 <= hot_fraction <= 1) or hot_factor < 0 or glow < 0:
        raise ValueError("glow, hot_fraction (0-1) and hot_factor must be non-negative")
    if not glow_length > 0:
        raise ValueError(f"glow_length must be positive, got {glow_length!r}")
    rng = stage_generator(seed, "synthetic-dark")
    y = np.arange(ny)[:, None] / max(ny - 1, 1)
    x = np.arange(nx)[None, :] / max(nx - 1, 1)
    dark = lvl * (1 + glow * np.exp(-np.hypot(x, y) / glow_length))
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


def normalise_flat(flat, shape, n_planes=6):
    """
    Check a flat field and normalise each plane by its median.

    Parameters
    ----------
    flat : array_like, dimensionless `~astropy.units.Quantity`, str or path-like
        Multiplicative gain map, shape (ny, nx) (the same for all planes) or
        (n_planes, ny, nx); a path is read with `read_flat`.
    shape : tuple of int
        (ny, nx) of the detector.
    n_planes : int
        The instrument's number of raw planes K (GONG's 6 by default).

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
    if flat.shape not in ((ny, nx), (n_planes, ny, nx)):
        raise ValueError(f"flat must have shape {(ny, nx)} or {(n_planes, ny, nx)}, got {flat.shape}")
    if flat.ndim == 3 and flat.strides[0] == 0:
        flat = flat[0]     # one map broadcast to every plane (as this returns it): checked and kept once
    check_finite(flat, "flat")
    bad = int(np.count_nonzero(flat <= 0))
    if bad:
        raise ValueError(f"flat must be strictly positive (it multiplies the signal and is "
                         f"divided out in the reduction); it has {bad} zero or negative pixel(s)")
    if flat.ndim == 2:
        return np.broadcast_to(flat / np.median(flat), (n_planes, ny, nx))
    return flat / np.median(flat.reshape(n_planes, -1), axis=1)[:, None, None]


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
