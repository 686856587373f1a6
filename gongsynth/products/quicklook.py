"""
The quick-look PNG of a run: every product map, on scales that show them.

Magnetograms and the truth share one grey scale, linear within ±20 G (the
noise) and logarithmic beyond, up to the field that 99.9 % of the magnetogram's
pixels stay under (at least GONG's ±150 G), so that spots and plage are not
saturated; colour bars carry arrows where values lie beyond their range.  In
a tiled scene each quadrant is labelled with its input magnification (1× is
the tile at its true size, seen at the instrument's own resolution), and a
full-disk run on a detector smaller than the disk says what part of the disk
it shows.
"""
import astropy.units as u
import numpy as np

__all__ = ["quicklook_figure", "field_norm"]

# Linear part of the magnetogram scale (G): the noise.
_LINEAR_FIELD = 20.0
# The smallest full scale of the magnetogram (GONG's display, G).
_MIN_FIELD = 150.0
# Dopplergram full scale (m/s).
_DOPPLER_LIMIT = 1500.0
# The most pixels a panel's image keeps along an axis: a map drawn at ~350 pixels gains nothing from
# more, and a 4096² map through matplotlib's resampling costs seconds and copies of itself in float64.
_DISPLAY_PIXELS = 1024


def _nice_ceiling(value):
    """The smallest 1, 2, 5 × 10**k at or above ``value``."""
    exponent = 10.0 ** np.floor(np.log10(value))
    for step in (1, 2, 5, 10):
        if step * exponent >= value:
            return float(step * exponent)
    return float(10 * exponent)


def field_norm(values):
    """
    The colour scale of a magnetogram: linear within ±20 G, logarithmic beyond.

    Parameters
    ----------
    values : array_like
        Field values in G (NaN ignored).

    Returns
    -------
    norm : `matplotlib.colors.SymLogNorm`
        Symmetric, up to the 99.9th percentile of |B| rounded up to 1, 2 or
        5 × 10ⁿ G (at least 150 G).
    extend : str
        ``"both"``, ``"min"``, ``"max"`` or ``"neither"``: where values lie beyond the scale.

    Examples
    --------
    >>> import numpy as np
    >>> norm, extend = field_norm(np.array([-3000.0, 0.0, 10.0] + [40.0] * 5000))
    >>> norm.vmax, extend
    (200.0, 'min')
    """
    import matplotlib.colors as mcolors

    data = np.asarray(values, dtype=float)
    finite = data[np.isfinite(data)]
    top = float(np.percentile(np.abs(finite), 99.9)) if finite.size else _MIN_FIELD
    limit = _nice_ceiling(max(top, _MIN_FIELD))
    return (mcolors.SymLogNorm(_LINEAR_FIELD, linscale=0.5, vmin=-limit, vmax=limit, base=10),
            _extend(finite, -limit, limit))


def _extend(finite, low, high):
    below = bool(finite.size) and bool(finite.min() < low)
    above = bool(finite.size) and bool(finite.max() > high)
    return {(True, True): "both", (True, False): "min", (False, True): "max"}.get((below, above), "neither")


def _panels(result):
    """(title, map, norm, extend, colour-bar label) for each product of the result."""
    import matplotlib.colors as mcolors

    norm, extend = field_norm(result.magnetogram.data)
    panels = [("magnetogram", result.magnetogram, norm, extend)]
    if result.truth_psf is not None:
        panels.append(("truth seen through the PSF", result.truth_psf, norm,
                       _extend(_finite(result.truth_psf), norm.vmin, norm.vmax)))
    if result.truth is not None:
        panels.append(("truth (input B_LOS per pixel)", result.truth, norm,
                       _extend(_finite(result.truth), norm.vmin, norm.vmax)))
    velocity = _finite(result.doppler)
    panels.append(("Dopplergram", result.doppler, mcolors.Normalize(-_DOPPLER_LIMIT, _DOPPLER_LIMIT),
                   _extend(velocity, -_DOPPLER_LIMIT, _DOPPLER_LIMIT)))
    light = _finite(result.continuum)
    low, high = (np.percentile(light, [0.5, 99.5]) if light.size else (0.0, 1.0))
    panels.append(("pseudo-continuum", result.continuum, mcolors.Normalize(low, high),
                   _extend(light, low, high)))
    return panels


def _finite(smap):
    data = np.asarray(smap.data, dtype=float)
    return data[np.isfinite(data)]


