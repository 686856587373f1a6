"""
Faults and bad input (issue 12): every mistake caught before computing, an output set complete
or absent, nothing silently wrong.

Each test drives the command line (`gongsynth.cli.main`) or the API through one finding of the
issue, or injects a fault into the writers (an exception, Ctrl-C, a full disk, no permission, a
killed process) and checks that the output folder holds the complete new set or the untouched old
one, with nothing else left behind, and that a rerun works.
"""
import errno
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import astropy.units as u
import numpy as np
import pytest
from astropy.io import fits

import gongsynth.products.output as output
from gongsynth.cli import main
from gongsynth.config import SimulationConfig
from gongsynth.instrument import GONGInstrument
from gongsynth.pipeline import simulate
from gongsynth.products.output import SET_FILES, clean_leftovers, save_result

from .realdata import REAL_DATA, real_file

SMALL = dict(sun="milne-eddington", duration=1 * u.min, detector_shape=16, resolutions=(1,),
             photosphere_shape=(64, 64),
             photosphere_pixel_size=1536 * u.km)


@pytest.fixture(scope="module")
def results():
    """Two small runs with different seeds."""
    return {seed: simulate(seed=seed, progress=False, **SMALL) for seed in (1, 2)}


@pytest.fixture
def small_config(tmp_path):
    path = tmp_path / "small.toml"
    path.write_text(SimulationConfig(seed=1, **SMALL).to_toml())
    return path


def _snapshot(folder):
    """{name: bytes} of every entry of a folder (hidden ones included)."""
    return {p.name: p.read_bytes() for p in sorted(Path(folder).iterdir())}


def _seed_of(folder):
    return SimulationConfig.from_toml(Path(folder) / "config.toml").seed


def _leftovers(parent):
    """Hidden staging folders or .part files anywhere below ``parent``."""
    return [p for p in Path(parent).rglob("*") if p.name.startswith(".") and
            (".gongsynth-" in p.name or ".part" in p.name)]


class _Boom(RuntimeError):
    pass


def _fail_on_write(monkeypatch, number, exc):
    """Make the ``number``-th FITS write of the test raise ``exc``."""
    real = fits.HDUList.writeto
    count = {"n": 0}

    def writeto(self, *args, **kwargs):
        count["n"] += 1
        if count["n"] == number:
            raise exc
        return real(self, *args, **kwargs)

    monkeypatch.setattr(fits.HDUList, "writeto", writeto)


FAULTS = {
    "exception": _Boom("disk controller on fire"),
    "ctrl-c": KeyboardInterrupt(),
    "disk full": OSError(errno.ENOSPC, os.strerror(errno.ENOSPC)),
    "no permission": PermissionError(errno.EACCES, os.strerror(errno.EACCES)),
}


# ----------------------------------------------------------------- #4 atomic output sets
@pytest.mark.parametrize("fault", FAULTS)
def test_a_fault_mid_save_leaves_no_new_folder(results, tmp_path, monkeypatch, fault):
    out = tmp_path / "run"
    _fail_on_write(monkeypatch, 3, FAULTS[fault])
    with pytest.raises(type(FAULTS[fault])):
        save_result(results[1], out)
    assert not out.exists()
    assert _leftovers(tmp_path) == []
    monkeypatch.undo()
    save_result(results[1], out)  # the rerun works
    assert sorted(p.name for p in out.iterdir()) == sorted(SET_FILES)


@pytest.mark.parametrize("fault", FAULTS)
def test_a_fault_mid_overwrite_leaves_the_old_set_untouched(results, tmp_path, monkeypatch, fault):
    out = tmp_path / "run"
    save_result(results[1], out)
    before = _snapshot(out)
    _fail_on_write(monkeypatch, 4, FAULTS[fault])
    with pytest.raises(type(FAULTS[fault])):
        save_result(results[2], out, overwrite=True)
    assert _snapshot(out) == before
    assert _leftovers(tmp_path) == []
    monkeypatch.undo()
    save_result(results[2], out, overwrite=True)
    assert _seed_of(out) == 2


def test_overwrite_replaces_the_whole_set(results, tmp_path):
    out = tmp_path / "run"
    save_result(results[1], out)
    save_result(results[2], out, overwrite=True, quicklook=False)
    names = sorted(p.name for p in out.iterdir())
    assert "quicklook.png" not in names  # the old set's quick-look went with it
    assert _seed_of(out) == 2
    with fits.open(out / "raw.fits") as hdul:
        assert int(hdul[0].header["SEED"]) == 2


