r"""
Integrating sampled spectra against an instrument's filtergrams (any instrument).

Every instrument gives its filtergram transmissions :math:`R_f(\lambda)`
(`~gongsynth.instruments.base.Instrument.responses`) and the window over
which they matter, :math:`\lambda_0 \pm` ``integration_half_width``, sampled
every ``quadrature_step``.  A spectrum known at a few wavelengths is
interpolated linearly and extended by its edge values (the continuum) over
that window (design §3.8), so that

.. math::

    \sum_j W_{fj} S_j = \int R_f(\lambda)\,S(\lambda)\,d\lambda

with the trapezoid rule on the fine grid.
"""
import functools
import math

import astropy.units as u
import numpy as np

from gongsynth.validation import check_wavelength_grid

__all__ = ["filter_quadrature", "channel_weights", "hat_weights"]


@functools.lru_cache(maxsize=32)
def filter_quadrature(inst):
    """
    The fine quadrature of an instrument's filtergrams (cached per instrument).

    Parameters
    ----------
    inst : `~gongsynth.instruments.base.Instrument`
        Any instrument of the family (hashable).

    Returns
    -------
    grid : `numpy.ndarray`
        Wavelengths in nm: λ0 ± ``integration_half_width`` every ``quadrature_step``.
    dlam : `numpy.ndarray`
        Trapezoid weights in nm.
    responses : `numpy.ndarray`
        (n_filtergrams, n) transmissions on the grid.
    """
    lam0 = inst.line_wavelength.to_value(u.nm)
    half = inst.integration_half_width.to_value(u.nm)
    step = inst.quadrature_step.to_value(u.nm)
    n = int(math.ceil(2 * half / step)) + 1
    grid = np.linspace(lam0 - half, lam0 + half, n)
    dlam = np.full(n, grid[1] - grid[0])
    dlam[[0, -1]] /= 2
    return grid, dlam, np.asarray(inst.responses(grid * u.nm).to_value(u.one))


def hat_weights(lam, grid):
    """
    Linear-interpolation weights of every fine quadrature point onto a spectral grid.

    Parameters
    ----------
    lam : `numpy.ndarray`
        The spectrum's sampling (strictly increasing, ≥ 2 points).
    grid : `numpy.ndarray`
        The fine quadrature points, same unit.

    Returns
    -------
    k : `numpy.ndarray`
        Index of the sample left of each fine point (clipped to the grid).
    t : `numpy.ndarray`
        Its fractional position in [0, 1] (edge values beyond the samples).
    """
    k = np.clip(np.searchsorted(lam, grid, side="right") - 1, 0, lam.size - 2)
    t = np.clip((grid - lam[k]) / (lam[k + 1] - lam[k]), 0.0, 1.0)
    return k, t


@u.quantity_input
def channel_weights(wavelength: u.nm, instrument=None):
    r"""
    Quadrature weights that integrate a sampled spectrum against each filtergram.

    For a spectrum :math:`S_j` sampled at ``wavelength`` (any, possibly
    non-uniform, increasing grid), :math:`\sum_j W_{ij} S_j = \int \bar R_i(\lambda)
    S(\lambda)\,d\lambda`, where :math:`S(\lambda)` is the piecewise-linear
    interpolant of the samples, extended by its edge values (the continuum) out
    to :math:`\lambda_0 \pm` ``integration_half_width`` (design §3.8).

    Parameters
    ----------
    wavelength : `~astropy.units.Quantity`
        Strictly increasing wavelengths, shape (nλ,), nλ ≥ 2, that must contain
        the line centre.
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
        Any instrument of the family (default GONG, whose three sector
        responses give a (3, nλ) result).

    Returns
    -------
    `~astropy.units.Quantity`
        Shape (n_filtergrams, nλ), in nm: ``W @ S`` has the units of the
        spectrum times nm.

    Examples
    --------
    >>> import astropy.units as u
    >>> import numpy as np
    >>> lam = np.linspace(676.73, 676.83, 51) * u.nm
    >>> w = channel_weights(lam)
    >>> w.shape, w.unit
    ((3, 51), Unit("nm"))
    """
    from gongsynth.instruments import get
    inst = get(instrument)
    lam = check_wavelength_grid(wavelength, inst.line_wavelength, "wavelength").to_value(u.nm)
    grid, dlam, resp = filter_quadrature(inst)
    k, t = hat_weights(lam, grid)
    weights = np.empty((resp.shape[0], lam.size))
    for i in range(resp.shape[0]):
        rw = resp[i] * dlam
        weights[i] = (np.bincount(k, rw * (1 - t), minlength=lam.size)
                      + np.bincount(k + 1, rw * t, minlength=lam.size))
    return u.Quantity(weights, u.nm)
