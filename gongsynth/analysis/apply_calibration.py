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
"""
import astropy.units as u
import numpy as np
import sunpy.map
from sunpy.coordinates import frames, sun

from gongsynth.analysis.calibration import gauss_values
from gongsynth.analysis.calibration_table import read_calibration_table, table_curve
from gongsynth.analysis.disk import check_map, disk_coordinates
from gongsynth.analysis.weak_flux import QUIET_LIMIT

__all__ = ["viewing_angle", "calibrate", "weak_flux_factor_map"]


def _is_synoptic(smap):
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
    """
    check_map(smap)
    if _is_synoptic(smap):
        ny, nx = smap.data.shape
        y, x = np.mgrid[:ny, :nx]
        latitude = smap.pixel_to_world(x * u.pix, y * u.pix).lat
        b0 = sun.B0(smap.date)
        return np.abs(latitude - b0).to(u.deg)
    _, mu = disk_coordinates(smap)
    return np.rad2deg(np.arccos(mu)) * u.deg


def _interpolation(theta, angles):
    """For each θ: index of the lower tabulated angle and the weight of the upper (clamped outside)."""
    clamped = np.clip(theta, angles[0], angles[-1])
    lower = np.clip(np.searchsorted(angles, clamped, side="right") - 1, 0, max(angles.size - 2, 0))
    if angles.size == 1:
        return lower, np.zeros_like(clamped)
    weight = (clamped - angles[lower]) / (angles[lower + 1] - angles[lower])
    return lower, weight


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


def calibrate(smap, *, table=None, force=False):
    """
    Calibrate a magnetogram: replace each measured value by the true B_LOS it implies.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        Line-of-sight magnetogram in G (or unitless values taken as G): a
        simulated or real GONG (or other) disk image, or a synoptic map.
    table : `~astropy.table.QTable` or path-like, optional
        Calibration table (`gongsynth.analysis.calibration_table`); default
        the table shipped with gongsynth.
    force : bool, optional
        Calibrate even a map that is not a measurement: one calibrated
        already (its ``CALTABLE``: a second calibration multiplies the
        correction again) or a gongsynth ground-truth map.  Refused (ValueError)
        unless true.

    Returns
    -------
    `~sunpy.map.GenericMap`
        Same WCS and metadata, calibrated data in G, with ``CALTABLE`` naming
        the table and a HISTORY line.
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
    if table is None or not hasattr(table, "colnames"):
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
    meta["bunit"] = "G"
    meta["caltable"] = str(table.meta.get("source", "in-memory table"))[:68]
    meta["history"] = (str(meta.get("history", "")) + "\ngongsynth.calibrate: truth = g(measured, theta) "
                       "from the papers' flux-conserving curves").strip()
    return sunpy.map.Map(out, meta)


def weak_flux_factor_map(smap, *, table=None):
    """
    The quiet-Sun weak-flux factor (true per measured flux at zero field) at every pixel's viewing angle.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        Any map `viewing_angle` understands.
    table : `~astropy.table.QTable` or path-like, optional
        Default the table shipped with gongsynth.

    Returns
    -------
    `~sunpy.map.GenericMap`
        Dimensionless factors on the map's grid (NaN off the disk).
    """
    if table is None or not hasattr(table, "colnames"):
        table = read_calibration_table(table)
    theta = viewing_angle(smap).to_value(u.deg)
    quiet = np.asarray(table["region"]) == "quiet"
    angles = table["latitude"][quiet].to_value(u.deg)
    order = np.argsort(angles)
    factors = np.asarray(table["factor"][quiet])[order]
    valid = np.isfinite(theta)
    out = np.full(theta.shape, np.nan)
    lower, weight = _interpolation(theta[valid], angles[order])
    upper = np.minimum(lower + 1, factors.size - 1)
    out[valid] = (1 - weight) * factors[lower] + weight * factors[upper]
    meta = smap.meta.copy()
    meta["bunit"] = ""
    return sunpy.map.Map(out, meta)
