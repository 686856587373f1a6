r"""
The calibration estimator of papers II and III: truth as a function of the measured field.

`gongsynth.analysis.calibration.calibration_curve` fits measured = s × truth;
the authors instead ask what the Sun holds *given* what GONG measured, the
question a user of real magnetograms has.  Their estimator (the
``gong_curve_fluxcons_binfit`` routine of the authors' IDL code, re-derived
here):

1. **Symmetrise** the pixels in sign: every (measured, truth) pair enters
   also as (−measured, −truth), so the curve is odd and passes through 0.
2. **Bin the measured values**: ``n_bins`` bins whose two outer bins run out
   to the extreme values and hold at least ``min_outer`` pixels; the inner
   bins are equal in width and symmetric about 0.
3. **Flux-conserving piecewise-linear fit**: the curve g is linear between
   nodes at the bin centres (and extrapolated linearly beyond the outer
   ones); its node values are the solution of one linear equation per bin,
   Σ_{pixels in bin} g(measured) = Σ_{pixels in bin} truth: the curve puts
   back in every bin the true flux that the bin holds.
4. The **weak-flux factor** is the slope dg/dmeasured at measured = 0 of the
   quiet-Sun curve: true flux per measured flux for weak fields.

Regions (paper III): the *quiet Sun* is |B_measured| < 400 G × cos θ outside
the sunspot; the *sunspot* region is where the pseudo-continuum, dilated by
7 × 7 pixels, is darker than 0.92 × the quiet-Sun median (the authors'
threshold and dilation).  Only the native-resolution (1×) part of a tiled
field is used.  The number of bins follows the authors per viewing angle
(`PAPER_BINS`).

Every instrument: what the authors set in GONG pixels is kept as the angle on
the Sun it spans (`PIXEL_SCALE_OF_THE_PAPER`, 2.5″), so that two instruments
looking at the same Sun select the same regions: the sunspot mask is dilated
by 17.5″ (7 GONG pixels, 35 HMI pixels of 0.504″) and the bootstrap blocks are
10″ wide (4 GONG pixels, 20 HMI pixels).  The sunspot's continuum threshold
is applied to the continuum seen at GONG's resolution (`gong_resolution`,
6.5″), since at HMI's the intergranular lanes fall below it.  ``min_outer``
and the numbers of bins count pixels and bins, not angles, and stay the
authors'.

Pooling: the authors fitted one magnetogram per angle, so their 400 pixels
per outer bin are a count *per map*.  When several runs are pooled into one
fit, ``min_outer`` is applied per run (the outer bins hold ``min_outer`` ×
the number of runs): the inner edge then sits at the same quantile of |B|
as in each run's own fit, and the pooled factor estimates the same slope as
the per-run factors with less scatter.  A fixed count would move the inner
edge outward as runs are added and, the curve not being a straight line,
change the slope at zero: on the 1024² GONG runs at 0° with seeds 1–4 it
gave 1.227 against per-seed factors 1.236–1.355 (mean 1.291); per run it
gives 1.284 (the Sun before its supergranular network; with it, 1.222
against a mean of 1.241).

Because the curve is E[truth | measured], noise in the measured values pulls
it towards zero (regression dilution): that is part of what a calibration of
noisy maps must do, and the reason the factor depends on the noise of the
maps it was derived from.
"""
import math
from dataclasses import dataclass

import astropy.units as u
import numpy as np
import scipy.ndimage

from gongsynth.analysis.calibration import gauss_values
from gongsynth.seeding import stage_generator

__all__ = ["PAPER_BINS", "PIXEL_SCALE_OF_THE_PAPER", "QUIET_LIMIT", "FluxConservingCurve", "WeakFluxFactor",
           "flux_conserving_fit", "gong_resolution", "paper_pixels", "paper_bins", "paper_regions",
           "region_pixels", "weak_flux_factor", "weak_flux_factor_difference"]

#: The authors' numbers of bins per viewing angle (deg): (quiet Sun, sunspot).
PAPER_BINS = {0: (35, 21), 25: (21, 9), 45: (15, 7), 60: (9, 7), 70: (7, 7), 75: (7, 7)}

#: Quiet-Sun pixels have |B_measured| below this times cos θ.
QUIET_LIMIT = 400 * u.G

