"""
Faults round 3 (issue 28): a segfault, inputs used without checks, caches trusted blindly, sweeps
that lost finished work, and errors that came after the computing.

One section per finding of the issue; each drives the command line (`gongsynth.cli.main`) where the
finding is the command line's, with the smallest runs that show it.
"""
import math
import re

import astropy.units as u
import numpy as np
import pytest

from gongsynth.cli import main
from gongsynth.sun.atmosphere import Atmosphere


def _column(nx=2, **fields):
    """
    A small photosphere, nx × 1 columns: T falls from 6500 K to 4500 K over 1.3 Mm, the pressure
    with a 130 km scale height from 1.2e5 dyn cm⁻² at z = 0 (roughly VAL-C's τ₅₀₀ = 1; built by hand,
    not hydrostatically, to stay fast).
    """
    z = np.linspace(-300.0, 1000.0, 40)
    t = 6500.0 - 2000.0 * (z + 300.0) / 1300.0
    p = 1.2e5 * np.exp(-z / 130.0)
    col = np.ones((1, 1, nx))
    return dict(temperature=t[:, None, None] * col, z=z, pixel_size=96.0,
                gas_pressure=p[:, None, None] * col, **fields)


# ----------------------------------------------------------------- 1 the segfault
@pytest.mark.parametrize(("name", "value", "words"), [
    ("velocity", 1e5, "velocity reaches 1e+05 km / s"),
    ("velocity", np.nan, "velocity contains non-finite"),
    ("magnetic_field", 1e6, "magnetic_field reaches 1e+06 G"),
    ("microturbulence", 500.0, "microturbulence reaches 500 km / s"),
])
def test_atmosphere_fields_out_of_physical_range_are_refused(name, value, words):
    nz = 40
    shape = (3, nz, 1, 2) if name != "microturbulence" else (nz, 1, 2)
    values = np.zeros(shape)
    values[-1] = value
    arrays = _column(**{name: values})
    with pytest.raises(ValueError, match=re.escape(words)):
        Atmosphere._from_arrays(arrays)


def test_cli_extreme_velocity_atmosphere_exits_2_naming_it(tmp_path, capsys):
    """The audit's case: v_z = 1e5 km/s everywhere crashed the transfer (exit 139)."""
    from gongsynth.sun import atmosphere_files

    arrays = _column(velocity=np.zeros((3, 40, 1, 2)))
    arrays["velocity"][2] = 1e5
    path = tmp_path / "v.h5"
    fields = {k: (None if arrays.get(k) is None else np.asarray(arrays[k], dtype=np.float32))
              for k in ("temperature", "gas_pressure", "density", "electron_density", "velocity",
                        "magnetic_field", "microturbulence")}
    atmosphere_files.write_hdf5(path, fields, arrays["z"], 96.0)
    code = main(["simulate", "--atmosphere", str(path), "--shape", "16", "--duration", "1", "--seed", "1",
                 "--quiet", "--out", str(tmp_path / "x")])
    err = capsys.readouterr().err
    assert code == 2 and "--atmosphere" in err and "velocity reaches" in err
    assert not (tmp_path / "x").exists()


