r"""
HMI's MDI-like observables algorithm: six filtergrams per polarisation → v, B_LOS.

For the six intensities :math:`I_k` of one polarisation at the tuning
positions :math:`\delta_k = (2.5 - k)\Delta` (Δ = 68.8 mÅ) the first and second
Fourier coefficients over the period T = 6Δ = 412.8 mÅ are (Couvidat et al.
2016, Sec. 4; Couvidat et al. 2012b)

.. math::

    a_n = \sum_k I_k \cos(n\theta_k),\quad b_n = \sum_k I_k \sin(n\theta_k),
    \qquad \theta_k = 2\pi\delta_k / T,

and, an absorption line being a dip, the raw velocities are

.. math::

    v_1 = \frac{c}{\lambda_0}\frac{T}{2\pi}\,\mathrm{atan2}(-b_1, -a_1),\qquad
    v_2 = \frac{c}{\lambda_0}\frac{T}{4\pi}\,\mathrm{atan2}(-b_2, -a_2)

(v_2 unwrapped to the branch nearest v_1).  The filters are not δ functions
and the line is not sampled over a full period, so v_1 is not the true
velocity: a look-up table built by passing a Gaussian reference line
(depth 0.661, FWHM 92.8 mÅ, the pipeline's disk-centre fit) Doppler-shifted
over ±9.6 km/s through the same filter model (`gongsynth.instruments.hmi.filters`)
maps v_1 back to the input velocity.  This is done for LCP (I+V) and RCP (I−V):

.. math::

    v = \tfrac12 (v_\mathrm{LCP} + v_\mathrm{RCP}),\qquad
    B_\mathrm{LOS} = (v_\mathrm{LCP} - v_\mathrm{RCP})\,K_m,
    \quad K_m = \frac{4\pi m_e c}{2 e g \lambda_0} = 0.2315\ \mathrm{G\,s\,m^{-1}}\ (g = 2.5).

Outside the monotonic part of the table the velocity is clipped to the
table's end (± 9.6 km/s) and the pixel flagged: the known saturation of strong
fields combined with large Doppler shifts.  As in the pipeline (Couvidat et
al. 2016), only v_1 enters v and B; v_2 and the Gaussian line width, depth and
continuum (from |F_1|/|F_2|) are diagnostics.  Simplifications: one table for
the whole disk (the pipeline interpolates tables on a 128² grid of filter
phases), no polynomial recalibration against the orbital velocity.
"""
from __future__ import annotations

import dataclasses
import functools
import math

import astropy.units as u
import numpy as np

from gongsynth.instruments.hmi.filters import filter_quadrature
from gongsynth.instruments.hmi.parameters import N_HMI_PLANES, N_TUNINGS, TUNING_INDICES, resolve_hmi
from gongsynth.instruments.tunable import reference_line_filtergrams
from gongsynth.stages.reduction import Observables
from gongsynth.validation import check_finite

__all__ = ["LookupTable", "lookup_table", "reference_filtergrams", "fourier_coefficients", "raw_velocities",
           "line_parameters", "reduce_hmi"]

_mA = u.Unit("mAA")
_BLOCK = 1 << 18  # pixels reduced at a time
_THETA = 2 * math.pi * np.asarray(TUNING_INDICES) / N_TUNINGS  # θ_k = 2π δ_k / T
_HARMONICS = np.stack([np.cos(_THETA), np.sin(_THETA), np.cos(2 * _THETA), np.sin(2 * _THETA)])


def fourier_coefficients(intensities, harmonic=1):
    """
    a_n and b_n of six filtergram intensities.

    Parameters
    ----------
    intensities : array_like
        Shape (6, ...), filtergrams I0..I5.
    harmonic : int
        n = 1 or 2.

    Returns
    -------
    a, b : `numpy.ndarray`
        Shape ``intensities.shape[1:]``.

    Examples
    --------
    >>> a, b = fourier_coefficients(np.ones(6))      # a flat continuum cancels
    >>> bool(abs(a) < 1e-12 and abs(b) < 1e-12)
    True
    """
    if harmonic not in (1, 2):
        raise ValueError(f"harmonic must be 1 or 2, got {harmonic!r}")
    a, b = _harmonics(intensities)[2 * harmonic - 2:2 * harmonic]
    return a, b


