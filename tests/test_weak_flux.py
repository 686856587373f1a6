"""The papers' flux-conserving calibration estimator against known answers."""
import astropy.units as u
import numpy as np
import pytest

from gongsynth.analysis.weak_flux import (
    PAPER_BINS,
    flux_conserving_fit,
    paper_regions,
    weak_flux_factor,
    weak_flux_factor_difference,
)


def test_half_measured_gives_factor_two_with_regression_dilution():
    # measured = truth / 2 + noise.  The estimator is E[truth | measured], whose
    # slope for Gaussian truth (σt) and noise (σn) is (σt²/2) / (σt²/4 + σn²).
    rng = np.random.default_rng(1)
    sigma_t, sigma_n = 60.0, 5.0
    truth = rng.normal(0, sigma_t, 200_000)
    measured = truth / 2 + rng.normal(0, sigma_n, truth.size)
    expected = (sigma_t**2 / 2) / (sigma_t**2 / 4 + sigma_n**2)
    curve = flux_conserving_fit(measured * u.G, truth * u.G, 35)
    # The statistical error of a regression slope over N pixels of the inner
    # bins is ~ σ_resid / (σ_m √N) ≈ 0.01 here; binning adds no bias for a linear g.
    assert curve.slope_at_zero == pytest.approx(expected, abs=0.03)
    assert expected == pytest.approx(1.946, abs=1e-3)  # not 2: the dilution is real


def test_noiseless_nonlinear_curve_is_recovered():
    # GONG saturating: measured = 300 tanh(truth / 300).  Without noise
    # E[truth | measured] is the inverse, 300 artanh(measured / 300).
    truth = np.random.default_rng(2).normal(0, 150, 100_000)
    measured = 300 * np.tanh(truth / 300)
    curve = flux_conserving_fit(measured, truth, 21)
    inner = np.abs(curve.nodes.to_value(u.G)) < 200
    exact = 300 * np.arctanh(curve.nodes.to_value(u.G)[inner] / 300)
    # Within a bin the curve is linear while artanh is not: the flux-conserving
    # node values differ from the exact inverse by the curvature over a bin
    # width (~ 20 G wide bins here), a few G at most.
    assert np.max(np.abs(curve.values.to_value(u.G)[inner] - exact)) < 3.0
    assert curve.slope_at_zero == pytest.approx(1.0, abs=0.02)


def test_fit_is_odd_and_conserves_flux_in_every_bin():
    rng = np.random.default_rng(3)
    truth = rng.laplace(0, 80, 50_000)
    measured = 0.6 * truth + rng.normal(0, 8, truth.size)
    curve = flux_conserving_fit(measured, truth, 15)
    nodes = curve.nodes.to_value(u.G)
    assert np.allclose(nodes, -nodes[::-1])
    assert np.allclose(curve.values.to_value(u.G), -curve.values.to_value(u.G)[::-1], atol=1e-6)
    # Flux conservation, on the symmetrised data the fit saw.
    m, t = np.concatenate([measured, -measured]), np.concatenate([truth, -truth])
    which = curve.bin_index(m)
    fitted = np.bincount(which, weights=curve(m).to_value(u.G))
    assert np.allclose(fitted, np.bincount(which, weights=t), rtol=1e-9, atol=1e-6)
    assert np.array_equal(np.bincount(which), curve.counts)
    assert np.all(curve.counts[[0, -1]] >= 400)


def test_bad_input():
    with pytest.raises(ValueError, match="n_bins"):
        flux_conserving_fit(np.ones(5000), np.ones(5000), 2)
    with pytest.raises(ValueError, match="at least"):
        flux_conserving_fit(np.arange(100.0), np.arange(100.0), 7)
    with pytest.raises(ValueError, match="same size"):
        flux_conserving_fit(np.ones(10), np.ones(11), 3)


