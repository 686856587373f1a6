"""
Statistics of map values: robust sigma, pixel-difference noise and on-disk field histograms.

These are the numbers that `gongsynth.compare` puts side by side for a
simulated and a real magnetogram (the quiet-box noise is in
`gongsynth.analysis.noise`).  `field_histogram` takes a sunpy Map and works on
any pixel scale and any helioprojective (or heliographic) WCS: "on the disk"
is measured in units of the apparent solar radius of the map's observer
(`gongsynth.analysis.disk`), so the same call means the same region for GONG,
MDI and HMI.  `FieldHistogram.to_table` gives the histogram as an
`astropy.table.QTable` with units, the summary numbers in its ``meta``.

The robust sigma is 1.4826 × MAD (median absolute deviation from the
median, `astropy.stats.mad_std`), which ignores the few strong pixels of a
quiet region.  The pixel-difference method (standard deviation of neighbour
differences / √2) removes structure larger than a pixel and so measures
spatially white noise, but it underestimates noise that is correlated between
pixels (interpolated data).
"""
from dataclasses import dataclass, field

import astropy.units as u
import numpy as np
from astropy.stats import mad_std
from astropy.table import QTable

from gongsynth.analysis.disk import disk_coordinates as disk_coordinates  # re-exported (was here)
from gongsynth.analysis.disk import disk_values, map_values
from gongsynth.analysis.disk import local_pixel_scale as local_pixel_scale  # re-exported (was here)

__all__ = [
    "MAD_TO_SIGMA",
    "robust_sigma",
    "pixel_difference_sigma",
    "check_fraction",
    "FieldHistogram",
    "field_histogram",
    "histogram_of_values",
    "TAIL_PERCENTILES",
    "tail_percentiles",
    "RING_EDGES",
    "ring_means",
    "rings_of_values",
]

#: Ratio of the standard deviation to the median absolute deviation of a
#: Gaussian, 1 / Φ⁻¹(3/4): the factor `astropy.stats.mad_std` applies.
MAD_TO_SIGMA = 1.482602218505602


def robust_sigma(values):
    """
    Robust standard deviation 1.4826 × MAD of the finite values (`astropy.stats.mad_std`).

    Parameters
    ----------
    values : array_like or `~astropy.units.Quantity`
        Any shape; NaN and infinities are ignored.

    Returns
    -------
    float or `~astropy.units.Quantity`
        Same unit as ``values``; NaN if no value is finite.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.random.default_rng(1).normal(0, 3, 100_000)
    >>> round(float(robust_sigma(x)), 1)
    3.0
    """
    unit = getattr(values, "unit", None)
    v = np.asarray(getattr(values, "value", values), dtype=np.float64).ravel()
    v = v[np.isfinite(v)]
    sigma = mad_std(v) if v.size else np.nan
    return sigma * unit if unit is not None else float(sigma)


def pixel_difference_sigma(values, *, robust=False):
    """
    Noise from neighbour differences: std(first differences) / √2.

    Differences are taken along both axes and pooled; pairs with a NaN are
    skipped.  For spatially white noise of standard deviation σ this returns σ
    whatever smooth structure lies underneath; noise correlated between
    neighbours (interpolated or smoothed data) is underestimated.

    Parameters
    ----------
    values : array_like or `~astropy.units.Quantity`
        2-D image.
    robust : bool
        Use 1.4826 × MAD of the differences instead of their standard deviation.

    Returns
    -------
    float or `~astropy.units.Quantity`
        Same unit as ``values``.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(2)
    >>> ramp = np.add.outer(np.arange(300.0), np.arange(300.0))   # smooth structure
    >>> round(float(pixel_difference_sigma(ramp + rng.normal(0, 2, (300, 300)))), 1)
    2.0
    """
    unit = getattr(values, "unit", None)
    v = np.asarray(getattr(values, "value", values), dtype=np.float64)
    if v.ndim != 2 or min(v.shape) < 2:
        raise ValueError(f"values must be a 2-D image of at least 2x2 pixels, got shape {v.shape}")
    diffs = np.concatenate([np.diff(v, axis=0).ravel(), np.diff(v, axis=1).ravel()])
    diffs = diffs[np.isfinite(diffs)]
    if diffs.size == 0:
        sigma = np.nan
    elif robust:
        sigma = robust_sigma(diffs) / np.sqrt(2)
    else:
        sigma = np.std(diffs) / np.sqrt(2)
    return sigma * unit if unit is not None else float(sigma)


