r"""
The surface-field product: a Carrington map of the radial flux density B_r, and how to read it.

Both sources of the large-scale field (a real map, `surface_field_from_map`,
and the seeded synthetic Sun, `synthetic_surface_field`) return the same
product, built here by `make_surface_field`:

* a `sunpy.map.GenericMap` of B_r in gauss, float32;
* on a Carrington cylindrical equal-area grid (``CRLN-CEA``/``CRLT-CEA``, as
  GONG's synoptic maps): ``360 / resolution`` longitudes (cell centres at
  ``resolution / 2, 3 resolution / 2, ...`` deg) by ``180 / resolution`` rows
  equally spaced in sin(latitude), so every cell has the same area
  ``4π R² / (nx ny)`` and a flux is a plain sum;
* DATE-OBS is the instant the map stands for (the run's ``obstime``), the
  observer is the Earth then, and the header says where the field came from
  (``BSOURCE``, ``HISTORY``) and what it holds (``CONTENT``);
* cells that nobody observed (the far side of a full-disk magnetogram) are NaN.

`surface_field_at` samples the map at heliographic Stonyhurst coordinates as
seen at any time, applying the differential rotation of the magnetic pattern
from the map's date to that time (`rotation_drift`): this is what a full-disk
scene calls with the longitudes and latitudes of `gongsynth.geometry.disk_geometry`.
`fill_unobserved` replaces the NaN cells by another field (the recommended
filler for the unobserved far side is a quiet-Sun
``synthetic_surface_field(..., active_regions=False)`` on the same grid).

The differential rotation of magnetic features is sunpy's
`sunpy.sun.models.differential_rotation` model ``"howard"`` (Howard, Harvey &
Forgach 1990, Sol. Phys. 130, 295: small magnetic features), relative to the
Carrington frame's rigid sidereal rate 14.1844 deg/day.
"""
import astropy.units as u
import numpy as np
import sunpy.map
from astropy.coordinates import SkyCoord
from astropy.time import Time
from sunpy.coordinates import frames, get_earth
from sunpy.map.header_helper import make_heliographic_header
from sunpy.sun import constants
from sunpy.sun.models import differential_rotation

from gongsynth.geometry import as_obstime
from gongsynth.validation import check_quantity

__all__ = ["DEFAULT_RESOLUTION", "CONTENT", "ROTATION_MODEL", "make_surface_field", "field_grid",
           "cell_area", "grid_shape", "rotation_drift", "carrington_offset", "surface_field_at",
           "fill_unobserved", "check_surface_field"]

#: Default longitude step of the product grid (rows: 180 / resolution, equal steps in sin latitude).
DEFAULT_RESOLUTION = 0.5 * u.deg
#: The CONTENT keyword of every surface-field map.
CONTENT = "radial magnetic flux density B_r (gongsynth surface field)"
#: Differential rotation model of the magnetic pattern (a `sunpy.sun.models.differential_rotation` name).
ROTATION_MODEL = "howard"


def grid_shape(resolution):
    """
    (ny, nx) of the surface-field grid of a given longitude step.

    Parameters
    ----------
    resolution : `~astropy.units.Quantity`
        Longitude step; must divide 360 deg.

    Returns
    -------
    (int, int)

    Examples
    --------
    >>> import astropy.units as u
    >>> grid_shape(0.5 * u.deg)
    (360, 720)
    """
    check_quantity(resolution, u.deg, "resolution")
    step = float(resolution.to_value(u.deg))
    nx = round(360.0 / step)
    if not 0 < step <= 10 or abs(nx * step - 360.0) > 1e-6 * 360:
        raise ValueError(f"resolution must divide 360 deg and lie in (0, 10] deg, got {resolution}")
    return nx // 2, nx


def field_grid(shape):
    """
    Carrington longitudes and latitudes of the cell centres of a surface-field grid.

    Parameters
    ----------
    shape : (int, int)
        (ny, nx) of the map.

    Returns
    -------
    longitude : `numpy.ndarray`
        (nx,) in deg, ``(j + 1/2) 360 / nx``.
    latitude : `numpy.ndarray`
        (ny,) in deg, ``arcsin((i + 1/2) 2 / ny - 1)``.

    Examples
    --------
    >>> lon, lat = field_grid((4, 8))
    >>> lon.tolist()
    [22.5, 67.5, 112.5, 157.5, 202.5, 247.5, 292.5, 337.5]
    >>> [round(float(x), 2) for x in lat]
    [-48.59, -14.48, 14.48, 48.59]
    """
    ny, nx = shape
    lon = (np.arange(nx) + 0.5) * 360.0 / nx
    lat = np.degrees(np.arcsin((np.arange(ny) + 0.5) * 2.0 / ny - 1.0))
    return lon, lat


def cell_area(shape):
    """
    Area of one cell of a surface-field grid (all cells are equal).

    Parameters
    ----------
    shape : (int, int)
        (ny, nx).

    Returns
    -------
    `~astropy.units.Quantity`
        In cm², ``4π R☉² / (nx ny)`` with sunpy's photospheric radius.

    Examples
    --------
    >>> f"{cell_area((360, 720)):.3e}"
    '2.346e+17 cm2'
    """
    ny, nx = shape
    return (4 * np.pi * constants.radius**2 / (nx * ny)).to(u.cm**2)


