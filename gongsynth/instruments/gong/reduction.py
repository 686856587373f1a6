r"""
GONG's reduction algorithm: six corrected planes to Doppler velocity, B_LOS and continuum.

After the shared dark and flat correction (`gongsynth.stages.reduction.reduce`),
following the paper's Sec. 3.3:

1. measure the phase of I+V and I-V with the √3 arctan (paper Eq. 5), resolve
   the quadrant, and reference it to the phase of a line at rest (design §3.4):
   :math:`v^\pm = v_0\,\mathrm{wrap}(\phi_\mathrm{ref} - \phi^\pm)`;
2. :math:`v = (v^+ + v^-)/2`, :math:`B_\mathrm{LOS} = k_B (v^+ - v^-)/2` with
   :math:`k_B = 4\pi m_e c/(e g \lambda_0)` (0.7038 G per m/s, paper Eq. 9);
3. the pseudo-continuum is the sum of the six planes (paper Eq. 11).

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

import astropy.units as u
import numpy as np

from gongsynth.instruments.base import Observables
from gongsynth.instruments.gong.parameters import resolve_instrument
from gongsynth.instruments.gong.planes import N_CHANNELS, N_POLARISATIONS
from gongsynth.instruments.quadrature import filter_quadrature
from gongsynth.validation import check_quantity

__all__ = ["three_phase", "measured_phase", "phase_to_velocity", "reference_phase"]


def three_phase(planes, instrument=None, *, wrap_margin=None):
    """
    GONG's algorithm on six dark- and flat-corrected planes.

    Parameters
    ----------
    planes : `numpy.ndarray`
        Shape (6, ...) in DN, in `gongsynth.planes` order.
    instrument : `~gongsynth.GONGInstrument`, optional
        Supplies v0, the Landé factor, the wrap margin and the filter model
        that fixes the velocity zero point.
    wrap_margin : `~astropy.units.Quantity`, optional
        Angular distance from ±π below which a pixel is flagged as wrapped;
        default the instrument's ``wrap_margin`` (0.3 rad).

    Returns
    -------
    `~gongsynth.instruments.base.Observables`
    """
    inst = resolve_instrument(instrument)
    phases = np.stack([measured_phase(planes[p * N_CHANNELS:(p + 1) * N_CHANNELS])
                       for p in range(N_POLARISATIONS)])
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
