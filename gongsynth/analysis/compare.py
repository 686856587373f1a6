"""
Comparison of simulated GONG magnetograms with real GONG, HMI and MDI observations.

The workflow is::

    sim = load_observation("sim.fits")            # a gongsynth magnetogram
    obs = load_observation("mdi.fits")            # real data, header checked
    report = compare(sim, obs)                    # obs degraded to GONG first
    print(report.summary()); report.figure.savefig("compare.png")

or, from files, `compare_files` (behind ``gongsynth compare SIM.fits OBS.fits``).

`degrade_to_gong` brings a higher-resolution observation to GONG's view: the
GONG PSF (Airy pattern of the 2.8 cm aperture at λ0 ⊗ Gaussian seeing, from
`gongsynth.stages.optics.psf_kernel`) applied at the observation's own sampling, then
area-weighted (flux-conserving) binning onto 2.5″ pixels whose grid shares
the observation's tangent point.  The magnetogram is treated as a linear
signal (B_LOS convolved like an intensity), the usual approximation for
weak-field magnetograms; the observation's own PSF stays in (HMI's ~1″ adds
~1 % to the width, MDI's ~4″ more: see ``native_fwhm``).

The statistics (histograms, noise, limb darkening) live in
`gongsynth.analysis.statistics`, the file reading and header checks in
`gongsynth.analysis.observations`; they are re-exported here.
"""
import json
import math
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import astropy.units as u
import numpy as np
import scipy.signal
import scipy.sparse
import sunpy.map
from astropy.coordinates import SkyCoord
from sunpy.coordinates import frames

from gongsynth.instrument import resolve_instrument
from gongsynth.analysis.observations import BadHeaderWarning, load_observation
from gongsynth.analysis.statistics import _disk_values, _histogram  # one disk mask for both histograms
from gongsynth.analysis.statistics import (
    LimbDarkeningProfile,
    disk_centre_level,
    field_histogram,
    limb_darkening,
    local_pixel_scale,
    noise_estimate,
)
from gongsynth.validation import check_quantity

__all__ = [
    "BadHeaderWarning",
    "load_observation",
    "degrade_to_gong",
    "field_histogram",
    "noise_estimate",
    "disk_centre_level",
    "limb_darkening",
    "MapSummary",
    "ComparisonReport",
    "summarize_map",
    "compare",
    "compare_files",
    "LimbDarkeningComparison",
    "compare_limb_darkening",
]

#: Maps with pixels finer than this fraction of GONG's plate scale are
#: degraded automatically by `compare`.
AUTO_DEGRADE_FRACTION = 0.8

# Display range of magnetograms in the figure (the paper's Fig. 1: ±150 G).
_DISPLAY_LIMIT = 150


def _check_map(smap, name):
    if not isinstance(smap, sunpy.map.GenericMap):
        raise TypeError(f"{name} must be a sunpy Map, got {type(smap).__name__}")
    if smap.data.ndim != 2:
        raise ValueError(f"{name} must be a 2-D map, got data of shape {smap.data.shape}")
    if not np.isfinite(np.asarray(smap.data, dtype=float)).any():
        raise ValueError(f"{name} holds no finite pixel (all NaN or infinite)")
    return smap


def _hpc_frame(smap):
    return frames.Helioprojective(observer=smap.observer_coordinate, obstime=smap.reference_date,
                                  rsun=smap.rsun_meters)


def _rotation_angle(smap):
    """Rotation of the map's pixel axes from solar north, degrees (0 for an aligned map)."""
    m = np.asarray(smap.rotation_matrix, dtype=float)
    return math.degrees(math.atan2(m[1, 0], m[0, 0])), m


