r"""
The offset between the images of a magnetograph's two polarisation states, read from its own maps.

A magnetograph such as GONG measures the line's shift in each circular
polarisation, :math:`v^\pm`, and takes the field from their difference,
:math:`B = g_v (v^+ - v^-)/2` (``gauss_per_velocity``, GONG paper I, Eq. 9).
If the two states' images do not lie on the same pixels, but are offset by
:math:`\boldsymbol\delta` (:math:`v^\pm(\mathbf x) = v(\mathbf x \pm
\boldsymbol\delta/2)`), the difference holds the Doppler shift's gradient:

.. math::

    B_\mathrm{false} = \tfrac{g_v}{2}\,\boldsymbol\delta\cdot\nabla v .

GONG alternates the two states every second and lists their images not
matching in space among its magnetograms' problems (*Status of GONG+
magnetograms*, MUG meeting presentation); the real Big Bear map of
2009-09-05 carries an east-west fingerprint, part of which an offset of about
0.05 pixel would leave (noise guide, ``scripts/limb_anisotropy.py``).

`state_offset` measures :math:`\boldsymbol\delta` from a magnetogram and the
Dopplergram of the same observation: the least-squares fit of the first to
the second's gradient, both high-passed alike (which takes out the solar
rotation's uniform gradient and the magnetogram's zero-point surface), over
the weak-field pixels of the disk.  The Sun's own correlations between field
and flow (the network in the supergranules' downflows) change sign from one
limb to the other and between the polarities, where a fixed offset's does
not, so they average out over the disk.  Its errors are a block jackknife over a grid of
the disk, since neither map's residual is white.  With ``stretch`` it also
fits an offset that grows across the image (two images at slightly different
scales): a shift reads the same everywhere, a stretch zero at disk centre
and most at the limbs.
"""
import astropy.units as u
import numpy as np
from astropy.table import QTable
from scipy.ndimage import gaussian_filter

from gongsynth.analysis.disk import check_map, map_values, pixel_to_helioprojective
from gongsynth.validation import check_quantity

__all__ = ["state_offset", "offset_field"]

# σ (pixels) of the average of |B| that finds the strong field left out of the fit.
_STRONG_SMOOTHING = 2.0


def _highpass(values, inside, sigma):
    """``values`` less their Gaussian mean over the pixels ``inside`` (σ in pixels); 0 outside."""
    filled = np.where(inside, values, 0.0)
    weight = gaussian_filter(inside.astype(float), sigma)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = gaussian_filter(filled, sigma) / weight
    return np.where(inside, values - mean, 0.0)


def _in_unit(values, unit, wanted, name):
    """``values`` of a map in ``unit`` converted to ``wanted`` (a map without a unit is taken as in it)."""
    if unit is None or unit == u.one:
        return values
    try:
        return (values * unit).to_value(wanted)
    except u.UnitConversionError as exc:
        raise ValueError(f"{name} must be in units of {wanted}, got {unit}") from exc


def _per_velocity(gauss_per_velocity):
    """g_v in G per m/s: the given Quantity, or GONG's."""
    if gauss_per_velocity is None:
        from gongsynth.instruments.gong.parameters import GONGInstrument

        gauss_per_velocity = GONGInstrument().gauss_per_velocity
    return check_quantity(gauss_per_velocity, u.G / (u.m / u.s), "gauss_per_velocity").to_value(
        u.G / (u.m / u.s))


def _disk_offsets(smap):
    """Each pixel's helioprojective offsets from disk centre, x and y, in solar radii."""
    ny, nx = smap.data.shape
    tx, ty = pixel_to_helioprojective(smap, *np.mgrid[:ny, :nx][::-1])
    return tuple(np.asarray(t) / smap.rsun_obs.to_value(u.arcsec) for t in (tx, ty))


