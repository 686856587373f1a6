"""Noise, histogram and limb-darkening statistics: analytic cases and PROVENANCE.md's real-data numbers."""
import math
import warnings

import astropy.units as u
import numpy as np
import pytest
import scipy.integrate
import scipy.stats
import sunpy.map
from astropy.coordinates import SkyCoord
from sunpy.coordinates import frames

from gongsynth.analysis.disk import disk_coordinates, local_pixel_scale, map_wcs
from gongsynth.analysis.limb import limb_darkening
from gongsynth.analysis.noise import disk_centre_level, noise_estimate
from gongsynth.analysis.observations import BadHeaderWarning, load_observation
from gongsynth.analysis.statistics import (
    MAD_TO_SIGMA,
    field_histogram,
    pixel_difference_sigma,
    robust_sigma,
)

from .realdata import real_file

MDI_M = "mdi/mdi.fd_m_96m_lev182.20101015_000000_TAI.data.fits"
MDI_IC = "mdi/mdi.fd_ic.20101015_230100_TAI.data.fits"
MDI_SMALL = "mdi/mdi_fd_M_96m_01d.5874.0005_s.fits"
HMI_M = "hmi/JSOC_hmi.m_45s.20101020_000000_TAI.2.magnetogram.fits"


def full_disk_header(shape=(860, 860), scale=2.5):
    """A helioprojective GONG-like full-disk grid seen from Earth, disk centre at the array centre."""
    ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective, observer="earth",
                   obstime="2020-06-01T12:00")
    return sunpy.map.make_fitswcs_header(shape, ref, scale=[scale, scale] * u.arcsec / u.pix, unit=u.G)


@pytest.fixture(scope="module")
def quiet_sun():
    """Uniform quiet Sun: white Gaussian noise of sigma = 4 G on the disk, NaN on the sky."""
    header = full_disk_header()
    rho, _ = disk_coordinates(sunpy.map.Map(np.zeros((860, 860)), header))
    data = np.random.default_rng(2024).normal(0, 4.0, (860, 860))
    data[~(rho < 1)] = np.nan
    return sunpy.map.Map(data, header), 4.0


@pytest.fixture(scope="module")
def mdi():
    return load_observation(real_file(MDI_M))


@pytest.fixture(scope="module")
def hmi():
    with pytest.warns(BadHeaderWarning):
        return load_observation(real_file(HMI_M))


# ----------------------------------------------------------------------------- estimators


def test_robust_sigma_gaussian_and_outliers():
    rng = np.random.default_rng(5)
    x = rng.normal(10, 2.0, 200_000)
    # Standard error of the MAD estimator: 1.166 sigma / sqrt(N) = 0.26 %.
    assert robust_sigma(x) == pytest.approx(2.0, rel=0.01)
    x[:2000] = 1e4  # 1 % outliers (a magnetic element) barely move it
    assert robust_sigma(x) == pytest.approx(2.0, rel=0.03)
    assert np.std(x) > 100
    assert robust_sigma(x * u.G).unit == u.G
    assert MAD_TO_SIGMA == pytest.approx(1 / scipy.stats.norm.ppf(0.75))
    assert math.isnan(robust_sigma([np.nan]))


def test_pixel_difference_sigma_white_and_correlated_noise():
    rng = np.random.default_rng(6)
    noise = rng.normal(0, 3.0, (400, 400))
    yy, xx = np.mgrid[:400, :400]
    structure = 50 * np.sin(xx / 40.0) * np.cos(yy / 55.0)  # smooth: removed by differencing
    assert pixel_difference_sigma(noise + structure) == pytest.approx(3.0, rel=0.02)
    assert pixel_difference_sigma(noise + structure, robust=True) == pytest.approx(3.0, rel=0.03)
    # 2x2 running mean: neighbours share half their pixels; var(diff) = 2 * (1 - 1/2) * sigma_s^2
    # with sigma_s = 3/2, so the method gives 3/2/sqrt(2) = 1.06 instead of the true 1.5.
    smooth = 0.25 * (noise[1:, 1:] + noise[:-1, 1:] + noise[1:, :-1] + noise[:-1, :-1])
    assert np.std(smooth) == pytest.approx(1.5, rel=0.02)
    assert pixel_difference_sigma(smooth) == pytest.approx(1.5 / math.sqrt(2), rel=0.03)
    with pytest.raises(ValueError, match="2-D image"):
        pixel_difference_sigma(np.zeros(5))