def _kernel_inputs(ncol, velocity_cm_s, field_g):
    from gongsynth.sun.rt.atomic_data import NiLineData
    from gongsynth.sun.rt.eos import solve_state
    from gongsynth.sun.rt.opacity import column_opacity, line_constants

    a = _column(nx=ncol)
    temp = np.ascontiguousarray(a["temperature"][:, 0, :].T)
    st = solve_state(temp, gas_pressure=np.ascontiguousarray(a["gas_pressure"][:, 0, :].T))
    const, pf = line_constants(NiLineData())
    opac = [np.empty(temp.shape) for _ in range(5)]
    column_opacity(temp, np.ascontiguousarray(st["electron_density"]),
                   np.ascontiguousarray(st["hydrogen_density"]), np.zeros(temp.shape), const, pf, *opac)
    lam = np.linspace(676.73, 676.83, 21) * 1e-7
    ds = np.diff(a["z"]) * 1e5
    full = np.broadcast_to(np.asarray(velocity_cm_s, dtype=float)[:, None], temp.shape).copy()
    bpar = np.full(temp.shape, field_g)
    zero = np.zeros(temp.shape)
    out = [np.empty((ncol, lam.size), dtype=np.float32) for _ in range(4)]
    taus = [np.empty(temp.shape, dtype=np.float32) for _ in range(2)]
    args = (lam, const[0], const[10], lam.size // 2, ds, *opac, full, bpar, 0.5 * bpar, zero, *out, *taus)
    return args, out


def test_rt_kernel_stays_in_bounds_whatever_the_input():
    """Velocities no atmosphere may hold (1e5 km/s, 1e12 km/s, NaN) run without a crash."""
    from gongsynth.sun.rt.kernels import _exp_neg, solve_columns

    # The exponential's table index: a negative optical-depth step indexed before the table.
    assert math.isfinite(_exp_neg.py_func(-4067.0)) and _exp_neg.py_func(1e9) == 0.0
    args, out = _kernel_inputs(3, [1e15, 1e22, np.nan], 1000.0)
    solve_columns(*args)
    assert np.isfinite(out[0][:2]).all()


def test_fast_solver_matches_reference_up_to_the_velocity_limit():
    """The fast solver agrees with the reference at the largest velocity an Atmosphere may hold."""
    from gongsynth.sun.rt.kernels import solve_columns, solve_columns_reference

    results = []
    for solver in (solve_columns, solve_columns_reference):
        args, out = _kernel_inputs(2, [300e5, -300e5], 1500.0)
        solver(*args)
        results.append([o.astype(float) for o in out])
    scale = results[1][0].max()
    for fast, ref in zip(*results):
        assert np.abs(fast - ref).max() < 1e-4 * scale


# ----------------------------------------------------------------- 3, 4 the library cache
TINY_LIBRARY = dict(shape=(16, 16), pixel_size=6 * u.Mm, seeds_per_level=(1, 1, 1, 1), theta=(0, 40, 80),
                    seed=3)


@pytest.fixture(scope="module")
def tiny_library():
    from gongsynth.stages.scene.library import build_library

    return build_library(**TINY_LIBRARY)


@pytest.fixture
def cache(tmp_path, monkeypatch, tiny_library):
    """
    An empty disk cache, a process that has loaded nothing yet, and a builder that hands out the
    tiny library built once (the cache's logic is under test here, not the build).
    """
    import gongsynth.stages.scene.library as library_module

    folder = tmp_path / "cache"
    monkeypatch.setenv("GONGSYNTH_CACHE_DIR", str(folder))
    monkeypatch.setattr(library_module, "_MEMO", {})
    monkeypatch.setattr(library_module, "_VERIFIED", set())
    monkeypatch.setattr(library_module, "build_library", lambda **arguments: tiny_library)

    def new_process():
        library_module._MEMO.clear()
        library_module._VERIFIED.clear()

    return folder, new_process


def _entry(folder):
    (entry,) = [p for p in folder.iterdir() if ".tmp-" not in p.name]
    return entry


@pytest.mark.parametrize("damage", ["scaled", "bit rot", "truncated", "missing"])
def test_a_damaged_cache_entry_is_detected_rebuilt_and_replaced(cache, damage):
    from gongsynth.stages.scene.library import CacheWarning, cached_library

    folder, new_process = cache
    # The numbers, copied: the library maps the entry's file (built or loaded alike), which this test
    # damages in place as if from outside; a replaced entry is a new file, which leaves a mapping intact.
    built = np.array(cached_library(**TINY_LIBRARY).patches)
    patches = _entry(folder) / "patches.npy"
    if damage == "scaled":      # the audit's case: a plausible library, 30 % brighter
        np.save(patches, np.load(patches) * 1.3)
    elif damage == "bit rot":
        data = bytearray(patches.read_bytes())
        data[-5] ^= 0x40
        patches.write_bytes(bytes(data))
    elif damage == "truncated":
        patches.write_bytes(patches.read_bytes()[:1000])
    else:
        patches.unlink()
    new_process()
    with pytest.warns(CacheWarning, match="damaged.*rebuilt and replaced"):
        again = cached_library(**TINY_LIBRARY)
    assert np.array_equal(again.patches, built)
    new_process()
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error", CacheWarning)     # repaired: loaded quietly, the same numbers
        loaded = cached_library(**TINY_LIBRARY)
    assert "cache" in loaded.meta and np.array_equal(loaded.patches, built)
    assert [p.name for p in folder.iterdir()] == [_entry(folder).name]


def test_stale_temporaries_of_killed_saves_are_removed(cache):
    import os
    import subprocess
    import sys

    from gongsynth.stages.scene.library import cached_library

    folder, _ = cache
    folder.mkdir()
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True).stdout.strip()
    stale = folder / f"library-0123.tmp-{dead}-abcd"
    live = folder / f"library-4567.tmp-{os.getpid()}-efgh"
    for tmp in (stale, live):
        tmp.mkdir()
        (tmp / "patches.npy").write_bytes(b"\0" * 100)
        os.utime(tmp, (0.0 + 10**9, 0.0 + 10**9) if tmp is stale else None)
    cached_library(**TINY_LIBRARY)
    assert not stale.exists() and live.exists()


