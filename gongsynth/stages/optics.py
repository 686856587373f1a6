r"""
Optics: the PSF applied by FFT convolution, pixelization and expected counts.

The PSF itself (Airy ⊗ seeing, paper Sec. 3.2, design §3.9) is modelled in
`gongsynth.stages.psf`; `psf_profile`, `psf_kernel` and `normalize_kernel`
are importable from here too.  Both effects can be switched off: ``psf=False``
(no PSF at all, pixel averages only) and ``seeing=False`` (diffraction only).

Pixelization (`gongsynth.stages.pixelization`, `pixelize` importable from
here too) follows the paper: bilinear resampling to exactly ``supersampling``
× the detector pixels, then binning.  All functions work on any stack
``(..., ny, nx)``: the instrument's K planes, or the true B_LOS pushed through the
same geometry.
"""
import math

import astropy.constants as const
import astropy.units as u
import numpy as np
import scipy.fft

from gongsynth import instruments
from gongsynth.stages.imagers import BandImager, BandLimitedImager, ExactImager, image_planes, pixel_means
from gongsynth.stages.pixelization import (
    PIXELIZE_METHODS,
    check_stack,
    pixelize,
    split_unit,
    with_unit,
)
from gongsynth.stages.psf import (
    fft_workers,
    normalize_kernel,
    psf_instrument,
    psf_kernel,
    psf_profile,
    wrapped_kernel,
)
from gongsynth.stages.scene.scene import BOUNDARIES, DeferredStack
from gongsynth.validation import check_quantity

__all__ = [
    "psf_profile",
    "psf_kernel",
    "normalize_kernel",
    "convolve",
    "PIXELIZE_METHODS",
    "pixelize",
    "observe",
    "photometric_factor",
    "expected_counts",
    "image_scene",
]


def _resolve_kernel(psf, seeing, scale, inst):
    """True/None -> instrument PSF (with or without seeing), False -> no PSF, array -> user kernel."""
    psf_instrument(inst, seeing=seeing)  # checks the switch
    if psf is None or psf is True:
        return psf_kernel(scale * u.arcsec, inst, seeing=seeing)
    if psf is False:
        return None
    if not seeing:
        raise ValueError("seeing=False applies to the instrument PSF; a user psf kernel is used as "
                         "given (pass psf=True for the diffraction-limited instrument PSF)")
    return normalize_kernel(psf)


def convolve(stack, kernel, *, boundary="periodic", workers=None):
    """
    Convolve every plane of a stack with a kernel by FFT.

    Parameters
    ----------
    stack : array_like or `~astropy.units.Quantity`
        Shape ``(..., ny, nx)``; the unit (if any) is kept.
    kernel : array_like
        2-D kernel with its centre at ``(ky // 2, kx // 2)``; it is normalised
        to unit sum (see `normalize_kernel`), so the total flux is conserved
        for ``boundary="periodic"``.
    boundary : {"periodic", "zero", "reflect"}
        ``"periodic"``: the scene repeats (circular convolution; a kernel larger
        than the field wraps around, as it must on a periodic scene).
        ``"zero"``: nothing beyond the field (dark sky; flux leaving the field is lost).
        ``"reflect"``: the field continues as its mirror image (no darkened edges).
    workers : int, optional
        Threads for `scipy.fft`.

    Returns
    -------
    `numpy.ndarray` or `~astropy.units.Quantity`
        Same shape, dtype (float32 stays float32) and unit as ``stack``.

    Examples
    --------
    >>> import numpy as np
    >>> img = np.zeros((8, 8)); img[4, 4] = 1
    >>> out = convolve(img, np.ones((3, 3)))
    >>> float(out.sum()), float(out[3, 3])
    (1.0, 0.1111111111111111)
    """
    values, unit = split_unit(stack, "stack")
    values = check_stack(values, "stack")
    out = np.empty_like(values)
    result = out.reshape((-1,) + values.shape[-2:])
    for i, conv in enumerate(_convolved_planes(values, kernel, boundary, workers)):
        result[i] = conv
    return with_unit(out, unit)