def test_disk_coordinates_and_pixel_scale():
    m = sunpy.map.Map(np.zeros((860, 860)), full_disk_header())
    rho, mu = disk_coordinates(m)
    rsun = m.rsun_obs.to_value(u.arcsec)
    # 2.5" pixels: the limb is rsun / 2.5 pixels from the centre (429.5, 429.5).
    assert rho[430, 430 + int(rsun / 2.5) - 1] < 1 < rho[430, 430 + int(rsun / 2.5) + 1]
    assert np.nanmax(mu) == pytest.approx(1, abs=1e-5)
    assert np.all(np.isnan(mu[rho > 1]))
    assert local_pixel_scale(m).to_value(u.arcsec) == pytest.approx(2.5, rel=1e-6)


def test_the_remembered_wcs_follows_a_changed_header():
    m = sunpy.map.Map(np.zeros((64, 64)), full_disk_header())
    assert map_wcs(m) is map_wcs(m)   # built once per header
    before = local_pixel_scale(m)
    m.meta["cdelt1"] = m.meta["cdelt2"] = 2 * m.meta["cdelt1"]
    # the WCS is built again for the new header: twice the scale, not the stale one
    assert local_pixel_scale(m).to_value(u.arcsec) == pytest.approx(2 * before.to_value(u.arcsec), rel=1e-3)
    assert map_wcs(m).wcs.cdelt[0] == m.wcs.wcs.cdelt[0]


# ----------------------------------------------------------------------------- uniform quiet Sun


def _expected_min_of_normals(n):
    """E[min of n standard normal variates]."""
    pdf = scipy.stats.norm.pdf
    sf = scipy.stats.norm.sf
    return scipy.integrate.quad(lambda x: x * n * pdf(x) * sf(x) ** (n - 1), -12, 12)[0]


def test_noise_recovered_on_uniform_quiet_sun(quiet_sun):
    smap, sigma = quiet_sun
    est = noise_estimate(smap)
    n_box = len(est.box_std)
    assert n_box == 29 and est.box_pixels == 24  # 60" / 2.5"
    npix = est.box_pixels**2
    # Medians over boxes are unbiased; relative scatter per box 1/sqrt(2N) (std) and
    # 1.166/sqrt(N) (MAD); the median of n_box of them ~1.25x that / sqrt(n_box).  4 sigma:
    assert est.median_std.to_value(u.G) == pytest.approx(sigma, rel=4 * 1.25 / math.sqrt(2 * npix * n_box))
    assert est.median_sigma.to_value(u.G) == pytest.approx(
        sigma, rel=4 * 1.25 * 1.166 / math.sqrt(npix * n_box))
    # Box centres within 0.35 solar radii of disk centre.
    r = np.hypot(*est.box_centres.to_value(u.arcsec).T) / smap.rsun_obs.to_value(u.arcsec)
    assert r.max() == pytest.approx(0.35, rel=1e-6)
    # Pixel differences over the whole disk measure white noise without bias (0.1 % scatter).
    assert pixel_difference_sigma(smap.data) == pytest.approx(sigma, rel=0.005)


