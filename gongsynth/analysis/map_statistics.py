"""
The statistics a solar physicist compares between two magnetograms, with and without matching their noise.

`compare_statistics` measures two maps the same way (after `gongsynth.compare`
has degraded the finer one to GONG): the two-sample Kolmogorov-Smirnov
distance of their on-disk pixel values (as they are and with each map's
median taken out: a site file's zero point is not the Sun's), the
quiet-box and pixel-difference noise (`gongsynth.analysis.noise`), the mean
|B| (as measured, and of |B - median|: a zero point of a few G adds to the
mean |B| of a noisy map as much as a weak field does), the 99th and 99.9th
percentiles of |B - median| (`gongsynth.analysis.statistics.tail_percentiles`),
the mean |B| in rings from disk centre to the limb
(`~gongsynth.analysis.statistics.ring_means`), the azimuthally averaged
spatial power spectrum of the central region (`gongsynth.analysis.power_spectrum`),
the network's clusters near disk centre: their number and flux per area,
the 99th percentile of their fluxes and the power-law index of the
distribution (`gongsynth.analysis.network_clusters`, its defaults), and how
the weak field's power at the network's scales falls toward the limb and
how much stronger it is east-west than north-south
(`gongsynth.analysis.limb_power`).

A seeded Sun and a real map differ in their noise as well as in their Sun;
the noise fills the core of the histogram, so a KS distance or a mean |B|
alone mixes the two.  Every number is therefore also given **with the noise
matched**: white Gaussian noise of variance σ_hi² − σ_lo² (σ: the
pixel-difference noise of the quietest box near disk centre, the measure
of white noise that ignores structure) is added to the quieter map, with a
fixed seed, and everything is measured again.  This is a diagnostic, not a model of the instrument.
"""
from dataclasses import dataclass

import astropy.units as u
import numpy as np
import scipy.stats
import sunpy.map
from astropy.table import QTable

from gongsynth.analysis.disk import check_map, disk_coordinates, map_values
from gongsynth.analysis.limb_power import limb_power_fit
from gongsynth.analysis.network_clusters import network_clusters
from gongsynth.analysis.noise import noise_estimate
from gongsynth.analysis.power_spectrum import power_spectrum, quadrant_power_spectrum
from gongsynth.analysis.statistics import RING_EDGES, rings_of_values, tail_percentiles

__all__ = ["StatisticsComparison", "compare_statistics", "match_noise", "quiet_noise", "SPECTRUM_BAND"]

#: The range of scales over which the spectra are compared (5-100 Mm: granular noise to
#: the supergranular network and the unipolar patches).
SPECTRUM_BAND = (5 * u.Mm, 100 * u.Mm)

_ROWS = ("sim", "obs", "sim, noise matched", "obs, noise matched")
_LIMB_COLUMNS = ("limb_exponent", "limb_exponent_error", "east_west_excess", "east_west_excess_error")


