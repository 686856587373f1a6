"""
The network's flux clusters in a magnetogram: connected pixels of one sign beyond a threshold.

A quiet-Sun magnetogram at GONG's resolution shows the network as clusters
of a few pixels, each holding 10¹⁸-10²⁰ Mx.  Their number and flux per unit
area compare two maps of the same resolution directly: a simulated and a
real one, or real maps of two instruments brought to one resolution with
`gongsynth.analysis.degrade.degrade_to_gong`.  Unlike a histogram or a mean
|B|, a cluster count above a threshold several times the noise hardly
depends on the noise.

`network_clusters` takes the region within ``max_radius`` of disk centre,
removes its median (a site file's zero point), leaves out active regions
and plage (pixels where the mean |B| over a ``quiet_window`` box exceeds
``quiet_below``), labels the 8-connected pixels of each sign beyond
``threshold`` and measures each cluster's flux under the radial-field
assumption: B_LOS/μ over the pixel's area on the sphere (its area on the
sky over μ), the convention of full-disk network studies (e.g. Meunier
2003, A&A 405, 1107; Parnell et al. 2009, ApJ 698, 75, who find one power
law N(Φ) ∝ Φ^-1.85 from 2e17 to 1e23 Mx).  `NetworkClusters.summary` gives
the number and flux of clusters per area, flux percentiles and the
maximum-likelihood power-law index above a flux (Clauset, Shalizi &
Newman 2009, SIAM Review 51, 661, eq. 3.1, with its standard error), and
the clusters' median elongation: the ratio of the principal axes of each
cluster's |B|-weighted second moments on the pixel grid, each pixel counted
as a uniform square (its own variance 1/12 pixel² per axis), so that a
single pixel, or any cluster with the symmetry of a square, reads 1.  On the
real Big Bear map the network lies in chains along the cell walls, which
this measures (noise guide).
"""
from dataclasses import dataclass

import astropy.units as u
import numpy as np
from astropy.table import QTable
from scipy import ndimage
from sunpy.sun.constants import radius as solar_radius

from gongsynth.analysis.disk import check_map, disk_coordinates, local_pixel_scale, map_values
from gongsynth.validation import check_quantity

__all__ = ["NetworkClusters", "network_clusters", "quiet_mask", "QUIET_WINDOW", "QUIET_BELOW", "INDEX_FLUX",
           "SHAPE_PIXELS"]

#: Side of the box over which the mean |B| decides whether a pixel is quiet (about 2 supergranules).
QUIET_WINDOW = 60 * u.arcsec
#: A pixel is quiet where the mean |B − median| over `QUIET_WINDOW` is below this (chosen: the
#: quiet network at GONG's resolution averages 5-10 G, plage tens of G).
QUIET_BELOW = 15 * u.G
#: Lower end of the flux range of the power-law index (Meunier 2003's network patches: 3e19-1e21 Mx).
INDEX_FLUX = 3e19 * u.Mx
#: The fewest pixels of a cluster whose elongation enters the summary (chosen: fewer have no shape
#: beyond the pixel grid's).
SHAPE_PIXELS = 6


@dataclass(frozen=True)
class NetworkClusters:
    """
    The clusters of one map, as measured by `network_clusters`.

    Attributes
    ----------
    table : `~astropy.table.QTable`
        One row per cluster: ``flux`` (unsigned, Mx), ``sign`` (±1),
        ``pixels``, ``area`` (on the sphere, Mm²), ``peak`` (largest
        |B − median|, G) and ``elongation`` (ratio ≥ 1 of the principal
        axes of its |B|-weighted second moments, on the sky's pixel grid),
        largest flux first.
    region_area : `~astropy.units.Quantity`
        Area on the sphere of the quiet region searched (Mm²).
    threshold, max_radius, quiet_below :
        The arguments it was measured with.
    """

    table: QTable
    region_area: u.Quantity
    threshold: u.Quantity
    max_radius: float
    quiet_below: u.Quantity

    def summary(self, *, index_flux=INDEX_FLUX):
        """
        Numbers per area and the flux distribution's shape.

        Parameters
        ----------
        index_flux : `~astropy.units.Quantity`
            Smallest flux of the power-law fit (default `INDEX_FLUX`).

        Returns
        -------
        dict
            ``number`` (clusters), ``number_density`` (per Mm² of the region),
            ``flux_density`` (the clusters' flux over the region's area, G),
            ``p50``, ``p90``, ``p99`` (percentiles of the cluster fluxes, Mx),
            ``above_index_flux`` and ``above_1e20`` (counts), ``index`` and
            ``index_error`` (N(Φ) ∝ Φ^-index above ``index_flux``; NaN with
            fewer than 10 clusters there), ``elongation`` (median over the
            clusters of at least `SHAPE_PIXELS` pixels; NaN if none) and
            ``shaped`` (their number).
        """
        flux = np.asarray(self.table["flux"].to_value(u.Mx))
        area_mm2 = self.region_area.to_value(u.Mm**2)
        lo = check_quantity(index_flux, u.Mx, "index_flux").to_value(u.Mx)
        tail = flux[flux >= lo]
        if tail.size >= 10:
            index = 1.0 + tail.size / np.sum(np.log(tail / lo))
            index_error = (index - 1.0) / np.sqrt(tail.size)
        else:
            index = index_error = np.nan
        percentiles = np.percentile(flux, [50, 90, 99]) if flux.size else np.full(3, np.nan)
        shaped = np.asarray(self.table["elongation"])[np.asarray(self.table["pixels"]) >= SHAPE_PIXELS]
        return {
            "number": int(flux.size),
            "number_density": (flux.size / area_mm2 if area_mm2 else np.nan) / u.Mm**2,
            "flux_density": (flux.sum() / (area_mm2 * 1e16) if area_mm2 else np.nan) * u.G,
            "p50": percentiles[0] * u.Mx,
            "p90": percentiles[1] * u.Mx,
            "p99": percentiles[2] * u.Mx,
            "above_index_flux": int(tail.size),
            "above_1e20": int(np.sum(flux >= 1e20)),
            "index": index,
            "index_error": index_error,
            "elongation": float(np.median(shaped)) if shaped.size else np.nan,
            "shaped": int(shaped.size),
        }


