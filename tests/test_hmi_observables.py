"""
HMI's MDI-like reduction on analytic profiles: Doppler and B recovery, linearity,
saturation, sign, Zeeman triplets, and the photon noise of 45-s and 720-s magnetograms.

The test profiles are built here (Gaussian σ components of a normal Zeeman
triplet, g = 2.5), independent of gongsynth.sun.
"""
import math

import astropy.units as u
import numpy as np
import pytest

from gongsynth.instruments.hmi import HMIInstrument
from gongsynth.instruments.hmi.filters import filtergram_weights
from gongsynth.instruments.hmi.noise import (
    CONTINUUM_COUNT_RATE,
    LIU_2012_NOISE,
    continuum_electrons,
    effective_area_from_counts,
    magnetogram_noise,
    sequence_weights,
)
from gongsynth.instruments.hmi.observables import (
    line_parameters,
    lookup_table,
    raw_velocities,
    reduce_hmi,
)
from gongsynth.instruments.hmi.profiles import gaussian_line, zeeman_shift, zeeman_triplet
from gongsynth.stages.reduction import Observables

MA = u.Unit("mAA")
HMI = HMIInstrument()
X = np.arange(-1200.0, 1200.01, 1.0)                       # λ − λ0 in mÅ
WEIGHTS = filtergram_weights(HMI.line_wavelength + X * MA, HMI).to_value(MA)
PER_MA = HMI.velocity_per_wavelength.to_value(u.m / u.s / MA)
DEPTH = HMI.reference_line_depth.to_value(u.one)
FWHM = HMI.reference_line_fwhm.to_value(MA)


def triplet(v, b, gamma=0.0, depth=DEPTH, fwhm=FWHM):
    """I and V of a triplet of the given line (g = 2.5) at velocity v (m/s) and field b (G)."""
    split = zeeman_shift(b * u.G, 2.5, HMI.line_wavelength).to_value(MA)
    return zeeman_triplet(X, v / PER_MA, split, gamma, depth, fwhm)


def observe(stokes_i, stokes_v):
    """The 12 planes (LCP = I+V at I0..I5, then RCP = I−V) of one spectrum."""
    return np.concatenate([WEIGHTS @ (stokes_i + stokes_v), WEIGHTS @ (stokes_i - stokes_v)])


def reduce_one(v, b, **kwargs):
    obs = reduce_hmi(observe(*triplet(v, b, **kwargs))[:, None], HMI)
    return obs.doppler.to_value(u.m / u.s)[0], obs.magnetogram.to_value(u.G)[0], bool(obs.wrapped[0])


def test_output_is_observables_with_units():
    planes = np.stack([observe(*triplet(v, 500.0)) for v in (-1000.0, 0.0, 1000.0)], axis=1)
    obs = reduce_hmi(planes * u.adu)
    assert isinstance(obs, Observables)
    assert obs.magnetogram.unit == u.G and obs.doppler.unit == u.m / u.s
    assert obs.continuum.unit == u.adu and obs.phase.unit == u.rad
    assert obs.velocity.shape == obs.phase.shape == (2, 3) and obs.wrapped.shape == (3,)
    np.testing.assert_allclose(obs.magnetogram.value, 500.0, atol=0.05)
    np.testing.assert_allclose(obs.doppler.value, [-1000.0, 0.0, 1000.0], atol=0.05)
    # HMI's continuum estimate from a Gaussian fit through δ-function filters: within 5 %
    # of the filtered continuum (Σ_k W_k / 6) for the reference line.
    np.testing.assert_allclose(obs.continuum.value, WEIGHTS.sum(axis=1).mean(), rtol=0.05)


@pytest.mark.parametrize("v", [-3000.0, 0.0, 3000.0])
def test_doppler_recovered_on_the_reference_line(v):
    # The table maps the reference line back exactly (nodes every 24 m/s; 1 m/s between them).
    for shift in (v, v + 7.0):
        doppler, b, wrapped = reduce_one(shift, 0.0)
        assert doppler == pytest.approx(shift, abs=0.5)
        assert abs(b) < 0.05 and not wrapped


def test_raw_velocity_needs_the_lookup_table():
    # Without the table the first-harmonic velocity is off by ~3 % at 3 km/s and 50 m/s at rest.
    raw = [raw_velocities(observe(*triplet(v, 0.0))[:6], HMI)[0] for v in (0.0, 3000.0)]
    assert 20 < abs(raw[0]) < 100
    assert 0.9 < raw[1] / 3000 < 0.99


@pytest.mark.parametrize("v", [-3000.0, 0.0, 3000.0])
def test_field_linear_below_saturation(v):
    # A longitudinal field: each circular polarisation is a shifted σ component.
    limit = 3000.0 if v else 4400.0
    for b in (-limit, -1000.0, 10.0, 100.0, 1000.0, limit):
        doppler, measured, wrapped = reduce_one(v, b)
        assert measured == pytest.approx(b, abs=0.05 + 1e-4 * abs(b))
        assert doppler == pytest.approx(v, abs=0.5) and not wrapped


