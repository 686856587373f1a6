"""
Comparison of simulated GONG magnetograms with real GONG, HMI and MDI observations.

The workflow is::

    sim = load_observation("sim.fits")            # a gongsynth magnetogram
    obs = load_observation("mdi.fits")            # real data, header checked
    report = compare(sim, obs)                    # obs degraded to GONG first
    print(report.summary()); report.figure.savefig("compare.png")
    report.to_table()                             # the numbers as a QTable

or, from files, `compare_files` (behind ``gongsynth compare SIM.fits OBS.fits``).

This module is ``gongsynth.compare``: it also re-exports what a comparison
uses from its neighbours, the file reading and header checks
(`gongsynth.analysis.observations`), the statistics (histograms:
`gongsynth.analysis.statistics`, noise: `gongsynth.analysis.noise`), the limb-darkening curves
(`gongsynth.analysis.limb`), `degrade_to_gong`
(`gongsynth.analysis.degrade`) and `network_clusters`
(`gongsynth.analysis.network_clusters`).
"""
import json
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import astropy.units as u
import numpy as np
import scipy.stats
import sunpy.map
from astropy.table import QTable

from gongsynth.analysis.compare_figure import plot_comparison
from gongsynth.analysis.degrade import AUTO_DEGRADE_FRACTION, degrade_if_finer, degrade_to_gong
from gongsynth.analysis.disk import check_map, disk_values, local_pixel_scale
from gongsynth.analysis.limb import (
    LimbDarkeningComparison,
    LimbDarkeningProfile,
    compare_limb_darkening,
    limb_darkening,
)
from gongsynth.analysis.map_statistics import compare_statistics, quiet_noise
from gongsynth.analysis.network_clusters import network_clusters
from gongsynth.analysis.noise import disk_centre_level, noise_estimate
from gongsynth.analysis.observations import BadHeaderWarning, load_observation
from gongsynth.analysis.power_spectrum import power_spectrum
from gongsynth.analysis.statistics import field_histogram, histogram_of_values
from gongsynth.files import atomic_path, check_writable

__all__ = [
    "BadHeaderWarning",
    "load_observation",
    "AUTO_DEGRADE_FRACTION",
    "degrade_to_gong",
    "field_histogram",
    "noise_estimate",
    "disk_centre_level",
    "limb_darkening",
    "LimbDarkeningProfile",
    "MapSummary",
    "ComparisonReport",
    "summarize_map",
    "compare",
    "compare_files",
    "compare_statistics",
    "power_spectrum",
    "network_clusters",
    "LimbDarkeningComparison",
    "compare_limb_darkening",
]


# ComparisonReport.to_table: keys of MapSummary.numbers() renamed, with their unit,
# and the keys that are in the map's unit (G).
_TABLE_COLUMNS = {"pixel_scale_arcsec": ("pixel_scale", u.arcsec),
                  "noise_box_arcsec": ("noise_box", u.arcsec)}
_IN_MAP_UNIT = ("mean", "mean_abs", "std", "robust_sigma", "p1", "p50", "p99", "noise_sigma", "noise_std",
                "noise_difference", "noise_median_std")


@dataclass(frozen=True)
class MapSummary:
    """
    The numbers `compare` reports for one map.

    Attributes
    ----------
    label : str
        Name in the report and figure.
    description : str
        Observatory, instrument and date of the map.
    pixel_scale : `~astropy.units.Quantity`
        Pixel side at disk centre (arcsec), after any degradation.
    degraded : bool
        Whether `degrade_to_gong` was applied.
    histogram : `~gongsynth.analysis.statistics.FieldHistogram`
        Signed on-disk histogram (mean, std, robust sigma, percentiles).
    abs_histogram : `~gongsynth.analysis.statistics.FieldHistogram`
        Histogram of |B| on log-spaced bins.
    noise : `~gongsynth.analysis.statistics.NoiseEstimate`
        Quiet-box noise near disk centre.
    map : `~sunpy.map.GenericMap`
        The map that was measured (degraded if ``degraded``), in G.
    values : `numpy.ndarray`
        The on-disk pixel values the histograms were made of (G, 1-D).
    """

    label: str
    description: str
    pixel_scale: u.Quantity
    degraded: bool
    histogram: object
    abs_histogram: object
    noise: object
    map: object = field(repr=False, default=None)
    values: np.ndarray = field(repr=False, default=None)

    def numbers(self):
        """
        The summary as a flat dict.

        Returns
        -------
        dict
            Floats (in G and arcsec, as the keys say) and strings.
        """
        h, n = self.histogram, self.noise
        unit = h.mean.unit
        return {
            "label": self.label,
            "description": self.description,
            "degraded": self.degraded,
            "pixel_scale_arcsec": float(self.pixel_scale.to_value(u.arcsec)),
            "unit": unit.to_string(),
            "n_disk_pixels": int(h.n),
            "mean": float(h.mean.value),
            "mean_abs": float(h.mean_abs.value),
            "std": float(h.std.value),
            "robust_sigma": float(h.robust_sigma.value),
            "p1": float(h.percentiles[1].value),
            "p50": float(h.percentiles[50].value),
            "p99": float(h.percentiles[99].value),
            "noise_sigma": float(n.sigma.to_value(unit)),
            "noise_std": float(n.std.to_value(unit)),
            "noise_difference": float(n.difference.to_value(unit)),
            "noise_median_std": float(n.median_std.to_value(unit)),
            "noise_box_arcsec": float(n.box_size.to_value(u.arcsec)),
            "noise_boxes": int(len(n.box_std)),
        }


