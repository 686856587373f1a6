"""
Noise of a map measured in quiet boxes near disk centre, and the disk-centre level.

Noise is measured the way ``shared/data/real/PROVENANCE.md`` measures the
quiet-Sun numbers of the real files: square boxes (~60″) whose centres lie
near disk centre; the *quietest* box (smallest standard deviation) gives the
noise, as its plain standard deviation and as the robust sigma 1.4826 × MAD
(`gongsynth.analysis.statistics.robust_sigma`), which ignores the few
magnetic elements a quiet box still holds, and as the pixel-difference noise
(`gongsynth.analysis.statistics.pixel_difference_sigma`).  Positions are in
units of the apparent solar radius of the map's observer
(`gongsynth.analysis.disk`), so the same call means the same region for
GONG, MDI and HMI.  `NoiseEstimate.to_table` gives the boxes as an
`astropy.table.QTable`.
"""
from dataclasses import dataclass

import astropy.units as u
import numpy as np
from astropy.table import QTable

from gongsynth.analysis.disk import (
    check_map,
    disk_centre_pixel,
    helioprojective_to_pixel,
    local_pixel_scale,
    map_values,
    pixel_to_helioprojective,
)
from gongsynth.analysis.statistics import check_fraction, pixel_difference_sigma, robust_sigma
from gongsynth.validation import check_quantity

__all__ = ["LAYOUTS", "NoiseEstimate", "noise_estimate", "disk_centre_level"]

#: Box layouts of `noise_estimate`.
LAYOUTS = ("grid", "tiles")


@dataclass(frozen=True)
class NoiseEstimate:
    """
    Noise of a map measured in quiet boxes near disk centre (see `noise_estimate`).

    Attributes
    ----------
    sigma : `~astropy.units.Quantity`
        Robust sigma (1.4826 × MAD) in the quietest box: the headline number.
    std : `~astropy.units.Quantity`
        Plain standard deviation in the quietest box.
    difference : `~astropy.units.Quantity`
        Pixel-difference noise (std of neighbour differences / √2) in the quietest box.
    mean : `~astropy.units.Quantity`
        Mean in the quietest box.
    median_std, median_sigma : `~astropy.units.Quantity`
        Median over all boxes of the plain and of the robust standard deviation.
    box_std, box_sigma, box_mean, box_difference : `~astropy.units.Quantity`
        Per box (n_boxes,): plain and robust standard deviation, mean and
        pixel-difference noise.
    box_centres : `~astropy.units.Quantity`
        (n_boxes, 2) helioprojective (Tx, Ty) of the box centres, arcsec.
    box_pixels : int
        Box side in pixels.
    box_size : `~astropy.units.Quantity`
        Box side on the sky, arcsec (at disk centre).
    quietest : int
        Index of the quietest box (smallest plain standard deviation).
    layout : str
        ``"grid"`` or ``"tiles"``.
    """

    sigma: u.Quantity
    std: u.Quantity
    difference: u.Quantity
    mean: u.Quantity
    median_std: u.Quantity
    median_sigma: u.Quantity
    box_std: u.Quantity
    box_sigma: u.Quantity
    box_mean: u.Quantity
    box_difference: u.Quantity
    box_centres: u.Quantity
    box_pixels: int
    box_size: u.Quantity
    quietest: int
    layout: str

    def to_table(self):
        """
        The boxes as a table, one row per box.

        Returns
        -------
        `~astropy.table.QTable`
            Columns ``Tx``, ``Ty`` (box centre, arcsec), ``std``,
            ``robust_sigma``, ``mean``, ``difference`` (map unit) and
            ``quietest`` (bool); ``meta`` holds the headline numbers
            (``sigma``, ``std``, ``difference``, ``mean``, ``median_std``,
            ``median_sigma``), ``box_pixels``, ``box_size`` and ``layout``.
        """
        centres = self.box_centres
        quietest = np.zeros(len(self.box_std), dtype=bool)
        quietest[self.quietest] = True
        columns = {"Tx": centres[:, 0], "Ty": centres[:, 1], "std": self.box_std,
                   "robust_sigma": self.box_sigma, "mean": self.box_mean,
                   "difference": self.box_difference, "quietest": quietest}
        meta = {"sigma": self.sigma, "std": self.std, "difference": self.difference, "mean": self.mean,
                "median_std": self.median_std, "median_sigma": self.median_sigma,
                "box_pixels": self.box_pixels, "box_size": self.box_size, "layout": self.layout}
        return QTable(columns, meta=meta)


