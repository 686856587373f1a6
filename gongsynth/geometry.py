"""
Viewing geometry: where the telescope points, how each column is seen, and the sky's WCS.

The one home of geometry for every stage: `Pointing` (latitude and time →
μ, line-of-sight azimuth, field centre, km per arcsec), `disk_geometry` (every
sample of a full-disk grid traced to the solar sphere), `los_basis` (the line
of sight in a column's local frame) and `wcs_header` (the helioprojective WCS of
every grid and product).

Local frame (CONTRACTS): x = west, y = north, z = up.  The unit vector toward
the observer is n = (sinθ cos a, sinθ sin a, cosθ) with θ = arccos μ and
a = ``los_azimuth``; a = -90° is a region north of disk centre on the central
meridian.  The sky frame (e1, e2, n) is right-handed with e1 the projection of
the local +x (west) onto the plane of the sky, so e1 = x, e2 = y at disk centre.
Stokes Q > 0 is linear polarisation along e1.
"""
import functools
import math
from collections import namedtuple

import astropy.units as u
import numpy as np
from astropy.coordinates import SkyCoord
from astropy.time import Time

from gongsynth.validation import check_quantity

__all__ = ["DEFAULT_OBSTIME", "TELESCOPE", "Pointing", "DiskGeometry", "as_obstime", "check_geometry",
           "disk_geometry", "field_centre", "los_basis", "pointing_centre", "pointing_offset",
           "viewing_geometry", "wcs_header"]


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


#: Default observation time: B0 = -0.3″ (the Sun's equator faces Earth), 1.0148 au.
DEFAULT_OBSTIME = Time("2019-06-07T00:20:00", scale="utc")

#: Telescope name written into every gongsynth WCS header: never ends in "GONG",
#: so sunpy's real-GONG map sources do not claim simulated files.
TELESCOPE = "gongsynth (simulated GONG)"


def as_obstime(obstime):
    """
    The observation time as an `~astropy.time.Time` (`DEFAULT_OBSTIME` for None).

    Parameters
    ----------
    obstime : `~astropy.time.Time`, str or None

    Returns
    -------
    `~astropy.time.Time`

    Examples
    --------
    >>> as_obstime(None).isot
    '2019-06-07T00:20:00.000'
    """
    if obstime is None:
        return DEFAULT_OBSTIME
    if isinstance(obstime, Time):
        return obstime      # resolved once (by the run's Pointing), never parsed again
    try:
        return Time(obstime)
    except ValueError as err:
        raise ValueError(f"obstime must be an astropy Time or a time string, got {obstime!r}") from err