def network_clusters(smap, *, threshold=20 * u.G, max_radius=0.35, quiet_below=QUIET_BELOW,
                     quiet_window=QUIET_WINDOW):
    """
    Label the network's clusters of a magnetogram near disk centre and measure their fluxes.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        A line-of-sight magnetogram in G (helioprojective or any WCS that
        `gongsynth.analysis.disk.disk_coordinates` understands).  Compare
        maps at one resolution: bring finer ones to GONG's first
        (`gongsynth.analysis.degrade.degrade_to_gong`).
    threshold : `~astropy.units.Quantity`
        A pixel belongs to a cluster where |B − median| exceeds this (G;
        default 20 G, four to five times GONG's quiet-Sun noise).
    max_radius : float
        The region: within this many apparent solar radii of disk centre
        (0 < max_radius < 1; default 0.35, where μ > 0.94).
    quiet_below : `~astropy.units.Quantity` or None
        Leave out pixels where the mean |B − median| over ``quiet_window``
        exceeds this (active regions, plage); ``None`` keeps every pixel.
    quiet_window : `~astropy.units.Quantity`
        Side of that box (arcsec; default `QUIET_WINDOW`).

    Returns
    -------
    NetworkClusters

    Raises
    ------
    ValueError
        A threshold or window that is not positive, or ``max_radius`` outside (0, 1).

    Examples
    --------
    >>> import numpy as np, astropy.units as u, sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> data = np.zeros((101, 101))
    >>> data[49:52, 49:52] = 100.0                       # one 3 × 3 pixel element of 100 G
    >>> m = sunpy.map.Map(data, sunpy.map.make_fitswcs_header(
    ...     data, ref, scale=[2.5, 2.5] * u.arcsec / u.pix, unit=u.G))
    >>> found = network_clusters(m, max_radius=0.1)
    >>> len(found.table), int(found.table["pixels"][0]), f"{found.table['flux'][0]:.3g}"
    (1, 9, '2.86e+19 Mx')
    """
    check_map(smap, finite=True)
    level = check_quantity(threshold, u.G, "threshold").to_value(u.G)
    if np.ndim(level) or not level > 0:
        raise ValueError(f"threshold must be a positive scalar field, got {threshold}")
    if not 0 < float(max_radius) < 1:
        raise ValueError(f"max_radius must be in (0, 1) solar radii, got {max_radius!r}")
    rho, mu = disk_coordinates(smap)
    field = map_values(smap)
    region = np.isfinite(field) & (rho < float(max_radius))
    if not region.any():
        raise ValueError(f"smap has no finite pixel within {max_radius} solar radii of disk centre")
    field = field - np.median(field[region])
    scale = local_pixel_scale(smap).to_value(u.arcsec)
    if quiet_below is not None:
        region &= quiet_mask(field, scale * u.arcsec, quiet_below=quiet_below, quiet_window=quiet_window)
    # Area on the sphere of each pixel: its area on the sky at the Sun's distance, over μ.
    km_per_arcsec = solar_radius.to_value(u.km) / smap.rsun_obs.to_value(u.arcsec)
    sphere_area = np.where(region, (scale * km_per_arcsec * 1e5) ** 2 / np.where(region, mu, 1.0), 0.0)
    radial_flux = np.where(region, field / np.where(region, mu, 1.0), 0.0) * sphere_area
    columns = {"flux": [], "sign": [], "pixels": [], "area": [], "peak": [], "elongation": []}
    weight = np.where(region, np.abs(field), 0.0)
    rows, cols = np.indices(field.shape, dtype=float)
    for sign in (1, -1):
        members = region & (sign * field > level)
        labels, n = ndimage.label(members, structure=np.ones((3, 3), dtype=bool))
        if n == 0:
            continue
        index = np.arange(1, n + 1)
        columns["flux"].append(np.abs(ndimage.sum(radial_flux, labels, index)))
        columns["sign"].append(np.full(n, sign))
        columns["pixels"].append(np.bincount(labels.ravel(), minlength=n + 1)[1:])
        columns["area"].append(ndimage.sum(sphere_area, labels, index) / 1e16)
        columns["peak"].append(ndimage.maximum(np.abs(field), labels, index))
        columns["elongation"].append(_elongation(labels, index, weight, rows, cols))
    stacked = {k: np.concatenate(v) if v else np.zeros(0) for k, v in columns.items()}
    order = np.argsort(-stacked["flux"], kind="stable")
    table = QTable({"flux": stacked["flux"][order] * u.Mx,
                    "sign": stacked["sign"][order].astype(int),
                    "pixels": stacked["pixels"][order].astype(np.int64),
                    "area": stacked["area"][order] * u.Mm**2,
                    "peak": stacked["peak"][order] * u.G,
                    "elongation": stacked["elongation"][order]})
    return NetworkClusters(table=table, region_area=sphere_area.sum() / 1e16 * u.Mm**2,
                           threshold=level * u.G, max_radius=float(max_radius),
                           quiet_below=None if quiet_below is None else u.Quantity(quiet_below, u.G))


