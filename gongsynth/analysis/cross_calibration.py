r"""
Cross-calibration of two magnetograms of the same Sun: ratio, bisector slope and correlation.

`cross_calibrate` compares two line-of-sight (or radial-field) magnetograms
of one Sun — simulated or real, any two of GONG, HMI and MDI, two disk images
or two Carrington synoptic maps — the way cross-instrument studies do
(e.g. Riley et al. 2014, Sol. Phys. 289, 769; Plowman & Berger paper II for
the flux-preserving resampling):

1. **A common, coarser grid** (`common_grid`), reached by flux-preserving
   resampling (the mean of each map over every cell of the grid, by exact
   area weighting):

   - *disk images*: each map is binned onto square helioprojective cells of
     side ``resolution`` with `gongsynth.analysis.degrade.degrade_to_gong`
     (``psf=False``: pixels only, no PSF), the cells anchored at the map's
     reference coordinate; ``map_b``'s cells are then put on ``map_a``'s by
     index where the two grids coincide (same observer, same reference
     point: e.g. two instruments' runs of one simulated field), and otherwise
     (different plate scales *and* observers, e.g. SDO and Earth) by
     `reproject`'s exact (area-weighted) algorithm;
   - *synoptic maps* (CEA or CAR, full Sun): both are binned onto the coarser
     map's pixel grid (or blocks of it, ``resolution`` a multiple of its
     longitude step) by exact area weighting along each axis, in the
     projection's own coordinates (longitude; sine latitude for CEA, whose
     pixels are of equal area, so the mean is flux-preserving).

2. **Masks**: a cell enters where both maps are finite on the common grid
   (disk images: on the disk), and the optional ``mask``; cells are then
   grouped by viewing angle θ from disk centre (synoptic maps: by |latitude|)
   and by field strength, the mean unsigned field of the two maps,
   (|a| + |b|) / 2 — symmetric in the two maps, so that selecting a bin does
   not bias the slope towards either map.

3. **Per group** (each angle bin × each strength bin, including the bins of
   all angles and all strengths): the unsigned- and signed-flux ratios b/a
   (Σ|b| / Σ|a| and Σb / Σa over the cells, weighted by their area on the
   Sun), the OLS-bisector slope of b against a with its uncertainty
   (`bisector_slope`; Isobe et al. 1990, ApJ 364, 104) and Pearson's
   correlation.

The bisector treats the two maps alike: with the same noise in both maps its
expected slope is the true ratio, where an ordinary least-squares fit of b on
a would be pulled towards zero by a's noise (regression dilution).  Its
uncertainty is Isobe et al.'s asymptotic formula, which assumes independent
cells: cells smaller than the maps' PSFs are correlated, and the uncertainty
is then too small.
"""
import math

import astropy.units as u
import numpy as np
import scipy.sparse
import sunpy.map
from astropy.table import QTable

from gongsynth.analysis.apply_calibration import is_synoptic, viewing_angle
from gongsynth.analysis.calibration import gauss_values
from gongsynth.analysis.degrade import degrade_to_gong, overlap_operator
from gongsynth.analysis.disk import check_map, local_pixel_scale
from gongsynth.analysis.open_flux import synoptic_pixel_edges
from gongsynth.validation import check_quantity

__all__ = ["DEFAULT_ANGLE_BINS", "DEFAULT_STRENGTH_BINS", "bisector_slope", "common_grid", "cross_calibrate"]

#: Default edges of the viewing-angle (synoptic maps: |latitude|) groups.
DEFAULT_ANGLE_BINS = u.Quantity([0, 25, 45, 60, 70, 90], u.deg)

#: Default edges of the field-strength groups, (|a| + |b|) / 2.
DEFAULT_STRENGTH_BINS = u.Quantity([0, 10, 50, 200, np.inf], u.G)

_MIN_COVERAGE = 0.5  # a cell needs at least this fraction of its area covered by finite pixels
_ALIGNED = 0.05  # cells: grids whose centres fall this close coincide (e.g. one field at dates minutes apart)


