"""
The row layout of a full-disk patch library: what both builders derive from their arguments.

A library row holds, per analyser state, a spectrum's continuum and its
coordinates in the Doppler basis (`gongsynth.stages.scene.shifts`), then the
true B_z and B_x.  `library_layout` checks a builder's arguments and returns
the instrument, angles, analyser layout, basis and row weights that the
Milne-Eddington (`gongsynth.stages.scene.library`) and 3-D
(`gongsynth.stages.scene.library_rt`) builders share.
"""
from collections import namedtuple

import astropy.units as u
import numpy as np

from gongsynth import instruments
from gongsynth.stages.channels import analyser_coefficients
from gongsynth.stages.scene.shifts import shift_basis
from gongsynth.sun.photosphere import default_wavelength
from gongsynth.validation import check_quantity

__all__ = ["analyser_layout", "row_weights", "library_angles", "LibraryLayout", "library_layout"]


def analyser_layout(mueller=None):
    """
    How a library stores the analyser states of a global Mueller matrix.

    Parameters
    ----------
    mueller : array_like, optional
        A (4, 4) instrument Mueller matrix (default: identity).

    Returns
    -------
    n_e : int
        1 when both analyser states share their (I, Q, U) part, else 2.
    e_index : tuple of int
        Which stored E part each state uses.
    v_sign : tuple of float
        The weight of V in each state.
    e_weights : `numpy.ndarray`
        (n_e, 3): the weights of I, Q, U in each stored E part.
    mirror_ok : bool
        Whether patches may be mirrored (no state sees U).

    Examples
    --------
    >>> n_e, e_index, v_sign, e_weights, mirror_ok = analyser_layout()
    >>> n_e, e_index, v_sign, e_weights.tolist(), mirror_ok
    (1, (0, 0), (1.0, -1.0), [[1.0, 0.0, 0.0]], True)
    """
    coeff = analyser_coefficients(mueller)
    if coeff.ndim != 2:
        raise ValueError("the full-disk library takes one (4, 4) Mueller matrix for the whole field")
    e_rows = coeff[:, :3]
    if np.array_equal(e_rows[0], e_rows[1]):
        n_e, e_index, weights = 1, (0, 0), e_rows[:1]
    else:
        n_e, e_index, weights = 2, (0, 1), e_rows
    return n_e, e_index, tuple(float(c) for c in coeff[:, 3]), weights, bool(np.all(e_rows[:, 2] == 0))


def row_weights(basis, e_weights, ld):
    """
    The weights that turn Stokes spectra into a stored row's spectral part (all but B_z, B_x).

    A row is, per analyser E part and for V, the continuum (the mean of the
    first and last samples) and the basis coordinates ``E_k · (S - S_cont)``,
    divided by the continuum limb darkening ``ld``: all linear in the Stokes
    spectra, so a synthesis can contract each column's spectra with them
    without storing them (`gongsynth.sun.photosphere.DeferredStokes.project`).

    Parameters
    ----------
    basis : `~gongsynth.stages.scene.shifts.ShiftBasis`
    e_weights : `numpy.ndarray`
        (n_e, 3), from `analyser_layout`.
    ld : float
        Continuum limb darkening at the viewing angle.

    Returns
    -------
    `numpy.ndarray`
        (n_out, 4, nλ) float64, n_out = (n_e + 1)(J + 1): ``row[o] = Σ_s Σ_j w[o, s, j] S_s(λ_j)``.

    Examples
    --------
    >>> import numpy as np
    >>> from gongsynth.stages.scene.shifts import shift_basis
    >>> from gongsynth.sun.photosphere import default_wavelength
    >>> basis = shift_basis(default_wavelength())
    >>> w = row_weights(basis, analyser_layout()[3], 1.0)
    >>> w.shape, float(w[0, 0] @ np.ones(51)), float(np.abs(w[1, 0] @ np.ones(51)))   # continuum: 1, line: 0
    ((22, 4, 51), 1.0, 0.0)
    """
    lam = basis.vectors.shape[1]
    edges = np.zeros(lam)
    edges[[0, -1]] = 0.5
    per_part = np.concatenate([edges[None], basis.vectors - basis.vectors.sum(axis=1)[:, None] * edges[None]])
    stokes = [np.append(np.asarray(w, dtype=float), 0.0) for w in e_weights] + [np.array([0.0, 0, 0, 1])]
    weights = np.concatenate([c[None, :, None] * per_part[:, None, :] for c in stokes])
    return weights / ld


