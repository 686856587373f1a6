import astropy.units as u
import numpy as np
import pytest

from gongsynth import GONGInstrument
from gongsynth.planes import plane_index
from gongsynth.stages.camera.schedule import dither_sequence, frame_schedule, n_frames_in

GONG = GONGInstrument()


def paper_dither(n_frames, start=32, step=2, interval=12, cycle=3600):
    """The paper's Sec. 3.2 list, literally: a running offset updated before each frame."""
    offset, out = start, []
    for k in range(n_frames):
        if k % interval == 0:
            offset += step if (k % cycle) < cycle / 2 else -step
        out.append(offset)
    return np.array(out)


def test_one_minute_schedule_matches_gong_headers():
    s = frame_schedule(1 * u.min)
    assert s.n_frames == len(s) == 3600
    assert s.frames_per_plane.tolist() == [600] * 6
    assert s.accum == 1800  # real GONG: ACCUM = 1800 per plane per minute (per polarisation)
    assert s.waveplate_turns == 300  # real GONG: COUNT = 300 wave-plate pulses per minute
    assert s.duration == 60 * u.s


def test_ten_minutes_has_6000_frames_per_plane():
    s = frame_schedule(10 * u.min)
    assert s.n_frames == 36000
    assert s.frames_per_plane.tolist() == [6000] * 6


def test_waveplate_sectors_channels_and_lcvr():
    s = frame_schedule(3 * u.s)
    k = np.arange(s.n_frames)
    np.testing.assert_allclose(s.time.to_value(u.s), k / 60)
    assert s.sector.tolist() == (k % 12).tolist()
    np.testing.assert_allclose(s.waveplate_angle.to_value(u.deg), 30 * (k % 12))
    assert s.channel.tolist() == (k % 3).tolist()
    # The LCVR holds I+V for the first second, I-V for the next, then I+V again.
    assert set(s.polarisation[:60]) == {0}
    assert set(s.polarisation[60:120]) == {1}
    assert set(s.polarisation[120:180]) == {0}
    assert all(s.plane[i] == plane_index(s.polarisation[i], s.channel[i]) for i in range(s.n_frames))
    # Each plane receives every 3rd frame of its second.
    assert np.flatnonzero(s.plane == 4)[:5].tolist() == [61, 64, 67, 70, 73]


def test_dither_follows_the_paper_literally():
    for n in (3600, 36000, 100):
        np.testing.assert_array_equal(dither_sequence(n), paper_dither(n))


def test_dither_triangle_shape_and_mean():
    d = dither_sequence(7200)
    assert d[0] == 34 and d[11] == 34 and d[12] == 36
    assert d.max() == 332 and np.flatnonzero(d[:3600] == 332).tolist() == list(range(1788, 1800))
    assert d[1800] == 330 and d[3599] == 32
    np.testing.assert_array_equal(d[:3600], d[3600:])  # repeats every minute
    steps = np.diff(d)
    assert set(np.unique(steps)) == {-2, 0, 2}
    assert d[:3600].mean() == 182  # design 3.11 / paper: "approximately 182"
    assert frame_schedule(10 * u.min).dither.mean() == 182 * u.adu


def test_dither_rises_then_falls_every_12_frames():
    d = dither_sequence(3600)
    changes = np.flatnonzero(np.diff(d)) + 1
    assert np.all(changes % 12 == 0)
    up = changes[np.diff(d)[changes - 1] > 0]
    down = changes[np.diff(d)[changes - 1] < 0]
    assert up.max() < 1800 <= down.min()


def test_per_plane_dither_bookkeeping():
    s = frame_schedule(2 * u.s)
    d = s.dither.to_value(u.adu)
    for p in range(6):
        assert s.dither_sum[p] == d[s.plane == p].sum()
    # Two seconds of a rising ramp: I-V (second 2) carries more dither than I+V.
    assert np.all(s.mean_dither[3:] > s.mean_dither[:3])
    np.testing.assert_allclose(frame_schedule(1 * u.min).mean_dither.to_value(u.adu), 182)


def test_instrument_parameters_are_used():
    slow_lcvr = GONG.replace(lcvr_period=2 * u.s)
    s = frame_schedule(4 * u.s, slow_lcvr)
    assert set(s.polarisation[:120]) == {0} and set(s.polarisation[120:240]) == {1}
    other = GONG.replace(dither_start=10 * u.adu, dither_step=1 * u.adu, dither_interval=6, dither_cycle=600)
    np.testing.assert_array_equal(dither_sequence(1200, other),
                                  paper_dither(1200, start=10, step=1, interval=6, cycle=600))
    assert n_frames_in(1 * u.s, GONG.replace(frame_rate=120 * u.Hz, waveplate_rate=10 * u.Hz)) == 120


def test_any_duration():
    assert frame_schedule(2.5 * u.s).n_frames == 150
    assert frame_schedule(1 / 60 * u.s).n_frames == 1
    assert n_frames_in(0.5 * u.h) == 108000


@pytest.mark.parametrize("duration, error", [
    (0 * u.s, ValueError), (-1 * u.min, ValueError), (0.01 * u.s, ValueError),
    (1.5 / 60 * u.s, ValueError), (60, TypeError), (1 * u.m, u.UnitsError),
    ([1, 2] * u.s, ValueError), (np.nan * u.s, ValueError),
])
def test_bad_durations(duration, error):
    with pytest.raises(error, match="duration"):
        frame_schedule(duration)


def test_unsupported_wave_plate_rate():
    with pytest.raises(ValueError, match="90°"):
        frame_schedule(1 * u.s, GONG.replace(waveplate_rate=4 * u.Hz))


def test_bad_dither_parameters():
    with pytest.raises(ValueError, match="dither_interval"):
        dither_sequence(10, GONG.replace(dither_interval=0))
    with pytest.raises(ValueError, match="whole number"):
        dither_sequence(10, GONG.replace(dither_step=1.5 * u.adu))
    with pytest.raises(ValueError, match="n_frames"):
        dither_sequence(-1)
