"""
Applying a calibration table to a magnetogram: ``truth = g(measured, viewing angle)``.

Rules (documented in the guide's calibration page):

- **Viewing angle per pixel.**  Disk images (helioprojective, or heliographic
  cut-outs): μ from the pixel's apparent distance to disk centre
  (`gongsynth.analysis.disk.disk_coordinates`), θ = arccos μ.  Synoptic maps
  (Carrington longitude spanning more than 180°): every longitude was seen
  near central-meridian passage, so θ = |latitude − B0| with B0 at the map's
  date (B0 changes by under 1° over a rotation; this is an approximation,
  exact only at central meridian).
- **Between the table's angles** the curves are interpolated linearly in θ,
  g = (1 − w) g_k + w g_{k+1}; **beyond them** the nearest curve is used (the
  papers stop at 75°, so the outermost ~4 % of the disk radius takes the 75°
  curve).
- **Which curve**: the quiet-Sun curve where |B_measured| < 400 G × cos θ
  (the papers' quiet-Sun limit), the sunspot curve elsewhere (or the
  quiet-Sun curve if the table has no sunspot rows).  Off-disk and NaN
  pixels stay NaN.
- **Scene** (``scene="distance"``, opt-in): each quiet pixel's calibrated
  value is multiplied by the scene table's ratio at its θ and its distance on
  the Sun to the nearest strong pixel of the map itself (``|B_measured|`` ≥ the
  table's threshold × cos θ, by default the same 400 G × cos θ;
  `gongsynth.analysis.scene_calibration`; shipped:
  ``gongsynth/data/scene_factors.ecsv``).  The default ``scene="angle"``
  applies the angle-only curves: the scene table was measured on one model
  scene (one spot size) at GONG's native 2.5″ pixels, where the threshold
  finds the spot; on coarser maps (synoptic maps' 1°) the same threshold
  finds fewer strong pixels, and the distances mean something else.
- **To another instrument's scale** (``to="hmi"``, ``to="mdi"``, ``to="gong"``): the map's instrument is
  read from its header (`map_instrument`); each pixel is multiplied by the
  predicted conversion factor at its viewing angle, interpolated in θ like
  the curves, from the conversion table
  (`gongsynth.analysis.cross_calibration_table`; shipped:
  ``gongsynth/data/cross_calibration_default.ecsv``).  The factor is one
  number per angle over all field strengths.
- **Uncertainties**: the table's ``uncertainty`` (statistical: seeds and
  bootstrap) and ``systematic`` (the Sun-model ensemble) of the quiet-Sun
  factor are kept apart: `weak_flux_factor_map` maps either at every pixel's
  θ (``column=``), and `calibrate` writes the largest relative value of each
  over the map's angles in the header (``CALSTAT``, ``CALSYST``; a table
  without a ``systematic`` column, as shipped before, writes no ``CALSYST``).
"""
import astropy.units as u
import numpy as np
import sunpy.map
from sunpy.coordinates import frames, sun

from gongsynth.analysis.calibration import gauss_values
from gongsynth.analysis.calibration_table import read_calibration_table, table_curve
from gongsynth.analysis.cross_calibration_table import conversion_factors, read_cross_calibration_table
from gongsynth.analysis.disk import check_map, disk_coordinates, tiled_pointing
from gongsynth.analysis.scene_calibration import (
    read_scene_table,
    scene_ratio,
    strong_field_distance,
    strong_field_mask,
)
from gongsynth.analysis.weak_flux import QUIET_LIMIT

__all__ = ["SCENES", "is_synoptic", "viewing_angle", "map_instrument", "calibrate", "weak_flux_factor_map",
           "scene_factor_map"]

#: The values of `calibrate`'s ``scene``: the angle-only table (default), or with the distance from
#: strong fields.
SCENES = ("angle", "distance")


def is_synoptic(smap):
    """
    Whether a map is a synoptic map: heliographic, spanning more than 180° of longitude.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`

    Returns
    -------
    bool
    """
    # The axis types first: cheaper than building the coordinate frame, which disk images never need here.
    if tuple(str(axis)[:4] for axis in smap.coordinate_system) not in (("CRLN", "CRLT"), ("HGLN", "HGLT")):
        return False
    frame = smap.coordinate_frame
    if not isinstance(frame, (frames.HeliographicCarrington, frames.HeliographicStonyhurst)):
        return False
    # Longitudes wrap, so the span comes from the pixel scale, not from the end pixels.
    span = abs(smap.scale.axis1 * smap.data.shape[1] * u.pix)
    return span.unit.is_equivalent(u.deg) and span.to_value(u.deg) > 180