#: GONG's pixel, in which the authors set the sunspot mask's dilation and this module its bootstrap blocks.
PIXEL_SCALE_OF_THE_PAPER = 2.5 * u.arcsec

_SPOT_DARKNESS = 0.92  # sunspot: continuum below this fraction of the quiet-Sun median
_SPOT_DILATION = 7     # GONG pixels: the sunspot mask is dilated by this square
_BLOCK = 4             # GONG pixels (10″, about GONG's PSF width): the bootstrap blocks' side


@dataclass(frozen=True)
class FluxConservingCurve:
    """
    A piecewise-linear curve truth = g(measured), linear beyond its outer nodes.

    Attributes
    ----------
    nodes : `~astropy.units.Quantity`
        Measured values at the bin centres (G), increasing.
    values : `~astropy.units.Quantity`
        g at the nodes (G).
    edges : `~astropy.units.Quantity`
        The bin edges (G), ``len(nodes) + 1``.
    counts : `numpy.ndarray`
        Pixels per bin (after symmetrising).
    """

    nodes: u.Quantity
    values: u.Quantity
    edges: u.Quantity
    counts: np.ndarray

    def __call__(self, measured):
        """
        g(measured), interpolated linearly between the nodes and extrapolated beyond them.

        Parameters
        ----------
        measured : `~astropy.units.Quantity` or array_like
            In G (a plain array is taken as G).

        Returns
        -------
        `~astropy.units.Quantity`
            In G.
        """
        x = gauss_values(measured, "measured")
        nodes, values = self.nodes.to_value(u.G), self.values.to_value(u.G)
        left, weight = _segments(x, nodes)
        return (values[left] * (1 - weight) + values[left + 1] * weight) * u.G

    def bin_index(self, measured):
        """
        The bin of each measured value (bins taken by |value| and mirrored, so ±x fall in mirror bins).

        Parameters
        ----------
        measured : `~astropy.units.Quantity` or array_like
            In G (a plain array is taken as G).

        Returns
        -------
        `numpy.ndarray` of int
        """
        return _bin_index(gauss_values(measured, "measured"), self.edges.to_value(u.G))

    @property
    def slope_at_zero(self):
        """dg/dmeasured at 0 (dimensionless): (g(δ) − g(−δ)) / 2δ, δ the node spacing there."""
        nodes = self.nodes.to_value(u.G)
        inner = np.diff(nodes)[1:-1] if nodes.size > 3 else np.diff(nodes)
        delta = float(np.min(inner)) if inner.size else 1.0
        pair = self(np.array([-delta, delta])).to_value(u.G)
        return float((pair[1] - pair[0]) / (2 * delta))


@dataclass(frozen=True)
class WeakFluxFactor:
    """
    True flux per measured flux for weak fields, with its uncertainty.

    Attributes
    ----------
    factor : float
        Slope of the quiet-Sun (or sunspot) curve at measured = 0.
    uncertainty : float
        Standard deviation of the factor over a block bootstrap (resampling
        blocks of pixels as large as the PSF, since neighbouring pixels are not
        independent).
    curve : `FluxConservingCurve`
        The fit to all the region's pixels.
    region : str
        ``"quiet"`` or ``"sunspot"``.
    n_pixels : int
        Pixels in the region (before symmetrising).
    latitude : `~astropy.units.Quantity` or None
        Viewing latitude of the simulation, when known.
    """

    factor: float
    uncertainty: float
    curve: FluxConservingCurve
    region: str
    n_pixels: int
    latitude: u.Quantity = None


def _segments(x, nodes):
    """For each x: its segment's left node (outer segments extended) and the right node's weight."""
    left = np.clip(np.searchsorted(nodes, x, side="right") - 1, 0, nodes.size - 2)
    weight = (x - nodes[left]) / (nodes[left + 1] - nodes[left])
    return left, weight


def _bin_index(x, edges):
    """Bin of each x for symmetric ``edges``: by |x|, mirrored for x < 0 (exactly odd on the edges too)."""
    n_bins = edges.size - 1
    mirror = np.clip(np.searchsorted(edges, np.abs(x), side="right") - 1, 0, n_bins - 1)
    return np.where(x < 0, n_bins - 1 - mirror, mirror)


