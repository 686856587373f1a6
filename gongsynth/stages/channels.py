r"""
Polarimetry and the filter: Stokes spectra → the instrument's K planes (filter first).

An instrument measures I+V and I−V (GONG: the LCVR's two states; HMI: LCP and
RCP) through its filtergrams (GONG: three wave-plate sectors; HMI: six tuning
positions).  The optics after the Sun (Mueller matrices, PSF, resampling,
binning) are linear and, over the line window, achromatic, so integrating the
spectra against the filtergram responses commutes with them (design §1).  This
module therefore collapses every spectrum to K numbers *before* any spatial
work:

.. math::

    P_k(x, y) = \sum_j W_{f_k j}\,\big[(M S)_0 + s_k\,(M S)_3\big](x, y, \lambda_j),

with :math:`(f_k, s_k)` the instrument's ``analysers`` (filtergram, sign of
V) of plane k, W = `gongsynth.instruments.quadrature.channel_weights` and M the
instrument Mueller matrix (identity by default: no cross-talk).  GONG's plane
order is `gongsynth.planes` (index = pol × 3 + channel, s = +1 then −1).

As in the paper the two states are I±V without the factor 1/2 of a real
analyser; the effective area (0.6 cm², tuned to real GONG counts) absorbs it.
"""
import astropy.units as u
import numpy as np

from gongsynth import instruments
from gongsynth.instruments.quadrature import channel_weights
from gongsynth.sun.model_atmosphere.transfer import DeferredTransfer
from gongsynth.sun.photosphere import DeferredStokes
from gongsynth.validation import check_finite

__all__ = ["CHANNEL_UNIT", "IDEAL_MUELLER", "analyser_coefficients", "polarized_spectra",
           "channel_images"]

#: Unit of channel images at the Sun: radiance integrated over wavelength.
CHANNEL_UNIT = u.Unit("erg / (s cm2 sr)")

#: The default Mueller matrix: a perfect instrument (identity, no cross-talk).
IDEAL_MUELLER = np.eye(4)

# Sign of V in the two analyser states, I+V then I-V.
_V_SIGN = (1, -1)

# Spectra converted to float64 this many at a time (bounded temporaries).
_BLOCK_SPECTRA = 65536


def analyser_coefficients(mueller=None, signs=_V_SIGN):
    """
    Weights of (I, Q, U, V) in the intensity measured through each analyser.

    Row p of the result is (M[0] + s_p M[3]): the Stokes I and V after the
    instrument Mueller matrix M, combined as I + s_p V.

    Parameters
    ----------
    mueller : array_like, optional
        Dimensionless Mueller matrix of shape (4, 4), or one per wavelength
        (nλ, 4, 4), or one per pixel (ny, nx, 4, 4).  Default: identity.
    signs : sequence of int
        The sign of V of each analyser: default (+1, −1), I+V and I−V; an
        instrument's per-plane signs give one row per plane.

    Returns
    -------
    `numpy.ndarray`
        Shape ``(..., len(signs), 4)`` where ``...`` is the leading shape of ``mueller``.

    Examples
    --------
    >>> analyser_coefficients()
    array([[ 1.,  0.,  0.,  1.],
           [ 1.,  0.,  0., -1.]])
    """
    m = _check_mueller(IDEAL_MUELLER if mueller is None else mueller)
    sign = np.asarray(signs, dtype=float)
    rows = m[..., 0, :][..., None, :] + sign[:, None] * m[..., 3, :][..., None, :]
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