def _display(data, extent):
    """
    The image a panel draws and its extent: ``data`` averaged over blocks of f × f pixels (NaN
    ignored; a block of NaN stays NaN), f the smallest factor that brings both axes to at most
    `_DISPLAY_PIXELS`, the rows and columns beyond the last whole block left out of the extent too.

    Examples
    --------
    >>> data = np.ones((2050, 2050))
    >>> data[:3, :3] = np.nan                   # one whole block of sky
    >>> image, extent = _display(data, (0.0, 2050.0, 0.0, 2050.0))
    >>> image.shape, extent, bool(np.isnan(image[0, 0])), float(image[1, 1])
    ((683, 683), (0.0, 2049.0, 0.0, 2049.0), True, 1.0)
    """
    ny, nx = data.shape
    f = -(-max(ny, nx) // _DISPLAY_PIXELS)
    if f == 1:
        return data, extent
    my, mx = ny // f, nx // f
    blocks = np.asarray(data[:my * f, :mx * f]).reshape(my, f, mx, f)
    finite = np.isfinite(blocks)
    total = np.where(finite, blocks, 0).sum(axis=(1, 3), dtype=np.float64)
    count = finite.sum(axis=(1, 3))
    with np.errstate(invalid="ignore", divide="ignore"):
        image = (total / count).astype(np.float32)
    left, right, bottom, top = extent
    return image, (left, left + (right - left) * mx * f / nx, bottom, bottom + (top - bottom) * my * f / ny)


def _field_ticks(limit):
    """Colour-bar ticks of a field scale: 0, the linear range and the decades up to the limit."""
    positive = [_LINEAR_FIELD] + [10.0 ** k for k in range(2, 6) if 10.0 ** k < 0.7 * limit] + [limit]
    return [-t for t in positive[::-1]] + [0.0] + positive


def _histograms(ax, result):
    """Histograms of the measured field and the truths (log counts), on the magnetogram's scale."""
    limit = _field_ticks(field_norm(result.magnetogram.data)[0].vmax)[-1]
    bins = np.linspace(-min(limit, 500.0), min(limit, 500.0), 201)
    for label, smap, colour in (("magnetogram", result.magnetogram, "k"),
                                ("truth through the PSF", result.truth_psf, "C0"),
                                ("truth", result.truth, "C1")):
        if smap is not None:
            ax.hist(_finite(smap), bins=bins, histtype="step", color=colour, label=label)
    ax.set_yscale("log")
    ax.set_xlabel("B_LOS [G] (|B| > 500 G not shown)" if limit > 500 else "B_LOS [G]", fontsize=8)
    ax.set_ylabel(f"pixels per {bins[1] - bins[0]:g} G bin", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.set_title("field histograms", fontsize=10)
    ax.legend(fontsize=7)


_SUPERSCRIPTS = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def _decade_ticks(bar, top, unit):
    """Label a colour bar's ticks in units of 10^k ``unit`` (k from ``top``); returns the axis label."""
    from matplotlib.ticker import FuncFormatter

    power = int(np.floor(np.log10(abs(top)))) if top else 0
    if abs(power) < 3:
        return f"[{unit}]"
    bar.ax.yaxis.set_major_formatter(FuncFormatter(lambda value, _: f"{value / 10.0 ** power:g}"))
    # Unicode superscripts: a mathtext label would cost the parser's ~0.3 s start-up.
    return f"[10{str(power).translate(_SUPERSCRIPTS)} {unit}]"


def _sky_extent(smap):
    """
    (left, right, bottom, top) of a north-up product map's pixel edges in helioprojective arcsec.

    Plain axes with this extent replace WCS axes in the quick-look (a second
    per panel less to draw): gongsynth's products are never rotated, and the
    tangent projection departs from a linear scale by < 1e-5 of the field
    even over the whole disk, far below a pixel.
    """
    if not np.allclose(smap.rotation_matrix, np.eye(2)):
        raise ValueError("the quick-look draws north-up maps; this map is rotated")
    ny, nx = smap.data.shape
    corners = smap.wcs.pixel_to_world_values([-0.5, nx - 0.5], [-0.5, ny - 0.5])
    # Helioprojective longitude comes back in [0, 360) deg: east of centre is near 360.
    (left, right), (bottom, top) = (u.Quantity(c, unit).to(u.deg).value
                                    for c, unit in zip(corners, smap.wcs.world_axis_units))
    left, right = ((angle + 180.0) % 360.0 - 180.0 for angle in (left, right))
    return tuple(float(angle) * 3600.0 for angle in (left, right, bottom, top))


def _label_quadrants(ax, resolution_map, extent):
    """Write each tiled region's input magnification (1× = the tile at its true size) at its centre."""
    levels = np.unique(resolution_map)
    if levels.size < 2:
        return
    ny, nx = resolution_map.shape
    left, right, bottom, top = extent
    for level in levels:
        rows, cols = np.nonzero(resolution_map == level)
        x = left + (cols.mean() + 0.5) / nx * (right - left)
        y = bottom + (rows.mean() + 0.5) / ny * (top - bottom)
        ax.text(x, y, f"{level:g}×", ha="center", va="center", fontsize=11,
                color="C1", fontweight="bold",
                bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": "none", "alpha": 0.8})


def _field_of_view(result):
    """A note on what the detector covers in full-disk mode, or ''."""
    smap = result.magnetogram
    ny, nx = smap.data.shape
    width = (nx * smap.scale.axis1 * u.pix).to(u.arcsec)
    diameter = 2 * smap.rsun_obs.to(u.arcsec)
    if result.config.mode != "full-disk":
        return f"field of view {width.value:.0f}″ × {(ny * smap.scale.axis2 * u.pix).to_value(u.arcsec):.0f}″"
    if width < diameter:
        return (f"full-disk mode, but the {nx}-pixel detector spans {width.value:.0f}″ of the "
                f"{diameter.value:.0f}″ disk: only its centre is shown (use --shape "
                f"{int(np.ceil((diameter / smap.scale.axis1 / u.pix).to_value(u.one))) + 8} or more "
                f"for the whole disk)")
    return f"full disk, {width.value:.0f}″ field of view"


# Fixed layout in inches (a layout engine costs a second rendering):
# a cell per panel, and within it (left, bottom, width, height) of the map, its
# colour bar (85 % of the map's height) and the histogram; the title's band on top.
_CELL = (4.6, 4.0)
_TITLE = 0.7
_MAP = (0.85, 0.6, 2.85, 2.85)
_BAR = (3.83, 0.6 + 0.075 * 2.85, 0.12, 0.85 * 2.85)
_PLOT = (0.85, 0.6, 3.2, 2.85)


def _rect(fig, index, ncols, nrows, box):
    """Figure-fraction rectangle of ``box`` (inches in a cell) in cell ``index`` (row-major, top first)."""
    width, height = fig.get_size_inches()
    row, col = divmod(index, ncols)
    left = col * _CELL[0] + box[0]
    bottom = (nrows - 1 - row) * _CELL[1] + box[1]
    return (left / width, bottom / height, box[2] / width, box[3] / height)


def quicklook_figure(result):
    """
    A figure with every product map of a run, each with its colour bar.

    Parameters
    ----------
    result : `~gongsynth.pipeline.SimulationResult`

    Returns
    -------
    `matplotlib.figure.Figure`
        Not attached to pyplot (save it with ``savefig``).

    Examples
    --------
    >>> import astropy.units as u
    >>> from gongsynth import simulate
    >>> result = simulate(duration=1 * u.min, detector_shape=16, resolutions=(1,), seed=1,
    ...                   photosphere_shape=(64, 64), photosphere_pixel_size=1536 * u.km,
    ...                   sun="milne-eddington", progress=False)
    >>> len(quicklook_figure(result).axes)   # five maps, their colour bars and the histograms
    11
    """
    from matplotlib.figure import Figure

    panels = _panels(result)
    ncols = 3
    nrows = int(np.ceil(len(panels) / ncols))
    fig = Figure(figsize=(_CELL[0] * ncols, _CELL[1] * nrows + _TITLE))
    units = {"magnetogram": "B_LOS [G]", "Dopplergram": "v_LOS [m/s], + away",
             "pseudo-continuum": "[DN]"}
    extent = _sky_extent(result.magnetogram)
    for i, (title, smap, norm, extend) in enumerate(panels):
        ax = fig.add_axes(_rect(fig, i, ncols, nrows, _MAP))
        shown, shown_extent = _display(smap.data, extent)
        image = ax.imshow(shown, origin="lower", extent=shown_extent, cmap=smap.cmap, norm=norm,
                          interpolation="antialiased")
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("Solar X [arcsec]", fontsize=8)
        ax.set_ylabel("Solar Y [arcsec]", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.locator_params(nbins=4)
        if any(smap is m for m in (result.magnetogram, result.truth, result.truth_psf)):
            _label_quadrants(ax, result.resolution_map, extent)
        bar = fig.colorbar(image, cax=fig.add_axes(_rect(fig, i, ncols, nrows, _BAR)), extend=extend)
        if title not in units or title == "magnetogram":
            bar.set_ticks(_field_ticks(norm.vmax))
            bar.set_ticklabels([f"{t:g}" for t in _field_ticks(norm.vmax)])
        label = units.get(title, "B_LOS [G]")
        if title == "pseudo-continuum":  # decades in the label, not as an offset text on the bar's corner
            label = _decade_ticks(bar, norm.vmax, "DN")
        bar.set_label(label, fontsize=8)
        bar.ax.tick_params(labelsize=7)
    if len(panels) < nrows * ncols:
        _histograms(fig.add_axes(_rect(fig, len(panels), ncols, nrows, _PLOT)), result)
    magnifications = np.unique(result.resolution_map)
    note = (f"; input magnified {', '.join(f'{m:g}×' for m in magnifications)} by quadrant (1× = true size)"
            if magnifications.size > 1 else "")
    head = result.summary().splitlines()
    fig.suptitle(f"{head[0]}\n{head[1].strip()}\n{_field_of_view(result)}{note}", fontsize=9)
    return fig