def _describe_map(smap):
    parts = []
    for part in (smap.observatory, smap.instrument):
        if part and str(part) not in parts:  # gongsynth maps: observatory and instrument alike
            parts.append(str(part))
    parts.append(smap.date.isot[:19] if smap.date is not None else "no date")
    return " ".join(parts)


def summarize_map(smap, label, *, instrument=None, degrade="auto", noise_box=60 * u.arcsec,
                  max_radius=0.98):
    """
    Degrade (if needed) and measure one magnetogram for `compare`.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        A magnetogram in G.
    label : str
        Its name in the report.
    instrument : `~gongsynth.GONGInstrument`, optional
    degrade : {"auto", True, False}
        ``"auto"``: apply `degrade_to_gong` when the pixels are finer than
        ``AUTO_DEGRADE_FRACTION`` × GONG's plate scale (`degrade_if_finer`).
    noise_box : `~astropy.units.Quantity`
        Box side for `noise_estimate`: the 7 x 7 grid within 0.35 R☉ of disk
        centre, or, if none of its boxes lies on the map (a field far from disk
        centre), boxes tiling the map on the disk (``noise.layout == "tiles"``).
    max_radius : float
        Outer radius (solar radii) of the histogram region.

    Returns
    -------
    `MapSummary`

    Examples
    --------
    >>> import numpy as np
    >>> import astropy.units as u
    >>> from gongsynth.products.maps import make_product_map
    >>> from gongsynth.geometry import field_centre
    >>> noise = np.random.default_rng(1).normal(0, 3, (200, 200)) * u.G
    >>> sim = make_product_map(noise, centre=field_centre(0 * u.deg)[0], scale=2.5 * u.arcsec,
    ...                        product="magnetogram")
    >>> summary = summarize_map(sim, "white noise")
    >>> summary.label, round(float(summary.noise.sigma.to_value(u.G)))
    ('white noise', 3)
    """
    check_map(smap, label, finite=True)
    if smap.unit is None or not smap.unit.is_equivalent(u.G):
        raise ValueError(f"{label}: expected a magnetogram in gauss, got unit {smap.unit}")
    smap, degraded = degrade_if_finer(smap, instrument, degrade=degrade)
    scale = local_pixel_scale(smap)
    if smap.unit != u.G:
        smap = sunpy.map.Map(smap.quantity.to_value(u.G), {**smap.meta, "bunit": "G"})
    values = disk_values(smap, max_radius)
    if values.size == 0:
        raise ValueError(f"{label}: no finite pixel within {max_radius} solar radii of disk centre")
    return MapSummary(
        label=label,
        description=_describe_map(smap),
        pixel_scale=scale,
        degraded=degraded,
        histogram=histogram_of_values(values, u.G),
        abs_histogram=histogram_of_values(values, u.G, absolute=True),
        noise=quiet_noise(smap, noise_box),
        map=smap,
        values=values,
    )


def _cdf_distance(h1, h2):
    """Largest difference of the two binned cumulative distributions on the common edges."""
    c1 = (h1.below + np.cumsum(h1.counts)) / h1.n
    c2 = (h2.below + np.cumsum(h2.counts)) / h2.n
    return float(np.max(np.abs(np.concatenate([[h1.below / h1.n - h2.below / h2.n], c1 - c2]))))


