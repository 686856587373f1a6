r"""
How the weak field's power changes over the disk: its fall toward the limb and its east-west excess.

A radial field seen at heliocentric angle θ reads :math:`B\cos\theta`, so the
power of a quiet network of the same strength everywhere falls toward the
limb about as :math:`\mu^{1\text{-}2}` (μ = cos θ).  Anything isotropic on the
Sun or in the atmosphere gives the same power at the same μ east-west and
north-south of disk centre.  `limb_power_fit` measures both on one map:

- the map, less its median, is clipped to ±``clip`` (15 G): the weak field,
  so that a few network clusters or a spot do not set a box's power;
- the disk within ``disk_edge`` (0.97 R☉) is cut into ``box`` squares
  (160″) on a square grid of that step from the disk's east and south
  edges (it need not pass through disk centre); a box is left out if more than
  ``strong_fraction`` (2 %) of its pixels lie beyond ``strong`` (50 G), i.e.
  an active region, or if the map does not hold it whole;
- the power P of each box at ``band`` (20-50 Mm, the network's scales;
  `gongsynth.analysis.power_spectrum.power_spectrum`, distances at disk
  centre) is fitted by least squares as

  .. math::

      \ln P = a + b \ln\mu + c\,(x^2 - y^2),

  with x and y the box centre's east-west and north-south offsets from disk
  centre in solar radii.  ``mu_exponent`` b says how fast the weak field's
  power falls toward the limb, ``east_west_excess`` c its excess east-west
  over north-south at equal μ.  Their errors are the least-squares ones,
  with the residuals' scatter as each box's error.

`axis_anisotropy` measures the other face of the same question, on scales
below the network's: in boxes on the east-west and north-south axes, the
power of the wavevectors nearer the map's x axis over that of those nearer
its y axis (``power_spectrum``'s ``direction``).  Foreshortening alone
gives the limb's radial direction the excess: x on the east-west axis, y on
the north-south one.

Measured on real maps (``scripts/limb_anisotropy.py``, the noise guide's
"The limb excess over the whole disk"): the real Big Bear GONG map of
2009-09-05 has b = −0.08 ± 0.21 and c = +0.49 ± 0.14, the real MDI map of
2010-10-15 b = 1.07 ± 0.26 and c = −0.29 ± 0.16, gongsynth's runs of both
b = 0.7-1.4 and c = −0.12 to +0.21.  `gongsynth.analysis.map_statistics`
reports b and c for every pair of maps it compares.
"""
from dataclasses import dataclass

import astropy.units as u
import numpy as np
import sunpy.map
from astropy.table import QTable

from gongsynth.analysis.disk import check_map, map_values
from gongsynth.analysis.power_spectrum import box_origin, power_spectrum
from gongsynth.validation import check_scalar

__all__ = ["LimbPowerFit", "limb_power_fit", "axis_anisotropy", "weak_field", "WEAK_CLIP", "STRONG_FIELD",
           "LIMB_BOX", "LIMB_BAND", "ANISOTROPY_BANDS", "ANISOTROPY_RADII"]

#: The weak field's clip about the median, and the field beyond which a pixel counts as strong.
WEAK_CLIP, STRONG_FIELD = 15 * u.G, 50 * u.G
#: Side of the boxes, and the band of the fit (the network's scales).
LIMB_BOX, LIMB_BAND = 160 * u.arcsec, (20 * u.Mm, 50 * u.Mm)
#: Bands of the anisotropy (below the network's scales) and the radii of its boxes (solar radii).
ANISOTROPY_BANDS, ANISOTROPY_RADII = ((3.7 * u.Mm, 7 * u.Mm), (7 * u.Mm, 15 * u.Mm)), (0.7, 0.85)
# The fit's three coefficients need more boxes than that to have a scatter.
_MIN_BOXES = 6


@dataclass(frozen=True)
class LimbPowerFit:
    """
    The fit of `limb_power_fit`.

    Attributes
    ----------
    mu_exponent, mu_exponent_error : float
        b of ln P = a + b ln μ + c (x² − y²), and its standard error.
    east_west_excess, east_west_excess_error : float
        c, and its standard error.
    boxes : int
        Boxes in the fit.
    """

    mu_exponent: float
    mu_exponent_error: float
    east_west_excess: float
    east_west_excess_error: float
    boxes: int


