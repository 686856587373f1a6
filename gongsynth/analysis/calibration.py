"""
Calibration curves: what GONG measures against what was there.

For every simulated pixel the true line-of-sight flux density is known (the
input field averaged over the same pixel, optionally through the same PSF;
design §3.13).  `calibration_curve` bins measured against true, fits a robust
slope through the origin separately for strong-field and quiet pixels, and
bootstraps its uncertainty; `calibration_vs_latitude` does it for a sweep.

The *slope* is measured / true (≈ 0.99 for a perfect GONG: the line's
effective phase slope, design §3.6); the *correction factor* is its inverse,
the number a modeller would multiply GONG magnetograms by.
"""
from dataclasses import dataclass

import astropy.units as u
import numpy as np
from astropy.table import QTable

from gongsynth.seeding import stage_generator

__all__ = ["CalibrationFit", "CalibrationCurve", "robust_slope", "calibration_curve",
           "calibration_vs_latitude", "latitude_table",
           "gauss_values"]


def gauss_values(data, name):
    """
    Plain float array in G from a Map, Quantity (convertible to G) or array (taken as G).

    Parameters
    ----------
    data : `~sunpy.map.GenericMap`, `~astropy.units.Quantity` or array_like
    name : str
        Named in the error for a unit that is not a flux density.

    Returns
    -------
    `numpy.ndarray`
    """
    if hasattr(data, "data") and hasattr(data, "meta"):  # a sunpy Map
        data = u.Quantity(data.data, data.unit) if data.unit is not None else data.data
    if isinstance(data, u.Quantity):
        if not data.unit.is_equivalent(u.G):
            raise u.UnitsError(f"{name} must be in units of magnetic flux density (G), got {data.unit}")
        data = data.to_value(u.G)
    return np.asarray(data, dtype=float)


def robust_slope(truth, measured, *, iterations=20, tuning=4.685):
    """
    Robust slope through the origin of ``measured = slope × truth``.

    Iteratively reweighted least squares with Tukey's biweight on residuals
    scaled by their median absolute deviation, started from the median ratio
    of the stronger half of the pixels.  Outliers (wrapped pixels, say) get zero weight.

    Parameters
    ----------
    truth, measured : `numpy.ndarray`
        Same shape, any units (the slope is their ratio).
    iterations : int
        IRLS iterations.
    tuning : float
        Biweight tuning constant in units of the robust σ (4.685: 95 %
        efficiency for Gaussian residuals).

    Returns
    -------
    slope : float
    scatter : float
        Robust σ of the residuals (1.4826 × MAD), units of ``measured``.

    Examples
    --------
    >>> t = np.linspace(-100, 100, 201)
    >>> m = 0.9 * t
    >>> m[::20] = 1e4  # outliers
    >>> s, _ = robust_slope(t, m)
    >>> round(s, 6)
    0.9
    """
    t = np.asarray(truth, float).ravel()
    m = np.asarray(measured, float).ravel()
    if t.size < 2 or not np.any(t):
        raise ValueError("need at least two pixels with non-zero truth to fit a slope")
    # Start from the median ratio of the stronger half: least squares is ruined by outliers.
    strong = np.abs(t) >= np.median(np.abs(t))
    slope = np.median(m[strong & (t != 0)] / t[strong & (t != 0)])
    scale = 0.0
    for _ in range(iterations):
        resid = m - slope * t
        scale = 1.4826 * np.median(np.abs(resid - np.median(resid)))
        if scale == 0:
            break
        z = resid / (tuning * scale)
        weights = np.where(np.abs(z) < 1, (1 - z**2) ** 2, 0.0)
        new = np.sum(weights * t * m) / np.sum(weights * t * t)
        if abs(new - slope) < 1e-12 * max(1.0, abs(slope)):
            slope = new
            break
        slope = new
    return float(slope), float(scale)