def _harmonics(intensities):
    """(a1, b1, a2, b2) stacked, shape (4, ...), by one matrix product."""
    data = np.asarray(intensities, dtype=float)
    return np.tensordot(_HARMONICS, data, axes=1)


def raw_velocities(intensities, instrument=None):
    """
    Uncorrected velocities and phase of the first and second Fourier coefficients.

    Parameters
    ----------
    intensities : array_like
        Shape (6, ...), one polarisation's filtergrams I0..I5 (any units).
    instrument : `~gongsynth.instruments.hmi.HMIInstrument`, optional

    Returns
    -------
    v1, v2, phase1 : `numpy.ndarray`
        v1 and v2 in m/s (positive = redshift), phase1 = atan2(−b1, −a1) in rad.
    """
    return _velocities(_harmonics(intensities), resolve_hmi(instrument))


def _velocities(harmonics, inst, second=True):
    """`raw_velocities` from the stacked Fourier coefficients (v2 None unless ``second``)."""
    per_rad = _velocity_per_radian(inst)
    a1, b1, a2, b2 = harmonics
    phase1 = np.arctan2(-b1, -a1)
    v1 = phase1 * per_rad
    if not second:
        return v1, None, phase1
    v2 = np.arctan2(-b2, -a2) * per_rad / 2
    period2 = math.pi * per_rad  # the second harmonic's velocity period
    v2 = v1 + np.mod(v2 - v1 + period2 / 2, period2) - period2 / 2
    return v1, v2, phase1


def _velocity_per_radian(inst):
    """(c / λ0) T / (2π) in m/s per radian."""
    return float((inst.velocity_per_wavelength * inst.tuning_period).to_value(u.m / u.s)) / (2 * math.pi)


@dataclasses.dataclass(frozen=True)
class LookupTable:
    """
    Raw → true velocity for the first and second Fourier coefficients.

    Attributes
    ----------
    velocity : `numpy.ndarray`
        Input (true) velocities of the reference line, m/s.
    raw1, raw2 : `numpy.ndarray`
        Raw v1 and v2 measured on the reference line shifted by ``velocity``.
    valid1, valid2 : slice
        The monotonic branch of each table around v = 0.
    """

    velocity: np.ndarray
    raw1: np.ndarray
    raw2: np.ndarray
    valid1: slice
    valid2: slice

    def correct(self, raw, harmonic=1):
        """
        True velocity for raw velocities, clipped to the table's end outside its valid range.

        Parameters
        ----------
        raw : array_like
            Raw velocities in m/s.
        harmonic : int
            1 or 2.

        Returns
        -------
        velocity : `numpy.ndarray`
            In m/s.
        outside : `numpy.ndarray` of bool
            True where ``raw`` lies outside the valid (monotonic) range.
        """
        table, valid = (self.raw1, self.valid1) if harmonic == 1 else (self.raw2, self.valid2)
        xs, vs = table[valid], self.velocity[valid]
        raw = np.asarray(raw, dtype=float)
        outside = (raw < xs[0]) | (raw > xs[-1])
        out = np.interp(raw, xs, vs)
        # Beyond the table HMI returns its extreme input velocity (the ±4444 G cap).
        out = np.where(raw < xs[0], self.velocity[0], np.where(raw > xs[-1], self.velocity[-1], out))
        return out, outside


def _monotonic_branch(raw, centre):
    """The largest slice around index ``centre`` on which ``raw`` strictly increases."""
    rising = np.diff(raw) > 0
    lo = centre
    while lo > 0 and rising[lo - 1]:
        lo -= 1
    hi = centre
    while hi < len(raw) - 1 and rising[hi]:
        hi += 1
    return slice(lo, hi + 1)


