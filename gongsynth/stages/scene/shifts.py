r"""
Doppler shifts in an instrument's passband without re-synthesis: a low-rank basis of the shifted weights.

A spectrum S(λ) moved by a line-of-sight velocity v (positive away from the
observer) is S(λ / (1 + v/c)).  Its channel integrals are

.. math::

    P_c(v) = \int \bar R_c(\lambda)\, S\!\Big(\frac{\lambda}{1+\beta}\Big)\, d\lambda
           = (1+\beta) \int \bar R_c\big(\lambda'(1+\beta)\big)\, S(\lambda')\, d\lambda'
           = \sum_j W_{cj}(v)\, S_j, \qquad \beta = v/c,

i.e. the sampled spectrum against the filter responses moved the other way,
with the quadrature of `gongsynth.instruments.quadrature.channel_weights` (which
``W(0)`` reproduces bit for bit).  Over a few km/s the family of rows
``W_c(v)`` spans few dimensions: the Michelson's cos ψ and sin ψ times the
slowly varying prefilter and Lyot envelope.  `shift_basis` finds them once (a
singular value decomposition of the rows over ``±max_velocity``): with the
continuum S_cont (the spectrum's edge value) taken out,

.. math:: P_c(v) = S_\mathrm{cont}\, T_c(v) + \sum_{k<J} A_{ck}(v)\, d_k,
          \qquad d_k = \sum_j E_{kj} (S_j - S_\mathrm{cont}),

so a column is stored as J + 1 numbers per polarisation state and any
velocity costs 3 (J + 1) multiply-adds per channel triple.  The error of the
truncation is measured against the exact weights and returned
(`ShiftBasis.error`); with the default tolerance it is below 1e-6 of the
channel integrals of a spectrum, ~0.02 m/s of Doppler velocity.
"""
from dataclasses import dataclass

import astropy.constants as const
import astropy.units as u
import numpy as np
from scipy.interpolate import CubicSpline

from gongsynth import instruments
from gongsynth.instruments.quadrature import filter_quadrature, hat_weights
from gongsynth.validation import check_quantity, check_wavelength_grid

__all__ = ["ShiftBasis", "shifted_channel_weights", "shift_basis", "reduced_basis"]

_C_KMS = const.c.to_value(u.km / u.s)
_NODE_KMS = 0.2   # spacing of the exact weights (km/s); a cubic spline between errs by ~1e-6


def _shifted_weights(lam, velocities_kms, inst):
    """(nv, 3, nλ) weights of spectra sampled at ``lam`` (nm) moved by each velocity (km/s)."""
    grid, dlam, unshifted = filter_quadrature(inst)
    k, t = hat_weights(lam, grid)
    n_filtergrams = unshifted.shape[0]
    factors = 1.0 + np.asarray(velocities_kms, dtype=float) / _C_KMS
    # One call for every shift: the responses at the moved quadrature points.
    resp = inst.responses((factors[:, None] * grid[None, :]).ravel() * u.nm).to_value(u.one)
    resp = resp.reshape(n_filtergrams, factors.size, grid.size)
    out = np.empty((factors.size, n_filtergrams, lam.size))
    for n, factor in enumerate(factors):
        for i in range(n_filtergrams):
            rw = resp[i, n] * dlam * factor
            out[n, i] = (np.bincount(k, rw * (1 - t), minlength=lam.size)
                         + np.bincount(k + 1, rw * t, minlength=lam.size))
    return out


