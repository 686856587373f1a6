"""
The azimuthally averaged spatial power spectrum of a magnetogram's central region, in Mm.

A solar physicist's first look at a magnetogram is its spatial organisation:
granular noise, the ~30 Mm supergranular network, the ~100 Mm unipolar
patches of decayed active regions.  `power_spectrum` measures it the same way
on any map: a square of ``box`` (640″ by default, 256 GONG pixels) centred on
disk centre (the map's centre if disk centre is off the map), the median
taken out, a 2-D Hann window, the FFT, the power averaged over annuli of
wavenumber.  Distances are on the Sun at disk centre: the pixel's angle
times the distance from the observer to the sub-observer point
(``dsun - rsun``), so that 1 Mm means the same for GONG, MDI and HMI; the
foreshortening over the box (μ ≥ 0.88 at the corners of the default box) is
not taken out.

The normalisation is Parseval's with the window's power taken out: the sum
of the 2-D spectral density over all modes times the wavenumber cell equals
the variance of the (median-removed) values in the window, so spectra of
maps with different pixels can be compared in G² Mm².
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
)
from gongsynth.validation import check_quantity

__all__ = ["PowerSpectrum", "power_spectrum", "quadrant_power_spectrum", "km_per_arcsec", "box_origin"]


@dataclass(frozen=True)
class PowerSpectrum:
    """
    Azimuthally averaged spatial power spectrum of a map (see `power_spectrum`).

    Attributes
    ----------
    wavenumber : `~astropy.units.Quantity`
        Geometric centre of each wavenumber annulus, 1/Mm (cycles per Mm).
    wavelength : `~astropy.units.Quantity`
        1 / wavenumber, Mm.
    power : `~astropy.units.Quantity`
        Mean 2-D spectral density in each annulus, (map unit)² Mm².
    modes : `numpy.ndarray`
        Fourier modes averaged in each annulus (int).
    pixel_size : `~astropy.units.Quantity`
        Pixel side on the Sun at disk centre, Mm.
    box_pixels : int
        Side of the square that was transformed.
    variance : `~astropy.units.Quantity`
        Variance of the windowed, median-removed values (the spectrum's integral).
    edges : `~astropy.units.Quantity`
        Wavenumber edges of the annuli, 1/Mm.
    """

    wavenumber: u.Quantity
    wavelength: u.Quantity
    power: u.Quantity
    modes: np.ndarray
    pixel_size: u.Quantity
    box_pixels: int
    variance: u.Quantity
    edges: u.Quantity = None

    def band_power(self, shortest, longest):
        """
        Mean power of the annuli whose wavelengths lie in [shortest, longest] (modes-weighted).

        Parameters
        ----------
        shortest, longest : `~astropy.units.Quantity`
            Wavelength range (length).

        Returns
        -------
        `~astropy.units.Quantity`
            NaN if no annulus lies in the range.
        """
        lo = check_quantity(shortest, u.Mm, "shortest").to_value(u.Mm)
        hi = check_quantity(longest, u.Mm, "longest").to_value(u.Mm)
        lam = self.wavelength.to_value(u.Mm)
        keep = (lam >= lo) & (lam <= hi) & (self.modes > 0)
        if not keep.any():
            return np.nan * self.power.unit
        return np.average(self.power.value[keep], weights=self.modes[keep]) * self.power.unit

    def to_table(self):
        """
        The spectrum as a table, one row per annulus.

        Returns
        -------
        `~astropy.table.QTable`
            Columns ``wavenumber`` (1/Mm), ``wavelength`` (Mm), ``power``
            and ``modes``; ``meta`` holds ``pixel_size``, ``box_pixels`` and ``variance``.
        """
        return QTable({"wavenumber": self.wavenumber, "wavelength": self.wavelength,
                       "power": self.power, "modes": self.modes},
                      meta={"pixel_size": self.pixel_size, "box_pixels": self.box_pixels,
                            "variance": self.variance})


def km_per_arcsec(smap):
    """
    Kilometres on the Sun per arcsec at disk centre, seen from the map's observer.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`

    Returns
    -------
    `~astropy.units.Quantity`
        (dsun - rsun) × 1″ in km (≈ 725 km at 1 AU).
    """
    near = (smap.dsun - smap.rsun_meters).to(u.km)
    return near * (1 * u.arcsec).to_value(u.rad) / u.arcsec


def box_origin(smap, side, offset=None):
    """
    First pixel and side, in pixels, of the square that `power_spectrum` transforms, before any cut.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        A helioprojective map.
    side : float
        The square's side, arcsec.
    offset : `~astropy.units.Quantity`, optional
        Helioprojective (Tx, Ty) of its centre (default: disk centre).

    Returns
    -------
    x0, y0, n : int
        Its first column and row (may lie outside the map) and its side.

    Raises
    ------
    ValueError
        If ``offset`` is not a finite point of this map.
    """
    cx, cy = disk_centre_pixel(smap)
    if offset is not None:
        shift = np.asarray(check_quantity(offset, u.arcsec, "offset").to_value(u.arcsec), dtype=float)
        if shift.shape != (2,) or not np.all(np.isfinite(shift)):
            raise ValueError(f"offset must be a finite (x, y) angle, got {offset}")
        x, y = helioprojective_to_pixel(smap, shift[0], shift[1])
        cx, cy = float(x[0]), float(y[0])
        if not (np.isfinite(cx) and np.isfinite(cy)):
            raise ValueError(f"offset {offset} is not a point of this map")
    n = int(round(side / local_pixel_scale(smap).to_value(u.arcsec)))

    def first(centre):
        # A start within a thousandth of a pixel of a half pixel (the gnomonic projection's offsets, rounding)
        # is taken as on it, then rounded half to even as always: four boxes tiling a square start where
        # they should.
        start = centre - n / 2
        halves = round(2 * start)
        return int(round(halves / 2 if abs(2 * start - halves) < 2e-3 else start))

    return first(cx), first(cy), n


def power_spectrum(smap, *, box=640 * u.arcsec, bins=16, edges=None, offset=None, direction=None):
    """
    Azimuthally averaged spatial power spectrum of the central ``box`` of a map (or of one off centre).

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        Any helioprojective map (a magnetogram in G); NaN pixels in the box
        (off the disk, blanked) are set to the median, i.e. to zero after it
        is removed, and count against the window.
    box : `~astropy.units.Quantity`
        Side of the square (angle; default 640″), centred on disk centre (on
        the map's centre if disk centre is off the map) and cut to what the
        map holds.
    bins : int
        Annuli, log-spaced in wavenumber from the box's fundamental to the
        Nyquist wavenumber (default 16).
    edges : `~astropy.units.Quantity`, optional
        The annuli's wavenumber edges instead (1/length, increasing), e.g.
        another map's ``spectrum.edges`` to compare the two annulus by annulus;
        annuli beyond this map's Nyquist wavenumber hold no mode (NaN).
    offset : `~astropy.units.Quantity`, optional
        Helioprojective (Tx, Ty) of the box's centre, an angle from disk
        centre (default: the box on disk centre); the box stays aligned with
        the pixels and is cut to what the map holds.  Distances stay those at
        disk centre: a box off centre is foreshortened toward the limb, the
        same way on any two maps compared.
    direction : {None, "x", "y"}
        Average only the wavevectors nearer one axis of the map: ``"x"`` those
        with :math:`|k_x| > |k_y|` (patterns that vary along the map's x axis,
        east-west on a solar-north-up map), ``"y"`` those with :math:`|k_y| >
        |k_x|`; default both and the diagonals.  Their ratio measures the
        spectrum's anisotropy, e.g. the foreshortening of a surface pattern
        near the limb.

    Returns
    -------
    `PowerSpectrum`

    Raises
    ------
    ValueError
        If the square holds fewer than 16 × 16 pixels or no finite value.

    Examples
    --------
    >>> import numpy as np, astropy.units as u, sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> hdr = sunpy.map.make_fitswcs_header((256, 256), ref, scale=[2.5, 2.5] * u.arcsec / u.pix,
    ...                                     unit=u.G)
    >>> white = sunpy.map.Map(np.random.default_rng(0).normal(0, 3, (256, 256)), hdr)
    >>> spectrum = power_spectrum(white)
    >>> spectrum.box_pixels, round(float(spectrum.variance.to_value(u.G ** 2)))
    (256, 9)
    """
    check_map(smap)
    side = check_quantity(box, u.arcsec, "box").to_value(u.arcsec)
    if not np.isfinite(side) or side <= 0:
        raise ValueError(f"box must be a positive angle, got {box}")
    if isinstance(bins, bool) or not isinstance(bins, (int, np.integer)) or bins < 2:
        raise ValueError(f"bins must be an int >= 2, got {bins!r}")
    if direction not in (None, "x", "y"):
        raise ValueError(f"direction must be None, 'x' or 'y', got {direction!r}")
    data = map_values(smap)
    unit = smap.unit if smap.unit is not None else u.one
    ny, nx = data.shape
    scale = local_pixel_scale(smap).to_value(u.arcsec)
    x0, y0, n = box_origin(smap, side, offset)
    x0, y0 = max(x0, 0), max(y0, 0)
    n = min(n, nx - x0, ny - y0)
    if n < 16:
        raise ValueError(f"power_spectrum: the {side:g}″ box holds {max(n, 0)} pixels a side on this map; "
                         "need at least 16")
    cut = np.asarray(data[y0:y0 + n, x0:x0 + n], dtype=np.float64)
    finite = np.isfinite(cut)
    if not finite.any():
        raise ValueError("power_spectrum: no finite value in the box")
    cut = np.where(finite, cut - np.median(cut[finite]), 0.0)
    hann = np.hanning(n + 2)[1:-1]           # no zero weight at the edges
    window = np.outer(hann, hann)
    dx = scale * km_per_arcsec(smap).to_value(u.km / u.arcsec) / 1e3   # Mm
    f = np.fft.fft2(cut * window)
    density = np.abs(f) ** 2 * dx ** 2 / np.sum(window ** 2)   # Parseval: Σ density Δk² = var
    kx, ky = np.meshgrid(np.fft.fftfreq(n, d=dx), np.fft.fftfreq(n, d=dx))
    k = np.hypot(kx, ky)
    if direction is not None:      # the other axis's modes (and the diagonals) fall outside every annulus
        k = np.where(np.abs(kx) > np.abs(ky) if direction == "x" else np.abs(ky) > np.abs(kx), k, -1.0)
    if edges is None:
        edges = np.geomspace(1.0 / (n * dx), 0.5 / dx, bins + 1)
    else:
        edges = np.asarray(check_quantity(edges, 1 / u.Mm, "edges").to_value(1 / u.Mm), dtype=float)
        if edges.ndim != 1 or edges.size < 2 or np.any(np.diff(edges) <= 0) or edges[0] < 0:
            raise ValueError("edges must be >= 2 increasing non-negative wavenumbers")
    bins = edges.size - 1
    index = np.digitize(k.ravel(), edges) - 1
    inside = (index >= 0) & (index < bins)
    modes = np.bincount(index[inside], minlength=bins)
    total = np.bincount(index[inside], weights=density.ravel()[inside], minlength=bins)
    with np.errstate(invalid="ignore", divide="ignore"):
        power = np.where(modes > 0, total / np.maximum(modes, 1), np.nan)
    centres = np.sqrt(edges[1:] * edges[:-1])
    variance = density.sum() / (n * dx) ** 2
    per_mm = 1 / u.Mm
    return PowerSpectrum(wavenumber=centres * per_mm, wavelength=(1 / centres) * u.Mm,
                         power=power * unit ** 2 * u.Mm ** 2, modes=modes.astype(int),
                         pixel_size=dx * u.Mm, box_pixels=int(n), variance=variance * unit ** 2,
                         edges=edges * per_mm)


def quadrant_power_spectrum(smap, *, box=640 * u.arcsec, bins=16, edges=None):
    """
    Mean spectrum of the four ``box`` squares that tile the central square of twice the side.

    One 640″ box holds few supergranules and fewer unipolar patches: its spectrum at network
    scales strays by a factor ~1.4 from one map of the same Sun to the next (the noise guide
    measures it on seeds of one run), four boxes' by ~1.15.  Each box is `power_spectrum`'s
    at ``offset`` (±box/2, ±box/2), foreshortened toward its outer corner (which the Hann
    window weighs least) the same way on any two maps.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        A helioprojective map that holds the whole central square of side 2 ``box``.
    box, bins, edges
        As for `power_spectrum` (the four boxes share the first one's annuli unless given).

    Returns
    -------
    `PowerSpectrum`
        The four boxes' mean power and variance, their modes summed, one box's side.

    Raises
    ------
    ValueError
        If the map does not hold the whole central square of side 2 ``box``.
    """
    check_map(smap)
    side = check_quantity(box, u.arcsec, "box")
    ny, nx = smap.data.shape
    offsets = [u.Quantity([sx * side / 2, sy * side / 2]) for sx in (-1, 1) for sy in (-1, 1)]
    for offset in offsets:
        x0, y0, n = box_origin(smap, side.to_value(u.arcsec), offset)
        if min(x0, y0) < 0 or x0 + n > nx or y0 + n > ny:
            raise ValueError(f"quadrant_power_spectrum: the map does not hold the central {2 * side:g}")
    spectra = []
    for offset in offsets:
        spectra.append(power_spectrum(smap, box=side, bins=bins, edges=edges, offset=offset))
        edges = spectra[0].edges
    first = spectra[0]
    return PowerSpectrum(wavenumber=first.wavenumber, wavelength=first.wavelength,
                         power=u.Quantity([s.power for s in spectra]).mean(axis=0),
                         modes=np.sum([s.modes for s in spectra], axis=0), pixel_size=first.pixel_size,
                         box_pixels=first.box_pixels,
                         variance=u.Quantity([s.variance for s in spectra]).mean(), edges=first.edges)