def offset_field(doppler, offset_x, offset_y=0.0, gauss_per_velocity=None, *, stretch=None):
    r"""
    The field an offset δ between the states' images makes of a Dopplergram: g_v δ·∇v / 2.

    The forward model that `state_offset` inverts, for ablations: add it to a
    magnetogram of the same pixels.

    Parameters
    ----------
    doppler : `~sunpy.map.GenericMap`
        Doppler shift (any unit of speed; m/s if it has none).
    offset_x, offset_y : float
        δ along the map's x and y axes (pixels); with ``stretch``, at disk centre.
    gauss_per_velocity : `~astropy.units.Quantity`, optional
        :math:`g_v` in G / (m/s) (default: GONG's).
    stretch : 2 × 2 array-like of float, optional
        An offset that grows across the image, as `state_offset` fits it
        with ``stretch=True``: δ(x, y) = δ₀ + S (x, y), S =
        ``[[stretch_xx, stretch_xy], [stretch_yx, stretch_yy]]`` in pixels
        per solar radius, x and y the helioprojective offsets from disk
        centre in solar radii (default: none).

    Returns
    -------
    `~sunpy.map.GenericMap`
        The field (G) on the Dopplergram's pixels; 0 where its gradient is
        undefined (off the disk and on the disk's outermost pixels).

    Examples
    --------
    >>> import numpy as np, astropy.units as u, sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> header = sunpy.map.make_fitswcs_header((8, 8), ref, scale=[5, 5] * u.arcsec / u.pix,
    ...                                        unit=u.m / u.s)
    >>> ramp = sunpy.map.Map(100.0 * np.arange(8)[None, :] * np.ones((8, 1)), header)   # 100 m/s per pixel
    >>> round(float(offset_field(ramp, 0.1, gauss_per_velocity=0.7 * u.G / (u.m / u.s)).data[4, 4]), 3)
    3.5
    """
    import sunpy.map

    check_map(doppler, "doppler")
    for name, value in (("offset_x", offset_x), ("offset_y", offset_y)):
        if isinstance(value, bool) or not np.isfinite(value):
            raise ValueError(f"{name} must be a finite number of pixels, got {value!r}")
    if stretch is not None:
        stretch = np.asarray(stretch, dtype=float)
        if stretch.shape != (2, 2) or not np.all(np.isfinite(stretch)):
            raise ValueError("stretch must be a finite 2 × 2 matrix (pixels per solar radius), "
                             f"got {stretch!r}")
    g_v = _per_velocity(gauss_per_velocity)
    velocity = _in_unit(map_values(doppler), doppler.unit, u.m / u.s, "doppler")
    grad_y, grad_x = np.gradient(velocity)
    if stretch is not None:
        x_sun, y_sun = _disk_offsets(doppler)
        offset_x = offset_x + stretch[0, 0] * x_sun + stretch[0, 1] * y_sun
        offset_y = offset_y + stretch[1, 0] * x_sun + stretch[1, 1] * y_sun
    field = np.nan_to_num(0.5 * g_v * (offset_x * grad_x + offset_y * grad_y))
    meta = doppler.meta.copy()
    meta["bunit"] = "G"
    return sunpy.map.Map(field, meta)


def _fit(gradients, field):
    """Least-squares coefficients of ``field`` on the columns of ``gradients``."""
    return np.linalg.lstsq(gradients, field, rcond=None)[0]


