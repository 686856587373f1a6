r"""
The MDI filter model: front window × blocker × Lyot filter × two tunable Michelsons.

MDI's last filter stage is a pair of tunable Michelson interferometers of free
spectral range FSR_N = 189 mÅ (narrow) and FSR_W = 377 mÅ (wide) behind a
Lyot filter of 465 mÅ FWHM, an 8 Å blocker and the front window (Scherrer et
al. 1995).  Each Michelson transmits

.. math::

    T(\lambda) = \tfrac12\Big[1 + C\cos\frac{2\pi(\lambda - \lambda_0 - \delta_k)}{\mathrm{FSR}}\Big],

both tuned to the filtergram's position :math:`\delta_k`: F1..F4 at
−113.4, −37.8, +37.8, +113.4 mÅ and F0 at +189 mÅ, i.e. half a wide-Michelson
period from the line centre, where the narrow Michelson repeats itself: F0
has two equal peaks at ±189 mÅ in the line's wings.  The Lyot filter is
modelled as an ideal one of N elements whose free spectral ranges double from
the narrowest F_L,

.. math:: T_L(\lambda) = \prod_{j=0}^{N-1} \cos^2\frac{\pi(\lambda-\lambda_0)}{2^j F_L}
          = \Big[\frac{\sin(2^N y)}{2^N \sin y}\Big]^2,\qquad y = \frac{\pi(\lambda - \lambda_0)}{2^N F_L},

with F_L set so that its FWHM is the documented 465 mÅ; the front window and
the blocker are band-passes :math:`1/[1 + (2(\lambda-\lambda_0)/w)^4]`
centred on the line (their peak transmissions are absorbed in the effective
area).  The filtergram transmission is

.. math:: R_k(\lambda) = T_\mathrm{W}\,T_\mathrm{B}\,T_L\,T_N^{(k)}\,T_W^{(k)}.

Two consequences of the documented numbers are kept as they come out: the
two Michelsons alone have a FWHM of 0.457 FSR_N = 86 mÅ (the documented
94 mÅ is wider: see the guide), and F1 and F4 carry a secondary peak one wide
period (377 mÅ) from the main one, damped only by the Lyot filter.
"""
import functools
import math

import astropy.units as u
import numpy as np

from gongsynth.instruments import quadrature
from gongsynth.instruments.hmi.filters import bandpass_transmission, element_transmission
from gongsynth.instruments.mdi.parameters import N_TUNINGS, resolve_mdi
from gongsynth.validation import check_quantity

__all__ = ["lyot_transmission", "lyot_narrowest_fsr", "fixed_transmission", "filtergram_responses",
           "filter_quadrature"]

_mA = u.Unit("mAA")


def lyot_transmission(offset, narrowest_fsr, elements):
    """
    An ideal Lyot filter of ``elements`` stages: the product of cos²(π x / (2^j F_L)).

    Parameters
    ----------
    offset : array_like
        λ − λ0, in the unit of ``narrowest_fsr``.
    narrowest_fsr : float
        FSR F_L of the narrowest-period element.
    elements : int
        Number of stages N (FSRs F_L, 2F_L, ..., 2^(N-1) F_L).

    Returns
    -------
    `numpy.ndarray`

    Examples
    --------
    >>> float(lyot_transmission(0.0, 1000.0, 4)), round(float(lyot_transmission(500.0, 1000.0, 4)), 12)
    (1.0, 0.0)
    """
    x = np.asarray(offset, dtype=float)
    t = np.ones_like(x)
    for j in range(elements):
        t = t * np.cos(math.pi * x / (2**j * narrowest_fsr)) ** 2
    return t


@functools.lru_cache(maxsize=16)
def _fwhm_per_fsr(elements):
    """FWHM / F_L of an ideal Lyot filter of ``elements`` stages (bisection on the half maximum)."""
    low, high = 0.0, 0.5  # the first null is at x = F_L / 2
    for _ in range(80):
        mid = (low + high) / 2
        if lyot_transmission(mid, 1.0, elements) > 0.5:
            low = mid
        else:
            high = mid
    return 2 * low


def lyot_narrowest_fsr(instrument=None):
    """
    The narrowest element's FSR F_L that gives the Lyot filter its documented FWHM.

    Parameters
    ----------
    instrument : `~gongsynth.instruments.mdi.MDIInstrument`, optional

    Returns
    -------
    `~astropy.units.Quantity`
        In mÅ (1049 mÅ for 465 mÅ and 5 elements: FWHM = 0.443 F_L).

    Examples
    --------
    >>> round(float(lyot_narrowest_fsr().value))
    1049
    """
    inst = resolve_mdi(instrument)
    return inst.lyot_fwhm.to(_mA) / _fwhm_per_fsr(inst.lyot_elements)