def shifted_channel_weights(wavelength, velocity, instrument=None):
    """
    Exact channel weights of a spectrum Doppler shifted by ``velocity``.

    Parameters
    ----------
    wavelength : `~astropy.units.Quantity`
        The spectrum's sampling (strictly increasing, containing the line centre).
    velocity : `~astropy.units.Quantity`
        Line-of-sight velocity (positive: redshift), scalar.
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional

    Returns
    -------
    `~astropy.units.Quantity`
        (n_filtergrams, nλ) in nm (GONG: 3): ``W @ S`` are the filtergram integrals
        of the shifted spectrum.

    Examples
    --------
    >>> import astropy.units as u, numpy as np
    >>> from gongsynth.stages.filters import channel_weights
    >>> lam = np.linspace(676.73, 676.83, 51) * u.nm
    >>> bool(np.array_equal(shifted_channel_weights(lam, 0 * u.m / u.s), channel_weights(lam)))
    True
    """
    inst = instruments.get(instrument)
    lam = check_wavelength_grid(wavelength, inst.line_wavelength, "wavelength").to_value(u.nm)
    check_quantity(velocity, u.km / u.s, "velocity")
    v = float(velocity.to_value(u.km / u.s))
    return u.Quantity(_shifted_weights(lam, [v], inst)[0], u.nm)


@dataclass(frozen=True)
class ShiftBasis:
    """
    Low-rank expansion of the channel weights over a range of Doppler shifts.

    Attributes
    ----------
    wavelength : `numpy.ndarray`
        The spectral grid (nλ,), nm.
    vectors : `numpy.ndarray`
        E, (J, nλ): a spectrum's coordinates are ``E @ (S - S_cont)``.
    velocity : `numpy.ndarray`
        The tabulation grid of the amplitudes (nv,), m/s, uniform.
    amplitudes : `numpy.ndarray`
        A(v), (nv, 3, J), in nm.
    totals : `numpy.ndarray`
        T(v) = the channel integrals of a unit continuum, (nv, 3), in nm.
    error : float
        Largest error of the truncated expansion on the tabulated rows,
        relative to the largest channel integral of a unit continuum.
    """

    wavelength: np.ndarray
    vectors: np.ndarray
    velocity: np.ndarray
    amplitudes: np.ndarray
    totals: np.ndarray
    error: float

    @property
    def rank(self):
        """J, the number of basis vectors."""
        return self.vectors.shape[0]

    @property
    def max_velocity(self):
        """The largest |v| tabulated (`~astropy.units.Quantity`, m/s)."""
        return float(self.velocity[-1]) * u.m / u.s

    def coordinates(self, spectra):
        """
        Continuum and coordinates of spectra.

        Parameters
        ----------
        spectra : `numpy.ndarray`
            (n, nλ) values (any unit).

        Returns
        -------
        continuum : `numpy.ndarray`
            (n,) the edge value (mean of the first and last sample).
        coordinates : `numpy.ndarray`
            (n, J).
        """
        spectra = np.asarray(spectra)
        if spectra.dtype != np.float32:
            spectra = spectra.astype(np.float64)
        continuum = 0.5 * (spectra[:, 0].astype(np.float64) + spectra[:, -1])
        # float32 spectra stay float32 (the line's depth relative to the continuum keeps 7 digits).
        line = spectra - continuum[:, None].astype(spectra.dtype)
        return continuum, (line @ self.vectors.T.astype(spectra.dtype)).astype(np.float64)

    def channels(self, continuum, coordinates, velocity):
        """
        The channel integrals of shifted spectra from their continuum and coordinates.

        Parameters
        ----------
        continuum : `numpy.ndarray`
            (n,).
        coordinates : `numpy.ndarray`
            (n, J).
        velocity : `numpy.ndarray` or float
            (n,) or scalar, m/s, within ``±max_velocity``.

        Returns
        -------
        `numpy.ndarray`
            (n, 3), in the spectra's unit × nm.
        """
        v = np.broadcast_to(np.asarray(velocity, dtype=np.float64), np.shape(continuum))
        if np.any(np.abs(v) > self.velocity[-1]):
            raise ValueError(f"velocities beyond the basis' ±{self.velocity[-1]:.0f} m/s")
        step = self.velocity[1] - self.velocity[0]
        x = (v - self.velocity[0]) / step
        i = np.clip(np.floor(x).astype(int), 0, self.velocity.size - 2)
        w = (x - i)[:, None]
        amp = (1 - w)[..., None] * self.amplitudes[i] + w[..., None] * self.amplitudes[i + 1]
        tot = (1 - w) * self.totals[i] + w * self.totals[i + 1]
        return continuum[:, None] * tot + np.einsum("nck,nk->nc", amp, coordinates)


