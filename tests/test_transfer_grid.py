"""
The 3-D Sun's transfer for GONG on `channel_wavelength` (39 of the default 51 wavelengths) and by
blocks on threads (issue 26 item 4): the channel integrals unchanged within 1e-4, the same bits for
any thread count and block size.
"""
import astropy.units as u
import numba
import numpy as np
import pytest

import gongsynth
from gongsynth.stages import channels
from gongsynth.sun.model_atmosphere import DeferredTransfer, model_sun
from gongsynth.sun.model_atmosphere.transfer import CORE_HALF_WIDTH, channel_wavelength


def test_channel_wavelength_is_the_default_grid_thinned_in_the_wings():
    full = gongsynth.rt.default_wavelength().to_value(u.nm)
    grid = channel_wavelength().to_value(u.nm)
    assert grid.size == 39 and np.isin(grid, full).all()             # the same floats, where kept
    lam0 = full[full.size // 2]
    core = np.abs(full - lam0) <= CORE_HALF_WIDTH + 1e-9
    assert np.isin(full[core], grid).all()                           # every core point kept
    assert grid[0] == full[0] and grid[-1] == full[-1]               # the same window
    steps = np.diff(grid) * 1e3
    inside = np.abs(grid - lam0) <= CORE_HALF_WIDTH + 1e-9
    np.testing.assert_allclose(steps[inside[1:] & inside[:-1]], 2.0, rtol=1e-6)
    np.testing.assert_allclose(steps[~(inside[1:] & inside[:-1])], 4.0, rtol=1e-6)


def test_gong_run_synthesises_channel_wavelength():
    """The chain's synthesis stage hands the channels stage a transfer on the GONG grid."""
    from gongsynth.chain import build_chain
    from gongsynth.config import SimulationConfig
    config = SimulationConfig(seed=1, photosphere_shape=(16, 16), duration=1 * u.min)
    chain = build_chain(config)
    state = {"photosphere": model_sun((16, 16), 384 * u.km, seed=1, nz=32, spot=False)}
    stokes = next(s for s in chain if s.name == "synthesis")(state)["stokes"]
    assert isinstance(stokes, DeferredTransfer)
    assert np.array_equal(stokes.wavelength, channel_wavelength())
    build_chain(config, stokes=stokes)    # handed back to a run: its own grid is not refused
    with pytest.raises(ValueError, match="steps of up to 4.00 pm"):
        build_chain(config, stokes=stokes.cube())     # as a plain cube it is (the rule for any cube)


def test_channel_integrals_on_channel_wavelength_within_1e_4():
    """A 3-D box with kG elements, flows and a 3 kG patch: each of the six planes of every column."""
    sun = model_sun((24, 24), 96 * u.km, seed=4, nz=48, spot=False, element_field=3000 * u.G,
                    element_flux_density=200 * u.G)
    planes = [channels.channel_images(DeferredTransfer(sun, mu=1.0, azimuth=0 * u.deg, wavelength=w)).value
              for w in (gongsynth.rt.default_wavelength(), channel_wavelength())]
    assert np.abs(planes[1] / planes[0] - 1).max() < 1e-4


@pytest.mark.parametrize("mu", [0.7, 1.0])
def test_same_bits_for_any_threads_and_blocks(mu):
    """Blocks of 1, 3 or all rows on 1 or 2 threads: one set of channel planes, spectra and truth."""
    sun = model_sun((12, 10), 384 * u.km, seed=6, nz=32, spot=False)
    before = numba.get_num_threads()
    results = []
    try:
        for threads, rows in ((1, 12), (2, 1), (2, 3), (min(2, numba.config.NUMBA_NUM_THREADS), 12)):
            numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
            sun.release()                      # the canopy made again on this thread count
            deferred = DeferredTransfer(sun, mu=mu, azimuth=-90 * u.deg, wavelength=channel_wavelength())
            parts = list(deferred.blocks(columns=rows * 10, halo_share=None))
            results.append((np.concatenate([c.V.value for _, c in parts]),
                            np.concatenate([c.I.value for _, c in parts]), deferred.blos.value))
    finally:
        numba.set_num_threads(before)
    for other in results[1:]:
        for a, b in zip(results[0], other):
            assert np.array_equal(a, b)
