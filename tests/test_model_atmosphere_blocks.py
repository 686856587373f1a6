"""
The 3-D model Sun assembled and synthesised a block of rows at a time (issue 26 item 4): the same
bits as the whole box, and memory that follows the block, not the box.
"""
import tracemalloc

import astropy.units as u
import numpy as np
import pytest

import gongsynth
from gongsynth.stages import channels
from gongsynth.sun.model_atmosphere import DeferredTransfer, model_atmosphere, model_sun

FIELDS = ("temperature", "gas_pressure", "velocity", "magnetic_field")


def test_rows_are_the_whole_boxs_rows_bit_for_bit():
    """Any rows (wrapping, out of order, repeated), with the potential canopy and without."""
    for kw in ({"canopy": True}, {"canopy": False}):
        whole = model_atmosphere((30, 28), 600 * u.km, seed=3, nz=24, spot=False, **kw)
        sun = model_sun((30, 28), 600 * u.km, seed=3, nz=24, spot=False, **kw)
        rows = np.array([-2, -1, 0, 1, 17, 5, 5, 29, 31])
        part = sun.rows(rows)
        assert part.shape == (24, rows.size, 28)
        for name in FIELDS:
            assert np.array_equal(part.raw(name), whole.raw(name)[..., rows % 30, :]), name
        assert part.meta == whole.meta
        assert np.array_equal(sun.atmosphere().raw("magnetic_field"), whole.raw("magnetic_field"))


@pytest.mark.parametrize("mu", [0.6, 1.0])
def test_blocks_are_the_whole_synthesis_bit_for_bit(mu):
    """Inclined rays cross rows: each block carries its halo, and the rays keep the box's anchor."""
    sun = model_sun((20, 12), 384 * u.km, seed=5, nz=32, spot=False)
    whole = gongsynth.rt.synthesize(sun.atmosphere(), mu=mu, azimuth=-60 * u.deg, progress=False)
    deferred = DeferredTransfer(sun, mu=mu, azimuth=-60 * u.deg)
    got = list(deferred.blocks(columns=7 * 12, halo_share=None))  # blocks of 7, 7, 6 rows
    assert [rows for rows, _ in got] == [slice(0, 7), slice(7, 14), slice(14, 20)]
    for name in ("I", "Q", "U", "V"):
        assert np.array_equal(np.concatenate([getattr(c, name).value for _, c in got]),
                              getattr(whole, name).value), name
    assert np.array_equal(deferred.blos, whole.blos)
    np.testing.assert_equal(deferred.meta, dict(whole.meta, truth_anchor_mean_km=None))  # nan == nan here
    if mu < 1:  # a halo over a quarter of the block (3 + 2 rows here) makes the blocks a multiple larger
        assert [rows for rows, _ in deferred.blocks(columns=7 * 12)] == [slice(0, 20)]
    assert deferred.shape == whole.shape and deferred.mu == whole.mu
    assert np.array_equal(deferred.V.value, whole.V.value)  # the whole cube on request


def test_channel_images_of_the_blocks_are_the_whole_cubes(monkeypatch):
    """Blocks aligned with the channel stage's chunks: the same bits; any other split within rounding."""
    sun = model_sun((16, 16), 384 * u.km, seed=2, nz=32, spot=False)
    whole = gongsynth.rt.synthesize(sun.atmosphere(), mu=0.8, azimuth=-90 * u.deg, progress=False)
    for chunk, exact in ((64, True), (48, False)):
        monkeypatch.setattr(channels, "_BLOCK_SPECTRA", chunk)
        expected = channels.channel_images(whole).value
        got = channels.channel_images(DeferredTransfer(sun, mu=0.8, azimuth=-90 * u.deg)).value
        if exact:
            assert np.array_equal(got, expected)
        else:
            np.testing.assert_allclose(got, expected, rtol=1e-12, atol=0)


def _peak(box_rows, block_rows, nx=128):
    """Peak traced memory (bytes) of a pass of blocks, and the bytes of the whole box's atmosphere."""
    sun = model_sun((box_rows, nx), 384 * u.km, seed=1, nz=16, spot=False, canopy=False)
    deferred = DeferredTransfer(sun, mu=0.9, azimuth=-90 * u.deg)
    tracemalloc.start()
    for _ in deferred.blocks(columns=block_rows * nx):
        pass
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak, 8 * 16 * box_rows * nx * 4         # T, P, v, B in float32


def test_block_path_memory_follows_the_block_not_the_box():
    """
    Peak traced memory of the assembly and transfer by blocks of 16 rows of 128 columns: doubling
    the box (4096 to 8192 columns) adds far less than its atmosphere (only the 2-D planes and the
    truth grow with the box; the rays' reference sample is capped at 4096 columns), and the same
    box whole peaks at several times the blocks' peak.
    """
    _peak(8, 8, nx=8)                      # the first pass's one-time tables, untraced below
    small, _ = _peak(32, 16)
    large, atmosphere = _peak(64, 16)
    whole, _ = _peak(64, 64)
    assert abs(large - small) < 0.125 * atmosphere / 2
    assert whole > 2 * large