@functools.lru_cache(maxsize=8)
def lookup_table(instrument=None):
    """
    The look-up table of an instrument (cached): its reference line through its filters.

    Parameters
    ----------
    instrument : `~gongsynth.instruments.hmi.HMIInstrument`, optional

    Returns
    -------
    `LookupTable`
    """
    inst = resolve_hmi(instrument)
    vmax = inst.lut_velocity_max.to_value(u.m / u.s)
    step = inst.lut_velocity_step.to_value(u.m / u.s)
    n = int(round(vmax / step))
    velocity = step * np.arange(-n, n + 1)
    shift = velocity / inst.velocity_per_wavelength.to_value(u.m / u.s / _mA)
    filtergrams = reference_filtergrams(shift, inst)  # (6, nv)
    raw1, raw2, _ = raw_velocities(filtergrams, inst)
    return LookupTable(velocity, raw1, raw2, _monotonic_branch(raw1, n), _monotonic_branch(raw2, n))


def reference_filtergrams(shift, instrument=None):
    """
    Filtergrams of the reference line Doppler-shifted by ``shift``, relative to the continuum.

    Parameters
    ----------
    shift : array_like
        Shifts λ_line − λ0 in mÅ, shape (n,).
    instrument : `~gongsynth.instruments.hmi.HMIInstrument`, optional

    Returns
    -------
    `numpy.ndarray`
        Shape (6, n), in mÅ (∫ R_k I dλ for a unit continuum).
    """
    inst = resolve_hmi(instrument)
    depth, fwhm = inst.reference_line_depth.to_value(u.one), inst.reference_line_fwhm.to_value(_mA)
    return reference_line_filtergrams(shift, filter_quadrature(inst), depth, fwhm)


def _split(planes):
    """(12, ...) float array and unit of planes given as an array or Quantity."""
    unit = planes.unit if isinstance(planes, u.Quantity) else u.one
    data = np.asarray(getattr(planes, "value", planes), dtype=float)
    if data.ndim < 1 or data.shape[0] != N_HMI_PLANES:
        raise ValueError(f"planes must have a leading axis of {N_HMI_PLANES} filtergrams "
                         f"(LCP I0..I5, RCP I0..I5), got shape {data.shape}")
    return check_finite(data, "planes"), unit


def line_parameters(intensities, instrument=None):
    r"""
    HMI's Gaussian line width, depth and continuum from one polarisation's filtergrams.

    With :math:`|F_n| = \frac{2}{6}\sqrt{a_n^2 + b_n^2}`, a Gaussian line of
    width σ sampled by δ functions gives :math:`\sigma = \frac{T}{\pi}\sqrt{\ln(|F_1|/|F_2|)/3}`,
    depth :math:`I_d = \frac{T |F_1|}{2\sigma\sqrt\pi} e^{\pi^2\sigma^2/T^2}` and continuum
    :math:`I_c = \frac16\sum_k [I_k + I_d e^{-(\delta_k - \lambda_c)^2/\sigma^2}]`
    (Couvidat et al. 2016, Sec. 4; no look-up-table correction, as in HMI).

    Parameters
    ----------
    intensities : array_like
        Shape (6, ...).
    instrument : `~gongsynth.instruments.hmi.HMIInstrument`, optional

    Returns
    -------
    fwhm : `~astropy.units.Quantity`
        Line FWHM 2√ln2 σ in mÅ (NaN where |F_2| ≥ |F_1|).
    depth, continuum : `numpy.ndarray`
        In the unit of ``intensities``; the continuum falls back to the mean
        of the six filtergrams where the width is undefined.
    """
    inst = resolve_hmi(instrument)
    data = np.asarray(intensities, dtype=float)
    harmonics = _harmonics(data)
    sigma, depth, continuum = _line_parameters(data, harmonics, _velocities(harmonics, inst, False)[0], inst)
    return u.Quantity(2 * math.sqrt(math.log(2)) * sigma, _mA), depth, continuum


