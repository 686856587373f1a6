"""
SOHO/MDI: parameters with sources, schedule (whole magnetograms only), filters, the onboard
ratio algorithm and its look-up table, level-1.8 recalibration, noise, registry and maps.

The test profiles are analytic (Gaussian σ components of a normal Zeeman triplet,
`gongsynth.instruments.hmi.profiles`), independent of gongsynth.sun.
"""
import dataclasses
import tomllib

import astropy.units as u
import numpy as np
import pytest

import gongsynth
from gongsynth import instruments
from gongsynth.config import SimulationConfig
from gongsynth.instruments.hmi.filters import profile_width
from gongsynth.instruments.hmi.profiles import gaussian_line, zeeman_shift, zeeman_triplet
from gongsynth.instruments.mdi import N_MDI_PLANES, MDIInstrument, resolve_mdi
from gongsynth.instruments.mdi.filters import filter_quadrature, lyot_narrowest_fsr, lyot_transmission
from gongsynth.instruments.mdi.noise import (
    FILTERGRAM_COUNTS,
    FILTERGRAM_SHOT_NOISE,
    continuum_electrons,
    effective_area_from_counts,
    magnetogram_noise,
)
from gongsynth.instruments.mdi.observables import doppler_ratio, lookup_table, onboard_continuum, reduce_mdi
from gongsynth.instruments.quadrature import channel_weights

MA = u.Unit("mAA")
MDI = MDIInstrument()
X = np.arange(-1500.0, 1500.01, 1.0)                        # λ − λ0 in mÅ
WEIGHTS = channel_weights(MDI.line_wavelength + X * MA, MDI).to_value(MA)
PER_MA = MDI.velocity_per_wavelength.to_value(u.m / u.s / MA)
DEPTH = MDI.reference_line_depth.to_value(u.one)
FWHM = MDI.reference_line_fwhm.to_value(MA)


def triplet(v, b, lande_g=1.5):
    """I and V of a longitudinal triplet of the reference line at velocity v (m/s) and field b (G)."""
    split = zeeman_shift(b * u.G, lande_g, MDI.line_wavelength).to_value(MA)
    return zeeman_triplet(X, v / PER_MA, split, 0.0, DEPTH, FWHM)


def reduce_one(v, b, inst=MDI, **kwargs):
    stokes_i, stokes_v = triplet(v, b, **kwargs)
    planes = np.concatenate([WEIGHTS @ (stokes_i + stokes_v), WEIGHTS @ (stokes_i - stokes_v)])
    obs = reduce_mdi(planes[:, None], inst)
    return obs.doppler.to_value(u.m / u.s)[0], obs.magnetogram.to_value(u.G)[0], bool(obs.wrapped[0])


def test_parameters_sources_and_registry():
    mdi = instruments.get("MDI")
    assert isinstance(mdi, MDIInstrument) and mdi == MDI and "mdi" in instruments.names()
    assert instruments.MDIInstrument is MDIInstrument
    assert (mdi.name, mdi.label, mdi.line) == ("mdi", "MDI", "Ni I 676.8")
    assert mdi.line_wavelength == 676.78 * u.nm and mdi.aperture == 12.5 * u.cm
    assert mdi.detector_shape == 1024 and abs(mdi.plate_scale - 2 * u.arcsec) < 0.02 * u.arcsec
    for field in dataclasses.fields(MDIInstrument):
        assert len(MDIInstrument.source(field.name)) > 10
    with pytest.raises(KeyError, match="no parameter"):
        MDIInstrument.source("name")
    np.testing.assert_allclose(mdi.tuning_offsets.to_value(MA), [189.0, -113.4, -37.8, 37.8, 113.4])
    assert mdi.analysers[:5] == tuple((k, 1) for k in range(5)) and mdi.analysers[5] == (0, -1)
    assert mdi.plane_names[0] == "LCP F0" and mdi.plane_names[-1] == "RCP F4"
    # K_m: half GONG's constant (which multiplies the half difference) for the same g and line.
    gong = instruments.get("gong")
    assert mdi.gauss_per_velocity.value == pytest.approx(gong.gauss_per_velocity.value / 2, rel=1e-12)
    text = mdi.replace(level="1.5").to_toml()
    assert 'name = "mdi"' in text and instruments.from_dict(
        tomllib.loads(text)["instrument"]) == mdi.replace(level="1.5")
    assert SimulationConfig.from_toml('[instrument]\nname = "mdi"\n').instrument == mdi
    assert resolve_mdi(None) == mdi
    with pytest.raises(ValueError, match="level"):
        mdi.replace(level="2.0")
    with pytest.raises(TypeError, match="MDIInstrument"):
        resolve_mdi(instruments.get("gong"))