def shift_basis(wavelength, instrument=None, *, max_velocity=4 * u.km / u.s, tolerance=1e-4,
                step=10 * u.m / u.s):
    """
    The low-rank basis of the channel weights for shifts within ±``max_velocity``.

    Parameters
    ----------
    wavelength : `~astropy.units.Quantity`
        The spectral grid of the spectra to be shifted.
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
    max_velocity : `~astropy.units.Quantity`
        Largest |v| (default 4 km/s: the solar rotation, the observer's motion
        and the convective blueshift together stay below ~3 km/s).
    tolerance : float
        Keep basis vectors until a bound on the truncation error (the sum of
        the rows' residuals, for a line as deep as the continuum), relative to
        the channel integrals of a unit continuum, is below this (default
        1e-4: 10 vectors for the default grid, and an actual error below 1e-6
        on the built-in Sun's spectra).
    step : `~astropy.units.Quantity`
        Spacing of the tabulated amplitudes (default 10 m/s; interpolated
        linearly between, an error of ~1e-6 of the modulation).  The exact
        weights are computed every 200 m/s and the amplitudes splined between.

    Returns
    -------
    `ShiftBasis`

    Examples
    --------
    >>> import astropy.units as u, numpy as np
    >>> lam = np.linspace(676.73, 676.83, 51) * u.nm
    >>> basis = shift_basis(lam)
    >>> basis.rank, basis.error < 1e-4
    (10, True)
    """
    inst = instruments.get(instrument)
    lam = check_wavelength_grid(wavelength, inst.line_wavelength, "wavelength").to_value(u.nm)
    vmax = float(check_quantity(max_velocity, u.km / u.s, "max_velocity").to_value(u.km / u.s))
    dv = float(check_quantity(step, u.km / u.s, "step").to_value(u.km / u.s))
    if not (vmax > 0 and dv > 0) or not 0 < tolerance < 1:
        raise ValueError("max_velocity and step must be positive and tolerance in (0, 1)")
    n = int(np.ceil(vmax / _NODE_KMS))
    nodes = np.arange(-n, n + 1) * _NODE_KMS
    weights = _shifted_weights(lam, nodes, inst)               # (nodes, 3, nλ)
    totals = weights.sum(axis=2)
    rows = weights.reshape(-1, lam.size)
    # Right singular vectors of the rows: eigenvectors of their (nλ × nλ) Gram matrix.
    eigenvalues, eigenvectors = np.linalg.eigh(rows.T @ rows)
    vt = eigenvectors[:, np.argsort(eigenvalues)[::-1]].T
    scale = np.abs(totals).max()
    # Test spectra: unit impulses minus the continuum of their edges.
    for rank in range(1, lam.size + 1):
        vectors = vt[:rank]
        residual = rows - (rows @ vectors.T) @ vectors
        # Error on the line part: the spectrum's deviation from the continuum is at most the
        # continuum itself, so the sum of |residual| bounds the error per unit continuum.
        error = float(np.abs(residual).sum(axis=1).max() / scale)
        if error < tolerance:
            break
    m = int(np.ceil(nodes[-1] / dv))
    velocity = np.arange(-m, m + 1) * dv
    velocity = velocity[np.abs(velocity) <= nodes[-1] + 1e-12]
    amplitudes = CubicSpline(nodes, weights @ vectors.T, axis=0)(velocity)   # (nv, 3, J)
    totals = CubicSpline(nodes, totals, axis=0)(velocity)
    return ShiftBasis(wavelength=lam, vectors=vectors, velocity=velocity * 1e3,
                      amplitudes=amplitudes, totals=totals, error=error)