@dataclass(frozen=True)
class CalibrationFit:
    """
    A robust fit of measured against true flux density over a set of pixels.

    Attributes
    ----------
    slope : float
        Measured / true.
    slope_error : float
        Bootstrap standard error of the slope.
    scatter : `~astropy.units.Quantity`
        Robust σ of measured - slope × true, in G.
    n_pixels : int
    """

    slope: float
    slope_error: float
    scatter: u.Quantity
    n_pixels: int

    @property
    def correction_factor(self):
        """Multiply measured values by this to recover the truth (1 / slope)."""
        return 1 / self.slope


@dataclass(frozen=True)
class CalibrationCurve:
    """
    Binned measured-vs-true statistics with robust fits.

    Attributes
    ----------
    bin_centres : `~astropy.units.Quantity`
        True flux density at the bin centres (G).
    median, p16, p84 : `~astropy.units.Quantity`
        Median and 16th / 84th percentiles of the measured values in each bin (G).
    counts : `numpy.ndarray`
        Pixels per bin.
    all_pixels, strong, quiet : `CalibrationFit`
        Fits over all pixels, over |true| ≥ threshold, and below it.
    threshold : `~astropy.units.Quantity`
        Strong/quiet boundary (G).
    truth, measured : `numpy.ndarray`
        The pixels used (G), for plotting.
    label : str
    """

    bin_centres: u.Quantity
    median: u.Quantity
    p16: u.Quantity
    p84: u.Quantity
    counts: np.ndarray
    all_pixels: CalibrationFit
    strong: CalibrationFit
    quiet: CalibrationFit
    threshold: u.Quantity
    truth: np.ndarray
    measured: np.ndarray
    label: str = ""

    def to_table(self):
        """
        The binned curve as a table, the fits in its ``meta``.

        Returns
        -------
        `~astropy.table.QTable`
            Columns ``true`` (bin centre), ``median``, ``p16``, ``p84`` (G) and
            ``n_pixels``; ``meta`` holds ``label``, ``threshold`` and, for
            ``all_pixels``, ``strong`` and ``quiet``, the slope, its error, the
            scatter and the correction factor.
        """
        meta = {"label": self.label, "threshold": self.threshold}
        for name in ("all_pixels", "strong", "quiet"):
            fit = getattr(self, name)
            meta[name] = {"slope": fit.slope, "slope_error": fit.slope_error, "scatter": fit.scatter,
                          "n_pixels": fit.n_pixels, "correction_factor": fit.correction_factor}
        return QTable({"true": self.bin_centres, "median": self.median, "p16": self.p16,
                       "p84": self.p84, "n_pixels": np.asarray(self.counts)}, meta=meta)

    def plot(self, ax=None, *, max_points=20000):
        """
        Scatter of measured vs true, binned medians with 16-84 % bands, and the fits.

        Parameters
        ----------
        ax : `matplotlib.axes.Axes`, optional
        max_points : int
            Subsample the scatter to at most this many pixels.

        Returns
        -------
        `matplotlib.axes.Axes`
        """
        import matplotlib.pyplot as plt

        ax = plt.gca() if ax is None else ax
        step = max(1, self.truth.size // max_points)
        ax.plot(self.truth[::step], self.measured[::step], ",", color="0.6", alpha=0.5,
                rasterized=True)
        ok = self.counts > 0
        x = self.bin_centres.to_value(u.G)[ok]
        ax.fill_between(x, self.p16.to_value(u.G)[ok], self.p84.to_value(u.G)[ok], alpha=0.3,
                        color="C0", label="16-84 %")
        ax.plot(x, self.median.to_value(u.G)[ok], "o-", ms=3, color="C0", label="median")
        lim = np.max(np.abs(x)) if x.size else 1
        line = np.array([-lim, lim])
        ax.plot(line, line, "k--", lw=1, label="measured = true")
        ax.plot(line, self.strong.slope * line, "C3", lw=1,
                label=f"strong fit: {self.strong.slope:.3f} ± {self.strong.slope_error:.3f}")
        ax.set_xlabel("true B_LOS [G]")
        ax.set_ylabel("measured B_LOS [G]")
        ax.set_title(self.label or "calibration curve")
        ax.legend(loc="upper left", fontsize="small")
        return ax


def _fit(truth, measured, rng, n_boot):
    if truth.size < 2 or not np.any(truth):
        return CalibrationFit(np.nan, np.nan, np.nan * u.G, int(truth.size))
    slope, scatter = robust_slope(truth, measured)
    boots = []
    for _ in range(n_boot):
        pick = rng.integers(0, truth.size, truth.size)
        if np.any(truth[pick]):
            boots.append(robust_slope(truth[pick], measured[pick])[0])
    error = float(np.std(boots, ddof=1)) if len(boots) > 1 else np.nan
    return CalibrationFit(slope, error, scatter * u.G, int(truth.size))


@u.quantity_input
def calibration_curve(measured, truth=None, *, mask=None, threshold: u.G = 100 * u.G,
                      bins=41, limit: u.G = None, n_boot=100, seed=0, label="", psf=True):
    """
    Measured vs true flux density, binned and fitted.

    Parameters
    ----------
    measured : `~gongsynth.pipeline.SimulationResult`, `~sunpy.map.GenericMap`, Quantity or array
        A simulation result (its magnetogram and truth are used, restricted
        to the GONG-resolution part of the field), or a measured map / array in G.
    truth : map, Quantity or array, optional
        True B_LOS (G) on the same pixels; required unless ``measured`` is a result.
    mask : array of bool, optional
        Pixels to use (True = use).  Non-finite pixels are always dropped.
    threshold : `~astropy.units.Quantity`
        |true B| separating strong-field from quiet pixels (G).
    bins : int
        Number of bins over ±``limit``.
    limit : `~astropy.units.Quantity`, optional
        Half range of the bins (G); default the 99.9th percentile of |true|.
    n_boot : int
        Bootstrap resamples for the slope errors.
    seed : int
        Seed of the bootstrap.
    label : str
        Title for plots.
    psf : bool
        When ``measured`` is a result: compare with the truth seen through the
        instrument PSF (``result.truth_psf``, the default: what a perfect GONG
        would measure) or only averaged over the pixel (``result.truth``).

    Returns
    -------
    `CalibrationCurve`

    Examples
    --------
    >>> import numpy as np
    >>> import astropy.units as u
    >>> rng = np.random.default_rng(1)
    >>> true = rng.normal(0, 300, 5000) * u.G
    >>> curve = calibration_curve(0.8 * true + rng.normal(0, 5, 5000) * u.G, true, n_boot=20)
    >>> round(curve.strong.slope, 2)
    0.8
    """
    if truth is None:
        if not hasattr(measured, "truth"):
            raise TypeError("truth is required unless measured is a SimulationResult")
        result = measured
        measured = result.magnetogram
        truth = result.truth_psf if psf else result.truth
        if truth is None:
            raise ValueError("this result has no ground truth (its input cube had no blos)")
        gong_resolution = getattr(result, "resolution_map", None)
        if gong_resolution is not None:
            select = np.asarray(gong_resolution) == 1
            mask = select if mask is None else (np.asarray(mask) & select)
        label = label or f"latitude {result.config.latitude:.0f}"
    m = gauss_values(measured, "measured")
    t = gauss_values(truth, "truth")
    if m.shape != t.shape:
        raise ValueError(f"measured and truth must have the same shape, got {m.shape} and {t.shape}")
    keep = np.isfinite(m) & np.isfinite(t)
    if mask is not None:
        mask = np.asarray(mask, dtype=bool)
        if mask.shape != m.shape:
            raise ValueError(f"mask must have shape {m.shape}, got {mask.shape}")
        keep &= mask
    if not np.any(keep):
        raise ValueError("no finite pixels to compare (check mask and NaNs)")
    m, t = m[keep], t[keep]
    thr = threshold.to_value(u.G)
    lim = np.percentile(np.abs(t), 99.9) if limit is None else limit.to_value(u.G)
    lim = lim if lim > 0 else 1.0
    edges = np.linspace(-lim, lim, bins + 1)
    which = np.digitize(t, edges) - 1
    med, lo, hi, counts = (np.full(bins, np.nan) for _ in range(4))
    for b in range(bins):
        sel = m[which == b]
        counts[b] = sel.size
        if sel.size:
            lo[b], med[b], hi[b] = np.percentile(sel, [16, 50, 84])
    rng = stage_generator(seed, "calibration-bootstrap")
    strong = np.abs(t) >= thr
    return CalibrationCurve(
        bin_centres=(edges[:-1] + edges[1:]) / 2 * u.G,
        median=med * u.G, p16=lo * u.G, p84=hi * u.G,
        counts=counts.astype(int),
        all_pixels=_fit(t, m, rng, n_boot),
        strong=_fit(t[strong], m[strong], rng, n_boot),
        quiet=_fit(t[~strong], m[~strong], rng, n_boot),
        threshold=threshold.to(u.G),
        truth=t, measured=m, label=label,
    )


def calibration_vs_latitude(results, **kwargs):
    """
    Calibration curves of a latitude sweep (e.g. from `gongsynth.simulate_many`).

    Parameters
    ----------
    results : iterable of `~gongsynth.pipeline.SimulationResult`
    **kwargs
        Passed to `calibration_curve`.

    Returns
    -------
    latitude : `~astropy.units.Quantity`
        The latitude of each result (deg).
    curves : list of `CalibrationCurve`

    See Also
    --------
    latitude_table : the fits of these curves as one table.

    Examples
    --------
    >>> import astropy.units as u
    >>> from gongsynth import simulate_many
    >>> runs = simulate_many(latitudes=[0, 60] * u.deg, seed=1, detector_shape=16,
    ...                      duration=1 * u.min, resolutions=(1,), photosphere_shape=(64, 64),
    ...                      photosphere_pixel_size=1536 * u.km, sun="milne-eddington",
    ...                      progress=False)
    >>> latitude, curves = calibration_vs_latitude(runs, threshold=50 * u.G, n_boot=5)
    >>> latitude
    <Quantity [ 0., 60.] deg>
    """
    results = list(results)
    curves = [calibration_curve(r, **kwargs) for r in results]
    latitude = u.Quantity([r.config.latitude for r in results]).to(u.deg)
    return latitude, curves


def latitude_table(latitude, curves):
    """
    The calibration of a latitude sweep as one table: a row per latitude.

    Parameters
    ----------
    latitude : `~astropy.units.Quantity`
        Latitude of each curve (as returned by `calibration_vs_latitude`).
    curves : sequence of `CalibrationCurve`

    Returns
    -------
    `~astropy.table.QTable`
        ``latitude`` (deg) and, for each fit (``all``, ``strong``, ``quiet``):
        ``slope_<fit>`` (measured / true), ``slope_error_<fit>``,
        ``correction_<fit>`` (true / measured) and ``n_pixels_<fit>``.

    Examples
    --------
    >>> import astropy.units as u
    >>> t = np.linspace(-300, 300, 2001)
    >>> curves = [calibration_curve(f * t * u.G, t * u.G, n_boot=5) for f in (0.5, 0.8)]
    >>> table = latitude_table([0, 60] * u.deg, curves)
    >>> [round(float(c), 3) for c in table["correction_all"]]
    [2.0, 1.25]
    """
    latitude = u.Quantity(latitude, u.deg)
    if latitude.shape != (len(curves),):
        raise ValueError(f"latitude must have one entry per curve ({len(curves)}), "
                         f"got shape {latitude.shape}")
    columns = {"latitude": latitude}
    for fit_name, column in (("all_pixels", "all"), ("strong", "strong"), ("quiet", "quiet")):
        fits = [getattr(c, fit_name) for c in curves]
        columns[f"slope_{column}"] = [f.slope for f in fits]
        columns[f"slope_error_{column}"] = [f.slope_error for f in fits]
        columns[f"correction_{column}"] = [f.correction_factor for f in fits]
        columns[f"n_pixels_{column}"] = [f.n_pixels for f in fits]
    threshold = curves[0].threshold if curves else None
    return QTable(columns, meta={"threshold": threshold})
