r"""
Polarimetry and the filter: Stokes spectra → six channel images (filter first).

GONG measures I+V and I−V (the LCVR's two states) through three wave-plate
sectors.  The optics after the Sun (Mueller matrices, PSF, resampling,
binning) are linear and, over the line window, achromatic, so integrating the
spectra against the channel responses commutes with them (design §1).  This
module therefore collapses every spectrum to six numbers *before* any spatial
work:

.. math::

    P_{p,c}(x, y) = \sum_j W_{c j}\,\big[(M S)_0 + s_p\,(M S)_3\big](x, y, \lambda_j),
    \qquad s_0 = +1,\ s_1 = -1,

with W = `gongsynth.filters.channel_weights` and M the instrument Mueller
matrix (identity by default: no cross-talk).  Plane order is
`gongsynth.planes` (index = pol × 3 + channel).

As in the paper the two states are I±V without the factor 1/2 of a real
analyser; the effective area (0.6 cm², tuned to real GONG counts) absorbs it.
"""
import astropy.units as u
import numpy as np

from gongsynth.instrument import resolve_instrument
from gongsynth.planes import N_CHANNELS, N_PLANES, N_POLARISATIONS
from gongsynth.stages.filters import channel_weights
from gongsynth.sun.photosphere import DeferredStokes
from gongsynth.validation import check_finite

__all__ = ["CHANNEL_UNIT", "IDEAL_MUELLER", "analyser_coefficients", "polarized_spectra",
           "channel_images"]

#: Unit of channel images at the Sun: radiance integrated over wavelength.
CHANNEL_UNIT = u.Unit("erg / (s cm2 sr)")

#: The default Mueller matrix: a perfect instrument (identity, no cross-talk).
IDEAL_MUELLER = np.eye(4)

# Sign of V in the two LCVR states (plane order of gongsynth.planes).
_V_SIGN = np.array([1.0, -1.0])

# Spectra converted to float64 this many at a time (bounded temporaries).
_BLOCK_SPECTRA = 65536


def analyser_coefficients(mueller=None):
    """
    Weights of (I, Q, U, V) in the intensity measured in each LCVR state.

    Row p of the result is (M[0] + s_p M[3]) with s = (+1, −1): the Stokes I
    and V after the instrument Mueller matrix M, combined as I+V and I−V.

    Parameters
    ----------
    mueller : array_like, optional
        Dimensionless Mueller matrix of shape (4, 4), or one per wavelength
        (nλ, 4, 4), or one per pixel (ny, nx, 4, 4).  Default: identity.

    Returns
    -------
    `numpy.ndarray`
        Shape ``(..., 2, 4)`` where ``...`` is the leading shape of ``mueller``.

    Examples
    --------
    >>> analyser_coefficients()
    array([[ 1.,  0.,  0.,  1.],
           [ 1.,  0.,  0., -1.]])
    """
    m = _check_mueller(IDEAL_MUELLER if mueller is None else mueller)
    rows = m[..., 0, :][..., None, :] + _V_SIGN[:, None] * m[..., 3, :][..., None, :]
    return rows


def _check_mueller(mueller):
    if isinstance(mueller, u.Quantity):
        if mueller.unit.physical_type != "dimensionless":
            raise u.UnitsError(f"mueller must be dimensionless, got unit {mueller.unit}")
        mueller = mueller.to_value(u.one)
    m = np.asarray(mueller, dtype=float)
    if m.ndim not in (2, 3, 4) or m.shape[-2:] != (4, 4):
        raise ValueError(
            f"mueller must have shape (4, 4), (nwavelength, 4, 4) or (ny, nx, 4, 4), got {m.shape}"
        )
    check_finite(m, "mueller")
    return m