def test_quietest_box_noise_over_realisations():
    """The headline (quietest-box) noise on uniform quiet Suns, averaged over 8 realisations.

    Selecting the box with the smallest std biases it low: its std is expected at
    sigma (1 + E[min of 29 normals] / sqrt(2N)) = 0.94 sigma for N = 24 x 24; the robust
    sigma of that box follows.  Both must recover the simulated noise within 10 %.
    """
    header = full_disk_header()
    rho, _ = disk_coordinates(sunpy.map.Map(np.zeros((860, 860)), header))
    sigma = 4.0
    stds, sigmas = [], []
    for seed in range(8):
        data = np.random.default_rng(100 + seed).normal(0, sigma, (860, 860))
        data[~(rho < 1)] = np.nan
        est = noise_estimate(sunpy.map.Map(data, header))
        stds.append(est.std.to_value(u.G))
        sigmas.append(est.sigma.to_value(u.G))
    npix = 24 * 24
    expected = sigma * (1 + _expected_min_of_normals(29) / math.sqrt(2 * npix))
    # Scatter of the minimum of 29 normals is ~0.5 of one: 0.5 sigma / sqrt(2N) per realisation.
    assert np.mean(stds) == pytest.approx(expected, abs=4 * 0.5 * sigma / math.sqrt(2 * npix * 8))
    assert np.mean(stds) == pytest.approx(sigma, rel=0.10)
    assert np.mean(sigmas) == pytest.approx(sigma, rel=0.10)
    assert np.all(np.abs(np.array(sigmas) / sigma - 1) < 0.2)


def test_noise_estimate_ignores_a_magnetic_element_in_box(quiet_sun):
    smap, sigma = quiet_sun
    data = smap.data.copy()
    # A 4x4-pixel 500 G element at disk centre (inside the central box).
    data[428:432, 428:432] = 500.0
    est = noise_estimate(sunpy.map.Map(data, smap.meta), grid=1, max_radius=0.1)
    assert est.std.to_value(u.G) > 5 * sigma
    assert est.sigma.to_value(u.G) == pytest.approx(sigma, rel=0.1)


def test_noise_estimate_bad_input(quiet_sun):
    smap, _ = quiet_sun
    with pytest.raises(ValueError, match="layout"):
        noise_estimate(smap, layout="spiral")
    with pytest.raises(ValueError, match="at least 2 pixels"):
        noise_estimate(smap, box=2 * u.arcsec)
    with pytest.raises(u.UnitsError, match="box"):
        noise_estimate(smap, box=60 * u.km)
    with pytest.raises(ValueError, match="max_radius"):
        noise_estimate(smap, max_radius=-1)
    with pytest.raises(ValueError, match="no 24x24-pixel box"):
        noise_estimate(sunpy.map.Map(np.full((860, 860), np.nan), smap.meta))
    with pytest.raises(TypeError, match="sunpy Map"):
        noise_estimate(np.zeros((10, 10)))


# ----------------------------------------------------------------------------- PROVENANCE numbers


def test_mdi_quiet_sun_noise_as_in_provenance(mdi):
    """PROVENANCE: 30-px (60") boxes, 7x7 grid within 0.35 Rsun: quietest box std 10.7 G,
    robust sigma 9.7 G at (-0.23, -0.12) Rsun, median box std 15.3 G."""
    est = noise_estimate(mdi, box=30 * u.pix)
    assert len(est.box_std) == 29
    assert est.sigma.to_value(u.G) == pytest.approx(9.7, rel=0.10)
    assert est.std.to_value(u.G) == pytest.approx(10.7, rel=0.10)
    assert est.median_std.to_value(u.G) == pytest.approx(15.3, rel=0.10)
    assert est.mean.to_value(u.G) == pytest.approx(0.04, abs=0.2)
    centre = est.box_centres[est.quietest] / mdi.rsun_obs
    assert centre.to_value(u.one) == pytest.approx([-0.23, -0.12], abs=0.01)
    # "~60 arcsec" boxes give the same 30 pixels at MDI's 1.986"/pixel.
    assert noise_estimate(mdi).box_pixels == 30