@pytest.mark.parametrize("kind", ["plain file", "read-only"])
def test_an_unwritable_cache_is_a_warning_and_the_run_goes_on(cache, kind, monkeypatch):
    import errno
    import tempfile

    from gongsynth.stages.scene.library import CacheWarning, cached_library

    folder, _ = cache
    if kind == "plain file":
        folder.write_text("not a folder")
    else:   # as a read-only file system answers (chmod would not stop root)
        def refuse(*args, **kwargs):
            raise OSError(errno.EROFS, "Read-only file system", kwargs.get("dir"))
        monkeypatch.setattr(tempfile, "mkdtemp", refuse)
    with pytest.warns(CacheWarning, match="could not write the patch library.*in memory"):
        library = cached_library(**TINY_LIBRARY)
    assert library.patches.size and "cache" not in library.meta


def test_cli_full_disk_with_an_unwritable_cache_runs(cache, tmp_path, monkeypatch):
    """The audit's case: a cache path that is a plain file gave exit 3, a read-only one exit 1."""
    import gongsynth.chain as chain_module
    import gongsynth.stages.scene.library as library_module

    folder, _ = cache
    folder.write_text("")
    real = library_module.cached_library
    monkeypatch.setattr(chain_module, "cached_library", lambda **arguments: real(**TINY_LIBRARY))
    with pytest.warns(library_module.CacheWarning):
        code = main(["simulate", "--mode", "full-disk", "--shape", "32", "--duration", "1", "--seed", "1",
                     "--quiet", "--out", str(tmp_path / "x")])
    assert code == 0 and (tmp_path / "x" / "magnetogram.fits").is_file()


# ----------------------------------------------------------------- 5 sweeps keep finished runs
def _small_toml(tmp_path, seed=None):
    """A quick tiled run's configuration; without a seed the file leaves it unset (fresh each run)."""
    from gongsynth.config import SimulationConfig

    cfg = SimulationConfig(seed=seed or 1, sun="milne-eddington", duration=1 * u.min, detector_shape=16,
                           resolutions=(1,), photosphere_shape=(64, 64), photosphere_pixel_size=1536 * u.km)
    path = tmp_path / "small.toml"
    path.write_text(cfg.to_toml(template=seed is None))
    return path


def _counting_simulate(monkeypatch, fail=None, exc=None):
    """Count the runs of `simulate` by latitude (at its first step), raising ``exc`` at latitude ``fail``."""
    import gongsynth.pipeline as pipeline

    real, calls = pipeline.check_resources, []

    def first_step(config):
        calls.append(float(config.latitude.to_value(u.deg)))
        if fail is not None and calls[-1] == fail:
            raise exc
        return real(config)

    monkeypatch.setattr(pipeline, "check_resources", first_step)
    return calls


@pytest.mark.parametrize(("exc", "code", "words"), [
    (RuntimeError("the camera broke"), 1,
     "1 run(s) of the sweep failed (latitude 30.0 deg: error: RuntimeError"),
    (KeyboardInterrupt(), 130, "interrupted"),
])
def test_a_sweep_keeps_each_finished_run_and_a_rerun_completes_it(tmp_path, monkeypatch, capsys, exc, code,
                                                                    words):
    from gongsynth.config import SimulationConfig

    config = _small_toml(tmp_path)        # no seed: the rerun takes the finished runs' one
    lats = ["0", "30"] if code == 130 else ["30", "0"]     # a failure: the next run still goes
    argv = ["simulate", "--config", str(config), "--latitude", *lats, "--quiet", "--out", str(tmp_path / "s")]
    calls = _counting_simulate(monkeypatch, fail=30.0, exc=exc)
    assert main(argv) == code
    err = capsys.readouterr().err
    assert words in err and str(tmp_path / "s" / "lat+000.000") in err
    done = sorted(p.name for p in (tmp_path / "s").iterdir())
    assert done == ["lat+000.000"]
    seed = SimulationConfig.from_toml(tmp_path / "s" / "lat+000.000" / "config.toml").seed
    monkeypatch.undo()
    calls = _counting_simulate(monkeypatch)
    assert main(argv) == 0
    assert calls == [30.0]     # only the missing run
    for lat in ("000", "030"):
        assert SimulationConfig.from_toml(tmp_path / "s" / f"lat+{lat}.000" / "config.toml").seed == seed


