import subprocess
import sys

import numpy as np
import pytest

from gongsynth.cli import main
from gongsynth.config import SimulationConfig


def test_print_defaults_is_a_complete_valid_config(capsys):
    assert main(["config", "--print-defaults"]) == 0
    text = capsys.readouterr().out
    assert "[simulation]" in text and "[instrument]" in text and "# " in text
    first, second = SimulationConfig.from_toml(text), SimulationConfig.from_toml(text)
    assert first == SimulationConfig().replace(seed=first.seed)
    # The printed defaults leave the seed unset, as --help says: every run draws its own.
    assert first.seed != second.seed
    assert "\nseed =" not in text


def test_console_script_runs_main_then_freezes_the_garbage_collector(monkeypatch, capsys):
    """The ``gongsynth`` command's entry point (pyproject) returns `main`'s code and freezes the objects
    out of the garbage collector's passes (before the run and before the exit); `main` itself, called in
    a process that goes on, does not."""
    import gc
    import tomllib
    from pathlib import Path

    from gongsynth.cli import run_command

    scripts = tomllib.loads((Path(__file__).parents[1] / "pyproject.toml").read_text())["project"]["scripts"]
    assert scripts["gongsynth"] == "gongsynth.cli:run_command"
    gc.unfreeze()
    assert main(["config", "--print-defaults"]) == 0
    assert gc.get_freeze_count() == 0
    monkeypatch.setattr(sys, "argv", ["gongsynth", "config", "--print-defaults"])
    try:
        code = run_command()
        frozen = gc.get_freeze_count()
    finally:
        gc.unfreeze()
    assert code == 0
    assert frozen > 0
    assert "[simulation]" in capsys.readouterr().out


def test_bad_config_key_exits_2_and_names_it(tmp_path, capsys):
    path = tmp_path / "run.toml"
    path.write_text('[simulation]\nlatitud = "30 deg"\n')
    assert main(["simulate", "--config", str(path), "--out", str(tmp_path / "out")]) == 2
    assert "latitud" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_missing_config_file_exits_2(tmp_path, capsys):
    assert main(["simulate", "--config", str(tmp_path / "nope.toml"), "--out", str(tmp_path)]) == 2
    assert "nope.toml" in capsys.readouterr().err


def test_out_of_range_latitude_exits_2(tmp_path, capsys):
    assert main(["simulate", "--latitude", "95", "--out", str(tmp_path / "o")]) == 2
    assert "latitude" in capsys.readouterr().err


