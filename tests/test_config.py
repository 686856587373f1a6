import inspect

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


def test_the_built_in_sun_and_its_defaults():
    """Shape and spacing default to the chosen Sun's builder; a change of Sun moves them along; the
    default Sun is the 3-D model in both modes, and a chosen Sun stays when the mode changes."""
    from gongsynth.suns import RUN_GRIDS, SUNS, photosphere_defaults
    default = SimulationConfig(seed=1)
    assert default.sun == "model-atmosphere"
    me = default.replace(sun="milne-eddington")
    assert me.sun == "milne-eddington" and me.photosphere_shape == (1024, 1024)
    assert me.replace(sun="model-atmosphere") == default
    disk = default.replace(mode="full-disk")
    assert disk.sun == "model-atmosphere" and disk.photosphere_shape == (256, 256)
    assert disk.replace(mode="tiled") == default
    assert SimulationConfig(seed=1, mode="full-disk") == disk
    assert SimulationConfig.from_toml(disk.to_toml()) == disk
    # The Milne-Eddington toy over the full disk is a choice; it stays through a change of mode.
    chosen = SimulationConfig(sun="milne-eddington", mode="full-disk")
    assert chosen.replace(mode="tiled").sun == "milne-eddington"
    atm = me.replace(sun="model-atmosphere")
    assert atm.photosphere_shape == RUN_GRIDS["model-atmosphere"]["shape"] == (256, 256)
    assert atm.photosphere_pixel_size == RUN_GRIDS["model-atmosphere"]["pixel_size"]
    # 98 Mm: the builder's own default box (1024 columns of 96 km), at a quarter of the resolution.
    signature = inspect.signature(SUNS["model-atmosphere"]).parameters
    box = [n * signature["pixel_size"].default for n in signature["shape"].default]
    assert u.allclose([n * atm.photosphere_pixel_size for n in atm.photosphere_shape], box)
    assert atm.replace(sun="milne-eddington") == me
    kept = me.replace(photosphere_shape=(128, 128)).replace(sun="model-atmosphere")
    assert kept.photosphere_shape == (128, 128)             # a shape the user chose stays
    assert SimulationConfig.from_toml(atm.to_toml()) == atm  # height_range etc. round trip
    assert "element_field" in photosphere_defaults("model-atmosphere")


def test_the_full_disk_follows_the_synthetic_sun_by_default():
    """A full-disk run's large-scale field is the synthetic Sun of its date unless told otherwise; the
    default follows the mode, a choice stays, and tiled runs have none."""
    disk = SimulationConfig(seed=1, mode="full-disk")
    assert disk.surface_field == "synthetic"
    assert SimulationConfig.from_toml(disk.to_toml()) == disk
    assert disk.replace(mode="tiled").surface_field is None
    assert disk.replace(mode="tiled").replace(mode="full-disk") == disk
    quiet = disk.replace(surface_field="quiet")
    assert quiet.replace(seed=2).surface_field == "quiet"
    with pytest.raises(ValueError, match="surface_field"):
        quiet.replace(mode="tiled")      # a field the user chose does not silently vanish


def test_knobs_belong_to_the_chosen_sun():
    with pytest.raises(KeyError, match="for sun = 'model-atmosphere'"):
        SimulationConfig(sun="model-atmosphere", photosphere={"umbra_radius_km": 1})
    with pytest.raises(KeyError, match="height_range"):
        SimulationConfig(sun="milne-eddington", photosphere={"height_range": ["-500 km", "600 km"]})
    cfg = SimulationConfig(sun="model-atmosphere", photosphere={"spot": False, "element_field": "1.3 kG",
                                                                "height_range": ["-500 km", "600 km"]})
    assert cfg.photosphere["element_field"] == 1.3 * u.kG
    assert SimulationConfig.from_toml(cfg.to_toml()) == cfg
    with pytest.raises(ValueError, match="sun must be one of"):
        SimulationConfig(sun="muram")
    # The 3-D Sun over the full disk: its knobs are the builder's, its grid the run's default for it.
    disk = SimulationConfig(sun="model-atmosphere", mode="full-disk", photosphere={"nz": 40})
    assert disk.sun_arguments()["nz"] == 40 and SimulationConfig.from_toml(disk.to_toml()) == disk


def test_network_chain_length_reaches_the_network_and_the_header():
    from gongsynth.chain import _network, run_header
    from gongsynth.sun.surface_field.network import CHAIN_LENGTH

    chained = SimulationConfig(mode="full-disk", network_chain_length=4 * u.Mm)
    assert SimulationConfig.from_toml(chained.to_toml()).network_chain_length == 4 * u.Mm
    assert _network(chained).chain_length == 4 * u.Mm
    assert run_header(chained)["netchain"][0] == pytest.approx(4.0)
    default = SimulationConfig(mode="full-disk")
    assert _network(default).chain_length == CHAIN_LENGTH == 3 * u.Mm    # the value measured on real maps
    assert run_header(default)["netchain"][0] == pytest.approx(3.0)
    points = SimulationConfig(mode="full-disk", network_chain_length=0 * u.Mm)
    assert run_header(points)["netchain"][0] == 0                    # recorded when off, too
    assert "netchain" not in run_header(SimulationConfig(mode="full-disk", network=False))
    assert "netchain" not in run_header(SimulationConfig(mode="tiled"))
    with pytest.raises(ValueError, match="network_chain_length"):
        SimulationConfig(mode="full-disk", network_chain_length=-1 * u.Mm)
    with pytest.raises(u.UnitsError, match="network_chain_length"):
        SimulationConfig(mode="full-disk", network_chain_length=3 * u.s)