def _bin_edges(x, n_bins, min_outer):
    """The authors' bins: outer ones reach the extremes (>= min_outer pixels each), inner ones equal."""
    ordered = np.sort(x)
    r = min(abs(ordered[min_outer - 1]), abs(ordered[-min_outer]))
    if not r > 0:
        raise ValueError(f"too few pixels away from zero for {n_bins} bins with {min_outer} "
                         "in each outer bin")
    span = max(abs(ordered[0]), abs(ordered[-1]))
    inner = np.linspace(-r, r, n_bins - 1)
    inner = (inner - inner[::-1]) / 2  # exactly odd, not merely to rounding
    outer = span * (1 + 1e-6)
    return np.concatenate([[-outer], inner, [outer]])


def flux_conserving_fit(measured, truth, n_bins, *, min_outer=400, symmetric=True):
    """
    Fit truth = g(measured) so that each bin of the measured values keeps its true flux.

    Parameters
    ----------
    measured, truth : `~astropy.units.Quantity` or array_like
        Pixel values in G (plain arrays taken as G), same size; non-finite
        pairs are dropped.
    n_bins : int
        Number of bins (and nodes), ≥ 3; odd puts a node at 0.
    min_outer : int
        Fewest pixels in each outer bin (the authors use 400).
    symmetric : bool
        Symmetrise in sign first (the authors' choice; the curve is then odd).

    Returns
    -------
    `FluxConservingCurve`

    Examples
    --------
    >>> import numpy as np
    >>> t = np.random.default_rng(0).normal(0, 100, 20000)
    >>> curve = flux_conserving_fit(t / 2, t, 15)        # GONG measures half the truth
    >>> round(curve.slope_at_zero, 3)
    2.0
    """
    m = gauss_values(measured, "measured").ravel()
    t = gauss_values(truth, "truth").ravel()
    if m.shape != t.shape:
        raise ValueError(f"measured and truth must have the same size, got {m.size} and {t.size}")
    if int(n_bins) != n_bins or n_bins < 3:
        raise ValueError(f"n_bins must be an integer >= 3, got {n_bins!r}")
    n_bins = int(n_bins)
    keep = np.isfinite(m) & np.isfinite(t)
    m, t = m[keep], t[keep]
    if symmetric:
        m, t = np.concatenate([m, -m]), np.concatenate([t, -t])
    if m.size < 2 * min_outer + n_bins:
        raise ValueError(f"need at least {2 * min_outer + n_bins} pixels for {n_bins} bins, got {m.size}")
    edges = _bin_edges(m, n_bins, min_outer)
    nodes = (edges[:-1] + edges[1:]) / 2
    which = _bin_index(m, edges)
    left, weight = _segments(m, nodes)
    # One equation per bin: the interpolated curve summed over the bin's pixels = the bin's true flux.
    system = np.zeros((n_bins, n_bins))
    np.add.at(system, (which, left), 1 - weight)
    np.add.at(system, (which, left + 1), weight)
    flux = np.bincount(which, weights=t, minlength=n_bins)
    values = np.linalg.lstsq(system, flux, rcond=None)[0]
    return FluxConservingCurve(nodes=nodes * u.G, values=values * u.G, edges=edges * u.G,
                               counts=np.bincount(which, minlength=n_bins))


def paper_pixels(gong_pixels, smap=None):
    """
    A length the authors gave in GONG pixels, in the pixels of another map.

    Parameters
    ----------
    gong_pixels : int
        Pixels of `PIXEL_SCALE_OF_THE_PAPER` (2.5″).
    smap : `~sunpy.map.GenericMap`, optional
        The map whose pixels to count in (its ``scale``); None or an array:
        GONG's pixels.

    Returns
    -------
    int
        The same angle on the Sun in the map's pixels (nearest, at least 1).

    Examples
    --------
    >>> import numpy as np, sunpy.map
    >>> header = {"cdelt1": 0.504, "cdelt2": 0.504, "cunit1": "arcsec", "cunit2": "arcsec",
    ...           "ctype1": "HPLN-TAN", "ctype2": "HPLT-TAN"}
    >>> hmi_like = sunpy.map.Map(np.zeros((4, 4)), header)
    >>> paper_pixels(7), paper_pixels(7, hmi_like), paper_pixels(4, hmi_like)
    (7, 35, 20)
    """
    scale = getattr(smap, "scale", None)
    if scale is None:
        return int(gong_pixels)
    pixel = u.Quantity(scale.axis1).to_value(u.arcsec / u.pix)
    angle = gong_pixels * PIXEL_SCALE_OF_THE_PAPER.to_value(u.arcsec)
    return max(1, int(round(angle / abs(pixel))))