class Pointing:
    """
    Where the telescope looks: a field centred on the central meridian at ``latitude``.

    The one home of the run's viewing geometry: the latitude is checked once,
    and μ, the line-of-sight azimuth, the field centre and the length scale are
    computed once (on first use) for every stage that needs them.  The observer
    is at Earth at ``obstime``.

    Parameters
    ----------
    latitude : `~astropy.units.Quantity`
        Heliographic Stonyhurst latitude of the field centre, strictly between
        -90° and 90°.
    obstime : `~astropy.time.Time` or str, optional
        Default `DEFAULT_OBSTIME` (B0 ≈ 0).

    Examples
    --------
    >>> import astropy.units as u
    >>> p = Pointing(60 * u.deg)
    >>> round(p.mu, 4), p.los_azimuth
    (0.5, <Quantity -90. deg>)
    """

    def __init__(self, latitude=0 * u.deg, obstime=None):
        check_quantity(latitude, u.deg, "latitude")
        value = float(latitude.to_value(u.deg))
        if not -90 < value < 90:
            raise ValueError(f"latitude must lie strictly between -90 and 90 deg, got {latitude}")
        self.latitude = value * u.deg
        self.obstime = as_obstime(obstime)

    def __repr__(self):
        return f"Pointing(latitude={self.latitude}, obstime={self.obstime.isot!r})"

    def __eq__(self, other):
        return (isinstance(other, Pointing) and self.latitude == other.latitude
                and self.obstime == other.obstime)

    __hash__ = None

    @functools.cached_property
    def b0(self):
        """Heliographic latitude of the disk centre seen from Earth (`~astropy.units.Quantity`, deg)."""
        from sunpy.coordinates import sun
        return sun.B0(self.obstime).to(u.deg)

    @functools.cached_property
    def mu(self):
        """
        cos(latitude − B0), a float (observer at infinity: the 0.23° parallax of
        a point at 60° seen from 1 au is ignored, as in the paper).
        """
        return math.cos(math.radians(self.latitude.to_value(u.deg) - self.b0.to_value(u.deg)))

    @property
    def los_azimuth(self):
        """
        -90° when the observer lies toward the south of the region (latitude
        above B0), +90° otherwise (the CONTRACTS sign convention).
        """
        return (-90.0 if self.latitude >= self.b0 else 90.0) * u.deg

    def check_mu(self, mu, name="stokes"):
        """
        Raise unless spectra computed at ``mu`` belong to this pointing (to 1e-3).

        Parameters
        ----------
        mu : float or array_like
            The μ the spectra were computed for; a per-column μ (a full-disk
            cube) is refused, since a tiled field needs one viewing angle.
        name : str
            The argument named in the message.

        Raises
        ------
        ValueError
        """
        if np.ndim(mu) != 0:
            raise ValueError(f"{name} has a per-column mu (a full-disk cube); a tiled field needs one mu")
        if abs(float(mu) - self.mu) > 1e-3:
            raise ValueError(
                f"{name} was computed for mu = {float(mu):.4f} but latitude {self.latitude:g} is seen "
                f"at mu = {self.mu:.4f} (los_azimuth {self.los_azimuth:g}): pass the latitude the "
                f"spectra were made for, or synthesise them at that mu"
            )

    @functools.cached_property
    def _centre_and_scale(self):
        from sunpy.coordinates import HeliographicStonyhurst, Helioprojective, get_earth
        from sunpy.sun.constants import radius
        point = SkyCoord(0 * u.deg, self.latitude, radius,
                         frame=HeliographicStonyhurst(obstime=self.obstime))
        hpc = point.transform_to(Helioprojective(observer=get_earth(self.obstime), obstime=self.obstime))
        km_per_arcsec = hpc.distance.to(u.km) * u.arcsec.to(u.rad) / u.arcsec
        # Keep the 2-D direction only: sunpy then intersects pixels with the solar sphere.
        return SkyCoord(hpc.Tx, hpc.Ty, frame=hpc.frame.replicate_without_data()), km_per_arcsec

    @property
    def centre(self):
        """Helioprojective `~astropy.coordinates.SkyCoord` of the field centre (observer at Earth)."""
        return self._centre_and_scale[0]

    @property
    def km_per_arcsec(self):
        """
        Length on the Sun per arcsec of sky at the field centre, for a surface
        perpendicular to the line of sight (distance × 1″).
        """
        return self._centre_and_scale[1]


@u.quantity_input
def viewing_geometry(latitude: u.deg, obstime=None):
    """
    Viewing angle of a region on the central meridian: ``(Pointing.mu, Pointing.los_azimuth)``.

    Parameters
    ----------
    latitude : `~astropy.units.Quantity`
        Heliographic latitude, strictly between -90° and 90°.
    obstime : `~astropy.time.Time` or str, optional
        Default `DEFAULT_OBSTIME` (B0 ≈ 0).

    Returns
    -------
    mu : float
    los_azimuth : `~astropy.units.Quantity`

    Examples
    --------
    >>> import astropy.units as u
    >>> mu, az = viewing_geometry(60 * u.deg)
    >>> round(mu, 4), az
    (0.5, <Quantity -90. deg>)
    """
    pointing = Pointing(latitude, obstime)
    return pointing.mu, pointing.los_azimuth


@u.quantity_input
def field_centre(latitude: u.deg, obstime=None):
    """
    Field centre and length scale of a region on the central meridian:
    ``(Pointing.centre, Pointing.km_per_arcsec)``.

    Parameters
    ----------
    latitude : `~astropy.units.Quantity`
        Heliographic Stonyhurst latitude, strictly between -90° and 90°.
    obstime : `~astropy.time.Time` or str, optional
        Default `DEFAULT_OBSTIME`.

    Returns
    -------
    centre : `~astropy.coordinates.SkyCoord`
    km_per_arcsec : `~astropy.units.Quantity`

    Examples
    --------
    >>> import astropy.units as u
    >>> centre, scale = field_centre(0 * u.deg)
    >>> round(float(scale.to_value(u.km / u.arcsec)), 1)
    732.7
    """
    pointing = Pointing(latitude, obstime)
    return pointing.centre, pointing.km_per_arcsec


