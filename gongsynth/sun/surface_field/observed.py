r"""
A real map as the large-scale truth: any magnetogram sunpy reads, remapped to the surface-field grid.

`surface_field_from_map` takes

* a full-disk line-of-sight magnetogram (GONG, MDI, HMI: a helioprojective
  map), turned into radial flux density by the radial-field assumption
  :math:`B_r = B_\mathrm{LOS}/\mu` (Wang & Sheeley 1992, ApJ 392, 310; the
  assumption of GONG's and HMI's synoptic maps).  Near the limb 1/μ amplifies
  the noise without bound, so pixels with μ < ``min_mu`` (default 0.1, an
  amplification of at most 10) are left out, and so is everything beyond:
  those cells stay NaN;
* or a heliographic map (a GONG/ADAPT/HMI synoptic or synchronic map, or a
  JSOC heliographic cut-out): taken as B_r unless ``quantity="los"`` says it
  holds B_LOS (then divided by μ as above, μ from the map's observer).

Every input pixel is traced to the solar sphere with sunpy's coordinate frames
(helioprojective → heliographic Stonyhurst, the sphere intersection done by
sunpy), moved by the differential rotation of the magnetic pattern
(`gongsynth.sun.surface_field.maps.rotation_drift`) from the time it was
observed to ``obstime``, and binned into the grid cell it falls in with its
area on the Sun as weight, so each cell holds the flux-weighted mean
B_r = Σ B_r,i A_i / Σ A_i and the flux of the observed hemisphere is kept.
Cells that no pixel reached but that were seen (small cells near the limb, or
a grid finer than the map) are filled by bilinear interpolation of the map at
the cell centre traced back to the map's time.  Maps much finer than the grid
(HMI) are first averaged in blocks of pixels (`sunpy.map.GenericMap.superpixel`).

Observation time of each pixel: the map's date for a full-disk or synchronic
map; for GONG's synoptic maps, whose second WCS (``CTYPE1A = 'CRN-CEA'``)
gives the Carrington rotation number of each column, the central-meridian
passage of the column (never after the map's date: the newest columns were
observed east of the central meridian at that date).

What the full-disk scene should do with the NaN (unobserved, far-side) cells:
fill them with a quiet Sun, ``fill_unobserved(field,
synthetic_surface_field(obstime, seed=..., active_regions=False,
resolution=...))``: they are what rotated into view since the map was taken.
"""
import warnings

import astropy.units as u
import numpy as np
import sunpy.map
from astropy.coordinates import SkyCoord
from astropy.time import Time
from scipy.ndimage import map_coordinates
from sunpy.coordinates import frames, sun

from gongsynth.sun.surface_field.maps import (
    DEFAULT_RESOLUTION,
    ROTATION_MODEL,
    carrington_offset,
    field_grid,
    grid_shape,
    make_surface_field,
    rotation_drift,
)
from gongsynth.validation import check_quantity

__all__ = ["QUANTITIES", "surface_field_from_map"]

#: Values of ``quantity`` in `surface_field_from_map`.
QUANTITIES = ("auto", "los", "radial")


def _values_in_gauss(smap):
    data = np.asarray(smap.data, dtype=np.float64)
    if smap.mask is not None:
        data = np.where(smap.mask, np.nan, data)
    unit = smap.unit
    if unit is None or unit == u.one:
        return data  # magnetograms without BUNIT (ADAPT, old GONG) are in gauss
    if not unit.is_equivalent(u.G):
        raise ValueError(f"the map's unit is {unit}, not a magnetic flux density")
    return data * unit.to(u.G)


def _block_factor(smap, resolution, helioprojective):
    """Pixels per block so that a block stays below half the smallest cell side."""
    ny, _ = grid_shape(resolution)
    cell = min(float(resolution.to_value(u.rad)), 2.0 / ny)  # radians on the Sun at the equator
    if helioprojective:
        distance = smap.observer_coordinate.radius
        cell_angle = (cell * smap.rsun_meters / distance * u.rad).to(u.arcsec)
        pixel = min(abs(smap.scale.axis1 * u.pix), abs(smap.scale.axis2 * u.pix)).to(u.arcsec)
    else:
        cell_angle = (cell * u.rad).to(u.deg)
        pixel = min(abs(smap.scale.axis1 * u.pix), abs(smap.scale.axis2 * u.pix)).to(u.deg)
    return max(1, int(np.floor((cell_angle / (2 * pixel)).to_value(u.one))))


