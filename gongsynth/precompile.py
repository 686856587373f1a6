"""
A first run's kernels compiled in background processes while the run starts (issue 26).

numba compiles gongsynth's kernels on their first call in a new environment and
keeps them in its cache (``NUMBA_CACHE_DIR``, by default ``__pycache__`` next to
the sources); a later run loads them.  A first ``gongsynth simulate`` would
otherwise spend ~25 s of CPU compiling the 3-D Sun's builder and the radiative
transfer before it could synthesise anything, one kernel after the other.

`start` launches compiler processes (one per group of `KERNELS`, two groups,
each about half the compile time: the radiative transfer's solver, and the
rest) that compile the kernels of the README's run, by the argument types
recorded in `KERNELS`, into the same cache, while the run imports its libraries
and builds its photosphere.  A stage calls `wait` before it needs them: it
blocks (logging "compiling kernels (first run only)") until the compilers have
ended, then loads the kernels from the cache.  The ``gongsynth`` command starts
them at ``import gongsynth`` (before sunpy's ~5 s of imports) for a
``simulate``; a script can call `start` itself.

Safety:

- A run starts compilers only when the kernels are not compiled yet: a
  finished compile leaves a record (`MANIFEST`) of the numba cache files and
  the stamps of their sources, and a whole record means nothing to do.
- Two first runs at once: their compilers take turns on a lock file in the
  numba cache, and the later ones find the record whole.  numba writes each
  cache file atomically, so a run that compiles a kernel itself at the same
  time (after `TIMEOUT`, or when a compiler failed) breaks nothing.
- A failed or slow compiler never stops a run: `wait` returns when the
  processes have ended, however they ended, or after `TIMEOUT` seconds (then
  it stops them); the run compiles what it still needs itself.  A stale
  `KERNELS` list (a kernel renamed or retyped) costs time, never a result.
- ``GONGSYNTH_PRECOMPILE=0`` (or ``off``) switches the mechanism off.

A compiler imports only the kernels' modules (a stub ``gongsynth`` package skips
the package's ``__init__``, which imports sunpy.map): ~2 s of imports, not ~7.
`KERNELS` is written by ``python benchmarks/bench_compile.py --write-kernels``
from a run with an empty numba cache.
"""
import json
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

__all__ = ["start", "start_for_command", "wait", "enabled", "compiled", "load_kernels", "ENV", "TIMEOUT",
           "MANIFEST", "KERNELS"]

#: The environment variable that switches background compiling off (``0``, ``off``, ``no``, ``false``).
ENV = "GONGSYNTH_PRECOMPILE"
#: Seconds `wait` waits for the compilers at most (then the run compiles what it needs itself).
TIMEOUT = 300.0
#: The record of a finished compile, in the numba cache folder of this module.
MANIFEST = "gongsynth-precompile.json"
#: The kernels of the README's run: groups of ``[module, function, [argument types]]``, one
#: compiler process per group (`benchmarks/bench_compile.py --write-kernels` writes it).
KERNELS = Path(__file__).parent / "data" / "precompile_kernels.json"

# The compiler process: a stub package (no gongsynth/__init__: no sunpy), then `_compile_here`.
_BOOT = ("import importlib.machinery, sys, types\n"
         "pkg = types.ModuleType('gongsynth')\n"
         "pkg.__path__ = [sys.argv[1]]\n"
         "pkg.__spec__ = importlib.machinery.ModuleSpec('gongsynth', None, is_package=True)\n"
         "pkg.__spec__.submodule_search_locations = [sys.argv[1]]\n"
         "sys.modules['gongsynth'] = pkg\n"
         "from gongsynth import precompile\n"
         "sys.exit(precompile._compile_here(sys.argv[2], int(sys.argv[3])))\n")

_lock = threading.Lock()
_jobs = []           # this process's compilers (`subprocess.Popen`)
_started = [None]    # when they were started (`time.monotonic`)