@dataclass
class ComparisonReport:
    """
    Result of `compare`: the numbers for both maps, their ratios, and the figure.

    Attributes
    ----------
    sim, obs : `MapSummary`
    ratios : dict
        sim / obs for the noise (quietest-box robust sigma, plain std,
        pixel-difference, median box std), on-disk std, robust sigma and mean |B|.
    ks_statistic, ks_pvalue : float
        Two-sample Kolmogorov-Smirnov test of the on-disk pixel values of B
        (`scipy.stats.ks_2samp`): the largest difference of the two empirical
        cumulative distributions (0 = identical) and the p-value of the
        hypothesis that both maps draw from one distribution.  Neighbouring
        pixels are not independent (PSF, binning), so the p-value is a
        lower bound on the real one: read it as a ranking, not a test.
    cdf_distance : float
        The same distance measured on the binned histograms (the signed
        histograms' common edges, 5 G bins by default; NaN if the edges
        differ): what a comparison of published histograms can give.
    statistics : `~gongsynth.analysis.map_statistics.StatisticsComparison` or None
        KS distances (medians removed too), noise, mean |B|, percentiles of
        |B - median|, mean |B| by centre-to-limb ring and the spatial power
        spectra, as measured and with the noise matched (`compare_statistics`);
        None if the central box of a map is too small for a spectrum.
    figure : `matplotlib.figure.Figure` or None
    """

    sim: MapSummary
    obs: MapSummary
    ratios: dict
    ks_statistic: float
    ks_pvalue: float
    cdf_distance: float
    statistics: object = None
    figure: object = None

    def to_dict(self):
        """
        All numbers as a JSON-serialisable dict.

        Returns
        -------
        dict
            ``{"sim": ..., "obs": ..., "ratios": ..., "ks_statistic": ..., "ks_pvalue": ...,
            "cdf_distance": ...}``.
        """
        return {"sim": self.sim.numbers(), "obs": self.obs.numbers(), "ratios": dict(self.ratios),
                "ks_statistic": self.ks_statistic, "ks_pvalue": self.ks_pvalue,
                "cdf_distance": self.cdf_distance}

    def to_table(self):
        """
        The numbers of both maps as a table, one row per map (``"sim"``, ``"obs"``).

        Returns
        -------
        `~astropy.table.QTable`
            Columns ``map``, ``label``, ``description``, ``degraded``,
            ``pixel_scale`` (arcsec), ``n_disk_pixels``, ``mean``, ``mean_abs``,
            ``std``, ``robust_sigma``, ``p1``, ``p50``, ``p99``, ``noise_sigma``,
            ``noise_std``, ``noise_difference``, ``noise_median_std`` (G),
            ``noise_box`` (arcsec) and ``noise_boxes``; ``meta`` holds
            ``ratios``, ``ks_statistic``, ``ks_pvalue`` and ``cdf_distance``.
        """
        rows = [self.sim.numbers(), self.obs.numbers()]
        unit = u.Unit(rows[0].pop("unit"))
        rows[1].pop("unit")
        columns = {"map": ["sim", "obs"]}
        for key in rows[0]:
            name, column_unit = _TABLE_COLUMNS.get(key, (key, unit if key in _IN_MAP_UNIT else None))
            values = [row[key] for row in rows]
            columns[name] = values * column_unit if column_unit is not None else values
        meta = {"ratios": dict(self.ratios), "ks_statistic": self.ks_statistic,
                "ks_pvalue": self.ks_pvalue, "cdf_distance": self.cdf_distance}
        return QTable(columns, meta=meta)

    def to_json(self, **kwargs):
        """
        `to_dict` as a JSON string.

        Parameters
        ----------
        **kwargs
            Passed to `json.dumps` (e.g. ``indent=2``).

        Returns
        -------
        str
        """
        return json.dumps(self.to_dict(), **kwargs)

    def __str__(self):
        return self.summary()

    def summary(self, *, figure=False):
        """
        A plain-text table of the main numbers.

        Parameters
        ----------
        figure : bool
            Short form for the figure panel (columns "sim" and "obs", no map descriptions).

        Returns
        -------
        str
        """
        s, o = self.sim.numbers(), self.obs.numbers()
        rows = [] if figure else [("map", s["description"], o["description"])]
        rows += [
            ("pixel scale [arcsec]", f"{s['pixel_scale_arcsec']:.3f}", f"{o['pixel_scale_arcsec']:.3f}"),
            ("degraded to GONG", str(s["degraded"]), str(o["degraded"])),
            ("disk pixels", str(s["n_disk_pixels"]), str(o["n_disk_pixels"])),
        ]
        for key, name in (("noise_sigma", "noise: robust sigma [G]"), ("noise_std", "noise: std [G]"),
                          ("noise_difference", "noise: pixel difference [G]"),
                          ("noise_median_std", "noise: median box std [G]"),
                          ("mean", "disk mean [G]"), ("mean_abs", "disk mean |B| [G]"),
                          ("std", "disk std [G]"), ("robust_sigma", "disk robust sigma [G]"),
                          ("p1", "1st percentile [G]"), ("p99", "99th percentile [G]")):
            rows.append((name, f"{s[key]:.2f}", f"{o[key]:.2f}"))
        width = max(len(r[0]) for r in rows)
        names = ("sim", "obs") if figure else (self.sim.label, self.obs.label)
        col = max(len(names[0]), len(names[1]), *(len(r[1]) for r in rows))
        lines = [f"{'':{width}}  {names[0]:>{col}}  {names[1]}"]
        lines += [f"{a:{width}}  {b:>{col}}  {c}" for a, b, c in rows]
        lines.append(f"{'KS distance of B':{width}}  {self.ks_statistic:>{col}.3f}")
        lines.append(f"{'KS p-value':{width}}  {self.ks_pvalue:>{col}.3g}")
        lines.append(f"{'noise ratio sim/obs':{width}}  {self.ratios['noise_sigma']:>{col}.3f}")
        if not figure and self.statistics is not None:
            lines += ["", "statistics (compare_statistics; 'matched': white noise added to the quieter map)",
                      self.statistics.summary()]
        return "\n".join(lines)