def gong_resolution():
    """
    The FWHM of GONG's view: seeing ⊗ the aperture's Airy core ⊗ the 2.5″ pixel, in quadrature.

    The scale on which the authors' continuum threshold was set: 3.6″ seeing,
    1.03 λ/D = 5.1″ for 2.8 cm at 676.8 nm, and the pixel's box (σ = 2.5″/√12).

    Returns
    -------
    `~astropy.units.Quantity`
        In arcsec (6.5″ for GONG's defaults).

    Examples
    --------
    >>> print(f"{gong_resolution():.2f}")
    6.50 arcsec
    """
    from gongsynth.instruments import get
    gong = get("gong")
    airy = (1.03 * gong.line_wavelength / gong.aperture * u.rad).to(u.arcsec)
    pixel = gong.plate_scale / math.sqrt(12) * math.sqrt(8 * math.log(2))
    return np.sqrt(gong.seeing_fwhm ** 2 + airy ** 2 + pixel ** 2).to(u.arcsec)


def _at_gong_resolution(light, fill, smap):
    """
    The continuum as GONG would see it at the map's own pixels: unchanged for pixels of GONG's size or
    larger, else smoothed by a Gaussian of `gong_resolution` (NaN filled with ``fill`` first).

    Without it a finer map's intergranular lanes fall below the authors' threshold (15 % of HMI's
    quiet pixels at 0.504″), and the 17.5″ dilation turns the whole field into "sunspot".
    """
    if paper_pixels(1, smap) <= 1:
        return light
    pixel = abs(u.Quantity(smap.scale.axis1).to_value(u.arcsec / u.pix))
    sigma = gong_resolution().to_value(u.arcsec) / pixel / math.sqrt(8 * math.log(2))
    return scipy.ndimage.gaussian_filter(np.where(np.isfinite(light), light, fill), sigma, mode="nearest")


def paper_regions(magnetogram, continuum, *, latitude=0 * u.deg, usable=None, dilation=None):
    """
    The authors' quiet-Sun and sunspot pixels of a magnetogram.

    The sunspot is where the continuum, seen at GONG's resolution, is darker
    than 0.92 × the quiet-Sun median: a map with pixels finer than GONG's
    (its ``scale``) has its continuum smoothed to `gong_resolution` first.

    Parameters
    ----------
    magnetogram : `~sunpy.map.GenericMap`, Quantity or array
        Measured B_LOS (G).
    continuum : `~sunpy.map.GenericMap` or array_like
        The pseudo-continuum on the same pixels (any unit).
    latitude : `~astropy.units.Quantity`
        Viewing angle θ (sets the quiet-Sun limit 400 G × cos θ).
    usable : array of bool, optional
        Pixels that may be used at all (e.g. the native-resolution part).
    dilation : int, optional
        Side in pixels of the square by which the dark pixels are dilated into
        the sunspot mask.  Default: the authors' 7 GONG pixels (17.5″) in the
        magnetogram's pixels when it is a map (`paper_pixels`: 35 for HMI's
        0.504″), else 7.

    Returns
    -------
    quiet, sunspot : `numpy.ndarray` of bool
    """
    b = gauss_values(magnetogram, "magnetogram")
    light = np.asarray(getattr(continuum, "data", continuum), dtype=float)
    if light.shape != b.shape:
        raise ValueError(f"continuum must have the magnetogram's shape {b.shape}, got {light.shape}")
    usable = np.isfinite(b) & np.isfinite(light) & (True if usable is None else np.asarray(usable, bool))
    if not usable.any():
        raise ValueError("no usable pixels (all NaN or masked)")
    limit = QUIET_LIMIT.to_value(u.G) * math.cos(u.Quantity(latitude, u.deg).to_value(u.rad))
    calm = usable & (np.abs(b) < limit)
    reference = np.median(light[calm if calm.any() else usable])
    dark = usable & (_at_gong_resolution(light, reference, magnetogram) < _SPOT_DARKNESS * reference)
    side = paper_pixels(_SPOT_DILATION, magnetogram) if dilation is None else int(dilation)
    if side < 1:
        raise ValueError(f"dilation must be a positive number of pixels, got {dilation!r}")
    sunspot = usable & scipy.ndimage.binary_dilation(dark, np.ones((side, side), bool))
    return calm & ~sunspot, sunspot