def _as_aligned_helioprojective(smap):
    """The map on a helioprojective grid with pixel axes along solar west and north."""
    if not isinstance(smap.coordinate_frame, frames.Helioprojective):
        # Heliographic cut-outs (e.g. a Postel HMI patch): interpolate onto a
        # helioprojective grid of the same sampling centred on the patch.
        scale = local_pixel_scale(smap, ((smap.data.shape[1] - 1) / 2, (smap.data.shape[0] - 1) / 2))
        centre = smap.pixel_to_world(*(((n - 1) / 2) * u.pix for n in smap.data.shape[::-1]))
        centre = centre.transform_to(_hpc_frame(smap))
        header = sunpy.map.make_fitswcs_header(
            smap.data.shape, centre, scale=u.Quantity([scale, scale]) / u.pix,
            instrument=smap.instrument, observatory=smap.observatory,
            wavelength=smap.wavelength, unit=smap.unit,
        )
        return smap.reproject_to(header, algorithm="interpolation", order="bilinear")
    angle, matrix = _rotation_angle(smap)
    if abs(angle) < 1e-3 and abs(matrix[0, 1]) < 1e-5 and abs(matrix[1, 0]) < 1e-5 \
            and matrix[0, 0] > 0 and matrix[1, 1] > 0:
        return smap
    return smap.rotate(order=1, missing=np.nan)


def _kernel(psf, scale, inst, native_fwhm):
    """The PSF kernel (unit sum) sampled at ``scale`` (arcsec), or None for no PSF."""
    if psf is False:
        if native_fwhm is not None:
            raise ValueError("native_fwhm applies to the instrument PSF; it cannot be used with psf=False")
        return None
    if psf is None:
        from gongsynth.stages.optics import psf_kernel  # imported here: optics is heavier than this module needs

        if native_fwhm is not None:
            check_quantity(native_fwhm, u.arcsec, "native_fwhm")
            seeing2 = inst.seeing_fwhm.to_value(u.arcsec) ** 2 - native_fwhm.to_value(u.arcsec) ** 2
            inst = inst.replace(seeing_fwhm=math.sqrt(max(seeing2, 0.0)) * u.arcsec)
        kernel = psf_kernel(scale * u.arcsec, inst)
    else:
        if native_fwhm is not None:
            raise ValueError("native_fwhm applies to the instrument PSF; give either psf or native_fwhm")
        kernel = psf(scale * u.arcsec) if callable(psf) else psf
    kernel = np.asarray(kernel, dtype=np.float64)
    if kernel.ndim != 2 or not np.all(np.isfinite(kernel)) or kernel.sum() <= 0:
        raise ValueError(
            f"psf must be a finite 2-D kernel with positive sum, got shape {kernel.shape}"
        )
    return kernel / kernel.sum()


def _masked_convolve(data, kernel):
    """Normalised convolution: the kernel-weighted mean of the finite pixels around each pixel."""
    valid = np.isfinite(data)
    # Kernel centre at (ky // 2, kx // 2), as gongsynth.stages.optics samples it: pad even sides at
    # the end so that the centre is the middle sample, which mode="same" keeps in place.
    ky, kx = kernel.shape
    kernel = np.pad(kernel, ((0, 1 - ky % 2), (0, 1 - kx % 2)))
    num = scipy.signal.fftconvolve(np.where(valid, data, 0.0), kernel, mode="same")
    den = scipy.signal.fftconvolve(valid.astype(np.float64), kernel, mode="same")
    with np.errstate(invalid="ignore", divide="ignore"):
        num /= den
    num[~valid | (den < 1e-6)] = np.nan
    return num


def _overlap_operator(n_in, cdelt_in, crpix0_in, scale_out):
    """
    Sparse (n_out, n_in) area-weight matrix and the output pixel position of the reference point.

    Input pixel j covers [(j - 0.5 - crpix0) cdelt, (j + 0.5 - crpix0) cdelt]
    in the projection plane (arcsec from the reference point).  Output pixels
    of side ``scale_out`` have their edges at whole multiples of ``scale_out``
    from the reference point (a grid fixed on the sky, whatever the input's
    extent or padding) and cover the input field, the outer ones possibly in
    part.  Entry (k, j) is the fraction of output pixel k covered by input
    pixel j, so rows sum to the covered fraction.  Returns the operator and
    the 0-based output pixel coordinate of the reference point.
    """
    a = (np.arange(n_in) - 0.5 - crpix0_in) * cdelt_in
    b = a + cdelt_in
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    origin = math.floor(lo.min() / scale_out + 1e-9) * scale_out
    n_out = max(1, int(math.ceil((hi.max() - origin) / scale_out - 1e-9)))
    rows, cols, vals = [], [], []
    first = np.floor((lo - origin) / scale_out + 1e-12).astype(int)
    for step in range(int(math.ceil(abs(cdelt_in) / scale_out)) + 2):
        k = first + step
        left = np.maximum(lo, origin + k * scale_out)
        right = np.minimum(hi, origin + (k + 1) * scale_out)
        width = right - left
        keep = (width > 1e-12 * scale_out) & (k < n_out)
        rows.append(k[keep])
        cols.append(np.nonzero(keep)[0])
        vals.append(width[keep] / scale_out)
    op = scipy.sparse.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n_out, n_in)
    )
    return op, -origin / scale_out - 0.5


