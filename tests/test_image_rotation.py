"""GONG's per-minute image rotation (instruments.gong.ucor) and the header count level (header_counts)."""
import astropy.units as u
import numpy as np
import pytest
import sunpy.data.test

from gongsynth import GONGInstrument
from gongsynth.config import SimulationConfig
from gongsynth.instruments.base import Observables
from gongsynth.instruments.gong.header_counts import count_scale, header_diodes
from gongsynth.instruments.gong.ucor import (
    INTERPOLANTS,
    from_camera,
    lagrange_weights,
    rotate_image,
    to_camera,
)
from gongsynth.observing import like_gong


@pytest.mark.parametrize("points", sorted(INTERPOLANTS.values()))
def test_lagrange_weights_reproduce_polynomials(points):
    t = np.random.default_rng(3).uniform(0, 1, 50)
    nodes = np.arange(points) - (points // 2 - 1)
    w = lagrange_weights(t, points)
    for degree in range(points):
        assert np.allclose(np.einsum("k...,k->...", w, nodes.astype(float) ** degree), t ** degree)
    # One degree more is not reproduced (the stencil is no larger than it should be).
    assert not np.allclose(np.einsum("k...,k->...", w, nodes.astype(float) ** points), t ** points)


def test_rotation_lowers_white_noise_as_its_weights_say():
    """Each pixel's variance is Σ w² of its own stencil: the mean over the image, within the noise."""
    n, angle = 192, 1.785431 * u.deg
    noise = np.random.default_rng(7).normal(0, 1, (2, n, n))
    theta = angle.to_value(u.rad)
    q = np.arange(n) - (n - 1) / 2
    qy, qx = np.meshgrid(q, q, indexing="ij")
    sx = (n - 1) / 2 + np.cos(theta) * qx + np.sin(theta) * qy
    sy = (n - 1) / 2 - np.sin(theta) * qx + np.cos(theta) * qy
    inner = slice(8, n - 8)
    for kind, points in INTERPOLANTS.items():
        out = rotate_image(noise, angle, interpolant=kind)[:, inner, inner]
        expected = (np.sum(lagrange_weights(sx % 1, points) ** 2, axis=0)
                    * np.sum(lagrange_weights(sy % 1, points) ** 2, axis=0))[inner, inner].mean()
        # 2 × 176² values: the variance is known to sqrt(2 / N) ≈ 0.6 % (more with the correlations).
        assert out.var() == pytest.approx(expected, rel=0.03)
        assert expected < 1
    # Linear interpolation smooths most, the quintic least.
    variances = {k: rotate_image(noise[0], angle, interpolant=k)[inner, inner].var() for k in INTERPOLANTS}
    assert variances["linear"] < variances["poly3"] < variances["poly5"] < 1


def test_camera_and_back_restore_a_band_limited_image():
    """The two rotations cancel: a PSF-smooth image (σ = 2 px, like GONG's 6″ PSF on 2.5″ pixels) returns."""
    n = 96
    y, x = np.mgrid[:n, :n]
    blob = sum(np.exp(-((x - cx) ** 2 + (y - cy) ** 2) / (2 * 2.0**2)) for cx, cy in ((30, 40), (60, 55)))
    inst = GONGInstrument(image_rotation_angle=21.4 * u.deg)
    planes = np.stack([blob] * 6) * u.electron
    camera = to_camera(planes, inst)
    assert camera.unit == u.electron and camera.shape == planes.shape
    assert np.abs(camera - planes).max() > 0.1 * u.electron   # it did turn
    obs = Observables(magnetogram=camera[0].value * u.G, doppler=camera[1].value * u.m / u.s,
                      continuum=camera[2].value * u.adu, velocity=camera[:2].value * u.m / u.s,
                      phase=camera[:2].value * u.rad, wrapped=np.zeros((n, n), bool))
    back = from_camera(obs, inst)
    assert np.abs(back.magnetogram.to_value(u.G) - blob).max() < 0.02
    assert back.velocity.shape == (2, n, n) and back.continuum.unit == u.adu


def test_wrapped_flags_follow_the_nearest_pixel():
    n = 41
    wrapped = np.zeros((n, n), bool)
    wrapped[20, 35] = True            # 15 px east of the centre (20, 20)
    zeros = np.zeros((n, n))
    obs = Observables(magnetogram=zeros * u.G, doppler=zeros * u.m / u.s, continuum=zeros * u.adu,
                      velocity=np.zeros((2, n, n)) * u.m / u.s, phase=np.zeros((2, n, n)) * u.rad,
                      wrapped=wrapped)
    back = from_camera(obs, GONGInstrument(image_rotation_angle=90 * u.deg))
    assert back.wrapped.sum() == 1
    # Turned by +90° (counter-clockwise, x east, y north): east goes north.
    assert back.wrapped[35, 20]


def test_interpolant_and_angle_checked():
    with pytest.raises(ValueError, match="image_interpolant"):
        GONGInstrument(image_interpolant="sinc")
    with pytest.raises(ValueError, match="interpolant"):
        rotate_image(np.zeros((4, 4)), 1 * u.deg, interpolant="cubic")
    with pytest.raises(TypeError, match="angle"):
        rotate_image(np.zeros((4, 4)), 1.0)


def test_like_takes_the_rotator_angle():
    """rot = −ROTATOR in both GHISTs seen (Big Bear 2009: 1.785431°; Learmonth 2025: −21.38885°)."""
    _, inst = like_gong(sunpy.data.test.get_test_filepath("gong_magnetogram.header"))
    assert inst.image_rotation_angle.to_value(u.deg) == pytest.approx(-21.38885, abs=1e-5)
    # An angle given explicitly wins.
    _, inst = like_gong(sunpy.data.test.get_test_filepath("gong_magnetogram.header"),
                        instrument=GONGInstrument(image_rotation_angle=3 * u.deg))
    assert inst.image_rotation_angle == 3 * u.deg


def test_count_scale_matches_the_diode_sums():
    inst = GONGInstrument()
    rng = np.random.default_rng(2)
    expected = np.pad(rng.uniform(0, 2e4, (6, 20, 20)), ((0, 0), (1, 1), (1, 1))) * u.electron
    per_plane = expected.to_value(u.electron).sum(axis=(1, 2)) / 33.0
    diodes = 0.5 * (per_plane[:3] + per_plane[3:]) * 0.2          # a real level 5 times lower
    header = {f"DIODE{k + 1}": d for k, d in enumerate(diodes)}
    assert count_scale(expected, header, inst) == pytest.approx(0.2, rel=1e-12)
    with pytest.raises(ValueError, match="DIODE"):
        header_diodes({"DIODE1": 1.0, "DIODE2": 2.0})
    with pytest.raises(ValueError, match="wholly"):
        count_scale(np.ones((6, 5, 5)) * u.electron, header, inst)


def test_like_counts_needs_a_gong_full_disk_like_run():
    with pytest.raises(ValueError, match="like_counts"):
        SimulationConfig(like_counts=True)
    with pytest.raises(TypeError, match="like_counts"):
        SimulationConfig(like_counts="yes")


def test_cli_like_counts_without_like_exits_2(tmp_path, capsys):
    from gongsynth.cli import main

    assert main(["simulate", "--like-counts", "--out", str(tmp_path / "o")]) == 2
    assert "like_counts" in capsys.readouterr().err


def test_the_chain_turns_the_camera_and_back():
    """With image_rotation the raw planes are the camera's turned view; without noise the maps come back."""
    from gongsynth.chain import build_chain
    from gongsynth.config import Effects

    quiet = dict(photon_noise=False, read_noise=False, dither=False, truncation=False, flat=False, dark=False)
    config = SimulationConfig(seed=3, detector_shape=32, resolutions=(1,), photosphere_shape=(32, 32),
                              photosphere_pixel_size=1536 * u.km, sun="milne-eddington", duration=1 * u.min,
                              instrument=GONGInstrument(image_rotation_angle=20 * u.deg),
                              effects=Effects(**quiet))
    expected = build_chain(config).run(until="optics", progress=False)["expected_counts"]
    made = {}
    for turned in (False, True):
        chain = build_chain(config.replace(effects=Effects(image_rotation=turned, **quiet)))
        state = chain["camera"].compute(expected_counts=expected)
        state.update(chain["reduction"].compute(**state))
        made[turned] = state
    assert not np.allclose(made[True]["raw"].data, made[False]["raw"].data, rtol=1e-3)
    flat, back = (made[k]["observables"].magnetogram.to_value(u.G)[8:-8, 8:-8] for k in (False, True))
    # Two interpolations of the PSF-smoothed planes, one of them the camera's model: 0.8 % measured.
    assert np.sqrt(np.mean((back - flat) ** 2)) < 0.03 * np.std(flat)
