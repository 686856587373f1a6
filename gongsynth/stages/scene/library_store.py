"""
The patch library's disk store: folders written whole or not at all, and arrays derived from a library.

`gongsynth.stages.scene.library.cached_library` keeps each library in a folder named by its key;
`derived_arrays` keeps what is computed from a cached library (HMI's reduced render rows,
`gongsynth.stages.scene.disk_render.render_rows`) inside that folder, so that it goes with it.
"""
import hashlib
import json
import os
import shutil
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from gongsynth.files import fingerprint

__all__ = ["CacheWarning", "warn_cache", "write_folder", "derived_arrays"]

# Temporary folders of a write are "<folder>.tmp-<pid>-<random>"; one older than this whose process is
# gone (or older than an hour: another machine's) was left by a killed write.
_STALE_SECONDS = 60.0


class CacheWarning(UserWarning):
    """The library cache could not be used (unwritable, or a damaged entry): the run goes on without it."""


def warn_cache(message):
    """Warn (a `CacheWarning`) at the caller of the function that calls this."""
    warnings.warn(message, CacheWarning, stacklevel=3)


def _clean_stale(parent, pattern):
    """Remove the temporary folders of killed writes (another process's live one is left alone)."""
    for tmp in parent.glob(pattern):
        try:
            age = time.time() - tmp.stat().st_mtime
            pid = int(tmp.name.split(".tmp-")[1].split("-")[0])
        except (OSError, ValueError, IndexError):
            continue
        if age > 3600 or (age > _STALE_SECONDS and not _alive(pid)):
            shutil.rmtree(tmp, ignore_errors=True)


def _alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:     # exists, another user's
        return True
    return True


def write_folder(folder, fill, stale):
    """
    Write a cache folder whole or not at all, replacing a damaged one of the same name.

    Parameters
    ----------
    folder : `pathlib.Path`
    fill : callable
        ``fill(tmp)`` writes the files into a temporary folder beside ``folder``, which then takes
        its name (a rename: readers see the old folder or the new one, never a part).
    stale : str
        Glob of the folder names whose temporary folders, left by killed writes, are removed on the way.

    Raises
    ------
    OSError
        Where it cannot be written (the temporary folder is removed).
    """
    folder.parent.mkdir(parents=True, exist_ok=True)
    _clean_stale(folder.parent, f"{stale}.tmp-*")
    tmp = Path(tempfile.mkdtemp(prefix=f"{folder.name}.tmp-{os.getpid()}-", dir=folder.parent))
    try:
        fill(tmp)
        if folder.exists():   # a damaged folder: moved aside, then removed
            old = Path(tempfile.mkdtemp(prefix=f"{folder.name}.tmp-{os.getpid()}-", dir=folder.parent))
            folder.rename(old / "entry")
            shutil.rmtree(old, ignore_errors=True)
        tmp.rename(folder)
    except OSError:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def derived_arrays(library, name, compute, key):
    """
    Arrays derived from a library, computed once and kept in its cache entry (`cached_library`).

    An entry's folder is named by the library's key (its arguments, gongsynth's version and the
    source of every module that shapes its numbers) and is removed with the entry, so what is kept in
    it belongs to that library alone; ``key`` names everything else the arrays depend on (parameters,
    the source of the code that computes them), so that a change of either computes them again.  The
    files are written atomically with their SHA-256, checked when read: a damaged or unwritable copy
    is computed again (a `CacheWarning`).  A library not in the cache is computed every time.

    Parameters
    ----------
    library : `PatchLibrary`
    name : str
        What the arrays are (a folder name's prefix).
    compute : callable
        ``compute()`` → dict of `numpy.ndarray` (float or int).
    key : iterable of str or bytes
        What else the arrays depend on.

    Returns
    -------
    dict
        The arrays (read back from the cache, or just computed).

    Examples
    --------
    >>> import astropy.units as u, numpy as np
    >>> from gongsynth.stages.scene.library import build_library
    >>> lib = build_library(shape=(16, 16), pixel_size=6 * u.Mm, seeds_per_level=(1, 1, 1, 1), theta=(0, 60))
    >>> derived_arrays(lib, "mean", lambda: {"mean": lib.patches.mean(axis=(1, 2))}, ["v1"])["mean"].shape
    (4, 2, 24)
    """
    cache = library.meta.get("cache")
    if cache is None:
        return compute()
    digest = hashlib.sha256()
    for part in key:
        digest.update(part if isinstance(part, bytes) else str(part).encode())
        digest.update(b"\0")
    folder = Path(cache) / f"{name}-{digest.hexdigest()[:24]}"
    if (folder / "arrays.json").is_file():
        try:
            sums = json.loads((folder / "arrays.json").read_text())["sha256"]
            arrays = {}
            for file, checksum in sums.items():
                if fingerprint(folder / file) != checksum:
                    raise ValueError(f"{file} does not match its checksum")
                arrays[file[:-4]] = np.load(folder / file)
            return arrays
        except (OSError, ValueError, KeyError, TypeError) as exc:
            warn_cache(f"the cached {name} arrays in {folder} are damaged ({exc}); they are computed again")
    arrays = compute()

    def fill(tmp):
        for key_name, array in arrays.items():
            np.save(tmp / f"{key_name}.npy", np.asarray(array))
        (tmp / "arrays.json").write_text(json.dumps(
            {"sha256": {p.name: fingerprint(p) for p in sorted(tmp.glob("*.npy"))}}))

    try:
        write_folder(folder, fill, f"{name}-*")
    except OSError as exc:
        if not (folder / "arrays.json").is_file():   # not another process's copy that won the race
            warn_cache(f"could not keep the {name} arrays in the cache {folder.parent} "
                       f"({exc.strerror or exc}); they are computed again next time")
    return arrays
