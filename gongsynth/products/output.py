"""
Writing a simulation's products to disk as one set: FITS maps, raw planes, the
run configuration and a PNG quick-look, complete or not at all.

A run's folder is written as a whole.  Every file goes into a hidden staging
folder first; only when all of them are complete does the set take the
folder's place:

* a new folder, or one that holds nothing but an earlier gongsynth set, is
  replaced by renaming the staging folder, a sibling
  ``.NAME.gongsynth-HOST-PID-XXXX.tmp``, onto it (on Linux one atomic exchange
  of the two folders; elsewhere two renames), and the old set is deleted
  afterwards.  Anyone looking at ``NAME`` sees the complete old set or the
  complete new one, never a mixture;
* a folder that also holds other files (``--out .``) keeps them: the staging
  folder is made inside it and the finished files are moved in by rename, with
  Ctrl-C held back for those few renames.  A run killed outright between two
  of them leaves a marked staging folder that the next save into the folder
  completes first.

An exception or Ctrl-C while writing deletes the staging folder and leaves the
old set untouched.  Leftovers of runs that were killed (staging folders of a
process that no longer runs, ``.part`` files of earlier versions) are cleaned
by the next save into the same place (`clean_leftovers`).
"""
import contextlib
import ctypes
import ctypes.util
import errno
import os
import re
import shutil
import signal
import socket
import tempfile
import threading
from pathlib import Path

from astropy.io import fits

from gongsynth.files import check_writable

__all__ = ["save_result", "planned_files", "check_output_folder", "clean_leftovers", "PRODUCT_FILES",
           "SET_FILES"]

#: File name of each map product.
PRODUCT_FILES = {
    "magnetogram": "magnetogram.fits",
    "doppler": "doppler.fits",
    "continuum": "continuum.fits",
    "truth": "truth.fits",
    "truth_psf": "truth_psf.fits",
}
RAW_FILE = "raw.fits"
CONFIG_FILE = "config.toml"
QUICKLOOK_FILE = "quicklook.png"

#: Every file name an output set can hold.
SET_FILES = (*PRODUCT_FILES.values(), RAW_FILE, CONFIG_FILE, QUICKLOOK_FILE)

_TAG = ".gongsynth-"
# Staging and old-set folders: .NAME.gongsynth-HOST-PID-RANDOM.tmp|.old (siblings) or
# .gongsynth-HOST-PID-RANDOM.tmp (inside a folder with other files).
_LEFTOVER = re.compile(r"^(?:\.(?P<name>.+))?\.gongsynth-(?P<host>[A-Za-z0-9_-]*)-(?P<pid>\d+)-[^.]+\."
                       r"(?P<kind>tmp|old)$")
# Marks a staging folder inside a shared folder whose files are being moved in.
_COMMITTING = "COMMITTING"


def planned_files(directory, *, quicklook=True, truth=True):
    """
    The files `save_result` writes into ``directory`` (to check them before a long run).

    Parameters
    ----------
    directory : path-like
    quicklook : bool
    truth : bool
        Whether the result has ground-truth maps.

    Returns
    -------
    list of `pathlib.Path`

    Examples
    --------
    >>> [p.name for p in planned_files("run", quicklook=False, truth=False)]
    ['magnetogram.fits', 'doppler.fits', 'continuum.fits', 'raw.fits', 'config.toml']
    """
    directory = Path(directory)
    names = [f for k, f in PRODUCT_FILES.items() if truth or not k.startswith("truth")]
    names += [RAW_FILE, CONFIG_FILE] + ([QUICKLOOK_FILE] if quicklook else [])
    return [directory / n for n in names]


def check_output_folder(directory, *, overwrite=False, name="directory"):
    """
    Refuse, before any work, an output folder that cannot take a new set.

    Leftovers of killed runs are cleaned first (`clean_leftovers`), so a
    finished but interrupted set is completed and counts as existing.

    Parameters
    ----------
    directory : path-like
    overwrite : bool
        Whether an existing set may be replaced.
    name : str
        How messages name the folder (``"--out run"`` on the command line).

    Raises
    ------
    NotADirectoryError
        ``directory`` is a file.
    PermissionError
        Nothing can be created in it (or in its nearest existing parent).
    FileExistsError
        It holds products and ``overwrite`` is false.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> check_output_folder(pathlib.Path(tempfile.mkdtemp()) / "new-run")   # fine: nothing there
    """
    directory = Path(directory)
    if directory.exists() and not directory.is_dir():
        raise NotADirectoryError(f"{name} {directory} is a file, not a folder")
    existing = directory
    while not existing.exists():
        existing = existing.parent
    if not os.access(existing, os.W_OK | os.X_OK):
        raise PermissionError(f"{name} {directory}: cannot write in {existing} (permission denied)")
    clean_leftovers(directory)
    check_writable([directory / n for n in SET_FILES], overwrite)


