"""Latitude sweeps: the Dask path gives the same bits as the serial one."""
import astropy.units as u
import numpy as np
import pytest

import gongsynth

TINY = dict(sun="milne-eddington", detector_shape=24, duration=1 * u.min, photosphere_shape=(128, 128),
            photosphere_pixel_size=768 * u.km, resolutions=(1,), seed=21)
LATITUDES = [0, 25, 45, 60, 70, 75] * u.deg


@pytest.fixture(scope="module")
def serial():
    return gongsynth.simulate_many(latitudes=LATITUDES, progress=False, **TINY)


def test_serial_sweep_matches_single_runs(serial):
    single = gongsynth.simulate(latitude=45 * u.deg, progress=False, **TINY)
    assert np.array_equal(single.magnetogram.data, serial[2].magnetogram.data)
    assert [r.config.latitude for r in serial] == list(LATITUDES)


@pytest.mark.filterwarnings("ignore::ResourceWarning")
@pytest.mark.filterwarnings("ignore:.*[Pp]ort.*:UserWarning")
def test_two_worker_local_cluster_is_bit_identical(serial):
    parallel = gongsynth.simulate_many(latitudes=LATITUDES, workers=2, progress=False, **TINY)
    for a, b in zip(serial, parallel):
        assert a.config == b.config
        assert np.array_equal(a.raw.data, b.raw.data)
        assert np.array_equal(a.magnetogram.data, b.magnetogram.data)
        assert np.array_equal(a.truth.data, b.truth.data)


def test_seeds_per_run():
    runs = gongsynth.simulate_many(latitudes=[0, 0] * u.deg, seeds=[1, 2], progress=False,
                                   **{k: v for k, v in TINY.items() if k != "seed"})
    assert not np.array_equal(runs[0].raw.data, runs[1].raw.data)
    with pytest.raises(ValueError, match="one entry per latitude"):
        gongsynth.simulate_many(latitudes=[0, 10] * u.deg, seeds=[1], **TINY)
