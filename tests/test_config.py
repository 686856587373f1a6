import astropy.units as u
import pytest

from gongsynth import GONGInstrument
from gongsynth.config import Effects, SimulationConfig


def test_default_round_trip_with_comments():
    cfg = SimulationConfig(seed=11, detector_shape=128, latitude=60 * u.deg)
    text = cfg.to_toml()
    assert "# heliographic latitude" in text and "[instrument]" in text
    assert SimulationConfig.from_toml(text) == cfg


def test_round_trip_of_modified_instrument(tmp_path):
    cfg = SimulationConfig(seed=2, instrument=GONGInstrument(seeing_fwhm=1.7 * u.arcsec))
    path = tmp_path / "run.toml"
    path.write_text(cfg.to_toml(comments=False))
    assert SimulationConfig.from_toml(path) == cfg


def test_partial_file_uses_defaults():
    cfg = SimulationConfig.from_toml('[simulation]\nlatitude = "45 deg"\nengine = "frames"\n')
    assert cfg.latitude == 45 * u.deg and cfg.engine == "frames"
    assert cfg.instrument == GONGInstrument()


@pytest.mark.parametrize("text, error, match", [
    ('[simulation]\nlatitud = "45 deg"\n', KeyError, "latitud"),
    ('[simulaton]\nlatitude = "45 deg"\n', KeyError, "simulaton"),
    ('[simulation]\nlatitude = 45\n', u.UnitsError, "latitude"),
    ('[simulation]\nduration = "10 km"\n', u.UnitsError, "duration"),
    ('[simulation]\nlatitude = "95 deg"\n', ValueError, "latitude"),
    ('[simulation]\nengine = "photons"\n', ValueError, "engine"),
    ('[instrument]\ngain = "33 km"\n', u.UnitsError, "gain"),
    ('[instrument]\ngian = 33\n', KeyError, "gian"),
])
def test_bad_config_names_the_key(text, error, match):
    with pytest.raises(error, match=match):
        SimulationConfig.from_toml(text)


def test_seed_none_is_recorded():
    a = SimulationConfig.from_arguments(seed=None)
    b = SimulationConfig.from_arguments(seed=None)
    assert isinstance(a.seed, int) and 0 <= a.seed < 2**63
    assert a.seed != b.seed
    assert SimulationConfig.from_arguments(seed=5).seed == 5


def test_strings_with_newlines_and_quotes_are_valid_toml():
    cfg = SimulationConfig(flat_file='odd "name"\nwith a newline', flat_sha256="0" * 64)
    assert SimulationConfig.from_toml(cfg.to_toml()) == cfg


def test_effects_round_trip_and_unknown_effect():
    cfg = SimulationConfig(effects=Effects(photon_noise=False, dither=False))
    assert SimulationConfig.from_toml(cfg.to_toml()).effects.off == ("photon_noise", "dither")
    with pytest.raises(KeyError, match="photon_nois"):
        SimulationConfig.from_toml('[effects]\nphoton_nois = false\n')
    with pytest.raises(TypeError, match="effects.psf"):
        SimulationConfig.from_toml('[effects]\npsf = "no"\n')


def test_flat_record_needs_both_path_and_digest():
    with pytest.raises(ValueError, match="flat_sha256"):
        SimulationConfig(flat_file="flat.fits")