def bisector_slope(x, y):
    """
    The OLS-bisector slope of y against x and its uncertainty (Isobe et al. 1990).

    The line that bisects the ordinary least-squares fits of y on x (slope
    β₁) and of x on y (slope β₂, written as y against x):
    β₃ = (β₁β₂ − 1 + √((1 + β₁²)(1 + β₂²))) / (β₁ + β₂), with the asymptotic
    variance of Isobe, Feigelson, Akritas & Babu (1990, ApJ 364, 104,
    Table 1), valid for independent points whatever the errors in x and y.

    Parameters
    ----------
    x, y : array_like
        Same shape; non-finite pairs are dropped.

    Returns
    -------
    slope : float
    uncertainty : float
        Standard deviation of the slope.
    intercept : float
        ȳ − slope x̄.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.random.default_rng(1).normal(0, 10, 1000)
    >>> slope, sigma, _ = bisector_slope(x, 1.3 * x)
    >>> round(slope, 12), round(sigma, 12)
    (1.3, 0.0)
    """
    x = np.asarray(x, dtype=float).ravel()
    y = np.asarray(y, dtype=float).ravel()
    if x.shape != y.shape:
        raise ValueError(f"x and y must have the same size, got {x.size} and {y.size}")
    keep = np.isfinite(x) & np.isfinite(y)
    x, y = x[keep], y[keep]
    if x.size < 3:
        raise ValueError(f"need at least 3 finite pairs for a bisector slope, got {x.size}")
    dx, dy = x - x.mean(), y - y.mean()
    sxx, syy, sxy = dx @ dx, dy @ dy, dx @ dy
    if sxx <= 0 or syy <= 0 or sxy <= 0:
        raise ValueError("the bisector slope needs positively correlated x and y with non-zero spread, "
                         f"got Sxx = {sxx:.3g}, Syy = {syy:.3g}, Sxy = {sxy:.3g}")
    b1, b2 = sxy / sxx, syy / sxy
    slope = (b1 * b2 - 1 + math.sqrt((1 + b1**2) * (1 + b2**2))) / (b1 + b2)
    r1, r2 = dy - b1 * dx, dy - b2 * dx  # residuals of the two OLS lines
    var1 = np.sum(dx**2 * r1**2) / sxx**2
    var2 = np.sum(dy**2 * r2**2) / sxy**2
    cov12 = np.sum(dx * dy * r1 * r2) / (b1 * sxx**2)
    variance = slope**2 / ((b1 + b2) ** 2 * (1 + b1**2) * (1 + b2**2)) * (
        (1 + b2**2) ** 2 * var1 + 2 * (1 + b1**2) * (1 + b2**2) * cov12 + (1 + b1**2) ** 2 * var2)
    return float(slope), float(math.sqrt(max(variance, 0.0))), float(y.mean() - slope * x.mean())


def _as_gauss_map(smap, name):
    """The map with float data in G (a plain map's data taken as G)."""
    check_map(smap, name, finite=True)
    data = gauss_values(smap, name)
    if smap.mask is not None and np.any(smap.mask):
        data = np.where(smap.mask, np.nan, data)
    meta = smap.meta.copy()
    meta["bunit"] = "G"
    return sunpy.map.Map(data, meta)


def _cells_of(smap, scale):
    """A disk image binned onto square cells of ``scale`` (arcsec), flux-preserving, no PSF."""
    from gongsynth import instruments

    grid = instruments.get("gong").replace(plate_scale=scale * u.arcsec)  # only its plate scale is used
    return degrade_to_gong(smap, grid, psf=False, min_coverage=_MIN_COVERAGE)