def _mu(hgs, observer):
    """The cosine of the angle between the local vertical and the direction to the observer."""
    r = hgs.cartesian.xyz.to_value(u.km)
    o = observer.transform_to(frames.HeliographicStonyhurst(obstime=hgs.obstime)).cartesian.xyz.to_value(u.km)
    o = o.reshape((3,) + (1,) * (r.ndim - 1))
    to_obs = o - r
    norm_r = np.sqrt((r * r).sum(axis=0))
    return (r * to_obs).sum(axis=0) / (norm_r * np.sqrt((to_obs * to_obs).sum(axis=0))), to_obs


def _column_lags(smap):
    """
    Days from each column's observation to the map's date, for a GONG synoptic map (else None):
    central-meridian passage of the column's Carrington rotation number (second WCS, CRN), the
    newest columns, seen east of the central meridian, at the map's date.
    """
    meta = smap.meta
    if not str(meta.get("ctype1a", "")).strip().upper().startswith("CRN"):
        return None
    columns = np.arange(smap.data.shape[1])
    crn = float(meta["crval1a"]) + (columns + 1 - float(meta["crpix1a"])) * float(meta["cdelt1a"])
    lag = (smap.date - sun.carrington_rotation_time(crn)).to_value(u.day)
    return np.maximum(lag, 0.0)


def _trace_pixels(smap, helioprojective):
    """Heliographic Stonyhurst coordinates of every pixel centre (NaN off the disk)."""
    ny, nx = smap.data.shape
    yy, xx = np.mgrid[0:ny, 0:nx]
    world = smap.wcs.pixel_to_world(xx, yy)
    return world.transform_to(frames.HeliographicStonyhurst(obstime=smap.date)), xx


def _pixel_areas(hgs, to_obs, mu, smap, helioprojective):
    """Relative area on the Sun of each pixel (only ratios within a cell matter)."""
    if helioprojective:
        distance2 = (to_obs * to_obs).sum(axis=0)
        return distance2 / np.maximum(mu, 1e-6)
    lon = np.radians(hgs.lon.to_value(u.deg))
    s = np.sin(hgs.lat.to_value(u.rad))
    dlon_y, dlon_x = (np.angle(np.exp(1j * d)) for d in np.gradient(lon))
    ds_y, ds_x = np.gradient(s)
    return np.abs(dlon_x * ds_y - dlon_y * ds_x)


def _forward_bin(lon, lat, value, weight, shape):
    ny, nx = shape
    j = np.floor(np.mod(lon, 360.0) * nx / 360.0).astype(np.int64) % nx
    i = np.clip(np.floor((np.sin(np.radians(lat)) + 1.0) * ny / 2.0).astype(np.int64), 0, ny - 1)
    index = i * nx + j
    total = np.bincount(index, weights=weight * value, minlength=nx * ny)
    norm = np.bincount(index, weights=weight, minlength=nx * ny)
    out = np.full(nx * ny, np.nan)
    hit = norm > 0
    out[hit] = total[hit] / norm[hit]
    return out.reshape(shape), int(hit.sum())