def test_an_existing_set_is_refused_without_overwrite(results, tmp_path):
    out = tmp_path / "run"
    save_result(results[1], out)
    before = _snapshot(out)
    with pytest.raises(FileExistsError, match="refusing to overwrite"):
        save_result(results[2], out)
    assert _snapshot(out) == before


def test_a_folder_with_other_files_keeps_them(results, tmp_path, monkeypatch):
    out = tmp_path / "project"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    _fail_on_write(monkeypatch, 2, KeyboardInterrupt())
    with pytest.raises(KeyboardInterrupt):
        save_result(results[1], out)
    assert _snapshot(out) == {"notes.txt": b"mine"}
    monkeypatch.undo()
    save_result(results[1], out)
    assert sorted(p.name for p in out.iterdir()) == sorted([*SET_FILES, "notes.txt"])
    assert _leftovers(tmp_path) == []


def test_a_killed_save_is_cleaned_by_the_next_one(tmp_path):
    """SIGKILL in the middle of the writes: a staging folder stays behind; the next save removes it."""
    out = tmp_path / "run"
    script = textwrap.dedent(f"""
        import os, signal
        import astropy.units as u
        from astropy.io import fits
        from gongsynth.pipeline import simulate
        result = simulate(seed=1, sun="milne-eddington", progress=False, duration=1 * u.min,
                          detector_shape=16,
                          resolutions=(1,), photosphere_shape=(64, 64),
                          photosphere_pixel_size=1536 * u.km)
        real, count = fits.HDUList.writeto, [0]
        def writeto(self, *args, **kwargs):
            count[0] += 1
            if count[0] == 3:
                os.kill(os.getpid(), signal.SIGKILL)
            return real(self, *args, **kwargs)
        fits.HDUList.writeto = writeto
        result.save({str(out)!r})
    """)
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert run.returncode == -signal.SIGKILL, run.stderr
    assert not out.exists()
    stale = _leftovers(tmp_path)
    assert len(stale) == 1 and stale[0].name.startswith(".run.gongsynth-")
    assert main(["simulate", "--quiet", "--out", str(out)] + _small_flags(tmp_path)) == 0
    assert _leftovers(tmp_path) == []
    assert sorted(p.name for p in out.iterdir()) == sorted(SET_FILES)


def _small_flags(tmp_path):
    """--config with the small photosphere (the command line has no flag for it)."""
    path = tmp_path / "photosphere.toml"
    cfg = SimulationConfig(seed=1, **SMALL)
    path.write_text(cfg.to_toml())
    return ["--config", str(path)]


def test_stale_part_files_and_interrupted_moves_are_finished(results, tmp_path):
    out = tmp_path / "run"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    (out / ".raw.fits.k2j3h4g5.part.fits").write_bytes(b"")  # an earlier version's killed write
    # A save killed while moving its finished files into a shared folder (a process that is gone).
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True).stdout.strip()
    stage = out / f".gongsynth-{output._host()}-{dead}-abc123.tmp"
    stage.mkdir()
    save_result(results[2], stage / "inner", quicklook=False)  # a complete set to move
    for path in (stage / "inner").iterdir():
        path.rename(stage / path.name)
    (stage / "inner").rmdir()
    (stage / "COMMITTING").write_text("\n".join(p.name for p in stage.iterdir()) + "\n")
    handled = clean_leftovers(out)
    assert {p.name for p in handled} == {stage.name, ".raw.fits.k2j3h4g5.part.fits"}
    assert _seed_of(out) == 2 and (out / "notes.txt").read_text() == "mine"
    assert _leftovers(tmp_path) == []


def test_a_live_process_staging_folder_is_left_alone(tmp_path):
    out = tmp_path / "run"
    live = tmp_path / f".run.gongsynth-{output._host()}-{os.getppid()}-xyz.tmp"
    live.mkdir()
    assert clean_leftovers(out) == [] and live.exists()


# ----------------------------------------------------------------- the CLI's messages
@pytest.mark.parametrize(("fault", "code", "words"), [
    ("ctrl-c", 130, "interrupted"),
    ("disk full", 1, "No space left on device"),
    ("no permission", 2, "Permission denied"),
])
def test_cli_faults_mid_save(tmp_path, monkeypatch, capsys, small_config, fault, code, words):
    out = tmp_path / "run"
    assert main(["simulate", "--config", str(small_config), "--quiet", "--out", str(out)]) == 0
    before = _snapshot(out)
    _fail_on_write(monkeypatch, 2, FAULTS[fault])
    argv = ["simulate", "--config", str(small_config), "--seed", "2", "--overwrite", "--quiet",
            "--out", str(out)]
    assert main(argv) == code
    err = capsys.readouterr().err
    assert words in err and f"{out} was left as it was before this run (no partial set)" in err
    assert _snapshot(out) == before and _leftovers(tmp_path) == []
    monkeypatch.undo()
    assert main(argv) == 0 and _seed_of(out) == 2


