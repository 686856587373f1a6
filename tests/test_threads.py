"""`gongsynth.threads.run_chunks`: every index once, on the threads numba is allowed, errors raised."""
import threading

import numba
import numpy as np
import pytest

from gongsynth.threads import CHUNKS_PER_THREAD, run_chunks


def _counting_kernel():
    seen = []
    names = set()

    def kernel(start, stop, out):
        seen.append((start, stop))
        names.add(threading.current_thread().name)
        out[start:stop] += 1

    return kernel, seen, names


@pytest.mark.parametrize("threads", [1, 2])
@pytest.mark.parametrize("n", [0, 1, 7, 1000])
def test_every_index_exactly_once(n, threads):
    if threads > numba.config.NUMBA_NUM_THREADS:
        pytest.skip("needs NUMBA_NUM_THREADS >= 2")
    kernel, seen, names = _counting_kernel()
    out = np.zeros(n, dtype=np.int64)
    previous = numba.get_num_threads()
    numba.set_num_threads(threads)
    try:
        run_chunks(kernel, n, out)
    finally:
        numba.set_num_threads(previous)
    np.testing.assert_array_equal(out, 1)
    assert len(seen) == (0 if n == 0 else 1 if threads == 1 else min(n, threads * CHUNKS_PER_THREAD))
    assert all(stop > start for start, stop in seen)
    if threads == 1:
        assert names <= {threading.current_thread().name}   # no pool for one thread


def test_small_work_stays_on_the_calling_thread():
    kernel, seen, names = _counting_kernel()
    run_chunks(kernel, 100, np.zeros(100), min_chunk=1024)
    assert seen == [(0, 100)] and names == {threading.current_thread().name}


def test_an_error_in_a_chunk_is_raised():
    def kernel(start, stop):
        if start > 0:
            raise ValueError("chunk failed")

    previous = numba.get_num_threads()
    numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
    try:
        with pytest.raises(ValueError, match="chunk failed"):
            run_chunks(kernel, 10) if numba.get_num_threads() > 1 else kernel(1, 2)
    finally:
        numba.set_num_threads(previous)
