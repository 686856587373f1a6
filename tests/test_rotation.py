"""The Sun's rotation and the observer's motion along the line of sight, against analytic values."""
import astropy.units as u
import numpy as np
import pytest
from astropy.coordinates import EarthLocation
from astropy.time import Time
from sunpy.coordinates import get_earth, sun
from sunpy.sun import constants

from gongsynth.sun.rotation import line_of_sight_velocity, rotation_rate

T = Time("2009-09-05T18:54:16")


def test_rotation_profile():
    # Snodgrass & Ulrich (1990): A + B sin²φ + C sin⁴φ.
    assert rotation_rate(0 * u.deg).to_value(u.deg / u.day) == pytest.approx(14.713)
    assert rotation_rate(90 * u.deg).to_value(u.deg / u.day) == pytest.approx(14.713 - 2.396 - 1.787)
    assert rotation_rate(-30 * u.deg) == rotation_rate(30 * u.deg)


def test_limbs_rotate_at_the_profile_rate():
    # Rotation alone: at the equatorial limbs the velocity is ±ωR cos B0
    # (the line of sight is inclined by B0 to the equatorial plane).
    v = line_of_sight_velocity([-90, 90] * u.deg, [0, 0] * u.deg, T, observer=False)
    omega_r = (rotation_rate(0 * u.deg).to(u.rad / u.s).value / u.s * constants.radius).to(u.m / u.s)
    expected = omega_r * np.cos(sun.B0(T))
    assert v[1].to_value(u.m / u.s) == pytest.approx(expected.value, abs=1.0)
    assert v[0] == -v[1]
    # At 60° latitude on the central meridian the rotation is across the line of sight: 0.
    assert abs(line_of_sight_velocity(0 * u.deg, 60 * u.deg, T, observer=False)) < 1e-6 * u.m / u.s


def test_the_sub_observer_point_moves_with_the_earth_sun_distance():
    # Observer motion alone at the point facing the Earth: the rate of change
    # of the Earth-Sun distance from the ephemeris (negative: the Earth approaches).
    b0 = sun.B0(T)
    v = line_of_sight_velocity(0 * u.deg, b0, T, rotation=False)
    step = 30 * u.s
    rate = ((get_earth(T + step).radius - get_earth(T - step).radius) / (2 * step)).to(u.m / u.s)
    assert v.to_value(u.m / u.s) == pytest.approx(rate.value, abs=1.0)
    assert rate < 0 * u.m / u.s  # September: after aphelion


def test_the_limbs_with_the_observer_and_a_site():
    v = line_of_sight_velocity([-90, 90] * u.deg, [0, 0] * u.deg, T)
    rotation = line_of_sight_velocity([-90, 90] * u.deg, [0, 0] * u.deg, T, observer=False)
    # The Earth's orbital motion across the line of sight slows the apparent
    # rotation to about the synodic rate (ω - 0.986°/day at this date).
    half = (v[1] - v[0]) / 2
    assert (half / rotation[1]).to_value(u.one) == pytest.approx(1 - 0.9856 / 14.713, abs=0.01)
    # A site on the turning Earth adds at most 465 m/s × cos(site latitude).
    big_bear = EarthLocation(lat=34.26 * u.deg, lon=-116.92 * u.deg, height=2067 * u.m)
    on_site = line_of_sight_velocity([-90, 90] * u.deg, [0, 0] * u.deg, T, site=big_bear)
    shift = (on_site - v).to_value(u.m / u.s)
    # Nearly the same at both limbs: the two lines of sight differ by ±0.27° (R☉/D), so the
    # site's 390 m/s projects differently by ~2 m/s, and its 6400 km offset changes the
    # geometry of the 30 km/s orbital motion by ~1 m/s.
    assert shift[0] == pytest.approx(shift[1], abs=5.0)
    assert 0 < abs(shift[0]) < 465 * np.cos(np.deg2rad(34.26))


def test_nan_points_stay_nan():
    v = line_of_sight_velocity([np.nan, 10] * u.deg, [0, 0] * u.deg, T)
    assert np.isnan(v[0]) and np.isfinite(v[1])
