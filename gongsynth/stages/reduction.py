r"""
The reduction stage: K raw planes to a magnetogram, a Dopplergram and a continuum.

Shared by every instrument (the paper's Sec. 3.3 steps 1-2):

1. subtract the dark, scaled by the number of frames in each plane;
2. divide by the flat (normalised by its median);

then the instrument's own algorithm (`~gongsynth.instruments.base.Instrument.algorithm`):
GONG's three-phase √3 arctan (`gongsynth.instruments.gong.reduction`), HMI's
Fourier coefficients and look-up tables.
"""
import dataclasses
import importlib
import os
from concurrent.futures import ThreadPoolExecutor

import astropy.units as u
import numpy as np

from gongsynth.instruments import get
from gongsynth.instruments.base import Observables
from gongsynth.stages.camera.detector import normalise_flat, read_dark
from gongsynth.stages.psf import fft_workers
from gongsynth.validation import check_finite, check_quantity

__all__ = ["Observables", "reduce", "algorithm", "subtract_dark", "divide_flat"]

#: Pixels reduced at a time (a band of detector rows): the dark, flat and the algorithm's
#: temporaries of a full-disk HMI frame (12 × 4096² planes) stay bounded.  GONG's 860² frame is one band.
BAND_PIXELS = 1 << 20

# GONG's algorithm moved to its instrument; its old path here still resolves.
_MOVED = {"measured_phase", "phase_to_velocity", "reference_phase"}