def make_surface_field(data, obstime, *, source, history=(), extra=None):
    """
    Wrap an array of B_r on the product grid as a surface-field map.

    Parameters
    ----------
    data : array_like or `~astropy.units.Quantity`
        (ny, nx) with nx = 2 ny, B_r (gauss if no unit); NaN where unobserved.
    obstime : `~astropy.time.Time` or str
        The instant the map stands for.
    source : str
        Where the field came from (written as BSOURCE).
    history : sequence of str
        Lines for HISTORY: what was done to it.
    extra : dict, optional
        More header keywords (at most 8 characters, FITS-safe values).

    Returns
    -------
    `sunpy.map.GenericMap`

    Examples
    --------
    >>> import numpy as np
    >>> m = make_surface_field(np.zeros((90, 180)), "2014-04-01", source="test")
    >>> m.meta["ctype1"], m.unit, m.dimensions.x
    ('CRLN-CEA', Unit("G"), <Quantity 180. pix>)
    """
    values = u.Quantity(data, u.G).to_value(u.G) if isinstance(data, u.Quantity) else np.asarray(data)
    values = np.asarray(values, dtype=np.float32)
    if values.ndim != 2 or values.shape[1] != 2 * values.shape[0]:
        raise ValueError(f"data must be (ny, 2 ny), got shape {values.shape}")
    time = as_obstime(obstime)
    header = make_heliographic_header(time, get_earth(time), values.shape, frame="carrington",
                                      projection_code="CEA", map_center_longitude=180 * u.deg)
    header["bunit"] = "G"
    header["content"] = CONTENT
    header["bsource"] = str(source)[:68]
    header["telescop"] = "gongsynth"
    header["instrume"] = "surface field"
    header["rotmodel"] = ROTATION_MODEL
    for key, value in (extra or {}).items():
        if len(key) > 8:
            raise ValueError(f"header keyword {key!r} is longer than 8 characters")
        header[key.lower()] = value
    header["history"] = "\n".join(str(line) for line in history)
    return sunpy.map.Map(values, header)


def check_surface_field(field, name="field"):
    """
    Raise unless ``field`` is a surface-field map (the product of this package).

    Parameters
    ----------
    field : `sunpy.map.GenericMap`
    name : str
        The argument named in messages.

    Returns
    -------
    (int, int)
        The grid's (ny, nx).
    """
    if not isinstance(field, sunpy.map.GenericMap):
        raise TypeError(f"{name} must be a surface-field sunpy Map, got {type(field).__name__}")
    meta = field.meta
    ny, nx = field.data.shape
    lon, _ = field_grid((ny, nx))
    if (meta.get("ctype1") != "CRLN-CEA" or meta.get("ctype2") != "CRLT-CEA" or nx != 2 * ny
            or not np.isclose(float(meta.get("crval1", np.nan)) + (1.0 - float(meta.get("crpix1", np.nan)))
                              * float(meta.get("cdelt1", np.nan)), lon[0])):
        raise ValueError(f"{name} is not a gongsynth surface field (a CRLN-CEA/CRLT-CEA map of 2 ny x ny "
                         f"cells from 0 deg); build it with surface_field_from_map or "
                         f"synthetic_surface_field")
    return ny, nx


def rotation_drift(latitude, duration, model=ROTATION_MODEL):
    """
    Longitude drift of the magnetic pattern in the Carrington frame.

    Parameters
    ----------
    latitude : `~astropy.units.Quantity`
        Heliographic latitude(s).
    duration : `~astropy.units.Quantity`
        Time elapsed (may be negative or an array broadcasting with ``latitude``).
    model : str
        A `sunpy.sun.models.differential_rotation` model.

    Returns
    -------
    `~astropy.units.Quantity`
        (ω(φ) − ω_Carrington) × duration, in deg (not wrapped).

    Examples
    --------
    >>> import astropy.units as u
    >>> rotation_drift([0, 60] * u.deg, 10 * u.day).round(2)
    <Quantity [  1.42, -24.77] deg>
    """
    lat = u.Quantity(latitude, u.deg)
    rate = differential_rotation(1 * u.day, lat, model=model).to_value(u.deg)  # < 360: no wrap
    carrington = constants.sidereal_rotation_rate.to_value(u.deg / u.day)
    return (rate - carrington) * u.Quantity(duration, u.day).to_value(u.day) * u.deg


def carrington_offset(obstime):
    """
    Carrington minus Stonyhurst longitude at ``obstime`` (observer at Earth).

    Parameters
    ----------
    obstime : `~astropy.time.Time` or str

    Returns
    -------
    `~astropy.units.Quantity`
        In deg, in [0, 360).

    Examples
    --------
    >>> round(float(carrington_offset("2009-09-05T18:54:16").to_value("deg")), 2)
    138.48
    """
    time = as_obstime(obstime)
    point = SkyCoord(0 * u.deg, 0 * u.deg, constants.radius,
                     frame=frames.HeliographicStonyhurst(obstime=time))
    carrington = point.transform_to(frames.HeliographicCarrington(observer="earth", obstime=time))
    return carrington.lon.wrap_at(360 * u.deg).to(u.deg)