def _coefficients_for(stokes, mueller, signs=_V_SIGN):
    """Analyser coefficients (one row per sign) and their kind: 'global', 'spectral' or 'spatial'."""
    ny, nx, nl = stokes.shape
    if mueller is None:
        return analyser_coefficients(signs=signs), "global"
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
    return analyser_coefficients(m, signs), kind


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
    out = np.zeros((len(_V_SIGN),) + stokes.shape)
    for p in range(len(_V_SIGN)):
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
    Integrate every spectrum against the instrument's K plane responses (filter first).

    Parameters
    ----------
    stokes : `~gongsynth.sun.stokes.StokesCube` or a deferred cube
        Spectral radiance at the Sun (ny, nx, nλ).  A deferred cube
        (`~gongsynth.sun.photosphere.DeferredStokes`,
        `~gongsynth.sun.model_atmosphere.transfer.DeferredTransfer`) is
        synthesised and collapsed `_BLOCK_SPECTRA` columns at a time, with the
        same result as its whole cube (a `DeferredTransfer`'s blocks go
        through the cube's own path: the same bits where the row length
        divides `_BLOCK_SPECTRA`).
    mueller : array_like, optional
        Dimensionless instrument Mueller matrix applied before the I±V
        analysis: (4, 4), per wavelength (nλ, 4, 4) or per pixel (ny, nx, 4, 4).
        Default: identity (the paper's no-cross-talk I+V and I−V).
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
        Its filtergrams (`gongsynth.instruments.quadrature.channel_weights`)
        and ``analysers`` (filtergram and sign of V of each plane).  Default GONG.

    Returns
    -------
    `~astropy.units.Quantity`
        Shape (K, ny, nx), float64, in erg s⁻¹ cm⁻² sr⁻¹ (radiance at the Sun
        integrated over wavelength), planes in the instrument's order (GONG:
        `gongsynth.planes`).

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
    inst = instruments.get(instrument)
    if isinstance(stokes, DeferredTransfer):
        # Radiative transfer a block of rows at a time, each block collapsed as its cube.
        m = None if mueller is None else _check_mueller(mueller)
        per_pixel = m is not None and m.ndim == 4
        out = None
        for rows, cube in stokes.blocks(_BLOCK_SPECTRA):
            part = channel_images(cube, mueller=m[rows] if per_pixel else m, instrument=inst).value
            if out is None:
                out = np.empty((part.shape[0],) + stokes.shape[:2])
            out[:, rows] = part
        return u.Quantity(out, CHANNEL_UNIT, copy=False)
    if isinstance(stokes, DeferredStokes):
        # Synthesised and collapsed a block of rows at a time: the cube is never held whole.
        return _deferred_channel_images(stokes, mueller, inst)
    filtergram, signs = _analysers(inst)
    coeff, kind = _coefficients_for(stokes, mueller, signs)  # (..., K, 4)
    weights = channel_weights(stokes.wavelength, inst).to_value(u.cm)  # (n_filtergrams, nλ)
    ny, nx, nl = stokes.shape
    n_planes = filtergram.size
    arrays = [a.reshape(ny * nx, nl) for a in _stokes_arrays(stokes)]
    if kind == "spectral":
        # W'[k, s, λ] = W[f_k, λ] coeff[λ, k, s]: one (4K, nλ) matrix, then one product.
        wmat = np.einsum("kl,lks->ksl", weights[filtergram], coeff)
        used = [s for s in range(4) if np.any(wmat[:, s] != 0)]
    else:
        used = [s for s in range(4) if kind == "spatial" or np.any(coeff[..., s] != 0)]
    out = np.zeros((n_planes, ny * nx))
    for start in range(0, ny * nx, _BLOCK_SPECTRA):
        rows = slice(start, start + _BLOCK_SPECTRA)
        for s in used:
            block = arrays[s][rows].astype(np.float64)
            if kind == "spectral":
                out[:, rows] += (wmat[:, s] @ block.T)
                continue
            integ = (weights @ block.T)[filtergram]  # (K, n): the filtergram integrals of Stokes s
            c = coeff[:, s, None] if kind == "global" else coeff[..., s].reshape(-1, n_planes)[rows].T
            out[:, rows] += c * integ
    return u.Quantity(out.reshape(n_planes, ny, nx), CHANNEL_UNIT, copy=False)


def _analysers(inst):
    """(filtergram index (K,), sign of V (K,)) of the instrument's planes."""
    filtergram, signs = (np.array(column, dtype=np.int64) for column in zip(*inst.analysers))
    return filtergram, signs


def _deferred_channel_images(stokes, mueller, inst):
    """
    `channel_images` of a `DeferredStokes`: the spectra contracted with the
    channel weights column by column, never stored (`DeferredStokes.project`),
    or block by block of whole rows for a per-pixel Mueller matrix.
    """
    ny, nx, nl = stokes.shape
    filtergram, signs = _analysers(inst)
    m = None if mueller is None else _check_mueller(mueller)
    if m is not None and m.ndim == 3 and m.shape[0] != nl:
        raise ValueError(f"a per-wavelength mueller must have shape ({nl}, 4, 4), got {m.shape}")
    if m is not None and m.ndim == 4 and m.shape[:2] != (ny, nx):
        raise ValueError(f"a per-pixel mueller must have shape ({ny}, {nx}, 4, 4), got {m.shape}")
    if m is None or m.ndim < 4:
        weights = channel_weights(stokes.wavelength, inst).to_value(u.cm)  # (n_filtergrams, nλ)
        coeff = analyser_coefficients(m, signs)  # (K, 4) or (nλ, K, 4)
        if coeff.ndim == 2:
            coeff = np.broadcast_to(coeff, (nl,) + coeff.shape)
        # W'[k, s, λ] = coeff[λ, k, s] W[f_k, λ]: plane k of Stokes s at λ.
        contraction = np.einsum("lks,kl->ksl", coeff, weights[filtergram])
        return u.Quantity(stokes.project(contraction, _BLOCK_SPECTRA), CHANNEL_UNIT, copy=False)
    out = np.empty((filtergram.size, ny, nx))
    for rows, cube in stokes.blocks(_BLOCK_SPECTRA):
        out[:, rows] = channel_images(cube, mueller=m[rows], instrument=inst).value
    return u.Quantity(out, CHANNEL_UNIT, copy=False)
