"""
A full-disk detector that does not look at the Sun's centre (``pointing``), like a real GONG image.

Moving the pointing by a whole number of pixels must move the rendered disk by
exactly that many pixels, in the library's numba renderer, in the ray tracing
that blanks the sky, and in the products' WCS.
"""
import astropy.units as u
import numpy as np
import pytest

from gongsynth import GONGInstrument
from gongsynth.config import SimulationConfig
from gongsynth.geometry import disk_geometry
from gongsynth.stages.scene.disk_render import library_scene
from gongsynth.stages.scene.library import build_library

# The whole disk on a small detector (fast): 64 pixels of 40″.
COARSE = GONGInstrument(plate_scale=40 * u.arcsec)
DATE = "2009-09-05T18:54:16"


@pytest.fixture(scope="module")
def tiny_library():
    return build_library(shape=(16, 16), pixel_size=6 * u.Mm, seeds_per_level=(1, 1, 1, 1), seed=2,
                         theta=(0, 45, 85))


def test_a_whole_pixel_pointing_moves_the_rendered_disk_by_that_pixel(tiny_library):
    shift_x, shift_y = 3, -2
    pointing = [shift_x, shift_y] * COARSE.plate_scale
    kwargs = dict(instrument=COARSE, detector_shape=64, supersampling=1, obstime=DATE, seed=4)
    light, truth = library_scene(tiny_library, **kwargs)
    moved, moved_truth = library_scene(tiny_library, pointing=pointing, **kwargs)
    # Sample (i, j) of the moved grid looks where sample (i + shift_y, j + shift_x) of the centred one does.
    ny, nx = truth.shape
    new = (slice(-shift_y, ny), slice(0, nx - shift_x))
    old = (slice(0, ny + shift_y), slice(shift_x, nx))
    np.testing.assert_allclose(moved.data.value[(slice(None),) + new], light.data.value[(slice(None),) + old],
                               rtol=1e-5, atol=1e-6 * light.data.value.max())
    np.testing.assert_allclose(moved_truth.data.value[new], truth.data.value[old], atol=1e-3)
    assert not np.allclose(moved.data.value, light.data.value)
    # The WCS says the same: the Sun's centre is 3 pixels east and 2 north of the detector's centre.
    assert moved.centre.Tx.to_value(u.arcsec) == pytest.approx(3 * 40)
    assert moved.centre.Ty.to_value(u.arcsec) == pytest.approx(-2 * 40)


def test_the_sky_blanking_follows_the_pointing():
    pointing = [100, -60] * u.arcsec
    centred = disk_geometry((64, 64), COARSE.plate_scale, obstime=DATE)
    moved = disk_geometry((64, 64), COARSE.plate_scale, obstime=DATE, pointing=pointing)
    rows, cols = np.nonzero(centred.on_disk)
    moved_rows, moved_cols = np.nonzero(moved.on_disk)
    assert moved_cols.mean() - cols.mean() == pytest.approx(-100 / 40, abs=0.05)
    assert moved_rows.mean() - rows.mean() == pytest.approx(60 / 40, abs=0.05)


def test_pointing_is_checked_and_recorded():
    config = SimulationConfig(mode="full-disk", seed=1, pointing=[29.7, 4.8] * u.arcsec)
    assert SimulationConfig.from_toml(config.to_toml()) == config
    assert SimulationConfig(mode="full-disk", seed=1).pointing == (0 * u.arcsec, 0 * u.arcsec)
    with pytest.raises(ValueError, match="tiled run points at its latitude"):
        SimulationConfig(pointing=[1, 0] * u.arcsec)
    with pytest.raises(ValueError, match="two finite angles"):
        SimulationConfig(mode="full-disk", pointing=[1, 2, 3] * u.arcsec)
    with pytest.raises(ValueError, match="two finite angles"):
        SimulationConfig(mode="full-disk", pointing=[1, 2] * u.m)


def test_a_pointed_run_puts_the_sun_where_its_maps_say():
    """The whole chain: products blanked beyond the moved limb; their WCS puts (0, 0) on the disk's centre."""
    import gongsynth
    coarse = GONGInstrument(plate_scale=10 * u.arcsec, detector_shape=240, supersampling=3)
    config = SimulationConfig(mode="full-disk", sun="milne-eddington", instrument=coarse, seed=4,
                              duration=1 * u.min, obstime=DATE,
                              pointing=[150, -100] * u.arcsec)
    result = gongsynth.simulate(config=config, progress=False)
    rows, cols = np.nonzero(np.isfinite(result.magnetogram.data))
    from astropy.coordinates import SkyCoord
    centre = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=result.magnetogram.coordinate_frame)
    x, y = result.magnetogram.wcs.world_to_pixel(centre)
    assert float(x) == pytest.approx(cols.mean(), abs=0.1) and float(y) == pytest.approx(rows.mean(), abs=0.1)
    assert float(x) == pytest.approx((240 - 1) / 2 - 15, abs=1e-3)
    assert float(y) == pytest.approx((240 - 1) / 2 + 10, abs=1e-3)