def _bilinear(data, lon, lat):
    """Bilinear interpolation on the CEA grid at Carrington (lon, lat) in deg: periodic in longitude."""
    ny, nx = data.shape
    x = np.mod(lon, 360.0) * nx / 360.0 - 0.5
    y = (np.sin(np.radians(lat)) + 1.0) * ny / 2.0 - 0.5
    y = np.clip(y, 0.0, ny - 1.0)  # the half-rows at the poles take the nearest row
    x0 = np.floor(x).astype(np.int64)
    y0 = np.minimum(np.floor(y).astype(np.int64), ny - 2)
    fx, fy = x - x0, y - y0
    x0 %= nx
    x1 = (x0 + 1) % nx
    y1 = y0 + 1
    return ((1 - fy) * ((1 - fx) * data[y0, x0] + fx * data[y0, x1])
            + fy * ((1 - fx) * data[y1, x0] + fx * data[y1, x1]))


def surface_field_at(field, longitude, latitude, obstime=None):
    """
    B_r of a surface field at heliographic Stonyhurst points seen from Earth at ``obstime``.

    The pattern is carried from the map's date to ``obstime`` by differential
    rotation (`rotation_drift`); values are bilinear in (longitude, sin
    latitude), periodic in longitude; NaN in (unobserved cells) or in the
    coordinates gives NaN.

    Parameters
    ----------
    field : `sunpy.map.GenericMap`
        A surface-field map.
    longitude, latitude : `~astropy.units.Quantity` or array_like
        Stonyhurst coordinates (deg if plain numbers), any matching shape, such
        as the ``longitude``/``latitude`` of `gongsynth.geometry.disk_geometry`.
    obstime : `~astropy.time.Time` or str, optional
        Default: the map's date.

    Returns
    -------
    `~astropy.units.Quantity`
        B_r in gauss, float64, the coordinates' shape.

    Examples
    --------
    >>> import numpy as np, astropy.units as u
    >>> m = make_surface_field(np.full((90, 180), 3.0), "2014-04-01", source="uniform")
    >>> surface_field_at(m, [0, 45] * u.deg, [0, -30] * u.deg)
    <Quantity [3., 3.] G>
    """
    check_surface_field(field)
    lon = u.Quantity(longitude, u.deg).to_value(u.deg)
    lat = u.Quantity(latitude, u.deg).to_value(u.deg)
    lon, lat = np.broadcast_arrays(np.asarray(lon, dtype=float), np.asarray(lat, dtype=float))
    time = field.date if obstime is None else Time(obstime)
    carrington = lon + carrington_offset(time).to_value(u.deg)
    elapsed = (time - field.date).to(u.day)
    if elapsed != 0:
        carrington = carrington - rotation_drift(np.where(np.isfinite(lat), lat, 0.0) * u.deg,
                                                 elapsed, field.meta.get("rotmodel", ROTATION_MODEL)).value
    good = np.isfinite(carrington) & np.isfinite(lat)
    out = np.full(lon.shape, np.nan)
    out[good] = _bilinear(np.asarray(field.data, dtype=np.float64), carrington[good], lat[good])
    return out * u.G


def fill_unobserved(field, fill):
    """
    Replace the NaN (unobserved) cells of a surface field by those of another.

    Parameters
    ----------
    field : `sunpy.map.GenericMap`
        A surface field with NaN cells (e.g. the far side of a full-disk map).
    fill : `sunpy.map.GenericMap` or `~astropy.units.Quantity`
        A surface field on the same grid (e.g. ``synthetic_surface_field(obstime,
        seed=..., active_regions=False)``: quiet network and polar fields), or a
        constant flux density.

    Returns
    -------
    `sunpy.map.GenericMap`
        A copy; its HISTORY says how many cells were filled and from what.

    Examples
    --------
    >>> import numpy as np, astropy.units as u
    >>> m = make_surface_field(np.full((90, 180), np.nan), "2014-04-01", source="empty")
    >>> float(fill_unobserved(m, 0 * u.G).data.max())
    0.0
    """
    shape = check_surface_field(field)
    data = np.array(field.data, dtype=np.float32)
    holes = ~np.isfinite(data)
    if isinstance(fill, sunpy.map.GenericMap):
        if check_surface_field(fill, "fill") != shape:
            raise ValueError(f"fill has shape {fill.data.shape}, the field {shape}: use the same resolution")
        data[holes] = fill.data[holes]
        what = f"{fill.meta.get('bsource', 'a surface field')} of {fill.date.isot}"
    else:
        check_quantity(fill, u.G, "fill")
        data[holes] = fill.to_value(u.G)
        what = f"a constant {fill}"
    meta = field.meta.copy()
    meta["history"] = (str(meta.get("history", "")) + f"\n{int(holes.sum())} unobserved cells filled "
                       f"with {what}").strip()
    return sunpy.map.Map(data, meta)
