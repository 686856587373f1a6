"""The statistics comparison: power spectra (analytic cases), tails, rings and noise matching."""
import astropy.units as u
import numpy as np
import pytest
import sunpy.map
from astropy.coordinates import SkyCoord
from sunpy.coordinates import frames

from gongsynth.analysis.map_statistics import compare_statistics, match_noise
from gongsynth.analysis.power_spectrum import km_per_arcsec, power_spectrum, quadrant_power_spectrum
from gongsynth.analysis.statistics import pixel_difference_sigma, ring_means, tail_percentiles


def _map(data, scale=2.5):
    ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective, observer="earth",
                   obstime="2020-06-01T12:00")
    header = sunpy.map.make_fitswcs_header(data.shape, ref, scale=[scale, scale] * u.arcsec / u.pix, unit=u.G)
    return sunpy.map.Map(data, header)


def test_spectrum_of_a_plane_wave_peaks_at_its_wavelength_with_its_variance():
    n = 256
    m = _map(np.zeros((n, n)))
    dx = (2.5 * u.arcsec * km_per_arcsec(m)).to_value(u.Mm)
    wavelength = n * dx / 12        # 12 whole periods across the box: ~39 Mm
    x = np.arange(n) * dx
    wave = _map(10 * np.cos(2 * np.pi * x / wavelength)[None, :] * np.ones((n, 1)))
    spectrum = power_spectrum(wave)
    k = spectrum.edges.to_value(1 / u.Mm)
    peak = int(np.nanargmax(spectrum.power.value))
    assert k[peak] <= 1 / wavelength < k[peak + 1]
    # Parseval with the window taken out: a cosine of amplitude A has variance A²/2.
    assert spectrum.variance.to_value(u.G ** 2) == pytest.approx(50, rel=0.02)


def test_spectrum_of_a_box_off_centre_sees_only_that_box():
    n = 512                                   # 1280″ at 2.5″: four 640″ quadrants
    m = _map(np.zeros((n, n)))
    dx = (2.5 * u.arcsec * km_per_arcsec(m)).to_value(u.Mm)
    wavelength = 256 * dx / 8                 # 8 whole periods across a quadrant
    x = np.arange(256) * dx
    data = np.zeros((n, n))
    data[256:, 256:] = 10 * np.cos(2 * np.pi * x / wavelength)[None, :]     # the north-west quadrant only
    wave = _map(data)
    inside = power_spectrum(wave, offset=[320, 320] * u.arcsec)
    outside = power_spectrum(wave, offset=[-320, -320] * u.arcsec)
    assert inside.box_pixels == outside.box_pixels == 256
    k = inside.edges.to_value(1 / u.Mm)
    peak = int(np.nanargmax(inside.power.value))
    assert k[peak] <= 1 / wavelength < k[peak + 1]
    # Parseval with the window taken out: A²/2 = 50 (the box is the quadrant to half a pixel).
    assert inside.variance.to_value(u.G ** 2) == pytest.approx(50, rel=0.02)
    assert outside.variance.to_value(u.G ** 2) == 0
    with pytest.raises(ValueError, match="offset"):
        power_spectrum(wave, offset=[1, 2, 3] * u.arcsec)
    # The four quadrants' mean: one of four boxes holds the wave.
    four = quadrant_power_spectrum(wave)
    assert four.box_pixels == 256 and np.all(four.modes == 4 * power_spectrum(wave).modes)
    assert four.variance.to_value(u.G ** 2) == pytest.approx(50 / 4, rel=0.02)
    with pytest.raises(ValueError, match="central"):
        quadrant_power_spectrum(_map(np.zeros((400, 400))))          # 1000″ cannot hold 2 x 640″


def test_spectrum_by_direction_splits_a_wave_by_its_axis_and_white_noise_evenly():
    n = 256
    m = _map(np.zeros((n, n)))
    dx = (2.5 * u.arcsec * km_per_arcsec(m)).to_value(u.Mm)
    x = np.arange(n) * dx
    along_x = _map(10 * np.cos(2 * np.pi * x / (n * dx / 12))[None, :] * np.ones((n, 1)))
    peak_x = power_spectrum(along_x, direction="x")
    peak_y = power_spectrum(along_x, direction="y")
    both = power_spectrum(along_x)
    # Every one of the cosine's modes lies on the kx axis: "x" holds its power, "y" only the window's leak.
    assert np.nanmax(peak_x.power.value) > 1e3 * np.nanmax(peak_y.power.value)
    assert np.all(peak_x.modes + peak_y.modes <= both.modes)
    # White noise: the two halves agree within their scatter.  Of an annulus's modes about a quarter
    # are independent (k and -k are one for a real map, and the Hann window ties each mode to its
    # neighbours), each an exponential variate: the ratio of two means strays by sqrt(2 / (modes / 4)).
    noise = _map(np.random.default_rng(11).normal(0, 3, (n, n)))
    sx, sy = power_spectrum(noise, direction="x"), power_spectrum(noise, direction="y")
    many = (sx.modes >= 400) & (sy.modes >= 400)
    ratio = sx.power.value[many] / sy.power.value[many]
    assert np.all(np.abs(ratio - 1) < 4 * np.sqrt(8 / sx.modes[many]))
    with pytest.raises(ValueError, match="direction"):
        power_spectrum(noise, direction="z")


