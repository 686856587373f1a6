r"""
GONG-style reduction: six raw planes to Doppler velocity, B_LOS and continuum.

The steps follow the paper's Sec. 3.3:

1. subtract the dark, scaled by the number of frames in each plane;
2. divide by the flat (normalised by its median);
3. measure the phase of I+V and I-V with the √3 arctan (paper Eq. 5), resolve
   the quadrant, and reference it to the phase of a line at rest (design §3.4):
   :math:`v^\pm = v_0\,\mathrm{wrap}(\phi_\mathrm{ref} - \phi^\pm)`;
4. :math:`v = (v^+ + v^-)/2`, :math:`B_\mathrm{LOS} = k_B (v^+ - v^-)/2` with
   :math:`k_B = 4\pi m_e c/(e g \lambda_0)` (0.7038 G per m/s, paper Eq. 9);
5. the pseudo-continuum is the sum of the six planes (paper Eq. 11).

Each polarisation's phase is only defined within ±π, i.e. ±v0·π ≈ ±6.76 km/s
about the reference: with a line at rest |B| up to about 4.7 kG is measured
without wrapping, less when the line is Doppler shifted.  A wrapped pixel
cannot be recognised from its own six numbers, so `Observables.wrapped` flags
the pixels *at risk*: those where either polarisation's phase lies within
``wrap_margin`` (the instrument's, 0.3 rad ≈ 650 m/s ≈ 450 G by default) of ±π.  With a line at
rest that flags 4.3 kG < |B| < 5.2 kG; fields stronger still wrap to values
that look ordinary.
"""
import functools
import math
import os
from dataclasses import dataclass

import astropy.units as u
import numpy as np

from gongsynth.instrument import resolve_instrument
from gongsynth.planes import N_CHANNELS, N_PLANES
from gongsynth.stages.camera.detector import normalise_flat, read_dark
from gongsynth.stages.filters import filter_quadrature
from gongsynth.validation import check_finite, check_quantity

__all__ = ["Observables", "reduce", "subtract_dark", "divide_flat", "measured_phase", "phase_to_velocity",
           "reference_phase"]


@dataclass(frozen=True)
class Observables:
    """
    What the reduction measures in each pixel.

    Attributes
    ----------
    magnetogram : `~astropy.units.Quantity`
        Line-of-sight flux density B_LOS, in G.
    doppler : `~astropy.units.Quantity`
        Line-of-sight velocity (positive = redshift, away from the observer), in m/s.
    continuum : `~astropy.units.Quantity`
        Pseudo-continuum: sum of the six dark- and flat-corrected planes, in DN (adu).
    velocity : `~astropy.units.Quantity`
        Shape (2, ...): velocities of I+V and I-V, in m/s.
    phase : `~astropy.units.Quantity`
        Shape (2, ...): measured phases of I+V and I-V, in rad.
    wrapped : `numpy.ndarray` of bool
        True where a polarisation's phase is within the wrap margin of ±π, so
        the measurement may have wrapped (design §3.5).
    """

    magnetogram: u.Quantity
    doppler: u.Quantity
    continuum: u.Quantity
    velocity: u.Quantity
    phase: u.Quantity
    wrapped: np.ndarray