def test_cli_refuses_before_computing(tmp_path, capsys, small_config, monkeypatch):
    afile = tmp_path / "afile"
    afile.write_text("")
    cases = [
        (["--out", str(afile)], 2, "is a file, not a folder"),
        (["--duration", "nan", "--out", str(tmp_path / "a")], 2, "not finite"),
        (["--duration", "0.001", "--out", str(tmp_path / "b")], 2, "whole number"),
        (["--shape", "100000", "--out", str(tmp_path / "c")], 4, "of memory but"),
        (["--latitude", "10.0001", "10.0002", "--out", str(tmp_path / "d")], 2, "share an output folder"),
    ]
    calls = []
    monkeypatch.setattr("gongsynth.pipeline.build_chain", lambda *a, **k: calls.append(a))
    for args, code, words in cases:
        if code == 2 and "nan" in args:
            with pytest.raises(SystemExit) as info:
                main(["simulate", *args])
            assert info.value.code == 2
        else:
            assert main(["simulate", "--config", str(small_config), *args]) == code, args
        assert words in capsys.readouterr().err
    assert calls == []  # nothing was computed


def test_cli_refuses_a_full_disk_before_computing(tmp_path, capsys, small_config, monkeypatch):
    import shutil

    monkeypatch.setattr(shutil, "disk_usage", lambda path: shutil._ntuple_diskusage(10**9, 10**9, 1000))
    assert main(["simulate", "--config", str(small_config), "--out", str(tmp_path / "r")]) == 4
    assert "of disk space but" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="root ignores file permissions")
def test_cli_read_only_folder(tmp_path, capsys, small_config):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        assert main(["simulate", "--config", str(small_config), "--out", str(folder / "run")]) == 2
        assert "permission denied" in capsys.readouterr().err
        assert list(folder.iterdir()) == []
    finally:
        folder.chmod(0o755)


def test_cli_read_only_folder_as_any_user(tmp_path, capsys, small_config, monkeypatch):
    """The early check, with os.access saying what a non-root user would hear."""
    folder = tmp_path / "ro"
    folder.mkdir()
    real = os.access
    monkeypatch.setattr(os, "access", lambda p, mode: False if Path(p) == folder else real(p, mode))
    assert main(["simulate", "--config", str(small_config), "--out", str(folder / "run")]) == 2
    assert "cannot write in" in capsys.readouterr().err


# ----------------------------------------------------------------- #8 instrument ranges
@pytest.mark.parametrize(("line", "words"), [
    ('seeing_fwhm = "-3 arcsec"', "GONGInstrument.seeing_fwhm must lie in [0, inf) arcsec"),
    ("quantum_efficiency = 1.6", "GONGInstrument.quantum_efficiency must lie in (0, 1]"),
    ('frame_rate = "0 Hz"', "GONGInstrument.frame_rate must lie in (0, inf) Hz"),
    ("truncate_bits = 40", "GONGInstrument.truncate_bits must lie in [0, 31]"),
])
def test_impossible_instrument_values_are_refused(tmp_path, capsys, line, words):
    path = tmp_path / "bad.toml"
    path.write_text(f"[instrument]\n{line}\n")
    assert main(["simulate", "--config", str(path), "--out", str(tmp_path / "o")]) == 2
    assert words in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_every_instrument_field_has_a_range():
    import dataclasses

    from gongsynth.instrument import _RANGES

    numeric = {f.name for f in dataclasses.fields(GONGInstrument)
               if f.name not in ("prefilter_form", "image_interpolant", "seeing_profile")}
    angles = {"lyot_angle_1", "lyot_angle_2", "lyot_angle_3", "michelson_angle",
              "image_rotation_angle"}  # any angle is valid
    assert numeric - angles - {"detector_map_seed"} == set(_RANGES)
    GONGInstrument(detector_shape=np.int64(32), supersampling=np.int32(3))  # numpy ints are ints


# ----------------------------------------------------------------- #9 messages
def test_compare_figure_without_suffix_is_a_png_and_bad_suffixes_are_refused_first(tmp_path, capsys):
    from gongsynth.geometry import field_centre
    from gongsynth.products.maps import make_product_map

    rng = np.random.default_rng(2)
    for name in ("a.fits", "b.fits"):
        make_product_map(rng.normal(0, 3, (200, 200)) * u.G, centre=field_centre(0 * u.deg)[0],
                         scale=2.5 * u.arcsec, product="magnetogram").save(tmp_path / name)
    a, b = str(tmp_path / "a.fits"), str(tmp_path / "b.fits")
    assert main(["compare", a, b, "--out", str(tmp_path / "figure")]) == 0
    assert (tmp_path / "figure").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    capsys.readouterr()
    assert main(["compare", a, b, "--out", str(tmp_path / "figure.xyz")]) == 2
    assert "cannot write a figure as .xyz" in capsys.readouterr().err
    assert main(["compare", a, b, "--out", str(tmp_path)]) == 2
    assert "is a folder" in capsys.readouterr().err
    assert _leftovers(tmp_path) == []