def match_noise(sim_map, obs_map, *, seed=0):
    """
    Add white noise to the quieter of two maps so that both have the same pixel-difference noise.

    Parameters
    ----------
    sim_map, obs_map : `~sunpy.map.GenericMap`
        Magnetograms in G.
    seed : int
        Seed of the added noise.

    Returns
    -------
    sim, obs : `~sunpy.map.GenericMap`
        The maps, one of them with noise added (NaN pixels stay NaN).
    added : (float, float)
        Standard deviation of the noise added to each, G (one of them 0).

    Examples
    --------
    >>> import numpy as np, astropy.units as u, sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> hdr = sunpy.map.make_fitswcs_header((300, 300), ref, scale=[2.5, 2.5] * u.arcsec / u.pix,
    ...                                     unit=u.G)
    >>> rng = np.random.default_rng(1)
    >>> a, b = (sunpy.map.Map(rng.normal(0, s, (300, 300)), hdr) for s in (3, 5))
    >>> a2, _, added = match_noise(a, b)
    >>> [round(x) for x in added]
    [4, 0]
    >>> round(_difference_noise(a2) / _difference_noise(b), 2)
    1.0
    """
    sigma = [_difference_noise(m) for m in (sim_map, obs_map)]
    low = int(np.argmin(sigma))
    maps = [sim_map, obs_map]
    added = [0.0, 0.0]
    target, start = sigma[1 - low] ** 2, sigma[low] ** 2
    if target > start:
        m = maps[low]
        data = map_values(m)
        unit_noise = np.random.default_rng(seed).normal(0.0, 1.0, data.shape)
        # The quietest box's variance grows linearly with the added variance, with a slope a little
        # below 1 (the box is picked as the quietest: 0.94² for white noise); one measurement fixes it.
        trial = target - start
        slope = (_difference_noise(sunpy.map.Map(data + np.sqrt(trial) * unit_noise, m.meta)) ** 2
                 - start) / trial
        extra = float(np.sqrt(trial / max(slope, 0.5)))
        maps[low] = sunpy.map.Map(data + extra * unit_noise, m.meta)
        added[low] = extra
    return maps[0], maps[1], tuple(added)


def _difference_noise(smap):
    """The quietest box's pixel-difference noise, G."""
    return float(quiet_noise(smap).difference.to_value(u.G))


def quiet_noise(smap, box=60 * u.arcsec):
    """
    Quiet-box noise near disk centre; on a field away from disk centre, boxes anywhere on the disk.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
    box : `~astropy.units.Quantity`
        Box side (default 60″).

    Returns
    -------
    `~gongsynth.analysis.noise.NoiseEstimate`
        ``layout`` records which boxes were used.
    """
    try:
        return noise_estimate(smap, box=box)
    except ValueError:
        # No grid box near disk centre lies on this map (e.g. a field at high latitude): tile the map.
        return noise_estimate(smap, box=box, layout="tiles", max_radius=1.0)


