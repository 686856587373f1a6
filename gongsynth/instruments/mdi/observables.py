r"""
MDI's onboard algorithm: four filtergrams per polarisation → a ratio → velocity → B_LOS.

MDI's image processor reduced every pixel on board (Scherrer et al. 1995).
From the filtergrams F1..F4 of one polarisation (nominally −120, −40, +40,
+120 mÅ from the line, SOI ``ipvcalc``) it forms the differences
(SOI ``ipvcalc``; Liu & Hoeksema 2008)

.. math::

    S_a = F_1 - F_3,\qquad S_c = F_2 - F_4,\qquad S = S_a + S_c = (F_1 + F_2) - (F_3 + F_4),

and the ratio

.. math::

    \alpha = \begin{cases} S / S_a = \dfrac{F_1 + F_2 - F_3 - F_4}{F_1 - F_3} & S > 0,\\[2ex]
                           S / (-S_c) = \dfrac{F_1 + F_2 - F_3 - F_4}{F_4 - F_2} & S \le 0,\end{cases}

whose denominator is the difference between a far wing and the near-core
filtergram on the side the line has moved to (a red-shifted line darkens F3
and F4, so S > 0).  α is 0 for a line at rest, grows with the shift and is
mapped to a velocity by a look-up table (MDI's 15-bit table; Liu & Hoeksema
2008), here built by passing a Gaussian reference line (the Ni I line at
disk centre: depth 0.6, FWHM 100 mÅ) Doppler-shifted over ±9 km/s through the
same filter model (`gongsynth.instruments.mdi.filters`) and keeping the
monotonic branch around 0.  This is done for LCP (I+V) and RCP (I−V):

.. math::

    v = \tfrac12 (v_\mathrm{LCP} + v_\mathrm{RCP}),\qquad
    B_\mathrm{LOS} = f\,(v_\mathrm{LCP} - v_\mathrm{RCP})\,K_m,\qquad
    K_m = \frac{4\pi m_e c}{2 e g \lambda_0} = 0.3519\ \mathrm{G\,s\,m^{-1}}\ (g = 1.5),

with f = 1 at level 1.5 (the onboard magnetogram) and f = 1.7 at level 1.8
(the archive's recalibration, `~gongsynth.instruments.mdi.MDIInstrument.archive_factor`).
Where α leaves the table's branch (a shift beyond about F1 or F4: strong
fields, large Doppler shifts) the velocity is held at the table's end and the
pixel flagged: MDI's known saturation (soi.stanford.edu/magnetic/Lev1.8).
The continuum is the onboard estimate (SOI-TN-132)
:math:`I_c = S_d/8 + I_d/4 + F_0/2`, :math:`S_d = \sum_{1}^{4} F_k`,
:math:`I_d = \sqrt{2(S_a^2 + S_c^2)}`, averaged over the two polarisations.
Simplifications: one table for every pixel (the onboard table was one too; the
ground's per-pixel Doppler corrections cannot reach magnetograms, which are
differences), the table's 15-bit quantisation and the shutter-jitter offset
that level 1.8 removes are not modelled.
"""
from __future__ import annotations

import dataclasses
import functools

import astropy.units as u
import numpy as np

from gongsynth.instruments.base import Observables
from gongsynth.instruments.mdi.filters import filter_quadrature
from gongsynth.instruments.mdi.parameters import N_MDI_PLANES, N_TUNINGS, resolve_mdi
from gongsynth.instruments.tunable import reference_line_filtergrams
from gongsynth.validation import check_finite

__all__ = ["LookupTable", "doppler_ratio", "lookup_table", "reference_filtergrams", "onboard_continuum",
           "reduce_mdi"]

_mA = u.Unit("mAA")