def region_pixels(result, region="quiet", *, psf=True):
    """
    Measured and true B_LOS of one region of a simulation, with each pixel's position.

    Parameters
    ----------
    result : `~gongsynth.pipeline.SimulationResult`
        A simulation with its truth (tiled mode: only the 1× part of the field is used).
    region : {"quiet", "sunspot"}
        See `paper_regions`.
    psf : bool
        The truth through the PSF (``truth_psf``, default) or pixel-averaged (``truth``).

    Returns
    -------
    measured, truth : `numpy.ndarray`
        In G, one value per pixel of the region.
    rows, columns : `numpy.ndarray` of int
        The pixels' positions.
    """
    if region not in ("quiet", "sunspot"):
        raise ValueError(f"region must be 'quiet' or 'sunspot', got {region!r}")
    truth = result.truth_psf if psf else result.truth
    if truth is None:
        raise ValueError("this result has no ground truth (its input cube had no blos)")
    resolution = getattr(result, "resolution_map", None)
    usable = None if resolution is None else np.asarray(resolution) == 1
    quiet, sunspot = paper_regions(result.magnetogram, result.continuum, latitude=result.config.latitude,
                                   usable=usable)
    m, t = gauss_values(result.magnetogram, "magnetogram"), gauss_values(truth, "truth")
    rows, columns = np.nonzero((quiet if region == "quiet" else sunspot) & np.isfinite(t))
    return m[rows, columns], t[rows, columns], rows, columns


def paper_bins(latitude, region="quiet"):
    """
    The authors' number of bins for the tabulated angle nearest ``latitude``.

    Parameters
    ----------
    latitude : `~astropy.units.Quantity`
    region : {"quiet", "sunspot"}

    Returns
    -------
    int

    Examples
    --------
    >>> import astropy.units as u
    >>> paper_bins(0 * u.deg), paper_bins(58 * u.deg, "sunspot")
    (35, 7)
    """
    angle = u.Quantity(latitude, u.deg).to_value(u.deg)
    nearest = min(PAPER_BINS, key=lambda tabulated: abs(tabulated - angle))
    return PAPER_BINS[nearest][0 if region == "quiet" else 1]


def weak_flux_factor(results, *, region="quiet", n_bins=None, min_outer=400, n_boot=50, block=None, seed=0,
                     psf=True):
    """
    The weak-flux calibration factor of a simulation, as papers II/III estimate it.

    Parameters
    ----------
    results : `~gongsynth.pipeline.SimulationResult` or sequence of them
        Simulations with their truth at one latitude (several seeds are
        pooled into one fit; tiled mode: the 1× part of the field is used).
    region : {"quiet", "sunspot"}
        Which curve (see `paper_regions`).
    n_bins : int, optional
        Default: the authors' number for the nearest tabulated angle (`paper_bins`).
    min_outer : int
        Fewest pixels in each outer bin per run (× the number of runs pooled;
        see the module's note on pooling).
    n_boot : int
        Block-bootstrap resamples for the uncertainty.
    block : int, optional
        Side of the bootstrap blocks in pixels.  Default 10″ in the run's
        pixels (`paper_pixels`): 4 GONG pixels, about GONG's PSF width, so that
        blocks are roughly independent; 20 HMI pixels, the same patch of Sun.
    seed : int
        Seed of the bootstrap.
    psf : bool
        Compare with the truth through the PSF (``truth_psf``; default, as the
        authors did) or only pixel-averaged (``truth``).

    Returns
    -------
    `WeakFluxFactor`
    """
    m, t, labels, latitude, n_runs = _pooled(results, region, psf, block)
    n_bins = paper_bins(latitude, region) if n_bins is None else n_bins
    min_outer = min_outer * n_runs
    curve = flux_conserving_fit(m, t, n_bins, min_outer=min_outer)
    factors = []
    for index in _block_resamples(labels, n_boot, seed):
        try:
            resampled = flux_conserving_fit(m[index], t[index], n_bins, min_outer=min_outer)
        except ValueError:  # a resample too small for the bins: skip it
            continue
        factors.append(resampled.slope_at_zero)
    uncertainty = float(np.std(factors, ddof=1)) if len(factors) > 1 else float("nan")
    return WeakFluxFactor(factor=curve.slope_at_zero, uncertainty=uncertainty, curve=curve, region=region,
                          n_pixels=int(m.size), latitude=latitude)


