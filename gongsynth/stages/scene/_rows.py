"""
The tiled scene's row kernel (`~gongsynth.stages.scene.tiled`): a CSR matrix times a block of rows.

A module of its own that imports numba and numpy only: a first run's background compiler
(`gongsynth.precompile`) imports it without the scene's imports (sunpy.coordinates among them).
"""
import numba
import numpy as np

__all__ = ["sparse_rows"]


@numba.njit(inline="always", cache=True)
def _row(indptr, indices, weights, first, narrow, out, r, row):
    """``out[r] = Σ_k weights[k] narrow[indices[k]]`` over CSR row ``first + r`` (sums in ``row``)."""
    row[:] = 0.0
    for k in range(indptr[first + r], indptr[first + r + 1]):
        w = weights[k]
        src = narrow[indices[k]]
        for c in range(out.shape[1]):
            row[c] += w * src[c]
    for c in range(out.shape[1]):
        out[r, c] = row[c]


@numba.njit(cache=True, nogil=True)
def sparse_rows(start, stop, indptr, indices, weights, first, narrow, out):
    """`_row` for rows ``start`` to ``stop`` of ``out`` (`~gongsynth.threads.run_chunks`)."""
    row = np.empty(out.shape[1])
    for r in range(start, stop):
        _row(indptr, indices, weights, first, narrow, out, r, row)
