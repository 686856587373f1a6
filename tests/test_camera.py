"""
Tests of the camera engines against the analytic moments of the paper's algorithm.

For a plane with N frames of mean λ electrons (signal × flat + dark), gain g,
read noise σ (adu) and b truncated bits, the raw value (DN) has

    mean     = N λ / g / 2^b
    variance = N (λ/g² + σ² + 1/12) / 4^b + (4^b − 1) / (12 · 4^b)

(Poisson, read noise, per-frame rounding, then the dropped low bits, which are
uniform because the summed noise spans many DN).
"""
import os

import astropy.units as u
import numpy as np
import pytest
from astropy.io import fits

from gongsynth import GONGInstrument
from gongsynth.stages.camera.detector import synthetic_dark, synthetic_flat
from gongsynth.stages.camera.integrate import RawPlanes, integrate, snapshot_index
from gongsynth.stages.filters import channel_weights
from gongsynth.stages.reduction import reduce

GONG = GONGInstrument()
#: Electrons per frame per pixel of the continuum in one channel at disk centre
#: (the lead's estimate from design §3.10: 1.2e5).
CONTINUUM = 1.2e5
LAM = np.linspace(676.6, 676.96, 1801) * u.nm


@pytest.fixture
def quiet_sun(shifted_planes):
    """Expected electrons per frame of a uniform quiet-Sun scene, (6, ny, nx)."""
    continuum = channel_weights(LAM, GONG).value.sum(axis=1).mean()

    def build(shape, field=0 * u.G, velocity=0 * u.m / u.s):
        planes = CONTINUUM * shifted_planes(field, velocity, GONG, LAM) / continuum
        return np.repeat(planes, np.prod(shape)).reshape((6,) + tuple(shape)) * u.electron

    return build


def moments(expected, frames, flat=1.0, dark=0.0, inst=GONG):
    """Analytic per-pixel mean and variance (DN) of the raw planes."""
    lam = expected.to_value(u.electron) * flat + np.asarray(getattr(dark, "value", dark))
    g = inst.gain.to_value(u.electron / u.adu)
    s = inst.read_noise.to_value(u.adu)
    scale = 2.0**inst.truncate_bits
    n = np.asarray(frames, float).reshape(-1, 1, 1)
    mean = n * lam / g / scale
    var = n * (lam / g**2 + s**2 + 1 / 12) / scale**2 + (scale**2 - 1) / (12 * scale**2)
    return mean, var


def test_raw_planes_have_the_analytic_mean_and_variance():
    shape = (40, 50)
    expected = np.full((6,) + shape, 5e4) * np.arange(1, 7)[:, None, None] / 3 * u.electron
    flat = synthetic_flat(shape, prnu=0.05)
    dark = synthetic_dark(shape)
    for engine in ("blocks", "frames"):
        raw = integrate(expected, duration=1 * u.min, engine=engine, seed=5, flat=flat, dark=dark,
                        progress=False)
        mean, var = moments(expected, raw.frames_per_plane, raw.flat, raw.dark)
        z = (raw.data - mean) / np.sqrt(var)
        n = z[0].size
        for p in range(6):
            assert abs(z[p].mean()) < 4 / np.sqrt(n), (engine, p)
            assert abs(z[p].var() - 1) < 4 * np.sqrt(2 / n), (engine, p)


@pytest.mark.parametrize("engine", ["blocks", "frames"])
def test_truncation_and_dither_bookkeeping_leave_a_faint_flat_scene_unbiased(engine):
    # A faint scene makes the 3 dropped bits count (0.44 DN bias if not put back), and a
    # 2 s run gives the two polarisations different mean dithers (34-44 vs 46-56 adu).
    shape = (100, 100) if engine == "frames" else (300, 300)
    expected = np.full((6,) + shape, 40.0) * u.electron
    raw = integrate(expected, duration=2 * u.s, engine=engine, seed=11, flat=np.ones(shape),
                    dark=5 * u.electron, progress=False)
    mean, var = moments(expected, raw.frames_per_plane, 1.0, 5.0)
    n = raw.data[0].size
    bias = (raw.data - mean).reshape(6, -1).mean(axis=1)
    assert np.all(np.abs(bias) < 4 * np.sqrt(var[:, 0, 0] / n))