def weak_flux_factor_difference(first, second, *, region="quiet", n_bins=None, min_outer=400, n_boot=50,
                                block=None, seed=0, psf=True):
    """
    The change of the weak-flux factor between two sets of runs of the same field, with its uncertainty.

    For ablations: the same seeds and pointing with one ingredient changed
    (e.g. the kG elements' temperature).  The two fits are bootstrapped
    together — each resample draws the same blocks of sky from both — so the
    structure and noise the two sets share cancel in the uncertainty, which
    two separate bootstraps would add instead.

    Parameters
    ----------
    first, second : `~gongsynth.pipeline.SimulationResult` or sequence of them
        Runs at one latitude, paired in order (same detector shape).
    region, n_bins, min_outer, n_boot, block, seed, psf
        As for `weak_flux_factor`.

    Returns
    -------
    difference : float
        Factor of ``second`` minus factor of ``first``.
    uncertainty : float
        Standard deviation of that difference over the paired block bootstrap.
    """
    pooled = [_pooled(runs, region, psf, block) for runs in (first, second)]
    if pooled[0][3] != pooled[1][3]:
        raise ValueError(f"the two sets must share one latitude, got {pooled[0][3]} and {pooled[1][3]}")
    n_bins = paper_bins(pooled[0][3], region) if n_bins is None else n_bins
    factors = [flux_conserving_fit(m, t, n_bins, min_outer=min_outer * n_runs).slope_at_zero
               for m, t, _, _, n_runs in pooled]
    # Blocks are named by run number and position, so one draw of names picks the same sky in both sets.
    names = np.union1d(pooled[0][2], pooled[1][2])
    rng = stage_generator(seed, "weak-flux-bootstrap")
    differences = []
    for _ in range(n_boot):
        counts = np.bincount(rng.integers(0, names.size, names.size), minlength=names.size)
        try:
            pair = [flux_conserving_fit(*_with_counts(m, t, labels, names, counts), n_bins,
                                        min_outer=min_outer * n_runs).slope_at_zero
                    for m, t, labels, _, n_runs in pooled]
        except ValueError:
            continue
        differences.append(pair[1] - pair[0])
    uncertainty = float(np.std(differences, ddof=1)) if len(differences) > 1 else float("nan")
    return factors[1] - factors[0], uncertainty


def _pooled(results, region, psf, block):
    """One latitude's region pixels of the runs, their bootstrap block names, and the number of runs."""
    results = [results] if hasattr(results, "magnetogram") else list(results)
    if not results:
        raise ValueError("results is empty")
    latitude = u.Quantity(results[0].config.latitude, u.deg)
    if any(u.Quantity(r.config.latitude, u.deg) != latitude for r in results):
        raise ValueError("pooled results must share one latitude, got "
                         f"{[str(r.config.latitude) for r in results]}")
    measured, truth, labels = [], [], []
    for number, result in enumerate(results):
        m, t, rows, columns = region_pixels(result, region, psf=psf)
        measured.append(m)
        truth.append(t)
        side = paper_pixels(_BLOCK, result.magnetogram) if block is None else int(block)
        # Bootstrap blocks never span two runs.
        labels.append((number * 100_003 + rows // side) * 100_003 + columns // side)
    return np.concatenate(measured), np.concatenate(truth), np.concatenate(labels), latitude, len(results)


def _block_resamples(labels, n_boot, seed):
    """Pixel indices of ``n_boot`` block-bootstrap resamples (whole blocks drawn with replacement)."""
    _, inverse = np.unique(labels, return_inverse=True)
    members = np.argsort(inverse, kind="stable")
    starts = np.searchsorted(inverse[members], np.arange(inverse.max() + 2))
    n_blocks = starts.size - 1
    rng = stage_generator(seed, "weak-flux-bootstrap")
    for _ in range(n_boot):
        picked = rng.integers(0, n_blocks, n_blocks)
        yield np.concatenate([members[starts[k]:starts[k + 1]] for k in picked])


def _with_counts(measured, truth, labels, names, counts):
    """Each pixel repeated as often as its block was drawn."""
    repeat = counts[np.searchsorted(names, labels)]
    return np.repeat(measured, repeat), np.repeat(truth, repeat)