def test_hmi_quiet_sun_noise_as_in_provenance(hmi):
    """PROVENANCE: quietest 100x100-px box std 8.8 G, robust sigma 7.3 G, pixel-difference 5.8 G;
    median box std 14.4 G (boxes on a 50-px grid over the cut-out, all within 0.35 Rsun)."""
    est = noise_estimate(hmi, box=100 * u.pix, layout="tiles", step=50)
    assert len(est.box_std) == 19 * 19
    assert est.sigma.to_value(u.G) == pytest.approx(7.3, rel=0.10)
    assert est.std.to_value(u.G) == pytest.approx(8.8, rel=0.10)
    assert est.difference.to_value(u.G) == pytest.approx(5.8, rel=0.10)
    assert est.median_std.to_value(u.G) == pytest.approx(14.4, rel=0.10)
    # 60" boxes (118 px at 0.509"/px) give the same quiet-Sun sigma within 10 %.
    est60 = noise_estimate(hmi, layout="tiles")
    assert est60.box_pixels == round(60 / local_pixel_scale(hmi).to_value(u.arcsec))
    assert est60.sigma.to_value(u.G) == pytest.approx(7.3, rel=0.10)


def test_small_mdi_noise_and_histogram_as_in_provenance():
    """PROVENANCE: 128x128 binned MDI: quietest 4-px box std 4.0 G; on-disk robust sigma 8.0 G."""
    m = load_observation(real_file(MDI_SMALL))
    assert noise_estimate(m, box=4 * u.pix).std.to_value(u.G) == pytest.approx(4.0, rel=0.10)
    assert field_histogram(m).robust_sigma.to_value(u.G) == pytest.approx(8.0, rel=0.05)


def test_mdi_histogram_numbers_as_in_provenance(mdi):
    """PROVENANCE: on disk (r < 0.98): std 27.6 G, robust sigma 13.2 G, percentiles -52.9 / 0.0 / +52.0 G."""
    h = field_histogram(mdi)
    assert h.std.to_value(u.G) == pytest.approx(27.6, rel=0.01)
    assert h.robust_sigma.to_value(u.G) == pytest.approx(13.2, rel=0.01)
    assert h.percentiles[1].to_value(u.G) == pytest.approx(-52.9, abs=0.3)
    assert h.percentiles[50].to_value(u.G) == pytest.approx(0.0, abs=0.1)
    assert h.percentiles[99].to_value(u.G) == pytest.approx(52.0, abs=0.3)
    assert h.counts.sum() + h.below + h.above == h.n
    finite = np.isfinite(mdi.data).sum()
    assert 0.9 * finite < h.n < finite


def test_hmi_histogram_numbers_as_in_provenance(hmi):
    """PROVENANCE (whole cut-out): std 51.7 G, robust sigma 8.5 G, p1/p99 -80.5 / +67.6 G."""
    h = field_histogram(hmi, max_radius=1.0)
    assert h.n == 1024 * 1024
    assert h.std.to_value(u.G) == pytest.approx(51.7, rel=0.01)
    assert h.robust_sigma.to_value(u.G) == pytest.approx(8.5, rel=0.01)
    assert h.percentiles[1].to_value(u.G) == pytest.approx(-80.5, abs=0.3)
    assert h.percentiles[99].to_value(u.G) == pytest.approx(67.6, abs=0.3)


# ----------------------------------------------------------------------------- histograms