def save_result(result, directory, *, overwrite=False, quicklook=True):
    """
    Write a `~gongsynth.pipeline.SimulationResult` into ``directory``, as one set.

    Nothing is written if the folder holds products and ``overwrite`` is
    false.  The files are written into a staging folder and take the place
    of any old set only when all are complete (see the module notes): an
    error or Ctrl-C on the way leaves the old set as it was, and no partial
    file anywhere.  With ``overwrite`` the old set is replaced as a whole, so
    products of two runs never sit side by side.

    Parameters
    ----------
    result : `~gongsynth.pipeline.SimulationResult`
    directory : path-like
        Created if missing.
    overwrite : bool
        Replace an existing set.
    quicklook : bool
        Also write a PNG of the products (`gongsynth.products.quicklook.quicklook_figure`).

    Returns
    -------
    list of `pathlib.Path`
        The files of the new set.

    Raises
    ------
    FileExistsError
        If the folder holds products and ``overwrite`` is false.
    OSError
        From the writers (a full disk, a folder that cannot be written); the
        old set is then untouched.

    Examples
    --------
    >>> import tempfile
    >>> import astropy.units as u
    >>> from gongsynth import simulate
    >>> result = simulate(duration=1 * u.min, detector_shape=16, resolutions=(1,), seed=1,
    ...                   photosphere_shape=(64, 64), photosphere_pixel_size=1536 * u.km,
    ...                   sun="milne-eddington", progress=False)
    >>> paths = save_result(result, tempfile.mkdtemp(), quicklook=False)
    >>> sorted(p.name for p in paths)[:3]
    ['config.toml', 'continuum.fits', 'doppler.fits']
    """
    directory = Path(directory)
    names = [p.name for p in planned_files(directory, quicklook=quicklook, truth=result.truth is not None)]
    check_output_folder(directory, overwrite=overwrite)
    swap = _can_swap(directory)
    stage = _make_stage(directory, inside=not swap)
    try:
        _write_set(result, stage, quicklook)
        if not overwrite:  # a set that appeared while we were writing
            check_writable([directory / n for n in SET_FILES], overwrite)
        with _ctrl_c_held():
            if swap:
                _swap_in(stage, directory)
            else:
                _move_in(stage, directory, names)
    finally:
        shutil.rmtree(stage, ignore_errors=True)  # the staging folder, or the old set after a swap
    return [directory / n for n in names]


def _write_set(result, stage, quicklook):
    """Every file of the set into the (empty) staging folder."""
    for name, filename in PRODUCT_FILES.items():
        smap = getattr(result, name)
        if smap is not None:
            fits.PrimaryHDU(smap.data, fits.Header(smap.fits_header)).writeto(stage / filename)
    result.raw.to_fits(stage / RAW_FILE)
    (stage / CONFIG_FILE).write_text(result.config.to_toml())
    if quicklook:
        from gongsynth.products.quicklook import quicklook_figure

        # zlib's fastest level: 0.12 s less of a ~6-s default run for a file 3 % larger.
        quicklook_figure(result).savefig(stage / QUICKLOOK_FILE, format="png", dpi=110,
                                         pil_kwargs={"compress_level": 1})


# ------------------------------------------------------------------ the commit
def _can_swap(directory):
    """Whether the whole folder can be replaced: new, or holding nothing but a set (and leftovers)."""
    if not directory.exists():
        return True
    resolved = directory.resolve()
    if resolved == Path.cwd() or resolved.parent == resolved or not os.access(resolved.parent, os.W_OK):
        return False
    return all(p.name in SET_FILES or _is_leftover_name(p.name) for p in directory.iterdir())


def _is_leftover_name(filename):
    return bool(_LEFTOVER.match(filename)) or (filename.startswith(".") and ".part" in filename
                                               and filename[1:].split(".part")[0].rsplit(".", 1)[0]
                                               in SET_FILES)


def _host():
    return re.sub(r"[^A-Za-z0-9_]", "_", socket.gethostname())[:40]


def _make_stage(directory, *, inside):
    """A new, empty staging folder: a hidden sibling of ``directory``, or hidden inside it."""
    if inside:
        return Path(tempfile.mkdtemp(prefix=f"{_TAG}{_host()}-{os.getpid()}-", suffix=".tmp",
                                     dir=directory))
    parent = directory.resolve().parent
    parent.mkdir(parents=True, exist_ok=True)
    stage = Path(tempfile.mkdtemp(prefix=f".{directory.name}{_TAG}{_host()}-{os.getpid()}-",
                                  suffix=".tmp", dir=parent))
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(stage, 0o777 & ~umask)  # mkdtemp makes it private; the set gets a normal folder's mode
    return stage


