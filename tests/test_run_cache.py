"""The resumable, distributed build: runs cached on disk, only what is missing recomputed, the same bits."""
import os
import shutil
import threading
import time

import astropy.units as u
import numpy as np
import pytest

import gongsynth.run_cache as run_cache
from gongsynth.calibration_sweep import build_calibration_table
from gongsynth.config import SimulationConfig
from gongsynth.run_cache import cached_runs, entry_path, run_key

# Tiny runs: the toy Sun on a coarse box, 32² GONG pixels, one minute; at 75° the quiet-Sun
# fit has the authors' 7 bins, which three seeds of 32² pixels fill.
TINY = dict(sun="milne-eddington", detector_shape=32, duration=1 * u.min, photosphere_shape=(64, 64),
            photosphere_pixel_size=1536 * u.km, resolutions=(1,))
BUILD = dict(latitudes=[75] * u.deg, seeds=[1, 2, 3], regions=["quiet"], n_boot=5, progress=False, **TINY)
COLUMNS = ("factor", "uncertainty", "n_pixels", "nodes", "values")


@pytest.fixture(scope="module")
def serial_build(tmp_path_factory):
    """The table built serially (one worker, this process) into a cache: the reference bits and entries."""
    folder = tmp_path_factory.mktemp("serial-cache")
    return build_calibration_table(cache=folder, **BUILD), folder


def entries(folder):
    """The finished entries (not the hidden temporary files of writes in progress or cut short)."""
    return sorted(path for path in folder.glob("*.fits") if not path.name.startswith("."))


def same_bits(first, second):
    return all(np.array_equal(np.asarray(first[c]), np.asarray(second[c]), equal_nan=True) for c in COLUMNS)


@pytest.fixture
def counted(monkeypatch):
    """The configurations simulated in this process."""
    calls = []
    simulate = run_cache.simulate

    def counting(*, config, progress):
        calls.append(config)
        return simulate(config=config, progress=progress)

    monkeypatch.setattr(run_cache, "simulate", counting)
    return calls


def test_the_key_is_the_whole_configuration_and_the_version(monkeypatch):
    base = SimulationConfig.from_arguments(seed=1, **TINY)
    assert run_key(base) == run_key(SimulationConfig.from_arguments(seed=1, **TINY))
    changed = [base.replace(seed=2), base.replace(latitude=1 * u.deg), base.replace(duration=2 * u.min),
               base.replace(instrument=base.instrument.replace(seeing_fwhm=4 * u.arcsec))]
    assert len({run_key(c) for c in changed} | {run_key(base)}) == len(changed) + 1
    key = run_key(base)
    monkeypatch.setattr(run_cache, "__version__", "0.0.0-another")
    assert run_key(base) != key


def test_an_inert_switch_at_its_inert_value_leaves_the_key_as_before_it_existed():
    base = SimulationConfig(seed=1)
    assert 'network = "auto"' in run_cache.run_config(base).to_toml(comments=False)   # the default lays it
    off = base.replace(photosphere={"network": False})
    text = run_cache.run_config(off).to_toml(comments=False)
    assert "network = false" in text       # the switch is in the configuration ...
    other_size = off.replace(photosphere={"network": False, "supergranule_size": 20 * u.Mm})
    assert run_key(other_size) == run_key(off)
    assert run_key(off) != run_key(base)   # ... but not in the key while it is off
    # An entry cached before the switch existed (its TOML without the two keys) still reads as the off run's.
    before = "".join(line for line in text.splitlines(keepends=True)
                     if not line.startswith(("network =", "supergranule_size =")))
    assert run_cache._keyed(before) == run_cache._keyed(text) != text
    on = base.replace(photosphere={"network": True})
    assert run_key(on) != run_key(base) and run_key(on) != run_key(off)
    assert run_key(on.replace(photosphere={"network": True, "supergranule_size": 20 * u.Mm})) != run_key(on)
    # The Milne-Eddington Sun's own supergranule size has no such switch: it stays in the key.
    me = SimulationConfig(seed=1, sun="milne-eddington")
    assert run_key(me.replace(photosphere={"supergranule_size": 20 * u.Mm})) != run_key(me)