def test_unknown_instrument_exits_2_and_lists_the_known(tmp_path, capsys):
    assert main(["simulate", "--instrument", "spectroheliograph", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "spectroheliograph" in err and "'gong'" in err


def test_usage_errors_exit_2():
    with pytest.raises(SystemExit) as info:
        main(["simulate"])  # --out is required
    assert info.value.code == 2


def test_console_script_runs():
    out = subprocess.run([sys.executable, "-m", "gongsynth.cli", "--version"], capture_output=True,
                         text=True, check=True)
    assert out.stdout.startswith("gongsynth ")


def test_effect_switches_and_obstime_reach_the_saved_config(tmp_path):
    import astropy.units as u

    cfg = SimulationConfig(seed=1, sun="milne-eddington", detector_shape=16, resolutions=(1,),
                           duration=1 * u.min, photosphere_shape=(64, 64), photosphere_pixel_size=1536 * u.km)
    path = tmp_path / "run.toml"
    path.write_text(cfg.to_toml())
    out = tmp_path / "o"
    assert main(["simulate", "--config", str(path), "--no-photon-noise", "--no-read-noise",
                 "--obstime", "2009-09-05T18:54:00", "--instrument", "gong", "--out", str(out),
                 "--quiet"]) == 0
    assert '[instrument]\n# the instrument (gongsynth.instruments.get)\nname = "gong"' in (
        out / "config.toml").read_text()
    saved = SimulationConfig.from_toml(out / "config.toml")
    assert saved.effects.off == ("photon_noise", "read_noise")
    assert saved.obstime.startswith("2009-09-05T18:54")
    assert saved.replace(effects=cfg.effects, obstime=cfg.obstime) == cfg


def test_calibrate_a_real_synoptic_map(tmp_path, capsys):
    import numpy as np
    import sunpy.map

    from .realdata import real_file

    source = real_file("gong/mrbqs221029t0304c2263_067.fits")
    out = tmp_path / "calibrated.fits"
    assert main(["calibrate", str(source), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "unsigned flux, calibrated / measured" in printed
    calibrated, original = sunpy.map.Map(out), sunpy.map.Map(source)
    assert calibrated.data.shape == original.data.shape and calibrated.unit == original.unit
    assert calibrated.meta["caltable"].endswith("calibration_default.ecsv")
    both = np.isfinite(calibrated.data) & np.isfinite(original.data)
    # The table's factors lie within 0.9-1.35: the flux changes, but boundedly.
    ratio = np.abs(calibrated.data[both]).sum() / np.abs(original.data[both]).sum()
    assert 0.9 < ratio < 1.35 and ratio != 1
    # Refuses to overwrite; a missing input is a usage error.
    assert main(["calibrate", str(source), "--out", str(out)]) == 3
    assert main(["calibrate", str(tmp_path / "none.fits"), "--out", str(tmp_path / "x.fits")]) == 2


def test_a_muram_snapshot_as_the_input_sun(tmp_path, capsys):
    # The genuine MURaM test snapshot (6 Mm box) through LTE radiative transfer and the instrument.
    from gongsynth.config import SimulationConfig as Config

    from .realdata import REAL_DATA

    muram = REAL_DATA.parent / "mhd" / "muram-test3d-it000000"
    if not muram.is_dir():
        pytest.skip(f"MURaM snapshot not found at {muram}")
    out = tmp_path / "muram"
    code = main(["simulate", "--atmosphere", str(muram), "--shape", "16", "--duration", "1", "--seed", "3",
                 "--quiet", "--out", str(out)])
    assert code == 0
    saved = Config.from_toml(out / "config.toml")
    assert saved.seed == 3 and saved.atmosphere_file == str(muram)
    import sunpy.map

    magnetogram = sunpy.map.Map(out / "magnetogram.fits")
    truth = sunpy.map.Map(out / "truth.fits")
    assert magnetogram.data.shape == (16, 16)
    # A quiet-Sun snapshot (net 10 G, |B| up to ~1 kG): finite maps and a truth within that range.
    assert np.isfinite(magnetogram.data).any() and np.nanmax(np.abs(truth.data)) < 1500
    # The saved configuration alone repeats the run: the atmosphere is read from the recorded path.
    config = str(out / "config.toml")
    assert main(["simulate", "--config", config, "--quiet", "--out", str(tmp_path / "again")]) == 0
    again = sunpy.map.Map(tmp_path / "again" / "magnetogram.fits")
    assert np.array_equal(again.data, magnetogram.data, equal_nan=True)
    assert main(["simulate", "--atmosphere", str(tmp_path / "none.h5"), "--out", str(tmp_path / "x")]) == 2


def test_date_site_and_like_flags(tmp_path, capsys):
    import astropy.units as u

    from gongsynth.cli import build_parser

    from .realdata import real_file

    args = build_parser().parse_args(["simulate", "--date", "2014-04-01T12:00", "--out", "o"])
    assert args.obstime == "2014-04-01T12:00"  # --date is --obstime
    args = build_parser().parse_args(["simulate", "--mode", "full-disk", "--surface-field", "synthetic",
                                      "--out", "o"])
    assert args.surface_field == "synthetic"
    assert main(["simulate", "--site", "XX", "--out", str(tmp_path / "bad")]) == 2
    assert "site" in capsys.readouterr().err and not (tmp_path / "bad").exists()
    # "What GONG saw at Big Bear on 2009-09-05 18:54": the saved run records the file, its date,
    # site and plate scale; --site still wins over the file.
    cfg = SimulationConfig(seed=1, detector_shape=16, resolutions=(1,), duration=1 * u.min,
                           photosphere_shape=(64, 64), photosphere_pixel_size=1536 * u.km)
    path = tmp_path / "run.toml"
    path.write_text(cfg.to_toml())
    big_bear = real_file("gong/bbbqa090905t1854.fits.gz")
    out = tmp_path / "o"
    assert main(["simulate", "--config", str(path), "--like", str(big_bear), "--site", "ml",
                 "--out", str(out), "--quiet"]) == 0
    saved = SimulationConfig.from_toml(out / "config.toml")
    assert saved.like == str(big_bear) and saved.site == "ML"
    assert saved.obstime.startswith("2009-09-05T18:54:16")
    assert abs(saved.instrument.plate_scale.to_value(u.arcsec) - 2.5613) < 1e-3