@dataclass(frozen=True)
class StatisticsComparison:
    """
    The numbers of `compare_statistics`.

    Attributes
    ----------
    table : `~astropy.table.QTable`
        One row per map and condition (``map``: "sim", "obs", "sim, noise
        matched", "obs, noise matched"); columns ``noise_added``,
        ``noise_box`` (quietest-box robust sigma), ``noise_difference``,
        ``mean``, ``median``, ``mean_abs``, ``mean_abs_centred`` (the mean
        of |B - median|), ``std``, ``p99``, ``p999`` (99th and 99.9th
        percentiles of |B - median|), all G; ``ks`` and
        ``ks_centred``: the KS distance between the sim and obs rows of the
        same condition (as they are, and medians removed); the network's
        clusters within 0.35 R☉ (`~gongsynth.analysis.network_clusters.network_clusters`):
        ``cluster_density`` (per Mm²), ``cluster_flux_density`` (G),
        ``cluster_p99`` (Mx), ``cluster_index`` and ``cluster_elongation``
        (the median axis ratio of clusters of at least 6 pixels; all NaN
        where the map does not reach disk centre); the weak field's power
        at 20-50 Mm over the disk (`~gongsynth.analysis.limb_power.limb_power_fit`):
        ``limb_exponent`` (b of P ∝ μ^b), ``east_west_excess`` (c of
        exp(c (x² − y²))) and their errors ``limb_exponent_error`` and
        ``east_west_excess_error`` (NaN where the map holds too little of the disk).
    rings : `~astropy.table.QTable`
        ``r_inner``, ``r_outer`` (solar radii), ``pixels_sim``, ``pixels_obs``
        and the mean |B| of each map and condition: ``sim``, ``obs``,
        ``sim_matched``, ``obs_matched`` (G), with ``ratio`` and ``ratio_matched`` (sim / obs);
        the robust width (1.4826 × MAD) and the robust pixel-difference noise of each
        (`~gongsynth.analysis.statistics.ring_means`): ``<map>_width`` and ``<map>_noise`` (G),
        with ``width_ratio`` and ``width_ratio_matched``.  Where the widths differ more than the
        noises, the rings differ in weak signal or in noise correlated between pixels.
    spectra : `~astropy.table.QTable`
        ``wavelength`` (Mm) and the power of each map and condition (G² Mm²)
        in the same columns, with ``ratio`` and ``ratio_matched``; the same
        for the mean spectrum of the four boxes that tile the central square of
        twice the side (``<map>_quadrants``, ``ratio_quadrants``,
        ``ratio_quadrants_matched``; NaN where a map does not hold them): one
        640″ box holds few supergranules, and its spectrum at network scales
        strays by a factor ~1.4 from one map of the same Sun to the next
        (``scripts/power_spectrum_seeds.py``), four boxes by ~1.15.
    """

    table: QTable
    rings: QTable
    spectra: QTable

    def row(self, name):
        """
        One row of ``table`` as a dict of Quantities and floats.

        Parameters
        ----------
        name : str
            One of "sim", "obs", "sim, noise matched", "obs, noise matched".

        Returns
        -------
        dict
        """
        if name not in _ROWS:
            raise ValueError(f"row must be one of {_ROWS}, got {name!r}")
        i = _ROWS.index(name)
        return {key: self.table[key][i] for key in self.table.colnames if key != "map"}

    def spectrum_ratio_range(self, band=SPECTRUM_BAND, *, matched=False, quadrants=False):
        """
        Smallest and largest sim/obs power ratio over the annuli whose wavelengths lie in ``band``.

        Parameters
        ----------
        band : (Quantity, Quantity)
            Wavelength range (default 5-100 Mm).
        matched : bool
            With the noise matched.
        quadrants : bool
            The mean spectrum of the four boxes that tile the central square of twice the side
            instead of the central box's (NaN if the maps do not hold them).

        Returns
        -------
        (float, float)
        """
        lam = self.spectra["wavelength"].to_value(u.Mm)
        keep = (lam >= band[0].to_value(u.Mm)) & (lam <= band[1].to_value(u.Mm))
        key = "ratio_quadrants" if quadrants else "ratio"
        ratio = np.asarray(self.spectra[key + "_matched" if matched else key])[keep]
        ratio = ratio[np.isfinite(ratio)]
        return (float(ratio.min()), float(ratio.max())) if ratio.size else (np.nan, np.nan)

    def summary(self):
        """
        A plain-text table of the numbers, without and with the noise matched.

        Returns
        -------
        str
        """
        t = self.table
        lines = [f"{'':26s}{'sim':>9s}{'obs':>9s}{'ratio':>8s}   "
                 f"{'matched: sim':>12s}{'obs':>9s}{'ratio':>8s}"]
        for key, name in (("noise_box", "quietest-box noise [G]"),
                          ("noise_difference", "pixel-diff. noise [G]"), ("mean", "disk mean [G]"),
                          ("mean_abs", "mean |B| [G]"), ("mean_abs_centred", "mean |B-median| [G]"),
                          ("std", "std [G]"),
                          ("p99", "99% |B-median| [G]"), ("p999", "99.9% |B-median| [G]")):
            v = t[key].to_value(u.G)
            lines.append(f"{name:26s}{v[0]:9.2f}{v[1]:9.2f}{v[0] / v[1]:8.2f}   "
                         f"{v[2]:12.2f}{v[3]:9.2f}{v[2] / v[3]:8.2f}")
        lines.append(f"{'KS distance':26s}{t['ks'][0]:9.3f}{'':17s}   {t['ks'][2]:12.3f}")
        lines.append(f"{'KS, medians removed':26s}{t['ks_centred'][0]:9.3f}{'':17s}   "
                     f"{t['ks_centred'][2]:12.3f}")
        lo, hi = self.spectrum_ratio_range()
        lo_m, hi_m = self.spectrum_ratio_range(matched=True)
        lines.append(f"{'power ratio 5-100 Mm':26s}{lo:9.2f} to {hi:.2f}{'':6s}   {lo_m:12.2f} to {hi_m:.2f}")
        lo, hi = self.spectrum_ratio_range(quadrants=True)
        lo_m, hi_m = self.spectrum_ratio_range(matched=True, quadrants=True)
        lines.append(f"{'power ratio, 4 boxes':26s}{lo:9.2f} to {hi:.2f}{'':6s}   {lo_m:12.2f} to {hi_m:.2f}")
        for key, name, scale in (("cluster_density", "clusters per 1e4 Mm2", 1e4),
                                 ("cluster_flux_density", "cluster flux / area [G]", 1.0),
                                 ("cluster_p99", "clusters' 99% [1e19 Mx]", 1e-19),
                                 ("cluster_index", "cluster index > 3e19 Mx", 1.0),
                                 ("cluster_elongation", "cluster elongation", 1.0)):
            v = np.asarray(getattr(t[key], "value", t[key]), dtype=float) * scale
            with np.errstate(invalid="ignore", divide="ignore"):
                lines.append(f"{name:26s}{v[0]:9.2f}{v[1]:9.2f}{v[0] / v[1]:8.2f}   "
                             f"{v[2]:12.2f}{v[3]:9.2f}{v[2] / v[3]:8.2f}")
        for key, name in (("limb_exponent", "weak power ∝ μ^b: b"),
                          ("limb_exponent_error", "  its standard error"),
                          ("east_west_excess", "east-west excess c"),
                          ("east_west_excess_error", "  its standard error")):
            v = np.asarray(t[key], dtype=float)
            lines.append(f"{name:26s}{v[0]:9.2f}{v[1]:9.2f}{'':8s}   {v[2]:12.2f}{v[3]:9.2f}")
        for r in self.rings:
            lines.append(f"{'mean |B| ' + f'{r['r_inner']:.2f}-{r['r_outer']:.2f} R':26s}"
                         f"{r['sim'].to_value(u.G):9.2f}{r['obs'].to_value(u.G):9.2f}{r['ratio']:8.2f}   "
                         f"{r['sim_matched'].to_value(u.G):12.2f}{r['obs_matched'].to_value(u.G):9.2f}"
                         f"{r['ratio_matched']:8.2f}")
        for r in self.rings:
            lines.append(f"{'robust σ ' + f'{r['r_inner']:.2f}-{r['r_outer']:.2f} R':26s}"
                         f"{r['sim_width'].to_value(u.G):9.2f}{r['obs_width'].to_value(u.G):9.2f}"
                         f"{r['width_ratio']:8.2f}   "
                         f"{r['sim_matched_width'].to_value(u.G):12.2f}{r['obs_matched_width'].to_value(u.G):9.2f}"
                         f"{r['width_ratio_matched']:8.2f}")
        for r in self.rings:
            lines.append(f"{'diff. noise ' + f'{r['r_inner']:.2f}-{r['r_outer']:.2f} R':26s}"
                         f"{r['sim_noise'].to_value(u.G):9.2f}{r['obs_noise'].to_value(u.G):9.2f}"
                         f"{float(r['sim_noise'] / r['obs_noise']):8.2f}   "
                         f"{r['sim_matched_noise'].to_value(u.G):12.2f}{r['obs_matched_noise'].to_value(u.G):9.2f}"
                         f"{float(r['sim_matched_noise'] / r['obs_matched_noise']):8.2f}")
        return "\n".join(lines)

    def plot_spectra(self, ax, colours=None):
        """
        Draw both maps' power spectra (solid), with the noise matched (dashed) and of 4 boxes (dotted).

        Parameters
        ----------
        ax : `matplotlib.axes.Axes`
        colours : dict, optional
            ``{"sim": colour, "obs": colour}`` (default C0 and C3).
        """
        colours = colours or {"sim": "C0", "obs": "C3"}
        t = self.spectra
        lam = t["wavelength"].to_value(u.Mm)
        for key in ("sim", "obs"):
            ax.loglog(lam, t[key].value, color=colours[key], label=key)
            ax.loglog(lam, t[key + "_matched"].value, color=colours[key], ls="--", lw=0.8,
                      label=f"{key}, noise matched")
            quadrants = t[key + "_quadrants"].value
            if np.isfinite(quadrants).any():
                ax.loglog(lam, quadrants, color=colours[key], ls=":", lw=1, label=f"{key}, 4 boxes")
        lo, hi = (b.to_value(u.Mm) for b in SPECTRUM_BAND)
        ax.axvspan(lo, hi, color="0.92", zorder=0)
        ax.invert_xaxis()
        ax.set_xlabel("wavelength [Mm]", fontsize=8)
        ax.set_ylabel("power [G² Mm²]", fontsize=8)
        ax.tick_params(labelsize=7)
        box = t.meta.get("box_pixels", ("?",))[0]
        ax.set_title(f"power spectrum, central {box}² pixels (dotted: 4 boxes; grey: 5-100 Mm)", fontsize=8)
        ax.legend(fontsize=6)

    def plot_rings(self, ax, colours=None):
        """
        Draw the mean |B| in centre-to-limb rings of both maps (dashed: noise matched; dotted: robust width).

        Where the maps hold enough of the disk, the text in the corner gives each map's fit of its weak
        field's power over the disk (``limb_exponent`` b, ``east_west_excess`` c).

        Parameters
        ----------
        ax : `matplotlib.axes.Axes`
        colours : dict, optional
            ``{"sim": colour, "obs": colour}`` (default C0 and C3).
        """
        colours = colours or {"sim": "C0", "obs": "C3"}
        t = self.rings
        r = 0.5 * (np.asarray(t["r_inner"]) + np.asarray(t["r_outer"]))
        for key in ("sim", "obs"):
            ax.plot(r, t[key].to_value(u.G), "o-", color=colours[key], ms=3, label=key)
            ax.plot(r, t[key + "_matched"].to_value(u.G), "--", color=colours[key], lw=0.8,
                    label=f"{key}, noise matched")
            ax.plot(r, t[key + "_width"].to_value(u.G), ":", color=colours[key], lw=1,
                    label=f"{key}, robust σ")
        ax.set_xlabel("ring distance from disk centre [R☉]", fontsize=8)
        ax.set_ylabel("mean |B|, robust σ [G]", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.set_ylim(bottom=0)
        ax.set_title("mean |B| and robust σ by centre-to-limb ring", fontsize=8)
        ax.legend(fontsize=6, ncol=2, loc="lower left")
        fits = [f"{key}: b = {row['limb_exponent']:.2f} ± {row['limb_exponent_error']:.2f}, "
                f"c = {row['east_west_excess']:+.2f} ± {row['east_west_excess_error']:.2f}"
                for key, row in zip(("sim", "obs"), self.table[:2]) if np.isfinite(row["limb_exponent"])]
        if fits:      # the weak field's power at 20-50 Mm ∝ μ^b exp(c (x² − y²)) (limb_power_fit)
            ax.text(0.98, 0.26, "weak power at 20-50 Mm $\\propto \\mu^b\\,e^{c\\,(x^2 - y^2)}$\n"
                    + "\n".join(fits), fontsize=6, ha="right", va="bottom", transform=ax.transAxes,
                    bbox={"facecolor": "white", "edgecolor": "0.8", "alpha": 0.9})


def _measure(smap, rho, max_radius, box, ring_edges, edges=None):
    data = map_values(smap)
    with np.errstate(invalid="ignore"):
        values = data[np.isfinite(data) & (rho < max_radius)]
    noise = quiet_noise(smap)
    tails = tail_percentiles(values)
    spectrum = power_spectrum(smap, box=box, edges=edges)
    try:
        clusters = network_clusters(smap).summary()
    except ValueError:                       # the map does not reach disk centre
        clusters = {"number_density": np.nan / u.Mm**2, "flux_density": np.nan * u.G,
                    "p99": np.nan * u.Mx, "index": np.nan, "elongation": np.nan}
    try:
        limb = limb_power_fit(smap)
        limb = [limb.mu_exponent, limb.mu_exponent_error, limb.east_west_excess, limb.east_west_excess_error]
    except ValueError:                       # too little of the disk for the fit
        limb = [np.nan] * 4
    return dict(
        clusters={"cluster_density": clusters["number_density"].to(u.Mm**-2),
                  "cluster_flux_density": clusters["flux_density"].to(u.G),
                  "cluster_p99": clusters["p99"].to(u.Mx), "cluster_index": float(clusters["index"]),
                  "cluster_elongation": float(clusters["elongation"])},
        limb=dict(zip(_LIMB_COLUMNS, limb)),
        values=values,
        numbers={"noise_box": noise.sigma.to_value(u.G), "noise_difference": noise.difference.to_value(u.G),
                 "mean": float(np.mean(values)), "median": float(np.median(values)),
                 "mean_abs": float(np.mean(np.abs(values))),
                 "mean_abs_centred": float(np.mean(np.abs(values - np.median(values)))),
                 "std": float(np.std(values)),
                 "p99": float(tails[99.0]), "p999": float(tails[99.9])},
        rings=rings_of_values(data, rho, ring_edges, u.G),
        spectrum=spectrum,
        quadrants=_quadrant_power(smap, box, spectrum.edges))


def _quadrant_power(smap, box, edges):
    """`quadrant_power_spectrum`'s power (G² Mm²) on ``edges``, NaN where the map does not hold the boxes."""
    try:
        return quadrant_power_spectrum(smap, box=box, edges=edges).power.to(u.G ** 2 * u.Mm ** 2)
    except ValueError:
        return np.full(edges.size - 1, np.nan) * u.G ** 2 * u.Mm ** 2


def compare_statistics(sim_map, obs_map, *, seed=0, max_radius=0.98, box=640 * u.arcsec,
                       ring_edges=RING_EDGES):
    """
    Measure two magnetograms the same way, as they are and with their noise matched.

    Parameters
    ----------
    sim_map, obs_map : `~sunpy.map.GenericMap`
        Magnetograms in G on comparable pixels (`gongsynth.compare` degrades
        the finer one to GONG before calling this).
    seed : int
        Seed of the noise added by `match_noise`.
    max_radius : float
        Outer radius of the histogram region, solar radii.
    box : `~astropy.units.Quantity`
        Side of the central square of the power spectrum (640″).
    ring_edges : sequence of float
        Centre-to-limb rings of the mean |B| (solar radii).

    Returns
    -------
    `StatisticsComparison`

    Examples
    --------
    >>> import numpy as np, astropy.units as u, sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> hdr = sunpy.map.make_fitswcs_header((300, 300), ref, scale=[2.5, 2.5] * u.arcsec / u.pix,
    ...                                     unit=u.G)
    >>> rng = np.random.default_rng(4)
    >>> a, b = (sunpy.map.Map(rng.normal(0, s, (300, 300)), hdr) for s in (3, 6))
    >>> stats = compare_statistics(a, b)
    >>> round(float(stats.table["ks"][0]), 2), bool(stats.table["ks"][2] < 0.02)  # matched: one law
    (0.16, True)
    """
    for name, m in (("sim_map", sim_map), ("obs_map", obs_map)):
        check_map(m, name, finite=True)
        if m.unit is None or not m.unit.is_equivalent(u.G):
            raise ValueError(f"{name}: expected a magnetogram in gauss, got unit {m.unit}")
    sim_map, obs_map = (m if m.unit == u.G
                        else sunpy.map.Map(m.quantity.to_value(u.G), {**m.meta, "bunit": "G"})
                        for m in (sim_map, obs_map))
    sim_matched, obs_matched, added = match_noise(sim_map, obs_map, seed=seed)
    # Matched maps share their originals' pixels: their distances from disk centre are measured once.
    rho = [disk_coordinates(m)[0] for m in (sim_map, obs_map)]
    first = _measure(sim_map, rho[0], max_radius, box, ring_edges)
    edges = first["spectrum"].edges      # every spectrum on the sim's annuli: ratios of like with like
    second = _measure(obs_map, rho[1], max_radius, box, ring_edges, edges)
    # The map that got no noise is measured once.
    measured = [first, second] + [_measure(m, r, max_radius, box, ring_edges, edges) if extra else same
                                  for m, r, extra, same in ((sim_matched, rho[0], added[0], first),
                                                            (obs_matched, rho[1], added[1], second))]
    columns = {"map": list(_ROWS), "noise_added": [0.0, 0.0, added[0], added[1]]}
    for key in measured[0]["numbers"]:
        columns[key] = [m["numbers"][key] for m in measured]
    ks, ks_centred = [], []
    for a, b in ((measured[0], measured[1]), (measured[2], measured[3])):
        va, vb = a["values"], b["values"]
        d = float(scipy.stats.ks_2samp(va, vb).statistic)
        dc = float(scipy.stats.ks_2samp(va - np.median(va), vb - np.median(vb)).statistic)
        ks += [d, d]
        ks_centred += [dc, dc]
    table = QTable({k: (v * u.G if k not in ("map",) else v) for k, v in columns.items()})
    table["ks"] = ks
    table["ks_centred"] = ks_centred
    for key in measured[0]["clusters"]:
        values = [m["clusters"][key] for m in measured]
        table[key] = u.Quantity(values) if isinstance(values[0], u.Quantity) else values
    for key in _LIMB_COLUMNS:
        table[key] = [m["limb"][key] for m in measured]

    names = ("sim", "obs", "sim_matched", "obs_matched")
    r0 = measured[0]["rings"]
    rings = QTable({"r_inner": r0["r_inner"], "r_outer": r0["r_outer"],
                    "pixels_sim": r0["pixels"], "pixels_obs": measured[1]["rings"]["pixels"]})
    for name, m in zip(names, measured):
        rings[name] = m["rings"]["mean_abs"].to(u.G)
    for name, m in zip(names, measured):
        rings[name + "_width"] = m["rings"]["robust_sigma"].to(u.G)
        rings[name + "_noise"] = m["rings"]["difference_sigma"].to(u.G)
    s0 = measured[0]["spectrum"]
    spectra = QTable({"wavelength": s0.wavelength})
    for name, m in zip(names, measured):
        spectra[name] = m["spectrum"].power.to(u.G ** 2 * u.Mm ** 2)
    for name, m in zip(names, measured):
        spectra[name + "_quadrants"] = m["quadrants"]
    for t in (rings, spectra):
        with np.errstate(invalid="ignore", divide="ignore"):
            t["ratio"] = np.asarray(t["sim"] / t["obs"])
            t["ratio_matched"] = np.asarray(t["sim_matched"] / t["obs_matched"])
    with np.errstate(invalid="ignore", divide="ignore"):
        spectra["ratio_quadrants"] = np.asarray(spectra["sim_quadrants"] / spectra["obs_quadrants"])
        spectra["ratio_quadrants_matched"] = np.asarray(spectra["sim_matched_quadrants"]
                                                        / spectra["obs_matched_quadrants"])
        rings["width_ratio"] = np.asarray(rings["sim_width"] / rings["obs_width"])
        rings["width_ratio_matched"] = np.asarray(rings["sim_matched_width"] / rings["obs_matched_width"])
    spectra.meta["box_pixels"] = (s0.box_pixels, measured[1]["spectrum"].box_pixels)
    spectra.meta["pixel_size"] = (s0.pixel_size, measured[1]["spectrum"].pixel_size)
    return StatisticsComparison(table=table, rings=rings, spectra=spectra)