def viewing_angle(smap):
    """
    The angle θ between the line of sight and the local vertical at every pixel.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        A disk image (helioprojective or heliographic cut-out) or a synoptic
        map (Carrington, more than 180° of longitude).

    Returns
    -------
    `~astropy.units.Quantity`
        (ny, nx) in deg; NaN off the disk.

    Examples
    --------
    >>> import numpy as np, astropy.units as u, sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> m = sunpy.map.Map(np.zeros((9, 9)), sunpy.map.make_fitswcs_header(
    ...     (9, 9), ref, scale=[250, 250] * u.arcsec / u.pix))
    >>> theta = viewing_angle(m)
    >>> float(theta[4, 4].value), bool(np.isnan(theta[0, 0]))
    (0.0, True)

    A simulated tiled map (``SIMMODE = 'tiled'``) is one box seen at one
    angle and repeated over the frame: its WCS only places the frame's
    centre on the disk, so every pixel gets the run's angle, that of its
    field-centre latitude ``SIMLAT`` at ``DATE-BEG``.
    """
    check_map(smap)
    pointing = tiled_pointing(smap)
    if pointing is not None:
        return np.full(smap.data.shape, np.rad2deg(np.arccos(pointing.mu))) * u.deg
    if is_synoptic(smap):
        ny, nx = smap.data.shape
        y, x = np.mgrid[:ny, :nx]
        latitude = smap.pixel_to_world(x * u.pix, y * u.pix).lat
        b0 = sun.B0(smap.date)
        return np.abs(latitude - b0).to(u.deg)
    _, mu = disk_coordinates(smap)
    return np.rad2deg(np.arccos(mu)) * u.deg


def map_instrument(smap):
    """
    The instrument of the family that made a map, from its header.

    Simulated maps say it in their TELESCOP (``"gongsynth (simulated HMI)"``);
    real ones: GONG (TELESCOP ending in "GONG", e.g. ``NSO-GONG``), HMI
    (TELESCOP ``SDO/HMI`` or INSTRUME ``HMI...``), MDI (INSTRUME ``MDI``).

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap` or dict-like
        The map, or its header.

    Returns
    -------
    str
        ``"gong"``, ``"hmi"`` or ``"mdi"``.

    Raises
    ------
    ValueError
        If the header names none of them.

    Examples
    --------
    >>> map_instrument({"telescop": "NSO-GONG"}), map_instrument({"telescop": "SOHO", "instrume": "MDI"})
    ('gong', 'mdi')
    """
    meta = smap.meta if hasattr(smap, "meta") else smap
    if not hasattr(meta, "get"):
        raise TypeError(f"smap must be a sunpy Map or a header, got {type(smap).__name__}")
    telescope = str(meta.get("telescop", "")).strip().upper()
    instrument = str(meta.get("instrume", "")).strip().upper()
    if telescope.startswith("GONGSYNTH (SIMULATED ") and telescope.endswith(")"):
        return telescope[len("GONGSYNTH (SIMULATED "):-1].lower()
    if telescope.endswith("GONG"):
        return "gong"
    if "HMI" in telescope or instrument.startswith("HMI"):
        return "hmi"
    if "MDI" in instrument or "MDI" in telescope:
        return "mdi"
    raise ValueError(f"cannot tell which instrument made smap (TELESCOP = {telescope!r}, INSTRUME = "
                     f"{instrument!r}): pass instrument= to calibrate (CLI: --instrument)")


def _interpolation(theta, angles):
    """For each θ: index of the lower tabulated angle and the weight of the upper (clamped outside)."""
    clamped = np.clip(theta, angles[0], angles[-1])
    lower = np.clip(np.searchsorted(angles, clamped, side="right") - 1, 0, max(angles.size - 2, 0))
    if angles.size == 1:
        return lower, np.zeros_like(clamped)
    weight = (clamped - angles[lower]) / (angles[lower + 1] - angles[lower])
    return lower, weight