def _interpolate_cells(smap, data, lon_c, lat_c, target, offset, los, min_mu, model, wraps):
    """Bilinear values of the map at cell centres (Carrington lon/lat at ``target``) traced back."""
    elapsed = (target - smap.date).to_value(u.day)
    lags = _column_lags(smap)
    if lags is not None:
        # The column each cell came from (one fixed-point step is enough: the drift is small).
        x0, _ = smap.wcs.world_to_pixel(SkyCoord(lon_c * u.deg, lat_c * u.deg,
                                                 frame=smap.coordinate_frame))
        columns = np.clip(np.round(np.nan_to_num(x0)), 0, smap.data.shape[1] - 1).astype(np.int64)
        elapsed = elapsed + lags[columns]
    elapsed = elapsed * u.day
    lon_src = lon_c - rotation_drift(lat_c * u.deg, elapsed, model).to_value(u.deg)
    hgs = SkyCoord((lon_src - offset) * u.deg, lat_c * u.deg, smap.rsun_meters,
                   frame=frames.HeliographicStonyhurst(obstime=smap.date))
    needs_mu = los or isinstance(smap.coordinate_frame, frames.Helioprojective)
    mu = _mu(hgs, smap.observer_coordinate)[0] if needs_mu else np.ones(lat_c.shape)
    x, y = smap.wcs.world_to_pixel(hgs)
    if wraps:  # a full-longitude heliographic map: one wrapped column each side
        data = np.concatenate([data[:, -1:], data, data[:, :1]], axis=1)
        x = np.mod(x + 0.5, smap.data.shape[1]) + 0.5
        y = np.clip(y, 0, smap.data.shape[0] - 1)
    values = map_coordinates(data, [y, x], order=1, mode="constant", cval=np.nan, prefilter=False)
    seen = mu >= min_mu if needs_mu else np.ones(mu.shape, bool)
    values = np.where(seen, values / (np.maximum(mu, min_mu) if los else 1.0), np.nan)
    return values


