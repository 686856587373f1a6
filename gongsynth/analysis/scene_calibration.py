r"""
The scene dependence of the weak-flux factor: distance from strong fields, measured and applied.

The quiet-Sun factor of the papers' curves is a property of a scene, not of
the Sun alone: near a sunspot the blur spreads the spot's light and flux over
its surroundings, and the factor there is larger than far away (the ablation
in ``gongsynth/data/weak_flux_factors.ecsv``; ``scripts/scene_dependence.py``
measures it).  This module describes each pixel's context by a number any
magnetogram gives — its distance on the Sun to the nearest **strong-field**
pixel of the map itself, :math:`|B| \ge` ``threshold`` × cos θ (by default
the papers' quiet-Sun limit, 400 G × cos θ: exactly the pixels
`gongsynth.calibrate` gives the sunspot curve) — and carries the factor's
dependence on it in a table:

- `strong_field_distance`: each pixel's great-circle distance (Mm, on the
  solar surface) to the nearest strong pixel: heliographic coordinates of
  every pixel (disk images: the visible hemisphere; synoptic maps: the map's
  own longitudes and latitudes), a k-d tree of the strong pixels' unit
  vectors.  A map with no strong pixel gives infinity everywhere.
- `scene_table` tabulates, per viewing angle and distance group, the quiet
  factor and its ratio to the same fit over all the scene's quiet pixels
  (both the mean of per-seed fits, with the seeds' standard error);
  `read_scene_table` reads the one shipped with gongsynth
  (``gongsynth/data/scene_factors.ecsv``).
- `scene_ratio` evaluates the ratio at any (θ, distance): linear in distance
  between the groups' median distances and in θ between the table's angles,
  the nearest value beyond both.

`gongsynth.calibrate` with ``scene="distance"`` multiplies each quiet pixel's
calibrated value by that ratio.  The ratio is relative, so the scene average of
the factor stays the angle-only table's; only its distribution over the map
changes.
"""
import importlib.resources

import astropy.units as u
import numpy as np
import scipy.spatial
from astropy.table import QTable
from sunpy.coordinates import frames
from sunpy.map import all_coordinates_from_map

from gongsynth.analysis.calibration import gauss_values
from gongsynth.analysis.disk import tiled_pointing
from gongsynth.analysis.weak_flux import QUIET_LIMIT

__all__ = ["SCENE_TABLE", "DISTANCE_EDGES", "strong_field_mask", "strong_field_distance",
           "local_flux_density", "scene_table", "read_scene_table", "scene_ratio"]

#: File name of the scene table shipped with gongsynth (in ``gongsynth/data``).
SCENE_TABLE = "scene_factors.ecsv"

#: Edges of the distance groups (Mm on the Sun): the sunspot's penumbra has a radius of 16 Mm in the
#: built-in Sun, its box 98 Mm, so no pixel there lies much more than 50 Mm from the spot.  Quiet pixels
#: within 5 Mm are the spot's blurred edge, few of them weak: their fit's slope at zero is
#: ill-conditioned (0.02 ± 0.01 at disk centre, 3.0 ± 0.6 at 45°), so they form no group, and
#: `scene_ratio` gives them the nearest group's ratio.
DISTANCE_EDGES = (5, 10, 20, 35, np.inf) * u.Mm

_COLUMNS = {"latitude", "distance_min", "distance_max", "distance", "ratio", "uncertainty"}


def strong_field_mask(values, theta, threshold=QUIET_LIMIT):
    r"""
    The strong-field pixels of a map: field strength at least ``threshold`` × cos θ.

    :math:`|B| \ge` ``threshold`` × cos θ, with θ each pixel's viewing angle.

    Parameters
    ----------
    values : array_like or `~astropy.units.Quantity`
        Measured field (G).
    theta : array_like
        Viewing angle of each pixel (deg; NaN off the disk).
    threshold : `~astropy.units.Quantity`
        At disk centre (G).

    Returns
    -------
    `numpy.ndarray` of bool
    """
    threshold = u.Quantity(threshold)
    if not threshold.unit.is_equivalent(u.G) or threshold.size != 1 or not threshold.value > 0:
        raise ValueError(f"threshold must be one positive field strength in G, got {threshold!r}")
    b = gauss_values(values, "values")
    theta = np.asarray(theta, float)
    if theta.shape != b.shape:
        raise ValueError(f"theta must have the map's shape {b.shape}, got {theta.shape}")
    with np.errstate(invalid="ignore"):
        return np.abs(b) >= threshold.to_value(u.G) * np.cos(np.deg2rad(theta))


