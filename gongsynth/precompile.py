"""
A first run's kernels compiled in background processes while the run starts (issue 26).

numba compiles gongsynth's kernels on their first call in a new environment and
keeps them in its cache (``NUMBA_CACHE_DIR``, by default ``__pycache__`` next to
the sources); a later run loads them.  A first ``gongsynth simulate`` would
otherwise spend ~22 s of CPU compiling the 3-D Sun's builder and the radiative
transfer before it could synthesise anything, one kernel after the other.

`start` launches two compiler processes that share one queue of tasks: every
numba function of the README's run that has a cache (the kernels called from
Python and the functions they call), with the argument types it is compiled
for, its compile time and the tasks it calls (`KERNELS`).  A compiler takes the
first task of the queue whose callees are compiled (the queue is ordered by the
longest chain of compiles that follows each task, so the radiative transfer's
solver chain starts at once and the short kernels fill in beside it); a callee
compiled by the other process is loaded from the cache, not compiled again.
The first compiler is a new Python process (it imports only the kernels'
modules: stub packages skip the ``__init__`` of ``gongsynth`` and of the
kernels' own packages, which import sunpy.map, scipy.signal and the rest of
the package, `_StubPackages`; the kernels live in modules that import little);
where the platform forks (Linux), the second is a fork of
the run itself once it has imported those modules and set numba up, which it
needs anyway: that saves the second compiler's ~2 s of imports.  They work
while the run imports its libraries and builds its photosphere.  A stage calls
`wait` before it needs the kernels: it blocks (logging "compiling kernels
(first run only)") until the compilers have ended, then loads the kernels from
the cache.  The ``gongsynth`` command starts them at ``import gongsynth``
(before sunpy's ~5 s of imports) for a ``simulate``; a script can call `start`
itself.

Safety:

- A run starts compilers only when the kernels are not compiled yet: a
  finished compile leaves a record (`MANIFEST`) of the numba cache files and
  the stamps of their sources, and a whole record means nothing to do.  The
  compilers note each task's cache file as they go; the last one to end writes
  the record from those notes (no module to import while the run waits).
- Two first runs at once: their compilers take turns on a lock file in the
  numba cache, and the later ones find the record whole.  numba writes each
  cache file atomically, so a run that compiles a kernel itself at the same
  time (after `TIMEOUT`, or when a compiler failed) breaks nothing.  The two
  compilers of one run never compile the same function at once (one task per
  function, all its signatures).
- A failed or slow compiler never stops a run: a compiler that waits for the
  other's task stops waiting when the other has ended (its lock is free) and
  compiles what is left itself; `wait` returns when the processes have ended,
  however they ended, or after `TIMEOUT` seconds (then it stops them); the run
  compiles what it still needs itself.  A stale `KERNELS` list (a kernel
  renamed or retyped) costs time, never a result.
- ``GONGSYNTH_PRECOMPILE=0`` (or ``off``) switches the mechanism off.

`KERNELS` is written by ``python benchmarks/bench_compile.py --write-kernels``
from a run with an empty numba cache.
"""
import gc
import json
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

__all__ = ["start", "start_for_command", "wait", "enabled", "compiled", "load_kernels", "ENV", "TIMEOUT",
           "MANIFEST", "KERNELS", "WORKERS"]

#: The environment variable that switches background compiling off (``0``, ``off``, ``no``, ``false``).
ENV = "GONGSYNTH_PRECOMPILE"
#: Seconds `wait` waits for the compilers at most (then the run compiles what it needs itself).
TIMEOUT = 300.0
#: The record of a finished compile, in the numba cache folder of this module.
MANIFEST = "gongsynth-precompile.json"
#: The tasks of the README's run, in queue order: ``{"module", "function", "signatures": [[argument
#: type, ...], ...], "cpu_s", "calls": [task index, ...]}`` (`benchmarks/bench_compile.py
#: --write-kernels` writes it).
KERNELS = Path(__file__).parent / "data" / "precompile_kernels.json"
#: Compiler processes on a machine of two cores or more (one on one core).
WORKERS = 2

