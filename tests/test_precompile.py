"""The background compile of a first run's kernels (`gongsynth.precompile`, issue 26)."""
import json
import os
import sys

import astropy.units as u
import numba
import pytest
from numba.core.dispatcher import Dispatcher

from gongsynth import precompile


def _entries(tasks):
    return [(task["module"], task["function"], tuple(types))
            for task in tasks for types in task["signatures"]]


def test_argument_types_read_back():
    """Every type of the shipped list reads back as the type numba prints; callees come before callers."""
    tasks = precompile.load_kernels()
    assert tasks
    for _, _, types in _entries(tasks):
        for text in types:
            assert str(precompile._argument_type(text)) == text
    stages = json.loads(precompile.KERNELS.read_text())["stages"]
    for number, task in enumerate(tasks):
        assert all(callee < number for callee in task["calls"]) and task["stage"] in stages


def test_list_is_the_runs_kernels():
    """
    Each listed kernel of the 3-D Sun and the transfer is what a run calls, with those argument
    types, and every kernel of theirs the run calls is listed.  Failing: a kernel was
    renamed or its arguments changed: rerun ``NUMBA_CACHE_DIR=$(mktemp -d)
    GONGSYNTH_PRECOMPILE=0 python benchmarks/bench_compile.py --write-kernels``.
    """
    import importlib

    from gongsynth.sun.model_atmosphere import model_atmosphere
    from gongsynth.sun.rt import synthesize

    def loads():
        """Cache loads so far of each module's own kernels (other tests in this process load some too)."""
        return {(module, name): sum(value._cache_hits.values())
                for module in {module for module, _, _ in _entries(precompile.load_kernels())}
                for name, value in vars(importlib.import_module(module)).items()
                if isinstance(value, Dispatcher) and value.py_func.__module__ == module}

    before = loads()
    # The run's builder and transfer on a small grid (the types do not depend on the sizes), with the
    # supergranular network that the default run's 98 Mm box lays (cells small enough for this box).
    synthesize(model_atmosphere((16, 16), pixel_size=384 * u.km, seed=0, nz=16, network=True,
                                supergranule_size=3 * u.Mm), mu=0.9, azimuth=-90 * u.deg, progress=False)
    tasks = precompile.load_kernels()
    called = {callee for task in tasks for callee in task["calls"]}
    names = {(module, name) for module, name, _ in _entries(tasks)}
    for module, name in names:
        assert isinstance(getattr(importlib.import_module(module), name), Dispatcher), (module, name)
    # The kernels called from Python (a callee is linked into its caller's cached code, not loaded).
    for module, name, types in _entries([task for n, task in enumerate(tasks) if n not in called]):
        if module.startswith("gongsynth.sun."):   # the scene's kernel: not called by this small run
            dispatcher = getattr(importlib.import_module(module), name)
            assert types in {tuple(map(str, sig)) for sig in dispatcher.signatures}, (module, name)
    for key, count in loads().items():
        if count > before.get(key, 0):   # loaded from the cache by this run
            assert key in names, f"{'.'.join(key)} is called by the run but not listed"


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """An empty numba cache for this process and the compilers it starts, and a tiny kernel module."""
    folder = tmp_path / "numba"
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(folder))
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(folder))
    monkeypatch.delenv(precompile.ENV, raising=False)
    (tmp_path / "fr_tiny_kernels.py").write_text(
        "import numba\n\n\n@numba.njit(cache=True)\ndef add(a, b):\n    return a + b\n\n\n"
        "@numba.njit(cache=True)\ndef total(x):\n    return x.sum()\n\n\n"
        "@numba.njit(cache=True)\ndef twice(x):\n    return add(1, x) + x - 1\n")
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")]))
    monkeypatch.syspath_prepend(str(tmp_path))
    return folder


def _tiny_list(tmp_path, tasks, stages=("a", "b")):
    kernels = tmp_path / "kernels.json"
    kernels.write_text(json.dumps({"stages": list(stages), "tasks": tasks}))
    return kernels


_TINY = [{"module": "fr_tiny_kernels", "function": "add", "cpu_s": 0.1, "calls": [], "stage": "a",
          "signatures": [["int64", "float64"], ["int64", "int64"]]},
         {"module": "fr_tiny_kernels", "function": "total", "cpu_s": 0.1, "calls": [], "stage": "a",
          "signatures": [["readonly array(float32, 2d, A)"]]},
         {"module": "fr_tiny_kernels", "function": "twice", "signatures": [["float64"]],
          "cpu_s": 0.1, "calls": [0], "stage": "b"}]


