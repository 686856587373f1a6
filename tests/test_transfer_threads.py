"""
The 3-D Sun's transfer by blocks (issue 26 item 4): the same bits for any thread count and block
size, on any wavelength grid.
"""
import astropy.units as u
import numba
import numpy as np
import pytest

import gongsynth
from gongsynth.sun.model_atmosphere import DeferredTransfer, model_sun


def test_blocks_on_a_given_grid_are_its_whole_synthesis():
    """``wavelength`` reaches every block: the cube is rt.synthesize's on that grid, bit for bit."""
    sun = model_sun((9, 8), 384 * u.km, seed=7, nz=24, spot=False)
    grid = gongsynth.rt.default_wavelength()[::3]
    deferred = DeferredTransfer(sun, mu=0.8, azimuth=-90 * u.deg, wavelength=grid.to(u.AA))
    assert deferred.wavelength.unit == u.nm and np.allclose(deferred.wavelength, grid, rtol=1e-15, atol=0)
    # On the grid the blocks use (nm back from Å may differ from ``grid`` in the last bit).
    whole = gongsynth.rt.synthesize(sun.atmosphere(), mu=0.8, azimuth=-90 * u.deg,
                                    wavelength=deferred.wavelength, progress=False)
    parts = [cube for _, cube in deferred.blocks(columns=3 * 8, halo_share=None)]
    assert parts[0].shape == (3, 8, 17) and deferred.shape == whole.shape
    for name in ("I", "V"):
        assert np.array_equal(np.concatenate([getattr(c, name).value for c in parts]),
                              getattr(whole, name).value)
    with pytest.raises(ValueError, match="does not cover the line"):
        DeferredTransfer(sun, mu=0.8, azimuth=-90 * u.deg, wavelength=[676.9, 677.0] * u.nm)


@pytest.mark.parametrize("mu", [0.7, 1.0])
def test_same_bits_for_any_threads_and_blocks(mu):
    """Blocks of 1, 3 or all rows, the canopy and the transfer on 1 or 2 threads: one result."""
    sun = model_sun((12, 10), 384 * u.km, seed=6, nz=32, spot=False)
    before = numba.get_num_threads()
    most = min(2, numba.config.NUMBA_NUM_THREADS)
    results = []
    try:
        for threads, rows in ((1, 12), (most, 1), (most, 3), (most, 12), (1, 3)):
            numba.set_num_threads(threads)
            sun.release()                      # the canopy made again on this thread count
            deferred = DeferredTransfer(sun, mu=mu, azimuth=-90 * u.deg)
            parts = list(deferred.blocks(columns=rows * 10, halo_share=None))
            results.append((np.concatenate([c.V.value for _, c in parts]),
                            np.concatenate([c.I.value for _, c in parts]), deferred.blos.value))
    finally:
        numba.set_num_threads(before)
    for other in results[1:]:
        for a, b in zip(results[0], other):
            assert np.array_equal(a, b)