def test_dither_bookkeeping_is_per_plane(quiet_sun):
    # A dither that changes every frame gives each channel its own dither sum; only an
    # exact per-plane subtraction keeps the three channels (and so B and v) unbiased.
    inst = GONG.replace(dither_interval=1, dither_cycle=360)
    shape = (100, 100)
    expected = quiet_sun(shape)
    raw = integrate(expected, duration=3 * u.s, engine="blocks", seed=2, instrument=inst,
                    flat=np.ones(shape), dark=0 * u.electron, progress=False)
    sums = raw.header
    assert len({sums[f"DITHSUM{p}"] for p in range(6)}) == 6
    mean, var = moments(expected, raw.frames_per_plane, inst=inst)
    n = raw.data[0].size
    bias = (raw.data - mean).reshape(6, -1).mean(axis=1)
    assert np.all(np.abs(bias) < 4 * np.sqrt(var[:, 0, 0] / n))
    obs = reduce(raw, inst)
    truth = reduce(mean[:, :1, :1], inst)
    for measured, true in ((obs.magnetogram, truth.magnetogram), (obs.doppler, truth.doppler)):
        assert abs(measured.mean() - true[0, 0]) < 4 * measured.std() / np.sqrt(n)


def test_engines_agree_on_raw_planes_and_observables(quiet_sun):
    shape = (200, 200)
    expected = quiet_sun(shape, field=80 * u.G, velocity=400 * u.m / u.s)
    runs = {engine: integrate(expected, duration=1 * u.min, engine=engine, seed=seed, progress=False)
            for engine, seed in (("frames", 1), ("blocks", 2))}
    frames, blocks = runs["frames"], runs["blocks"]
    np.testing.assert_array_equal(frames.flat, blocks.flat)
    mean, var = moments(expected, frames.frames_per_plane, frames.flat, frames.dark)
    n = mean[0].size
    for p in range(6):
        a, b = frames.data[p] - mean[p], blocks.data[p] - mean[p]
        assert abs(a.mean() - b.mean()) < 3 * np.sqrt((a.var() + b.var()) / n)
        assert abs(a.var() / b.var() - 1) < 0.03
    obs = {k: reduce(r) for k, r in runs.items()}
    for name in ("magnetogram", "doppler"):
        a, b = (getattr(obs[k], name).value for k in ("frames", "blocks"))
        assert abs(a.mean() - b.mean()) < 3 * np.sqrt((a.var() + b.var()) / n), name
        assert abs(a.var() / b.var() - 1) < 0.03, name
    # And the measurement itself is right (B about 1 % low is line physics, design 3.6).
    assert 76 < obs["blocks"].magnetogram.mean().to_value(u.G) < 81
    assert 380 < obs["blocks"].doppler.mean().to_value(u.m / u.s) < 410


def test_noise_scales_as_inverse_sqrt_duration(quiet_sun):
    shape = (100, 100)
    expected = quiet_sun(shape)
    noise = {}
    for minutes in (1, 10):
        obs = reduce(integrate(expected, duration=minutes * u.min, seed=minutes, progress=False))
        noise[minutes] = (obs.magnetogram.std(), obs.doppler.std())
    ratio_b = noise[1][0] / noise[10][0]
    ratio_v = noise[1][1] / noise[10][1]
    # 10 000 pixels: each std is known to 0.7 %, so each ratio to 1 %.
    assert abs(ratio_b / np.sqrt(10) - 1) < 0.04
    assert abs(ratio_v / np.sqrt(10) - 1) < 0.04
    # Photon-limited GONG-like levels: a few G per pixel in one minute (GONG+: ~3 G, NSO).
    assert 1 * u.G < noise[1][0] < 6 * u.G


