"""
The large scales of a full-disk scene on a heliographic grid: the radial field and the line-of-sight velocity.

`large_scale_grid` puts on one regular Stonyhurst (longitude, latitude) grid,
for the run's date and observer:

- the radial flux density B_r of a heliographic `sunpy.map.Map` (its quiet
  part carried by the supergranular network when one is given,
  `gongsynth.sun.surface_field.network`): a
  `gongsynth.sun.surface_field` map through its own
  `~gongsynth.sun.surface_field.surface_field_at` (differential rotation
  from the map's date to the run's), any other (Carrington or Stonyhurst,
  any projection its WCS describes, e.g. the GONG synoptic maps' CEA or
  plate carrée) through its WCS (bilinear, `sample_surface_field`); pixels
  the map does not know (NaN, or outside it) are 0: the quiet Sun.  No map:
  0 everywhere;
- the large-scale Doppler velocity, `gongsynth.sun.rotation.disk_velocity`:
  differential rotation, the observer's motion, the convective blueshift;
  with a network, also the supergranular flow of its cells
  (`gongsynth.sun.surface_field.supergranulation`) seen along each line of
  sight: outflows toward the walls where the network lies.

The scene interpolates both bilinearly at each of its samples; they vary
over degrees, the grid spacing is a quarter of one by default.
"""
from dataclasses import dataclass

import astropy.units as u
import numpy as np
from astropy.coordinates import SkyCoord

from gongsynth.geometry import as_obstime
from gongsynth.sun.rotation import CONVECTIVE_BLUESHIFT_FE6302, disk_velocity
from gongsynth.sun.surface_field.maps import check_surface_field, surface_field_at
from gongsynth.sun.surface_field.supergranulation import supergranular_flow
from gongsynth.validation import check_quantity

__all__ = ["LargeScale", "sample_surface_field", "large_scale_grid"]


@dataclass(frozen=True)
class LargeScale:
    """
    The large-scale inputs of a full-disk scene on a regular Stonyhurst grid.

    Attributes
    ----------
    longitude, latitude : `numpy.ndarray`
        Grid axes, deg (increasing, uniform).
    field : `numpy.ndarray`
        (nlat, nlon) radial flux density, G (0 where unknown).
    velocity : `numpy.ndarray`
        (nlat, nlon) line-of-sight velocity, m/s (positive away from the observer).
    meta : dict
        What went in.
    """

    longitude: np.ndarray
    latitude: np.ndarray
    field: np.ndarray
    velocity: np.ndarray
    meta: dict


def sample_surface_field(smap, longitude, latitude, obstime=None):
    """
    B_r of a heliographic map at Stonyhurst coordinates (bilinear in the map's pixels).

    Parameters
    ----------
    smap : `sunpy.map.GenericMap`
        A heliographic map of the radial flux density (G), in a Carrington or
        Stonyhurst frame.
    longitude, latitude : `~astropy.units.Quantity`
        Stonyhurst coordinates (any shape).
    obstime : `~astropy.time.Time` or str, optional
        When the points are seen (sets the Carrington longitude of the
        Stonyhurst meridian); default `gongsynth.geometry.DEFAULT_OBSTIME`.

    Returns
    -------
    `~astropy.units.Quantity`
        In G; NaN where the map has no value.

    Examples
    --------
    >>> import astropy.units as u, numpy as np, sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import HeliographicStonyhurst
    >>> ref = SkyCoord(0 * u.deg, 0 * u.deg, frame=HeliographicStonyhurst(obstime="2019-06-07"))
    >>> header = sunpy.map.make_fitswcs_header((180, 360), ref, scale=[1, 1] * u.deg / u.pix,
    ...                                        projection_code="CAR")
    >>> lat = np.radians(np.arange(180) - 89.5)[:, None] * np.ones(360)
    >>> smap = sunpy.map.Map(10 * np.sin(lat), header)
    >>> b = sample_surface_field(smap, [0, 0] * u.deg, [30, -60] * u.deg, "2019-06-07")
    >>> np.round(b.to_value(u.G), 2)
    array([ 5.  , -8.66])
    """
    from scipy.ndimage import map_coordinates
    from sunpy.coordinates import HeliographicStonyhurst
    check_quantity(longitude, u.deg, "longitude")
    check_quantity(latitude, u.deg, "latitude")
    time = as_obstime(obstime)
    frame = smap.coordinate_frame
    if frame.name not in ("heliographic_stonyhurst", "heliographic_carrington"):
        raise ValueError(f"the surface field must be a heliographic map (Carrington or Stonyhurst), "
                         f"got a {frame.name} map")
    # The map's longitude of the Stonyhurst meridian at the run's date (one point; the rest shifts).
    offset = 0.0
    if frame.name == "heliographic_carrington":
        origin = SkyCoord(0 * u.deg, 0 * u.deg, frame=HeliographicStonyhurst(obstime=time))
        carrington = frame.replicate_without_data(obstime=time, observer="earth")
        offset = origin.transform_to(carrington).lon.to_value(u.deg)
    lon = np.asarray(u.Quantity(longitude, u.deg).value, dtype=float) + offset
    lat = np.asarray(u.Quantity(latitude, u.deg).value, dtype=float)
    # World axes of a heliographic WCS are (lon, lat) in the map's CUNIT (deg).
    units = [u.Unit(c) for c in smap.wcs.wcs.cunit]
    x, y = smap.wcs.world_to_pixel_values((lon * u.deg).to_value(units[0]), (lat * u.deg).to_value(units[1]))
    ny, nx = smap.data.shape
    # A full-Sun map wraps in longitude: take the pixel within the map's 360°.
    period = abs(360.0 / (smap.scale.axis1 * u.pix).to_value(u.deg))
    if abs(period - nx) < 0.51:
        x = np.mod(x + 0.5, period) - 0.5
    data = np.asarray(smap.data, dtype=float)
    known = np.isfinite(data)
    values = map_coordinates(np.where(known, data, 0.0), [np.ravel(y), np.ravel(x)], order=1,
                             mode="nearest")
    weight = map_coordinates(known.astype(float), [np.ravel(y), np.ravel(x)], order=1, mode="nearest")
    inside = (np.ravel(x) > -0.5) & (np.ravel(x) < nx - 0.5) & (np.ravel(y) > -0.5) & (np.ravel(y) < ny - 0.5)
    values = np.where(inside & (weight > 0.5) & np.isfinite(np.ravel(x) + np.ravel(y)),
                      values / np.where(weight > 0, weight, 1.0), np.nan)
    unit = smap.unit if smap.unit is not None and smap.unit.is_equivalent(u.G) else u.G
    return u.Quantity(values.reshape(np.shape(lon)), unit).to(u.G)