# The compiler process: stub packages (no gongsynth/__init__: no sunpy; nor the ``__init__`` of the
# kernels' own packages: `_StubPackages`), then `_compile_here`.
_STUBS = ("import importlib.machinery, sys, types\n"
          "pkg = types.ModuleType('gongsynth')\n"
          "pkg.__path__ = [sys.argv[1]]\n"
          "pkg.__spec__ = importlib.machinery.ModuleSpec('gongsynth', None, is_package=True)\n"
          "pkg.__spec__.submodule_search_locations = [sys.argv[1]]\n"
          "sys.modules['gongsynth'] = pkg\n"
          "from gongsynth import precompile\n"
          "sys.meta_path.insert(0, precompile._StubPackages(sys.argv[1], sys.argv[2]))\n")
_BOOT = _STUBS + ("code = precompile._compile_here(sys.argv[2], int(sys.argv[3]), sys.argv[4])\n"
                  "import os\n"
                  "os._exit(code)   # no interpreter teardown (numba, LLVM): the run waits for this exit\n")


class _StubPackages:
    """
    An import finder for the compiler process: the packages that hold the kernels' modules, empty.

    A kernel's module needs its own imports only; its packages' ``__init__`` import the rest
    of the package (``gongsynth.sun.rt`` the synthesis with scipy.signal and reproject,
    ``gongsynth.sun.model_atmosphere`` sunpy.map): ~1 s of CPU that a compiler spent before its
    first kernel.  Other packages are imported as they are.  A kernel module that needed a
    name of its package's ``__init__`` would fail to import here, and the run would compile
    its kernels itself (``tests/test_precompile.py`` imports the shipped list's modules so).

    Parameters
    ----------
    root : path-like
        The ``gongsynth`` package's folder.
    kernels : path-like
        The compile tasks (`KERNELS`): their modules' packages are the ones left empty.
    """

    def __init__(self, root, kernels):
        self.root = Path(root)
        self.packages = {module.rsplit(".", n)[0] for module in {t["module"] for t in load_kernels(kernels)}
                         for n in range(1, module.count("."))}

    def find_spec(self, name, path=None, target=None):
        import importlib.machinery

        if name not in self.packages:
            return None
        spec = importlib.machinery.ModuleSpec(name, self, is_package=True)
        spec.submodule_search_locations = [str(self.root.joinpath(*name.split(".")[1:]))]
        return spec

    def create_module(self, spec):
        return None          # the default module, its __path__ from the spec

    def exec_module(self, module):
        pass                 # no __init__ code


# A task's state in the queue file (one byte per task): free, claimed by compiler ``1 + n``, done.
_FREE, _DONE = 0, 255
# A file each compiler appends its tasks to (compiler, function, start and end time, CPU s): a diagnostic.
_LOG = "GONGSYNTH_PRECOMPILE_LOG"
# Seconds between two looks at the queue while the other compiler's task is needed first.
_POLL = 0.01

