"""
Atomic, non-clobbering file output, and fingerprints of input files.

Every file gongsynth writes goes to a temporary name in the destination
directory and is renamed into place only once complete, so an interrupted
write never leaves a half-written product; existing files are only replaced
when the caller asks for it.  The temporary name keeps the destination's
suffix, so writers that choose the format from it (``GenericMap.save``,
``Figure.savefig``, astropy's ``.gz`` compression) write what the final name says.
"""
import hashlib
import os
import tempfile
from contextlib import contextmanager
from pathlib import Path

import astropy.units as u
import numpy as np

__all__ = ["atomic_path", "check_writable", "fingerprint"]


def check_writable(paths, overwrite):
    """
    Refuse to go on if any of ``paths`` exists and ``overwrite`` is false.

    Parameters
    ----------
    paths : iterable of path-like
    overwrite : bool

    Raises
    ------
    FileExistsError
        Naming every file that would be overwritten.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> existing = pathlib.Path(tempfile.mkdtemp()) / "m.fits"
    >>> _ = existing.write_bytes(b"")
    >>> check_writable([existing], overwrite=True)   # allowed
    >>> check_writable([existing], overwrite=False)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    FileExistsError: refusing to overwrite existing file(s) [...]; pass overwrite=True ...
    """
    existing = [str(p) for p in map(Path, paths) if p.exists()]
    if existing and not overwrite:
        raise FileExistsError(
            f"refusing to overwrite existing file(s) {existing}; pass overwrite=True "
            "(or --overwrite on the command line) to replace them"
        )


@contextmanager
def atomic_path(path, *, overwrite=False):
    """
    Context manager yielding a temporary path that becomes ``path`` on success.

    Parameters
    ----------
    path : path-like
        Final destination.
    overwrite : bool
        Replace an existing file.

    Yields
    ------
    `pathlib.Path`
        Write the complete file here; it is renamed to ``path`` when the block
        exits without an exception, and deleted otherwise.  A hidden name in
        the same folder, ``.NAME.XXXXXXXX.part.SUFFIX``, ending in the suffix of ``path``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> target = pathlib.Path(tempfile.mkdtemp()) / "out.txt"
    >>> with atomic_path(target) as tmp:
    ...     _ = tmp.write_text("done")
    >>> target.read_text()
    'done'
    >>> with atomic_path(target.with_name("map.fits")) as tmp:
    ...     tmp.name.startswith(".map.fits.") and tmp.name.endswith(".part.fits")
    True
    """
    path = Path(path)
    check_writable([path], overwrite)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=f".part{path.suffix}", dir=path.parent)
    os.close(fd)
    tmp = Path(tmp)
    # mkstemp makes the file private (0600); give it the permissions of a normal new file.
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)
    try:
        yield tmp
        if not overwrite and path.exists():  # appeared while we were writing
            raise FileExistsError(f"refusing to overwrite {path}, which appeared during the write")
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def fingerprint(data):
    """
    SHA-256 of a file, of a folder's files (names and contents), or of an array (values and unit).

    Parameters
    ----------
    data : path-like, array_like or `~astropy.units.Quantity`

    Returns
    -------
    str
        Hex digest.

    Examples
    --------
    >>> fingerprint([1.0, 2.0]) == fingerprint(np.array([1.0, 2.0]))
    True
    """
    digest = hashlib.sha256()
    if isinstance(data, (str, Path)) and Path(data).is_dir():   # a folder (a MURaM snapshot): its files
        for path in sorted(p for p in Path(data).rglob("*") if p.is_file()):
            digest.update(path.relative_to(data).as_posix().encode())
            digest.update(fingerprint(path).encode())
        return digest.hexdigest()
    if isinstance(data, (str, Path)):
        with open(data, "rb") as handle:
            for block in iter(lambda: handle.read(1 << 20), b""):
                digest.update(block)
        return digest.hexdigest()
    unit = data.unit.to_string() if isinstance(data, u.Quantity) else ""
    values = np.ascontiguousarray(u.Quantity(data).value if unit else np.asarray(data), dtype=np.float64)
    digest.update(repr(values.shape).encode())
    digest.update(values.tobytes())
    digest.update(unit.encode())
    return digest.hexdigest()