def state_offset(magnetogram, doppler, gauss_per_velocity=None, *, highpass=10.0, max_radius=0.95,
                 weak=50 * u.G, blocks=6, stretch=False):
    r"""
    The offset δ between the two polarisation states' images, from the field's fit to the Doppler gradient.

    Parameters
    ----------
    magnetogram : `~sunpy.map.GenericMap`
        Line-of-sight field (any unit of magnetic flux density; G if it has none).
    doppler : `~sunpy.map.GenericMap`
        The same observation's Doppler shift on the same pixels (any unit of
        speed; m/s if it has none).
    gauss_per_velocity : `~astropy.units.Quantity`, optional
        :math:`g_v` in G / (m/s) (default: GONG's,
        `gongsynth.GONGInstrument.gauss_per_velocity`).
    highpass : float
        σ (pixels) of the Gaussian mean taken out of both maps (default 10).
    max_radius : float
        Pixels within this fraction of the disk's radius are fitted (default 0.95).
    weak : `~astropy.units.Quantity`
        Pixels where the high-passed field's magnitude, averaged over a
        Gaussian of σ = 2 pixels, exceeds this are left out: sunspots and
        plage carry crosstalks of their own (default 50 G).
    blocks : int
        The jackknife's grid: ``blocks`` × ``blocks`` squares over the
        image, each left out in turn (default 6).
    stretch : bool
        Also fit an offset that grows across the image (the two images at
        slightly different scales, or one sheared): δ(x, y) = δ₀ + S (x, y)
        with x and y the helioprojective offsets from disk centre in solar
        radii.  ``offset_x`` and ``offset_y`` are then δ₀, the offset at disk
        centre, and ``stretch_xx``, ``stretch_xy``, ``stretch_yx``,
        ``stretch_yy`` the matrix S (pixels per solar radius: S_xy is how much
        δ_x grows with y), with their errors.

    Returns
    -------
    `~astropy.table.QTable`
        One row: ``offset_x`` and ``offset_y`` (pixels, along the map's x and
        y axes), their jackknife standard errors ``offset_x_error`` and
        ``offset_y_error``, the same in arcsec (``offset_x_arcsec``,
        ``offset_y_arcsec``), the pixels fitted (``pixels``) and, with
        ``stretch``, its four coefficients and their errors.

    Raises
    ------
    ValueError
        If the maps' shapes differ, a parameter is out of range, or fewer than
        1000 pixels are left to fit.

    Examples
    --------
    >>> import numpy as np, astropy.units as u, sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from scipy.ndimage import gaussian_filter
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> header = sunpy.map.make_fitswcs_header((400, 400), ref, scale=[5, 5] * u.arcsec / u.pix)
    >>> rng = np.random.default_rng(0)
    >>> v = 3000 * gaussian_filter(rng.normal(size=(400, 400)), 3)      # m/s
    >>> b = rng.normal(0, 3, (400, 400)) + 0.7038 * 0.2 * np.gradient(v, axis=1) / 2
    >>> row = state_offset(sunpy.map.Map(b, header), sunpy.map.Map(v, header))[0]
    >>> bool(abs(row["offset_x"].value - 0.2) < 4 * row["offset_x_error"].value)
    True
    """
    check_map(magnetogram, "magnetogram")
    check_map(doppler, "doppler")
    if magnetogram.data.shape != doppler.data.shape:
        raise ValueError(f"doppler must have the magnetogram's shape {magnetogram.data.shape}, "
                         f"got {doppler.data.shape}")
    g_v = _per_velocity(gauss_per_velocity)
    if not (np.isfinite(highpass) and highpass > 0):
        raise ValueError(f"highpass must be a positive number of pixels, got {highpass!r}")
    if not 0 < max_radius <= 1:
        raise ValueError(f"max_radius must lie in (0, 1], got {max_radius!r}")
    if isinstance(blocks, bool) or not isinstance(blocks, (int, np.integer)) or blocks < 2:
        raise ValueError(f"blocks must be an int >= 2, got {blocks!r}")
    weak_g = check_quantity(weak, u.G, "weak").to_value(u.G)

    field = _in_unit(map_values(magnetogram), magnetogram.unit, u.G, "magnetogram")
    velocity = _in_unit(map_values(doppler), doppler.unit, u.m / u.s, "doppler")
    x_sun, y_sun = _disk_offsets(magnetogram)
    rho = np.hypot(x_sun, y_sun)
    inside = np.isfinite(field) & np.isfinite(velocity) & (np.nan_to_num(rho, nan=np.inf) < max_radius)
    grad_y, grad_x = np.gradient(np.where(inside, velocity, 0.0))
    # The gradient's central differences reach one pixel out: keep pixels whose neighbours are inside.
    interior = np.zeros_like(inside)
    interior[1:-1, 1:-1] = (inside[1:-1, 1:-1] & inside[:-2, 1:-1] & inside[2:, 1:-1]
                            & inside[1:-1, :-2] & inside[1:-1, 2:])
    # The field and every term of the model are high-passed alike, so that the fit stays exact
    # (a filter does not commute with a stretch's factor of position).
    field_hp = _highpass(field, interior, highpass)
    # Strong field is found on the field's magnitude averaged over a few pixels: a cut on each pixel
    # would select on the offset's own small-scale field and bias the fit (by -1.3 % on a Big Bear run).
    used = interior & (gaussian_filter(np.abs(field_hp), _STRONG_SMOOTHING) < weak_g)
    if used.sum() < 1000:
        raise ValueError(f"state_offset: only {int(used.sum())} pixels to fit; need at least 1000")
    terms = [grad_x, grad_y]
    if stretch:
        terms += [x_sun * grad_x, y_sun * grad_x, x_sun * grad_y, y_sun * grad_y]
    columns = [_highpass(term, interior, highpass)[used] for term in terms]
    design = 0.5 * g_v * np.column_stack(columns)
    target = field_hp[used]
    offset = _fit(design, target)
    rows, cols = np.nonzero(used)
    block = (rows * blocks // field.shape[0]) * blocks + cols * blocks // field.shape[1]
    present = np.unique(block)
    leave_out = np.array([_fit(design[block != b], target[block != b]) for b in present])
    n = present.size
    error = np.sqrt((n - 1) / n * np.sum((leave_out - leave_out.mean(axis=0)) ** 2, axis=0))
    scale = magnetogram.scale[0].to_value(u.arcsec / u.pix), magnetogram.scale[1].to_value(u.arcsec / u.pix)
    table = QTable()
    table["offset_x"] = [offset[0]] * u.pix
    table["offset_y"] = [offset[1]] * u.pix
    table["offset_x_error"] = [error[0]] * u.pix
    table["offset_y_error"] = [error[1]] * u.pix
    table["offset_x_arcsec"] = [offset[0] * scale[0]] * u.arcsec
    table["offset_y_arcsec"] = [offset[1] * scale[1]] * u.arcsec
    table["pixels"] = [int(used.sum())]
    if stretch:
        per_radius = u.pix / u.R_sun
        for k, name in enumerate(("stretch_xx", "stretch_xy", "stretch_yx", "stretch_yy"), start=2):
            table[name] = [offset[k]] * per_radius
            table[f"{name}_error"] = [error[k]] * per_radius
    return table