def _factor_at(theta, angles, factors):
    """Factors tabulated at increasing ``angles`` (deg), interpolated linearly in θ (clamped); NaN θ: NaN."""
    valid = np.isfinite(theta)
    out = np.full(theta.shape, np.nan)
    lower, weight = _interpolation(theta[valid], angles)
    upper = np.minimum(lower + 1, factors.size - 1)
    out[valid] = (1 - weight) * factors[lower] + weight * factors[upper]
    return out


def _apply(values, theta, table, region):
    """g(values) for one region's curves, interpolated in θ between the tabulated angles."""
    angles = np.unique(table["latitude"][np.asarray(table["region"]) == region].to_value(u.deg))
    lower, weight = _interpolation(theta, angles)
    out = np.zeros_like(values)
    for k, angle in enumerate(angles):
        near = (lower == k) | (lower == k - 1)
        if not near.any():
            continue
        curve = table_curve(table, angle * u.deg, region)
        share = np.where(lower[near] == k, 1 - weight[near], weight[near])
        out[near] += share * curve(values[near]).to_value(u.G)
    return out


def calibrate(smap, *, table=None, force=False, to="truth", instrument=None, scene="angle", scene_table=None):
    """
    Calibrate a magnetogram: each value replaced by the true B_LOS it implies, or put on another scale.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        Line-of-sight magnetogram in G (or unitless values taken as G): a
        simulated or real GONG (or other) disk image, or a synoptic map.
    table : `~astropy.table.QTable` or path-like, optional
        ``to="truth"``: the calibration table
        (`gongsynth.analysis.calibration_table`); otherwise the conversion
        table (`gongsynth.analysis.cross_calibration_table`).  Default the
        table shipped with gongsynth (for ``to="truth"``: the map's
        instrument's).
    force : bool, optional
        Calibrate even a map that is not a measurement: one calibrated
        already (its ``CALTABLE``: a second calibration multiplies the
        correction again) or a gongsynth ground-truth map.  Refused (ValueError)
        unless true.
    to : str
        ``"truth"`` (default): the papers' curves, truth = g(measured, θ)
        (with a conversion table as ``table``: the map's instrument's
        predicted factor to the truth instead, for any instrument).
        An instrument's name (``"hmi"``, ``"mdi"``, ``"gong"``): the map on
        that instrument's scale, measured × the predicted factor at each
        pixel's θ (any ordered pair of the conversion table's instruments:
        the shipped one has GONG, HMI and MDI).  The factors are predicted
        from physics, not fitted: the shipped GONG→HMI one is below the
        published whole-disk factor (see the Cross-calibration guide).
    instrument : str, optional
        The map's instrument (``"gong"``, ``"hmi"``, ``"mdi"``); default read
        from its header (`map_instrument`).  With ``to`` another instrument it
        picks the conversion (ValueError when the header names none); with
        ``to="truth"`` and no ``table`` it picks the shipped table of that
        instrument (`~gongsynth.analysis.calibration_table.INSTRUMENT_TABLES`;
        GONG's when the header names none).
    scene : {"angle", "distance"}
        ``"angle"`` (default): the curves of the table at each pixel's θ.
        ``"distance"``: besides, each quiet pixel's value times the scene
        table's ratio at its θ and distance from the map's own strong pixels
        (`scene_factor_map`; module notes).  Only with the calibration
        curves (``to="truth"`` and a calibration table).
    scene_table : `~astropy.table.QTable` or path-like, optional
        The scene table for ``scene="distance"``
        (`gongsynth.analysis.scene_calibration.read_scene_table`); default the
        shipped one.

    Returns
    -------
    `~sunpy.map.GenericMap`
        Same WCS and metadata, calibrated data in G, with ``CALTABLE`` naming
        the table (``CALTO`` the target scale; ``CALSCENE`` the scene table
        with ``scene="distance"``), ``CALSTAT`` and ``CALSYST`` (the largest
        relative statistical and systematic uncertainty of the quiet-Sun
        factor over the map's angles, where the table has them) and a
        HISTORY line.

    Examples
    --------
    >>> import numpy as np, astropy.units as u, sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> header = sunpy.map.make_fitswcs_header((3, 3), ref, scale=[2.5, 2.5] * u.arcsec / u.pix,
    ...                                        unit=u.G, telescope="NSO-GONG")
    >>> on_hmi = calibrate(sunpy.map.Map(np.full((3, 3), 10.0), header), to="hmi")
    >>> on_hmi.meta["calto"], bool(on_hmi.data[1, 1] > 10)
    ('hmi', True)
    """
    check_map(smap)
    content = str(smap.meta.get("content", ""))
    if not force and "caltable" in smap.meta:
        raise ValueError(f"the map is calibrated already (CALTABLE = {smap.meta['caltable']!r}): calibrating "
                         f"it again would multiply the correction; calibrate the measured map instead, or "
                         f"force it (calibrate --force)")
    if not force and content.upper().startswith("TRUE B_LOS"):
        raise ValueError(f"the map is a ground-truth map (CONTENT = {content!r}), not a measurement: "
                         f"calibrate the magnetogram, or force it (calibrate --force)")
    to = _scale_name(to, "to", truth=True)
    if scene not in SCENES:
        raise ValueError(f"scene must be one of {SCENES}, got {scene!r}")
    conversion = to != "truth" or (hasattr(table, "colnames") and "target" in table.colnames)
    if scene != "angle" and conversion:
        raise ValueError("scene='distance' applies to the calibration curves only (to='truth' with a "
                         "calibration table), not to a conversion table's factors")
    if scene_table is not None and scene == "angle":
        raise ValueError("scene_table is used only with scene='distance'")
    if conversion:
        return _convert(smap, to, table, instrument)
    if table is None:
        # Each instrument has its own curves: a map read with GONG's would be wrong by ~2x for HMI or MDI.
        table = read_calibration_table(instrument=_truth_instrument(smap, instrument))
        if scene != "angle" and scene_table is None and table.meta.get("instrument_name", "gong") != "gong":
            raise ValueError("scene='distance': the shipped scene table is GONG's; pass scene_table= one "
                             "made for this instrument")
    elif instrument is not None:
        raise ValueError("with to='truth', instrument chooses the shipped table: pass table or instrument, "
                         "not both")
    elif not hasattr(table, "colnames"):
        table = read_calibration_table(table)
    measured = gauss_values(smap, "smap")
    theta = viewing_angle(smap).to_value(u.deg)
    valid = np.isfinite(measured) & np.isfinite(theta)
    regions = set(np.asarray(table["region"]))
    if "quiet" not in regions:
        raise ValueError("the calibration table has no quiet-Sun curves")
    limit = QUIET_LIMIT.to_value(u.G) * np.cos(np.deg2rad(theta))
    strong = valid & (np.abs(measured) >= limit) & ("sunspot" in regions)
    quiet = valid & ~strong
    out = np.full(measured.shape, np.nan)
    out[quiet] = _apply(measured[quiet], theta[quiet], table, "quiet")
    if strong.any():
        out[strong] = _apply(measured[strong], theta[strong], table, "sunspot")
    meta = smap.meta.copy()
    how = "truth = g(measured, theta) from the papers' flux-conserving curves"
    if scene == "distance":
        scene_table = _scene_table(scene_table)
        out[quiet] *= _scene_ratio(smap, measured, theta, scene_table)[quiet]
        meta["calscene"] = str(scene_table.meta.get("source", "in-memory table"))[:68]
        how += ", quiet pixels x ratio(theta, distance from |B| >= threshold cos theta)"
    meta["bunit"] = "G"
    meta["caltable"] = str(table.meta.get("source", "in-memory table"))[:68]
    meta.update(_relative_uncertainties(theta[valid], table))
    meta["history"] = (str(meta.get("history", "")) + f"\ngongsynth.calibrate: {how}").strip()
    return sunpy.map.Map(out, meta)


