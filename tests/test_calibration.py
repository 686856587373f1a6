import astropy.units as u
import numpy as np
import pytest

from gongsynth.analysis.calibration import calibration_curve, robust_slope
from gongsynth.geometry import Pointing


def test_robust_slope_ignores_outliers():
    rng = np.random.default_rng(4)
    truth = rng.normal(0, 500, 4000)
    measured = 0.93 * truth + rng.normal(0, 10, truth.size)
    measured[:200] = -measured[:200]  # 5 % wrapped-like outliers
    slope, scatter = robust_slope(truth, measured)
    assert slope == pytest.approx(0.93, abs=3e-3)
    assert scatter == pytest.approx(10, rel=0.15)


def test_curve_recovers_known_slopes_and_errors():
    rng = np.random.default_rng(7)
    truth = np.concatenate([rng.normal(0, 20, 20000), rng.normal(0, 800, 2000)])
    noise = 8.0
    measured = np.where(np.abs(truth) >= 100, 0.8, 0.95) * truth + rng.normal(0, noise, truth.size)
    curve = calibration_curve(measured * u.G, truth * u.G, n_boot=50, seed=1)
    assert curve.strong.slope == pytest.approx(0.8, abs=3 * curve.strong.slope_error + 1e-3)
    assert curve.quiet.slope == pytest.approx(0.95, abs=0.03)
    # The bootstrap error is close to the analytic sigma / sqrt(sum t^2) of least squares.
    strong = np.abs(truth) >= 100
    analytic = noise / np.sqrt(np.sum(truth[strong] ** 2))
    assert curve.strong.slope_error == pytest.approx(analytic, rel=0.5)
    assert curve.strong.correction_factor == pytest.approx(1 / curve.strong.slope)
    # Binned medians follow the input relation.
    ok = (curve.counts > 50) & (np.abs(curve.bin_centres) > 200 * u.G)
    assert np.allclose(curve.median[ok] / curve.bin_centres[ok], 0.8, atol=0.05)


def test_curve_bad_input():
    with pytest.raises(ValueError, match="same shape"):
        calibration_curve(np.zeros(3) * u.G, np.zeros(4) * u.G)
    with pytest.raises(ValueError, match="no finite pixels"):
        calibration_curve(np.full(3, np.nan) * u.G, np.zeros(3) * u.G)
    with pytest.raises(u.UnitsError, match="measured"):
        calibration_curve(np.zeros(3) * u.m, np.zeros(3) * u.G)
    with pytest.raises(TypeError, match="truth is required"):
        calibration_curve(np.zeros(3) * u.G)


@pytest.mark.parametrize("latitude", [0, 60] * u.deg)
def test_noiseless_psf_free_factor_is_the_line_physics(latitude):
    """Without noise and PSF, GONG measures the pixel-averaged field up to the line's ~0.99."""
    from gongsynth.geometry import viewing_geometry
    from gongsynth.stages.channels import channel_images
    from gongsynth.stages.optics import expected_counts, observe
    from gongsynth.stages.reduction import reduce
    from gongsynth.stages.scene.tiled import tiled_scenes
    from gongsynth.sun.photosphere import model_photosphere, synthesize

    photosphere = model_photosphere(shape=(256, 256), pixel_size=384 * u.km, seed=5)
    mu, los_azimuth = viewing_geometry(latitude)
    stokes = synthesize(photosphere, mu=mu, los_azimuth=los_azimuth)
    light, truth = tiled_scenes(channel_images(stokes), stokes.blos, stokes.pixel_size,
                                pointing=Pointing(latitude), resolutions=(1,), detector_shape=96)
    measured = reduce(expected_counts(light, psf=False).value).magnetogram
    true = observe(truth.data, truth.pixel_scale, psf=False, boundary=truth.boundary)
    curve = calibration_curve(measured, true, threshold=100 * u.G, n_boot=10)
    # Quiet pixels: the weak-field line physics, 0.988 for a uniform field (test_reduction).
    assert curve.quiet.slope == pytest.approx(0.988, abs=0.005)
    # All pixels: within ~2 % of it; kG fields are measured lower (Zeeman saturation and
    # intensity weighting inside the pixel), which the strong-field fit shows.
    assert curve.all_pixels.slope == pytest.approx(0.988, abs=0.02)
    assert 0.85 < curve.strong.slope < curve.quiet.slope


def test_curves_as_tables():
    from gongsynth.analysis.calibration import latitude_table

    rng = np.random.default_rng(3)
    truth = rng.normal(0, 300, 5000)
    curves = [calibration_curve(f * truth * u.G + rng.normal(0, 5, truth.size) * u.G, truth * u.G,
                                n_boot=20, seed=2, label=f"x{f}") for f in (0.5, 0.9)]
    table = curves[0].to_table()
    assert table["median"].unit == u.G and len(table) == curves[0].bin_centres.size
    assert np.array_equal(table["n_pixels"], curves[0].counts)
    assert table.meta["all_pixels"]["correction_factor"] == pytest.approx(2.0, rel=0.01)
    sweep = latitude_table([0, 60] * u.deg, curves)
    assert sweep["latitude"].unit == u.deg
    assert list(sweep["slope_all"]) == [c.all_pixels.slope for c in curves]
    assert sweep["correction_all"][1] == pytest.approx(1 / 0.9, rel=0.01)
    with pytest.raises(ValueError, match="one entry per curve"):
        latitude_table([0] * u.deg, curves)
