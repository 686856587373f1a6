"""
Where the solar disk lies on a map: pixel ↔ helioprojective positions, distance
from disk centre, μ and the local pixel scale, for any map sunpy reads.

These are the geometry helpers that the statistics, the degrading to GONG and
the header checks of real observations share.  Positions on the disk are
measured in units of the apparent solar radius of the map's observer, so the
same call means the same region for GONG, MDI and HMI.  Helioprojective maps
go through plain WCS arithmetic (no coordinate-frame machinery); heliographic
ones (e.g. a Postel HMI cut-out) through sunpy's coordinate transformations.
"""
import astropy.units as u
import numpy as np
import sunpy.map
from astropy.coordinates import SkyCoord
from astropy.wcs.utils import wcs_to_celestial_frame
from sunpy.coordinates import frames

from gongsynth.geometry import Pointing

__all__ = [
    "check_map",
    "map_values",
    "map_wcs",
    "helioprojective_frame",
    "is_helioprojective",
    "pixel_to_helioprojective",
    "helioprojective_to_pixel",
    "disk_centre_pixel",
    "disk_coordinates",
    "local_pixel_scale",
    "disk_values",
    "tiled_pointing",
]


def check_map(smap, name="smap", *, finite=False):
    """
    Check that ``smap`` is a 2-D sunpy Map (with a finite pixel, if asked).

    Parameters
    ----------
    smap : object
        What the caller was given.
    name : str
        Its name in the error message.
    finite : bool
        Also require at least one finite pixel.

    Returns
    -------
    `~sunpy.map.GenericMap`
        ``smap`` itself.

    Raises
    ------
    TypeError
        If ``smap`` is not a sunpy Map.
    ValueError
        If its data are not 2-D, or (``finite``) hold no finite pixel.

    Examples
    --------
    >>> import numpy as np
    >>> check_map(np.zeros((2, 2)))
    Traceback (most recent call last):
    ...
    TypeError: smap must be a sunpy Map, got ndarray
    """
    if not isinstance(smap, sunpy.map.GenericMap):
        raise TypeError(f"{name} must be a sunpy Map, got {type(smap).__name__}")
    if smap.data.ndim != 2:
        raise ValueError(f"{name} must be a 2-D map, got data of shape {smap.data.shape}")
    if finite and not np.isfinite(np.asarray(smap.data, dtype=float)).any():
        raise ValueError(f"{name} holds no finite pixel (all NaN or infinite)")
    return smap


def map_values(smap):
    """
    The map's data as a float64 array, masked pixels set to NaN.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`

    Returns
    -------
    `numpy.ndarray`
        (ny, nx), in the map's unit.
    """
    data = np.asarray(smap.data, dtype=np.float64)
    if smap.mask is not None and np.any(smap.mask):
        data = np.where(smap.mask, np.nan, data)
    return data


def _geometry(smap, name, compute):
    """
    ``compute()``, remembered on the map for as long as its header and shape are unchanged.

    sunpy rebuilds a map's WCS on every access, and for a GONG map that means
    placing the site's observer again (an ITRS transformation, ~0.1 s): the
    statistics of two maps asked for it some 350 times.
    """
    key = (smap.data.shape, tuple(sorted((str(k), repr(v)) for k, v in smap.meta.items())))
    cached = smap.__dict__.get("_gongsynth_geometry")
    if cached is None or cached[0] != key:
        cached = (key, {})
        smap.__dict__["_gongsynth_geometry"] = cached
    if name not in cached[1]:
        cached[1][name] = compute()
    return cached[1][name]


def map_wcs(smap):
    """
    The map's WCS, built once per header (sunpy builds it again at every ``smap.wcs``).

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`

    Returns
    -------
    `~astropy.wcs.WCS`
        Shared between calls: do not modify it.
    """
    return _geometry(smap, "wcs", lambda: smap.wcs)


def helioprojective_frame(smap):
    """
    The helioprojective frame of the map's observer at its reference date.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`

    Returns
    -------
    `~sunpy.coordinates.frames.Helioprojective`
    """
    return _geometry(smap, "frame", lambda: frames.Helioprojective(
        observer=smap.observer_coordinate, obstime=smap.reference_date, rsun=smap.rsun_meters))