def compare(sim_map, obs_map, *, instrument=None, degrade="auto", labels=("simulated", "observed"),
            noise_box=60 * u.arcsec, plot=True, fig=None, statistics=True, seed=0):
    """
    Compare a simulated GONG magnetogram with an observed one: numbers and a figure.

    Both maps are measured the same way after any map finer than
    ``AUTO_DEGRADE_FRACTION`` × GONG's 2.5″ pixels has been degraded to GONG
    (`degrade_to_gong`): on-disk histograms (signed and |B|), summary numbers
    (mean, mean |B|, std, robust sigma, percentiles), quiet-box noise near
    disk centre (robust sigma, std, pixel difference), their ratios and the
    two-sample Kolmogorov-Smirnov statistic and p-value of the two
    distributions of B (`scipy.stats.ks_2samp`); and, with ``statistics``,
    the table of `~gongsynth.analysis.map_statistics.compare_statistics`.

    Parameters
    ----------
    sim_map, obs_map : `~sunpy.map.GenericMap`
        Magnetograms in G (e.g. from `load_observation`).
    instrument : `~gongsynth.GONGInstrument`, optional
    degrade : {"auto", True, False}
        Applied to both maps (see `summarize_map`).
    labels : (str, str)
        Names of the two maps in the report and figure.
    noise_box : `~astropy.units.Quantity`
        Box side for the noise estimate (default 60″).
    plot : bool
        Draw the side-by-side figure.
    fig : `matplotlib.figure.Figure`, optional
        Figure to draw into (e.g. ``plt.figure(figsize=(17, 8))`` to show it
        with pyplot); default a new stand-alone Figure.
    statistics : bool
        Also measure `~gongsynth.analysis.map_statistics.compare_statistics`
        (KS distances with medians removed, percentiles of |B - median|, mean
        |B| by ring, spatial power spectra; each also with the noise matched):
        ``report.statistics``, and the spectra and rings in the figure.
    seed : int
        Seed of the noise that matches the two maps' noise (statistics only).

    Returns
    -------
    `ComparisonReport`

    Examples
    --------
    >>> import numpy as np, astropy.units as u, sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> rng = np.random.default_rng(0)
    >>> hdr = sunpy.map.make_fitswcs_header((200, 200), ref, scale=[2.5, 2.5] * u.arcsec / u.pix,
    ...                                     unit=u.G)
    >>> a = sunpy.map.Map(rng.normal(0, 3, (200, 200)), hdr)
    >>> b = sunpy.map.Map(rng.normal(0, 6, (200, 200)), hdr)
    >>> report = compare(a, b, plot=False, statistics=False)
    >>> round(report.ratios["noise_median_std"], 1)
    0.5
    >>> table = report.to_table()
    >>> [str(name) for name in table["map"]], table["noise_sigma"].unit
    (['sim', 'obs'], Unit("G"))
    """
    if len(labels) != 2:
        raise ValueError(f"labels must be two strings, got {labels!r}")
    sim = summarize_map(sim_map, str(labels[0]), instrument=instrument, degrade=degrade,
                        noise_box=noise_box)
    obs = summarize_map(obs_map, str(labels[1]), instrument=instrument, degrade=degrade,
                        noise_box=noise_box)
    s, o = sim.numbers(), obs.numbers()
    ratios = {}
    for key in ("noise_sigma", "noise_std", "noise_difference", "noise_median_std", "std",
                "robust_sigma", "mean_abs"):
        ratios[key] = s[key] / o[key] if o[key] != 0 else float("nan")
    same_edges = (sim.histogram.edges.shape == obs.histogram.edges.shape
                  and np.allclose(sim.histogram.edges.to_value(u.G), obs.histogram.edges.to_value(u.G)))
    distance = _cdf_distance(sim.histogram, obs.histogram) if same_edges else float("nan")
    ks = scipy.stats.ks_2samp(sim.values, obs.values)
    stats = None
    if statistics:
        try:
            stats = compare_statistics(sim.map, obs.map, seed=seed)
        except ValueError as error:   # e.g. a field too small for the spectrum's central box
            warnings.warn(f"compare: no statistics table ({error})", stacklevel=2)
    report = ComparisonReport(sim=sim, obs=obs, ratios=ratios, ks_statistic=float(ks.statistic),
                              ks_pvalue=float(ks.pvalue), cdf_distance=distance, statistics=stats)
    if plot:
        if fig is None:
            from matplotlib.figure import Figure

            fig = Figure(figsize=(13, 8) if stats is None else (17, 8))
        report.figure = plot_comparison(report, fig)
    return report