def quiet_mask(field, pixel_scale, *, quiet_below=QUIET_BELOW, quiet_window=QUIET_WINDOW):
    """
    The quiet pixels of a magnetogram: mean |B| over a box below a level (active regions and plage out).

    Parameters
    ----------
    field : `numpy.ndarray`
        B_LOS in G with its median taken out (NaN counts as 0).
    pixel_scale : `~astropy.units.Quantity`
        The side of a pixel (arcsec).
    quiet_below : `~astropy.units.Quantity`
        A pixel is quiet where the mean :math:`|B|` over the box is below this (`QUIET_BELOW`).
    quiet_window : `~astropy.units.Quantity`
        Side of the box (`QUIET_WINDOW`).

    Returns
    -------
    `numpy.ndarray`
        Bool, the shape of ``field``.

    Examples
    --------
    >>> import numpy as np, astropy.units as u
    >>> field = np.zeros((60, 60)); field[:, 40:] = 50.0      # a plage strip
    >>> quiet = quiet_mask(field, 2.5 * u.arcsec)
    >>> bool(quiet[:, :20].all()), bool(quiet[:, 45:].any())
    (True, False)
    """
    below = check_quantity(quiet_below, u.G, "quiet_below").to_value(u.G)
    if np.ndim(below) or not below > 0:
        raise ValueError(f"quiet_below must be a positive scalar field or None, got {quiet_below}")
    window = check_quantity(quiet_window, u.arcsec, "quiet_window").to_value(u.arcsec)
    if np.ndim(window) or not window > 0:
        raise ValueError(f"quiet_window must be a positive angle, got {quiet_window}")
    scale = check_quantity(pixel_scale, u.arcsec, "pixel_scale").to_value(u.arcsec)
    side = max(1, int(round(window / scale)))
    return ndimage.uniform_filter(np.nan_to_num(np.abs(field)), side, mode="nearest") < below


def _elongation(labels, index, weight, rows, cols):
    """Axis ratio of each labelled cluster's weighted second moments (pixels as uniform squares)."""
    total = ndimage.sum(weight, labels, index)
    moment = {name: ndimage.sum(weight * a, labels, index) / total for name, a in
              (("x", cols), ("y", rows), ("xx", cols * cols), ("yy", rows * rows), ("xy", cols * rows))}
    cxx = moment["xx"] - moment["x"] ** 2 + 1 / 12
    cyy = moment["yy"] - moment["y"] ** 2 + 1 / 12
    cxy = moment["xy"] - moment["x"] * moment["y"]
    half_trace, root = 0.5 * (cxx + cyy), np.sqrt(0.25 * (cxx - cyy) ** 2 + cxy ** 2)
    return np.sqrt((half_trace + root) / np.maximum(half_trace - root, 1 / 12))