def is_helioprojective(smap):
    """
    Whether the map's WCS is helioprojective.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`

    Returns
    -------
    bool
    """
    return _geometry(smap, "helioprojective",
                     lambda: isinstance(wcs_to_celestial_frame(map_wcs(smap)), frames.Helioprojective))


def pixel_to_helioprojective(smap, x, y):
    """
    Helioprojective (Tx, Ty) in arcsec of 0-based pixel positions.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
    x, y : array_like
        0-based pixel positions (any matching shapes).

    Returns
    -------
    tx, ty : `numpy.ndarray`
        Arcsec, as seen by the map's observer; Tx wrapped into [-180°, 180°).
    """
    wcs = map_wcs(smap)
    if is_helioprojective(smap):
        # Plain WCS arithmetic: no coordinate-frame machinery needed for the map's own frame.
        tx, ty = wcs.pixel_to_world_values(x, y)
        units = [u.Unit(un) for un in wcs.world_axis_units]
        tx = (np.asarray(tx) * units[0]).to_value(u.arcsec)
        ty = (np.asarray(ty) * units[1]).to_value(u.arcsec)
        return (tx + 648000) % 1296000 - 648000, ty  # longitudes to [-180, 180) deg
    c = wcs.pixel_to_world(x, y).transform_to(helioprojective_frame(smap))
    return c.Tx.to_value(u.arcsec), c.Ty.to_value(u.arcsec)


def helioprojective_to_pixel(smap, tx, ty):
    """
    0-based pixel positions of helioprojective points of the map's observer.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
    tx, ty : float or array_like
        Helioprojective longitude and latitude, arcsec.

    Returns
    -------
    x, y : `numpy.ndarray`
        1-D float arrays (NaN where the point is not on the map's projection).
    """
    wcs = map_wcs(smap)
    if is_helioprojective(smap):
        units = [u.Unit(un) for un in wcs.world_axis_units]
        x, y = wcs.world_to_pixel_values((np.atleast_1d(tx) * u.arcsec).to_value(units[0]),
                                              (np.atleast_1d(ty) * u.arcsec).to_value(units[1]))
        return np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    c = SkyCoord(np.atleast_1d(tx) * u.arcsec, np.atleast_1d(ty) * u.arcsec,
                 frame=helioprojective_frame(smap))
    x, y = wcs.world_to_pixel(c)
    return np.asarray(x, dtype=float), np.asarray(y, dtype=float)


def disk_centre_pixel(smap):
    """
    0-based (x, y) pixel position of disk centre, or of the map centre if disk centre is off the map.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`

    Returns
    -------
    (float, float)
    """
    x, y = helioprojective_to_pixel(smap, 0.0, 0.0)
    ny, nx = smap.data.shape
    x, y = float(x[0]), float(y[0])
    if not (np.isfinite(x) and np.isfinite(y)) or not (-0.5 <= x <= nx - 0.5 and -0.5 <= y <= ny - 0.5):
        return (nx - 1) / 2, (ny - 1) / 2
    return x, y


def disk_coordinates(smap):
    """
    Distance from disk centre (in solar radii) and μ = cos θ of every pixel.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        Any map whose WCS sunpy understands (helioprojective, or heliographic
        such as a Postel cut-out).

    Returns
    -------
    rho : `numpy.ndarray`
        (ny, nx) apparent distance from disk centre divided by the apparent
        solar radius ``smap.rsun_obs`` (1 at the limb); NaN where undefined.
    mu : `numpy.ndarray`
        (ny, nx) √(1 - ρ²) on the disk, NaN off the disk (the observer's
        finite distance shifts the limb by ~0.5 % of ρ and is ignored).

    Examples
    --------
    >>> import astropy.units as u
    >>> import numpy as np
    >>> import sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> m = sunpy.map.Map(np.zeros((9, 9)), sunpy.map.make_fitswcs_header(
    ...     (9, 9), ref, scale=[250, 250] * u.arcsec / u.pix))
    >>> rho, mu = disk_coordinates(m)
    >>> round(float(rho[4, 4]), 6), round(float(mu[4, 4]), 6)
    (0.0, 1.0)
    """
    check_map(smap)
    ny, nx = smap.data.shape
    y, x = np.mgrid[:ny, :nx]
    tx, ty = pixel_to_helioprojective(smap, x, y)
    rho = np.hypot(tx, ty) / smap.rsun_obs.to_value(u.arcsec)
    with np.errstate(invalid="ignore"):
        mu = np.where(rho <= 1, np.sqrt(np.clip(1 - rho**2, 0, None)), np.nan)
    return rho, mu