def _planes(raw):
    """The (6, ...) float array of a RawPlanes-like object or an array."""
    data = getattr(raw, "data", raw)
    data = np.asarray(getattr(data, "value", data), dtype=float)
    if data.ndim < 1 or data.shape[0] != N_PLANES:
        raise ValueError(
            f"raw must have a leading axis of {N_PLANES} planes (I+V ch0-2, I-V ch0-2), "
            f"got shape {data.shape}"
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
        Shape (6, ...), DN.
    dark : `~astropy.units.Quantity`
        Dark current in electron (per frame), shape ``planes.shape[1:]`` or scalar.
    frames_per_plane : array_like of int
        Frames accumulated in each plane, shape (6,).
    instrument : `~gongsynth.GONGInstrument`, optional

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
    inst = resolve_instrument(instrument)
    check_quantity(dark, u.electron, "dark")
    check_finite(dark, "dark")
    dark_dn = (dark / inst.gain).to_value(u.adu) / 2**inst.truncate_bits
    frames = _frames(frames_per_plane, planes.ndim)
    return planes - frames * dark_dn


def _frames(frames_per_plane, ndim):
    frames = np.asarray(frames_per_plane, dtype=float)
    if frames.shape == ():
        frames = np.full(N_PLANES, float(frames))
    if frames.shape != (N_PLANES,) or np.any(frames <= 0):
        raise ValueError(f"frames_per_plane must be {N_PLANES} positive numbers, got {frames_per_plane!r}")
    return frames.reshape((N_PLANES,) + (1,) * (ndim - 1))


def divide_flat(planes, flat):
    """
    Divide planes by a median-normalised flat (`gongsynth.stages.camera.detector.normalise_flat`).

    Parameters
    ----------
    planes : `numpy.ndarray`
        Shape (6, ny, nx).
    flat : array_like or path-like
        (ny, nx) or (6, ny, nx), as given to the camera.

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
    return planes / normalise_flat(flat, planes.shape[1:])


def phase_to_velocity(phase, instrument=None):
    """
    Velocity of a measured phase relative to the rest-line reference phase.

    Parameters
    ----------
    phase : array_like or `~astropy.units.Quantity`
        Measured phase (rad).
    instrument : `~gongsynth.GONGInstrument`, optional

    Returns
    -------
    `~astropy.units.Quantity`
        m/s; positive for a redshift (the Michelson phase falls with wavelength).

    Examples
    --------
    >>> phase_to_velocity(reference_phase() - 0.1 * u.rad).round(2)  # 0.1 rad * v0
    <Quantity 215.19 m / s>
    """
    inst = resolve_instrument(instrument)
    phase = u.Quantity(phase, u.rad).value
    delta = np.angle(np.exp(1j * (reference_phase(inst).value - phase)))
    return (inst.v0 * delta * u.rad).to(u.m / u.s)


def reduce(raw, instrument=None, dark=None, flat=None, *, frames_per_plane=None, wrap_margin=None):
    """
    Reduce six raw planes to a magnetogram, a Dopplergram and a pseudo-continuum.

    Parameters
    ----------
    raw : `~gongsynth.stages.camera.integrate.RawPlanes` or array_like
        The planes, shape (6, ...) in DN, ordered as in `gongsynth.planes`.
        Any spatial shape works (including none: a single pixel).
    instrument : `~gongsynth.GONGInstrument`, optional
        Supplies v0, the Landé factor, the gain, the truncation, the wrap
        margin and the filter model that fixes the velocity zero point.
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
    wrap_margin : `~astropy.units.Quantity`, optional
        Angular distance from ±π below which a pixel is flagged as wrapped;
        default the instrument's ``wrap_margin`` (0.3 rad).

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
    inst = resolve_instrument(instrument)
    planes = _planes(raw)
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
        planes = subtract_dark(planes, dark, frames_per_plane, inst)
    if flat is not None and flat is not False:
        planes = divide_flat(planes, flat)

    phases = np.stack([measured_phase(planes[p * N_CHANNELS:(p + 1) * N_CHANNELS])
                       for p in range(2)])
    velocity = phase_to_velocity(phases, inst)
    doppler = velocity.mean(axis=0)
    magnetogram = (inst.gauss_per_velocity * (velocity[0] - velocity[1]) / 2).to(u.G)
    wrap_margin = inst.wrap_margin if wrap_margin is None else wrap_margin
    margin = check_quantity(wrap_margin, u.rad, "wrap_margin").to_value(u.rad)
    offset = np.angle(np.exp(1j * (reference_phase(inst).value - phases)))
    wrapped = np.any(np.abs(offset) > math.pi - margin, axis=0)
    return Observables(
        magnetogram=magnetogram,
        doppler=doppler,
        continuum=u.Quantity(planes.sum(axis=0), u.adu),
        velocity=velocity,
        phase=u.Quantity(phases, u.rad),
        wrapped=wrapped,
    )


def measured_phase(channels):
    r"""
    GONG phase of three channel intensities (the √3 arctan, paper Eq. 5).

    :math:`\phi = \mathrm{atan2}\big(\sqrt3(I_1 - I_2),\ 2I_0 - I_1 - I_2\big)`,
    i.e. the paper's arctan with the quadrant resolved, so φ covers (-π, π].

    Parameters
    ----------
    channels : array_like
        Shape (3, ...): I_0, I_1, I_2.  Any units (they cancel).

    Returns
    -------
    `numpy.ndarray`
        Phase in radians, shape (...).

    Examples
    --------
    >>> import numpy as np
    >>> x = 0.4
    >>> channels = [1 + np.cos(x - 2 * np.pi * i / 3) for i in range(3)]
    >>> round(float(measured_phase(channels)), 6)
    0.4
    """
    i0, i1, i2 = (np.asarray(getattr(c, "value", c), dtype=float) for c in channels)
    return np.arctan2(math.sqrt(3) * (i1 - i2), 2 * i0 - i1 - i2)


def _reference_spectrum(lam_nm, inst):
    """Continuum-normalised Gaussian rest line used to fix the phase zero point."""
    sigma = inst.reference_line_fwhm.to_value(u.nm) / (2 * math.sqrt(2 * math.log(2)))
    depth = inst.reference_line_depth.to_value(u.one)
    lam0 = inst.line_wavelength.to_value(u.nm)
    return 1 - depth * np.exp(-0.5 * ((lam_nm - lam0) / sigma) ** 2)


@functools.lru_cache(maxsize=32)
def _reference_phase(inst):
    grid, dlam, resp = filter_quadrature(inst)
    spectrum = _reference_spectrum(grid, inst)
    return float(measured_phase(resp @ (spectrum * dlam)))


def reference_phase(instrument=None):
    """
    Phase that a line at rest produces: the zero point of GONG velocities.

    The Michelson's λ0/Δλ_m ≈ 22190 waves make θ_m useless as an absolute
    zero point (design §3.4), so velocities are measured relative to the phase
    of a Gaussian rest line (``reference_line_fwhm``, ``reference_line_depth``)
    pushed through the instrument's own filter chain.

    Parameters
    ----------
    instrument : `~gongsynth.GONGInstrument`, optional

    Returns
    -------
    `~astropy.units.Quantity`
        In radians, within (-π, π].

    Examples
    --------
    >>> phi = reference_phase()
    >>> phi.unit, bool(-3.15 < phi.value < 3.15)
    (Unit("rad"), True)
    """
    return _reference_phase(resolve_instrument(instrument)) * u.rad