def test_field_histogram_of_gaussian(quiet_sun):
    smap, sigma = quiet_sun
    h = field_histogram(smap)
    widths = np.diff(h.edges.to_value(u.G))
    assert np.sum(h.density.to_value(1 / u.G) * widths) == pytest.approx(
        (h.n - h.below - h.above) / h.n)
    edges = h.edges.to_value(u.G)
    expected = np.diff(scipy.stats.norm.cdf(edges, scale=sigma)) / widths  # mean density per bin
    counts_expected = expected * widths * h.n
    used = counts_expected > 100
    # Poisson: each bin within 5 sigma of its expected count.
    assert np.all(np.abs(h.counts[used] - counts_expected[used]) < 5 * np.sqrt(counts_expected[used]))
    assert np.allclose(h.density.to_value(1 / u.G)[used], expected[used], rtol=0.2)
    assert h.std.to_value(u.G) == pytest.approx(sigma, rel=0.01)
    assert h.mean_abs.to_value(u.G) == pytest.approx(sigma * math.sqrt(2 / math.pi), rel=0.01)
    a = field_histogram(smap, absolute=True)
    assert a.absolute and a.edges[0] == 1 * u.G
    assert np.all(np.diff(np.log(a.edges.value)) == pytest.approx(np.log(3000) / 60))
    rho, _ = disk_coordinates(smap)
    used = np.abs(smap.data[np.isfinite(smap.data) & (rho < 0.98)])
    assert a.n == used.size
    assert a.below == np.count_nonzero(used < 1)
    assert a.counts.sum() == np.count_nonzero((used >= 1) & (used <= 3000))
    custom = field_histogram(smap, bins=np.array([-10, 0, 10]) * u.G)
    assert custom.counts.sum() + custom.below + custom.above == custom.n


def test_field_histogram_bad_input(quiet_sun):
    smap, _ = quiet_sun
    with pytest.raises(ValueError, match="strictly increasing"):
        field_histogram(smap, bins=np.array([1, 0]) * u.G)
    with pytest.raises(TypeError, match="bins"):
        field_histogram(smap, bins="auto")
    with pytest.raises(ValueError, match="no finite pixel"):
        field_histogram(sunpy.map.Map(np.full((860, 860), np.nan), smap.meta))


# ----------------------------------------------------------------------------- count levels


def test_limb_darkening_law_recovered():
    header = full_disk_header((300, 300), 7.0)
    m = sunpy.map.Map(np.zeros((300, 300)), header)
    _, mu = disk_coordinates(m)
    a, b = 0.47, 0.23
    law = 1000 * (1 - a * (1 - mu) - b * (1 - mu) ** 2)
    prof = limb_darkening(sunpy.map.Map(np.nan_to_num(law, nan=0.0), header))
    assert prof.coefficients == pytest.approx((a, b), abs=2e-3)
    assert prof.centre_level.value == pytest.approx(1000, rel=1e-3)
    assert np.allclose(prof.intensity, prof.law(prof.mu), atol=2e-3)
    assert np.all(np.diff(prof.mu) < 0)


def test_mdi_continuum_levels_as_in_provenance():
    """PROVENANCE: quiet 60" box near centre mean 13 590, std 209; on-disk mean 11 570, std 1640."""
    ic = load_observation(real_file(MDI_IC), kind="continuum")
    quiet = noise_estimate(ic, box=30 * u.pix)
    assert quiet.mean.value == pytest.approx(13590, rel=0.01)
    assert quiet.std.value == pytest.approx(209, rel=0.05)
    h = field_histogram(ic, bins=np.linspace(0, 20000, 21) * u.one)
    assert h.mean.value == pytest.approx(11570, rel=0.005)
    assert h.std.value == pytest.approx(1640, rel=0.01)
    centre = disk_centre_level(ic)
    assert 13400 < centre.value < 13800
    prof = limb_darkening(ic)
    # Darker towards the limb, monotonically; the quadratic law fits the profile.
    assert np.all(np.diff(prof.intensity) < 0)
    assert prof.intensity[0] == pytest.approx(1, abs=0.02)
    assert np.allclose(prof.intensity, prof.law(prof.mu), atol=0.01)
    assert 0.5 < prof.law(0.3) < 0.8


def test_limb_darkening_bad_input(quiet_sun):
    smap, _ = quiet_sun
    with pytest.raises(ValueError, match="bins"):
        limb_darkening(smap, bins=1)
    with pytest.raises(ValueError, match="must be positive"):
        limb_darkening(sunpy.map.Map(np.where(np.isfinite(smap.data), -1.0, np.nan), smap.meta))


def test_warnings_are_not_swallowed_by_statistics(quiet_sun):
    smap, _ = quiet_sun
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        noise_estimate(smap)
        field_histogram(smap)