def _unit_vectors(smap):
    """Heliographic unit vectors (ny, nx, 3) of every pixel; NaN where the pixel is off the Sun."""
    coords = all_coordinates_from_map(smap)
    if not isinstance(coords.frame, (frames.HeliographicCarrington, frames.HeliographicStonyhurst)):
        coords = coords.transform_to(frames.HeliographicStonyhurst(obstime=smap.date))
    lon, lat = coords.lon.to_value(u.rad), coords.lat.to_value(u.rad)
    return np.stack([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)], axis=-1)


def _tile_positions(smap, pointing):
    """Positions (ny, nx, 2) in Mm on a simulated tiled map's box (seen on the central meridian:
    the north-south axis foreshortened by μ).
    """
    ny, nx = smap.data.shape
    scale = [u.Quantity(s).to_value(u.arcsec / u.pix) for s in (smap.scale.axis1, smap.scale.axis2)]
    mm_per_arcsec = pointing.km_per_arcsec.to_value(u.Mm / u.arcsec)
    y, x = np.mgrid[:ny, :nx]
    return np.stack([x * scale[0] * mm_per_arcsec, y * scale[1] * mm_per_arcsec / pointing.mu], axis=-1)


def strong_field_distance(smap, strong, *, usable=None):
    """
    Each pixel's distance on the Sun to the nearest strong-field pixel.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        A disk image or a synoptic map (only its coordinates are used).
    strong : array of bool
        The strong pixels (`strong_field_mask`), the map's shape.
    usable : array of bool, optional
        Pixels that may count as strong (e.g. the native-resolution part of a
        tiled simulation); default all.

    Returns
    -------
    `~astropy.units.Quantity`
        Great-circle distance (Mm, on a sphere of the map's ``rsun_meters``);
        NaN off the Sun, infinity everywhere if no pixel is strong.  On a
        simulated tiled map (``gongsynth.analysis.disk.tiled_pointing``), the
        distance in the run's box, its north-south axis foreshortened by μ.
    """
    strong = np.asarray(strong)
    if strong.dtype != bool or strong.shape != smap.data.shape:
        raise ValueError(f"strong must be a boolean array of the map's shape {smap.data.shape}, got "
                         f"{strong.dtype} {strong.shape}")
    pointing = tiled_pointing(smap)
    positions = _unit_vectors(smap) if pointing is None else _tile_positions(smap, pointing)
    on_sun = np.all(np.isfinite(positions), axis=-1)
    sources = strong & on_sun & (True if usable is None else np.asarray(usable, bool))
    out = np.full(strong.shape, np.nan)
    if not sources.any():
        out[on_sun] = np.inf
        return out * u.Mm
    nearest, _ = scipy.spatial.cKDTree(positions[sources]).query(positions[on_sun])
    if pointing is None:   # a chord between unit vectors: the great-circle distance
        radius = u.Quantity(smap.rsun_meters, u.Mm).value
        nearest = 2 * radius * np.arcsin(np.minimum(nearest / 2, 1))
    out[on_sun] = nearest
    return out * u.Mm


def local_flux_density(values, side):
    """
    The mean unsigned field over a square of ``side`` pixels around each pixel (NaN-aware).

    Parameters
    ----------
    values : array_like or `~astropy.units.Quantity`
        Measured field (G).
    side : int
        Odd number of pixels ≥ 1.

    Returns
    -------
    `~astropy.units.Quantity`
        In G; NaN where the pixel itself is NaN.
    """
    import scipy.ndimage

    if int(side) != side or side < 1 or side % 2 == 0:
        raise ValueError(f"side must be an odd positive number of pixels, got {side!r}")
    b = np.abs(gauss_values(values, "values"))
    finite = np.isfinite(b)
    total = scipy.ndimage.uniform_filter(np.where(finite, b, 0.0), int(side), mode="nearest")
    count = scipy.ndimage.uniform_filter(finite.astype(float), int(side), mode="nearest")
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(finite, total / count, np.nan) * u.G