def _on_grid_of(target, smap):
    """``smap``'s values at ``target``'s pixels: by index where the grids coincide, else reprojected."""
    ny, nx = target.data.shape
    y, x = np.mgrid[:ny, :nx]
    wcs_a, wcs_b = target.wcs.wcs, smap.wcs.wcs
    if (list(wcs_a.ctype) == list(wcs_b.ctype) and np.allclose(wcs_a.cdelt, wcs_b.cdelt)
            and np.allclose(wcs_a.crval, wcs_b.crval) and np.allclose(wcs_a.get_pc(), wcs_b.get_pc())
            and target.coordinate_frame.is_equivalent_frame(smap.coordinate_frame)):
        # One frame and one tangent point: the grids differ by a shift of the reference pixel only.
        px, py = x + (wcs_b.crpix[0] - wcs_a.crpix[0]), y + (wcs_b.crpix[1] - wcs_a.crpix[1])
    else:
        px, py = smap.wcs.world_to_pixel(target.pixel_to_world(x * u.pix, y * u.pix))
    finite = np.isfinite(px) & np.isfinite(py)
    if finite.any() and np.allclose(px[finite], np.round(px[finite]), atol=_ALIGNED) \
            and np.allclose(py[finite], np.round(py[finite]), atol=_ALIGNED):
        ix = np.round(np.where(finite, px, -1)).astype(int)
        iy = np.round(np.where(finite, py, -1)).astype(int)
        inside = finite & (ix >= 0) & (iy >= 0) & (ix < smap.data.shape[1]) & (iy < smap.data.shape[0])
        out = np.full((ny, nx), np.nan)
        out[inside] = np.asarray(smap.data, float)[iy[inside], ix[inside]]
        how = "the same cells (by index)"
    else:
        out = np.asarray(smap.reproject_to(target.wcs, algorithm="exact").data, float)
        how = "reproject's exact (area-weighted) algorithm"
    meta = target.meta.copy()
    for key in ("telescop", "instrume", "obsrvtry", "detector", "content", "origin", "dtype"):
        meta.pop(key, None)
        if key in smap.meta:
            meta[key] = smap.meta[key]
    return sunpy.map.Map(out, meta), how


def _projection(smap):
    return str(smap.wcs.wcs.ctype[0])[-3:]


def _axis_operator(edges_in, edges_out, period=None):
    """Sparse (n_out, n_in) area fractions between two uniform 1-D grids (edges in one world coordinate)."""
    step_in = edges_in[1] - edges_in[0]
    step_out = abs(edges_out[1] - edges_out[0])
    low = min(edges_out[0], edges_out[-1])
    if period is not None:  # the output origin taken to the input's period
        low += period * round((min(edges_in[0], edges_in[-1]) - low) / period)
    # overlap_operator puts output edges at multiples of step_out from the input pixel at ``low``.
    op, ref = overlap_operator(edges_in.size - 1, step_in, (low - edges_in[0]) / step_in - 0.5, step_out)
    op = op.tocoo()
    n_out = edges_out.size - 1
    rows = op.row - int(round(ref + 0.5))  # ascending output index, 0 at ``low``
    if period is not None:
        rows = np.mod(rows, n_out)
    if edges_out[-1] < edges_out[0]:
        rows = n_out - 1 - rows
    keep = (rows >= 0) & (rows < n_out)
    return scipy.sparse.csr_matrix((op.data[keep], (rows[keep], op.col[keep])),
                                   shape=(n_out, edges_in.size - 1))


def _synoptic_axes(smap, name):
    """Longitude edges (deg) and latitude-axis edges in the projection's own coordinate."""
    sin_lat, lon = synoptic_pixel_edges(smap)
    projection = _projection(smap)
    if projection == "CAR":
        return lon, np.rad2deg(np.arcsin(sin_lat)), projection
    return lon, sin_lat, projection


def _synoptic_to(smap, lon_out, y_out):
    """A synoptic map's flux-preserving means over the output cells (NaN below the coverage threshold)."""
    lon_in, y_in, _ = _synoptic_axes(smap, "map")
    opx = _axis_operator(lon_in, lon_out, period=360.0)
    opy = _axis_operator(y_in, y_out)
    data = np.asarray(smap.data, float)
    valid = np.isfinite(data)
    total = (opx @ (opy @ np.where(valid, data, 0.0)).T).T
    cover = (opx @ (opy @ valid.astype(float)).T).T
    with np.errstate(invalid="ignore", divide="ignore"):
        out = total / cover
    out[~(cover >= _MIN_COVERAGE)] = np.nan
    return out