def doppler_ratio(filtergrams):
    """
    MDI's onboard ratio α of the filtergrams F1..F4 of one polarisation.

    Parameters
    ----------
    filtergrams : array_like
        Shape (4, ...) F1..F4, or (5, ...) F0..F4 (F0 is not used).

    Returns
    -------
    alpha : `numpy.ndarray`
        (F1 + F2 − F3 − F4) / (F1 − F3) where the numerator is positive,
        (F1 + F2 − F3 − F4) / (F4 − F2) elsewhere; ±inf (the numerator's sign:
        the line has moved beyond F1 or F4) where that denominator is not
        positive, NaN where the numerator is 0 too (no line to measure).

    Examples
    --------
    >>> float(doppler_ratio([3000.0, 2500.0, 2500.0, 3000.0]))       # line at rest
    0.0
    >>> float(doppler_ratio([3000.0, 2800.0, 2400.0, 2900.0]))       # red-shifted: F3, F4 darker
    0.8333333333333334
    """
    f = np.asarray(filtergrams, dtype=float)
    if f.shape[0] == N_TUNINGS:
        f = f[1:]
    if f.shape[0] != 4:
        raise ValueError(f"filtergrams must have a leading axis of 4 (F1..F4) or 5 (F0..F4), got {f.shape}")
    sa, sc = f[0] - f[2], f[1] - f[3]
    total = sa + sc
    denominator = np.where(total > 0, sa, -sc)
    with np.errstate(divide="ignore", invalid="ignore"):
        beyond = np.where(total != 0, np.sign(total) * np.inf, np.nan)
        return np.where(denominator > 0, total / denominator, beyond)


def onboard_continuum(filtergrams):
    """
    The image processor's continuum Ic = Sd/8 + Id/4 + F0/2 (SOI-TN-132).

    Parameters
    ----------
    filtergrams : array_like
        Shape (5, ...), F0..F4 of one polarisation.

    Returns
    -------
    `numpy.ndarray`
        In the unit of ``filtergrams``.

    Examples
    --------
    >>> float(onboard_continuum([3000.0, 3000.0, 2500.0, 2500.0, 3000.0]))   # SOI-TN-132's example
    3125.0
    """
    f = np.asarray(filtergrams, dtype=float)
    sa, sc = f[1] - f[3], f[2] - f[4]
    return f[1:].sum(axis=0) / 8 + np.sqrt(2 * (sa**2 + sc**2)) / 4 + f[0] / 2


def reference_filtergrams(shift, instrument=None):
    """
    F0..F4 of the reference line Doppler-shifted by ``shift``, relative to the continuum.

    Parameters
    ----------
    shift : array_like
        Shifts λ_line − λ0 in mÅ, shape (n,).
    instrument : `~gongsynth.instruments.mdi.MDIInstrument`, optional

    Returns
    -------
    `numpy.ndarray`
        Shape (5, n), in mÅ (∫ R_k I dλ for a unit continuum).
    """
    inst = resolve_mdi(instrument)
    depth, fwhm = inst.reference_line_depth.to_value(u.one), inst.reference_line_fwhm.to_value(_mA)
    return reference_line_filtergrams(shift, filter_quadrature(inst), depth, fwhm)


@dataclasses.dataclass(frozen=True)
class LookupTable:
    """
    α → velocity on the reference line.

    Attributes
    ----------
    velocity : `numpy.ndarray`
        Input velocities of the reference line, m/s (the table's monotonic branch).
    alpha : `numpy.ndarray`
        The ratio α measured on the reference line at each, strictly increasing.
    """

    velocity: np.ndarray
    alpha: np.ndarray

    def correct(self, alpha):
        """
        Velocity of each α, held at the table's end outside it.

        Parameters
        ----------
        alpha : array_like

        Returns
        -------
        velocity : `numpy.ndarray`
            In m/s.
        outside : `numpy.ndarray` of bool
            True where α lies outside the table or is NaN (saturated, or no line).
        """
        alpha = np.asarray(alpha, dtype=float)
        outside = ~((alpha >= self.alpha[0]) & (alpha <= self.alpha[-1]))
        # ±inf is held at the table's blue or red end; NaN (no line at all) reads 0, flagged.
        return np.interp(np.nan_to_num(alpha, nan=0.0, posinf=np.inf, neginf=-np.inf),
                         self.alpha, self.velocity), outside