def enabled():
    """
    Whether background compiling is on (``GONGSYNTH_PRECOMPILE`` is not ``0``/``off``/``no``/``false``).

    Returns
    -------
    bool
    """
    return os.environ.get(ENV, "1").strip().lower() not in ("0", "off", "no", "false")


def _probe():  # pragma: no cover - located by numba's cache, never compiled
    return 0


def _cache_folder():
    """The numba cache folder for this module's source (a dispatcher is made, nothing compiled)."""
    import numba

    return Path(numba.njit(cache=True)(_probe)._cache._cache_path)


def load_kernels(path=None):
    """
    The groups of kernels to compile, as recorded in `KERNELS`.

    Parameters
    ----------
    path : path-like, optional
        Another list (default `KERNELS`).

    Returns
    -------
    list of list
        Each group a list of ``[module, function, [argument type, ...]]``, the types
        as numba prints them (``"int64"``, ``"readonly array(float32, 3d, A)"``).
    """
    return json.loads(Path(KERNELS if path is None else path).read_text())["groups"]


def compiled(kernels=None):
    """
    Whether a finished compile of ``kernels`` left a whole record: every numba
    cache index it lists exists and every kernel source has the stamp (mtime,
    size) it had then.

    Parameters
    ----------
    kernels : path-like, optional
        The list compiled (default `KERNELS`).

    Returns
    -------
    bool
    """
    try:
        record = json.loads((_cache_folder() / MANIFEST).read_text())
        if record.get("kernels") != str(Path(KERNELS if kernels is None else kernels).resolve()):
            return False
        if record.get("python") != list(sys.version_info[:2]) or not record["entries"]:
            return False
        for index, source, stamp in record["entries"]:
            st = os.stat(source)
            if not os.path.exists(index) or [st.st_mtime, st.st_size] != stamp:
                return False
        return True
    except (OSError, ValueError, KeyError, TypeError, AttributeError, RuntimeError):
        return False


def start(kernels=None):
    """
    Start compiling the kernels of ``kernels`` in background processes, one per group.

    Does nothing when switched off (`ENV`), when they are compiled already
    (`compiled`), or when this process's compilers run.

    Parameters
    ----------
    kernels : path-like, optional
        The list to compile (default `KERNELS`).

    Returns
    -------
    bool
        Whether compilers were started.
    """
    with _lock:
        if _jobs or not enabled() or compiled(kernels):
            return False
        kernels = str(Path(KERNELS if kernels is None else kernels).resolve())
        try:
            _cache_folder()                 # numba can cache here at all
            groups = len(load_kernels(kernels))
        except Exception:
            return False
        package = str(Path(__file__).resolve().parent)
        for group in range(groups if (os.cpu_count() or 1) > 1 else 1):
            try:
                _jobs.append(subprocess.Popen([sys.executable, "-c", _BOOT, package, kernels, str(group)],
                                              stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                              stderr=subprocess.DEVNULL))
            except OSError:
                break
        _started[0] = time.monotonic()
        return bool(_jobs)


def start_for_command(argv):
    """
    `start` when ``argv`` is the ``gongsynth simulate`` command of a 3-D Sun run.

    Called by ``import gongsynth`` before its slow imports: the compilers work while they run.

    Parameters
    ----------
    argv : list of str
        The process's `sys.argv`.

    Returns
    -------
    bool
        Whether compilers were started.
    """
    if (len(argv) < 2 or Path(argv[0]).name.split(".")[0] != "gongsynth" or argv[1] != "simulate"
            or any(a in ("-h", "--help", "milne-eddington", "--sun=milne-eddington") for a in argv)):
        return False
    if "multiprocessing" in sys.modules and sys.modules["multiprocessing"].parent_process() is not None:
        return False        # a sweep's worker (it has the command's argv): its parent started them
    try:
        return start()
    except Exception:   # never in the way of the import: the run compiles its kernels itself
        return False


