r"""
The GONG filter chain: prefilter, Lyot, Michelson and rotating half-wave plate.

(Also ``gongsynth.filters``, the path promised in DESIGN §2, and the old
``gongsynth.stages.filters``; `channel_weights` and `filter_quadrature`, which
serve every instrument, live in `gongsynth.instruments.quadrature`.)

The transmission for a wave-plate angle :math:`\theta_w` is (paper Eq. 4 with
design §3.1: a half-wave plate rotates polarisation by twice its angle)

.. math::

    R_\mathrm{GONG}(\lambda, \theta_w) = R_p(\lambda)\,R_L(\lambda)\,
        \cos^2\!\Big(\frac{\pi\lambda_0^2}{\Delta\lambda_m\lambda} + \theta_m - 2\theta_w\Big).

A frame integrates the wave plate's sweep through a 30° sector, so the
response of sector *i* is the time average (design §3.2)

.. math::

    \bar R_i(\lambda) = \frac{6}{\pi}\int_{i\pi/6}^{(i+1)\pi/6} R_\mathrm{GONG}\,d\theta_w
      = \frac{R_p R_L}{2}\Big[1 + \mathrm{sinc}\big(\tfrac{\pi}{3}\big)
        \cos\big(\psi(\lambda) + 2\theta_m - \tfrac{\pi}{3} - \tfrac{2\pi i}{3}\big)\Big],

with :math:`\psi = 2\pi\lambda_0^2/(\Delta\lambda_m\lambda)` and
:math:`\mathrm{sinc}(x) = \sin x / x`.  The three sectors are 120° apart in
modulation phase and the pattern repeats every 90° of wave-plate rotation.
"""

import math

import astropy.units as u
import numpy as np

from gongsynth.instruments.gong.parameters import resolve_instrument
from gongsynth.instruments.gong.planes import N_CHANNELS
from gongsynth.instruments.quadrature import channel_weights, filter_quadrature
from gongsynth.validation import check_quantity

__all__ = [
    "prefilter_transmission",
    "lyot_transmission",
    "michelson_phase",
    "waveplate_transmission",
    "channel_responses",
    "channel_weights",
    "modulation_amplitude",
    "filter_quadrature",
]



def _nm(wavelength, name="wavelength"):
    return check_quantity(wavelength, u.nm, name).to_value(u.nm)


@u.quantity_input
def prefilter_transmission(wavelength: u.nm, instrument=None):
    """
    Transmission of the interference prefilter.

    Parameters
    ----------
    wavelength : `~astropy.units.Quantity`
        Wavelengths (any length unit), any shape.
    instrument : `~gongsynth.GONGInstrument`, optional
        Chooses the form (``prefilter_form``), centre and width.

    Returns
    -------
    `~astropy.units.Quantity`
        Dimensionless transmission, same shape as ``wavelength``.

    Examples
    --------
    >>> import astropy.units as u
    >>> float(prefilter_transmission(676.78 * u.nm))
    1.0
    """
    inst = resolve_instrument(instrument)
    x = _nm(wavelength) - inst.prefilter_center.to_value(u.nm)
    w = inst.prefilter_fwhm.to_value(u.nm)
    if inst.prefilter_form == "memo":
        t = (1 + 1.6569 * (x / w) ** 2) ** -2
    else:
        t = 1 / (1 + (x / (w / 2)) ** 4)
    return u.Quantity(t, u.one)


@u.quantity_input
def lyot_transmission(wavelength: u.nm, instrument=None):
    r"""
    Transmission of the three-element Lyot filter (paper Eq. 3, design §3.3).

    :math:`R_L = \prod_{k=1}^{3} \cos^2(2^{k-1}\pi\Delta h/\lambda - \theta_k)`.

    Parameters
    ----------
    wavelength : `~astropy.units.Quantity`
        Wavelengths, any shape.
    instrument : `~gongsynth.GONGInstrument`, optional

    Returns
    -------
    `~astropy.units.Quantity`
        Dimensionless transmission.

    Examples
    --------
    >>> import astropy.units as u
    >>> round(float(lyot_transmission(676.78 * u.nm)), 2)
    0.99
    """
    inst = resolve_instrument(instrument)
    lam = _nm(wavelength)
    dh = inst.lyot_delta_h.to_value(u.nm)
    angles = [inst.lyot_angle_1, inst.lyot_angle_2, inst.lyot_angle_3]
    t = np.ones_like(lam, dtype=float)
    for k, theta in enumerate(angles):
        t = t * np.cos(2**k * math.pi * dh / lam - theta.to_value(u.rad)) ** 2
    return u.Quantity(t, u.one)