def fixed_transmission(wavelength, instrument=None):
    """
    The untuned part of the filter: front window × blocker × Lyot filter.

    Parameters
    ----------
    wavelength : `~astropy.units.Quantity`
        Wavelengths, any shape.
    instrument : `~gongsynth.instruments.mdi.MDIInstrument`, optional

    Returns
    -------
    `~astropy.units.Quantity`
        Dimensionless, same shape as ``wavelength``; 1 at the line centre.
    """
    inst = resolve_mdi(instrument)
    lam = check_quantity(wavelength, u.nm, "wavelength")
    return u.Quantity(_fixed((lam - inst.line_wavelength).to_value(_mA), inst), u.one)


def _fixed(offset_mA, inst):
    """`fixed_transmission` on offsets λ − λ0 in mÅ."""
    lam = inst.line_wavelength + offset_mA * _mA
    t = bandpass_transmission(lam, inst.line_wavelength, inst.front_window_fwhm, 1.0)
    t = t * bandpass_transmission(lam, inst.line_wavelength, inst.blocker_fwhm, 1.0)
    return t * lyot_transmission(offset_mA, lyot_narrowest_fsr(inst).to_value(_mA), inst.lyot_elements)


@u.quantity_input
def filtergram_responses(wavelength: u.nm, instrument=None):
    """
    Transmission R_k(λ) of the five filtergrams F0..F4.

    Parameters
    ----------
    wavelength : `~astropy.units.Quantity`
        Wavelengths, shape (nλ,).
    instrument : `~gongsynth.instruments.mdi.MDIInstrument`, optional

    Returns
    -------
    `~astropy.units.Quantity`
        Dimensionless, shape (5, nλ); row k is F_k, centred near
        ``instrument.tuning_offsets[k]`` (F0: twin peaks at ±189 mÅ).

    Examples
    --------
    >>> import astropy.units as u
    >>> r = filtergram_responses(676.78 * u.nm + [-37.8, 37.8] * u.Unit("mAA"))
    >>> r.shape, bool(r[2, 0] > r[2, 1] and r[3, 1] > r[3, 0])   # F2 blue of the line, F3 red
    ((5, 2), True)
    """
    inst = resolve_mdi(instrument)
    lam = np.atleast_1d(check_quantity(wavelength, u.nm, "wavelength"))
    if lam.ndim != 1:
        raise ValueError(f"wavelength must be one-dimensional, got shape {lam.shape}")
    return u.Quantity(_responses((lam - inst.line_wavelength).to_value(_mA), inst), u.one)


def _responses(offset_mA, inst):
    """(5, n) responses on offsets λ − λ0 in mÅ."""
    fixed = _fixed(offset_mA, inst)
    michelsons = [(inst.nb_fsr.to_value(_mA), inst.nb_contrast.to_value(u.one)),
                  (inst.wb_fsr.to_value(_mA), inst.wb_contrast.to_value(u.one))]
    out = np.empty((N_TUNINGS,) + np.shape(offset_mA))
    for k, centre in enumerate(inst.tuning_offsets.to_value(_mA)):
        t = fixed.copy()
        for fsr, contrast in michelsons:
            t *= element_transmission(offset_mA - centre, fsr, contrast)
        out[k] = t
    return out


@functools.lru_cache(maxsize=16)
def filter_quadrature(inst):
    """
    The family's fine quadrature of the filter (`gongsynth.instruments.quadrature`) in mÅ about the line.

    Parameters
    ----------
    inst : `~gongsynth.instruments.mdi.MDIInstrument`

    Returns
    -------
    offset : `numpy.ndarray`
        λ − λ0 in mÅ over ± ``integration_half_width`` every ``quadrature_step``.
    weights : `numpy.ndarray`
        Trapezoid weights in mÅ.
    responses : `numpy.ndarray`
        (5, n) filtergram responses on the grid.
    """
    grid, dlam, responses = quadrature.filter_quadrature(inst)
    per_nm = (1 * u.nm).to_value(_mA)
    return (grid - inst.line_wavelength.to_value(u.nm)) * per_nm, dlam * per_nm, responses