def _synoptic_grid(map_a, map_b, resolution):
    """Both synoptic maps on the coarser one's grid (or blocks of it)."""
    axes = [_synoptic_axes(m, n) for m, n in ((map_a, "map_a"), (map_b, "map_b"))]
    if axes[0][2] != axes[1][2]:
        raise ValueError(f"map_a and map_b must share a projection, got {axes[0][2]} and {axes[1][2]}")
    coarse = 0 if map_a.data.size <= map_b.data.size else 1
    lon, y, _ = axes[coarse]
    step = abs(lon[1] - lon[0])
    block = 1
    if resolution is not None:
        check_quantity(resolution, u.deg, "resolution")
        block = float((resolution / (step * u.deg)).to_value(u.one))
        if block < 1 - 1e-6 or abs(block - round(block)) > 1e-6:
            raise ValueError(f"resolution must be a whole multiple of the coarser synoptic grid's longitude "
                             f"step ({step:g} deg) for synoptic maps, got {resolution}")
        block = int(round(block))
    lon, y = lon[::block], y[::block]
    if (lon.size - 1) * block != len(axes[coarse][0]) - 1 or (y.size - 1) * block != len(axes[coarse][1]) - 1:
        raise ValueError(f"resolution {resolution} does not divide the coarser grid "
                         f"({len(axes[coarse][1]) - 1} x {len(axes[coarse][0]) - 1} pixels) into whole "
                         "blocks")
    template = (map_a, map_b)[coarse]
    meta = template.meta.copy()
    if block > 1:  # the header's own convention (sunpy's sources fix some synoptic headers when read)
        for axis in ("1", "2"):
            meta["cdelt" + axis] = float(meta["cdelt" + axis]) * block
            meta["crpix" + axis] = (float(meta["crpix" + axis]) - 0.5) / block + 0.5
            meta["naxis" + axis] = (lon.size if axis == "1" else y.size) - 1
    meta["bunit"] = "G"
    maps = [sunpy.map.Map(_synoptic_to(smap, lon, y), meta.copy()) for smap in (map_a, map_b)]
    maps[1].meta["history"] = (str(meta.get("history", "")) + f"\ngongsynth.common_grid: the data of "
                               f"{_describe(map_b)} resampled onto this grid").strip()
    how = (f"the coarser map's synoptic grid ({'' if block == 1 else f'blocks of {block} x {block} of '}"
           f"{template.data.shape[1]} x {template.data.shape[0]} {axes[coarse][2]} pixels), exact area "
           "weighting "
           f"in longitude and {'sine latitude' if axes[coarse][2] == 'CEA' else 'latitude'}")
    return maps[0], maps[1], how


def common_grid(map_a, map_b, *, resolution=None):
    """
    Both maps on one common, coarser grid by flux-preserving resampling.

    Parameters
    ----------
    map_a, map_b : `~sunpy.map.GenericMap`
        Two magnetograms in G (or unitless, taken as G): two disk images
        (helioprojective or heliographic cut-outs) or two full-Sun synoptic
        maps (CEA or CAR).
    resolution : `~astropy.units.Quantity`, optional
        Disk images: the side of the common cells (arcsec), at least the
        coarser map's pixel (default: that pixel).  Synoptic maps: the cells'
        longitude step (deg), a whole multiple of the coarser map's (default:
        the coarser map's grid).

    Returns
    -------
    a, b : `~sunpy.map.GenericMap`
        The two maps' means over the cells of ``a``'s grid, in G.
    how : str
        How the grid was reached (for the table's metadata).
    """
    map_a = _as_gauss_map(map_a, "map_a")
    map_b = _as_gauss_map(map_b, "map_b")
    synoptic = (is_synoptic(map_a), is_synoptic(map_b))
    if synoptic[0] != synoptic[1]:
        raise ValueError("map_a and map_b must both be disk images or both synoptic maps, got a "
                         f"{'synoptic map' if synoptic[0] else 'disk image'} and a "
                         f"{'synoptic map' if synoptic[1] else 'disk image'}")
    if synoptic[0]:
        return _synoptic_grid(map_a, map_b, resolution)
    coarser = max(local_pixel_scale(map_a), local_pixel_scale(map_b))
    if resolution is None:
        resolution = coarser
    check_quantity(resolution, u.arcsec, "resolution")
    if not (np.isscalar(resolution.value) and np.isfinite(resolution.value)):
        raise ValueError(f"resolution must be one finite angle, got {resolution}")
    if resolution < coarser * (1 - 1e-3):
        raise ValueError(f"resolution must be at least the coarser map's pixel ({coarser:.4g}): "
                         f"resampling is to a common, coarser grid; got {resolution}")
    scale = resolution.to_value(u.arcsec)
    a = _cells_of(map_a, scale)
    b, how = _on_grid_of(a, _cells_of(map_b, scale))
    return a, b, (f"helioprojective cells of {scale:.4g} arcsec: each map's pixels averaged by exact area "
                  f"weighting (no PSF), map_b's cells put on map_a's by {how}")