def scene_table(rows, *, metadata=None):
    """
    Tabulate measured scene ratios: one row per (latitude, distance group).

    Parameters
    ----------
    rows : sequence of dict
        Each with ``latitude`` (deg), ``distance_min``, ``distance_max`` and
        ``distance`` (the group's median distance; Mm), ``n_pixels``,
        ``n_seeds``, ``factor`` and ``factor_uncertainty`` (the group's quiet
        factor: mean and standard error over seeds), ``ratio`` and
        ``uncertainty`` (its ratio to the fit over all quiet pixels of the
        same run: mean and standard error over seeds).
    metadata : dict, optional
        Provenance (grid, seeds, instrument, ``threshold``, method).

    Returns
    -------
    `~astropy.table.QTable`
        Sorted by latitude and distance.
    """
    table = QTable(rows=list(rows))
    missing = _COLUMNS - set(table.colnames)
    if missing:
        raise ValueError(f"rows lack {sorted(missing)}")
    for name, unit in (("latitude", u.deg), ("distance_min", u.Mm), ("distance_max", u.Mm),
                       ("distance", u.Mm)):
        table[name] = u.Quantity(table[name], unit)
    table.sort(["latitude", "distance_min"])
    table.meta.update(metadata or {})
    return table


def read_scene_table(path=None):
    """
    Read a scene table; by default the one shipped with gongsynth.

    Parameters
    ----------
    path : str or path-like, optional

    Returns
    -------
    `~astropy.table.QTable`
        With ``meta["threshold"]`` (G, at disk centre) and ``meta["source"]``.

    Examples
    --------
    >>> table = read_scene_table()
    >>> table.meta["threshold"], table["distance"].unit
    ('400.0 G', Unit("Mm"))
    """
    if path is None:
        resource = importlib.resources.files("gongsynth") / "data" / SCENE_TABLE
        with importlib.resources.as_file(resource) as file:
            table = QTable.read(file, format="ascii.ecsv")
        table.meta["source"] = f"gongsynth/data/{SCENE_TABLE}"
        return table
    table = QTable.read(path, format="ascii.ecsv")
    missing = _COLUMNS - set(table.colnames)
    if missing or "threshold" not in table.meta:
        raise ValueError(f"{path} is not a gongsynth scene table: columns {sorted(missing)} and/or its "
                         f"'threshold' metadata are missing")
    table.meta["source"] = str(path)
    return table


def scene_ratio(table, theta, distance):
    """
    The tabulated ratio at each pixel's viewing angle and distance from strong fields.

    Linear in distance between the groups' median distances and in θ between
    the table's angles; beyond them the nearest value (an infinite distance:
    the farthest group's).

    Parameters
    ----------
    table : `~astropy.table.QTable`
        A scene table (`read_scene_table`).
    theta : array_like
        Viewing angle (deg).
    distance : `~astropy.units.Quantity`
        Distance from strong fields (Mm), θ's shape.

    Returns
    -------
    `numpy.ndarray`
        NaN where θ or the distance is NaN.

    Examples
    --------
    >>> import astropy.units as u
    >>> table = scene_table([dict(latitude=0, distance_min=0, distance_max=10, distance=5, ratio=1.2,
    ...                           uncertainty=0.01),
    ...                      dict(latitude=0, distance_min=10, distance_max=30, distance=15, ratio=1.0,
    ...                           uncertainty=0.01)])
    >>> scene_ratio(table, [0, 0, 40], [0, 10, 99] * u.Mm).round(3).tolist()
    [1.2, 1.1, 1.0]
    """
    theta = np.asarray(theta, float)
    distance = u.Quantity(distance)
    if not distance.unit.is_equivalent(u.Mm):
        raise ValueError(f"distance must be a length, got {distance.unit}")
    d = distance.to_value(u.Mm)
    if d.shape != theta.shape:
        raise ValueError(f"distance must have theta's shape {theta.shape}, got {d.shape}")
    latitudes = np.unique(table["latitude"].to_value(u.deg))
    out = np.zeros(theta.shape)
    valid = np.isfinite(theta) & ~np.isnan(d)
    clamped = np.where(valid, d, 0.0)
    for k, latitude in enumerate(latitudes):
        rows = table[np.isclose(table["latitude"].to_value(u.deg), latitude)]
        order = np.argsort(rows["distance"].to_value(u.Mm))
        nodes = rows["distance"].to_value(u.Mm)[order]
        along = np.interp(np.minimum(clamped, nodes[-1]), nodes, np.asarray(rows["ratio"])[order])
        # The hat function of angle k: its weight in the linear interpolation in θ (clamped at the ends).
        weight = np.interp(np.where(valid, theta, 0.0), latitudes, np.eye(latitudes.size)[k])
        out += weight * along
    return np.where(valid, out, np.nan)