# ----------------------------------------------------------------- 6 calibration does not compound
@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    """A saved quick tiled run (magnetogram, truth maps, raw planes, config)."""
    folder = tmp_path_factory.mktemp("run")
    toml = _small_toml(folder, seed=4)
    assert main(["simulate", "--config", str(toml), "--quiet", "--out", str(folder / "run")]) == 0
    return folder / "run"


def test_calibrate_refuses_a_calibrated_map_unless_forced(tmp_path, capsys):
    from .realdata import real_file

    source = real_file("gong/mrbqs221029t0304c2263_067.fits")
    once, twice = tmp_path / "once.fits", tmp_path / "twice.fits"
    assert main(["calibrate", str(source), "--out", str(once)]) == 0
    capsys.readouterr()
    assert main(["calibrate", str(once), "--out", str(twice)]) == 2
    assert "calibrated already (CALTABLE" in capsys.readouterr().err and not twice.exists()
    assert main(["calibrate", str(once), "--out", str(twice), "--force"]) == 0


@pytest.mark.parametrize("product", ["truth.fits", "truth_psf.fits"])
def test_calibrate_refuses_a_truth_map_unless_forced(small_run, tmp_path, capsys, product):
    out = tmp_path / "cal.fits"
    assert main(["calibrate", str(small_run / product), "--out", str(out)]) == 2
    assert "ground-truth map" in capsys.readouterr().err and not out.exists()
    assert main(["calibrate", str(small_run / "magnetogram.fits"), "--out", str(out)]) == 0


# ----------------------------------------------------------------- 7 errors before the computing
@pytest.fixture
def nothing_computed(monkeypatch):
    """Fail the test if a chain of stages is built (the computing starts there)."""
    calls = []
    monkeypatch.setattr("gongsynth.pipeline.build_chain", lambda *a, **k: calls.append(a) or 1 / 0)
    return calls