def degrade_to_gong(smap, instrument=None, *, psf=None, native_fwhm=None, min_coverage=0.5):
    """
    Bring an observation to GONG's resolution: GONG PSF, then 2.5″ pixels.

    Steps: (1) put the map on a helioprojective grid with axes along solar
    west/north (heliographic cut-outs are interpolated, rotated maps such as
    HMI's 180° images are rotated); (2) convolve with the PSF sampled at the
    map's own pixel scale (NaN-aware: the mean over the finite pixels under
    the kernel, so off-disk blanks do not bleed in); (3) bin onto
    ``instrument.plate_scale`` pixels by exact area weighting (flux
    conserving: the mean over each GONG pixel of what falls in it).  The
    output grid shares the input's tangent point (``CRVAL``) and has its pixel
    edges at whole multiples of the plate scale from it, so the same sky gives
    the same grid whatever the input's extent, and the WCS is exact.  The observer is the observation's
    own (SOHO for MDI, SDO for HMI).

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        The observation (any unit; magnetograms in G).
    instrument : `~gongsynth.GONGInstrument`, optional
        Supplies ``plate_scale``, aperture, wavelength and seeing.
    psf : None, False, callable or array_like
        ``None``: the GONG PSF, `gongsynth.stages.optics.psf_kernel`; ``False``: no
        PSF (pixel binning only); a callable ``psf(pixel_scale) -> kernel``
        (``pixel_scale`` in arcsec); or a kernel array already sampled at the
        map's pixel scale, centred at ``(ky // 2, kx // 2)``.  Normalised to
        unit sum here.
    native_fwhm : `~astropy.units.Quantity`, optional
        Resolution (FWHM, arcsec) the observation already has; the seeing of
        the GONG PSF is reduced to √(seeing² - native²) (zero if negative) so
        the total width matches GONG.  Only with ``psf=None``.
    min_coverage : float
        GONG pixels with less than this fraction of their area covered by
        finite input pixels are NaN.

    Returns
    -------
    `~sunpy.map.GenericMap`
        Same unit and observer, pixel scale ``instrument.plate_scale``.

    Examples
    --------
    >>> import numpy as np, astropy.units as u, sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> m = sunpy.map.Map(np.ones((100, 100)), sunpy.map.make_fitswcs_header(
    ...     (100, 100), ref, scale=[0.5, 0.5] * u.arcsec / u.pix, unit=u.G))
    >>> g = degrade_to_gong(m, psf=False)
    >>> g.data.shape, g.scale.axis1, float(np.nanmean(g.data))
    ((20, 20), <Quantity 2.5 arcsec / pix>, 1.0)
    """
    _check_map(smap, "smap")
    inst = resolve_instrument(instrument)
    min_coverage = float(min_coverage)
    if not 0 < min_coverage <= 1:
        raise ValueError(f"min_coverage must lie in (0, 1], got {min_coverage}")
    aligned = _as_aligned_helioprojective(smap)
    cdelt = [aligned.scale.axis1.to_value(u.arcsec / u.pix), aligned.scale.axis2.to_value(u.arcsec / u.pix)]
    scale_in = math.sqrt(abs(cdelt[0] * cdelt[1]))
    kernel = _kernel(psf, scale_in, inst, native_fwhm)
    data = np.asarray(aligned.data, dtype=np.float64)
    if aligned.mask is not None and np.any(aligned.mask):
        data = np.where(aligned.mask, np.nan, data)
    if kernel is not None:
        data = _masked_convolve(data, kernel)
    plate = inst.plate_scale.to_value(u.arcsec)
    crpix = aligned.reference_pixel  # 0-based
    opx, refx = _overlap_operator(data.shape[1], cdelt[0], crpix.x.to_value(u.pix), plate)
    opy, refy = _overlap_operator(data.shape[0], cdelt[1], crpix.y.to_value(u.pix), plate)
    valid = np.isfinite(data)
    total = (opx @ (opy @ np.where(valid, data, 0.0)).T).T
    cover = (opx @ (opy @ valid.astype(np.float64)).T).T
    with np.errstate(invalid="ignore", divide="ignore"):
        binned = total / cover
    binned[~(cover >= min_coverage)] = np.nan

    header = sunpy.map.make_fitswcs_header(
        binned.shape, aligned.reference_coordinate,
        reference_pixel=u.Quantity([refx, refy], u.pix),
        scale=u.Quantity([plate, plate], u.arcsec / u.pix),
        unit=aligned.unit,
    )
    # Keep what the observation is and when it was taken (make_fitswcs_header writes the
    # frame's reference date as DATE-OBS).
    for key in ("telescop", "instrume", "obsrvtry", "detector", "wavelnth", "waveunit", "content",
                "rsun_obs", "rsun_ref", "origin", "dtype"):
        if key in smap.meta:
            header[key] = smap.meta[key]
    for key, value in (("instrume", smap.instrument), ("obsrvtry", smap.observatory)):
        if key not in header and value:
            header[key] = str(value)
    header["date-obs"] = smap.date.utc.isot
    if smap.reference_date != smap.date:
        header["date-avg"] = smap.reference_date.utc.isot
    psf_note = ("no PSF" if kernel is None else
                "GONG PSF" if psf is None else "user PSF") + (
        f" (native FWHM {native_fwhm} removed from the seeing)" if native_fwhm is not None else "")
    header["history"] = (f"gongsynth.degrade_to_gong: {psf_note} at {scale_in:.4g} arcsec/pixel, "
                         f"then area-weighted binning to {plate:g} arcsec pixels")
    return sunpy.map.Map(binned, header)


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
    """

    label: str
    description: str
    pixel_scale: u.Quantity
    degraded: bool
    histogram: object
    abs_histogram: object
    noise: object
    map: object = field(repr=False, default=None)

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
    parts = [str(p) for p in (smap.observatory, smap.instrument) if p]
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
        ``AUTO_DEGRADE_FRACTION`` × GONG's plate scale.
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
    _check_map(smap, label)
    if smap.unit is None or not smap.unit.is_equivalent(u.G):
        raise ValueError(f"{label}: expected a magnetogram in gauss, got unit {smap.unit}")
    inst = resolve_instrument(instrument)
    if degrade not in ("auto", True, False):
        raise ValueError(f"degrade must be 'auto', True or False, got {degrade!r}")
    scale = local_pixel_scale(smap)
    if degrade == "auto":
        degrade = bool(scale < AUTO_DEGRADE_FRACTION * inst.plate_scale)
    if degrade:
        smap = degrade_to_gong(smap, inst)
        scale = local_pixel_scale(smap)
    if smap.unit != u.G:
        smap = sunpy.map.Map(smap.quantity.to_value(u.G), {**smap.meta, "bunit": "G"})
    values = _disk_values(smap, max_radius)
    if values.size == 0:
        raise ValueError(f"{label}: no finite pixel within {max_radius} solar radii of disk centre")
    return MapSummary(
        label=label,
        description=_describe_map(smap),
        pixel_scale=scale,
        degraded=bool(degrade),
        histogram=_histogram(values, u.G, None, False),
        abs_histogram=_histogram(values, u.G, None, True),
        noise=_noise(smap, noise_box),
        map=smap,
    )


def _noise(smap, box):
    """Quiet-box noise near disk centre; on a field away from disk centre, boxes anywhere on the disk."""
    try:
        return noise_estimate(smap, box=box)
    except ValueError:
        # No grid box near disk centre lies on this map (e.g. a field at high latitude):
        # tile the map instead; NoiseEstimate.layout records it.
        return noise_estimate(smap, box=box, layout="tiles", max_radius=1.0)


def _cdf_distance(h1, h2):
    """Largest difference of the two cumulative distributions on the common edges."""
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
    cdf_distance : float
        Kolmogorov-Smirnov distance between the on-disk distributions of B
        (largest difference of the cumulative distributions, 0 = identical).
    figure : `matplotlib.figure.Figure` or None
    """

    sim: MapSummary
    obs: MapSummary
    ratios: dict
    cdf_distance: float
    figure: object = None

    def to_dict(self):
        """
        All numbers as a JSON-serialisable dict.

        Returns
        -------
        dict
            ``{"sim": ..., "obs": ..., "ratios": ..., "cdf_distance": ...}``.
        """
        return {"sim": self.sim.numbers(), "obs": self.obs.numbers(),
                "ratios": dict(self.ratios), "cdf_distance": self.cdf_distance}

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
        lines.append(f"{'KS distance of B':{width}}  {self.cdf_distance:>{col}.3f}")
        lines.append(f"{'noise ratio sim/obs':{width}}  {self.ratios['noise_sigma']:>{col}.3f}")
        return "\n".join(lines)