def check_fraction(value, name, *, upper=None):
    """
    A positive finite number (at most ``upper``), or a clear error naming the argument.

    Parameters
    ----------
    value : float
    name : str
        Argument name for the message.
    upper : float, optional
        Largest allowed value.

    Returns
    -------
    float

    Examples
    --------
    >>> check_fraction("0.5", "max_radius")
    0.5
    >>> check_fraction(2, "min_valid", upper=1)
    Traceback (most recent call last):
    ...
    ValueError: min_valid must be a positive number and at most 1, got 2.0
    """
    value = float(value)
    if not np.isfinite(value) or value <= 0 or (upper is not None and value > upper):
        limit = f" and at most {upper}" if upper is not None else ""
        raise ValueError(f"{name} must be a positive number{limit}, got {value!r}")
    return value


@dataclass(frozen=True)
class FieldHistogram:
    """
    Histogram and summary numbers of the on-disk pixels of a map.

    Attributes
    ----------
    edges : `~astropy.units.Quantity`
        Bin edges (nbins + 1,), unit of the map (G for magnetograms).
    counts : `numpy.ndarray`
        Pixels per bin (int).
    density : `~astropy.units.Quantity`
        counts / (n × bin width): a probability density, 1 / (map unit).
    n : int
        Pixels used (finite, within ``max_radius``).
    below, above : int
        Pixels below the first and above the last edge (not in ``counts``).
    mean, std, robust_sigma, mean_abs : `~astropy.units.Quantity`
        Of all ``n`` pixels.
    percentiles : dict
        1st, 50th and 99th percentiles (keys 1, 50, 99).
    absolute : bool
        True if the histogram is of |value| (log-spaced edges).
    """

    edges: u.Quantity
    counts: np.ndarray
    density: u.Quantity
    n: int
    below: int
    above: int
    mean: u.Quantity
    std: u.Quantity
    robust_sigma: u.Quantity
    mean_abs: u.Quantity
    percentiles: dict = field(default_factory=dict)
    absolute: bool = False

    @property
    def centres(self):
        """Bin centres (arithmetic, or geometric for an absolute histogram)."""
        e = self.edges
        return np.sqrt(e[1:] * e[:-1]) if self.absolute else 0.5 * (e[1:] + e[:-1])

    def to_table(self):
        """
        The histogram as a table, one row per bin.

        Returns
        -------
        `~astropy.table.QTable`
            Columns ``lower``, ``upper``, ``centre`` (map unit), ``counts`` and
            ``density`` (1 / map unit); ``meta`` holds ``n``, ``below``,
            ``above``, ``mean``, ``std``, ``robust_sigma``, ``mean_abs``,
            ``percentiles`` and ``absolute``.

        Examples
        --------
        >>> import astropy.units as u
        >>> import numpy as np
        >>> h = histogram_of_values(np.array([-2.0, 1.0, 1.5]), u.G, np.array([-3, 0, 3]) * u.G,
        ...                         absolute=False)
        >>> t = h.to_table()
        >>> t["counts"].tolist(), t["centre"].unit, t.meta["n"]
        ([1, 2], Unit("G"), 3)
        """
        columns = {"lower": self.edges[:-1], "upper": self.edges[1:], "centre": self.centres,
                   "counts": self.counts, "density": self.density}
        meta = {"n": self.n, "below": self.below, "above": self.above, "mean": self.mean,
                "std": self.std, "robust_sigma": self.robust_sigma, "mean_abs": self.mean_abs,
                "percentiles": dict(self.percentiles), "absolute": self.absolute}
        return QTable(columns, meta=meta)


def field_histogram(smap, *, bins=None, max_radius=0.98, absolute=False):
    """
    Histogram of the on-disk values of a map (a magnetogram: B_LOS in G).

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        The map; pixels that are NaN, masked or farther than ``max_radius``
        from disk centre are left out.
    bins : int or `~astropy.units.Quantity`, optional
        Number of bins or the bin edges (in the map's unit).  Default: 5 G
        bins over ±500 G (signed), or 60 log-spaced bins over 1–3000 G
        (``absolute=True``).  An int gives bins of equal width over ±500 G
        (signed) or log-spaced bins over 1–3000 G (absolute).
    max_radius : float
        Outer radius of the region used, in solar radii (default 0.98).
    absolute : bool
        Histogram of |value| instead of value (for log-log plots).

    Returns
    -------
    `FieldHistogram`

    Raises
    ------
    ValueError
        If no finite on-disk pixel is left.

    Examples
    --------
    >>> import astropy.units as u
    >>> import numpy as np
    >>> import sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> data = np.random.default_rng(0).normal(0, 10, (100, 100))
    >>> m = sunpy.map.Map(data, sunpy.map.make_fitswcs_header(
    ...     data, ref, scale=[5, 5] * u.arcsec / u.pix, unit=u.G))
    >>> h = field_histogram(m)
    >>> h.n, h.std.round(0)
    (10000, <Quantity 10. G>)
    """
    max_radius = check_fraction(max_radius, "max_radius")
    unit = smap.unit if smap.unit is not None else u.one
    values = disk_values(smap, max_radius)
    if values.size == 0:
        raise ValueError(
            f"field_histogram: the map has no finite pixel within {max_radius} solar radii of disk centre"
        )
    return histogram_of_values(values, unit, bins, absolute)