def test_schedule_takes_only_whole_magnetograms():
    s = MDI.schedule(MDI.default_duration)
    assert MDI.default_duration == 1 * u.min and s.n_frames == 20
    assert s.frames_per_plane.tolist() == [2] * N_MDI_PLANES and s.duration == 60 * u.s
    # 15-s passes of F0..F4, LCP and RCP alternating.
    assert s.plane[:15].tolist() == [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 0, 1, 2, 3, 4]
    assert MDI.schedule(5 * u.min).frames_per_plane.tolist() == [10] * N_MDI_PLANES
    # An incomplete magnetogram would give LCP planes more frames than RCP (the HMI bug class).
    for bad in (45 * u.s, 90 * u.s, 1.5 * u.min):
        with pytest.raises(ValueError, match="duration must be a whole number of"):
            MDI.schedule(bad)
    with pytest.raises(ValueError, match="duration"):
        SimulationConfig(seed=1, instrument="mdi", duration=90 * u.s)
    from gongsynth.cli import _simulation_config, build_parser, main
    # A run that names no duration takes one magnetogram, in Python and on the command line.
    assert SimulationConfig(seed=1, instrument="mdi").duration == 1 * u.min
    assert _simulation_config(build_parser().parse_args(["simulate", "--instrument", "mdi", "--out", "x"])) \
        .duration == 1 * u.min
    assert main(["simulate", "--instrument", "mdi", "--duration", "0.75", "--out", "unused"]) == 2


def test_filtergrams_against_the_documented_design():
    offset, weights, responses = filter_quadrature(MDI)
    # Narrow Michelson alone: cos² of FSR 189 mÅ, FWHM = FSR / 2 = 94.5 mÅ (documented 94 mÅ).
    michelson = 0.5 * (1 + np.cos(2 * np.pi * offset / MDI.nb_fsr.to_value(MA)))
    assert profile_width(offset[np.abs(offset) < 94], michelson[np.abs(offset) < 94])[1] == \
        pytest.approx(94.5, abs=0.3)
    lyot = lyot_transmission(offset, lyot_narrowest_fsr(MDI).to_value(MA), MDI.lyot_elements)
    assert profile_width(offset, lyot)[1] == pytest.approx(465.0, abs=0.5)
    for k, nominal in enumerate(MDI.tuning_offsets.to_value(MA)[1:], start=1):
        near = np.abs(offset - nominal) < 150
        peak, fwhm = profile_width(offset[near], responses[k, near])
        # The Lyot envelope pulls each peak a few mÅ toward the line; two Michelsons: 0.457 FSR.
        assert abs(peak - nominal) < 5 and abs(peak) < abs(nominal)
        assert fwhm == pytest.approx(85, abs=2)
    # F0 has equal twin peaks in the wings at ±189 mÅ (half a wide-Michelson period).
    twin = responses[0][np.argmin(np.abs(offset - 182))], responses[0][np.argmin(np.abs(offset + 182))]
    assert twin[0] == pytest.approx(twin[1], rel=1e-3) and responses[0][np.argmin(np.abs(offset))] < 0.01
    # Mirror symmetry: F1 ↔ F4, F2 ↔ F3; equal integrals (equal continua).
    np.testing.assert_allclose(responses[1], responses[4][::-1], atol=1e-9)
    np.testing.assert_allclose(responses @ weights, (responses @ weights)[0], rtol=1e-6)


def test_doppler_ratio_and_continuum_by_hand():
    assert float(doppler_ratio([3000.0, 2500.0, 2500.0, 3000.0])) == 0.0
    red = [3000.0, 2800.0, 2400.0, 2900.0]     # S = 500, Sa = 600
    blue = red[::-1]                           # S = -500, F4 - F2 = 600
    assert float(doppler_ratio(red)) == pytest.approx(500 / 600)
    assert float(doppler_ratio(blue)) == pytest.approx(-500 / 600)
    # Beyond F4 (F1 − F3 < 0 with a red numerator): +inf, held at the table's red end.
    assert doppler_ratio([2000.0, 2600.0, 2500.0, 1900.0]) == np.inf
    assert doppler_ratio([1900.0, 2500.0, 2600.0, 2000.0]) == -np.inf
    assert np.isnan(doppler_ratio([2000.0, 2000.0, 2000.0, 2000.0]))     # no line at all
    with pytest.raises(ValueError, match="leading axis"):
        doppler_ratio(np.ones(3))
    assert float(onboard_continuum([3000.0, 3000.0, 2500.0, 2500.0, 3000.0])) == 3125.0


@pytest.mark.parametrize("v", [-3000.0, 0.0, 3000.0])
def test_doppler_and_field_recovered_below_saturation(v):
    for shift in (v, v + 3.0):
        doppler, b, wrapped = reduce_one(shift, 0.0)
        assert doppler == pytest.approx(shift, abs=0.5) and abs(b) < 0.5 and not wrapped
    onboard = MDI.replace(level="1.5")
    for b in (-2000.0, -100.0, 10.0, 1000.0, 2500.0):
        doppler, measured, wrapped = reduce_one(v, b, onboard)
        assert measured == pytest.approx(b, abs=0.5 + 1e-4 * abs(b)) and not wrapped
        assert doppler == pytest.approx(v, abs=0.5)
        # Level 1.8 is the same magnetogram times the archive's factor.
        assert reduce_one(v, b)[1] == pytest.approx(1.7 * measured, rel=1e-12)
    # A Sun with the measured Landé factor (1.426) reads 1.426 / 1.5 of its field onboard.
    assert reduce_one(v, 1000.0, onboard, lande_g=1.426)[1] == pytest.approx(1000 * 1.426 / 1.5, rel=1e-3)


