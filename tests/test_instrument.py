import math

import astropy.units as u
import pytest

from gongsynth import GONGInstrument


def test_defaults_are_the_papers_values():
    gong = GONGInstrument()
    assert gong.line_wavelength == 676.78 * u.nm
    assert gong.michelson_fsr == 0.305 * u.AA
    assert gong.lyot_delta_h == 608 * u.um
    assert gong.effective_area == 0.6 * u.cm**2
    assert gong.gain == 33 * u.electron / u.adu
    assert gong.read_noise == 4.8 * u.adu
    assert gong.waveplate_step == 30 * u.deg
    assert gong.frames_per_sector_cycle == 3


def test_v0_from_fsr_matches_paper():
    gong = GONGInstrument()
    # The paper's 2151.86 m/s/rad used c = 3e8 m/s; with the exact c it must agree to < 0.1 %.
    assert abs(gong.v0_from_fsr / gong.v0 - 1) < 1e-3
    c_paper = 3e8
    v0_paper_c = c_paper * 0.305e-10 / (2 * math.pi * 676.78e-9)
    assert abs(v0_paper_c / 2151.86 - 1) < 1e-4


def test_gauss_per_velocity():
    gong = GONGInstrument()
    k = gong.gauss_per_velocity.to_value(u.G / (u.m / u.s))
    assert abs(k / 0.7038 - 1) < 1e-3
    # Scales as 1/(g lambda0): computed, not hard-coded.
    k2 = gong.replace(lande_g=1.426).gauss_per_velocity.to_value(u.G / (u.m / u.s))
    assert k2 == pytest.approx(k * 1.5 / 1.426, rel=1e-12)
    # Cross-check with the Zeeman shift 4.67e-13 g lambda0^2 B (A, G): 0.03205 A per kG.
    shift_per_kG = 1000 / k * 676.78e-9 / 2.99792458e8 * 1e10  # A per kG of the velocity shift
    assert shift_per_kG == pytest.approx(4.6686e-13 * 1.5 * 6767.8**2 * 1000, rel=2e-3)


def test_toml_round_trip_is_exact():
    gong = GONGInstrument().replace(seeing_fwhm=2.0 / 3.0 * u.arcsec, prefilter_form="ideal",
                                    lande_g=1.43)
    again = GONGInstrument.from_toml(gong.to_toml())
    assert again == gong
    assert again.seeing_fwhm.value == 2.0 / 3.0  # bit for bit


def test_toml_file(tmp_path):
    path = tmp_path / "gong.toml"
    path.write_text('[instrument]\nseeing_fwhm = "2 arcsec"\nquantum_efficiency = 0.2\n')
    gong = GONGInstrument.from_toml(path)
    assert gong.seeing_fwhm == 2 * u.arcsec
    assert gong.quantum_efficiency == 0.2


def test_unknown_key_is_named():
    with pytest.raises(KeyError, match="seeing_fwmh"):
        GONGInstrument.from_toml('seeing_fwmh = "2 arcsec"')


def test_wrong_units_are_named():
    with pytest.raises(u.UnitsError, match="seeing_fwhm"):
        GONGInstrument(seeing_fwhm=3.6 * u.km)
    with pytest.raises(TypeError, match="aperture"):
        GONGInstrument(aperture=2.8)
    with pytest.raises(ValueError, match="plate_scale"):
        GONGInstrument.from_toml('plate_scale = "two arcsec"')
    with pytest.raises(ValueError, match="prefilter_form"):
        GONGInstrument(prefilter_form="gaussian")
    with pytest.raises(TypeError, match="dither_interval"):
        GONGInstrument(dither_interval=12.5)
    with pytest.raises(TypeError, match="no parameter"):
        GONGInstrument().replace(focal_length=1 * u.m)


def test_frozen_and_hashable():
    gong = GONGInstrument()
    with pytest.raises(AttributeError):
        gong.gain = 10 * u.electron / u.adu
    assert hash(gong) == hash(GONGInstrument())
    assert gong != gong.replace(gain=30 * u.electron / u.adu)
