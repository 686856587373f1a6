r"""
The solar cycle that the synthetic Sun follows: sunspot number, active latitudes, polarities, polar fields.

**Cycle timing and amplitude.**  Minima and smoothed maxima (13-month
smoothed sunspot number, SILSO version 2, Clette et al. 2014, Space Sci. Rev.
186, 35) of cycles 21–25; cycle 25's maximum (~161, October 2024) is
provisional and cycle 26's start (2030.9) assumed, 11 years after cycle 25's.
Outside 1976–2041 cycles are extrapolated with an 11.0-year period and a
peak of 180 (an assumption, the mean of the v2 maxima of cycles 21–25).

**Shape.**  Each cycle's sunspot number is Hathaway, Wilson & Reichmann's
(1994, Sol. Phys. 151, 177; Hathaway 2015, Living Rev. Sol. Phys. 12, 4)
function of the time since its start, in months,

.. math:: R(t) = \frac{a\,t^3}{\exp(t^2/b^2) - c}, \qquad c = 0.8,
          \qquad b = 27.12 + 25.15\,(10^3 a)^{-1/4},

fitted to the version-1 numbers (≈ 0.6 × v2); here ``a`` is solved so that
the curve's peak equals the observed one (v2 × 0.6), and the curve is
returned in v2 units.  The start ``t0`` is taken at the minimum.  Cycles
overlap: the old one fades while the new one rises.

**Spörer's law.**  The centroid latitude of the sunspot zone of a cycle is
28° exp(−t/90 months) after its start (Hathaway 2011, Sol. Phys. 273, 221);
emergences scatter about it with a standard deviation of 6° (an assumption:
the butterfly wings are about ±10–15° wide).

**Hale's law.**  The leading polarity of a bipole is the same all over a
hemisphere during a cycle, opposite in the other hemisphere, and alternates
from cycle to cycle: positive in the north for the odd cycles (23, 25),
negative for the even ones (24), as observed.

**Joy's law.**  The axis of a bipole is tilted, the leading polarity closer to
the equator, by γ = 32.1° sin|φ| (Stenflo & Kosovichev 2012, ApJ 745, 129),
with a scatter of 15° about it (an assumption, of the order found by Wang &
Sheeley 1989, ApJ 375, 761).

**Polar fields.**  B_r = B_p sin⁸φ (Svalgaard, Duvall & Scherrer 1978, Sol.
Phys. 58, 225), in the north of the sign the cycle's northern leading
polarity had at its start (the trailing flux of the old cycle built it),
reversing near maximum and rebuilding: B_p(phase) = B_p cos(π clip((phase −
0.05)/0.70, 0, 1)), zero at phase 0.40 (reversal ~4.5 years after minimum)
and at full strength from phase 0.75 (~3 years before the next minimum), a
schematic reading of the Wilcox Solar Observatory polar-field record.  The
south is the opposite.
"""
import functools
import math

import astropy.units as u
import numpy as np
from astropy.time import Time
from scipy.optimize import brentq, minimize_scalar

__all__ = ["CYCLES", "ZONE_WIDTH", "JOY_AMPLITUDE", "JOY_SCATTER", "SolarCycle", "cycle_of", "sunspot_number",
           "active_latitude", "leading_polarity", "joy_tilt", "polar_field"]

#: (cycle, start of cycle at minimum [decimal year], smoothed maximum [SILSO v2]);
#: cycle 25's maximum is provisional, cycle 26's start assumed.
CYCLES = ((21, 1976.2, 232.9), (22, 1986.7, 212.5), (23, 1996.6, 180.3), (24, 2008.9, 116.4),
          (25, 2019.9, 160.9), (26, 2030.9, 180.0))