def test_spectrum_of_white_noise_is_flat_at_sigma_squared_dx_squared():
    n = 256
    noise = _map(np.random.default_rng(7).normal(0, 3, (n, n)))
    spectrum = power_spectrum(noise)
    dx = spectrum.pixel_size.to_value(u.Mm)
    many = spectrum.modes >= 200      # annuli of >= 200 modes: the mean of exponential variates to ~10 %
    level = spectrum.power.value[many] / (9 * dx ** 2)
    assert np.all(np.abs(level - 1) < 0.3)
    assert np.average(level, weights=spectrum.modes[many]) == pytest.approx(1, abs=0.05)
    with pytest.raises(ValueError, match="box"):
        power_spectrum(noise, box=-1 * u.arcsec)


def test_tails_and_rings():
    x = np.random.default_rng(3).normal(5, 2, 400_000)
    tails = tail_percentiles(x)
    assert tails[99.0] == pytest.approx(2 * 2.5758, rel=0.02)
    assert tails[99.9] == pytest.approx(2 * 3.2905, rel=0.03)
    data = np.full((128, 128), 4.0)
    m = _map(data, scale=16)
    rings = ring_means(m, (0, 0.5, 0.9))
    assert np.allclose(rings["mean_abs"].to_value(u.G), 4.0) and np.all(rings["pixels"] > 0)
    assert np.all(rings["robust_sigma"].value == 0) and np.all(rings["difference_sigma"].value == 0)


def test_ring_width_and_noise_tell_white_noise_from_signal_and_correlated_noise():
    from scipy.ndimage import uniform_filter
    rng = np.random.default_rng(5)
    n, sigma = 400, 3.0
    white = rng.normal(0, sigma, (n, n))
    y = np.arange(n)[:, None] * np.ones((1, n))
    signal = 6 * np.sin(2 * np.pi * y / 80)             # smooth: ~0.2 G between neighbours
    # 2 x 2 boxcar of white noise of sigma 2 sigma: sigma again, neighbours correlated by 1/2.
    correlated = uniform_filter(rng.normal(0, 2 * sigma, (n, n)), size=2, mode="wrap")
    edges = (0, 0.3, 0.6)
    # Rings of >= 2.8e4 pixels: a robust sigma is known to 1.17 / sqrt(n) < 0.7 %, so 5 % is > 7 of those.
    flat = ring_means(_map(white, scale=3), edges)
    assert np.allclose(flat["robust_sigma"].to_value(u.G), sigma, rtol=0.05)
    assert np.allclose(flat["difference_sigma"].to_value(u.G), sigma, rtol=0.05)
    structured = ring_means(_map(white + signal, scale=3), edges)
    assert np.allclose(structured["difference_sigma"].to_value(u.G), sigma, rtol=0.05)
    assert np.all(structured["robust_sigma"].to_value(u.G) > 1.4 * sigma)
    smooth = ring_means(_map(correlated, scale=3), edges)
    assert np.allclose(smooth["robust_sigma"].to_value(u.G), sigma, rtol=0.05)
    # A neighbour difference of correlated noise has variance 2 sigma^2 (1 - 1/2): sigma / sqrt(2).
    assert np.allclose(smooth["difference_sigma"].to_value(u.G), sigma / np.sqrt(2), rtol=0.05)


def test_matching_the_noise_equalises_pixel_difference_noise_and_ks():
    rng = np.random.default_rng(11)
    a, b = _map(rng.normal(0, 2, (400, 400))), _map(rng.normal(0, 5, (400, 400)))
    a2, b2, added = match_noise(a, b, seed=1)
    assert added[1] == 0 and b2 is b
    # Matched on the quietest boxes, each known to ~1.2 % (noise_estimate): 5 % is three sigma of both.
    assert pixel_difference_sigma(a2.data) == pytest.approx(pixel_difference_sigma(b.data), rel=0.05)
    stats = compare_statistics(a, b)
    t = stats.table
    assert list(t["map"]) == ["sim", "obs", "sim, noise matched", "obs, noise matched"]
    assert t["ks"][0] > 0.2 and t["ks"][2] < 0.02     # different laws, then the same (n ~ 1e5: KS ~ 0.005)
    assert t["mean_abs"][2].to_value(u.G) == pytest.approx(5 * np.sqrt(2 / np.pi), rel=0.05)
    low, high = stats.spectrum_ratio_range(matched=True)
    assert 0.7 < low <= high < 1.4
    assert "power ratio 5-100 Mm" in stats.summary()
    from matplotlib.figure import Figure
    ax = Figure().add_subplot()
    stats.plot_spectra(ax)
    assert len(ax.get_lines()) == 4 and "power spectrum" in ax.get_title()   # no room for 4 boxes here
    assert np.all(np.isnan(stats.spectra["ratio_quadrants"]))
    assert np.isnan(stats.spectrum_ratio_range(quadrants=True)[0])