def large_scale_grid(obstime=None, surface_field=None, *, step=0.25 * u.deg, site=None,
                     rotation=True, observer=True, blueshift=CONVECTIVE_BLUESHIFT_FE6302, network=None,
                     supergranulation=True):
    """
    The radial field and the large-scale velocity on a regular Stonyhurst grid.

    Parameters
    ----------
    obstime : `~astropy.time.Time` or str, optional
        The observation (observer at Earth, or at ``site``); default
        `gongsynth.geometry.DEFAULT_OBSTIME`.
    surface_field : `sunpy.map.GenericMap`, optional
        Heliographic B_r map (see `sample_surface_field`); None: no large-scale field.
    step : `~astropy.units.Quantity`
        Grid spacing (default 0.25°).
    site : `~astropy.coordinates.EarthLocation`, optional
        Ground site whose motion the observer shares; default the Earth's centre.
    rotation, observer : bool
        Include the solar rotation and the observer's motion.
    blueshift : tuple or None
        Convective-blueshift table (`gongsynth.sun.rotation.convective_blueshift`), None for none.
    network : `~gongsynth.sun.surface_field.network.SupergranularNetwork`, optional
        Lays the magnetic network on the grid: the field's quiet part carried
        by flux concentrations on supergranular cell walls; None: the field as it is.
    supergranulation : bool
        With a network: add its cells' supergranular flow to the velocity
        (`~gongsynth.sun.surface_field.supergranulation.supergranular_flow`).
        No effect without a network.

    Returns
    -------
    `LargeScale`

    Examples
    --------
    >>> grid = large_scale_grid(step=2 * u.deg)
    >>> grid.field.shape, float(abs(grid.field).max())
    ((91, 181), 0.0)
    """
    from sunpy.coordinates import get_earth, sun
    from sunpy.sun.constants import radius
    time = as_obstime(obstime)
    dstep = check_quantity(step, u.deg, "step").to_value(u.deg)
    if not 0 < dstep <= 5:
        raise ValueError(f"step must be in (0, 5] deg, got {step}")
    lon = np.linspace(-180, 180, int(round(360 / dstep)) + 1)
    lat = np.linspace(-90, 90, int(round(180 / dstep)) + 1)
    glon, glat = np.meshgrid(lon, lat)
    if surface_field is None:
        field = np.zeros(glon.shape)
    else:
        try:   # a gongsynth surface field: carried to the date by differential rotation
            check_surface_field(surface_field)
            field = surface_field_at(surface_field, glon * u.deg, glat * u.deg, time).to_value(u.G)
        except (ValueError, TypeError):
            field = sample_surface_field(surface_field, glon * u.deg, glat * u.deg, time).to_value(u.G)
        field = np.where(np.isfinite(field), field, 0.0)
    # μ of each grid point seen from the Earth at its distance (the blueshift's argument; 0 beyond the limb).
    b0 = sun.B0(time).to_value(u.rad)
    distance = (get_earth(time).radius / radius).to_value(u.one)
    rlat, rlon = np.radians(glat), np.radians(glon)
    point = np.stack([np.cos(rlat) * np.cos(rlon), np.cos(rlat) * np.sin(rlon), np.sin(rlat)])
    sight = np.array([distance * np.cos(b0), 0.0, distance * np.sin(b0)])[:, None, None] - point
    facing = (point * sight).sum(axis=0) / np.sqrt((sight ** 2).sum(axis=0))
    mu = np.clip(facing, 0.0, 1.0)
    visible = facing > -0.02     # the visible side and a degree beyond: the scene samples nothing else
    if network is not None:
        field = network.on_grid(lon, lat, field, where=visible)
    velocity = disk_velocity(glon * u.deg, glat * u.deg, mu, time, site=site, rotation=rotation,
                             observer=observer, blueshift=blueshift).to_value(u.m / u.s)
    flow = network is not None and supergranulation
    if flow:
        at = point[:, visible].T
        vector = supergranular_flow(network.cells()[0], at).to_value(u.m / u.s)
        toward = sight[:, visible].T
        # Positive away from the observer: minus the flow's component toward it.
        velocity[visible] -= (vector * toward).sum(axis=1) / np.linalg.norm(toward, axis=1)
    meta = {"obstime": time.isot, "step_deg": dstep, "surface_field": None if surface_field is None
            else str(getattr(surface_field, "name", "map")), "site": None if site is None else str(site),
            "rotation": bool(rotation), "observer": bool(observer), "blueshift": blueshift is not None,
            "network": None if network is None else repr(network), "supergranulation": bool(flow)}
    return LargeScale(longitude=lon, latitude=lat, field=field, velocity=velocity, meta=meta)