def weak_field(smap, clip=WEAK_CLIP, strong=STRONG_FIELD):
    """
    The map less its median, clipped to ±``clip``, and where it is strong.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        A magnetogram in G (or another unit of flux density; a map without a unit is taken as in G).
    clip, strong : `~astropy.units.Quantity`
        The clip (15 G) and the field beyond which a pixel is strong (50 G), both about the median.

    Returns
    -------
    weak : `~sunpy.map.GenericMap`
        The clipped map (NaN stays NaN).
    is_strong : `numpy.ndarray`
        Boolean, True where ``|B - median| > strong``.

    Examples
    --------
    >>> import astropy.units as u
    >>> import numpy as np
    >>> import sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> m = sunpy.map.Map(np.array([[2.0, 2.0, 2.0], [2.0, 40.0, 100.0], [-80.0, 2.0, 2.0]]),
    ...                   sunpy.map.make_fitswcs_header((3, 3), ref, scale=[2.5, 2.5] * u.arcsec / u.pix,
    ...                                                 unit=u.G))
    >>> weak, is_strong = weak_field(m)
    >>> weak.data.tolist(), int(is_strong.sum())
    ([[0.0, 0.0, 0.0], [0.0, 15.0, 15.0], [-15.0, 0.0, 0.0]], 2)
    """
    check_map(smap)
    clip_g = check_scalar(clip, u.G, "clip")
    strong_g = check_scalar(strong, u.G, "strong")
    data = map_values(smap)
    if smap.unit is not None and smap.unit != u.one:
        if not smap.unit.is_equivalent(u.G):
            raise ValueError(f"smap must be a magnetogram in units of G, got {smap.unit}")
        data = (data * smap.unit).to_value(u.G)
    data = data - np.nanmedian(data)
    with np.errstate(invalid="ignore"):
        is_strong = np.abs(data) > strong_g
    return sunpy.map.Map(np.clip(data, -clip_g, clip_g), {**smap.meta, "bunit": "G"}), is_strong


def _box_pixels(smap, centre, side):
    """(x0, y0, n) of `power_spectrum`'s ``side``-arcsec box at ``centre`` (arcsec); None if cut."""
    try:
        x0, y0, n = box_origin(smap, side, centre * u.arcsec)
    except ValueError:                       # not a point of this map
        return None
    ny, nx = smap.data.shape
    return (x0, y0, n) if x0 >= 0 and y0 >= 0 and x0 + n <= nx and y0 + n <= ny else None


def limb_power_fit(smap, *, box=LIMB_BOX, band=LIMB_BAND, clip=WEAK_CLIP, strong=STRONG_FIELD,
                   strong_fraction=0.02, disk_edge=0.97):
    """
    Fit the weak field's power at network scales over the disk as a fall with μ and an east-west excess.

    See the module notes for the method.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        A helioprojective magnetogram in G, at best the whole disk.
    box : `~astropy.units.Quantity`
        Side of the boxes (160″).
    band : (Quantity, Quantity)
        The wavelengths whose power is fitted (20-50 Mm).
    clip, strong : `~astropy.units.Quantity`
        The weak field's clip (15 G) and the strong field's threshold (50 G), about the median.
    strong_fraction : float
        A box with more strong pixels than this fraction is left out (0.02).
    disk_edge : float
        Outermost reach of a box on the disk, solar radii (0.97).

    Returns
    -------
    `LimbPowerFit`

    Raises
    ------
    ValueError
        If the map is not a magnetogram, an argument is out of range, or
        fewer than 7 boxes are left (too little of the disk, or too much
        strong field).

    Examples
    --------
    White noise whose power falls as μ² reads back b ≈ 2 and no east-west excess:

    >>> import astropy.units as u
    >>> import numpy as np
    >>> import sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> m = sunpy.map.Map(np.zeros((800, 800)), sunpy.map.make_fitswcs_header(
    ...     (800, 800), ref, scale=[2.5, 2.5] * u.arcsec / u.pix, unit=u.G))
    >>> from gongsynth.analysis.disk import disk_coordinates
    >>> mu = np.nan_to_num(disk_coordinates(m)[1])
    >>> noise = np.random.default_rng(1).normal(0, 1, mu.shape) * 2 * mu
    >>> fit = limb_power_fit(sunpy.map.Map(np.where(mu > 0, noise, np.nan), m.meta))
    >>> bool(abs(fit.mu_exponent - 2) < 4 * fit.mu_exponent_error)
    True
    >>> bool(abs(fit.east_west_excess) < 4 * fit.east_west_excess_error)
    True
    """
    side = check_scalar(box, u.arcsec, "box")
    if len(band) != 2:
        raise ValueError(f"band must be (shortest, longest) wavelengths, got {band!r}")
    shortest, longest = (check_scalar(b, u.Mm, "band") for b in band)
    if shortest >= longest:
        raise ValueError(f"band must be (shortest, longest) with shortest < longest, got {band!r}")
    if not 0 <= strong_fraction <= 1:
        raise ValueError(f"strong_fraction must lie in [0, 1], got {strong_fraction!r}")
    if not 0 < disk_edge <= 1:
        raise ValueError(f"disk_edge must lie in (0, 1] solar radii, got {disk_edge!r}")
    weak, is_strong = weak_field(smap, clip, strong)
    radius = smap.rsun_obs.to_value(u.arcsec)
    steps = np.arange(-radius, radius + 1, side)
    # 0.75 box: a little beyond the half-diagonal, so the whole box lies within disk_edge.
    centres = [(x, y) for x in steps for y in steps if np.hypot(x, y) + 0.75 * side <= disk_edge * radius]
    kept, power = [], []
    for centre in centres:
        pixels = _box_pixels(smap, centre, side)
        if pixels is None:
            continue
        x0, y0, n = pixels
        if is_strong[y0:y0 + n, x0:x0 + n].mean() > strong_fraction:
            continue
        spectrum = power_spectrum(weak, box=side * u.arcsec, bins=10, offset=centre * u.arcsec)
        band_power = spectrum.band_power(shortest * u.Mm, longest * u.Mm).to_value(u.G ** 2 * u.Mm ** 2)
        if np.isfinite(band_power) and band_power > 0:
            kept.append(centre)
            power.append(band_power)
    if len(kept) <= _MIN_BOXES:
        raise ValueError(f"limb_power_fit: {len(kept)} boxes of {side:g}″ left on this map (of "
                         f"{len(centres)} on the disk); need more than {_MIN_BOXES}")
    x, y = np.transpose(kept) / radius
    design = np.column_stack([np.ones_like(x), np.log(np.sqrt(1 - x**2 - y**2)), x**2 - y**2])
    coefficients, _, rank, _ = np.linalg.lstsq(design, np.log(power), rcond=None)
    if rank < design.shape[1]:
        raise ValueError("limb_power_fit: the boxes left do not tell μ from east-west (all on one ring)")
    residual = np.log(power) - design @ coefficients
    covariance = np.linalg.inv(design.T @ design) * residual.var(ddof=design.shape[1])
    errors = np.sqrt(np.diag(covariance))
    return LimbPowerFit(mu_exponent=float(coefficients[1]), mu_exponent_error=float(errors[1]),
                        east_west_excess=float(coefficients[2]), east_west_excess_error=float(errors[2]),
                        boxes=len(kept))