def test_regions_and_factor_of_a_simulation():
    import gongsynth

    result = gongsynth.simulate(seed=4, detector_shape=160, duration=1 * u.min, sun="milne-eddington",
                                progress=False)
    quiet, spot = paper_regions(result.magnetogram, result.continuum, usable=result.resolution_map == 1)
    assert quiet.any() and spot.any() and not (quiet & spot).any()
    assert np.all(np.abs(result.magnetogram.data[quiet]) < 400)
    assert np.median(result.continuum.data[spot]) < np.median(result.continuum.data[quiet])
    factor = weak_flux_factor(result, n_boot=20)
    assert factor.region == "quiet" and factor.n_pixels == quiet.sum()
    assert len(factor.curve.nodes) == PAPER_BINS[0][0]
    # A factor is a ratio of fluxes of the same sign: positive, and finite with
    # a finite bootstrap spread (its size is reported, not asserted).
    assert factor.factor > 0 and np.isfinite(factor.uncertainty) and factor.uncertainty > 0
    with pytest.raises(ValueError, match="region"):
        weak_flux_factor(result, region="plage")


def _mixture_sample(rng, n):
    # Quiet-Sun-like truth: a narrow Gaussian core and Laplace wings (so E[truth | measured]
    # is curved and the slope at zero depends on where the inner bins end); measured = truth/2 + noise.
    narrow = rng.random(n) < 0.85
    truth = np.where(narrow, rng.normal(0, 15, n), rng.laplace(0, 120, n))
    return truth / 2 + rng.normal(0, 6, n), truth


def test_pooling_keeps_the_estimand_when_min_outer_counts_per_run():
    """K samples pooled with min_outer × K estimate what each sample's own fit estimates (the inner
    edge sits at the same quantile); the reference is 24 samples pooled the same way."""
    rng = np.random.default_rng(7)
    n, k = 15_000, 4
    samples = [_mixture_sample(rng, n) for _ in range(24)]
    pooled = np.concatenate(samples[:k], axis=1)
    reference = flux_conserving_fit(*np.concatenate(samples, axis=1), 35, min_outer=400 * 24).slope_at_zero
    per_run = [flux_conserving_fit(m, t, 35).slope_at_zero for m, t in samples[:k]]
    error = np.std(per_run, ddof=1) / np.sqrt(k)   # standard error of the per-run mean (~0.01)
    per_run_rule = flux_conserving_fit(*pooled, 35, min_outer=400 * k).slope_at_zero
    assert np.mean(per_run) == pytest.approx(reference, abs=3 * error)
    assert per_run_rule == pytest.approx(reference, abs=3 * error)
    assert per_run_rule == pytest.approx(np.mean(per_run), abs=error)


def test_paired_difference_of_two_runs():
    """Same pixels, truth scaled by 1.5: the factor scales exactly (the fit is linear in the truth, to
    float32 round-off), and the paired bootstrap sees the same blocks as the single one, so both numbers
    are known; identical runs differ by exactly zero."""
    import dataclasses

    import sunpy.map

    import gongsynth

    coarse = dict(duration=1 * u.min, sun="milne-eddington", photosphere_shape=(64, 64),
                  photosphere_pixel_size=1536 * u.km, resolutions=(1,), progress=False)
    result = gongsynth.simulate(seed=5, detector_shape=96, **coarse)
    single = weak_flux_factor(result, n_boot=20)
    truth = result.truth_psf
    scaled = dataclasses.replace(result, truth_psf=sunpy.map.Map(truth.data * 1.5, truth.meta))
    difference, uncertainty = weak_flux_factor_difference(result, scaled, n_boot=20)
    assert difference == pytest.approx(0.5 * single.factor, rel=1e-6)     # the maps are float32
    assert uncertainty == pytest.approx(0.5 * single.uncertainty, rel=1e-6)
    assert weak_flux_factor_difference(result, result, n_boot=20) == (0.0, 0.0)
    # min_outer counts per run: pooling copies of one run puts the bins, and so the factor, exactly
    # where the run's own fit has them (a fixed count would move the inner edge outward).
    copies = weak_flux_factor([result] * 3, n_boot=0)
    assert copies.factor == pytest.approx(single.factor, rel=1e-9)
    assert np.array_equal(copies.curve.edges, single.curve.edges)
    assert weak_flux_factor_difference([result] * 3, [scaled] * 3, n_boot=0)[0] == pytest.approx(difference,
                                                                                                rel=1e-9)
    other = gongsynth.simulate(seed=5, detector_shape=24, latitude=30 * u.deg, **coarse)
    with pytest.raises(ValueError, match="latitude"):
        weak_flux_factor_difference(result, other)


