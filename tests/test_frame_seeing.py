"""Frame-to-frame seeing (stages/seeing.py) and GONG's one-minute averaging (stages/averaging.py)."""
import math

import astropy.units as u
import numpy as np
import pytest

import gongsynth
from gongsynth import GONGInstrument
from gongsynth.chain import build_chain
from gongsynth.config import Effects, SimulationConfig
from gongsynth.seeding import child_sequence
from gongsynth.stages.averaging import minutes_in
from gongsynth.stages.camera.integrate import integrate
from gongsynth.stages.reduction import reduce
from gongsynth.stages.seeing import SeeingPlanes, frame_motion, motion_spectrum

GONG = GONGInstrument()
SMALL = dict(seed=3, detector_shape=16, resolutions=(1,), photosphere_shape=(32, 32),
             photosphere_pixel_size=1536 * u.km, sun="milne-eddington", duration=2 * u.min)


def _camera_and_reduction(config, expected):
    chain = build_chain(config)
    state = chain["camera"].compute(expected_counts=expected)
    state.update(chain["reduction"].compute(**state))
    return state


@pytest.fixture(scope="module")
def runs():
    """Two-minute runs of one small Sun: all on (1 and 2 workers), without frame seeing, both off."""
    config = SimulationConfig(**SMALL)
    expected = build_chain(config).run(until="optics", progress=False)["expected_counts"]
    made = {"expected": expected}
    on = Effects(frame_seeing=True, minute_average=True)
    for name, changes in (("on", dict(workers=1, effects=on)), ("on2", dict(workers=2, effects=on)),
                          ("no_seeing", dict(effects=Effects(frame_seeing=False, minute_average=True))),
                          ("off", dict(effects=Effects(frame_seeing=False, minute_average=False)))):
        made[name] = _camera_and_reduction(config.replace(**changes), expected)
    return made


def _brute_force_frames(n_series, n_frames, rng, oversample=8):
    """
    Independent reference: the motion drawn at ``oversample`` × the frame rate from
    `motion_spectrum` (no aliasing formula) and box-averaged over each frame's exposure.
    """
    rate = GONG.frame_rate.to_value(u.Hz) * oversample
    n = n_frames * oversample * 2
    freq = np.fft.rfftfreq(n, 1 / rate)
    sigma2 = (GONG.seeing_fwhm.to_value(u.arcsec) / (2 * math.sqrt(2 * math.log(2)))) ** 2
    f = np.geomspace(1e-6, 1e6, 40001)
    norm = sigma2 / (2 * np.trapezoid(motion_spectrum(f * u.Hz, GONG), f))
    density = norm * motion_spectrum(freq * u.Hz, GONG)
    amplitude = np.sqrt(density * rate * n / 2)
    amplitude[0] = 0
    z = rng.standard_normal((n_series, freq.size)) + 1j * rng.standard_normal((n_series, freq.size))
    x = np.fft.irfft(z * amplitude, n=n, axis=1)[:, :n_frames * oversample]
    return x.reshape(n_series, n_frames, oversample).mean(axis=2), sigma2


def test_plane_motion_statistics_match_a_brute_force_simulation():
    schedule = GONG.schedule(1 * u.min)
    frames, sigma2 = _brute_force_frames(200, schedule.n_frames, np.random.default_rng(5), oversample=6)
    means = np.stack([frames[:, schedule.plane == p].mean(axis=1) for p in range(6)], axis=1)
    motion = frame_motion(schedule, (600, 600), GONG, seed=5)  # ~100 nodes: 100 independent draws
    drawn = motion.mean[0, :, 0].reshape(6, -1).T
    # Frame variance: the exposure keeps most of the motion (D < r0: the seeing is image motion).
    assert motion.sigma_f2 == pytest.approx(frames.var(), rel=0.1)
    assert 0.5 * sigma2 < motion.sigma_f2 < sigma2
    # The I+V minus I-V difference (the magnetogram's crosstalk) and a channel difference.
    for a, b in ((drawn, means),):
        pol = [x[:, :3].mean(axis=1) - x[:, 3:].mean(axis=1) for x in (a, b)]
        chan = [x[:, 0] - x[:, 1] for x in (a, b)]
        for d_drawn, d_brute, n in ((pol[0], pol[1], 200), (chan[0], chan[1], 200)):
            tolerance = 4 * math.sqrt(2 / min(n, d_drawn.size))  # 4 sigma of two variance estimates
            assert d_drawn.var() == pytest.approx(d_brute.var(), rel=tolerance)