def _coefficients_for(stokes, mueller):
    """Analyser coefficients and their kind: 'global', 'spectral' or 'spatial'."""
    ny, nx, nl = stokes.shape
    if mueller is None:
        return analyser_coefficients(), "global"
    m = _check_mueller(mueller)
    if m.ndim == 2:
        kind = "global"
    elif m.ndim == 3:
        if m.shape[0] != nl:
            raise ValueError(f"a per-wavelength mueller must have shape ({nl}, 4, 4), got {m.shape}")
        kind = "spectral"
    else:
        if m.shape[:2] != (ny, nx):
            raise ValueError(f"a per-pixel mueller must have shape ({ny}, {nx}, 4, 4), got {m.shape}")
        kind = "spatial"
    return analyser_coefficients(m), kind


def _stokes_arrays(stokes):
    """The four Stokes arrays (ny, nx, nλ) as plain arrays in erg/(s cm2 sr cm)."""
    from gongsynth.sun.stokes import RADIANCE_UNIT
    return [getattr(stokes, name).to_value(RADIANCE_UNIT) for name in ("I", "Q", "U", "V")]


def polarized_spectra(stokes, *, mueller=None):
    """
    The I±V spectra after the Mueller matrix, wavelength by wavelength (the paper's order).

    Needed only to run the paper's literal order (Mueller → PSF → pixelize →
    filter) for comparison; `channel_images` is the fast path.

    Parameters
    ----------
    stokes : `~gongsynth.sun.stokes.StokesCube`
    mueller : array_like, optional
        As in `analyser_coefficients`.

    Returns
    -------
    `~astropy.units.Quantity`
        Shape (2, ny, nx, nλ), float64, in erg s⁻¹ cm⁻² sr⁻¹ cm⁻¹: I+V then I−V.

    Examples
    --------
    >>> import numpy as np, astropy.units as u
    >>> from gongsynth.sun.stokes import StokesCube
    >>> lam = np.linspace(676.73, 676.83, 5) * u.nm
    >>> one = np.ones((1, 1, 5)) * u.Unit("erg / (s cm2 sr cm)")
    >>> cube = StokesCube(one, 0 * one, 0 * one, 0.1 * one, lam, 96 * u.km)
    >>> polarized_spectra(cube)[:, 0, 0, 0].value
    array([1.1, 0.9])
    """
    from gongsynth.sun.stokes import RADIANCE_UNIT
    coeff, kind = _coefficients_for(stokes, mueller)
    arrays = _stokes_arrays(stokes)
    out = np.zeros((N_POLARISATIONS,) + stokes.shape)
    for p in range(N_POLARISATIONS):
        for s, a in enumerate(arrays):
            if kind == "global":
                c = coeff[p, s]
            elif kind == "spectral":
                c = coeff[:, p, s]
            else:
                c = coeff[:, :, p, s][..., None]
            if np.any(c != 0):
                out[p] += c * a
    return u.Quantity(out, RADIANCE_UNIT, copy=False)