def _plot(report, fig):
    """Draw maps, histograms on log axes and the noise boxes of both maps."""
    import matplotlib.colors as mcolors

    limit = _DISPLAY_LIMIT
    colours = {"sim": "C0", "obs": "C3"}
    for i, (key, summ) in enumerate((("sim", report.sim), ("obs", report.obs))):
        ax = fig.add_subplot(2, 3, i + 1, projection=summ.map)
        summ.map.plot(axes=ax, cmap="gray", norm=mcolors.Normalize(-limit, limit), title=False)
        ax.set_title(f"{summ.label}: {summ.description}\n{summ.pixel_scale.to_value(u.arcsec):.2f}″ pixels"
                     + (", degraded to GONG" if summ.degraded else ""), fontsize=9)
        ax.coords[0].set_axislabel("Solar X")
        ax.coords[1].set_axislabel("Solar Y")
        c = summ.noise.box_centres.to_value(u.arcsec)
        q = summ.noise.quietest
        ax.plot_coord(SkyCoord(c[:, 0] * u.arcsec, c[:, 1] * u.arcsec, frame=summ.map.coordinate_frame),
                      "s", ms=3, mfc="none", mec=colours[key], lw=0)
        ax.plot_coord(SkyCoord(c[q, 0] * u.arcsec, c[q, 1] * u.arcsec, frame=summ.map.coordinate_frame),
                      "s", ms=6, mfc="none", mec="yellow", lw=0)
    ax = fig.add_subplot(2, 3, 3)
    for key, summ in (("sim", report.sim), ("obs", report.obs)):
        c = summ.noise.box_centres.to_value(u.arcsec)
        r = np.hypot(c[:, 0], c[:, 1]) / summ.map.rsun_obs.to_value(u.arcsec)
        ax.plot(r, summ.noise.box_sigma.to_value(u.G), "o", color=colours[key], ms=4, mfc="none",
                label=f"{summ.label}: robust σ per box")
        ax.axhline(summ.noise.sigma.to_value(u.G), color=colours[key], lw=1,
                   label=f"quietest box σ = {summ.noise.sigma.to_value(u.G):.2f} G")
        ax.axhline(summ.noise.difference.to_value(u.G), color=colours[key], lw=1, ls=":",
                   label=f"pixel-difference σ = {summ.noise.difference.to_value(u.G):.2f} G")
    ax.set_xlabel("box distance from disk centre [R☉]")
    ax.set_ylabel("noise [G]")
    ax.set_yscale("log")
    ax.set_title(f"noise in {report.sim.noise.box_size.to_value(u.arcsec):.0f}″ boxes", fontsize=9)
    ax.legend(fontsize=7)

    _plot_histograms(fig.add_subplot(2, 3, 4), report, colours, "histogram", "B_LOS [G]",
                     "on-disk histogram")
    _plot_histograms(fig.add_subplot(2, 3, 5), report, colours, "abs_histogram", "|B_LOS| [G]",
                     "on-disk |B| histogram", log_x=True)

    ax = fig.add_subplot(2, 3, 6)
    ax.axis("off")
    ax.text(0, 1, report.summary(figure=True), family="monospace", fontsize=7, va="top", ha="left",
            transform=ax.transAxes)
    # Fixed margins: tight_layout costs more than the rest of the figure.
    fig.subplots_adjust(left=0.06, right=0.98, bottom=0.07, top=0.93, wspace=0.35, hspace=0.35)
    return fig