def _box_side_pixels(smap, box, centre_pixel):
    """Box side in whole pixels from an angle or a pixel count."""
    if isinstance(box, u.Quantity) and box.unit.is_equivalent(u.pix):
        n = box.to_value(u.pix)
    else:
        check_quantity(box, u.arcsec, "box")
        n = (box / local_pixel_scale(smap, centre_pixel)).to_value(u.one)
    n = int(round(float(n)))
    if n < 2:
        raise ValueError(f"box must span at least 2 pixels, got {box} = {n} pixel(s)")
    return n


def noise_estimate(smap, *, box=60 * u.arcsec, layout="grid", max_radius=0.35, grid=7, step=None,
                   min_valid=0.9):
    """
    Robust noise of a map in quiet boxes near disk centre.

    Square boxes are placed near disk centre; in each, the plain standard
    deviation and the robust sigma 1.4826 × MAD are computed.  The quietest box
    (smallest standard deviation) gives the headline robust ``sigma``, its
    plain ``std`` and its pixel-difference noise; medians over all boxes are
    reported too.  On a map of uniform white noise σ, ``median_std`` and
    ``median_sigma`` are unbiased; selecting the quietest box biases it low:
    its std is expected at σ (1 + E[min of n normals] / √(2N)) for n boxes of
    N pixels, 0.94 σ for the default 29 boxes of 24 × 24 GONG pixels (measured
    over 40 noise maps: std 0.939 ± 0.012 σ, robust ``sigma`` 0.937 ± 0.041 σ).

    Two layouts reproduce the two ways the quiet-Sun numbers in
    ``PROVENANCE.md`` were measured:

    ``"grid"`` (default)
        ``grid`` × ``grid`` box centres at offsets evenly spaced over
        ±``max_radius`` solar radii in x and y, keeping those within
        ``max_radius`` of disk centre (29 boxes for 7 × 7 and 0.35 R☉: the MDI
        full-disk numbers).
    ``"tiles"``
        Boxes tiling the image from its first pixel in steps of ``step``
        pixels (default: half a box), keeping those whose centres lie within
        ``max_radius`` of disk centre (the HMI cut-out numbers: 100-pixel
        boxes, 50-pixel steps).

    Boxes that leave the image or have fewer than ``min_valid`` finite
    pixels are dropped.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        A magnetogram (or any map); its WCS places disk centre.
    box : `~astropy.units.Quantity`
        Box side: an angle (rounded to whole pixels at disk centre) or a
        number of pixels (``u.pix``).  Default 60″.
    layout : {"grid", "tiles"}
    max_radius : float
        Largest distance of a box centre from disk centre, solar radii.
    grid : int
        Boxes per side of the ``"grid"`` layout (odd: one box at disk centre).
    step : int, optional
        Tile step in pixels for ``"tiles"``.
    min_valid : float
        Smallest fraction of finite pixels for a box to count.

    Returns
    -------
    `NoiseEstimate`

    Raises
    ------
    ValueError
        If no box qualifies, or an argument is out of range.

    Examples
    --------
    >>> import astropy.units as u
    >>> import numpy as np
    >>> import sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> data = np.random.default_rng(3).normal(0, 4, (300, 300))
    >>> m = sunpy.map.Map(data, sunpy.map.make_fitswcs_header(
    ...     data, ref, scale=[2.5, 2.5] * u.arcsec / u.pix, unit=u.G))
    >>> est = noise_estimate(m)
    >>> len(est.box_std), est.box_pixels, est.median_sigma.round(0)
    (29, 24, <Quantity 4. G>)
    >>> table = est.to_table()
    >>> len(table), table["robust_sigma"].unit, int(table["quietest"].sum())
    (29, Unit("G"), 1)
    """
    check_map(smap)
    if layout not in LAYOUTS:
        raise ValueError(f"layout must be one of {LAYOUTS}, got {layout!r}")
    max_radius = check_fraction(max_radius, "max_radius")
    min_valid = check_fraction(min_valid, "min_valid", upper=1)
    if isinstance(grid, bool) or not isinstance(grid, (int, np.integer)) or grid < 1:
        raise ValueError(f"grid must be a positive int, got {grid!r}")
    unit = smap.unit if smap.unit is not None else u.one
    data = map_values(smap)
    ny, nx = data.shape
    rsun = smap.rsun_obs.to_value(u.arcsec)
    centre = disk_centre_pixel(smap)
    n = _box_side_pixels(smap, box, centre)
    half = n // 2
    if layout == "grid":
        offsets = np.linspace(-max_radius, max_radius, grid) if grid > 1 else np.zeros(1)
        ox, oy = np.meshgrid(offsets, offsets)
        inside = np.hypot(ox, oy) <= max_radius * (1 + 1e-9)
        tx, ty = ox[inside] * rsun, oy[inside] * rsun
        px, py = helioprojective_to_pixel(smap, tx, ty)
        ok = np.isfinite(px) & np.isfinite(py)
        x0 = np.round(px[ok]).astype(int) - half
        y0 = np.round(py[ok]).astype(int) - half
        tx, ty = tx[ok], ty[ok]
    else:
        if step is None:
            step = max(1, n // 2)
        if isinstance(step, bool) or not isinstance(step, (int, np.integer)) or step < 1:
            raise ValueError(f"step must be a positive int (pixels), got {step!r}")
        starts_x = np.arange(0, nx - n + 1, step)
        starts_y = np.arange(0, ny - n + 1, step)
        gx, gy = np.meshgrid(starts_x, starts_y)
        x0, y0 = gx.ravel(), gy.ravel()
        tx, ty = pixel_to_helioprojective(smap, x0 + (n - 1) / 2, y0 + (n - 1) / 2)
        with np.errstate(invalid="ignore"):
            keep = np.hypot(tx, ty) <= max_radius * rsun * (1 + 1e-9)
        x0, y0, tx, ty = x0[keep], y0[keep], tx[keep], ty[keep]

    stds, sigmas, means, diffs, centres = [], [], [], [], []
    for xs, ys, cx, cy in zip(x0, y0, tx, ty):
        if xs < 0 or ys < 0 or xs + n > nx or ys + n > ny:
            continue
        b = data[ys:ys + n, xs:xs + n]
        finite = np.isfinite(b)
        if finite.mean() < min_valid:
            continue
        stds.append(np.std(b[finite]))
        sigmas.append(robust_sigma(b))
        means.append(np.mean(b[finite]))
        diffs.append(pixel_difference_sigma(b))
        centres.append((cx, cy))
    if not stds:
        raise ValueError(
            f"noise_estimate: no {n}x{n}-pixel box with >= {min_valid:.0%} finite pixels lies within "
            f"{max_radius} solar radii of disk centre on the {ny}x{nx} map (layout={layout!r})"
        )
    stds = np.array(stds)
    q = int(np.argmin(stds))
    box_size = n * local_pixel_scale(smap, centre)
    return NoiseEstimate(
        sigma=sigmas[q] * unit,
        std=stds[q] * unit,
        difference=diffs[q] * unit,
        mean=means[q] * unit,
        median_std=np.median(stds) * unit,
        median_sigma=np.median(sigmas) * unit,
        box_std=stds * unit,
        box_sigma=np.array(sigmas) * unit,
        box_mean=np.array(means) * unit,
        box_difference=np.array(diffs) * unit,
        box_centres=np.array(centres) * u.arcsec,
        box_pixels=n,
        box_size=box_size,
        quietest=q,
        layout=layout,
    )


def disk_centre_level(smap, *, box=60 * u.arcsec):
    """
    Mean value in a box centred on disk centre (e.g. the continuum level).

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
    box : `~astropy.units.Quantity`
        Box side, angle or pixels (``u.pix``); default 60″.

    Returns
    -------
    `~astropy.units.Quantity`
        In the map's unit (dimensionless if it has none).

    Examples
    --------
    >>> import astropy.units as u
    >>> import numpy as np
    >>> import sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> m = sunpy.map.Map(np.full((100, 100), 7.0), sunpy.map.make_fitswcs_header(
    ...     (100, 100), ref, scale=[20, 20] * u.arcsec / u.pix))
    >>> disk_centre_level(m)
    <Quantity 7.>
    """
    est = noise_estimate(smap, box=box, layout="grid", grid=1, max_radius=1.0)
    return est.mean
