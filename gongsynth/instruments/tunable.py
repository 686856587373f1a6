"""
What the tunable-filter magnetographs (HMI, MDI) share.

Both take a few narrow filtergrams across one line (HMI six, MDI five), each
a transmission R_k(λ) sampled on the instrument's fine quadrature in mÅ about
the line; both calibrate their velocities with a Gaussian reference line
passed through those filters, and both count the photons of a filtergram
from its equivalent width W_k = ∫ R_k dλ.
"""
from __future__ import annotations

import astropy.constants as const
import astropy.units as u
import numpy as np

from gongsynth.instruments.hmi.profiles import gaussian_line

__all__ = ["filtergram_electrons", "reference_line_filtergrams"]


def filtergram_electrons(instrument, intensity, widths):
    """
    Electrons per filtergram (one exposure) of a continuum of specific intensity ``intensity``.

    N_k = I W_k Ω_pixel A_eff QE t_exp / (h c / λ0).

    Parameters
    ----------
    instrument : `~gongsynth.instruments.base.Instrument`
        Supplies ``line_wavelength``, ``plate_scale``, ``effective_area``,
        ``quantum_efficiency`` and ``exposure_time``.
    intensity : `~astropy.units.Quantity`
        Specific intensity per unit wavelength.
    widths : array_like
        W_k = ∫ R_k dλ of the filtergrams, in mÅ.

    Returns
    -------
    `~astropy.units.Quantity`
        Shape of ``widths``, in electron.
    """
    photon = (const.h * const.c / instrument.line_wavelength).to(u.erg)
    pixel = (instrument.plate_scale**2).to(u.sr)
    n = (intensity * np.asarray(widths) * u.Unit("mAA") * pixel * instrument.effective_area
         * instrument.quantum_efficiency * instrument.exposure_time / photon)
    return n.to(u.one).value * u.electron


def reference_line_filtergrams(shift, quadrature, depth, fwhm):
    """
    Filtergrams of a Gaussian line of ``depth`` and ``fwhm`` shifted by ``shift``, for a unit continuum.

    Parameters
    ----------
    shift : array_like
        Shifts λ_line − λ0 in mÅ, shape (n,).
    quadrature : tuple
        ``(offset, weights, responses)``: the instrument's fine quadrature
        in mÅ about the line, responses of shape (K, m).
    depth : float
        Line depth (fraction of the continuum).
    fwhm : float
        Line FWHM in mÅ.

    Returns
    -------
    `numpy.ndarray`
        Shape (K, n), in mÅ (∫ R_k I dλ).
    """
    offset, weights, responses = quadrature
    shift = np.atleast_1d(np.asarray(shift, dtype=float))
    # The line only matters within a few widths of the largest shift: integrate the dip there.
    near = np.abs(offset) <= np.abs(shift).max() + 6 * fwhm
    dip = 1 - gaussian_line(offset[near][None, :], depth, fwhm, shift[:, None])
    return (responses @ weights)[:, None] - (responses[:, near] * weights[near]) @ dip.T