def compare(sim_map, obs_map, *, instrument=None, degrade="auto", labels=("simulated", "observed"),
            noise_box=60 * u.arcsec, plot=True, fig=None):
    """
    Compare a simulated GONG magnetogram with an observed one: numbers and a figure.

    Both maps are measured the same way after any map finer than
    ``AUTO_DEGRADE_FRACTION`` × GONG's 2.5″ pixels has been degraded to GONG
    (`degrade_to_gong`): on-disk histograms (signed and |B|), summary numbers
    (mean, mean |B|, std, robust sigma, percentiles), quiet-box noise near
    disk centre (robust sigma, std, pixel difference), their ratios and the
    Kolmogorov-Smirnov distance between the two distributions of B.

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
        Figure to draw into (e.g. ``plt.figure(figsize=(13, 8))`` to show it
        with pyplot); default a new stand-alone Figure.

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
    >>> report = compare(a, b, plot=False)
    >>> round(report.ratios["noise_median_std"], 1)
    0.5
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
    report = ComparisonReport(sim=sim, obs=obs, ratios=ratios, cdf_distance=distance)
    if plot:
        if fig is None:
            from matplotlib.figure import Figure

            fig = Figure(figsize=(13, 8))
        report.figure = _plot(report, fig)
    return report


def compare_files(sim_path, obs_path, *, out=None, overwrite=False, instrument=None, degrade="auto"):
    """
    Compare a simulated and an observed magnetogram FITS file (``gongsynth compare``).

    Parameters
    ----------
    sim_path, obs_path : str or `pathlib.Path`
        FITS files read with `load_observation` (``kind="magnetogram"``).
    out : str or `pathlib.Path`, optional
        Where to save the side-by-side figure (format from the suffix, e.g.
        ``.png`` or ``.pdf``); written atomically.  No figure is drawn if None.
    overwrite : bool
        Replace an existing ``out``.
    instrument : `~gongsynth.GONGInstrument`, optional
    degrade : {"auto", True, False}
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
        if out.exists() and not overwrite:
            raise FileExistsError(f"compare_files: {out} exists; pass overwrite=True to replace it")
        if not out.parent.is_dir():
            raise FileNotFoundError(f"compare_files: the folder of out does not exist: {out.parent}")
    sim = load_observation(sim_path, kind="magnetogram")
    obs = load_observation(obs_path, kind="magnetogram")
    labels = (f"simulated ({Path(sim_path).name})", f"observed ({Path(obs_path).name})")
    report = compare(sim, obs, instrument=instrument, degrade=degrade, labels=labels,
                     plot=out is not None)
    if out is not None:
        fd, tmp = tempfile.mkstemp(prefix=f".{out.stem}.", suffix=out.suffix, dir=out.parent)
        os.close(fd)
        try:
            report.figure.savefig(tmp, dpi=110)
            os.replace(tmp, out)
        except BaseException:
            if os.path.exists(tmp):
                os.unlink(tmp)
            raise
    return report