def _line_parameters(data, harmonics, v1, inst):
    """σ (mÅ), depth and continuum of `line_parameters` from precomputed coefficients."""
    period = inst.tuning_period.to_value(_mA)
    a1, b1, a2, b2 = harmonics
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = 0.5 * np.log((a1**2 + b1**2) / (a2**2 + b2**2))   # ln(|F1| / |F2|)
        sigma = np.where(ratio > 0, period / math.pi * np.sqrt(np.abs(ratio) / 3), np.nan)
        f1 = np.hypot(a1, b1) * 2 / N_TUNINGS
        depth = period * f1 / (2 * sigma * math.sqrt(math.pi)) * np.exp((math.pi * sigma / period) ** 2)
        centre = v1 / inst.velocity_per_wavelength.to_value(u.m / u.s / _mA)
        continuum = data.mean(axis=0)
        for delta in inst.tuning_offsets.to_value(_mA):
            continuum = continuum + depth * np.exp(-((delta - centre) / sigma) ** 2) / N_TUNINGS
    continuum = np.where(np.isfinite(continuum), continuum, data.mean(axis=0))
    return sigma, depth, continuum


def reduce_hmi(planes, instrument=None):
    """
    HMI's LOS reduction: 12 filtergrams → magnetogram, Dopplergram, continuum.

    Parameters
    ----------
    planes : array_like or `~astropy.units.Quantity`
        Shape (12, ...), dark- and flat-corrected filtergrams in any unit:
        plane = polarisation × 6 + tuning, LCP (I+V) first, tunings I0..I5
        (`HMIInstrument.analysers`).
    instrument : `~gongsynth.instruments.hmi.HMIInstrument`, optional

    Returns
    -------
    `~gongsynth.stages.reduction.Observables`
        ``magnetogram`` (G), ``doppler`` (m/s, positive = redshift),
        ``continuum`` (HMI's continuum estimate averaged over LCP and RCP, in
        the unit of ``planes``), ``velocity`` (2, ...) corrected v_LCP and
        v_RCP (m/s) and ``phase`` (2, ...) first-harmonic phases (rad), both
        float32, and
        ``wrapped``: True where either polarisation's raw velocity lies outside
        the look-up table's monotonic range (the velocity is then clipped to
        ±``lut_velocity_max``: saturation).

    Examples
    --------
    >>> import numpy as np
    >>> obs = reduce_hmi(np.ones((12, 2)))   # no line at all: undefined phase, but finite
    >>> obs.magnetogram.shape
    (2,)
    """
    inst = resolve_hmi(instrument)
    data, unit = _split(planes)
    shape = data.shape[1:]
    flat = data.reshape(N_HMI_PLANES, -1)
    table = lookup_table(inst)
    gauss = inst.gauss_per_velocity.to_value(u.G * u.s / u.m)
    # v and B in float64; each polarisation's velocity and phase, diagnostics, in float32 (1 mm/s at
    # 10 km/s, 1e-7 rad: far below the noise; 0.27 GB less for a 4096² frame).
    velocity = np.empty((2, flat.shape[1]), dtype=np.float32)
    phase = np.empty_like(velocity)
    magnetogram, doppler = np.empty(flat.shape[1]), np.empty(flat.shape[1])
    wrapped = np.zeros(flat.shape[1], dtype=bool)
    continuum = np.zeros(flat.shape[1])
    # Blocks of pixels bound the temporaries (a 4096² frame is 16.8 M pixels).
    for start in range(0, flat.shape[1], _BLOCK):
        block = slice(start, start + _BLOCK)
        corrected = []
        for pol in (0, 1):
            part = flat[pol * N_TUNINGS:(pol + 1) * N_TUNINGS, block]
            harmonics = _harmonics(part)
            v1, _, phase[pol, block] = _velocities(harmonics, inst, second=False)
            v, outside = table.correct(v1, 1)
            velocity[pol, block] = v
            corrected.append(v)
            wrapped[block] |= outside
            continuum[block] += _line_parameters(part, harmonics, v1, inst)[2] / 2
        v_lcp, v_rcp = corrected
        magnetogram[block] = (v_lcp - v_rcp) * gauss
        doppler[block] = (v_lcp + v_rcp) / 2
    return Observables(
        magnetogram=u.Quantity(magnetogram.reshape(shape), u.G),
        doppler=u.Quantity(doppler.reshape(shape), u.m / u.s),
        continuum=u.Quantity(continuum.reshape(shape), unit),
        velocity=u.Quantity(velocity.reshape((2,) + shape), u.m / u.s),
        phase=u.Quantity(phase.reshape((2,) + shape), u.rad),
        wrapped=wrapped.reshape(shape),
    )