def local_pixel_scale(smap, pixel=None):
    """
    Side of one pixel on the sky (arcsec) at a given pixel, measured through the WCS.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
    pixel : (float, float), optional
        0-based (x, y) pixel position; default: the pixel nearest disk centre
        (the map centre if disk centre is off the map).

    Returns
    -------
    `~astropy.units.Quantity`
        Geometric mean of the x and y pixel sides, arcsec.

    Examples
    --------
    >>> import astropy.units as u
    >>> import numpy as np
    >>> import sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> m = sunpy.map.Map(np.zeros((8, 8)), sunpy.map.make_fitswcs_header(
    ...     (8, 8), ref, scale=[2.5, 2.5] * u.arcsec / u.pix))
    >>> local_pixel_scale(m).round(6)
    <Quantity 2.5 arcsec>
    """
    check_map(smap)
    if pixel is None:
        pixel = disk_centre_pixel(smap)
    x, y = (float(p) for p in pixel)
    px = np.array([x - 0.5, x + 0.5, x, x])
    py = np.array([y, y, y - 0.5, y + 0.5])
    tx, ty = pixel_to_helioprojective(smap, px, py)
    sx = np.hypot(tx[1] - tx[0], ty[1] - ty[0])
    sy = np.hypot(tx[3] - tx[2], ty[3] - ty[2])
    scale = np.sqrt(sx * sy)
    if not np.isfinite(scale) or scale <= 0:
        raise ValueError(f"cannot measure the pixel scale of the map at pixel ({x}, {y})")
    return scale * u.arcsec


def disk_values(smap, max_radius, name="smap"):
    """
    The finite map values within ``max_radius`` solar radii of disk centre.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
    max_radius : float
        Solar radii.
    name : str
        Name of the map in error messages.

    Returns
    -------
    `numpy.ndarray`
        1-D float64, in the map's unit (masked and non-finite pixels left out).

    Examples
    --------
    >>> import astropy.units as u
    >>> import numpy as np
    >>> import sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> m = sunpy.map.Map(np.ones((9, 9)), sunpy.map.make_fitswcs_header(
    ...     (9, 9), ref, scale=[250, 250] * u.arcsec / u.pix))
    >>> disk_values(m, 0.5).size   # the 3 x 3 pixels nearest disk centre, 250" apart
    9
    """
    check_map(smap, name)
    data = map_values(smap)
    rho, _ = disk_coordinates(smap)
    with np.errstate(invalid="ignore"):
        keep = np.isfinite(data) & (rho < max_radius)
    return data[keep]


def tiled_pointing(smap):
    """
    The pointing of a simulated tiled map's run, or None for any other map.

    A tiled run (header ``SIMMODE = 'tiled'``) is one box of the Sun seen at one
    angle and repeated over the frame; its WCS places only the frame's centre on
    the disk.  Tools that need a pixel's viewing angle or a distance on the Sun
    use this pointing instead of the WCS.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap` or dict-like
        A map, or its header.

    Returns
    -------
    `~gongsynth.geometry.Pointing` or None
        The run's field-centre latitude (``SIMLAT``) at its start (``DATE-BEG``).
    """
    meta = getattr(smap, "meta", smap)
    if str(meta.get("simmode", "")).strip().lower() != "tiled" or meta.get("simlat") is None:
        return None
    start = meta.get("date-beg") or meta.get("date-obs")
    return Pointing(float(meta["simlat"]) * u.deg, start)