_lock = threading.Lock()
_jobs = []           # this process's compilers (`subprocess.Popen` or `_Forked`)
_started = [None]    # when they were started (`time.monotonic`)
_queue = [None]      # their queue file
_kernels = [None]    # their list (`KERNELS` read)
_said = [False, 0.0]  # "compiling kernels" logged; seconds waited


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
    The compile tasks, in queue order, as recorded in `KERNELS`.

    Parameters
    ----------
    path : path-like, optional
        Another list (default `KERNELS`).

    Returns
    -------
    list of dict
        Each ``{"module", "function", "signatures", "cpu_s", "calls"}``: the
        function's argument types as numba prints them (``"int64"``,
        ``"readonly array(float32, 3d, A)"``), one list per signature; its
        compile CPU seconds; the indices of the tasks it calls (earlier in the
        list).
    """
    return json.loads(Path(KERNELS if path is None else path).read_text())["tasks"]


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


def _workers():
    """How many compilers: `WORKERS` where there are two cores and file locks (they coordinate by them)."""
    try:
        import fcntl  # noqa: F401
    except ImportError:   # pragma: no cover - Windows
        return 1
    return WORKERS if (os.cpu_count() or 1) > 1 else 1


def start(kernels=None, *, fork=True):
    """
    Start compiling the tasks of ``kernels`` in background processes.

    Does nothing when switched off (`ENV`), when they are compiled already
    (`compiled`), or when this process's compilers run.

    Parameters
    ----------
    kernels : path-like, optional
        The list to compile (default `KERNELS`).
    fork : bool, optional
        Make the second compiler a fork of this process after it has imported
        the tasks' modules (where ``os.fork`` exists and this process runs one
        thread); otherwise, or when that fails, a new process like the first.

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
            folder = _cache_folder()                 # numba can cache here at all
            listed = json.loads(Path(kernels).read_text())
            tasks = listed["tasks"]
            folder.mkdir(parents=True, exist_ok=True)
            queue = folder / f"gongsynth-precompile-{os.getpid()}-{time.monotonic_ns()}.queue"
            queue.write_bytes(bytes(len(tasks)))
        except Exception:
            return False
        _queue[0], _kernels[0], _said[:] = queue, listed, [False, 0.0]
        _started[0] = time.monotonic()
        package = str(Path(__file__).resolve().parent)
        for worker in range(_workers()):
            job = _fork(tasks, kernels, worker, queue) if worker and fork else None
            try:
                _jobs.append(job or subprocess.Popen(
                    [sys.executable, "-c", _BOOT, package, kernels, str(worker), str(queue)],
                    stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
            except OSError:
                break
        return bool(_jobs)


class _Forked:
    """A forked compiler, with the `subprocess.Popen` methods `wait` uses."""

    def __init__(self, pid):
        self.pid, self.returncode = pid, None

    def poll(self):
        if self.returncode is None:
            try:
                pid, status = os.waitpid(self.pid, os.WNOHANG)
            except ChildProcessError:     # reaped elsewhere (SIGCHLD ignored): it has ended
                pid, status = self.pid, 0
            if pid:
                self.returncode = os.waitstatus_to_exitcode(status)
        return self.returncode

    def wait(self, timeout=None):
        end = None if timeout is None else time.monotonic() + timeout
        while self.poll() is None:
            if end is not None and time.monotonic() > end:
                raise subprocess.TimeoutExpired(f"compiler {self.pid}", timeout)
            time.sleep(_POLL)
        return self.returncode

    def kill(self):
        try:
            os.kill(self.pid, 9)
        except OSError:
            pass


def _fork(tasks, kernels, worker, queue):
    """A compiler forked from this process once it has imported the tasks' modules; None where it cannot."""
    if not hasattr(os, "fork") or sys.platform != "linux" or threading.active_count() > 1:
        return None
    try:
        import importlib

        from numba.core.registry import cpu_target

        for module in dict.fromkeys(task["module"] for task in tasks):
            importlib.import_module(module)
        cpu_target.target_context.refresh()      # numba's compiler set up: the run needs it too
        cpu_target.typing_context.refresh()
        pid = os.fork()
    except Exception:
        return None
    if pid:
        return _Forked(pid)
    code = 1   # pragma: no cover - the child (coverage does not follow it)
    try:       # pragma: no cover
        null = os.open(os.devnull, os.O_RDWR)
        for fd in (0, 1, 2):
            os.dup2(null, fd)
        code = _compile_here(kernels, worker, queue)
    finally:   # pragma: no cover - never the run's own exit handlers
        os._exit(code)


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


def wait(stage=None, *, progress=True):
    """
    Wait until this process's compilers have ended, or have compiled what ``stage`` needs
    (at most until `TIMEOUT` after their start).

    Parameters
    ----------
    stage : str, optional
        A stage of the chain (`gongsynth.chain.Stage.name`): wait only for the
        tasks that the README's run needed up to that stage (`KERNELS` records
        where each was needed first); not at all for a stage `KERNELS` does
        not know.  None: wait for the compilers to end.
    progress : bool
        Log "compiling kernels (first run only)" (sunpy's logger, level INFO) when it waits.

    Returns
    -------
    float
        Seconds waited (0 without compilers).
    """
    with _lock:
        jobs, queue, kernels = list(_jobs), _queue[0], _kernels[0]
    if not jobs:
        return 0.0
    need = None
    if stage is not None:
        try:
            stages = kernels["stages"]
            if stage not in stages:
                return 0.0
            need = [n for n, task in enumerate(kernels["tasks"])
                    if task["stage"] in stages[:stages.index(stage) + 1]]
        except (TypeError, KeyError, ValueError):
            return 0.0
    began = time.monotonic()
    logged = False
    while any(job.poll() is None for job in jobs) and not _done(queue, need):
        if progress and not _said[0]:
            from sunpy import log

            log.info("gongsynth: compiling kernels (first run only)")
            _said[0] = logged = True
        if time.monotonic() - _started[0] > TIMEOUT:
            for job in jobs:
                job.kill()
            break
        time.sleep(_POLL)
    waited = time.monotonic() - began
    _said[1] += waited
    if need is None or not any(job.poll() is None for job in jobs):
        with _lock:
            for job in jobs:
                job.wait()
            _jobs.clear()
            _queue[0] = None
        for path in (queue, Path(f"{queue}.entries")):
            try:
                path.unlink()
            except OSError:
                pass
        if progress and _said[0]:
            from sunpy import log

            log.info(f"gongsynth: kernels compiled ({_said[1]:.0f} s waited)")
    elif progress and logged:
        from sunpy import log

        log.info(f"gongsynth: the {stage} stage's kernels compiled ({waited:.0f} s waited)")
    return waited


def _done(queue, need):
    """Whether the tasks ``need`` (indices) are compiled (never for None: all compilers must end)."""
    if need is None:
        return False
    try:
        with open(queue, "rb") as file:
            state = file.read()
        return all(state[n] == _DONE for n in need)
    except (OSError, IndexError):
        return False


def _argument_type(text):
    """A numba type from its printed name (``int64``, ``readonly array(float32, 2d, C)``)."""
    from numba.core import types

    readonly = text.startswith("readonly ")
    text = text.removeprefix("readonly ")
    if text.startswith("array(") and text.endswith(")"):
        dtype, ndim, layout = (part.strip() for part in text[6:-1].split(","))
        return types.Array(getattr(types, dtype), int(ndim.removesuffix("d")), layout, readonly=readonly)
    return types.boolean if text == "bool" else getattr(types, text)


def _compile_here(kernels, worker, queue):
    """A compiler process: take tasks off the shared ``queue`` until none is left; record when whole."""
    # numba's compiler makes reference cycles by the million, and the garbage collector's passes over them
    # are ~17 % of its CPU (7.9 against 6.5 s for the kernel list); this process is brief (~0.1 GB more).
    gc.disable()
    import importlib

    folder = _cache_folder()
    folder.mkdir(parents=True, exist_ok=True)
    tasks = load_kernels(kernels)
    failed = 0
    with _turns(folder / f"gongsynth-precompile-{worker}.lock"):   # held while it compiles
        if compiled(kernels):
            return 0
        while (number := _claim(queue, tasks, worker, folder)) is not None:
            if number < 0:
                time.sleep(_POLL)      # the other compiler's task is needed first
                continue
            task = tasks[number]
            began = (time.time(), time.process_time())
            try:
                dispatcher = getattr(importlib.import_module(task["module"]), task["function"])
                for argtypes in task["signatures"]:
                    dispatcher.compile(tuple(_argument_type(t) for t in argtypes))
                _note(queue, number, dispatcher)
            except Exception:   # a stale entry: the run compiles that kernel itself
                failed += 1
            _set(queue, number, _DONE)
            if os.environ.get(_LOG):
                with open(os.environ[_LOG], "a") as log:
                    log.write(f"{worker} {task['function']} {began[0]:.3f} {time.time():.3f} "
                              f"{time.process_time() - began[1]:.3f}\n")
    with _turns(folder / "gongsynth-precompile.lock"):
        _record(folder, kernels, tasks, queue)
    return 1 if failed else 0


def _claim(queue, tasks, worker, folder):
    """
    Claim the first free task whose callees are compiled; None when no task is free, -1 when the
    free ones wait for the other compiler's tasks (or the first free one when that compiler has ended).
    """
    try:
        with _turns(queue) as held:
            state = bytearray(os.pread(held.file.fileno(), len(tasks), 0))
            free = [n for n, s in enumerate(state) if s == _FREE]
            if not free:
                return None
            ready = [n for n in free if all(state[c] == _DONE for c in tasks[n]["calls"])]
            if not ready:
                others = {state[c] - 1 for n in free for c in tasks[n]["calls"]
                          if state[c] not in (_FREE, _DONE)}
                if any(_alive(folder / f"gongsynth-precompile-{w}.lock") for w in others if w != worker):
                    return -1
            number = (ready or free)[0]
            os.pwrite(held.file.fileno(), bytes([1 + worker]), number)
            return number
    except OSError:
        return None


def _set(queue, number, value):
    """Write task ``number``'s state."""
    try:
        with _turns(queue) as held:
            os.pwrite(held.file.fileno(), bytes([value]), number)
    except OSError:
        pass


def _alive(path):
    """Whether a compiler holds its lock ``path`` (a free lock: it has ended)."""
    import fcntl

    with open(path, "a") as file:
        try:
            fcntl.flock(file, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            return True
        return False


class _turns:
    """An exclusive lock on a file (``fcntl.flock``; no lock where there is no fcntl)."""

    def __init__(self, path):
        self.path = path

    def __enter__(self):
        self.file = open(self.path, "r+b" if str(self.path).endswith(".queue") else "a")
        try:
            import fcntl

            fcntl.flock(self.file, fcntl.LOCK_EX)
        except ImportError:   # pragma: no cover - Windows
            pass
        return self

    def __exit__(self, *exc):
        self.file.close()      # releases the lock


def _note(queue, number, dispatcher):
    """
    Add task ``number``'s numba cache index, its source and the source's stamp to the queue's
    entries (``<queue>.entries``, a JSON line each): the record is written from them, without
    importing the other compiler's modules.
    """
    index = dispatcher._cache._cache_file._index_path
    source = dispatcher.py_func.__code__.co_filename
    st = os.stat(source)
    with _turns(queue):
        with open(f"{queue}.entries", "a") as file:
            file.write(json.dumps([number, index, source, [st.st_mtime, st.st_size]]) + "\n")


def _record(folder, kernels, tasks, queue):
    """Write `MANIFEST` when every task of ``tasks`` has an entry (`_note`) and its numba cache index."""
    import numba

    try:
        with _turns(queue):
            lines = Path(f"{queue}.entries").read_text().splitlines()
    except OSError:
        return
    found = {}
    for line in lines:
        number, index, source, stamp = json.loads(line)
        found[number] = (index, source, stamp)
    if sorted(found) != list(range(len(tasks))) or not all(os.path.exists(e[0]) for e in found.values()):
        return      # another compiler still works (it writes the record when it ends), or a task failed
    record = {"kernels": str(Path(kernels).resolve()), "python": list(sys.version_info[:2]),
              "numba": numba.__version__, "entries": [found[n] for n in range(len(tasks))]}
    tmp = folder / f"{MANIFEST}.{os.getpid()}"
    tmp.write_text(json.dumps(record))
    os.replace(tmp, folder / MANIFEST)