def compare_files(sim_path, obs_path, *, out=None, overwrite=False, instrument=None, degrade="auto",
                  statistics=True):
    """
    Compare a simulated and an observed magnetogram FITS file (``gongsynth compare``).

    Parameters
    ----------
    sim_path, obs_path : str or `pathlib.Path`
        FITS files read with `load_observation` (``kind="magnetogram"``).
    out : str or `pathlib.Path`, optional
        Where to save the side-by-side figure (format from the suffix, e.g.
        ``.png`` or ``.pdf``; PNG if there is none); written atomically.  An
        unknown suffix is refused before any work.  No figure is drawn if None.
    overwrite : bool
        Replace an existing ``out``.
    instrument : `~gongsynth.GONGInstrument`, optional
    degrade : {"auto", True, False}
        See `compare`.
    statistics : bool
        See `compare`.

    Returns
    -------
    `ComparisonReport`
        ``report.summary()`` is what the command line prints.

    Raises
    ------
    FileExistsError
        If ``out`` exists and ``overwrite`` is False.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> import numpy as np
    >>> import astropy.units as u
    >>> from gongsynth.products.maps import make_product_map
    >>> from gongsynth.geometry import field_centre
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> rng = np.random.default_rng(2)
    >>> for name, sigma in (("a.fits", 3), ("b.fits", 6)):
    ...     m = make_product_map(rng.normal(0, sigma, (200, 200)) * u.G,
    ...                          centre=field_centre(0 * u.deg)[0], scale=2.5 * u.arcsec,
    ...                          product="magnetogram")
    ...     m.save(folder / name)
    >>> report = compare_files(folder / "a.fits", folder / "b.fits")
    >>> round(report.ratios["noise_sigma"], 1)   # simulated noise is half the observed
    0.5
    """
    if out is not None:
        out = Path(out)
        if out.is_dir():
            raise IsADirectoryError(f"compare_files: out {out} is a folder; give a file name such as "
                                    f"{out / 'compare.png'}")
        check_writable([out], overwrite)  # before the work, not after it
        if not out.parent.is_dir():
            raise FileNotFoundError(f"compare_files: the folder of out does not exist: {out.parent}")
        image_format = _figure_format(out)
    sim = load_observation(sim_path, kind="magnetogram")
    obs = load_observation(obs_path, kind="magnetogram")
    labels = (f"simulated ({Path(sim_path).name})", f"observed ({Path(obs_path).name})")
    report = compare(sim, obs, instrument=instrument, degrade=degrade, labels=labels,
                     plot=out is not None, statistics=statistics)
    if out is not None:
        with atomic_path(out, overwrite=overwrite) as tmp:
            report.figure.savefig(tmp, dpi=110, format=image_format)
    return report


def _figure_format(out):
    """The image format of ``out`` from its suffix (PNG without one); refuse one matplotlib cannot write."""
    from matplotlib.backend_bases import FigureCanvasBase

    suffix = out.suffix.lower().lstrip(".")
    if not suffix:
        return "png"
    supported = FigureCanvasBase.get_supported_filetypes()
    if suffix not in supported:
        raise ValueError(f"compare: cannot write a figure as .{suffix} ({out}); use one of "
                         f"{', '.join('.' + k for k in sorted(supported))}, or no suffix for PNG")
    return suffix