@pytest.mark.parametrize("engine", ["frames", "blocks"])
def test_same_seed_is_bit_identical_for_any_chunking_and_threads(engine):
    shape = (23, 17)
    expected = np.random.default_rng(0).uniform(0, 6e4, (6,) + shape) * u.electron
    runs = [integrate(expected, duration=5 * u.s, engine=engine, seed=42, chunk_rows=rows,
                      workers=workers, progress=False)
            for rows, workers in ((None, None), (1, 1), (7, 2), (23, 2), (5, 1))]
    for raw in runs[1:]:
        np.testing.assert_array_equal(raw.data, runs[0].data)
    other = integrate(expected, duration=5 * u.s, engine=engine, seed=43, progress=False)
    assert not np.array_equal(other.data, runs[0].data)


@pytest.mark.parametrize("engine", ["frames", "blocks"])
def test_different_seeds_give_independent_noise(engine):
    shape = (60, 60)
    expected = np.full((6,) + shape, 3e4) * u.electron
    kw = dict(duration=10 * u.s, engine=engine, flat=np.ones(shape), dark=0 * u.electron, progress=False)
    a, b = (integrate(expected, seed=s, **kw).data.ravel() for s in (1, 2))
    a, b = a - a.mean(), b - b.mean()
    r = (a * b).mean() / (a.std() * b.std())
    assert abs(r) < 4 / np.sqrt(a.size)
    # Neighbouring pixels of one run are independent too (per-pixel streams).
    assert abs(np.corrcoef(a[:-1], a[1:])[0, 1]) < 4 / np.sqrt(a.size)


def test_time_varying_input():
    shape = (50, 50)
    flat, dark = np.ones(shape), 0 * u.electron
    first = np.full((6,) + shape, 2e4)
    second = first * np.array([1, 2, 3, 1, 2, 3])[:, None, None]
    expected = np.stack([first, second]) * u.electron
    assert snapshot_index(3600, 2)[[0, 1799, 1800, 3599]].tolist() == [0, 0, 1, 1]
    (mean1, var1), (mean2, var2) = (moments(x * u.electron, [300] * 6) for x in (first, second))
    truncation = 63 / 768  # counted once, not twice
    mean, var = mean1 + mean2, var1 + var2 - truncation
    for engine in ("frames", "blocks"):
        raw = integrate(expected, duration=1 * u.min, engine=engine, seed=3, flat=flat, dark=dark,
                        progress=False)
        assert raw.header["NSNAP"] == 2
        z = ((raw.data - mean) / np.sqrt(var)).reshape(6, -1)
        assert np.all(np.abs(z.mean(axis=1)) < 4 / np.sqrt(z.shape[1])), engine
        assert np.all(np.abs(z.var(axis=1) - 1) < 4 * np.sqrt(2 / z.shape[1])), engine


def test_defaults_header_and_fits_round_trip(tmp_path):
    import gongsynth

    expected = np.full((6, 8, 9), 1e4) * u.electron
    raw = integrate(expected, duration=1 * u.min, seed=7, engine="frames", progress=False)
    h = raw.header
    assert (h["ACCUM"], h["COUNT"], h["NFRAMES"], h["ITIME"]) == (1800, 300, 3600, 60.0)
    assert h["ENGINE"] == raw.engine == "frames" and raw.seed == 7 == h["SEED"]
    assert h["GSVERS"] == gongsynth.__version__
    assert h["DTYPE"] != "OBSERVE"
    assert h["FLATSRC"] == "synthetic" and h["DARKSRC"] == "synthetic"
    np.testing.assert_allclose(np.median(raw.flat.reshape(6, -1), axis=1), 1)
    assert raw.dark.unit == u.electron and raw.dark.shape == (8, 9)

    path = tmp_path / "raw.fits"
    raw.to_fits(path)
    assert os.listdir(tmp_path) == ["raw.fits"]  # no temporary file left behind
    back = RawPlanes.from_fits(path)
    np.testing.assert_array_equal(back.data, raw.data)
    np.testing.assert_array_equal(back.flat, raw.flat)
    np.testing.assert_array_equal(back.frames_per_plane, raw.frames_per_plane)
    assert u.allclose(back.dark, raw.dark) and back.header["SEED"] == 7
    with pytest.raises(FileExistsError, match="overwrite"):
        raw.to_fits(path)
    raw.to_fits(path, overwrite=True)
    assert os.listdir(tmp_path) == ["raw.fits"]


