"""
Degrading an observation to GONG's view: GONG PSF, then 2.5″ pixels.

`degrade_to_gong` brings a higher-resolution observation to GONG's view: the
GONG PSF (Airy pattern of the 2.8 cm aperture at λ0 ⊗ Gaussian seeing, from
`gongsynth.stages.optics.psf_kernel`) applied at the observation's own sampling, then
area-weighted (flux-conserving) binning onto 2.5″ pixels whose grid shares
the observation's tangent point.  The magnetogram is treated as a linear
signal (B_LOS convolved like an intensity), the usual approximation for
weak-field magnetograms; the observation's own PSF stays in (HMI's ~1″ adds
~1 % to the width, MDI's ~4″ more: see ``native_fwhm``).

The binning is exact area weighting by a sparse operator per axis
(`overlap_operator`); ``tests/test_degrade.py`` checks it against
`reproject.reproject_exact` (spherical-polygon overlaps), which it matches
to round-off on a plane-parallel grid while being faster and independent of the
input's extent.
"""
import math

import astropy.units as u
import numpy as np
import scipy.signal
import scipy.sparse
import sunpy.map

from gongsynth import instruments
from gongsynth.analysis.disk import (
    check_map,
    helioprojective_frame,
    is_helioprojective,
    local_pixel_scale,
    map_values,
)
from gongsynth.validation import check_quantity

__all__ = ["AUTO_DEGRADE_FRACTION", "DEGRADE_OPTIONS", "overlap_operator", "degrade_to_gong",
           "degrade_if_finer"]

#: Maps with pixels finer than this fraction of GONG's plate scale are
#: degraded automatically (``degrade="auto"``).
AUTO_DEGRADE_FRACTION = 0.8

#: Accepted values of the ``degrade`` argument of `degrade_if_finer` and its callers.
DEGRADE_OPTIONS = ("auto", True, False)


def _rotation_angle(smap):
    """Rotation of the map's pixel axes from solar north, degrees (0 for an aligned map)."""
    m = np.asarray(smap.rotation_matrix, dtype=float)
    return math.degrees(math.atan2(m[1, 0], m[0, 0])), m


def _as_aligned_helioprojective(smap):
    """The map on a helioprojective grid with pixel axes along solar west and north."""
    if not is_helioprojective(smap):
        # Heliographic cut-outs (e.g. a Postel HMI patch): interpolate onto a
        # helioprojective grid of the same sampling centred on the patch.
        scale = local_pixel_scale(smap, ((smap.data.shape[1] - 1) / 2, (smap.data.shape[0] - 1) / 2))
        centre = smap.pixel_to_world(*(((n - 1) / 2) * u.pix for n in smap.data.shape[::-1]))
        centre = centre.transform_to(helioprojective_frame(smap))
        header = sunpy.map.make_fitswcs_header(
            smap.data.shape, centre, scale=u.Quantity([scale, scale]) / u.pix,
            instrument=smap.instrument, observatory=smap.observatory,
            wavelength=smap.wavelength, unit=smap.unit,
        )
        reprojected = smap.reproject_to(header, algorithm="interpolation", order="bilinear")
        # reproject_to keeps only the WCS: give the new map back the unit (BUNIT), what the
        # observation is, its date and the solar radius of the header it was made from.
        meta = reprojected.meta.copy()
        for key, value in header.items():
            if key not in meta and not key.startswith(("naxis", "crpix", "cdelt", "crval", "ctype",
                                                       "cunit", "pc", "cd")):
                meta[key] = value
        for key in ("telescop", "instrume", "obsrvtry", "detector", "wavelnth", "waveunit", "content",
                    "origin", "dtype", "rsun_obs"):
            if key in smap.meta:
                meta[key] = smap.meta[key]
        if smap.unit is not None:
            meta["bunit"] = smap.unit.to_string("fits")
        meta["date-avg"] = smap.reference_date.utc.isot  # the WCS's own date
        meta["date-obs"] = smap.date.utc.isot
        return sunpy.map.Map(reprojected.data, meta)
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
        from gongsynth.stages.optics import (
            psf_kernel,  # imported here: optics is heavier than this module needs
        )

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