def reduced_basis(basis, spectra, tolerance):
    r"""
    A basis of lower rank that reproduces the channels of a given set of spectra within a tolerance.

    The rows of the (velocity, channel) × J matrix of amplitudes are
    reduced for the spectra actually present, not for every spectrum: with
    the covariance of the spectra's coordinates per unit continuum,
    C = L Lᵀ, the singular value decomposition A L = U S Vᵀ gives the
    coordinates y = Vᵀ L⁻¹ d, uncorrelated and ordered by their weight in
    the channels, and A d = U S y exactly.  Keeping the first r, the error
    of channel c at velocity v is bounded (Cauchy-Schwarz) by
    ‖(U S)_{vc, ≥r}‖ ‖y_{≥r}‖, taken at its largest over the tabulated
    velocities and the spectra, relative to the channel of the spectrum's
    continuum; the smallest r whose bound is within ``tolerance`` is kept.

    Parameters
    ----------
    basis : `ShiftBasis`
    spectra : `numpy.ndarray` or callable
        (n, J + 1): each spectrum's continuum (positive) then its J coordinates (`ShiftBasis.coordinates`);
        or a function returning an iterable of such arrays (read twice: a large set a chunk at a time).
    tolerance : float
        Largest error allowed in any channel, relative to that channel of the spectrum's continuum.

    Returns
    -------
    transform : `numpy.ndarray` or None
        (r, J): the new coordinates are ``transform @ d``; None when no r < J is within the tolerance.
    amplitudes : `numpy.ndarray`
        (nv, C, r), in nm (``basis.amplitudes`` when ``transform`` is None).
    bound : float
        The bound on the relative error of the channels (0 when ``transform`` is None).

    Examples
    --------
    >>> import astropy.units as u, numpy as np
    >>> lam = np.linspace(676.73, 676.83, 51) * u.nm
    >>> basis = shift_basis(lam)
    >>> line = 1 - 0.5 * np.exp(-((lam.value - 676.78) / 0.008) ** 2)
    >>> cont, coords = basis.coordinates(np.stack([line, 1 - 0.3 * (1 - line)]))
    >>> transform, amplitudes, bound = reduced_basis(basis, np.column_stack([cont, coords]), 1e-6)
    >>> transform.shape[0] < basis.rank, bound <= 1e-6
    (True, True)
    """
    if not 0 < tolerance < 1:
        raise ValueError(f"tolerance must be in (0, 1), got {tolerance!r}")
    rank = basis.rank
    chunks = spectra if callable(spectra) else (lambda: [spectra])

    def coordinates():      # per unit continuum, a chunk at a time (a large library stays on disk)
        for chunk in chunks():
            chunk = np.asarray(chunk, dtype=np.float64)
            if chunk.ndim != 2 or chunk.shape[1] != rank + 1 or not np.all(chunk[:, 0] > 0):
                raise ValueError(f"spectra must be (n, {rank + 1}) rows with a positive continuum first")
            yield chunk[:, 1:] / chunk[:, :1]

    gram, count = np.zeros((rank, rank)), 0
    for d in coordinates():
        gram += d.T @ d
        count += d.shape[0]
    eigenvalues, q = np.linalg.eigh(gram / max(count, 1))
    root = np.sqrt(np.maximum(eigenvalues, 1e-30 * max(eigenvalues.max(), 1e-300)))
    matrix = basis.amplitudes.reshape(-1, rank)
    left, singular, vt = np.linalg.svd(matrix @ (q * root), full_matrices=False)
    to_y = vt @ (q / root).T                                   # y = to_y @ d
    us = left * singular
    # Tail norms: tail[r] = ‖x_{≥r}‖, for the spectra's y and the channels' rows of U S.
    row_tail = np.zeros(rank)
    for d in coordinates():
        y2 = (d @ to_y.T) ** 2
        row_tail = np.maximum(row_tail, np.sqrt(np.cumsum(y2[:, ::-1], axis=1)[:, ::-1]).max(axis=0))
    channel_tail = (np.sqrt(np.cumsum((us ** 2)[:, ::-1], axis=1)[:, ::-1])
                    / np.abs(basis.totals.reshape(-1))[:, None]).max(axis=0)
    for r in range(1, rank):
        bound = float(row_tail[r] * channel_tail[r])
        if bound <= tolerance:
            return to_y[:r], us[:, :r].reshape(basis.amplitudes.shape[:2] + (r,)), bound
    return None, basis.amplitudes, 0.0