def test_positive_field_gives_positive_magnetogram():
    # Weak-field V = −Δλ_B dI/dλ (B > 0 toward the observer), by finite differences.
    stokes_i = gaussian_line(X, DEPTH, FWHM)
    for b in (20.0, -20.0):
        stokes_v = -zeeman_shift(b * u.G, 1.5, MDI.line_wavelength).to_value(MA) * np.gradient(stokes_i, X)
        planes = np.concatenate([WEIGHTS @ (stokes_i + stokes_v), WEIGHTS @ (stokes_i - stokes_v)])
        measured = reduce_mdi(planes[:, None], MDI.replace(level="1.5")).magnetogram.to_value(u.G)[0]
        assert measured == pytest.approx(b, rel=0.01)


def test_saturation_beyond_the_table():
    table = lookup_table(MDI)
    assert np.all(np.diff(table.alpha) > 0) and np.all(np.diff(table.velocity) > 0)
    vmax = table.velocity[-1]
    assert 5000 < vmax < 9000      # the ratio's branch ends where F1 − F3 changes sign
    per_gauss = zeeman_shift(1 * u.G, 1.5, MDI.line_wavelength).to_value(MA) * PER_MA
    onset = (vmax - 3000.0) / per_gauss           # v_LCP = v + c Δλ_B / λ0 leaves the table
    onboard = MDI.replace(level="1.5")
    assert not reduce_one(3000.0, 0.98 * onset, onboard)[2]
    doppler, measured, wrapped = reduce_one(3000.0, 1.3 * onset, onboard)
    assert wrapped and measured < 1.3 * onset * 0.9 and doppler < 3000.0


def test_photon_budget_and_noise():
    assert effective_area_from_counts().value == pytest.approx(MDI.effective_area.value, rel=2e-3)
    target = (FILTERGRAM_COUNTS / FILTERGRAM_SHOT_NOISE).to_value(u.one) ** 2
    assert continuum_electrons(MDI)[0].value == pytest.approx(target, rel=2e-3)
    one = magnetogram_noise(1, MDI)
    # Monte Carlo of 1000 draws: its σ is known to 2.2 % (1/√(2·999)); 4σ.
    assert magnetogram_noise(1, MDI, method="montecarlo", n_trials=1000, seed=3).value == \
        pytest.approx(one.value, rel=0.09)
    # The 96-minute product: five independent one-minute reductions averaged.
    assert magnetogram_noise(5, MDI, method="montecarlo", n_trials=1000, seed=4).value == \
        pytest.approx(one.value / np.sqrt(5), rel=0.09)
    assert magnetogram_noise(1, MDI.replace(level="1.5")).value == pytest.approx(one.value / 1.7, rel=1e-9)
    # Four times the light: half the noise.
    dark = MDI.replace(read_noise=0 * u.adu)
    brighter = dark.replace(effective_area=4 * MDI.effective_area)
    expected = magnetogram_noise(1, dark).value / 2
    assert magnetogram_noise(1, brighter).value == pytest.approx(expected, rel=1e-5)
    with pytest.raises(ValueError, match="minutes"):
        magnetogram_noise(0, MDI)


def test_a_zero_field_run_has_no_zero_offset_and_honest_maps():
    import sunpy.map

    from gongsynth.sun.photosphere import Photosphere, synthesize

    one = np.ones((32, 32))
    still = 0 * u.km / u.s * one
    sun = Photosphere(0 * u.G * one, 0 * u.deg * one, 0 * u.deg * one, still, still, still, one,
                      1536 * u.km, periodic=True)
    cube = synthesize(sun, mu=1.0, instrument=MDI)
    result = gongsynth.simulate(cube, instrument="mdi", seed=5, duration=1 * u.min, detector_shape=24,
                                resolutions=(1,), progress=False)
    b = result.magnetogram
    noise = magnetogram_noise(1, MDI).value
    # 576 pixels of photon noise: the median is 0 within 4 σ/√N (×1.25 for a median).
    assert abs(np.median(b.data)) < 4 * 1.25 * noise / np.sqrt(b.data.size)
    assert 0.5 * noise < np.std(b.data) < 1.5 * noise
    assert b.meta["telescop"] == "gongsynth (simulated MDI)" and b.meta["recalfac"] == 1.7
    assert b.meta["xposure"] == pytest.approx(20 * MDI.exposure_time.value)
    # sunpy's real MDI source must not claim a simulated file (sunpy issue 7294).
    remade = sunpy.map.Map(b.data, b.meta)
    assert type(remade) is type(b) and type(remade).__name__ == "GONGSynthMap"
    assert not sunpy.map.sources.MDIMap.is_datasource_for(b.data, b.meta)