_PERIOD = 11.0  # years, extrapolation
_MEAN_PEAK = 180.0  # v2, extrapolation
_V1_PER_V2 = 0.6  # Clette et al. 2014
_C = 0.8
_ZONE_START, _ZONE_FOLD = 28.0, 90.0 / 12.0  # deg, years (Hathaway 2011)
#: Standard deviation (deg) of emergence latitudes about the sunspot zone's centroid (assumed).
ZONE_WIDTH = 6.0
#: Joy's law amplitude (deg): mean tilt 32.1° sin|latitude| (Stenflo & Kosovichev 2012).
JOY_AMPLITUDE = 32.1
#: Scatter (deg) of tilts about Joy's law (assumed).
JOY_SCATTER = 15.0


def _start(n):
    first, last = CYCLES[0], CYCLES[-1]
    if n < first[0]:
        return first[1] - (first[0] - n) * _PERIOD
    if n > last[0]:
        return last[1] + (n - last[0]) * _PERIOD
    return CYCLES[n - first[0]][1]


def _peak(n):
    first, last = CYCLES[0], CYCLES[-1]
    if n == last[0] or not first[0] <= n <= last[0]:
        return _MEAN_PEAK
    return CYCLES[n - first[0]][2]


def _b(a):
    return 27.12 + 25.15 / (a * 1e3) ** 0.25


@functools.cache
def _shape_peak():
    """The maximum over s of s³ / (exp(s²) − c): the peak of the curve in units of a b³."""
    best = minimize_scalar(lambda s: -s**3 / (math.exp(s * s) - _C), bounds=(0.2, 3.0), method="bounded")
    return -best.fun


@functools.cache
def _amplitude(n):
    """Hathaway's a (v1 units, months) for which the curve peaks at the cycle's observed maximum."""
    target = _V1_PER_V2 * _peak(n)
    g = _shape_peak()
    return brentq(lambda a: a * _b(a) ** 3 * g - target, 1e-6, 1.0, xtol=1e-12)


def _year(obstime):
    return Time(obstime).utc.decimalyear


def cycle_of(obstime):
    """
    The cycle in progress at ``obstime`` (the one whose minimum came last) and the phase in it.

    Parameters
    ----------
    obstime : `~astropy.time.Time` or str

    Returns
    -------
    number : int
    phase : float
        Fraction of the way from this cycle's minimum to the next, in [0, 1).

    Examples
    --------
    >>> n, phase = cycle_of("2014-04-01")
    >>> n, round(phase, 3)
    (24, 0.486)
    """
    year = _year(obstime)
    n = CYCLES[0][0] + math.floor((year - CYCLES[0][1]) / _PERIOD) - 1
    while _start(n + 1) <= year:
        n += 1
    while _start(n) > year:
        n -= 1
    return n, float((year - _start(n)) / (_start(n + 1) - _start(n)))


class SolarCycle:
    """
    One sunspot cycle: its number, start, length and Hathaway-curve amplitude.

    Parameters
    ----------
    number : int
        The cycle (24 began in 2008.9).

    Examples
    --------
    >>> c = SolarCycle(24)
    >>> c.start, round(c.length, 1), round(c.sunspot_number(2014.3), 1)
    (2008.9, 11.0, 111.0)
    """

    def __init__(self, number):
        self.number = int(number)
        self.start = _start(self.number)
        self.length = _start(self.number + 1) - self.start
        self.a = _amplitude(self.number)
        self.b = _b(self.a)

    def __repr__(self):
        return f"SolarCycle({self.number})"

    def sunspot_number(self, year):
        """
        Smoothed sunspot number (v2) contributed by this cycle at decimal ``year``(s).

        Parameters
        ----------
        year : float or `numpy.ndarray`

        Returns
        -------
        float or `numpy.ndarray`
            Zero before the cycle's start.
        """
        months = np.maximum(12.0 * (np.asarray(year, dtype=float) - self.start), 0.0)
        with np.errstate(over="ignore"):
            value = self.a * months**3 / (np.exp((months / self.b) ** 2) - _C)
        value = value / _V1_PER_V2
        return float(value) if value.ndim == 0 else value

    def phase(self, year):
        """Fraction of the cycle elapsed at decimal ``year``(s) (may lie outside [0, 1))."""
        return (np.asarray(year, dtype=float) - self.start) / self.length