def test_flat_and_dark_from_fits(tmp_path):
    shape = (6, 7)
    flat = np.full(shape, 3.0)
    flat[0, 0] = 6.0
    fits.writeto(tmp_path / "flat.fits", flat)
    dark_hdu = fits.PrimaryHDU(np.full(shape, 12.0))
    dark_hdu.header["BUNIT"] = "electron"
    dark_hdu.writeto(tmp_path / "dark.fits")
    fits.writeto(tmp_path / "nounit.fits", np.full(shape, 12.0))
    expected = np.full((6,) + shape, 1e4) * u.electron
    raw = integrate(expected, duration=1 * u.s, seed=1, flat=tmp_path / "flat.fits",
                    dark=str(tmp_path / "dark.fits"), progress=False)
    assert raw.flat[3, 0, 0] == 2.0 and raw.flat[3, 1, 1] == 1.0
    assert u.allclose(raw.dark, 12 * u.electron)
    assert raw.header["FLATSRC"] == "user"
    with pytest.raises(ValueError, match="BUNIT"):
        integrate(expected, duration=1 * u.s, dark=tmp_path / "nounit.fits", progress=False)
    with pytest.raises(FileNotFoundError, match="flat"):
        integrate(expected, duration=1 * u.s, flat=tmp_path / "missing.fits", progress=False)


def test_progress_bar(capsys):
    integrate(np.full((6, 2, 2), 1.0) * u.electron, duration=1 * u.s, progress=True)
    assert "camera (blocks)" in capsys.readouterr().err


GOOD = np.full((6, 4, 5), 1e3) * u.electron


@pytest.mark.parametrize("kwargs, error, match", [
    (dict(expected=-GOOD), ValueError, "non-negative"),
    (dict(expected=GOOD * np.where(np.arange(6) == 2, np.nan, 1)[:, None, None]), ValueError, "NaN"),
    (dict(expected=GOOD.value), TypeError, "expected must be an astropy Quantity"),
    (dict(expected=GOOD.value * u.adu), u.UnitsError, "expected"),
    (dict(expected=GOOD[:5]), ValueError, r"shape \(6, ny, nx\)"),
    (dict(flat=np.zeros((4, 5))), ValueError, "strictly positive"),
    (dict(flat=np.where(np.arange(20).reshape(4, 5) == 13, 0.0, 1.0)), ValueError, "1 zero or negative"),
    (dict(flat=np.ones((5, 4))), ValueError, "flat must have shape"),
    (dict(flat=np.full((4, 5), np.nan)), ValueError, "flat contains"),
    (dict(flat=np.ones((4, 5)) * u.m), u.UnitsError, "dimensionless"),
    (dict(dark=np.ones((3, 5)) * u.electron), ValueError, "dark must be a scalar or have shape"),
    (dict(dark=-1 * u.electron), ValueError, "non-negative"),
    (dict(dark=np.ones((4, 5))), TypeError, "dark must be an astropy Quantity"),
    (dict(engine="fast"), ValueError, "engine must be one of"),
    (dict(chunk_rows=0), ValueError, "chunk_rows"),
    (dict(workers=0), ValueError, "workers"),
    (dict(duration=1.5 / 60 * u.s), ValueError, "duration"),
    (dict(expected=np.ones((61, 6, 4, 5)) * u.electron), ValueError, "snapshots"),
    (dict(instrument="spectroheliograph"), ValueError, "instrument must be one of"),
    (dict(instrument={"gain": 33}), TypeError, "instrument"),
    (dict(instrument=GONG.replace(read_noise=0.5 * u.adu)), ValueError, "engine='frames'"),
])
def test_bad_input(kwargs, error, match):
    args = dict(expected=GOOD, duration=1 * u.s, progress=False) | kwargs
    with pytest.raises(error, match=match):
        integrate(args.pop("expected"), **args)


