"""Synthetic line profiles with known Doppler and Zeeman shifts, for tests."""
import math

import astropy.units as u
import numpy as np

#: Speed of light in m/s.
C_LIGHT = 299792458.0


def gaussian_line(wavelength, centre, *, fwhm=10 * u.pm, depth=0.6):
    """Continuum-normalised Gaussian absorption line (dimensionless ndarray)."""
    sigma = (fwhm / (2 * math.sqrt(2 * math.log(2)))).to_value(u.nm)
    x = (wavelength - centre).to_value(u.nm)
    return 1 - depth * np.exp(-0.5 * (x / sigma) ** 2)


def zeeman_shift(field, instrument):
    """Wavelength shift of the sigma components, 4.67e-13 g lambda0^2 B (in nm)."""
    lam_a = instrument.line_wavelength.to_value(u.AA)
    g = instrument.lande_g.to_value(u.one)
    return 4.6686e-13 * g * lam_a**2 * field.to_value(u.G) * u.AA