def test_a_ramp_is_shifted_by_each_planes_own_mean_motion():
    inst = GONG.replace(seeing_layer_height=0 * u.m)  # one node: the whole image moves together
    motion = frame_motion(inst.schedule(1 * u.min), (20, 30), inst, seed=2)
    assert motion.mean.shape == (1, 6, 2, 1, 1)
    x = np.arange(30.0)
    ramp = np.broadcast_to(1000.0 + 7.0 * x, (6, 20, 30))
    seen = SeeingPlanes(ramp, motion, inst)[0]
    pixel = inst.plate_scale.to_value(u.arcsec)
    for p in range(6):
        expected = ramp[p] - motion.mean[0, p, 1, 0, 0] / pixel * 7.0
        np.testing.assert_allclose(seen[p], expected, rtol=1e-6)
    # The planes really differ: a sub-pixel motion of a few hundredths of an arcsec.
    assert 0.005 < np.std(motion.mean[0, :, 1]) < 0.5


def test_motion_is_deterministic_and_bad_groups_are_refused():
    schedule = GONG.schedule(2 * u.min)
    a = frame_motion(schedule, (50, 50), GONG, seed=9, groups=2)
    b = frame_motion(schedule, (50, 50), GONG, seed=9, groups=2)
    assert np.array_equal(a.mean, b.mean) and np.array_equal(a.second, b.second)
    assert not np.array_equal(a.mean[0], a.mean[1])  # every minute its own motion
    with pytest.raises(ValueError, match="groups"):
        frame_motion(schedule, (50, 50), GONG, seed=9, groups=7)


def test_minutes_in():
    assert minutes_in(9 * u.min, GONG) == 9
    assert minutes_in(1 * u.min, GONG) == 1
    assert minutes_in(150 * u.s, GONG) == 1  # not whole minutes: reduced at once
    assert minutes_in(9 * u.min, gongsynth.instruments.get("hmi")) == 1


def test_minute_average_is_the_mean_of_the_minutes_and_switches_off_to_the_old_bits(runs):
    state = runs["no_seeing"]
    raws = state["raw_minutes"]
    assert len(raws) == 2 and state["raw"].header["NMINUTES"] == 2
    assert state["raw"].header["ITIME"] == 120 and state["raw"].header["ACCUM"] == 3600
    mean = (reduce(raws[0], GONG).magnetogram + reduce(raws[1], GONG).magnetogram) / 2
    np.testing.assert_array_equal(state["observables"].magnetogram, mean)
    # Both switches off: the camera exactly as before (one accumulation, the "camera" stream).
    direct = integrate(runs["expected"], duration=2 * u.min, seed=child_sequence(3, "camera"), progress=False)
    np.testing.assert_array_equal(runs["off"]["raw"].data, direct.data)


def test_frame_seeing_changes_the_planes_and_not_with_the_workers(runs):
    one, two, no_seeing = runs["on"], runs["on2"], runs["no_seeing"]
    np.testing.assert_array_equal(one["observables"].magnetogram, two["observables"].magnetogram)
    assert not np.array_equal(one["raw"].data, no_seeing["raw"].data)
    # The crosstalk is small next to the planes (a sub-pixel shift of a 5″ PSF).
    ratio = one["raw"].data / no_seeing["raw"].data
    assert np.nanmax(np.abs(ratio - 1)) < 0.05