def library_angles(theta):
    """
    Checked viewing angles of a library.

    Parameters
    ----------
    theta : sequence of float
        Deg, increasing from 0 to below 90.

    Returns
    -------
    `numpy.ndarray`
        float64 (n,).

    Examples
    --------
    >>> library_angles((0, 45, 80)).tolist()
    [0.0, 45.0, 80.0]
    """
    theta = np.asarray(theta, dtype=float)
    if theta.ndim != 1 or theta.size < 2 or theta[0] != 0 or np.any(np.diff(theta) <= 0) or theta[-1] >= 90:
        raise ValueError(f"theta must increase from 0 to below 90 deg, got {theta.tolist()}")
    return theta


#: What both library builders derive from their arguments before synthesising (`library_layout`).
LibraryLayout = namedtuple("LibraryLayout", ["instrument", "wavelength", "theta", "mu", "n_e", "e_index",
                                             "v_sign", "mirror_ok", "basis", "weights", "k_row"])


def library_layout(*, instrument, wavelength, pixel_size, theta, seeds_per_level, levels, mueller,
                   max_velocity, line):
    """
    The checked arguments and the row layout shared by the Milne-Eddington and 3-D library builders.

    Parameters
    ----------
    instrument : `~gongsynth.GONGInstrument` or None
    wavelength : `~astropy.units.Quantity` or None
        Spectral grid (None: the paper's 51 points about the instrument's line, as finely sampled as
        its filters need: `gongsynth.sun.photosphere.default_wavelength`).
    pixel_size : `~astropy.units.Quantity`
        Patch column size (checked to be a length).
    theta : sequence of float
        Viewing angles (`library_angles`).
    seeds_per_level, levels : sequence
        Patches per level and the levels (one count each, all ≥ 1).
    mueller : array_like or None
        The instrument Mueller matrix (`analyser_layout`).
    max_velocity : `~astropy.units.Quantity`
        Largest Doppler shift of the basis.
    line : `~gongsynth.sun.photosphere.NiLine`
        Its limb darkening divides the stored rows.

    Returns
    -------
    `LibraryLayout`
        The instrument, wavelengths, angles and their μ, the analyser layout,
        the Doppler basis, the row weights per angle and the row length.

    Examples
    --------
    >>> import astropy.units as u
    >>> from gongsynth.sun.photosphere import NiLine
    >>> lay = library_layout(instrument=None, wavelength=None, pixel_size=384 * u.km, theta=(0, 60),
    ...                      seeds_per_level=(1,), levels=(("quiet", {}),), mueller=None,
    ...                      max_velocity=4 * u.km / u.s, line=NiLine())
    >>> lay.n_e, len(lay.weights), lay.k_row == (lay.n_e + 1) * (lay.basis.rank + 1) + 2
    (1, 2, True)
    """
    inst = instruments.get(instrument)
    wavelength = default_wavelength(inst) if wavelength is None else wavelength
    check_quantity(pixel_size, u.km, "pixel_size")
    theta = library_angles(theta)
    if len(seeds_per_level) != len(levels) or min(seeds_per_level) < 1:
        raise ValueError(f"seeds_per_level needs one positive count per level ({len(levels)}), "
                         f"got {seeds_per_level!r}")
    n_e, e_index, v_sign, e_weights, mirror_ok = analyser_layout(mueller)
    basis = shift_basis(wavelength, inst, max_velocity=max_velocity)
    mu = np.cos(np.radians(theta))
    weights = [row_weights(basis, e_weights, factor) for factor in line.limb_darkening_factor(mu)]
    return LibraryLayout(inst, wavelength, theta, mu, n_e, e_index, v_sign, mirror_ok, basis, weights,
                         (n_e + 1) * (basis.rank + 1) + 2)
