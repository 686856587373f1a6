r"""
HMI's point-spread function: the measured core and scattered-light wings of Wachter et al. (2012).

Wachter et al. (2012, Sol. Phys. 275, 261, "Image quality of the Helioseismic and Magnetic Imager
(HMI) onboard the Solar Dynamics Observatory", Sec. 4) describe HMI's PSF, measured on the ground
and checked on the solar limb in flight, as a Gaussian core plus a Lorentzian-like wing,

.. math::

    \mathrm{PSF}(r) \propto (1 - \epsilon)\, e^{-(r/\omega)^2}
        + \frac{\epsilon}{1 + (r/W)^k}, \qquad r = \frac{\pi D}{\lambda_0}\,\theta,

with :math:`\epsilon = 0.1`, :math:`\omega = 1.8`, :math:`W = 3`, :math:`k = 3` (the radius in
units of :math:`\lambda_0/(\pi D)` = 0.2895″ for D = 14 cm at 617.3 nm; the parameters as quoted by
Díaz Baso & Asensio Ramos 2018, A&A 614, A5, Sec. 2.2, who degrade simulations to HMI with it).
The core's FWHM is 0.87″ (the 14-cm Airy core's is 0.94″) and the wing falls as θ⁻³: about 43 %
of the light lies in it, 28 % beyond 1″, 3.1 % beyond 10″, 1.5 % beyond 20″ and 0.3 % beyond 100″
(`encircled_energy`).

`psf_profile` is the profile with unit integral over the plane, in arcsec⁻²; the shared optics
stage (`gongsynth.stages.psf`) takes it through ``HMIInstrument.psf_model`` and samples and
truncates it at the instrument's ``psf_radius`` like any instrument's PSF.  The instrument's
``aperture`` and ``line_wavelength`` set the radius unit; ``seeing_fwhm`` (0 in space) is ignored.

Yeo et al. (2014, A&A 561, A22) fit a different form to the Venus transit of 2012 (five
Gaussians with azimuthally varying amplitudes, convolved with the Airy function) and Norton et
al. (2025, arXiv:2511.13348) an Airy function convolved with a Lorentzian; their parameter tables
were not at hand in this work, so the Wachter et al. form is the one implemented (the Instruments
guide, ``instrument_hmi``, lists the comparison numbers).
"""
import math

import astropy.units as u
import numpy as np
import scipy.integrate

__all__ = ["WACHTER_2012", "psf_profile", "encircled_energy", "radius_unit"]

#: Wachter et al. (2012) PSF parameters: wing fraction ε of the peak, core width ω, wing width W
#: (both in units of λ0/(πD)) and wing exponent k.
WACHTER_2012 = {"epsilon": 0.1, "omega": 1.8, "width": 3.0, "exponent": 3.0}


def radius_unit(instrument):
    """
    λ0/(πD) in arcsec: the radius unit of the Wachter et al. (2012) form.

    Parameters
    ----------
    instrument : `~gongsynth.instruments.hmi.parameters.HMIInstrument`

    Returns
    -------
    float

    Examples
    --------
    >>> from gongsynth.instruments.hmi.parameters import HMIInstrument
    >>> round(radius_unit(HMIInstrument()), 4)
    0.2895
    """
    return float((instrument.line_wavelength / (math.pi * instrument.aperture)).to_value(u.one)
                 * u.rad.to(u.arcsec))


def _norm(p):
    """∫ PSF 2πr dr in units of the radius unit (before normalisation)."""
    eps, om, w, k = p["epsilon"], p["omega"], p["width"], p["exponent"]
    # ∫0^∞ x / (1 + x^k) dx = (π/k) / sin(2π/k), k > 2.
    return (1 - eps) * math.pi * om**2 + eps * 2 * math.pi * w**2 * (math.pi / k) / math.sin(2 * math.pi / k)


def psf_profile(radius, instrument, parameters=None):
    """
    HMI's PSF at radii in arcsec, unit integral over the plane (arcsec⁻²).

    Parameters
    ----------
    radius : `numpy.ndarray`
        Radii in arcsec (any shape).
    instrument : `~gongsynth.instruments.hmi.parameters.HMIInstrument`
        Its ``aperture`` and ``line_wavelength``.
    parameters : dict, optional
        Default `WACHTER_2012`.

    Returns
    -------
    `numpy.ndarray`
        Same shape as ``radius``.

    Examples
    --------
    >>> import numpy as np
    >>> from gongsynth.instruments.hmi.parameters import HMIInstrument
    >>> r = np.linspace(0, 400, 400001)
    >>> p = psf_profile(r, HMIInstrument())
    >>> round(float(np.sum(2 * np.pi * r * p) * (r[1] - r[0])), 3)    # 0.08 % beyond 400″
    0.999
    """
    p = WACHTER_2012 if parameters is None else parameters
    unit = radius_unit(instrument)
    x = np.asarray(radius, dtype=float) / unit
    core = (1 - p["epsilon"]) * np.exp(-(x / p["omega"]) ** 2)
    wing = p["epsilon"] / (1 + (x / p["width"]) ** p["exponent"])
    return (core + wing) / (_norm(p) * unit**2)


def encircled_energy(radius, instrument, parameters=None):
    """
    The fraction of a point source's light within ``radius`` (arcsec) of it.

    Parameters
    ----------
    radius : float
        Arcsec.
    instrument : `~gongsynth.instruments.hmi.parameters.HMIInstrument`
    parameters : dict, optional
        Default `WACHTER_2012`.

    Returns
    -------
    float

    Examples
    --------
    >>> from gongsynth.instruments.hmi.parameters import HMIInstrument
    >>> round(1 - encircled_energy(10.0, HMIInstrument()), 3)     # light beyond 10″
    0.031
    """
    p = WACHTER_2012 if parameters is None else parameters
    big_x = float(radius) / radius_unit(instrument)
    eps, om, w, k = p["epsilon"], p["omega"], p["width"], p["exponent"]
    core = (1 - eps) * math.pi * om**2 * (1 - math.exp(-(big_x / om) ** 2))
    wing = eps * 2 * math.pi * scipy.integrate.quad(lambda x: x / (1 + (x / w) ** k), 0, big_x, limit=200)[0]
    return (core + wing) / _norm(p)