def test_the_papers_pixel_lengths_are_angles_on_the_sun():
    """The sunspot mask is the authors' in any map's pixels: dilation by 17.5 arcsec (7 GONG pixels),
    and the continuum threshold on the continuum seen at GONG's resolution."""
    import sunpy.map

    from gongsynth.analysis.weak_flux import gong_resolution, paper_pixels

    def as_map(data, scale):
        return sunpy.map.Map(data, {"cdelt1": scale, "cdelt2": scale, "cunit1": "arcsec",
                                    "cunit2": "arcsec", "ctype1": "HPLN-TAN", "ctype2": "HPLT-TAN"})

    def rows(mask):
        return int(mask.any(axis=1).sum())

    light = np.ones((201, 201))
    light[80:121, 80:121] = 0.5                          # a 41-pixel dark square
    field = np.zeros_like(light)
    assert paper_pixels(7, as_map(field, 2.5)) == 7 and paper_pixels(7, as_map(field, 0.504)) == 35
    # GONG's pixels: no smoothing, a side-7 dilation: 41 + 7 - 1 rows.
    assert rows(paper_regions(as_map(field, 2.5), light)[1]) == 47
    assert rows(paper_regions(field, light)[1]) == 47            # a plain array: GONG pixels
    # HMI's: a side-35 dilation of the square seen at 6.5 arcsec, which reaches 0.92 about one
    # Gaussian sigma (5.5 pixels) outside the square's edge.
    sigma = gong_resolution().to_value(u.arcsec) / 0.504 / 2.3548
    hmi_rows = rows(paper_regions(as_map(field, 0.504), light)[1])
    assert 41 + 35 - 1 + 2 * (sigma - 1) <= hmi_rows <= 41 + 35 - 1 + 2 * (sigma + 1)
    # Lanes 10 % dark on a 4-pixel grid: resolved granulation.  Below the threshold pixel by pixel,
    # above it at GONG's resolution: no sunspot for HMI, all "sunspot" for GONG-sized pixels.
    lanes = np.ones((120, 120))
    lanes[2::4] = lanes[:, 2::4] = 0.9
    assert not paper_regions(as_map(np.zeros_like(lanes), 0.504), lanes)[1].any()
    assert paper_regions(np.zeros_like(lanes), lanes)[1].all()
    assert paper_regions(field, light, dilation=1)[1].sum() == 41 * 41
    with pytest.raises(ValueError, match="dilation"):
        paper_regions(field, light, dilation=0)


def test_weak_flux_factor_of_an_hmi_run():
    """weak_flux_factor works for HMI; its bootstrap blocks are 10 arcsec: 20 HMI pixels by default."""
    import gongsynth

    result = gongsynth.simulate(instrument="hmi", seed=6, detector_shape=64, sun="milne-eddington",
                                photosphere_shape=(128, 128), photosphere={"spot": False},
                                resolutions=(1,), progress=False)
    factor = weak_flux_factor(result, n_boot=10)
    assert factor.factor > 0 and np.isfinite(factor.uncertainty) and factor.uncertainty > 0
    same = weak_flux_factor(result, n_boot=10, block=20)
    assert (same.factor, same.uncertainty) == (factor.factor, factor.uncertainty)
    assert weak_flux_factor(result, n_boot=10, block=4).uncertainty != factor.uncertainty