@pytest.mark.parametrize(("flags", "words"), [
    (["--latitude", "89.5"], "spans only 1.17″ × 134″ on the sky at latitude 89.5"),
    (["--latitude", "0", "89.5"], "spans only 1.17″"),
    (["--duration", "0.0125"], "leaves accumulation plane(s) without a frame"),
    (["--date", "9999-12-31T23:59"], "within the years 0001-9999"),
    (["--mode", "full-disk", "--pointing", "1e9", "1e9"], "off the solar disk"),
    (["--mode", "full-disk", "--shape", "64", "--pointing", "1100", "0"], "off the solar disk"),
])
@pytest.mark.filterwarnings("ignore:ERFA function:erfa.ErfaWarning")   # year 9999: "dubious year"
def test_late_errors_are_caught_before_computing(tmp_path, capsys, nothing_computed, flags, words):
    config = _small_toml(tmp_path, seed=1)
    assert main(["simulate", "--config", str(config), *flags, "--quiet", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert words in err and "Latitude" not in err
    assert nothing_computed == [] and not (tmp_path / "o").exists()


def test_bad_instrument_timing_in_toml_is_caught_before_computing(tmp_path, capsys, nothing_computed):
    path = tmp_path / "t.toml"
    path.write_text('[instrument]\nlcvr_period = "0.01 s"\n')
    assert main(["simulate", "--config", str(path), "--quiet", "--out", str(tmp_path / "o")]) == 2
    assert "frames per LCVR state" in capsys.readouterr().err and nothing_computed == []


def test_toml_native_datetime_is_accepted():
    from gongsynth.config import SimulationConfig

    config = SimulationConfig.from_toml("[simulation]\nobstime = 2020-01-01T00:00:00\nseed = 1\n")
    assert config.obstime == "2020-01-01T00:00:00.000"
    assert SimulationConfig.from_toml(config.to_toml()) == config      # and it saves


# ----------------------------------------------------------------- 2 --surface-field is checked
@pytest.mark.parametrize(("relpath", "words"), [
    ("mdi/mdi.fd_ic.20101015_230100_TAI.data.fits", "is not a magnetogram"),     # an intensity map
    ("hinode/FGMG4_20110214_030443.7.fits", "is not a magnetogram"),            # Hinode V/I
    ("gong/bbiqa090905t1854.fits.gz", "is not a magnetogram"),                  # GONG intensity
    ("gong", "is a folder, not a FITS file"),
    ("", "no such surface_field file"),
    ("http://example.com/m.fits", "a URL; gongsynth reads local files only"),
])
def test_cli_surface_field_goes_through_the_checked_reader(tmp_path, capsys, nothing_computed, relpath,
                                                          words):
    from .realdata import REAL_DATA

    value = relpath if relpath in ("", "http://example.com/m.fits") else str(REAL_DATA / relpath)
    if value == str(REAL_DATA / relpath) and not (REAL_DATA / relpath).exists():
        pytest.skip(f"real data not found at {REAL_DATA / relpath}")
    code = main(["simulate", "--mode", "full-disk", "--shape", "16", "--duration", "1", "--seed", "1",
                 "--surface-field", value, "--quiet", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2 and "--surface-field" in err and words in err and "allow_errors" not in err
    assert nothing_computed == []


def test_cli_surface_field_of_a_runs_raw_planes_is_refused(small_run, tmp_path, capsys, nothing_computed):
    code = main(["simulate", "--mode", "full-disk", "--shape", "16", "--duration", "1", "--seed", "1",
                 "--surface-field", str(small_run / "raw.fits"), "--quiet", "--out", str(tmp_path / "o")])
    assert code == 2 and "--surface-field" in capsys.readouterr().err and nothing_computed == []


# ----------------------------------------------------------------- 8 reruns from config.toml
def test_rerun_records_absolute_paths_and_refuses_a_changed_input(tmp_path, capsys, monkeypatch):
    """Findings 8 and 9: a 1-D model through the command line, recorded by absolute path and SHA-256."""
    import shutil

    import sunpy.map

    from gongsynth.config import SimulationConfig

    from .realdata import REAL_DATA

    source = REAL_DATA / "models" / "hsra11.1d"
    if not source.is_file():
        pytest.skip(f"1-D model not found at {source}")
    here = tmp_path / "here"
    here.mkdir()
    shutil.copy(source, here / "model.1d")
    monkeypatch.chdir(here)
    assert main(["simulate", "--atmosphere", "model.1d", "--shape", "16", "--duration", "1", "--seed", "1",
                 "--quiet", "--out", "run"]) == 0
    saved = SimulationConfig.from_toml(here / "run" / "config.toml")
    assert saved.atmosphere_file == str(here / "model.1d") and len(saved.atmosphere_sha256) == 64
    # Finding 9: the 1-D model ran (it failed with "tile spans only 0.00136″"), as a horizontally uniform,
    # field-free atmosphere: a continuum flat to the camera's noise, no field.
    continuum = sunpy.map.Map(here / "run" / "continuum.fits").data
    assert np.isfinite(continuum).all() and np.std(continuum) < 0.01 * np.mean(continuum)
    assert np.all(sunpy.map.Map(here / "run" / "truth.fits").data == 0)
    # From another folder, the recorded absolute path is found; a changed file is refused before computing.
    monkeypatch.chdir(tmp_path)
    (here / "model.1d").write_text((here / "model.1d").read_text().replace("0.6", "0.7", 1))
    calls = []
    monkeypatch.setattr("gongsynth.pipeline.build_chain", lambda *a, **k: calls.append(a) or 1 / 0)
    assert main(["simulate", "--config", str(here / "run" / "config.toml"), "--quiet", "--out", "again"]) == 2
    err = capsys.readouterr().err
    assert "atmosphere_file" in err and "has changed since this configuration recorded it" in err
    assert calls == []


# ----------------------------------------------------------------- 10 messages and exit codes
def test_cli_bad_like_file_is_named_with_exit_2(tmp_path, capsys):
    bad = tmp_path / "bad.fits"
    bad.write_text("not FITS")
    for like in (bad, tmp_path):
        assert main(["simulate", "--like", str(like), "--out", str(tmp_path / "o")]) == 2
        assert f"--like {like}" in capsys.readouterr().err


@pytest.mark.parametrize("name", ["x", "x.png"])
def test_calibrate_out_suffix_is_checked_first(small_run, tmp_path, capsys, name):
    assert main(["calibrate", str(small_run / "magnetogram.fits"), "--out", str(tmp_path / name)]) == 2
    err = capsys.readouterr().err
    assert ".fits, .fts" in err and "part" not in err and not (tmp_path / name).exists()


def test_calibrate_writes_fits_gz(small_run, tmp_path, capsys):
    from astropy.io import fits

    out = tmp_path / "cal.fits.gz"
    assert main(["calibrate", str(small_run / "magnetogram.fits"), "--out", str(out)]) == 0
    assert out.read_bytes()[:2] == b"\x1f\x8b"          # gzip
    with fits.open(out) as hdus:
        assert any(h.data is not None and h.data.ndim == 2 for h in hdus)


def test_out_of_memory_message_says_what_to_do(tmp_path, capsys, monkeypatch):
    def no_memory(*args, **kwargs):
        raise MemoryError

    monkeypatch.setattr("gongsynth.pipeline.build_chain", no_memory)
    config = _small_toml(tmp_path, seed=1)
    assert main(["simulate", "--config", str(config), "--quiet", "--out", str(tmp_path / "o")]) == 4
    assert "cannot run here: out of memory: use a smaller --shape" in capsys.readouterr().err


@pytest.mark.parametrize(("text", "words"), [
    ("photosphere_shape = 256", "photosphere_shape is a list, e.g. photosphere_shape = [256, 256], got 256"),
    ('latitude = ["0 deg", "30 deg"]', "latitude is one value"),
])
def test_toml_shape_and_latitude_list_messages(tmp_path, capsys, text, words):
    path = tmp_path / "c.toml"
    path.write_text(f"[simulation]\n{text}\n")
    assert main(["simulate", "--config", str(path), "--out", str(tmp_path / "o")]) == 2
    assert words in capsys.readouterr().err


# ----------------------------------------------------------------- 11 silent results
def test_latitude_in_full_disk_mode_is_refused(tmp_path, capsys, nothing_computed):
    assert main(["simulate", "--mode", "full-disk", "--latitude", "30", "--out", str(tmp_path / "o")]) == 2
    assert "--latitude 30.0: a full-disk run" in capsys.readouterr().err and nothing_computed == []


def test_empty_out_is_refused(capsys):
    with pytest.raises(SystemExit) as info:
        main(["simulate", "--out", ""])
    assert info.value.code == 2 and "--out: is empty" in capsys.readouterr().err


def test_sigterm_stops_like_ctrl_c(tmp_path, capsys, monkeypatch):
    import os
    import signal

    def terminated(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGTERM)

    monkeypatch.setattr("gongsynth.pipeline.build_chain", terminated)
    before = signal.getsignal(signal.SIGTERM)
    config = _small_toml(tmp_path, seed=1)
    assert main(["simulate", "--config", str(config), "--quiet", "--out", str(tmp_path / "o")]) == 143
    err = capsys.readouterr().err
    assert "terminated (SIGTERM)" in err and "nothing was written" in err
    assert signal.getsignal(signal.SIGTERM) is before and not (tmp_path / "o").exists()


# ----------------------------------------------------------------- the exit codes, documented
def test_exit_codes_are_listed_in_help_readme_and_troubleshooting(capsys):
    from pathlib import Path

    from gongsynth import cli

    with pytest.raises(SystemExit):
        main(["--help"])
    help_text = capsys.readouterr().out
    root = Path(cli.__file__).resolve().parents[1]
    readme = (root / "README.md").read_text()
    page = (root / "docs" / "guide" / "troubleshooting.rst").read_text()
    codes = {v for k, v in vars(cli).items() if k.startswith("EXIT_") and isinstance(v, int)}
    assert codes == set(cli.EXIT_CODES)
    for code in codes - {0}:
        assert f"  {code:<4d}" in help_text
        assert f" {code} " in " ".join(readme.split("Exit codes:")[1].split("## ")[0].split())
        assert f"\n{code:<4d}  " in page


# ----------------------------------------------------------------- 11 (continued) a scene without light
def test_a_scene_without_light_is_blanked_not_a_noise_magnetogram():
    """Finding 11: a prefilter 30 nm from the line lets 0.1 e- per frame through: ±2 kG of noise before."""
    from gongsynth.config import SimulationConfig
    from gongsynth.pipeline import simulate

    base = SimulationConfig(seed=1, sun="milne-eddington", duration=1 * u.min, detector_shape=16,
                            resolutions=(1,), photosphere_shape=(64, 64), photosphere_pixel_size=1536 * u.km)
    dark = base.instrument.replace(prefilter_center=base.instrument.prefilter_center + 30 * u.nm)
    result = simulate(config=base.replace(instrument=dark), progress=False)
    assert float(result.expected_counts.sum(axis=0).max().value) < 1     # electrons per frame
    assert np.isnan(result.magnetogram.data).all() and np.isnan(result.doppler.data).all()