def wait(*, progress=True):
    """
    Wait until this process's compilers have ended (at most until `TIMEOUT` after their start).

    Parameters
    ----------
    progress : bool
        Log "compiling kernels (first run only)" (sunpy's logger, level INFO) when it waits.

    Returns
    -------
    float
        Seconds waited (0 without compilers).
    """
    with _lock:
        jobs = list(_jobs)
        _jobs.clear()
    if not any(job.poll() is None for job in jobs):
        return 0.0
    if progress:
        from sunpy import log

        log.info("gongsynth: compiling kernels (first run only)")
    began = time.monotonic()
    for job in jobs:
        try:
            job.wait(max(TIMEOUT - (time.monotonic() - _started[0]), 0.0))
        except subprocess.TimeoutExpired:
            job.kill()
            job.wait()
    waited = time.monotonic() - began
    if progress:
        log.info(f"gongsynth: kernels compiled ({waited:.0f} s waited)")
    return waited


def _argument_type(text):
    """A numba type from its printed name (``int64``, ``readonly array(float32, 2d, C)``)."""
    from numba.core import types

    readonly = text.startswith("readonly ")
    text = text.removeprefix("readonly ")
    if text.startswith("array(") and text.endswith(")"):
        dtype, ndim, layout = (part.strip() for part in text[6:-1].split(","))
        return types.Array(getattr(types, dtype), int(ndim.removesuffix("d")), layout, readonly=readonly)
    return types.boolean if text == "bool" else getattr(types, text)


def _compile_here(kernels, group):
    """A compiler process: compile group ``group`` of ``kernels``; the last to end writes the record."""
    import importlib

    folder = _cache_folder()
    folder.mkdir(parents=True, exist_ok=True)
    groups = load_kernels(kernels)
    mine = [entry for number, entry in enumerate(groups) if number == group]
    if group == 0 and len(groups) > 1 and (os.cpu_count() or 1) == 1:
        mine = groups          # one core: one compiler for all
    failed = 0
    with _turns(folder / f"gongsynth-precompile-{group}.lock"):
        if compiled(kernels):
            return 0
        for entries in mine:
            for module, name, argtypes in entries:
                try:
                    dispatcher = getattr(importlib.import_module(module), name)
                    dispatcher.compile(tuple(_argument_type(t) for t in argtypes))
                except Exception:   # a stale entry: the run compiles that kernel itself
                    failed += 1
    with _turns(folder / "gongsynth-precompile.lock"):
        _record(folder, kernels, groups)
    return 1 if failed else 0


class _turns:
    """An exclusive lock on a file (``fcntl.flock``; no lock where there is no fcntl)."""

    def __init__(self, path):
        self.path = path

    def __enter__(self):
        self.file = open(self.path, "a")
        try:
            import fcntl

            fcntl.flock(self.file, fcntl.LOCK_EX)
        except ImportError:   # pragma: no cover - Windows
            pass
        return self

    def __exit__(self, *exc):
        self.file.close()      # releases the lock


def _record(folder, kernels, groups):
    """Write `MANIFEST` when every kernel of ``groups`` has a numba cache index."""
    import importlib

    import numba

    entries = []
    for module, name, _ in (entry for entries in groups for entry in entries):
        try:
            dispatcher = getattr(importlib.import_module(module), name)
            index = dispatcher._cache._cache_file._index_path
            source = dispatcher.py_func.__code__.co_filename
        except Exception:
            return
        if not os.path.exists(index):
            return      # another group still compiles: it writes the record when it ends
        st = os.stat(source)
        entries.append((index, source, [st.st_mtime, st.st_size]))
    record = {"kernels": str(Path(kernels).resolve()), "python": list(sys.version_info[:2]),
              "numba": numba.__version__, "entries": entries}
    tmp = folder / f"{MANIFEST}.{os.getpid()}"
    tmp.write_text(json.dumps(record))
    os.replace(tmp, folder / MANIFEST)