def __getattr__(name):
    if name in _MOVED:
        from gongsynth.instruments.gong import reduction
        return getattr(reduction, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _planes(raw, inst):
    """The (K, ...) float array of a RawPlanes-like object or an array."""
    data = getattr(raw, "data", raw)
    data = np.asarray(getattr(data, "value", data))
    if data.dtype != np.float32:       # float32 planes (HMI's whole DN) are widened a band at a time
        data = data.astype(float, copy=False)
    n_planes = len(inst.analysers)
    if data.ndim < 1 or data.shape[0] != n_planes:
        raise ValueError(
            f"raw must have a leading axis of {n_planes} planes ({', '.join(inst.plane_names)}) "
            f"for {inst.label}, got shape {data.shape}"
        )
    return check_finite(data, "raw")


def subtract_dark(planes, dark, frames_per_plane, instrument=None):
    """
    Subtract the accumulated dark current from raw planes.

    A dark rate of d electrons per frame adds on average
    ``frames_per_plane * d / gain / 2**truncate_bits`` DN to a truncated plane.

    Parameters
    ----------
    planes : `numpy.ndarray`
        Shape (K, ...), DN.
    dark : `~astropy.units.Quantity`
        Dark current in electron (per frame), shape ``planes.shape[1:]`` or scalar.
    frames_per_plane : array_like of int
        Frames accumulated in each plane, shape (K,).
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
        Supplies the gain and ``truncate_bits`` (default GONG).

    Returns
    -------
    `numpy.ndarray`
        Dark-subtracted planes, DN.

    Examples
    --------
    >>> import numpy as np
    >>> import astropy.units as u
    >>> planes = np.full((6, 1), 1000.0)
    >>> subtract_dark(planes, 264 * u.electron, [600] * 6)[:, 0].tolist()  # 600*264/33/8 = 600
    [400.0, 400.0, 400.0, 400.0, 400.0, 400.0]
    """
    inst = get(instrument)
    check_quantity(dark, u.electron, "dark")
    check_finite(dark, "dark")
    dark_dn = (dark / inst.gain).to_value(u.adu) / 2**inst.truncate_bits
    frames = _frames(frames_per_plane, planes.shape[0], planes.ndim)
    return planes - frames * dark_dn


def _frames(frames_per_plane, n_planes, ndim):
    frames = np.asarray(frames_per_plane, dtype=float)
    if frames.shape == ():
        frames = np.full(n_planes, float(frames))
    if frames.shape != (n_planes,) or np.any(frames <= 0):
        raise ValueError(f"frames_per_plane must be {n_planes} positive numbers, got {frames_per_plane!r}")
    return frames.reshape((n_planes,) + (1,) * (ndim - 1))


def divide_flat(planes, flat):
    """
    Divide planes by a median-normalised flat (`gongsynth.stages.camera.detector.normalise_flat`).

    Parameters
    ----------
    planes : `numpy.ndarray`
        Shape (K, ny, nx).
    flat : array_like or path-like
        (ny, nx) or (K, ny, nx), as given to the camera.

    Returns
    -------
    `numpy.ndarray`
        The flat-fielded planes.

    Examples
    --------
    >>> import numpy as np
    >>> divide_flat(np.full((6, 1, 2), 4.0), [[1.0, 2.0]])[0].tolist()  # median 1.5
    [[6.0, 3.0]]

    Returns
    -------
    `numpy.ndarray`
    """
    return planes / normalise_flat(flat, planes.shape[1:], planes.shape[0])


def reduce(raw, instrument=None, dark=None, flat=None, *, frames_per_plane=None, band_pixels=None,
           workers=None, **options):
    """
    Reduce K raw planes to a magnetogram, a Dopplergram and a (pseudo-)continuum.

    Parameters
    ----------
    raw : `~gongsynth.stages.camera.integrate.RawPlanes` or array_like
        The planes, shape (K, ...) in DN, in the instrument's plane order
        (GONG: six, as in `gongsynth.planes`).  Any spatial shape works
        (including none: a single pixel).
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
        Supplies the gain and truncation (dark subtraction) and the algorithm
        (`~gongsynth.instruments.base.Instrument.algorithm`; GONG's: v0, the
        Landé factor, the wrap margin and the filter model that fixes the
        velocity zero point).  Default GONG.
    dark : None, bool, `~astropy.units.Quantity`, str or path-like
        ``None`` or ``True`` (default): the dark the camera used, ``raw.dark``,
        when ``raw`` carries one, else no dark subtraction; ``False``: a zero
        dark (no subtraction, as after ``integrate(..., dark=False)``); a
        Quantity (electron per frame, scalar or the planes' shape) or a FITS
        path: that dark.
    flat : None, bool, array_like, str or path-like
        ``None`` or ``True`` (default): the flat the camera used, ``raw.flat``,
        when present, else none; ``False``: a unity flat (no division, as
        after ``integrate(..., flat=False)``); an array or a FITS path: that
        flat, as given to the camera.
    frames_per_plane : array_like of int, optional
        Frames in each plane; taken from ``raw.frames_per_plane`` if omitted.
        Needed only for the dark subtraction.
    band_pixels : int, optional
        A (K, ny, nx) frame of more pixels is reduced a band of rows of about
        this many pixels at a time (default `BAND_PIXELS`): the dark, the flat
        and the algorithm work pixel by pixel, so the result does not depend
        on it; only the temporaries' size does.
    workers : int, optional
        Threads reducing bands side by side (default: every core; numpy
        releases the GIL in its loops).  Each band is reduced alone, so the
        result is the same, bit for bit, for any number.
    **options
        Passed to the instrument's algorithm; GONG: ``wrap_margin``
        (`~astropy.units.Quantity`, angular distance from ±π below which a
        pixel is flagged as wrapped; default the instrument's, 0.3 rad).

    Returns
    -------
    `Observables`

    Examples
    --------
    A spectrum with a Gaussian Ni line at rest, as seen through the default
    filters, reduces to zero velocity and zero field:

    >>> import numpy as np
    >>> import astropy.units as u
    >>> from gongsynth.stages.filters import channel_weights
    >>> lam = np.linspace(676.6, 676.96, 721) * u.nm
    >>> line = 1 - 0.6 * np.exp(-0.5 * ((lam - 676.78 * u.nm) / (4.2466 * u.pm)) ** 2)
    >>> channels = channel_weights(lam).value @ line.value
    >>> obs = reduce(np.concatenate([channels, channels]))
    >>> abs(obs.doppler.to_value(u.m / u.s)) < 0.5, float(obs.magnetogram.to_value(u.G))
    (np.True_, 0.0)
    """
    inst = get(instrument)
    planes = _planes(raw, inst)
    # A RawPlanes carries what the camera used; a plain array (which has its
    # own unrelated ``.flat``) carries nothing.
    carried = {} if isinstance(raw, np.ndarray) or not hasattr(raw, "frames_per_plane") else {
        "dark": getattr(raw, "dark", None), "flat": getattr(raw, "flat", None),
        "frames": raw.frames_per_plane}
    dark = carried.get("dark") if dark is None or dark is True else dark
    flat = carried.get("flat") if flat is None or flat is True else flat
    if dark is not None and dark is not False:
        if frames_per_plane is None:
            frames_per_plane = carried.get("frames")
        if frames_per_plane is None:
            raise ValueError("frames_per_plane is needed to subtract a dark from a plain array")
        if isinstance(dark, (str, os.PathLike)):
            dark = read_dark(dark)
        check_quantity(dark, u.electron, "dark")
        check_finite(dark, "dark")
    else:
        dark = None
    if flat is not None and flat is not False:
        # Once: its median is the whole frame's, whatever the bands.
        flat = normalise_flat(flat, planes.shape[1:], planes.shape[0])
    else:
        flat = None

    def band(rows):
        part = (planes if rows is None else planes[:, rows]).astype(float, copy=False)
        if dark is not None:
            part = subtract_dark(part, dark if rows is None or dark.ndim < 2 else dark[rows],
                                 frames_per_plane, inst)
        if flat is not None:
            part = part / (flat if rows is None else flat[:, rows])
        return algorithm(inst)(part, inst, **options)

    band_rows = _band_rows(planes.shape, BAND_PIXELS if band_pixels is None else band_pixels)
    if band_rows is None:
        observed = band(None)
    else:
        bands = [slice(start, start + band_rows) for start in range(0, planes.shape[1], band_rows)]
        observed = _place(None, band(bands[0]), bands[0], planes.shape[1])
        with ThreadPoolExecutor(max(1, min(fft_workers(workers), len(bands) - 1))) as pool:
            # In order, as each is done: the temporaries of `workers` bands at a time.
            for rows, part in zip(bands[1:], pool.map(band, bands[1:])):
                observed = _place(observed, part, rows, planes.shape[1])
    continuum = u.Quantity(observed.continuum)
    if continuum.unit == u.one:
        # The planes given to the algorithm are plain numbers in DN: so is a continuum made from them.
        observed = dataclasses.replace(observed, continuum=u.Quantity(continuum.value, u.adu))
    return observed


def _band_rows(shape, band_pixels):
    """Rows per band of a (K, ny, nx) frame, or None: one pass over the whole frame (any other shape)."""
    if isinstance(band_pixels, bool) or not isinstance(band_pixels, (int, np.integer)) or band_pixels < 1:
        raise ValueError(f"band_pixels must be a positive int, got {band_pixels!r}")
    if len(shape) != 3 or shape[1] * shape[2] <= band_pixels:
        return None
    return max(1, int(band_pixels) // shape[2])


def _place(whole, part, rows, ny):
    """
    Put the `Observables` of a band of rows into those of the whole frame (each field's
    second-last axis; made from the first band's fields' shapes and types).
    """
    if whole is None:
        fields = {}
        for field in dataclasses.fields(part):
            value = getattr(part, field.name)
            if value is not None:
                data = np.empty(value.shape[:-2] + (ny,) + value.shape[-1:], dtype=value.dtype)
                unit = getattr(value, "unit", None)
                value = data if unit is None else u.Quantity(data, unit, copy=False)
            fields[field.name] = value
        whole = dataclasses.replace(part, **fields)
    for field in dataclasses.fields(part):
        value = getattr(part, field.name)
        if value is not None:
            target = getattr(whole, field.name)
            target = getattr(target, "value", target)
            target[..., rows, :] = getattr(value, "value", value)
    return whole


def algorithm(instrument):
    """
    The instrument's reduction algorithm, imported from where its ``algorithm`` names it.

    Parameters
    ----------
    instrument : `~gongsynth.instruments.base.Instrument`

    Returns
    -------
    callable
        ``f(planes, instrument, **options)`` → `Observables`.

    Examples
    --------
    >>> from gongsynth import instruments
    >>> algorithm(instruments.get("gong")).__name__
    'three_phase'
    """
    module, _, name = instrument.algorithm.partition(":")
    return getattr(importlib.import_module(module), name)
