r"""
The HMI filter model: front window × blocker × Lyot E1-E5 × two tunable Michelsons.

Each birefringent or Michelson element transmits (Couvidat et al. 2012a, Eq. 1)

.. math::

    T_e(\lambda) = \tfrac12\Big[1 + C_e \cos\Big(\frac{2\pi(\lambda - \lambda_e)}{\mathrm{FSR}_e}
        + \phi_e\Big)\Big],

with free spectral range FSR_e and contrast C_e.  The three tunable elements
(NB and WB Michelsons, Lyot E1) are centred at the tuning position
:math:`\lambda_e = \lambda_0 + \delta_k`, :math:`\delta_k = (2.5 - k)\,\Delta` with
Δ = 68.8 mÅ (filtergram I_k, k = 0..5); E2-E5 stay centred on the line
(φ_e = ``nontunable_phase``).  The front window and the blocker are smooth
band-passes fitted to their measured profiles,
:math:`T(\lambda) = T_\mathrm{peak} / [1 + (2(\lambda-\lambda_c)/w)^4]`.  The
filtergram transmission is the product

.. math:: R_k(\lambda) = T_\mathrm{W} T_\mathrm{B} \prod_{e=E2}^{E5} T_e
          \; T_{E1}^{(k)} T_\mathrm{WB}^{(k)} T_\mathrm{NB}^{(k)}.

The FSRs double from one element to the next (172, 344, 695, 1417, ... mÅ), so
the product is close to an ideal Lyot profile
:math:`[\sin(2^7 x)/(2^7 \sin x)]^2`, whose FWHM is 0.443 FSR_NB = 76 mÅ.
Phases are linear in λ (the 1/λ dependence of a real retarder changes the
phase by < 0.4 % over the ±2 nm integrated).
"""
import functools
import math

import astropy.units as u
import numpy as np

from gongsynth.instruments.hmi.parameters import N_TUNINGS, resolve_hmi
from gongsynth.validation import check_quantity

__all__ = ["element_transmission", "bandpass_transmission", "fixed_transmission",
           "filtergram_responses", "filter_quadrature", "filtergram_weights", "profile_width"]


def _mA(wavelength, name="wavelength"):
    return check_quantity(wavelength, u.nm, name).to_value(u.Unit("mAA"))


def element_transmission(offset, fsr, contrast, phase=0.0):
    """
    Transmission (1 + C cos(2π offset / FSR + φ)) / 2 of one Lyot element or Michelson.

    Parameters
    ----------
    offset : array_like
        λ − λ_e, in the unit of ``fsr``.
    fsr : float
        Free spectral range.
    contrast : float
        Contrast C in [0, 1].
    phase : float
        Phase φ in radians.

    Returns
    -------
    `numpy.ndarray`

    Examples
    --------
    >>> float(element_transmission(0.0, 172.0, 1.0)), float(element_transmission(86.0, 172.0, 1.0))
    (1.0, 0.0)
    """
    return 0.5 * (1 + contrast * np.cos(2 * math.pi * np.asarray(offset) / fsr + phase))


def bandpass_transmission(wavelength, center, fwhm, peak):
    """
    A two-cavity-like band-pass peak / (1 + (2(λ − λc)/w)⁴), for the front window and blocker.

    Parameters
    ----------
    wavelength, center, fwhm : `~astropy.units.Quantity`
        Lengths.
    peak : float
        Peak transmission.

    Returns
    -------
    `numpy.ndarray`
    """
    x = 2 * ((wavelength - center) / fwhm).to_value(u.one)
    return peak / (1 + x**4)


def fixed_transmission(wavelength, instrument=None):
    """
    The untuned part of the filter: front window × blocker × Lyot E2-E5.

    Parameters
    ----------
    wavelength : `~astropy.units.Quantity`
        Wavelengths, any shape.
    instrument : `~gongsynth.instruments.hmi.HMIInstrument`, optional

    Returns
    -------
    `~astropy.units.Quantity`
        Dimensionless, same shape as ``wavelength``.
    """
    inst = resolve_hmi(instrument)
    lam = check_quantity(wavelength, u.nm, "wavelength")
    offset = _mA(lam) - inst.line_wavelength.to_value(u.Unit("mAA"))
    t = bandpass_transmission(lam, inst.front_window_center, inst.front_window_fwhm,
                              inst.front_window_peak.to_value(u.one))
    t = t * bandpass_transmission(lam, inst.blocker_center, inst.blocker_fwhm,
                                  inst.blocker_peak.to_value(u.one))
    phase = inst.nontunable_phase.to_value(u.rad)
    for fsr, contrast in _elements(inst, ("e2", "e3", "e4", "e5")):
        t = t * element_transmission(offset, fsr, contrast, phase)
    return u.Quantity(t, u.one)


def _elements(inst, names):
    """(FSR in mÅ, contrast) of the named elements."""
    return [(getattr(inst, f"{n}_fsr").to_value(u.Unit("mAA")),
             getattr(inst, f"{n}_contrast").to_value(u.one)) for n in names]