def sunspot_number(obstime):
    """
    The smoothed sunspot number (v2) of the model at ``obstime``: the sum over overlapping cycles.

    Parameters
    ----------
    obstime : `~astropy.time.Time` or str

    Returns
    -------
    float

    Examples
    --------
    >>> round(sunspot_number("2009-09-05"), 1), round(sunspot_number("2014-04-01"), 1)
    (5.6, 111.7)
    """
    year = _year(obstime)
    n, _ = cycle_of(obstime)
    return float(sum(SolarCycle(m).sunspot_number(year) for m in (n - 1, n, n + 1)))


def active_latitude(years_since_start):
    """
    Centroid |latitude| of the sunspot zone a time after the cycle's start (Spörer's law).

    Parameters
    ----------
    years_since_start : float or `numpy.ndarray`

    Returns
    -------
    `~astropy.units.Quantity`
        In deg.

    Examples
    --------
    >>> active_latitude([0.0, 5.0, 10.0]).round(1)
    <Quantity [28. , 14.4,  7.4] deg>
    """
    t = np.maximum(np.asarray(years_since_start, dtype=float), 0.0)
    return _ZONE_START * np.exp(-t / _ZONE_FOLD) * u.deg


def leading_polarity(cycle, hemisphere):
    """
    Sign of the leading (westward) polarity of bipoles of a cycle in a hemisphere (Hale's law).

    Parameters
    ----------
    cycle : int or array of int
    hemisphere : int or array
        +1 north, −1 south.

    Returns
    -------
    int or `numpy.ndarray`
        +1 or −1.

    Examples
    --------
    >>> leading_polarity(24, 1), leading_polarity(24, -1), leading_polarity(25, 1)
    (-1, 1, 1)
    """
    sign = np.where(np.asarray(cycle) % 2 == 1, 1, -1) * np.sign(hemisphere)
    return int(sign) if np.ndim(sign) == 0 else sign.astype(int)


def joy_tilt(latitude):
    """
    Mean tilt of a bipole's axis at a latitude (Joy's law), leading polarity equatorward.

    Parameters
    ----------
    latitude : `~astropy.units.Quantity`

    Returns
    -------
    `~astropy.units.Quantity`
        In deg, ≥ 0 (the angle toward the equator).

    Examples
    --------
    >>> import astropy.units as u
    >>> joy_tilt([-30, 0, 20] * u.deg).round(2)
    <Quantity [16.05,  0.  , 10.98] deg>
    """
    return JOY_AMPLITUDE * np.abs(np.sin(u.Quantity(latitude, u.deg))) * u.deg


def polar_field(obstime, latitude, strength=10 * u.G, *, cycle_phase=None):
    """
    Radial polar field at latitudes, at the cycle phase of ``obstime``.

    Parameters
    ----------
    obstime : `~astropy.time.Time` or str
        Sets the cycle (hence the signs) and, unless ``cycle_phase`` is given, the phase.
    latitude : `~astropy.units.Quantity`
    strength : `~astropy.units.Quantity`
        B_p, the field at the pole at full strength.
    cycle_phase : float, optional
        Phase in the cycle of ``obstime`` instead of the date's own.

    Returns
    -------
    `~astropy.units.Quantity`
        In gauss.

    Examples
    --------
    >>> import astropy.units as u
    >>> polar_field("2009-01-01", [90, -90] * u.deg).round(2)   # cycle 24 starts: north negative
    <Quantity [-10.,  10.] G>
    """
    n, phase = cycle_of(obstime)
    if cycle_phase is not None:
        phase = float(cycle_phase)
    lat = u.Quantity(latitude, u.deg)
    north_sign = leading_polarity(n, 1)
    strength_now = np.cos(np.pi * np.clip((phase - 0.05) / 0.70, 0.0, 1.0))
    sin = np.sin(lat).value
    return (north_sign * strength_now * np.sign(sin) * sin**8 * u.Quantity(strength, u.G)).to(u.G)