def _quiet_column(table, column):
    """A quiet-Sun column of the table at its angles, in increasing order: (angles, values)."""
    quiet = np.asarray(table["region"]) == "quiet"
    angles = table["latitude"][quiet].to_value(u.deg)
    order = np.argsort(angles)
    return angles[order], np.asarray(table[column][quiet], float)[order]


def _relative_uncertainties(theta, table):
    """Header keywords: the largest relative statistical (CALSTAT) and systematic (CALSYST) error on θ."""
    keywords = {}
    if theta.size == 0:
        return keywords
    angles, factors = _quiet_column(table, "factor")
    for keyword, column in (("calstat", "uncertainty"), ("calsyst", "systematic")):
        if column in table.colnames:
            relative = _factor_at(theta, angles, _quiet_column(table, column)[1] / factors)
            if np.isfinite(relative).any():
                keywords[keyword] = round(float(np.nanmax(relative)), 4)
    return keywords


def _scene_table(table):
    if table is None or not hasattr(table, "colnames"):
        return read_scene_table(table)
    if "threshold" not in table.meta:
        raise ValueError("scene_table has no 'threshold' in its metadata (see read_scene_table)")
    return table


def _scene_ratio(smap, measured, theta, table):
    """The scene table's ratio at every pixel (NaN off the disk)."""
    threshold = u.Quantity(table.meta["threshold"])
    distance = strong_field_distance(smap, strong_field_mask(measured, theta, threshold))
    return scene_ratio(table, theta, distance)


