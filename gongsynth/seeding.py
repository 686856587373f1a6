"""
Reproducible random streams.

gongsynth never touches global random state.  Every stochastic stage receives
a `numpy.random.SeedSequence` and spawns children from it by *name* (the stage)
and *index* (the chunk), so that the numbers a pixel receives do not depend on
how the work was chunked, on the number of threads, or on the number of Dask
workers.
"""
import hashlib

import numpy as np

__all__ = ["as_seed_sequence", "child_sequence", "stage_generator", "root_seed"]


def as_seed_sequence(seed):
    """
    Turn a user seed into a `numpy.random.SeedSequence`.

    Parameters
    ----------
    seed : None, int, `numpy.random.SeedSequence` or `numpy.random.Generator`
        ``None`` draws fresh entropy (recorded, so the run can be repeated);
        a Generator contributes one 128-bit draw from its stream.

    Returns
    -------
    `numpy.random.SeedSequence`

    Examples
    --------
    >>> as_seed_sequence(42).entropy
    42
    """
    if isinstance(seed, np.random.SeedSequence):
        return seed
    if isinstance(seed, np.random.Generator):
        return np.random.SeedSequence(int(seed.integers(0, 2**63)) << 64
                                      | int(seed.integers(0, 2**63)))
    if seed is None:
        return np.random.SeedSequence()
    if isinstance(seed, (int, np.integer)) and not isinstance(seed, bool) and seed >= 0:
        return np.random.SeedSequence(int(seed))
    raise TypeError(
        f"seed must be None, a non-negative int, a numpy SeedSequence or Generator; got {seed!r}"
    )


def _name_key(name):
    """A stable 32-bit integer for a stage name (Python's hash() is salted)."""
    return int.from_bytes(hashlib.sha256(name.encode()).digest()[:4], "little")


def child_sequence(seed, name, *index):
    """
    The SeedSequence of one named stage and (optionally) one chunk of it.

    Parameters
    ----------
    seed : seed-like
        Anything `as_seed_sequence` accepts.
    name : str
        Stage name, e.g. ``"camera"`` or ``"photosphere"``.
    *index : int
        Chunk coordinates (non-negative ints), e.g. the index of a pixel block.

    Returns
    -------
    `numpy.random.SeedSequence`
        Depends only on the root entropy, the root's spawn key, ``name`` and
        ``index``: never on the order in which children were requested.

    Examples
    --------
    >>> a = child_sequence(7, "camera", 3).generate_state(1)
    >>> b = child_sequence(7, "camera", 3).generate_state(1)
    >>> bool((a == b).all()), bool((a != child_sequence(7, "camera", 4).generate_state(1)).all())
    (True, True)
    """
    root = as_seed_sequence(seed)
    key = tuple(root.spawn_key) + (_name_key(name),) + tuple(int(i) for i in index)
    return np.random.SeedSequence(root.entropy, spawn_key=key)


def stage_generator(seed, name, *index):
    """
    A `numpy.random.Generator` (PCG64) for one stage / chunk; see `child_sequence`.

    Parameters
    ----------
    seed : seed-like
        Anything `as_seed_sequence` accepts.
    name : str
        Stage name.
    *index : int
        Chunk coordinates.

    Returns
    -------
    `numpy.random.Generator`

    Examples
    --------
    >>> a = stage_generator(1, "camera", 0).normal()
    >>> b = stage_generator(1, "camera", 0).normal()
    >>> a == b
    True
    """
    return np.random.Generator(np.random.PCG64(child_sequence(seed, name, *index)))


def root_seed(seed):
    """
    The run's root seed as a non-negative int, drawing fresh entropy for None.

    An int is kept as it is; anything else (None, a `numpy.random.SeedSequence`
    or `numpy.random.Generator`) is reduced to 63 bits of its state, so it fits
    a FITS header and a config file and the run can be repeated from them.

    Parameters
    ----------
    seed : seed-like
        Anything `as_seed_sequence` accepts.

    Returns
    -------
    int

    Examples
    --------
    >>> root_seed(12)
    12
    >>> 0 <= root_seed(None) < 2**63
    True
    """
    if isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
        return int(as_seed_sequence(seed).entropy)
    state = as_seed_sequence(seed).generate_state(2, dtype="uint32").astype(object)
    return int(state.dot([1, 2**32])) & (2**63 - 1)