def _convolved_planes(values, kernel, boundary, workers):
    """
    Yield each plane of ``values`` (..., ny, nx) convolved with ``kernel``.

    The yielded arrays are views into a work buffer that the next plane
    overwrites: one plane's FFT temporaries at a time, whatever the stack.
    """
    if boundary not in BOUNDARIES:
        raise ValueError(f"boundary must be one of {BOUNDARIES}, got {boundary!r}")
    k = normalize_kernel(kernel, "kernel")
    workers = fft_workers(workers)
    ny, nx = values.shape[-2:]
    ky, kx = k.shape
    if boundary == "periodic":
        pads = ((0, 0), (0, 0))
        fshape = (ny, nx)
    else:
        # Linear convolution: pad by the kernel reach so nothing wraps into the field.
        pads = ((ky - 1 - ky // 2, ky // 2), (kx - 1 - kx // 2, kx // 2))
        fshape = (scipy.fft.next_fast_len(ny + ky - 1, real=True),
                  scipy.fft.next_fast_len(nx + kx - 1, real=True))
    kfft = scipy.fft.rfft2(wrapped_kernel(k, fshape, values.dtype), workers=workers)
    mode = "constant" if boundary == "zero" else "symmetric"
    buffer = np.zeros(fshape, dtype=values.dtype)
    for plane in values.reshape((-1, ny, nx)):
        if boundary == "periodic":
            buffer[...] = plane
        else:
            # Zero beyond the padded field (the kernel never reaches it from the field).
            padded = np.pad(plane, pads, mode=mode)
            buffer[:padded.shape[0], :padded.shape[1]] = padded
            del padded
        spectrum = scipy.fft.rfft2(buffer, workers=workers)
        spectrum *= kfft
        conv = scipy.fft.irfft2(spectrum, s=fshape, workers=workers)
        del spectrum
        # With pads (p, q): field pixel j sits at padded index j + p, and the
        # circular convolution with the centred kernel keeps it there.
        yield conv[pads[0][0]:pads[0][0] + ny, pads[1][0]:pads[1][0] + nx]


def _imager(shape, pixel_scale, inst, kernel, boundary, dtype, workers, band_limited=True):
    """
    The Fourier-space operator (`BandLimitedImager`, or `ExactImager` with every
    alias) when ``shape`` holds exactly supersampling² samples per detector pixel, else None.
    """
    if boundary not in BOUNDARIES:
        raise ValueError(f"boundary must be one of {BOUNDARIES}, got {boundary!r}")
    factor = inst.supersampling
    scale = float(u.Quantity(pixel_scale, u.arcsec).value)
    plate = inst.plate_scale.to_value(u.arcsec)
    if not math.isclose(scale * factor, plate, rel_tol=1e-9) or shape[0] % factor or shape[1] % factor:
        return None
    kind = BandLimitedImager if band_limited else ExactImager
    return kind(shape, normalize_kernel(kernel, "psf"), boundary, factor,
                np.float32 if dtype == np.float32 else np.float64, workers)


def _banded(values, light, inst, kernel, band_limited, psf, workers):
    """
    A `BandImager` for a deferred light that makes bands of rows of every plane at once (a
    full-disk grid too large to hold) under the exact operator with zero edges, else None.
    """
    if not (isinstance(values, DeferredStack) and values.has_bands) or kernel is None \
            or light.boundary != "zero" or _band_limited(band_limited, psf, inst):
        return None
    factor = inst.supersampling
    scale = light.pixel_scale.to_value(u.arcsec)
    shape = values.shape[-2:]
    if not math.isclose(scale * factor, inst.plate_scale.to_value(u.arcsec), rel_tol=1e-9) \
            or shape[0] % factor or shape[1] % factor:
        return None
    return BandImager(shape, normalize_kernel(kernel, "psf"), factor,
                      np.float32 if values.dtype == np.float32 else np.float64, workers)


def _band_limited(band_limited, psf, inst):
    """
    Whether the band-limited operator may be used: asked for, the instrument's
    PSF (a user kernel is taken at its word: the exact operator), and the
    aperture's cut-off at the detector's Nyquist frequency or below (0.5 %
    above it is tolerated: GONG's D/λ0 = 0.2006 cycles per arcsec against
    0.2, where the Airy OTF is ~1e-4).
    """
    if not band_limited or not (psf is None or psf is True) or getattr(inst, "psf_model", None) is not None:
        return False  # a user kernel, or an instrument's measured PSF: not band limited by construction
    cutoff = (inst.aperture / inst.line_wavelength).to_value(u.one) * u.arcsec.to(u.rad)
    return cutoff <= 1.005 / (2 * inst.plate_scale.to_value(u.arcsec))


@u.quantity_input
def observe(stack, pixel_scale: u.arcsec, *, instrument=None, psf=True, seeing=True, boundary="periodic",
            method="bilinear", workers=None, band_limited=True):
    """
    PSF (optional) then pixelization of any stack: light and ground truth alike.

    Parameters
    ----------
    stack : array_like or `~astropy.units.Quantity`
        Shape ``(..., ny, nx)`` sampled at ``pixel_scale``; unit kept.
    pixel_scale : `~astropy.units.Quantity`
        Sampling of ``stack`` (arcsec per pixel).
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
    psf : bool, None or array_like
        ``True`` (default; ``None`` is the same): the instrument PSF
        (`psf_kernel`); ``False``: no PSF at all (pixel average only, e.g. for
        a truth map); an array: a user kernel sampled at ``pixel_scale``,
        centre at ``(ky // 2, kx // 2)``, normalised to unit sum.
    seeing : bool
        ``True`` (default): the instrument PSF includes the Gaussian seeing;
        ``False``: diffraction only (the Airy pattern of the aperture).  Only
        meaningful with the instrument PSF (an error with a user kernel).
    boundary : {"periodic", "zero", "reflect"}
        Edge handling of the convolution (see `convolve`); ``"periodic"`` also
        makes the resampling wrap.
    method : {"bilinear", "area"}
        Resampling of `pixelize`.
    workers : int, optional
        Threads for the FFTs.
    band_limited : bool
        On a grid of exactly ``supersampling`` samples per detector pixel (every
        gongsynth scene's), the PSF and the binning run in Fourier space.
        ``True`` (default): with the instrument PSF, at the frequencies the
        detector samples, which are all the aperture passes
        (`~gongsynth.stages.imagers.BandLimitedImager`; the aliases it leaves
        out are the kernel's leakage beyond them, < 2e-5 of the transfer
        function); a user kernel, or an aperture whose cut-off lies above the
        detector's Nyquist frequency, gets the exact operator.  ``False``:
        always the exact one (`~gongsynth.stages.imagers.ExactImager`: the
        same numbers as `convolve` then `pixelize`, to rounding).  Other grids
        take the reference path (`convolve`, then `pixelize`).

    Returns
    -------
    `numpy.ndarray` or `~astropy.units.Quantity`
        Shape ``(..., ny_det, nx_det)``: the mean over each detector pixel.

    Examples
    --------
    >>> import astropy.units as u
    >>> import numpy as np
    >>> flat = np.ones((2, 50, 50))
    >>> out = observe(flat, 0.5 * u.arcsec)
    >>> out.shape, bool(np.allclose(out, 1))
    ((2, 10, 10), True)
    >>> bool(np.allclose(observe(flat, 0.5 * u.arcsec, psf=False), 1))
    True
    """
    inst = instruments.get(instrument)
    kernel = _resolve_kernel(psf, seeing, pixel_scale.to_value(u.arcsec), inst)
    periodic = boundary == "periodic"
    if kernel is None:
        return pixelize(stack, pixel_scale, instrument=inst, periodic=periodic, method=method)
    values, unit = split_unit(stack, "stack")
    values = check_stack(values, "stack")
    imager = _imager(values.shape[-2:], pixel_scale, inst, kernel, boundary, values.dtype, workers,
                     _band_limited(band_limited, psf, inst))
    if imager is not None:
        planes = values.reshape((-1,) + values.shape[-2:])
        out = np.empty((planes.shape[0],) + imager.detector_shape)
        for i, plane in enumerate(planes):
            out[i] = imager(plane)
        return with_unit(out.reshape(values.shape[:-2] + imager.detector_shape), unit)
    # Plane by plane: PSF then pixelization, so no convolved copy of the stack is held.
    planes = [pixelize(conv, pixel_scale, instrument=inst, periodic=periodic, method=method)
              for conv in _convolved_planes(values, kernel, boundary, workers)]
    out = np.stack(planes).reshape(values.shape[:-2] + planes[0].shape)
    return with_unit(out, unit)


def photometric_factor(instrument=None):
    """
    Electrons per frame per detector pixel for a unit radiance at Earth.

    factor = plate_scale² × effective_area × exposure_time × quantum_efficiency / (h c / λ0)
    (design §3.10); the filter transmission is already inside the channel planes.

    Parameters
    ----------
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional

    Returns
    -------
    `~astropy.units.Quantity`
        In electron / (erg s⁻¹ cm⁻² arcsec⁻²).

    Examples
    --------
    >>> import astropy.units as u
    >>> f = photometric_factor()
    >>> f.unit == u.electron / (u.erg / (u.s * u.cm**2 * u.arcsec**2))
    True
    """
    inst = instruments.get(instrument)
    photon = (const.h * const.c / inst.line_wavelength).to(u.erg)
    factor = (inst.plate_scale**2 * inst.effective_area * inst.exposure_time
              * inst.quantum_efficiency / photon)
    return (factor.to(u.arcsec**2 * u.cm**2 * u.s / u.erg)) * u.electron


def expected_counts(scene, instrument=None, *, psf=True, seeing=True, workers=None, band_limited=True):
    """
    Expected electrons per frame in each detector pixel for the instrument's K planes.

    PSF (with the scene's boundary handling), pixelization, then photometry
    (`photometric_factor`).

    Parameters
    ----------
    scene : `~gongsynth.stages.scene.scene.Scene`
        Radiance at Earth per arcsec², ``(6, NY, NX)`` (any leading length works).
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
        Defaults to the instrument the scene was built with.
    psf : bool, None or array_like
        As in `observe`: ``True`` (default) the instrument PSF, ``False`` none,
        or a user kernel.
    seeing : bool
        As in `observe`: ``False`` for the diffraction-limited PSF.
    workers : int, optional
        Threads for the FFTs.
    band_limited : bool
        As in `observe`.

    Returns
    -------
    `~astropy.units.Quantity`
        Shape ``(6, ny_det, nx_det)``, in electron (per frame per pixel).

    Examples
    --------
    >>> import astropy.units as u
    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> radiance = np.full((6, 20, 20), 3.5e-5) * u.erg / (u.s * u.cm**2 * u.arcsec**2)
    >>> scene = SimpleNamespace(data=radiance, pixel_scale=0.5 * u.arcsec, boundary="periodic")
    >>> e = expected_counts(scene)
    >>> e.shape, e.unit
    ((6, 4, 4), Unit("electron"))
    """
    inst = instruments.get(instrument if instrument is not None else getattr(scene, "instrument", None))
    radiance = check_quantity(scene.data, u.erg / (u.s * u.cm**2 * u.arcsec**2), "scene.data")
    planes = observe(radiance, scene.pixel_scale, instrument=inst, psf=psf, seeing=seeing,
                     boundary=scene.boundary, workers=workers, band_limited=band_limited)
    return _counts(planes, inst, radiance.dtype)


def _counts(planes, inst, dtype):
    """Detector-pixel radiances (a Quantity of a fresh array: scaled in place) to electrons per frame."""
    factor = photometric_factor(inst)
    values = planes.value
    values *= factor.value          # in place: a full-disk HMI stack is 1.6 GB
    scale = (planes.unit * factor.unit).to(u.electron)
    if scale != 1:
        values *= scale
    counts = u.Quantity(values, u.electron, copy=False)
    # FFT convolution leaves round-off of either sign (~1e-16 of the peak, ~3e-7 for
    # float32 planes) where the scene is dark (beyond the limb); counts cannot be
    # negative, so those are zeroed.  Anything larger would be a real error and is left to fail.
    rtol = 1e-5 if np.dtype(dtype) == np.float32 else 1e-9
    tiny = rtol * max(float(np.max(counts.value, initial=0.0)), 0.0)
    counts[(counts.value < 0) & (counts.value > -tiny)] = 0 * u.electron
    return counts


def image_scene(light, truth=None, instrument=None, *, psf=True, seeing=True, workers=None,
                band_limited=True):
    """
    Expected counts of a scene and its truth map without and with the PSF, in one pass.

    The same as `expected_counts` for ``light`` and `observe` (``psf=False``,
    then ``psf``) for ``truth``, but the PSF operator (its transfer function)
    is built once and shared by the light planes and the truth, and deferred
    scenes (`~gongsynth.stages.scene.scene.DeferredStack`) are read a block of
    rows at a time, never made whole.

    Parameters
    ----------
    light : `~gongsynth.stages.scene.scene.Scene`
        Radiance at Earth per arcsec² (6, NY, NX).
    truth : `~gongsynth.stages.scene.scene.Scene`, optional
        A map (NY, NX) on the same grid (e.g. B_LOS in G).
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
        Defaults to the light scene's.
    psf, seeing : optional
        As in `observe`.
    workers : int, optional
        Threads for the FFTs (default: every core).
    band_limited : bool
        As in `observe`: the operator at the detector's frequencies (default),
        or with every alias (the reference).

    Returns
    -------
    counts : `~astropy.units.Quantity`
        (6, ny_det, nx_det) electrons per frame (`expected_counts`).
    truth_map, truth_psf : `~astropy.units.Quantity` or None
        The truth averaged over each detector pixel, without and with the PSF.
    """
    inst = instruments.get(instrument if instrument is not None else getattr(light, "instrument", None))
    unit = u.erg / (u.s * u.cm**2 * u.arcsec**2)
    values = getattr(light, "planes", None)
    if isinstance(values, DeferredStack):  # made from checked (finite) input
        radiance_unit = values.unit
        if not u.Unit(radiance_unit).is_equivalent(unit):
            raise u.UnitsError(f"light.data must be in {unit}, got {radiance_unit}")
    else:
        radiance = check_quantity(light.data, unit, "light.data")
        values, radiance_unit = check_stack(radiance.value, "light.data"), radiance.unit
    kernel = _resolve_kernel(psf, seeing, light.pixel_scale.to_value(u.arcsec), inst)
    banded = _banded(values, light, inst, kernel, band_limited, psf, workers)
    if banded is not None:
        return _image_bands(values, truth, banded, inst)
    imager = None if kernel is None else _imager(values.shape[-2:], light.pixel_scale, inst, kernel,
                                                 light.boundary, values.dtype, workers,
                                                 _band_limited(band_limited, psf, inst))
    if imager is None:  # no PSF, or a grid that needs the reference resampling
        counts = expected_counts(light, inst, psf=psf, seeing=seeing, workers=workers,
                                 band_limited=band_limited)
    else:
        planes = image_planes(values, imager)
        counts = _counts(u.Quantity(planes, radiance_unit, copy=False), inst, values.dtype)
    if isinstance(values, DeferredStack):
        values.release()
    if truth is None:
        return counts, None, None
    truth_shape = getattr(truth, "planes", truth.data).shape
    truth_values = getattr(truth, "planes", None)
    if not isinstance(truth_values, DeferredStack) or truth_values.ndim != 2:
        truth_values = None
    periodic = truth.boundary == "periodic"
    factor = inst.supersampling
    exact_grid = (truth_values is not None and imager is not None and truth_shape == values.shape[-2:]
                  and truth.pixel_scale == light.pixel_scale)
    if exact_grid:
        truth_map = u.Quantity(pixel_means(truth_values.plane(), factor), truth_values.unit)
    else:
        truth_map = pixelize(truth.data, truth.pixel_scale, instrument=inst, periodic=periodic)
    if kernel is None:
        return counts, truth_map, truth_map.copy()
    if imager is None or truth_shape != values.shape[-2:] or truth.boundary != light.boundary:
        truth_psf = observe(truth.data, truth.pixel_scale, instrument=inst, psf=psf, seeing=seeing,
                            boundary=truth.boundary, workers=workers, band_limited=band_limited)
    elif exact_grid and isinstance(imager, BandLimitedImager):
        truth_psf = u.Quantity(imager(truth_values.plane()), truth_values.unit)
    else:
        data, unit = split_unit(truth.data, "truth.data")
        truth_psf = with_unit(imager(check_stack(data, "truth.data")), unit)
    if truth_values is not None:
        truth_values.release()
    return counts, truth_map, truth_psf


def _image_bands(values, truth, banded, inst):
    """`image_scene` of a light made by bands (`_banded`): one pass over its rows, the truth after it."""
    # float32 counts (0.8 GB for HMI's 12 × 4096² instead of 1.6): relative rounding 6e-8, far below
    # the photon noise of any pixel the camera draws from them (1/√λ, λ ≥ 1 e⁻ where light falls).
    counts = _counts(u.Quantity(banded(values.band, values.shape[0], dtype=np.float32), values.unit,
                                copy=False), inst, values.dtype)
    values.release()
    if truth is None:
        return counts, None, None
    data = getattr(truth, "planes", None)
    data = truth.data if not isinstance(data, DeferredStack) else data
    if data.shape != values.shape[-2:] or truth.boundary != "zero":
        raise ValueError(f"the truth of a light made by bands must be a (ny, nx) map on its grid with "
                         f"zero edges, got shape {data.shape} and boundary {truth.boundary!r}")
    unit = getattr(data, "unit", None)
    if isinstance(data, DeferredStack):
        plane = data.plane()
        truth_map = with_unit(pixel_means(plane, inst.supersampling), unit)
    else:
        plane = check_stack(split_unit(data, "truth.data")[0], "truth.data")
        truth_map = pixelize(data, truth.pixel_scale, instrument=inst, periodic=False)
    truth_psf = banded(lambda start, stop: np.asarray(plane[start:stop], dtype=banded.dtype)[None], 1,
                       common=False)[0]
    if isinstance(data, DeferredStack):
        data.release()
    return counts, truth_map, with_unit(truth_psf, unit)