def _swap_in(stage, directory):
    """Put the staging folder in ``directory``'s place; afterwards ``stage`` holds the old set (if any)."""
    directory = directory.resolve() if directory.exists() else directory.absolute()
    if not directory.exists():
        try:
            os.rename(stage, directory)
        except OSError as err:
            if err.errno in (errno.EEXIST, errno.ENOTEMPTY):
                raise FileExistsError(f"{directory} appeared while the set was being written") from err
            raise
        return
    if _exchange(stage, directory):
        return
    # No atomic exchange here: two renames, the old set kept aside until the new one is in.
    old = stage.with_name(stage.name[:-len(".tmp")] + ".old")
    os.rename(directory, old)
    try:
        os.rename(stage, directory)
    except BaseException:
        os.rename(old, directory)
        raise
    os.rename(old, stage)


_RENAME_EXCHANGE = 2


def _exchange(a, b):
    """Atomically exchange two paths (Linux renameat2); False where the system cannot."""
    libc_name = ctypes.util.find_library("c")
    if libc_name is None:
        return False
    try:
        libc = ctypes.CDLL(libc_name, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    at_fdcwd = -100
    if renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP):
        return False  # not supported by this kernel or file system
    raise OSError(err, os.strerror(err), str(b))


def _move_in(stage, directory, names):
    """Move the finished files from a staging folder inside ``directory`` into it (renames only)."""
    (stage / _COMMITTING).write_text("\n".join(names) + "\n")
    _finish_moves(stage, directory)


def _finish_moves(stage, directory):
    """Move every set file left in ``stage`` into ``directory`` and delete the old set's other files."""
    names = (stage / _COMMITTING).read_text().split()
    for filename in names:
        if (stage / filename).exists():
            os.replace(stage / filename, directory / filename)
    for filename in SET_FILES:
        if filename not in names and (directory / filename).exists():
            (directory / filename).unlink()  # the old set's: no products of two runs side by side
    shutil.rmtree(stage, ignore_errors=True)


@contextlib.contextmanager
def _ctrl_c_held():
    """
    Hold back SIGINT (Ctrl-C) and SIGTERM for the block, then raise KeyboardInterrupt if one came
    (a SIGTERM: through the handler it had, e.g. the command line's).
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught = []
    previous = {sig: signal.signal(sig, lambda signum, frame: caught.append(signum))
                for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    if signal.SIGTERM in caught and callable(previous[signal.SIGTERM]):
        previous[signal.SIGTERM](signal.SIGTERM, None)
    if caught:
        raise KeyboardInterrupt


# ------------------------------------------------------------------ leftovers
def clean_leftovers(directory):
    """
    Remove what killed saves into ``directory`` left behind.

    * staging and old-set folders of a process of this machine that no longer
      runs: a staging folder whose files were being moved in is completed
      (the set it holds is whole), any other is deleted; an old set kept aside
      while ``directory`` itself is missing is put back;
    * hidden ``.part`` files of product names inside ``directory`` (written
      by earlier gongsynth versions, which wrote file by file).

    Folders of runs still going, or of other machines, are left alone.

    Parameters
    ----------
    directory : path-like
        An output folder (it need not exist).

    Returns
    -------
    list of `pathlib.Path`
        What was removed, completed or restored.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp()) / "run"
    >>> folder.mkdir()
    >>> _ = (folder / ".raw.fits.x1y2z3.part.fits").write_bytes(b"")   # a killed write
    >>> [p.name for p in clean_leftovers(folder)]
    ['.raw.fits.x1y2z3.part.fits']
    """
    directory = Path(directory)
    handled = []
    parent = directory.absolute().parent
    places = [(parent, directory.name)] + ([(directory, None)] if directory.is_dir() else [])
    for place, owner in places:
        if not place.is_dir():
            continue
        for path in sorted(place.iterdir()):
            match = _LEFTOVER.match(path.name)
            if match is None or match.group("name") != owner or not _is_dead(match):
                continue
            if match.group("kind") == "old" and not directory.exists():
                os.rename(path, directory)  # killed between the two renames of a swap
            elif owner is None and (path / _COMMITTING).exists():
                _finish_moves(path, directory)
            else:
                shutil.rmtree(path, ignore_errors=True)
            handled.append(path)
    if directory.is_dir():
        for path in sorted(directory.iterdir()):
            if path.is_file() and path.name.startswith(".") and _is_leftover_name(path.name) \
                    and not _LEFTOVER.match(path.name):
                path.unlink()
                handled.append(path)
    return handled


def _is_dead(match):
    """Whether the process that made a leftover (this machine only) no longer runs."""
    if match.group("host") != _host():
        return False
    pid = int(match.group("pid"))
    if pid == os.getpid():
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except PermissionError:
        return False  # someone else's live process
    return False