def test_frames_engine_without_read_noise():
    # The blocks engine refuses σ < 1 adu; the frames engine rounds each frame exactly.
    inst = GONG.replace(read_noise=0 * u.adu)
    expected = np.full((6, 30, 30), 3.0) * u.electron
    raw = integrate(expected, duration=2 * u.s, engine="frames", instrument=inst, seed=1,
                    flat=np.ones((30, 30)), dark=0 * u.electron, progress=False)
    # 3 e- per frame at 33 e-/adu always rounds to 0 adu: only the dither remains.
    dither = np.array([raw.header[f"DITHSUM{p}"] for p in range(6)])[:, None, None]
    np.testing.assert_array_equal(raw.data, np.broadcast_to(7 / 16 + np.floor(dither / 8) - dither / 8,
                                                             raw.data.shape))


def test_planes_without_frames_hold_zero():
    raw = integrate(GOOD, duration=1 * u.s, seed=1, progress=False)
    assert raw.frames_per_plane.tolist() == [20, 20, 20, 0, 0, 0]
    assert np.all(raw.data[3:] == 0)


# Inversion below λ = 10, algorithm PD from 10 up (its correction steps Q, E, H do most
# work at small λ); every draw through the frames engine's own block loop, 2000 pixels
# × 100 frames, so that serial draws of one stream and parallel streams are both tested.
@pytest.mark.parametrize("lam", [0.5, 7.0, 9.99, 10.0, 14.0, 40.0, 200.0, 499.0, 501.0, 1e3, 5e4, 3e5])
def test_poisson_sampler_matches_the_poisson_distribution(lam):
    from scipy import stats

    from gongsynth.stages.camera.kernels import sample_kernel

    x, _ = sample_kernel(np.full(2000, lam), 100, np.uint64(2024), np.uint64(7), int(lam * 10))
    x = x.ravel()
    n = x.size
    assert np.all(x == np.round(x)) and x.min() >= 0
    # Chi-square over ~40 bins of equal probability.
    edges = np.unique(stats.poisson.ppf(np.linspace(0, 1, 42)[1:-1], lam))
    observed = np.bincount(np.searchsorted(edges, x, side="left"), minlength=edges.size + 1)
    probs = np.diff(np.concatenate([[0], stats.poisson.cdf(edges, lam), [1]]))
    chi2 = ((observed - n * probs) ** 2 / (n * probs)).sum()
    assert stats.chi2.sf(chi2, edges.size) > 1e-3
    assert abs(x.mean() - lam) < 4 * np.sqrt(lam / n)
    assert abs(x.var() / lam - 1) < 4 * np.sqrt(2 / n)


def test_normal_sampler_including_the_ziggurat_tail():
    from scipy import stats

    from gongsynth.stages.camera.kernels import ZIGGURAT_R, sample_kernel

    n, z = sample_kernel(np.zeros(5000), 200, np.uint64(99), np.uint64(1), 5, photon=False)
    assert np.all(n == 0)
    z = z.ravel()
    assert stats.kstest(z, "norm").pvalue > 1e-3
    tail = 2 * stats.norm.sf(ZIGGURAT_R)  # beyond the base strip: the exact-tail branch
    count = np.count_nonzero(np.abs(z) > ZIGGURAT_R)
    assert abs(count - tail * z.size) < 4 * np.sqrt(tail * z.size)
    assert abs(np.mean(z**4) - 3) < 4 * np.sqrt(96 / z.size)
    # Successive frames of one stream are independent.
    frames = z.reshape(200, 5000)
    r = np.corrcoef(frames[:-1].ravel(), frames[1:].ravel())[0, 1]
    assert abs(r) < 4 / np.sqrt(frames[1:].size)


