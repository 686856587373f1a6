"""
Row-parallel numba kernels on Python threads.

A kernel compiled with ``parallel=True`` costs several times the compile time
of the same loop compiled serially (numba builds, types and optimises a
gufunc for each ``prange``), and a user's first run pays it for every kernel
(issue 26).  gongsynth's loop kernels are therefore serial, ``nogil=True``
functions of a half-open range ``(start, stop)`` of their outer index, and
`run_chunks` hands contiguous chunks of that range to a thread pool of
`numba.get_num_threads` threads (``NUMBA_NUM_THREADS``).  Each index's result
must depend on that index's data only; then the output is the same, bit for
bit, for any number of threads.
"""
from concurrent.futures import ThreadPoolExecutor

import numba

__all__ = ["run_chunks", "CHUNKS_PER_THREAD"]

#: Chunks per thread: more than one balances rows of unequal cost.
CHUNKS_PER_THREAD = 4


def run_chunks(kernel, n, *args, min_chunk=1):
    """
    Call ``kernel(start, stop, *args)`` over the chunks of ``range(n)``, on threads.

    Parameters
    ----------
    kernel : numba dispatcher
        A ``nogil=True`` kernel whose first two arguments are the range of its
        outer index (``start`` included, ``stop`` excluded); it must write
        each index's result from that index's data only.
    n : int
        Length of the outer index.
    *args
        The kernel's remaining arguments (shared by every chunk).
    min_chunk : int, optional
        Fewest indices per chunk (work too small to be worth a thread stays on
        the calling thread).

    Examples
    --------
    >>> import numba, numpy as np
    >>> @numba.njit(nogil=True)
    ... def square(start, stop, x, out):
    ...     for i in range(start, stop):
    ...         out[i] = x[i] * x[i]
    >>> x = np.arange(10.0); out = np.empty(10)
    >>> run_chunks(square, 10, x, out)
    >>> out[:4].tolist()
    [0.0, 1.0, 4.0, 9.0]
    """
    n = int(n)
    threads = min(numba.get_num_threads(), max(1, n // max(1, min_chunk)))
    if threads <= 1:
        if n > 0:
            kernel(0, n, *args)
        return
    count = min(n, threads * CHUNKS_PER_THREAD)
    bounds = [n * c // count for c in range(count + 1)]
    with ThreadPoolExecutor(max_workers=threads) as pool:
        for _ in pool.map(lambda c: kernel(bounds[c], bounds[c + 1], *args), range(count)):
            pass