def test_saturation_with_large_doppler_shift():
    # v_LCP = v + c Δλ_B/λ0 leaves the table (±9.6 km/s) when B > (9.6 km/s − |v|)/(2.16 m/s/G):
    # 3055 G at |v| = 3 km/s, 4444 G at rest (the cap of real hmi.M_45s files).
    per_gauss = zeeman_shift(1 * u.G, 2.5, HMI.line_wavelength).to_value(MA) * PER_MA
    vmax = HMI.lut_velocity_max.to_value(u.m / u.s)
    onset = (vmax - 3000.0) / per_gauss
    assert onset == pytest.approx(3055, abs=2)
    below = reduce_one(3000.0, 0.99 * onset)
    assert below[1] == pytest.approx(0.99 * onset, rel=1e-4) and not below[2]
    for b in (3500.0, 4000.0):
        doppler, measured, wrapped = reduce_one(3000.0, b)
        assert wrapped
        # v_LCP is clipped to 9.6 km/s: the magnetogram under-reads, with half the slope.
        assert measured == pytest.approx(b - (b - onset) / 2, rel=1e-3)
        assert doppler < 3000.0 - 0.9 * (b - onset) * per_gauss / 2
    _, capped, wrapped = reduce_one(0.0, 5000.0)
    cap = 2 * vmax * HMI.gauss_per_velocity.to_value(u.G * u.s / u.m)
    assert wrapped and capped == pytest.approx(cap, rel=1e-6) and cap == pytest.approx(4443.8, abs=1)


def test_positive_field_gives_positive_magnetogram():
    # Weak-field Stokes V from gongsynth's convention V = −Δλ_B dI/dλ (B > 0 toward
    # the observer), computed by finite differences: independent of `triplet`.
    stokes_i = gaussian_line(X, DEPTH, FWHM)
    for b in (20.0, -20.0):
        stokes_v = -zeeman_shift(b * u.G, 2.5, HMI.line_wavelength).to_value(MA) * np.gradient(stokes_i, X)
        measured = reduce_hmi(observe(stokes_i, stokes_v)[:, None]).magnetogram.to_value(u.G)[0]
        assert np.sign(measured) == np.sign(b)
        assert measured == pytest.approx(b, rel=0.01)


@pytest.mark.parametrize("gamma, b, tolerance", [
    (0, 100.0, 0.015), (0, 1000.0, 0.015), (0, 2000.0, 0.015),
    (30, 1000.0, 0.015), (60, 1000.0, 0.03), (60, 2000.0, 0.10),
])
def test_zeeman_triplet_of_another_line(gamma, b, tolerance):
    # A line 18 % wider and 17 % shallower than the table's: the MDI-like algorithm
    # reads B_LOS = B cosγ to ~1 % for a longitudinal field (the table assumes the
    # reference shape); the π component of inclined strong fields adds a few %.
    measured = reduce_one(0.0, b, gamma=math.radians(gamma), depth=0.55, fwhm=110.0)[1]
    assert measured == pytest.approx(b * math.cos(math.radians(gamma)), rel=tolerance)


def test_line_parameters_of_the_reference_line():
    fwhm, depth, continuum = line_parameters(observe(*triplet(0.0, 0.0))[:6])
    # δ-function formulas applied to 76-mÅ filters: wider and shallower than the line, as in HMI.
    assert FWHM < fwhm.to_value(MA) < 1.5 * FWHM
    assert 0.5 * DEPTH * 50 < depth < DEPTH * 50


def test_bad_planes():
    with pytest.raises(ValueError, match="leading axis of 12"):
        reduce_hmi(np.ones((6, 3)))
    planes = np.ones((12, 2))
    planes[3, 1] = np.nan
    with pytest.raises(ValueError, match="planes"):
        reduce_hmi(planes)


def test_lookup_table_is_monotonic_over_its_range():
    table = lookup_table(HMI)
    assert table.velocity[0] == -9600 and table.velocity[-1] == 9600
    assert table.valid1 == slice(0, table.velocity.size)
    assert np.all(np.diff(table.raw1) > 0)


# ------------------------------------------------------------------- noise
def test_effective_area_reproduces_the_counts():
    electrons = continuum_electrons(HMI).mean()
    target = CONTINUUM_COUNT_RATE * HMI.exposure_time * HMI.gain
    assert (electrons / target).to_value(u.one) == pytest.approx(1, rel=0.01)
    assert effective_area_from_counts(HMI).to_value(u.cm**2) == pytest.approx(
        HMI.effective_area.to_value(u.cm**2), rel=0.01)


def test_720s_weights():
    times, weights = sequence_weights("720s")
    assert len(times) == 9 and weights.sum() == pytest.approx(1)
    assert times[-1] - times[0] == HMI.vector_window - HMI.vector_cycle
    np.testing.assert_allclose(weights, weights[::-1])
    with pytest.raises(ValueError, match="product"):
        sequence_weights("90s")


@pytest.mark.parametrize("product", ["45s", "720s"])
def test_noise_monte_carlo_matches_propagation(product):
    analytic = magnetogram_noise(product).to_value(u.G)
    mc = magnetogram_noise(product, method="montecarlo", n_trials=4000, seed=7).to_value(u.G)
    # The relative standard error of a standard deviation from n draws is 1/sqrt(2(n−1)) = 1.1 %.
    assert mc == pytest.approx(analytic, rel=4 * 0.0112)
    # Photon noise is part of the documented total noise (Liu et al. 2012: 10.2 G, 6.3 G),
    # which also holds the quiet Sun's own signal and the pipeline's processing.
    documented = LIU_2012_NOISE[product].to_value(u.G)
    assert analytic < documented
    if product == "45s":
        assert analytic > 0.5 * documented


def test_noise_scales_with_photons():
    faint = HMI.replace(exposure_time=HMI.exposure_time / 4)
    ratio = magnetogram_noise("45s", faint) / magnetogram_noise("45s")
    assert ratio.to_value(u.one) == pytest.approx(2, rel=0.02)