def wcs_header(shape, pixel_scale, centre, *, wavelength=None, unit=None):
    """
    Helioprojective FITS-WCS header of a grid centred on ``centre`` (the one WCS builder).

    Parameters
    ----------
    shape : (int, int)
        (ny, nx) of the grid.
    pixel_scale : `~astropy.units.Quantity`
        Angle per pixel (arcsec, or arcsec / pix).
    centre : `~astropy.coordinates.SkyCoord`
        Helioprojective coordinate (with observer and obstime) of the field
        centre, which lies at pixel ((nx - 1) / 2, (ny - 1) / 2); solar north up.
    wavelength : `~astropy.units.Quantity`, optional
        Written as WAVELNTH.
    unit : `~astropy.units.Unit`, optional
        Written as BUNIT.

    Returns
    -------
    `sunpy.util.MetaDict`
        From `sunpy.map.make_fitswcs_header`, with TELESCOP `TELESCOPE`.

    Examples
    --------
    >>> import astropy.units as u
    >>> header = wcs_header((100, 200), 0.5 * u.arcsec, Pointing(60 * u.deg).centre)
    >>> float(header["crpix1"]), float(header["cdelt2"]), header["ctype2"]
    (100.5, 0.5, 'HPLT-TAN')
    """
    import sunpy.map
    if pixel_scale.unit.is_equivalent(u.arcsec / u.pix):
        pixel_scale = pixel_scale * u.pix
    scale = pixel_scale.to_value(u.arcsec)
    ny, nx = shape
    return sunpy.map.make_fitswcs_header(
        (ny, nx), centre,
        reference_pixel=[(nx - 1) / 2, (ny - 1) / 2] * u.pix,
        scale=[scale, scale] * u.arcsec / u.pix,
        telescope=TELESCOPE, instrument="gongsynth", observatory="gongsynth",
        wavelength=wavelength, unit=unit,
    )


#: Per-sample geometry of a full-disk grid (arrays of the grid's shape).
DiskGeometry = namedtuple("DiskGeometry", ["on_disk", "mu", "los_azimuth", "longitude", "latitude",
                                           "x", "y"])
DiskGeometry.__doc__ = """
Geometry of each sample of a full-disk grid.

Attributes
----------
on_disk : `numpy.ndarray` of bool
    The line of sight meets the solar sphere (and μ > 0).
mu : `numpy.ndarray`
    Cosine of the angle between the local vertical and the direction to the
    observer (0 off the disk).
los_azimuth : `numpy.ndarray`
    Azimuth of the direction to the observer, deg, from local west toward north.
longitude, latitude : `numpy.ndarray`
    Heliographic Stonyhurst coordinates, deg (NaN off the disk).
x, y : `numpy.ndarray`
    Position in the photosphere's plane, km (sinusoidal projection; NaN off the disk).

Examples
--------
>>> import astropy.units as u
>>> g = disk_geometry((3, 3), 700 * u.arcsec)   # the corners are beyond the limb
>>> int(g.on_disk.sum()), round(float(g.latitude[2, 1]), 1)
(5, 47.6)
"""


def pointing_offset(pointing):
    """
    A pointing (Tx, Ty) checked and in radians: the offsets of a grid's centre from the Sun's.

    Parameters
    ----------
    pointing : `~astropy.units.Quantity` or None
        Two angles; None: (0, 0).

    Returns
    -------
    (float, float)

    Examples
    --------
    >>> import astropy.units as u
    >>> [round(v * 206264.806, 3) for v in pointing_offset([30, -4.5] * u.arcsec)]
    [30.0, -4.5]
    """
    if pointing is None:
        return 0.0, 0.0
    if isinstance(pointing, (tuple, list)) and all(isinstance(v, u.Quantity) for v in pointing):
        pointing = u.Quantity(pointing)   # a configuration's (Tx, Ty)
    check_quantity(pointing, u.arcsec, "pointing")
    values = pointing.to_value(u.rad)
    if values.shape != (2,) or not np.all(np.isfinite(values)):
        raise ValueError(f"pointing must be two finite angles (Tx, Ty), got {pointing}")
    return float(values[0]), float(values[1])


def pointing_centre(pointing, obstime):
    """
    The helioprojective coordinate of a full-disk grid's centre, seen from Earth at ``obstime``.

    Parameters
    ----------
    pointing : `~astropy.units.Quantity` or None
        (Tx, Ty); None: the Sun's centre.
    obstime : `~astropy.time.Time` or str

    Returns
    -------
    `~astropy.coordinates.SkyCoord`

    Examples
    --------
    >>> import astropy.units as u
    >>> c = pointing_centre([30, 0] * u.arcsec, "2009-09-05T18:54")
    >>> round(float(c.Tx.to_value(u.arcsec)), 6), c.observer.radius.unit
    (30.0, Unit("AU"))
    """
    from sunpy.coordinates import Helioprojective, get_earth
    time = as_obstime(obstime)
    x0, y0 = pointing_offset(pointing)
    return SkyCoord(x0 * u.rad, y0 * u.rad, frame=Helioprojective(observer=get_earth(time), obstime=time))