def test_a_truncated_fits_file_is_named_and_called_truncated(tmp_path, capsys):
    from gongsynth.geometry import field_centre
    from gongsynth.products.maps import make_product_map

    whole = tmp_path / "whole.fits"
    noise = np.random.default_rng(3).normal(0, 3, (300, 300)) * u.G
    make_product_map(noise, centre=field_centre(0 * u.deg)[0], scale=2.5 * u.arcsec,
                     product="magnetogram").save(whole)
    cut = tmp_path / "cut.fits"
    cut.write_bytes(whole.read_bytes()[: whole.stat().st_size // 2])
    assert main(["compare", str(whole), str(cut), "--out", str(tmp_path / "c.png")]) == 2
    err = capsys.readouterr().err
    assert f"{cut}: the image data cannot be read, the file is probably truncated" in err
    assert not (tmp_path / "c.png").exists()


def test_shape_zero_names_the_flag(capsys):
    with pytest.raises(SystemExit) as info:
        main(["simulate", "--shape", "0", "--out", "x"])
    assert info.value.code == 2
    assert "argument --shape: must be at least 8, got 0" in capsys.readouterr().err


def test_numpy_ints_and_config_paths():
    assert SimulationConfig(detector_shape=np.int64(32)).detector_shape == 32
    with pytest.raises(FileNotFoundError, match="run.cfg"):
        SimulationConfig.from_toml("run.cfg")


# ----------------------------------------------------------------- #1 compare with every real file
REAL_FILES = (sorted(str(p.relative_to(REAL_DATA)) for p in REAL_DATA.glob("*/*"))
              if REAL_DATA.is_dir() else [])
#: What each real file that is not a single magnetogram is, in the words the error must use.
NOT_A_MAGNETOGRAM = {
    "gong/adapt40311_03k012_201707200800_i00015600n1.fts.gz": "the ADAPT model's 12 realisations",
    "gong/bbiqa090905t1854.fits.gz": "is not a magnetogram: BUNIT = '(none)', CONTENT = '(none)', "
                                     "IMTYPE = 'INTENSITY'",
    "gong/bbzqa240209t1734_dim-860.jpg": "is not a readable FITS file",
    "hinode/FGMG4_20110214_030443.7.fits": "OBS_TYPE = 'FG MG4 V/I'",
    "hinode/HinodeSOT.fits": "OBS_TYPE 'SP IQUV 4D array'",
    "hinode/hinode4d.20130912.sample.fits": "4-D array",
    "hmi/2023_01_31__03_39_23_200__SDO_HMI_HMI_continuum.jp2": "is not a readable FITS file",
    "mdi/mdi.fd_ic.20101015_230100_TAI.data.fits": "is not a magnetogram: BUNIT = 'Arbitrary intensity",
}


@pytest.fixture(scope="module")
def simulated_magnetogram(tmp_path_factory):
    result = simulate(seed=1, sun="milne-eddington", progress=False, duration=1 * u.min, detector_shape=96,
                      resolutions=(1,), photosphere_shape=(128, 128), photosphere_pixel_size=1536 * u.km)
    path = tmp_path_factory.mktemp("sim") / "magnetogram.fits"
    result.magnetogram.save(path)
    return path


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore::gongsynth.analysis.observations.BadHeaderWarning")
@pytest.mark.parametrize("relpath", REAL_FILES or ["(no real data)"])
def test_compare_with_every_real_file(relpath, simulated_magnetogram, tmp_path, capsys):
    if relpath.endswith(".md") or relpath.startswith("models/"):
        pytest.skip("not an observation (provenance notes, model atmospheres)")
    path = real_file(relpath)
    figure = tmp_path / "compare.png" if relpath.startswith("hmi/") else None
    code = main(["compare", str(simulated_magnetogram), str(path)]
                + (["--out", str(figure)] if figure else []))
    err = capsys.readouterr().err
    if relpath in NOT_A_MAGNETOGRAM:
        assert code == 2 and NOT_A_MAGNETOGRAM[relpath] in err, err
    else:
        assert code == 0, err
        if figure is not None:
            assert figure.stat().st_size > 10_000