def test_the_cache_recomputes_only_missing_entries_with_the_same_bits(tmp_path, serial_build, counted):
    serial_table, folder = serial_build
    assert len(entries(folder)) == 3 and not list(folder.glob(".*"))  # no temporary left behind
    copies = [shutil.copy2(path, tmp_path / path.name) for path in entries(folder)]
    before = {path: (path.read_bytes(), path.stat().st_mtime_ns) for path in copies}
    # Built from the cache alone (read from the files, not from the runs): nothing simulated, the same bits.
    assert same_bits(build_calibration_table(cache=tmp_path, **BUILD), serial_table) and not counted
    # An interrupted build: one entry missing, one write cut short (its temporary file left behind),
    # and one entry damaged by hand (truncated), which is simulated again with a warning.
    copies[2].unlink()
    (tmp_path / f".{copies[1].name}.x.part.fits").write_bytes(before[copies[1]][0][:2880])
    copies[0].write_bytes(before[copies[0]][0][:5000])
    with pytest.warns(UserWarning, match="ignoring the cache entry"):
        again = build_calibration_table(cache=tmp_path, **BUILD)
    assert same_bits(again, serial_table)
    assert sorted(c.seed for c in counted) == [1, 3]
    for path, (data, mtime) in before.items():
        assert path.read_bytes() == data  # the recomputed entries too: the same bits
        assert path in (copies[0], copies[2]) or path.stat().st_mtime_ns == mtime  # the others untouched


def test_a_failed_run_is_named_and_the_others_are_kept(tmp_path, monkeypatch):
    configs = [SimulationConfig.from_arguments(seed=seed, latitude=70 * u.deg, **TINY) for seed in (1, 2)]

    def fails_for_seed_1(*, config, progress):
        if config.seed == 1:
            raise FloatingPointError("a broken run")
        return simulate(config=config, progress=progress)

    simulate = run_cache.simulate
    monkeypatch.setattr(run_cache, "simulate", fails_for_seed_1)
    named = rf"run 0 of the sweep, gong at latitude 70 deg, seed 1 \(cache key {run_key(configs[0])}\)"
    with pytest.raises(RuntimeError, match=named + ", failed: FloatingPointError: a broken run; the finish"):
        list(cached_runs(configs, cache=tmp_path, progress=False))
    assert not entry_path(tmp_path, configs[0]).exists() and entry_path(tmp_path, configs[1]).exists()


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore::ResourceWarning")
@pytest.mark.filterwarnings("ignore:.*[Pp]ort.*:UserWarning")
def test_a_worker_killed_mid_build_then_a_rerun_gives_the_same_bits(tmp_path, serial_build):
    """Two worker processes; one is killed while it runs a task; the rerun finishes from the cache."""
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        outcome = {}

        def build():
            try:
                outcome["table"] = build_calibration_table(cache=tmp_path, client=client, **BUILD)
            except Exception as exc:  # noqa: BLE001 - a lost worker may end the build: the rerun is the test
                outcome["error"] = exc

        builder = threading.Thread(target=build)
        builder.start()
        killed = None
        while builder.is_alive() and killed is None:
            busy = [worker for worker, keys in client.processing().items() if keys]
            if busy and entries(tmp_path):  # one run done, another running: kill its worker
                killed = client.run(os.getpid, workers=busy[:1])[busy[0]]
                os.kill(killed, 9)
            time.sleep(0.05)
        builder.join()
        assert killed is not None, "the build ended before a worker could be killed"
        done = {path: path.stat().st_mtime_ns for path in entries(tmp_path)}
        rerun = build_calibration_table(cache=tmp_path, client=client, **BUILD)
    serial_table = serial_build[0]
    assert same_bits(rerun, serial_table)  # 2 workers, a restart: the serial table's bits
    if "table" in outcome:
        assert same_bits(outcome["table"], serial_table)
    assert all(path.stat().st_mtime_ns == mtime for path, mtime in done.items())  # only the missing reran
    assert len(entries(tmp_path)) == 3