@pytest.mark.parametrize("photon", [True, False])
def test_vectorised_path_equals_the_whole_algorithm(photon):
    # The block loop finishes most pixel-frames on a branch-free common path and
    # leaves the rest to the whole algorithm; both must give the same bits.
    from gongsynth.stages.camera.kernels import LANES, sample_kernel

    means = np.array([0.0, 0.5, 3.0, 9.99, 10.0, 30.0, 300.0, 499.0, 501.0, 2e4, 1e5, 3e5])
    lam = np.resize(means, 3 * LANES + 5)  # partial last block, every mean in many lanes
    fast = sample_kernel(lam, 300, np.uint64(3), np.uint64(4), 11, photon=photon)
    whole = sample_kernel(lam, 300, np.uint64(3), np.uint64(4), 11, photon=photon, reference=True)
    np.testing.assert_array_equal(fast[0], whole[0])
    np.testing.assert_array_equal(fast[1], whole[1])
    # A pixel's numbers depend on its detector index only, not on its block.
    shifted = sample_kernel(lam[7:], 300, np.uint64(3), np.uint64(4), 18, photon=photon)
    np.testing.assert_array_equal(shifted[0], fast[0][:, 7:])
    np.testing.assert_array_equal(shifted[1], fast[1][:, 7:])


@pytest.mark.parametrize("layers", [256, 2048])
def test_packed_ziggurat_tables_cover_the_normal_with_equal_layers(layers):
    # The conditions that make the ziggurat exact, checked on the tables themselves:
    # equal layer areas, each layer as wide as the curve over its height, the base
    # strip's part beyond r as large as the tail, and conservative coarse core bounds.
    import math

    from scipy import stats

    from gongsynth.stages.camera.ziggurat import COARSE_BITS, ziggurat_tables

    bits = 46
    words, heights, r = ziggurat_tables(layers, bits)
    width = words.view(np.float64) * 2.0**bits
    kc = (words & np.uint64(2**COARSE_BITS - 1)).astype(np.int64)
    f_r = math.exp(-0.5 * r * r)
    tail = math.sqrt(2 * math.pi) * stats.norm.sf(r)
    v = r * f_r + tail
    assert width[0] * f_r == pytest.approx(v, rel=1e-14)
    area = width[1:] * (heights[:-1] - heights[1:])
    np.testing.assert_allclose(area, v, rtol=1e-11)
    assert heights[0] >= 1.0 > heights[1] and heights[-1] == pytest.approx(f_r, rel=1e-15)
    assert np.all(np.diff(heights) < 0)
    # Width of each layer i >= 1 covers the curve at its bottom; its core ends where the curve meets its top.
    cover = np.sqrt(-2 * np.log(heights[1:]))
    assert np.all(width[1:] >= cover * (1 - 1e-15))
    edge = np.concatenate([[r], np.sqrt(-2 * np.log(np.minimum(heights[:-1], 1.0)))])
    last = (kc << (bits - COARSE_BITS)) - 1  # the widest abscissa step a coarse bound accepts
    inside = kc > 0
    assert np.all(last[inside] * words.view(np.float64)[inside] < edge[inside])
    assert kc[1] == 0 and np.mean(kc[1:] / 2**COARSE_BITS) > 1 - 20 / layers


def test_frame_sums_are_the_rounded_recorded_variates():
    # The kernel's accumulated ADU (its vector loop and rare paths) against the variates
    # that the test entry point records for the same streams, rounded frame by frame.
    from gongsynth.stages.camera.kernels import LANES, frames_kernel, sample_kernel

    lam = np.resize(np.array([0.0, 3.0, 12.0, 300.0, 2e4, 1e5]), 2 * LANES + 9)
    n_frames, key0, key1, first = 400, np.uint64(5), np.uint64(6), 3
    inv_gain, sigma = 1 / 33, 4.8
    n, z = sample_kernel(lam, n_frames, key0, key1, first)
    expected = np.floor(n * inv_gain + sigma * z + 0.5).astype(np.int64).sum(axis=0)
    out = np.empty((1, lam.size), np.int64)
    frames_kernel(lam.reshape(1, 1, -1), np.array([0, n_frames]), np.zeros(1, np.int64),
                  np.zeros(n_frames, np.int64), np.zeros(n_frames, np.int64), inv_gain, sigma, True,
                  key0, key1, first, out)
    np.testing.assert_array_equal(out[0], expected)