def channel_images(stokes, *, mueller=None, instrument=None):
    """
    Integrate every spectrum against the six channel responses (filter first).

    Parameters
    ----------
    stokes : `~gongsynth.sun.stokes.StokesCube` or `~gongsynth.sun.photosphere.DeferredStokes`
        Spectral radiance at the Sun (ny, nx, nλ).  A deferred cube is
        synthesised and collapsed `_BLOCK_SPECTRA` columns at a time, with the
        same result as its whole cube.
    mueller : array_like, optional
        Dimensionless instrument Mueller matrix applied before the I±V
        analysis: (4, 4), per wavelength (nλ, 4, 4) or per pixel (ny, nx, 4, 4).
        Default: identity (the paper's no-cross-talk I+V and I−V).
    instrument : `~gongsynth.GONGInstrument`, optional
        Filter chain (`gongsynth.filters.channel_weights`).

    Returns
    -------
    `~astropy.units.Quantity`
        Shape (6, ny, nx), float64, in erg s⁻¹ cm⁻² sr⁻¹ (radiance at the Sun
        integrated over wavelength), planes in `gongsynth.planes` order.

    Examples
    --------
    >>> import numpy as np, astropy.units as u
    >>> from gongsynth.sun.stokes import StokesCube
    >>> lam = np.linspace(676.73, 676.83, 51) * u.nm
    >>> I = np.full((2, 3, 51), 3e14) * u.Unit("erg / (s cm2 sr cm)")
    >>> cube = StokesCube(I, 0 * I, 0 * I, 0 * I, lam, 96 * u.km)
    >>> planes = channel_images(cube)
    >>> planes.shape, planes.unit
    ((6, 2, 3), Unit("erg / (s sr cm2)"))
    """
    inst = resolve_instrument(instrument)
    if isinstance(stokes, DeferredStokes):
        # Synthesised and collapsed a block of rows at a time: the cube is never held whole.
        return _deferred_channel_images(stokes, mueller, inst)
    coeff, kind = _coefficients_for(stokes, mueller)
    weights = channel_weights(stokes.wavelength, inst).to_value(u.cm)  # (3, nλ)
    ny, nx, nl = stokes.shape
    arrays = [a.reshape(ny * nx, nl) for a in _stokes_arrays(stokes)]
    if kind == "spectral":
        # W'[p, c, s, λ] = W[c, λ] coeff[λ, p, s]: one (24, nλ) matrix, then one product.
        wmat = np.einsum("cl,lps->pcsl", weights, coeff)
        used = [s for s in range(4) if np.any(wmat[:, :, s] != 0)]
    else:
        used = [s for s in range(4) if kind == "spatial" or np.any(coeff[..., s] != 0)]
    out = np.zeros((N_PLANES, ny * nx))
    for start in range(0, ny * nx, _BLOCK_SPECTRA):
        rows = slice(start, start + _BLOCK_SPECTRA)
        for s in used:
            block = arrays[s][rows].astype(np.float64)
            if kind == "spectral":
                out[:, rows] += (wmat[:, :, s].reshape(N_PLANES, nl) @ block.T)
                continue
            integ = weights @ block.T  # (3, n): the channel integrals of Stokes s
            for p in range(N_POLARISATIONS):
                c = coeff[p, s] if kind == "global" else coeff[:, :, p, s].reshape(-1)[rows]
                out[p * N_CHANNELS:(p + 1) * N_CHANNELS, rows] += c * integ
    return u.Quantity(out.reshape(N_PLANES, ny, nx), CHANNEL_UNIT, copy=False)


def _deferred_channel_images(stokes, mueller, inst):
    """
    `channel_images` of a `DeferredStokes`: the spectra contracted with the
    channel weights column by column, never stored (`DeferredStokes.project`),
    or block by block of whole rows for a per-pixel Mueller matrix.
    """
    ny, nx, nl = stokes.shape
    m = None if mueller is None else _check_mueller(mueller)
    if m is not None and m.ndim == 3 and m.shape[0] != nl:
        raise ValueError(f"a per-wavelength mueller must have shape ({nl}, 4, 4), got {m.shape}")
    if m is not None and m.ndim == 4 and m.shape[:2] != (ny, nx):
        raise ValueError(f"a per-pixel mueller must have shape ({ny}, {nx}, 4, 4), got {m.shape}")
    if m is None or m.ndim < 4:
        weights = channel_weights(stokes.wavelength, inst).to_value(u.cm)  # (3, nλ)
        coeff = analyser_coefficients(m)  # (2, 4) or (nλ, 2, 4)
        if coeff.ndim == 2:
            coeff = np.broadcast_to(coeff, (nl,) + coeff.shape)
        # W'[p, c, s, λ] = coeff[λ, p, s] W[c, λ]: plane p × 3 + c of Stokes s at λ.
        contraction = np.einsum("lps,cl->pcsl", coeff, weights).reshape(N_PLANES, 4, nl)
        return u.Quantity(stokes.project(contraction, _BLOCK_SPECTRA), CHANNEL_UNIT, copy=False)
    out = np.empty((N_PLANES, ny, nx))
    for rows, cube in stokes.blocks(_BLOCK_SPECTRA):
        out[:, rows] = channel_images(cube, mueller=m[rows], instrument=inst).value
    return u.Quantity(out, CHANNEL_UNIT, copy=False)