def test_four_boxes_spectrum_agrees_for_one_law_and_is_drawn():
    rng = np.random.default_rng(12)
    a, b = _map(rng.normal(0, 3, (560, 560))), _map(rng.normal(0, 3, (560, 560)))   # 1400″ hold 2 x 640″
    stats = compare_statistics(a, b)
    t = stats.spectra
    quad = np.asarray(t["ratio_quadrants"])
    lam = t["wavelength"].to_value(u.Mm)
    small = np.isfinite(quad) & (lam < 10)
    assert small.sum() >= 3
    # Below 10 Mm each annulus holds >= 3600 modes per box (half of them independent): one box's mean
    # power is known to ~2.3 % (~3.4 % with the Hann window's neighbours correlated), four boxes' to
    # ~1.7 %, the ratio of two maps' to ~2.4 %: 12 % is five of those.
    assert np.all(np.abs(quad[small] - 1) < 0.12)
    assert np.isfinite(stats.spectrum_ratio_range(quadrants=True)[0])
    from matplotlib.figure import Figure
    ax = Figure().add_subplot()
    stats.plot_spectra(ax)
    assert len(ax.get_lines()) == 6


def test_mean_abs_centred_takes_out_a_zero_point():
    # A site file's zero point: N(-2.4, 5) on the disk.  |B| is inflated by the offset; |B - median| is
    # the noise's half-normal mean, 5 sqrt(2/pi) = 3.99 G (n ~ 1e5 pixels: known to ~0.3 %).
    rng = np.random.default_rng(5)
    offset, noisy = _map(rng.normal(-2.4, 5, (400, 400))), _map(rng.normal(0, 5, (400, 400)))
    t = compare_statistics(offset, noisy).table
    half_normal = 5 * np.sqrt(2 / np.pi)
    assert t["mean_abs_centred"][0].to_value(u.G) == pytest.approx(half_normal, rel=0.02)
    assert t["mean_abs_centred"][1].to_value(u.G) == pytest.approx(half_normal, rel=0.02)
    assert t["mean_abs"][0].to_value(u.G) > 1.1 * half_normal   # E|N(2.4, 5)| = 4.58 G
    assert "mean |B-median|" in compare_statistics(offset, noisy).summary()


def test_cluster_columns_are_network_clusters_of_each_map():
    """The cluster columns are `network_clusters` of each map; a field away from disk centre has NaN."""
    from gongsynth.analysis.network_clusters import network_clusters

    rng = np.random.default_rng(11)
    data = [rng.normal(0, 3, (300, 300)) for _ in range(2)]
    for d, amplitude in zip(data, (60.0, 30.0)):
        d[rng.integers(20, 280, 40), rng.integers(20, 280, 40)] += amplitude     # one-pixel elements
    sim, obs = _map(data[0]), _map(data[1])
    t = compare_statistics(sim, obs).table
    for row, smap in ((0, sim), (1, obs)):
        expected = network_clusters(smap).summary()
        assert t["cluster_density"][row] == expected["number_density"]
        assert t["cluster_flux_density"][row] == expected["flux_density"]
        assert t["cluster_p99"][row] == expected["p99"]
        np.testing.assert_equal(t["cluster_elongation"][row], expected["elongation"])
    assert t["cluster_flux_density"][0] > t["cluster_flux_density"][1] > 0 * u.G
    ref = SkyCoord(600 * u.arcsec, 600 * u.arcsec, frame=frames.Helioprojective, observer="earth",
                   obstime="2020-06-01T12:00")
    header = sunpy.map.make_fitswcs_header((100, 100), ref, scale=[2.5, 2.5] * u.arcsec / u.pix, unit=u.G)
    off = [sunpy.map.Map(d[:100, :100], header) for d in data]
    t_off = compare_statistics(*off).table
    assert np.all(np.isnan(t_off["cluster_density"].value)) and np.all(np.isnan(t_off["cluster_index"]))
    assert np.all(np.isnan(t_off["cluster_elongation"]))