def histogram_of_values(values, unit, bins=None, absolute=False):
    """
    `FieldHistogram` of a 1-D array of finite values (what `field_histogram` does after picking the pixels).

    Parameters
    ----------
    values : `numpy.ndarray`
        1-D, finite, in ``unit``.
    unit : `~astropy.units.Unit`
        Unit of ``values``.
    bins : int or `~astropy.units.Quantity`, optional
        As for `field_histogram`.
    absolute : bool
        Histogram of |value| on log-spaced bins.

    Returns
    -------
    `FieldHistogram`

    Examples
    --------
    >>> import astropy.units as u
    >>> import numpy as np
    >>> h = histogram_of_values(np.array([-7.0, 2.0, 4.0]), u.G)
    >>> h.n, int(h.counts.sum()), h.mean
    (3, 3, <Quantity -0.33333333 G>)
    """
    if absolute:
        values_h = np.abs(values)
        default = np.geomspace(1, 3000, 61)
    else:
        values_h = values
        default = np.linspace(-500, 500, 201)
    if bins is None:
        edges = default
    elif isinstance(bins, u.Quantity):
        edges = np.asarray(bins.to_value(unit), dtype=float)
    elif isinstance(bins, (int, np.integer)) and not isinstance(bins, bool) and bins > 0:
        edges = (np.geomspace(1, 3000, bins + 1) if absolute else np.linspace(-500, 500, bins + 1))
    else:
        raise TypeError(f"bins must be a positive int or a Quantity of bin edges, got {bins!r}")
    if edges.ndim != 1 or edges.size < 2 or np.any(np.diff(edges) <= 0) or not np.all(np.isfinite(edges)):
        raise ValueError("bins: edges must be a finite, strictly increasing 1-D sequence of >= 2 values")
    counts, _ = np.histogram(values_h, bins=edges)
    n = values.size
    density = counts / (n * np.diff(edges))
    p1, p50, p99 = np.percentile(values, [1, 50, 99])
    return FieldHistogram(
        edges=edges * unit,
        counts=counts,
        density=density / unit,
        n=int(n),
        below=int(np.count_nonzero(values_h < edges[0])),
        above=int(np.count_nonzero(values_h > edges[-1])),
        mean=np.mean(values) * unit,
        std=np.std(values) * unit,
        robust_sigma=robust_sigma(values) * unit,
        mean_abs=np.mean(np.abs(values)) * unit,
        percentiles={1: p1 * unit, 50: p50 * unit, 99: p99 * unit},
        absolute=bool(absolute),
    )


#: Percentiles of |B - median| that `tail_percentiles` reports: the strong network and plage pixels.
TAIL_PERCENTILES = (99.0, 99.9)

#: Centre-to-limb rings of `ring_means`, in solar radii.
RING_EDGES = (0.0, 0.2, 0.4, 0.6, 0.8, 0.9, 0.95, 0.98)


def tail_percentiles(values, percentiles=TAIL_PERCENTILES):
    """
    Percentiles of |value - median|: how strong the strongest pixels are, whatever the zero point.

    Parameters
    ----------
    values : array_like or `~astropy.units.Quantity`
        Any shape; NaN and infinities are ignored.
    percentiles : sequence of float
        In [0, 100] (default 99 and 99.9).

    Returns
    -------
    dict
        ``{percentile: value}`` in the unit of ``values``.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.random.default_rng(3).normal(5, 2, 1_000_000)
    >>> round(float(tail_percentiles(x)[99.0]) / 2, 1)    # 2.576 sigma for a Gaussian
    2.6
    """
    unit = getattr(values, "unit", None)
    v = np.asarray(getattr(values, "value", values), dtype=np.float64).ravel()
    v = v[np.isfinite(v)]
    q = np.asarray(percentiles, dtype=float)
    if q.ndim != 1 or not np.all((q >= 0) & (q <= 100)):
        raise ValueError(f"percentiles must be numbers in [0, 100], got {percentiles!r}")
    result = np.percentile(np.abs(v - np.median(v)), q) if v.size else np.full(q.shape, np.nan)
    return {float(p): (r * unit if unit is not None else float(r)) for p, r in zip(q, result)}