def _edges(bins, unit, name):
    edges = u.Quantity(bins, unit) if bins is not None else None
    if edges is None or edges.ndim != 1 or edges.size < 2 or np.any(np.diff(edges.value) <= 0):
        raise ValueError(f"{name} must be at least two increasing edges in {unit}, got {bins!r}")
    return edges.to_value(unit)


def _describe(smap):
    return " ".join(str(smap.meta.get(k, "")).strip() for k in ("telescop", "instrume", "content")
                    if smap.meta.get(k)) + f" ({smap.date.isot})"


def cross_calibrate(map_a, map_b, *, resolution=None, angle_bins=DEFAULT_ANGLE_BINS,
                    strength_bins=DEFAULT_STRENGTH_BINS, mask=None, min_pixels=20):
    """
    Compare two magnetograms of the same Sun at a common, coarser resolution.

    See the module notes for the grid, the masks and the estimators.

    Parameters
    ----------
    map_a, map_b : `~sunpy.map.GenericMap`
        Two magnetograms (G) of one Sun: two disk images, or two full-Sun
        synoptic maps.  Ratios and slopes are of ``map_b`` against
        ``map_a`` (b ≈ slope × a).
    resolution : `~astropy.units.Quantity`, optional
        The common cells (see `common_grid`).
    angle_bins : `~astropy.units.Quantity`
        Edges (deg) of the viewing-angle groups (synoptic maps: |latitude|).
    strength_bins : `~astropy.units.Quantity`
        Edges (G) of the groups in (|a| + |b|) / 2.
    mask : array of bool, optional
        Cells of the common grid (``common_grid(...)[0]``'s shape) to use.
    min_pixels : int
        Groups with fewer cells get NaN statistics.

    Returns
    -------
    `~astropy.table.QTable`
        One row per group (angle bin × strength bin, each also over all
        angles / all strengths): ``angle_min``, ``angle_max`` (deg),
        ``strength_min``, ``strength_max`` (G), ``n_pixels``,
        ``unsigned_a``, ``unsigned_b`` (mean |B|, G), ``flux_ratio`` (Σ|b|/Σ|a|),
        ``signed_ratio`` (Σb/Σa), ``slope``, ``slope_uncertainty``,
        ``intercept`` (G), ``correlation``.  The metadata describe the grid,
        the masks, the maps and the estimators.

    Examples
    --------
    >>> import numpy as np, astropy.units as u, sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> field = np.random.default_rng(0).normal(0, 50, (200, 200))
    >>> header = sunpy.map.make_fitswcs_header((200, 200), ref, scale=[2.5, 2.5] * u.arcsec / u.pix, unit=u.G)
    >>> a, b = sunpy.map.Map(field, header), sunpy.map.Map(1.3 * field, header)
    >>> row = cross_calibrate(a, b, resolution=5 * u.arcsec)[0]
    >>> round(float(row["flux_ratio"]), 6), round(float(row["slope"]), 6)
    (1.3, 1.3)
    """
    angles = _edges(angle_bins, u.deg, "angle_bins")
    strengths = _edges(strength_bins, u.G, "strength_bins")
    if int(min_pixels) != min_pixels or min_pixels < 3:
        raise ValueError(f"min_pixels must be an integer >= 3, got {min_pixels!r}")
    a_map, b_map, how = common_grid(map_a, map_b, resolution=resolution)
    a, b = np.asarray(a_map.data, float), np.asarray(b_map.data, float)
    synoptic = is_synoptic(a_map)
    if synoptic:
        ny, nx = a.shape
        y, x = np.mgrid[:ny, :nx]
        latitude = a_map.pixel_to_world(x * u.pix, y * u.pix).lat.to_value(u.deg)
        angle = np.abs(latitude)
        # Cell area on the Sun: equal for CEA, cos(latitude) for plate carrée.
        weight = np.cos(np.deg2rad(latitude)) if _projection(a_map) == "CAR" else np.ones_like(a)
    else:
        angle = viewing_angle(a_map).to_value(u.deg)
        weight = np.ones_like(a)  # cells of equal area on the sky: line-of-sight flux
    valid = np.isfinite(a) & np.isfinite(b) & np.isfinite(angle)
    if mask is not None:
        mask = np.asarray(mask)
        if mask.shape != a.shape or mask.dtype != bool:
            raise ValueError(f"mask must be a boolean array of the common grid's shape {a.shape}, "
                             f"got {mask.dtype} {mask.shape}")
        valid &= mask
    if not valid.any():
        raise ValueError("map_a and map_b share no finite cell on the common grid (do they cover the same "
                         "Sun?)")
    strength = (np.abs(a) + np.abs(b)) / 2
    angle_groups = [(angles[0], angles[-1])] + list(zip(angles[:-1], angles[1:]))
    strength_groups = [(strengths[0], strengths[-1])] + list(zip(strengths[:-1], strengths[1:]))
    if len(angles) == 2:
        angle_groups = angle_groups[:1]
    if len(strengths) == 2:
        strength_groups = strength_groups[:1]
    rows = []
    for lo, hi in angle_groups:
        in_angle = valid & (angle >= lo) & ((angle < hi) | ((hi == angles[-1]) & (angle <= hi)))
        for slo, shi in strength_groups:
            sel = in_angle & (strength >= slo) & (strength < shi)
            rows.append((lo, hi, slo, shi) + _statistics(a[sel], b[sel], weight[sel], min_pixels))
    table = QTable(rows=rows, names=("angle_min", "angle_max", "strength_min", "strength_max", "n_pixels",
                                     "unsigned_a", "unsigned_b", "flux_ratio", "signed_ratio", "slope",
                                     "slope_uncertainty", "intercept", "correlation"))
    for name, unit in (("angle_min", u.deg), ("angle_max", u.deg), ("strength_min", u.G),
                       ("strength_max", u.G), ("unsigned_a", u.G), ("unsigned_b", u.G), ("intercept", u.G)):
        table[name] = table[name] * unit
    scale = (a_map.scale.axis1 * u.pix).to(u.deg if synoptic else u.arcsec)
    table.meta.update({
        "map_a": _describe(map_a), "map_b": _describe(map_b),
        "ratio": "map_b / map_a (b = slope x a + intercept)",
        "grid": how, "grid_shape": list(a.shape), "resolution": str(abs(scale).round(6)),
        "mask_valid": f"finite in both maps on the common grid (cells >= {_MIN_COVERAGE:g} covered)"
                      + ("" if mask is None else ", and the caller's mask") + f": {int(valid.sum())} cells",
        "mask_angle": "|latitude| of the cell (synoptic maps)" if synoptic
                      else "viewing angle theta = arccos(mu) of the cell centre",
        "mask_strength": "(|a| + |b|) / 2 of the cell, G; groups [min, max)",
        "weights": ("cell area on the Sun (CAR: cos latitude)" if synoptic
                    else "equal (cells of equal sky area)"),
        "slope_estimator": "OLS bisector with its asymptotic uncertainty, Isobe et al. 1990, ApJ 364, 104 "
                           "(assumes independent cells)",
        "min_pixels": int(min_pixels),
    })
    return table


def _statistics(a, b, weight, min_pixels):
    """n, mean |a|, mean |b|, unsigned and signed flux ratios, bisector slope ± σ, intercept, correlation."""
    n = int(a.size)
    if n < min_pixels:
        return (n,) + (np.nan,) * 8
    with np.errstate(invalid="ignore", divide="ignore"):
        mean_a = float(np.sum(weight * np.abs(a)) / np.sum(weight))
        mean_b = float(np.sum(weight * np.abs(b)) / np.sum(weight))
        signed = float(np.sum(weight * b) / np.sum(weight * a))
        correlation = float(np.corrcoef(a, b)[0, 1]) if np.std(a) > 0 and np.std(b) > 0 else np.nan
    try:
        slope, sigma, intercept = bisector_slope(a, b)
    except ValueError:  # uncorrelated or constant cells: no line to fit
        slope = sigma = intercept = np.nan
    return n, mean_a, mean_b, mean_b / mean_a if mean_a > 0 else np.nan, signed, slope, sigma, intercept, \
        correlation