@u.quantity_input
def michelson_phase(wavelength: u.nm, instrument=None):
    r"""
    Modulation phase :math:`\psi(\lambda) = 2\pi\lambda_0^2/(\Delta\lambda_m\lambda)`.

    The cos² of the Michelson has argument :math:`\psi/2 + \theta_m - 2\theta_w`.
    A shift of the spectrum by :math:`+\delta\lambda` changes ψ by about
    :math:`-2\pi\delta\lambda/\Delta\lambda_m`.

    Parameters
    ----------
    wavelength : `~astropy.units.Quantity`
    instrument : `~gongsynth.GONGInstrument`, optional

    Returns
    -------
    `~astropy.units.Quantity`
        In radians (not wrapped).

    Examples
    --------
    >>> import astropy.units as u
    >>> step = michelson_phase(676.78 * u.nm) - michelson_phase(676.78 * u.nm + 0.305 * u.AA)
    >>> round(float(step.to_value(u.rad)), 3)   # one free spectral range = one cycle
    6.283
    """
    inst = resolve_instrument(instrument)
    lam0 = inst.line_wavelength.to_value(u.nm)
    fsr = inst.michelson_fsr.to_value(u.nm)
    return u.Quantity(2 * math.pi * lam0**2 / (fsr * _nm(wavelength)), u.rad)


def modulation_amplitude(instrument=None):
    """
    Contrast of the modulated term after averaging over one sector.

    For a sector of width Δθ_w the 2θ_w term sweeps 4Δθ_w of modulation phase,
    so the average contrast is sinc(2Δθ_w) = sin(π/3)/(π/3) ≈ 0.827 for 30°.

    Parameters
    ----------
    instrument : `~gongsynth.GONGInstrument`, optional
        Supplies the wave-plate step per frame.

    Returns
    -------
    float
        Dimensionless contrast.

    Examples
    --------
    >>> round(modulation_amplitude(), 4)
    0.827
    """
    inst = resolve_instrument(instrument)
    half_sweep = 2 * inst.waveplate_step.to_value(u.rad)  # half of the 4Δθ sweep
    return float(math.sin(half_sweep) / half_sweep)


@u.quantity_input
def waveplate_transmission(wavelength: u.nm, angle: u.deg, instrument=None):
    """
    Instantaneous transmission R_GONG(λ, θ_w) of the whole chain.

    Parameters
    ----------
    wavelength : `~astropy.units.Quantity`
        Wavelengths, shape (nλ,) or broadcastable with ``angle``.
    angle : `~astropy.units.Quantity`
        Wave-plate angle θ_w, broadcastable with ``wavelength``.
    instrument : `~gongsynth.GONGInstrument`, optional

    Returns
    -------
    `~astropy.units.Quantity`
        Dimensionless, broadcast shape.

    Examples
    --------
    >>> import astropy.units as u
    >>> t0 = waveplate_transmission(676.78 * u.nm, 10 * u.deg)
    >>> t90 = waveplate_transmission(676.78 * u.nm, 100 * u.deg)
    >>> bool(abs(t0 - t90) < 1e-9)   # the pattern repeats every 90 degrees
    True
    """
    inst = resolve_instrument(instrument)
    envelope = (prefilter_transmission(wavelength, inst) * lyot_transmission(wavelength, inst)).value
    arg = (michelson_phase(wavelength, inst).value / 2 + inst.michelson_angle.to_value(u.rad)
           - 2 * angle.to_value(u.rad))
    return u.Quantity(envelope * np.cos(arg) ** 2, u.one)


def _sector_responses(lam_nm, inst):
    """(3, n) time-averaged sector responses at wavelengths ``lam_nm`` (floats, nm)."""
    lam = lam_nm * u.nm
    envelope = (prefilter_transmission(lam, inst) * lyot_transmission(lam, inst)).value
    psi = michelson_phase(lam, inst).value
    step = inst.waveplate_step.to_value(u.rad)
    contrast = modulation_amplitude(inst)
    theta_m = inst.michelson_angle.to_value(u.rad)
    out = np.empty((N_CHANNELS,) + lam_nm.shape)
    for i in range(N_CHANNELS):
        # cos² = (1 + cos 2·arg)/2; averaging -4θ_w over the sector leaves the
        # mid-sector angle and the contrast sinc(2Δθ_w) (module docstring).
        centre = (i + 0.5) * step
        out[i] = 0.5 * envelope * (1 + contrast * np.cos(psi + 2 * theta_m - 4 * centre))
    return out


@u.quantity_input
def channel_responses(wavelength: u.nm, instrument=None):
    """
    Time-averaged transmission of each of the three 30° wave-plate sectors.

    Parameters
    ----------
    wavelength : `~astropy.units.Quantity`
        Wavelengths, shape (nλ,).
    instrument : `~gongsynth.GONGInstrument`, optional

    Returns
    -------
    `~astropy.units.Quantity`
        Dimensionless, shape (3, nλ): R̄_i(λ) for sectors i = 0, 1, 2.

    Examples
    --------
    >>> import astropy.units as u
    >>> import numpy as np
    >>> r = channel_responses(np.linspace(676.7, 676.9, 5) * u.nm)
    >>> r.shape
    (3, 5)
    """
    lam = np.atleast_1d(_nm(wavelength))
    if lam.ndim != 1:
        raise ValueError(f"wavelength must be one-dimensional, got shape {lam.shape}")
    return u.Quantity(_sector_responses(lam, resolve_instrument(instrument)), u.one)