@dataclass
class LimbDarkeningComparison:
    """
    Result of `compare_limb_darkening`: two centre-to-limb profiles and their difference.

    Attributes
    ----------
    sim, obs : `~gongsynth.analysis.statistics.LimbDarkeningProfile`
        Profiles normalised to each map's own disk-centre level, on the same μ bins.
    max_difference, rms_difference : float
        Largest and rms |I_sim/I_sim(0) - I_obs/I_obs(0)| over the μ bins both maps fill.
    centre_ratio : float
        Ratio of the disk-centre levels, sim / obs (meaningful when both are in
        the same unit, e.g. DN of the same exposure).
    figure : `matplotlib.figure.Figure` or None
    """

    sim: LimbDarkeningProfile
    obs: LimbDarkeningProfile
    max_difference: float
    rms_difference: float
    centre_ratio: float
    figure: object = None


def compare_limb_darkening(sim_map, obs_map, *, instrument=None, degrade="auto", bins=20, max_radius=0.98,
                           labels=("simulated", "observed"), plot=True, fig=None):
    """
    Compare the count levels of two intensity maps: limb-darkening curves normalised to disk centre.

    Maps finer than ``AUTO_DEGRADE_FRACTION`` × GONG's pixels are first
    degraded to GONG (``degrade="auto"``), so the limb is blurred alike.

    Parameters
    ----------
    sim_map, obs_map : `~sunpy.map.GenericMap`
        Intensity maps (pseudo-continuum, continuum; any unit).
    instrument : `~gongsynth.GONGInstrument`, optional
    degrade : {"auto", True, False}
    bins : int
        Number of μ bins.
    max_radius : float
        Outermost distance from disk centre used, solar radii.
    labels : (str, str)
    plot : bool
        Draw the two curves and their difference.
    fig : `matplotlib.figure.Figure`, optional

    Returns
    -------
    `LimbDarkeningComparison`

    Examples
    --------
    >>> import numpy as np, astropy.units as u, sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> from gongsynth.analysis.statistics import disk_coordinates
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> hdr = sunpy.map.make_fitswcs_header((200, 200), ref, scale=[10, 10] * u.arcsec / u.pix)
    >>> _, mu = disk_coordinates(sunpy.map.Map(np.zeros((200, 200)), hdr))
    >>> a = sunpy.map.Map(np.nan_to_num(1 - 0.6 * (1 - mu)), hdr)
    >>> b = sunpy.map.Map(np.nan_to_num(2 * (1 - 0.5 * (1 - mu))), hdr)
    >>> result = compare_limb_darkening(a, b, plot=False)
    >>> round(result.centre_ratio, 2), round(result.max_difference, 2)
    (0.5, 0.08)
    """
    if len(labels) != 2:
        raise ValueError(f"labels must be two strings, got {labels!r}")
    if degrade not in ("auto", True, False):
        raise ValueError(f"degrade must be 'auto', True or False, got {degrade!r}")
    inst = resolve_instrument(instrument)
    profiles = []
    for smap, name in ((sim_map, "sim_map"), (obs_map, "obs_map")):
        _check_map(smap, name)
        if degrade is True or (degrade == "auto"
                               and local_pixel_scale(smap) < AUTO_DEGRADE_FRACTION * inst.plate_scale):
            smap = degrade_to_gong(smap, inst)
        profiles.append(limb_darkening(smap, bins=bins, max_radius=max_radius))
    sim, obs = profiles
    both = (sim.counts > 0) & (obs.counts > 0)
    diff = np.abs(sim.intensity[both] - obs.intensity[both])
    ratio = sim.centre_level / obs.centre_level
    result = LimbDarkeningComparison(
        sim=sim, obs=obs, max_difference=float(diff.max()),
        rms_difference=float(np.sqrt(np.mean(diff**2))),
        centre_ratio=float(ratio.to_value(u.one)) if ratio.unit.is_equivalent(u.one) else float("nan"),
    )
    if plot:
        if fig is None:
            from matplotlib.figure import Figure

            fig = Figure(figsize=(7, 6))
        top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=[3, 1])
        for profile, label, colour in ((sim, labels[0], "C0"), (obs, labels[1], "C3")):
            top.plot(profile.mu, profile.intensity, "o", ms=3, color=colour,
                     label=f"{label}: centre {profile.centre_level:.4g}")
            top.plot(profile.mu, profile.law(profile.mu), "-", lw=0.8, color=colour)
        top.set_ylabel("I(μ) / I(disk centre)")
        top.legend(fontsize=8)
        bottom.plot(sim.mu[both], sim.intensity[both] - obs.intensity[both], "ko", ms=3)
        bottom.axhline(0, color="0.5", lw=0.8)
        bottom.set_xlabel("μ = cos θ")
        bottom.set_ylabel("difference")
        result.figure = fig
    return result


def _plot_histograms(ax, report, colours, attribute, xlabel, title, *, log_x=False):
    """Histograms (``attribute`` of each map summary) of both maps on log axes."""
    for key, summ in (("sim", report.sim), ("obs", report.obs)):
        h = getattr(summ, attribute)
        ax.stairs(np.where(h.density.value > 0, h.density.value, np.nan), h.edges.to_value(u.G),
                  color=colours[key], label=summ.label)
    if log_x:
        ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("probability density [1/G]")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=8)