def overlap_operator(n_in, cdelt_in, crpix0_in, scale_out):
    """
    Exact area weights of a 1-D rebinning: a sparse (n_out, n_in) matrix and the output reference pixel.

    Input pixel j covers [(j - 0.5 - crpix0) cdelt, (j + 0.5 - crpix0) cdelt]
    in the projection plane (arcsec from the reference point).  Output pixels
    of side ``scale_out`` have their edges at whole multiples of ``scale_out``
    from the reference point (a grid fixed on the sky, whatever the input's
    extent or padding) and cover the input field, the outer ones possibly in
    part.  Entry (k, j) is the fraction of output pixel k covered by input
    pixel j, so rows sum to the covered fraction.  A 2-D image is rebinned
    as ``opx @ (opy @ image).T`` (transposed back), one operator per axis.

    Parameters
    ----------
    n_in : int
        Number of input pixels along the axis.
    cdelt_in : float
        Input pixel size (arcsec; negative for a reversed axis).
    crpix0_in : float
        0-based input pixel coordinate of the reference point.
    scale_out : float
        Output pixel size (arcsec, positive).

    Returns
    -------
    operator : `scipy.sparse.csr_matrix`
        (n_out, n_in) covered fractions.
    crpix0_out : float
        0-based output pixel coordinate of the reference point.

    Examples
    --------
    >>> op, ref = overlap_operator(5, 1.0, 2.0, 2.5)   # five 1" pixels, the middle one on the reference
    >>> op.toarray().round(2).tolist(), ref
    ([[0.4, 0.4, 0.2, 0.0, 0.0], [0.0, 0.0, 0.2, 0.4, 0.4]], 0.5)
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
    check_map(smap, "smap", finite=True)
    inst = instruments.get(instrument)
    min_coverage = float(min_coverage)
    if not 0 < min_coverage <= 1:
        raise ValueError(f"min_coverage must lie in (0, 1], got {min_coverage}")
    aligned = _as_aligned_helioprojective(smap)
    cdelt = [aligned.scale.axis1.to_value(u.arcsec / u.pix), aligned.scale.axis2.to_value(u.arcsec / u.pix)]
    scale_in = math.sqrt(abs(cdelt[0] * cdelt[1]))
    kernel = _kernel(psf, scale_in, inst, native_fwhm)
    data = map_values(aligned)
    if kernel is not None:
        data = _masked_convolve(data, kernel)
    plate = inst.plate_scale.to_value(u.arcsec)
    crpix = aligned.reference_pixel  # 0-based
    opx, refx = overlap_operator(data.shape[1], cdelt[0], crpix.x.to_value(u.pix), plate)
    opy, refy = overlap_operator(data.shape[0], cdelt[1], crpix.y.to_value(u.pix), plate)
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


def degrade_if_finer(smap, instrument=None, *, degrade="auto"):
    """
    `degrade_to_gong` where asked, or (``"auto"``) where the map's pixels are finer than GONG's.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
    instrument : `~gongsynth.GONGInstrument`, optional
        Supplies the plate scale and the PSF.
    degrade : {"auto", True, False}
        ``"auto"``: degrade when the pixel side at disk centre is below
        ``AUTO_DEGRADE_FRACTION`` × ``instrument.plate_scale``.

    Returns
    -------
    smap : `~sunpy.map.GenericMap`
        The degraded map, or ``smap`` itself.
    degraded : bool

    Examples
    --------
    >>> import numpy as np, astropy.units as u, sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> m = sunpy.map.Map(np.ones((40, 40)), sunpy.map.make_fitswcs_header(
    ...     (40, 40), ref, scale=[2.5, 2.5] * u.arcsec / u.pix, unit=u.G))
    >>> degrade_if_finer(m)[1]   # already at GONG's plate scale
    False
    """
    if degrade not in DEGRADE_OPTIONS:
        raise ValueError(f"degrade must be 'auto', True or False, got {degrade!r}")
    inst = instruments.get(instrument)
    if degrade == "auto":
        degrade = bool(local_pixel_scale(smap) < AUTO_DEGRADE_FRACTION * inst.plate_scale)
    if degrade:
        return degrade_to_gong(smap, inst), True
    return smap, False