def surface_field_from_map(smap, obstime=None, *, resolution=DEFAULT_RESOLUTION, quantity="auto",
                           min_mu=0.1, rotation_model=ROTATION_MODEL):
    """
    The radial field of a real magnetogram on the surface-field grid, as it stands at ``obstime``.

    Parameters
    ----------
    smap : `sunpy.map.GenericMap`
        A full-disk line-of-sight magnetogram (helioprojective: GONG, MDI,
        HMI; read with `gongsynth.load_observation` or sunpy) or a
        heliographic map (GONG/ADAPT synoptic, synchronic, a JSOC cut-out),
        in gauss (or no unit: gauss).
    obstime : `~astropy.time.Time` or str, optional
        The time the field should stand for; default the map's date.  The
        pattern is moved by differential rotation from the time each pixel
        was observed.
    resolution : `~astropy.units.Quantity`
        Longitude step of the grid (default 0.5 deg).
    quantity : {"auto", "los", "radial"}
        What the map holds: ``"auto"`` means B_LOS for a helioprojective map
        and B_r for a heliographic one.
    min_mu : float
        Line-of-sight data seen at μ below this are left out (NaN): the cap on
        the 1/μ amplification of the radial-field assumption.
    rotation_model : str
        A `sunpy.sun.models.differential_rotation` model.

    Returns
    -------
    `sunpy.map.GenericMap`
        The surface field (see `gongsynth.sun.surface_field.maps`); NaN where
        nothing was observed.  Its header records the source map and date,
        the counts of binned and interpolated cells.

    Examples
    --------
    >>> import numpy as np, sunpy.map, astropy.units as u
    >>> from sunpy.coordinates import get_earth
    >>> from sunpy.map.header_helper import make_fitswcs_header
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import Helioprojective
    >>> t = "2010-10-15T00:00"
    >>> centre = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=Helioprojective(observer=get_earth(t), obstime=t))
    >>> disk = sunpy.map.Map(np.full((64, 64), 5.0), make_fitswcs_header((64, 64), centre,
    ...                      scale=[32, 32] * u.arcsec / u.pix, unit=u.G))
    >>> field = surface_field_from_map(disk, resolution=2 * u.deg)
    >>> round(float(np.nanmin(field.data)), 3), float(np.isfinite(field.data).mean()) < 0.5
    (5.0, True)
    """
    if not isinstance(smap, sunpy.map.GenericMap) or smap.data.ndim != 2:
        raise TypeError(f"smap must be a 2-D sunpy Map, got {type(smap).__name__}")
    if quantity not in QUANTITIES:
        raise ValueError(f"quantity must be one of {QUANTITIES}, got {quantity!r}")
    if not 0 < float(min_mu) < 1:
        raise ValueError(f"min_mu must lie in (0, 1), got {min_mu!r}")
    check_quantity(resolution, u.deg, "resolution")
    shape = grid_shape(resolution)
    frame = smap.coordinate_frame
    helioprojective = isinstance(frame, frames.Helioprojective)
    if not helioprojective and not isinstance(frame, (frames.HeliographicCarrington,
                                                      frames.HeliographicStonyhurst)):
        raise ValueError(f"smap must be helioprojective or heliographic, got a {type(frame).__name__} map")
    los = quantity == "los" or (quantity == "auto" and helioprojective)
    target = smap.date if obstime is None else Time(obstime)
    source_name = f"{smap.meta.get('telescop', '')} {smap.name}".strip()
    block = _block_factor(smap, resolution, helioprojective)
    work = smap
    if block > 1:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN blocks off the disk
            ny0, nx0 = smap.data.shape
            cropped = smap.submap([0, 0] * u.pix, top_right=[nx0 // block * block - 1,
                                                             ny0 // block * block - 1] * u.pix)
            work = cropped.superpixel([block, block] * u.pix, func=np.nanmean)
    data = _values_in_gauss(work)
    hgs, columns = _trace_pixels(work, helioprojective)
    needs_mu = los or helioprojective
    if needs_mu and work.observer_coordinate is None:
        raise ValueError(f"{source_name} has no observer position in its header: mu cannot be computed")
    mu, to_obs = _mu(hgs, work.observer_coordinate) if needs_mu else (np.ones(data.shape), None)
    offset = carrington_offset(work.date).to_value(u.deg)
    lon = hgs.lon.to_value(u.deg) + offset
    lat = hgs.lat.to_value(u.deg)
    lags = _column_lags(work)
    elapsed = (target - work.date).to_value(u.day) + (0.0 if lags is None else lags[columns])
    on = np.isfinite(lon) & np.isfinite(lat) & np.isfinite(data)
    if needs_mu:
        on &= mu >= min_mu
    value = data / np.where(on, mu, 1.0) if los else data
    weight = _pixel_areas(hgs, to_obs, mu, work, helioprojective)
    on &= np.isfinite(weight) & (weight > 0)
    if not on.any():
        raise ValueError(f"{source_name}: no pixel of the map lies on the visible Sun with mu >= {min_mu}")
    elapsed = np.broadcast_to(elapsed, lon.shape)[on]
    lon_t = lon[on] + rotation_drift(lat[on] * u.deg, elapsed * u.day, rotation_model).to_value(u.deg)
    binned, n_binned = _forward_bin(lon_t, lat[on], value[on], weight[on], shape)
    # Cells no pixel reached: interpolate those that were seen.
    lon_c, lat_c = field_grid(shape)
    empty = ~np.isfinite(binned)
    rows, cols = np.nonzero(empty)
    wraps = (not helioprojective and abs(abs(float(work.scale.axis1.to_value(u.deg / u.pix)))
                                         * work.data.shape[1] - 360) < 1e-3)
    filled = _interpolate_cells(work, data, lon_c[cols], lat_c[rows], target, offset, los,
                                min_mu, rotation_model, wraps)
    binned[rows, cols] = filled
    n_interp = int(np.isfinite(filled).sum())
    lag = (target - smap.date).to(u.day)
    history = [
        f"from {source_name} ({'B_LOS' if los else 'B_r'}), observed {smap.date.isot}",
        (f"B_r = B_LOS / mu for mu >= {min_mu} (radial-field assumption); lower mu and the far side NaN"
         if los else "values taken as B_r"),
        f"{n_binned} cells area-weighted means of the map's pixels (blocks of {block}x{block}), "
        f"{n_interp} cells interpolated (bilinear)",
        (f"moved by differential rotation ({rotation_model}) to {target.isot}: by {lag:.3f} from the "
         f"map's date" + ("" if lags is None else f", plus 0 to {float(lags.max()):.1f} d from each "
                          f"column's central-meridian passage (synoptic map)")),
    ]
    extra = {"srcdate": smap.date.isot, "minmu": float(min_mu) if los else 0.0, "los": bool(los),
             "nbinned": n_binned, "ninterp": n_interp}
    return make_surface_field(binned, target, source=source_name, history=history, extra=extra)