def scene_factor_map(smap, *, table=None):
    """
    The scene ratio that ``calibrate(smap, scene="distance")`` applies to each quiet pixel.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        A magnetogram (G) that `viewing_angle` understands.
    table : `~astropy.table.QTable` or path-like, optional
        A scene table; default the shipped one.

    Returns
    -------
    `~sunpy.map.GenericMap`
        Dimensionless ratios on the map's grid (NaN off the disk); the strong
        pixels, which keep the sunspot curve, have theirs too.
    """
    check_map(smap)
    table = _scene_table(table)
    measured = gauss_values(smap, "smap")
    ratio = _scene_ratio(smap, measured, viewing_angle(smap).to_value(u.deg), table)
    meta = smap.meta.copy()
    meta["bunit"] = ""
    return sunpy.map.Map(ratio, meta)


def _scale_name(name, argument, *, truth=False):
    """A scale's name in lower case: an instrument of the family (or ``"truth"``); ValueError otherwise."""
    from gongsynth import instruments

    known = (("truth",) if truth else ()) + tuple(instruments.names())
    if not isinstance(name, str) or name.lower() not in known:
        raise ValueError(f"{argument} must be one of {known}, got {name!r}")
    return name.lower()


def _truth_instrument(smap, instrument):
    """Whose shipped calibration table: ``instrument``, else the map's header's, else GONG's."""
    if instrument is not None:
        return _scale_name(instrument, "instrument")
    try:
        return map_instrument(smap)
    except ValueError:
        return "gong"       # a header that names no instrument: GONG's table, as before the family


def _convert(smap, to, table, instrument):
    """The map on instrument ``to``'s scale: measured × the predicted factor at each pixel's θ."""
    source = map_instrument(smap) if instrument is None else _scale_name(instrument, "instrument")
    if source == to:
        raise ValueError(f"smap is a {source.upper()} map already: to={to!r} would change nothing")
    if table is None or not hasattr(table, "colnames"):
        table = read_cross_calibration_table(table)
    latitude, factors, _ = conversion_factors(table, source, to)
    measured = gauss_values(smap, "smap")
    out = measured * _factor_at(viewing_angle(smap).to_value(u.deg), latitude.to_value(u.deg), factors)
    meta = smap.meta.copy()
    meta["bunit"] = "G"
    meta["caltable"] = str(table.meta.get("source", "in-memory table"))[:68]
    meta["calto"] = to
    meta["history"] = (str(meta.get("history", "")) + f"\ngongsynth.calibrate: {source.upper()} put on "
                       f"{to.upper()}'s scale, measured x predicted factor(theta)").strip()
    return sunpy.map.Map(out, meta)


def weak_flux_factor_map(smap, *, table=None, column="factor"):
    """
    The quiet-Sun weak-flux factor (true per measured flux at zero field) at every pixel's viewing angle.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        Any map `viewing_angle` understands.
    table : `~astropy.table.QTable` or path-like, optional
        Default the table shipped with gongsynth.
    column : {"factor", "uncertainty", "systematic"}
        The factor (default), or its statistical or systematic uncertainty
        (absolute, interpolated in θ like the factor).

    Returns
    -------
    `~sunpy.map.GenericMap`
        Dimensionless values on the map's grid (NaN off the disk).
    """
    if column not in ("factor", "uncertainty", "systematic"):
        raise ValueError(f"column must be 'factor', 'uncertainty' or 'systematic', got {column!r}")
    if table is None or not hasattr(table, "colnames"):
        table = read_calibration_table(table)
    if column not in table.colnames:
        raise ValueError(f"the calibration table has no {column!r} column (tables built before issue 24 "
                         f"have no 'systematic')")
    theta = viewing_angle(smap).to_value(u.deg)
    out = _factor_at(theta, *_quiet_column(table, column))
    meta = smap.meta.copy()
    meta["bunit"] = ""
    return sunpy.map.Map(out, meta)