def ring_means(smap, edges=RING_EDGES):
    """
    Mean |value|, robust width and pixel-difference noise of a map in rings from disk centre to the limb.

    The three together tell a ring's noise from its signal: the pixel-difference
    noise is the spatially white part of the noise, the robust width (1.4826 ×
    MAD) the core of the ring's histogram, noise and weak signal together, and
    the mean |value| adds the strong pixels.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        A magnetogram (or any map); rings in units of the apparent solar radius.
    edges : sequence of float
        Increasing ring edges in solar radii (default `RING_EDGES`).

    Returns
    -------
    `~astropy.table.QTable`
        Columns ``r_inner``, ``r_outer`` (solar radii), ``mean_abs`` (map
        unit; NaN for an empty ring), ``pixels``, ``robust_sigma`` (1.4826 ×
        MAD of the ring's values about their median) and ``difference_sigma``
        (`pixel_difference_sigma`, robust, of the neighbour pairs whose two
        pixels lie in the ring), both in the map unit.

    Examples
    --------
    >>> import astropy.units as u, numpy as np, sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> m = sunpy.map.Map(-2 * np.ones((64, 64)), sunpy.map.make_fitswcs_header(
    ...     (64, 64), ref, scale=[32, 32] * u.arcsec / u.pix, unit=u.G))
    >>> ring_means(m, (0, 0.5, 1))["mean_abs"]
    <Quantity [2., 2.] G>
    """
    e = np.asarray(edges, dtype=float)
    if e.ndim != 1 or e.size < 2 or np.any(np.diff(e) <= 0) or e[0] < 0:
        raise ValueError(f"edges must be >= 2 increasing radii >= 0 (solar radii), got {edges!r}")
    unit = smap.unit if smap.unit is not None else u.one
    return rings_of_values(map_values(smap), disk_coordinates(smap)[0], e, unit)


def rings_of_values(data, rho, edges, unit):
    """
    `ring_means` of an image whose distances from disk centre are known (what it does after finding them).

    Parameters
    ----------
    data, rho : `numpy.ndarray`
        (ny, nx) values and distances from disk centre (solar radii; NaN where undefined).
    edges : `numpy.ndarray`
        Increasing ring edges, solar radii.
    unit : `~astropy.units.Unit`
        Unit of ``data``.

    Returns
    -------
    `~astropy.table.QTable`
        As for `ring_means`.
    """
    e = np.asarray(edges, dtype=float)
    with np.errstate(invalid="ignore"):
        good = np.isfinite(data) & np.isfinite(rho)
    ring_map = np.full(data.shape, -1, dtype=np.int64)
    ring_map[good] = np.digitize(rho[good], e) - 1
    ring_map[ring_map >= e.size - 1] = -1
    ring = ring_map[good]
    inside = ring >= 0
    pixels = np.bincount(ring[inside], minlength=e.size - 1)
    total = np.bincount(ring[inside], weights=np.abs(data[good][inside]), minlength=e.size - 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(pixels > 0, total / np.maximum(pixels, 1), np.nan)
    # Neighbour differences whose two pixels lie in the same ring (both axes), for each ring's white noise.
    pairs = [(ring_map[1:, :], ring_map[:-1, :], np.diff(data, axis=0)),
             (ring_map[:, 1:], ring_map[:, :-1], np.diff(data, axis=1))]
    width = np.full(e.size - 1, np.nan)
    difference = np.full(e.size - 1, np.nan)
    for i in np.flatnonzero(pixels > 1):
        width[i] = robust_sigma(data[ring_map == i])
        diffs = np.concatenate([d[(a == i) & (b == i)] for a, b, d in pairs])
        if diffs.size:
            difference[i] = robust_sigma(diffs) / np.sqrt(2)
    return QTable({"r_inner": e[:-1], "r_outer": e[1:], "mean_abs": mean * unit, "pixels": pixels,
                   "robust_sigma": width * unit, "difference_sigma": difference * unit})