@functools.lru_cache(maxsize=8)
def lookup_table(instrument=None):
    """
    The look-up table of an instrument (cached): its reference line through its filters.

    Parameters
    ----------
    instrument : `~gongsynth.instruments.mdi.MDIInstrument`, optional

    Returns
    -------
    `LookupTable`

    Examples
    --------
    >>> t = lookup_table()
    >>> bool(t.alpha[0] < 0 < t.alpha[-1]), bool(t.velocity[0] < -4000 and t.velocity[-1] > 4000)
    (True, True)
    """
    inst = resolve_mdi(instrument)
    vmax = inst.lut_velocity_max.to_value(u.m / u.s)
    step = inst.lut_velocity_step.to_value(u.m / u.s)
    n = int(round(vmax / step))
    velocity = step * np.arange(-n, n + 1)
    shift = velocity / inst.velocity_per_wavelength.to_value(u.m / u.s / _mA)
    alpha = doppler_ratio(reference_filtergrams(shift, inst))
    with np.errstate(invalid="ignore"):   # ±inf beyond the branch: inf − inf
        rising = np.isfinite(alpha[1:]) & np.isfinite(alpha[:-1]) & (np.diff(alpha) > 0)
    lo = hi = n
    while lo > 0 and rising[lo - 1]:
        lo -= 1
    while hi < 2 * n and rising[hi]:
        hi += 1
    return LookupTable(velocity[lo:hi + 1], alpha[lo:hi + 1])


def _split(planes):
    """(10, ...) float array and unit of planes given as an array or Quantity."""
    unit = planes.unit if isinstance(planes, u.Quantity) else u.one
    data = np.asarray(getattr(planes, "value", planes), dtype=float)
    if data.ndim < 1 or data.shape[0] != N_MDI_PLANES:
        raise ValueError(f"planes must have a leading axis of {N_MDI_PLANES} filtergrams "
                         f"(LCP F0..F4, RCP F0..F4), got shape {data.shape}")
    return check_finite(data, "planes"), unit


def reduce_mdi(planes, instrument=None):
    """
    MDI's magnetogram: 10 filtergram planes → magnetogram, Dopplergram, continuum.

    Parameters
    ----------
    planes : array_like or `~astropy.units.Quantity`
        Shape (10, ...), dark- and flat-corrected filtergrams in any unit:
        plane = polarisation × 5 + filtergram, LCP (I+V) first, F0..F4
        (`MDIInstrument.analysers`).  Planes that accumulate several
        one-minute magnetograms' frames give their average (to first order in
        the noise; exactly for a scene that does not change).
    instrument : `~gongsynth.instruments.mdi.MDIInstrument`, optional
        Its ``level`` decides whether the archive's recalibration factor is applied.

    Returns
    -------
    `~gongsynth.stages.reduction.Observables`
        ``magnetogram`` (G), ``doppler`` (m/s, positive = redshift),
        ``continuum`` (the onboard estimate, mean of LCP and RCP, in the unit
        of ``planes``), ``velocity`` (2, ...) v_LCP and v_RCP (m/s), ``phase``
        (2, ...) the ratios α (dimensionless, in the phase slot), and
        ``wrapped``: True where either α lies outside the look-up table
        (saturation: the velocity is held at the table's end).

    Examples
    --------
    >>> import numpy as np
    >>> obs = reduce_mdi(np.ones((10, 2)))   # no line at all: flagged, but finite
    >>> obs.magnetogram.shape, bool(obs.wrapped.all())
    ((2,), True)
    """
    inst = resolve_mdi(instrument)
    data, unit = _split(planes)
    shape = data.shape[1:]
    flat = data.reshape(N_MDI_PLANES, -1)
    table = lookup_table(inst)
    velocity = np.empty((2, flat.shape[1]))
    alpha = np.empty_like(velocity)
    wrapped = np.zeros(flat.shape[1], dtype=bool)
    continuum = np.zeros(flat.shape[1])
    for pol in (0, 1):
        part = flat[pol * N_TUNINGS:(pol + 1) * N_TUNINGS]
        alpha[pol] = doppler_ratio(part)
        velocity[pol], outside = table.correct(alpha[pol])
        wrapped |= outside
        continuum += onboard_continuum(part) / 2
    v_lcp, v_rcp = velocity
    gauss = inst.gauss_per_velocity.to_value(u.G * u.s / u.m) * inst.archive_factor
    return Observables(
        magnetogram=u.Quantity(((v_lcp - v_rcp) * gauss).reshape(shape), u.G),
        doppler=u.Quantity(((v_lcp + v_rcp) / 2).reshape(shape), u.m / u.s),
        continuum=u.Quantity(continuum.reshape(shape), unit),
        velocity=u.Quantity(velocity.reshape((2,) + shape), u.m / u.s),
        phase=u.Quantity(alpha.reshape((2,) + shape), u.one),
        wrapped=wrapped.reshape(shape),
    )
