"""
The compare figure: both maps with their noise boxes, noise against distance from disk centre,
histograms, and (with the statistics table) spatial power spectra and centre-to-limb rings.
"""
from __future__ import annotations

import astropy.units as u
import numpy as np
from astropy.coordinates import SkyCoord

__all__ = ["plot_comparison", "DISPLAY_LIMIT"]

#: The maps' grey scale saturates at ± this many gauss (the paper's Fig. 1: ±150 G).
DISPLAY_LIMIT = 150


def plot_comparison(report, fig):
    """
    Draw a `~gongsynth.analysis.compare.ComparisonReport` on ``fig``.

    Parameters
    ----------
    report : `~gongsynth.analysis.compare.ComparisonReport`
    fig : `matplotlib.figure.Figure`

    Returns
    -------
    `matplotlib.figure.Figure`
        ``fig``, with the maps (colour bars, noise boxes), the noise panel,
        the histograms on log axes and, with a statistics table, the spectra
        and the rings.
    """
    import matplotlib.colors as mcolors

    limit = DISPLAY_LIMIT
    colours = {"sim": "C0", "obs": "C3"}
    ncols = 3 if report.statistics is None else 4       # a fourth column for the spectra and rings
    grid = fig.add_gridspec(2, ncols, left=0.06 if ncols == 3 else 0.05, right=0.98, bottom=0.07, top=0.86,
                            wspace=0.42, hspace=0.42)
    for i, (key, summ) in enumerate((("sim", report.sim), ("obs", report.obs))):
        ax = fig.add_subplot(grid[0, i], projection=summ.map)
        image = summ.map.plot(axes=ax, cmap="gray", norm=mcolors.Normalize(-limit, limit), title=False)
        ax.set_title(f"{key}: {summ.description}\n{summ.pixel_scale.to_value(u.arcsec):.2f}″ pixels"
                     + (", degraded to GONG" if summ.degraded else ""), fontsize=8)
        for coord, axis in zip(ax.coords, ("Solar X", "Solar Y")):
            coord.set_axislabel(axis, fontsize=8)
            coord.set_ticklabel(size=7, exclude_overlapping=True)
            coord.set_ticks(number=4)
        values = summ.values
        extend = {(True, True): "both", (True, False): "min", (False, True): "max"}.get(
            (bool(values.size and values.min() < -limit), bool(values.size and values.max() > limit)),
            "neither")
        bar = fig.colorbar(image, ax=ax, shrink=0.85, extend=extend)
        bar.set_label(f"B_LOS [G], saturated at ±{limit} G", fontsize=7)
        bar.ax.tick_params(labelsize=7)
        c = summ.noise.box_centres.to_value(u.arcsec)
        q = summ.noise.quietest
        ax.plot_coord(SkyCoord(c[:, 0] * u.arcsec, c[:, 1] * u.arcsec, frame=summ.map.coordinate_frame),
                      "s", ms=3, mfc="none", mec=colours[key], lw=0)
        ax.plot_coord(SkyCoord(c[q, 0] * u.arcsec, c[q, 1] * u.arcsec, frame=summ.map.coordinate_frame),
                      "s", ms=6, mfc="none", mec="yellow", lw=0)
    ax = fig.add_subplot(grid[0, 2])
    for key, summ in (("sim", report.sim), ("obs", report.obs)):
        c = summ.noise.box_centres.to_value(u.arcsec)
        r = np.hypot(c[:, 0], c[:, 1]) / summ.map.rsun_obs.to_value(u.arcsec)
        ax.plot(r, summ.noise.box_sigma.to_value(u.G), "o", color=colours[key], ms=4, mfc="none",
                label=f"{key}: robust σ per box")
        ax.axhline(summ.noise.sigma.to_value(u.G), color=colours[key], lw=1,
                   label=f"{key}: quietest box σ = {summ.noise.sigma.to_value(u.G):.2f} G")
        ax.axhline(summ.noise.difference.to_value(u.G), color=colours[key], lw=1, ls=":",
                   label=f"{key}: pixel-difference σ = {summ.noise.difference.to_value(u.G):.2f} G")
    ax.set_xlabel("box distance from disk centre [R☉]", fontsize=8)
    ax.set_ylabel("noise [G]", fontsize=8)
    ax.set_yscale("log")
    ax.tick_params(labelsize=7)
    ax.set_title(f"noise in {report.sim.noise.box_size.to_value(u.arcsec):.0f}″ boxes "
                 "(squares on the maps; yellow: quietest)", fontsize=8)
    low, high = ax.get_ylim()
    ax.set_ylim(low, high * (high / low) ** 0.6)  # room above the points for the legend
    ax.legend(fontsize=6, loc="upper right", ncol=2, framealpha=0.9)

    _plot_histograms(fig.add_subplot(grid[1, 0]), report, colours, "histogram", "B_LOS [G]",
                     "on-disk histogram")
    _plot_histograms(fig.add_subplot(grid[1, 1]), report, colours, "abs_histogram", "|B_LOS| [G]",
                     "on-disk |B| histogram", log_x=True)

    if report.statistics is not None:
        report.statistics.plot_spectra(fig.add_subplot(grid[1, 2]), colours)
        report.statistics.plot_rings(fig.add_subplot(grid[0, 3]), colours)
    ax = fig.add_subplot(grid[1, ncols - 1])
    ax.axis("off")
    ax.text(0, 1, report.summary(figure=True), family="monospace", fontsize=7, va="top", ha="left",
            transform=ax.transAxes)
    fig.suptitle(f"sim = {report.sim.label}\nobs = {report.obs.label}", fontsize=9)
    return fig


def _plot_histograms(ax, report, colours, attribute, xlabel, title, *, log_x=False):
    """Histograms (``attribute`` of each map summary) of both maps on log axes."""
    for key, summ in (("sim", report.sim), ("obs", report.obs)):
        h = getattr(summ, attribute)
        ax.stairs(np.where(h.density.value > 0, h.density.value, np.nan), h.edges.to_value(u.G),
                  color=colours[key], label=key)
    if log_x:
        ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(xlabel, fontsize=8)
    ax.set_ylabel("probability density [1/G]", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=8)