def test_kernel_modules_import_in_a_compiler():
    """
    The shipped list's modules import in a new compiler process, whose packages are stubs
    (`precompile._StubPackages`: no package ``__init__``), and without sunpy.  Failing: a kernel
    module needs a name of its package's ``__init__`` (a first run would compile it itself), or
    imports sunpy (a compiler's second of CPU).
    """
    import subprocess
    from pathlib import Path

    code = precompile._STUBS + (
        "import importlib\n"
        "for task in precompile.load_kernels(sys.argv[2]):\n"
        "    getattr(importlib.import_module(task['module']), task['function'])\n"
        "print(sorted(name for name in sys.modules if name.split('.')[0] == 'sunpy'))\n")
    done = subprocess.run([sys.executable, "-c", code, str(Path(precompile.__file__).parent),
                           str(precompile.KERNELS)], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


@pytest.mark.parametrize("fork", [True, False])
def test_background_compile(cache, tmp_path, fork):
    """
    Two compilers (the second forked from this process or a new one) share the queue and fill an
    empty cache; the record then says compiled, and nothing starts again.
    """
    import fr_tiny_kernels

    kernels = _tiny_list(tmp_path, _TINY)
    assert not precompile.compiled(kernels)
    import threading

    assert precompile.start(kernels, fork=fork)
    forked = [isinstance(job, precompile._Forked) for job in precompile._jobs]
    assert forked == [False, fork and sys.platform == "linux" and threading.active_count() == 1]
    queue = precompile._queue[0]
    assert queue.exists() and not precompile.start(kernels)        # this process's compilers run already
    assert precompile.wait("no such stage", progress=False) == 0   # a stage the list does not know
    assert precompile.wait("a", progress=False) >= 0               # add and total compiled (or all)
    assert precompile._done(queue, [0, 1]) or not queue.exists()
    assert precompile.wait(progress=False) >= 0
    assert precompile.wait(progress=False) == 0 and not queue.exists()
    assert precompile.compiled(kernels)
    record = json.loads((precompile._cache_folder() / precompile.MANIFEST).read_text())
    assert len(record["entries"]) == 3 and all(os.path.exists(index) for index, _, _ in record["entries"])
    assert not precompile.start(kernels)        # compiled: nothing to do
    # This process loads what the compilers made, both signatures and the caller: nothing compiles.
    assert fr_tiny_kernels.add(1, 2.5) == 3.5 and fr_tiny_kernels.add(1, 2) == 3
    assert fr_tiny_kernels.twice(1.5) == 3.0
    for kernel in (fr_tiny_kernels.add, fr_tiny_kernels.twice):
        assert dict(kernel._cache_hits) and not kernel._cache_misses
    # A changed source is a stale record.
    source = tmp_path / "fr_tiny_kernels.py"
    source.write_text(source.read_text() + "\n")
    assert not precompile.compiled(kernels)


def test_queue_claims(cache, tmp_path):
    """
    A compiler takes the first free task whose callees are compiled; it waits (-1) while the
    other compiler, alive, compiles a callee, and takes the task itself once that one has ended.
    """
    import fcntl

    folder = cache / "q"
    folder.mkdir(parents=True)
    queue = folder / "test.queue"
    queue.write_bytes(bytes(3))
    assert precompile._claim(queue, _TINY, 0, folder) == 0      # add: no callees
    assert precompile._claim(queue, _TINY, 1, folder) == 1      # total: no callees (twice calls add)
    precompile._set(queue, 1, precompile._DONE)
    with open(folder / "gongsynth-precompile-0.lock", "a") as held:
        fcntl.flock(held, fcntl.LOCK_EX)                          # compiler 0 alive, add not compiled
        assert precompile._claim(queue, _TINY, 1, folder) == -1
    assert precompile._claim(queue, _TINY, 1, folder) == 2      # compiler 0 ended: take twice anyway
    assert precompile._claim(queue, _TINY, 1, folder) is None   # nothing free
    assert not precompile._done(queue, [0, 1]) and precompile._done(queue, [1])


def test_switched_off_and_stale(cache, tmp_path, monkeypatch):
    """``GONGSYNTH_PRECOMPILE=0`` starts nothing; a stale entry ends its compiler without a record."""
    kernels = _tiny_list(tmp_path, [{"module": "fr_tiny_kernels", "function": "no_such_kernel",
                                     "signatures": [["int64"]], "cpu_s": 0.1, "calls": [], "stage": "a"}])
    monkeypatch.setenv(precompile.ENV, "off")
    assert not precompile.enabled() and not precompile.start(kernels)
    monkeypatch.setenv(precompile.ENV, "1")
    assert precompile.start(kernels)
    precompile.wait(progress=False)
    assert not precompile.compiled(kernels)


def test_started_by_the_simulate_command(monkeypatch):
    """Only ``gongsynth simulate`` of a 3-D Sun run starts the compilers at import."""
    calls = []
    monkeypatch.setattr(precompile, "start", lambda: calls.append(1) or True)
    assert precompile.start_for_command(["/venv/bin/gongsynth", "simulate", "--seed", "1"])
    for argv in (["/venv/bin/gongsynth", "compare", "a", "b"], ["pytest", "simulate"],
                 ["/venv/bin/gongsynth", "simulate", "--sun", "milne-eddington"],
                 ["/venv/bin/gongsynth", "simulate", "--help"], ["gongsynth"]):
        assert not precompile.start_for_command(argv)
    assert calls == [1]