@u.quantity_input
def filtergram_responses(wavelength: u.nm, instrument=None):
    """
    Transmission R_k(λ) of the six tuning positions I0..I5.

    Parameters
    ----------
    wavelength : `~astropy.units.Quantity`
        Wavelengths, shape (nλ,).
    instrument : `~gongsynth.instruments.hmi.HMIInstrument`, optional

    Returns
    -------
    `~astropy.units.Quantity`
        Dimensionless, shape (6, nλ); row k is filtergram I_k, centred near
        ``instrument.tuning_offsets[k]``.

    Examples
    --------
    >>> import astropy.units as u, numpy as np
    >>> r = filtergram_responses(617.33433 * u.nm + [-34.4, 34.4] * u.Unit("mAA"))
    >>> r.shape, bool(r[2, 1] > r[2, 0] and r[3, 0] > r[3, 1])   # I2 red of the line, I3 blue
    ((6, 2), True)
    """
    inst = resolve_hmi(instrument)
    lam = np.atleast_1d(check_quantity(wavelength, u.nm, "wavelength"))
    if lam.ndim != 1:
        raise ValueError(f"wavelength must be one-dimensional, got shape {lam.shape}")
    return u.Quantity(_responses(_mA(lam) - inst.line_wavelength.to_value(u.Unit("mAA")), inst), u.one)


def _responses(offset_mA, inst):
    """(6, n) responses on offsets λ − λ0 in mÅ."""
    lam = inst.line_wavelength + offset_mA * u.Unit("mAA")
    fixed = fixed_transmission(lam, inst).value
    tunable = _elements(inst, ("nb", "wb", "e1"))
    out = np.empty((N_TUNINGS,) + np.shape(offset_mA))
    for k, centre in enumerate(inst.tuning_offsets.to_value(u.Unit("mAA"))):
        t = fixed.copy()
        for fsr, contrast in tunable:
            t *= element_transmission(offset_mA - centre, fsr, contrast)
        out[k] = t
    return out


@functools.lru_cache(maxsize=16)
def filter_quadrature(inst):
    """
    The fine quadrature of the filter (cached per instrument).

    Parameters
    ----------
    inst : `~gongsynth.instruments.hmi.HMIInstrument`

    Returns
    -------
    offset : `numpy.ndarray`
        λ − λ0 in mÅ over ± ``integration_half_width`` every ``quadrature_step``.
    weights : `numpy.ndarray`
        Trapezoid weights in mÅ.
    responses : `numpy.ndarray`
        (6, n) filtergram responses on the grid.
    """
    half = inst.integration_half_width.to_value(u.Unit("mAA"))
    step = inst.quadrature_step.to_value(u.Unit("mAA"))
    n = int(math.ceil(2 * half / step)) + 1
    offset = np.linspace(-half, half, n)
    weights = np.full(n, offset[1] - offset[0])
    weights[[0, -1]] /= 2
    return offset, weights, _responses(offset, inst)


def filtergram_weights(wavelength, instrument=None):
    r"""
    Quadrature weights that integrate sampled spectra against the six filtergrams.

    For spectra :math:`S_j` on ``wavelength`` (increasing, possibly
    non-uniform), :math:`\sum_j W_{kj} S_j = \int R_k(\lambda) S(\lambda)\,d\lambda`,
    with S the piecewise-linear interpolant of the samples, extended by its
    edge values (the continuum) over λ0 ± ``integration_half_width``.

    Parameters
    ----------
    wavelength : `~astropy.units.Quantity`
        Shape (nλ,), at least two points.
    instrument : `~gongsynth.instruments.hmi.HMIInstrument`, optional

    Returns
    -------
    `~astropy.units.Quantity`
        Shape (6, nλ), in mÅ.
    """
    inst = resolve_hmi(instrument)
    lam = check_quantity(wavelength, u.nm, "wavelength")
    x = (lam - inst.line_wavelength).to_value(u.Unit("mAA"))
    if x.ndim != 1 or x.size < 2 or np.any(np.diff(x) <= 0):
        raise ValueError("wavelength must be a strictly increasing 1-D grid of at least two points")
    offset, weights, responses = filter_quadrature(inst)
    q = np.clip(offset, x[0], x[-1])
    j = np.clip(np.searchsorted(x, q) - 1, 0, x.size - 2)
    frac = (q - x[j]) / (x[j + 1] - x[j])
    out = np.zeros((N_TUNINGS, x.size))
    wr = responses * weights
    for k in range(N_TUNINGS):
        np.add.at(out[k], j, wr[k] * (1 - frac))
        np.add.at(out[k], j + 1, wr[k] * frac)
    return u.Quantity(out, u.Unit("mAA"))


def profile_width(offset, profile):
    """
    Peak position (parabola through the three highest samples) and FWHM of a single-peaked profile.

    Parameters
    ----------
    offset : array_like
        Uniform grid.
    profile : array_like
        Samples on ``offset``.

    Returns
    -------
    peak, fwhm : float
        In the unit of ``offset``; the FWHM between the linearly interpolated
        half-maximum crossings either side of the main peak.
    """
    x = np.asarray(offset, dtype=float)
    y = np.asarray(profile, dtype=float)
    i = int(np.argmax(y))
    if i == 0 or i == len(y) - 1:
        raise ValueError("the profile's maximum lies on the edge of the grid")
    den = y[i - 1] - 2 * y[i] + y[i + 1]
    peak = x[i] + 0.5 * (x[1] - x[0]) * (y[i - 1] - y[i + 1]) / den if den else x[i]
    half = 0.5 * y[i]
    left = i - np.argmax(y[i::-1] < half)
    right = i + np.argmax(y[i:] < half)
    x_left = np.interp(half, [y[left], y[left + 1]], [x[left], x[left + 1]])
    x_right = np.interp(half, [y[right], y[right - 1]], [x[right], x[right - 1]])
    return float(peak), float(x_right - x_left)
