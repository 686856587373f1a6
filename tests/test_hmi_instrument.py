"""HMIInstrument: defaults with sources, the family contract, TOML round trip, bad input."""
import dataclasses
import math

import astropy.units as u
import numpy as np
import pytest

from gongsynth.instruments.hmi import N_HMI_PLANES, HMIInstrument, resolve_hmi
from gongsynth.instruments.hmi.parameters import TUNING_INDICES


def test_contract_attributes():
    hmi = HMIInstrument()
    assert hmi.name == "hmi" and hmi.line == "Fe I 617.3"
    assert hmi.line_wavelength == 617.33433 * u.nm
    assert hmi.plate_scale == 0.504 * u.arcsec and hmi.detector_shape == 4096
    assert hmi.aperture == 14 * u.cm and hmi.seeing_fwhm == 0 * u.arcsec
    for name in ("effective_area", "quantum_efficiency", "gain", "read_noise", "full_well",
                 "exposure_time", "integration_half_width", "quadrature_step"):
        assert isinstance(getattr(hmi, name), u.Quantity)
    assert isinstance(hmi.supersampling, int) and isinstance(hmi.adc_bits, int)
    responses = hmi.responses(hmi.line_wavelength + hmi.tuning_offsets)
    assert responses.unit == u.one and responses.shape == (6, 6)
    # Each filtergram transmits most at its own tuning position.
    np.testing.assert_array_equal(np.argmax(responses.value, axis=1), np.arange(6))


def test_every_field_has_a_source():
    for f in dataclasses.fields(HMIInstrument):
        assert len(HMIInstrument.source(f.name)) > 10
    with pytest.raises(KeyError, match="no parameter"):
        HMIInstrument.source("nope")


def test_tuning_offsets_and_period():
    hmi = HMIInstrument()
    np.testing.assert_allclose(hmi.tuning_offsets.to_value(u.Unit("mAA")),
                               [172.0, 103.2, 34.4, -34.4, -103.2, -172.0])
    assert hmi.tuning_period.to_value(u.Unit("mAA")) == pytest.approx(412.8)
    # Schou et al. 2012: the tuning step is FSR_NB / 2.5.
    assert hmi.tuning_step.to_value(u.Unit("mAA")) == pytest.approx(hmi.nb_fsr.to_value(u.Unit("mAA")) / 2.5)
    assert len(TUNING_INDICES) == 6


def test_analysers_plane_order_and_signs():
    analysers = HMIInstrument().analysers
    assert len(analysers) == N_HMI_PLANES == 12
    for plane, (tuning, sign) in enumerate(analysers):
        assert tuning == plane % 6
        assert sign == (1 if plane < 6 else -1)     # LCP = I+V first, then RCP = I-V


def test_schedule():
    hmi = HMIInstrument()
    assert hmi.frames_per_sequence == 12
    assert hmi.frame_interval * hmi.frames_per_sequence == hmi.sequence_cadence


def test_gauss_per_velocity_from_lande_factor():
    hmi = HMIInstrument()
    # Couvidat et al. 2016: K_m = 1 / (2 × 4.67e-5 λ0[cm] g c[m/s]) with the rounded Zeeman constant.
    rounded = 1 / (2 * 4.67e-5 * 6.1733433e-5 * 2.5 * 299792458.0)
    assert hmi.gauss_per_velocity.to_value(u.G * u.s / u.m) == pytest.approx(rounded, rel=1e-3)
    # K_m scales as 1/g.
    ratio = hmi.replace(lande_g=1.25).gauss_per_velocity / hmi.gauss_per_velocity
    assert ratio.to_value(u.one) == pytest.approx(2)


def test_velocity_per_wavelength():
    hmi = HMIInstrument()
    expected = 299792458.0 / 6173.3433e3          # m/s per mÅ
    assert hmi.velocity_per_wavelength.to_value(u.m / u.s / u.Unit("mAA")) == pytest.approx(expected)


def test_toml_round_trip(tmp_path):
    hmi = HMIInstrument().replace(exposure_time=0.1 * u.s, gain=15.5 * u.electron / u.adu)
    text = hmi.to_toml()
    assert 'name = "hmi"' in text and "Schou et al. 2012" in text
    assert HMIInstrument.from_toml(text) == hmi
    path = tmp_path / "hmi.toml"
    path.write_text(text)
    assert HMIInstrument.from_toml(path) == hmi
    assert HMIInstrument.from_dict(hmi.to_dict()) == hmi
    assert hash(HMIInstrument.from_dict(hmi.to_dict())) == hash(hmi)


def test_replace_and_resolve():
    hmi = HMIInstrument()
    assert hmi.replace(plate_scale=0.5 * u.arcsec).plate_scale == 0.5 * u.arcsec
    assert resolve_hmi(None) == hmi and resolve_hmi(hmi) is hmi
    with pytest.raises(TypeError, match="no parameter"):
        hmi.replace(colour="blue")
    with pytest.raises(TypeError, match="HMIInstrument or None"):
        resolve_hmi("hmi")


@pytest.mark.parametrize("changes, error, match", [
    ({"plate_scale": 0.5}, TypeError, "plate_scale must be an astropy Quantity"),
    ({"plate_scale": 0.5 * u.s}, u.UnitsError, "plate_scale must have units"),
    ({"plate_scale": -0.5 * u.arcsec}, ValueError, r"plate_scale must lie in \(0, inf\) arcsec"),
    ({"nb_contrast": 1.2}, ValueError, r"nb_contrast must lie in \(0, 1\]"),
    ({"detector_shape": 0}, ValueError, r"detector_shape must lie in \[1, inf\)"),
    ({"detector_shape": 2.0}, TypeError, "detector_shape must be a non-negative int"),
    ({"adc_bits": 32}, ValueError, r"adc_bits must lie in \[1, 31\]"),
    ({"read_noise": -1 * u.adu}, ValueError, r"read_noise must lie in \[0, inf\)"),
    ({"quadrature_step": 3 * u.nm}, ValueError, "quadrature_step .* smaller than integration_half_width"),
    ({"lut_velocity_step": 10 * u.km / u.s}, ValueError, "lut_velocity_step .* must be smaller"),
    ({"exposure_time": math.nan * u.s}, ValueError, "finite scalar"),
])
def test_bad_values_are_named(changes, error, match):
    with pytest.raises(error, match=match):
        HMIInstrument(**changes)


def test_from_dict_errors():
    with pytest.raises(KeyError, match="unknown key"):
        HMIInstrument.from_dict({"colour": 1})
    with pytest.raises(ValueError, match="name = 'gong', but HMIInstrument is 'hmi'"):
        HMIInstrument.from_dict({"name": "gong"})
    with pytest.raises(ValueError, match="is not a quantity"):
        HMIInstrument.from_dict({"plate_scale": "wide"})


def test_tiled_default_detector_is_the_instruments():
    """A tiled HMI run without --shape gets 1024² of the CCD; full disk its 4096²; GONG 860 either way."""
    from gongsynth.config import SimulationConfig
    assert HMIInstrument.tiled_detector_shape == 1024 < HMIInstrument().detector_shape == 4096
    assert SimulationConfig(seed=1, instrument="hmi").detector_pixels == 1024
    assert SimulationConfig(seed=1, instrument="hmi", mode="full-disk").detector_pixels == 4096
    assert SimulationConfig(seed=1, instrument="hmi", detector_shape=64).detector_pixels == 64
    assert SimulationConfig(seed=1).detector_pixels == 860
    assert SimulationConfig(seed=1, mode="full-disk").detector_pixels == 860
