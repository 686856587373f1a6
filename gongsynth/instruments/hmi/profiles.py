r"""
Analytic line profiles for HMI's look-up tables and validation (independent of `gongsynth.sun`).

`gaussian_line` is the reference line of the look-up tables; `zeeman_triplet`
builds Stokes I and V of a weak normal Zeeman triplet from it (Gaussian π and
σ components, optically thin):

.. math::

    I = 1 - d\Big[\phi_\pi \frac{\sin^2\gamma}{2}
        + (\phi_b + \phi_r)\frac{1 + \cos^2\gamma}{4}\Big],\qquad
    V = d\cos\gamma\,\frac{\phi_b - \phi_r}{2},

with :math:`\phi_{b,r}` the line shape centred at :math:`\mp\Delta\lambda_B`,
:math:`\Delta\lambda_B = e\lambda_0^2 g B / (4\pi m_e c^2)`.  For B > 0
(toward the observer) this is gongsynth's convention V ≈ −Δλ_B cosγ dI/dλ.
"""
import math

import astropy.constants as const
import astropy.units as u
import numpy as np

__all__ = ["gaussian_line", "zeeman_shift", "zeeman_triplet"]


def gaussian_line(offset, depth, fwhm, shift=0.0):
    """
    Normalised Gaussian absorption line 1 − d exp(−(x − x_s)²/σ²), σ = FWHM / (2√ln2).

    Parameters
    ----------
    offset : array_like
        λ − λ0 (same unit as ``fwhm`` and ``shift``).
    depth, fwhm, shift : float or array_like
        Broadcast against ``offset``.

    Returns
    -------
    `numpy.ndarray`

    Examples
    --------
    >>> float(gaussian_line(0.0, 0.6, 100.0)), float(gaussian_line(50.0, 0.6, 100.0))
    (0.4, 0.7)
    """
    sigma = np.asarray(fwhm) / (2 * math.sqrt(math.log(2)))
    return 1 - np.asarray(depth) * np.exp(-((np.asarray(offset) - shift) / sigma) ** 2)


def zeeman_shift(field, lande_g, wavelength):
    """
    Splitting Δλ_B = e λ0² g B / (4π m_e c²) of the σ components (Gaussian units).

    Parameters
    ----------
    field : `~astropy.units.Quantity`
        B in G (or T).
    lande_g : float
    wavelength : `~astropy.units.Quantity`

    Returns
    -------
    `~astropy.units.Quantity`
        In mÅ.

    Examples
    --------
    >>> import astropy.units as u
    >>> round(float(zeeman_shift(1000 * u.G, 2.5, 617.33433 * u.nm).value), 2)   # 4.67e-13 g λ² B
    44.48
    """
    b = field.to_value(u.G)
    lam = wavelength.to_value(u.cm)
    m_c2 = const.m_e.cgs.value * const.c.cgs.value**2
    cm = const.e.gauss.value * lam**2 * lande_g * b / (4 * math.pi * m_c2)
    return (cm * u.cm).to(u.Unit("mAA"))


def zeeman_triplet(offset, shift, split, gamma, depth, fwhm):
    """
    Stokes I and V of a weak normal Zeeman triplet with Gaussian components.

    Parameters
    ----------
    offset : array_like
        λ − λ0 in mÅ.
    shift : float
        Doppler shift of the line in mÅ (positive = redshift).
    split : float
        Δλ_B in mÅ (`zeeman_shift`; its sign is that of B_LOS).
    gamma : float
        Inclination of the field to the line of sight, radians.
    depth, fwhm : float
        Central depth and FWHM (mÅ) of the unsplit line.

    Returns
    -------
    stokes_i, stokes_v : `numpy.ndarray`
        Relative to the continuum.
    """
    pi, blue, red = (1 - gaussian_line(offset, 1, fwhm, shift + s) for s in (0.0, -split, split))
    stokes_i = 1 - depth * (pi * math.sin(gamma) ** 2 / 2 + (blue + red) * (1 + math.cos(gamma) ** 2) / 4)
    stokes_v = depth * math.cos(gamma) * (blue - red) / 2
    return stokes_i, stokes_v