def _observer(obstime):
    from sunpy.coordinates import get_earth, sun
    from sunpy.sun.constants import radius
    time = as_obstime(obstime)
    distance = get_earth(time).radius.to_value(u.km)
    b0 = sun.B0(time).to_value(u.rad)
    return time, distance, float(b0), radius.to_value(u.km)


def disk_geometry(shape, pixel_scale, *, obstime=None, rows=None, pointing=None):
    """
    Trace every sample of a grid centred on the Sun (or near it) to the solar sphere.

    Pixel (i, j) looks along the gnomonic (TAN) direction of helioprojective
    offsets (Tx + (j - (nx-1)/2) × pixel_scale, Ty + (i - (ny-1)/2) × pixel_scale)
    from the Sun's centre, solar north up, as in the scene's WCS; (Tx, Ty) is
    the ``pointing`` of the grid's centre.

    Parameters
    ----------
    shape : (int, int)
        (ny, nx) of the grid.
    pixel_scale : `~astropy.units.Quantity`
        Arcsec per sample.
    obstime : `~astropy.time.Time` or str, optional
        Observer at Earth at this time; default `gongsynth.geometry.DEFAULT_OBSTIME`.
    rows : slice, optional
        Only these rows (for chunked processing).
    pointing : `~astropy.units.Quantity`, optional
        Helioprojective (Tx, Ty) of the grid's centre (default the Sun's
        centre; a real GONG image is off centre by up to tens of arcsec).

    Returns
    -------
    `DiskGeometry`

    Examples
    --------
    >>> import astropy.units as u
    >>> g = disk_geometry((5, 5), 400 * u.arcsec)
    >>> float(g.mu[2, 2]), bool(g.on_disk[0, 0])
    (1.0, False)
    """
    check_quantity(pixel_scale, u.arcsec, "pixel_scale")
    ny, nx = shape
    rows = slice(0, ny) if rows is None else rows
    _, dist, b0, radius = _observer(obstime)
    h = pixel_scale.to_value(u.rad)
    x0, y0 = pointing_offset(pointing)
    yy = y0 + (np.arange(ny)[rows] - (ny - 1) / 2) * h
    xx = x0 + (np.arange(nx) - (nx - 1) / 2) * h
    x, y = np.meshgrid(xx, yy)
    q = x * x + y * y
    norm = np.sqrt(1 + q)
    # Ray from the observer (0, 0, D) along (x, y, -1)/norm in heliocentric-
    # Cartesian axes; the discriminant written without cancellation.
    disc = radius**2 - dist**2 * q / (1 + q)
    on = disc > 0
    t = np.where(on, dist / norm - np.sqrt(np.where(on, disc, 0.0)), np.nan)
    px, py, pz = t * x / norm, t * y / norm, dist - t / norm
    cb, sb = math.cos(b0), math.sin(b0)

    def to_hgs(a, b, c):  # HCC (x west, y north, z to observer) -> Stonyhurst Cartesian
        return c * cb - b * sb, a, c * sb + b * cb

    X, Y, Z = to_hgs(px, py, pz)
    lat = np.arcsin(np.clip(Z / radius, -1, 1))
    lon = np.arctan2(Y, X)
    nX, nY, nZ = to_hgs(-x / norm, -y / norm, 1 / norm)  # unit vector toward the observer
    mu = (nX * X + nY * Y + nZ * Z) / radius
    west = -np.sin(lon) * nX + np.cos(lon) * nY
    north = -np.sin(lat) * (np.cos(lon) * nX + np.sin(lon) * nY) + np.cos(lat) * nZ
    on &= mu > 0
    off = ~on
    mu = np.where(on, np.minimum(mu, 1.0), 0.0)
    azimuth = np.degrees(np.arctan2(north, west))
    lon, lat = np.where(on, lon, np.nan), np.where(on, lat, np.nan)
    xs, ys = radius * lon * np.cos(lat), radius * lat
    azimuth[off] = np.nan
    return DiskGeometry(on, mu, azimuth, np.degrees(lon), np.degrees(lat), xs, ys)