def axis_anisotropy(smap, *, bands=ANISOTROPY_BANDS, radii=ANISOTROPY_RADII, box=LIMB_BOX, clip=WEAK_CLIP):
    """
    The weak field's power along the map's x axis over that along its y axis, on the disk's two axes.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        A helioprojective magnetogram in G holding the boxes.
    bands : sequence of (Quantity, Quantity)
        Wavelength bands (3.7-7 and 7-15 Mm).
    radii : sequence of float
        Distances of the boxes from disk centre, solar radii (0.7 and 0.85): at each, one box on
        either side of centre on each axis.
    box : `~astropy.units.Quantity`
        Side of the boxes (160″).
    clip : `~astropy.units.Quantity`
        The weak field's clip about the median (15 G).

    Returns
    -------
    `~astropy.table.QTable`
        One row per axis and band: ``axis`` ("east-west", "north-south"),
        ``shortest``, ``longest`` (Mm) and ``xy_ratio``, the mean over the
        axis's boxes of the power of the wavevectors nearer x over that of
        those nearer y; NaN for a band finer than the map resolves.

    Raises
    ------
    ValueError
        If an argument is out of range or the map does not hold a box.

    Examples
    --------
    Stripes that vary along x put their power in x:

    >>> import astropy.units as u
    >>> import numpy as np
    >>> import sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> stripes = np.tile(5 * np.sin(2 * np.pi * np.arange(800) / 4), (800, 1))
    >>> m = sunpy.map.Map(stripes, sunpy.map.make_fitswcs_header(
    ...     stripes.shape, ref, scale=[2.5, 2.5] * u.arcsec / u.pix, unit=u.G))
    >>> bool(np.all(axis_anisotropy(m)["xy_ratio"] > 100))
    True
    """
    side = check_scalar(box, u.arcsec, "box")
    if not radii or not all(0 <= r < 1 for r in radii):
        raise ValueError(f"radii must be distances from disk centre in [0, 1) solar radii, got {radii!r}")
    limits = []
    for band in bands:
        if len(band) != 2:
            raise ValueError(f"each band must be (shortest, longest) wavelengths, got {band!r}")
        shortest, longest = (check_scalar(b, u.Mm, "bands") for b in band)
        if shortest >= longest:
            raise ValueError(f"each band must have shortest < longest, got {band!r}")
        limits.append((shortest, longest))
    if not limits:
        raise ValueError("bands must hold at least one (shortest, longest) band")
    weak, _ = weak_field(smap, clip)
    radius = smap.rsun_obs.to_value(u.arcsec)
    rows = []
    for axis, unit_vectors in (("east-west", ((-1, 0), (1, 0))), ("north-south", ((0, 1), (0, -1)))):
        per_box = []
        for r in radii:
            for ex, ey in unit_vectors:
                centre = (ex * r * radius, ey * r * radius)
                if _box_pixels(smap, centre, side) is None:
                    raise ValueError(f"axis_anisotropy: the map does not hold the {side:g}″ box at "
                                     f"{r:g} R☉ on the {axis} axis")
                along = {d: power_spectrum(weak, box=side * u.arcsec, bins=10, offset=centre * u.arcsec,
                                           direction=d) for d in ("x", "y")}
                per_box.append([float(along["x"].band_power(lo * u.Mm, hi * u.Mm)
                                      / along["y"].band_power(lo * u.Mm, hi * u.Mm)) for lo, hi in limits])
        for (lo, hi), ratio in zip(limits, np.mean(per_box, axis=0)):
            rows.append((axis, lo, hi, ratio))
    table = QTable(rows=rows, names=("axis", "shortest", "longest", "xy_ratio"))
    table["shortest"].unit = table["longest"].unit = u.Mm
    return table
