"""degrade_to_gong, compare and compare_files: analytic checks and real MDI / HMI / GONG-format data."""
import json
import math

import astropy.units as u
import numpy as np
import pytest
import sunpy.map
from astropy.coordinates import SkyCoord
from sunpy.coordinates import frames

from gongsynth import GONGInstrument
from gongsynth.analysis.compare import (
    ComparisonReport,
    compare,
    compare_files,
    compare_limb_darkening,
    degrade_to_gong,
    load_observation,
    noise_estimate,
)
from gongsynth.analysis.disk import disk_coordinates, local_pixel_scale
from gongsynth.analysis.observations import BadHeaderWarning, ObservationKindError

from .realdata import gong_rho, real_file, write_gong_fits

MDI_M = "mdi/mdi.fd_m_96m_lev182.20101015_000000_TAI.data.fits"
MDI_IC = "mdi/mdi.fd_ic.20101015_230100_TAI.data.fits"
HMI_M = "hmi/JSOC_hmi.m_45s.20101020_000000_TAI.2.magnetogram.fits"


def hpc_map(data, scale, *, ref_pixel=None, rotation_angle=None, centre=(0, 0)):
    """A helioprojective map seen from Earth with square pixels of ``scale`` arcsec."""
    ref = SkyCoord(centre[0] * u.arcsec, centre[1] * u.arcsec, frame=frames.Helioprojective,
                   observer="earth", obstime="2020-06-01T12:00")
    kwargs = {}
    if ref_pixel is not None:
        kwargs["reference_pixel"] = u.Quantity(ref_pixel, u.pix)
    if rotation_angle is not None:
        kwargs["rotation_angle"] = rotation_angle
    header = sunpy.map.make_fitswcs_header(np.shape(data), ref, scale=[scale, scale] * u.arcsec / u.pix,
                                           unit=u.G, **kwargs)
    return sunpy.map.Map(np.asarray(data, dtype=float), header)


def gaussian_kernel(sigma_arcsec):
    """A unit-sum Gaussian PSF as a callable of the pixel scale (what psf= accepts)."""
    def kernel(pixel_scale):
        s = sigma_arcsec / pixel_scale.to_value(u.arcsec)
        half = int(math.ceil(6 * s))
        x = np.arange(-half, half + 1)
        k = np.exp(-0.5 * (x[:, None] ** 2 + x[None, :] ** 2) / s**2)
        return k / k.sum()
    return kernel


def world_centroid(smap):
    """Flux-weighted helioprojective centroid (arcsec) of a map."""
    data = np.nan_to_num(smap.data)
    c = sunpy.map.all_coordinates_from_map(smap)
    w = data / data.sum()
    return float(np.sum(w * c.Tx.to_value(u.arcsec))), float(np.sum(w * c.Ty.to_value(u.arcsec)))


def world_variance(smap, centroid):
    data = np.nan_to_num(smap.data)
    c = sunpy.map.all_coordinates_from_map(smap)
    w = data / data.sum()
    return (float(np.sum(w * (c.Tx.to_value(u.arcsec) - centroid[0]) ** 2)),
            float(np.sum(w * (c.Ty.to_value(u.arcsec) - centroid[1]) ** 2)))


# ----------------------------------------------------------------------------- degrade_to_gong


def test_integer_binning_of_white_noise_and_wcs():
    rng = np.random.default_rng(1)
    m = hpc_map(rng.normal(0, 5.0, (500, 500)), 0.5)
    g = degrade_to_gong(m, psf=False)
    assert g.data.shape == (100, 100)
    assert g.scale.axis1 == 2.5 * u.arcsec / u.pix and g.scale.axis2 == 2.5 * u.arcsec / u.pix
    # 5x5 means of independent pixels: sigma / 5 (std estimate over 1e4 values: 0.7 %).
    assert np.std(g.data) == pytest.approx(1.0, rel=0.03)
    # Each GONG pixel is exactly the mean of its 5x5 block ...
    assert g.data[7, 11] == pytest.approx(m.data[35:40, 55:60].mean(), rel=1e-12)
    # ... and sits at the mean world position of that block.
    block = m.pixel_to_world(np.arange(55, 60) * u.pix, np.arange(35, 40) * u.pix)
    c = g.pixel_to_world(11 * u.pix, 7 * u.pix)
    assert c.Tx.to_value(u.arcsec) == pytest.approx(block.Tx.to_value(u.arcsec).mean(), abs=1e-6)
    assert c.Ty.to_value(u.arcsec) == pytest.approx(block.Ty.to_value(u.arcsec).mean(), abs=1e-6)
    assert "area-weighted" in g.meta["history"]


def test_flux_and_position_conserved_at_mdi_scale():
    """Non-integer ratio (MDI's 1.986"): flux, centroid and second moments are kept."""
    scale = 1.986
    n = 301
    ref = (150.3, 149.8)
    yy, xx = np.mgrid[:n, :n]
    x0, y0, w = 170.4, 133.7, 3.0  # pixel position and width (pixels) of a compact blob
    blob = np.exp(-0.5 * ((xx - x0) ** 2 + (yy - y0) ** 2) / w**2)
    m = hpc_map(blob, scale, ref_pixel=ref, centre=(-200, 300))
    g = degrade_to_gong(m, psf=False)
    assert np.nansum(g.data) * 2.5**2 == pytest.approx(blob.sum() * scale**2, rel=1e-10)
    cm, cg = world_centroid(m), world_centroid(g)
    assert cg == pytest.approx(cm, abs=0.01)
    # The input pixels (top hats of 1.986") are spread over GONG pixels whose centres stand
    # for them (Sheppard: + 2.5^2 / 12): the variance grows by (1.986^2 + 2.5^2) / 12 per axis.
    vm, vg = world_variance(m, cm), world_variance(g, cm)
    assert np.array(vg) - np.array(vm) == pytest.approx((2.5**2 + scale**2) / 12 * np.ones(2), rel=0.02)
    # The reference coordinate is kept.
    assert g.reference_coordinate.Tx.to_value(u.arcsec) == pytest.approx(-200)
    assert g.reference_coordinate.Ty.to_value(u.arcsec) == pytest.approx(300)


def test_psf_width_adds_in_quadrature():
    scale, sigma_psf = 0.5, 2.0
    point = np.zeros((241, 241))
    point[120, 120] = 1.0
    m = hpc_map(point, scale, ref_pixel=(120, 120))
    g = degrade_to_gong(m, psf=gaussian_kernel(sigma_psf))
    c = world_centroid(g)
    assert c == pytest.approx((0, 0), abs=1e-4)
    var = world_variance(g, c)
    expected = sigma_psf**2 + (scale**2 + 2.5**2) / 12
    assert var == pytest.approx((expected, expected), rel=0.01)
    assert np.nansum(g.data) * 2.5**2 == pytest.approx(scale**2, rel=1e-9)


def test_gong_psf_from_optics_is_the_default():
    optics = pytest.importorskip("gongsynth.stages.optics")
    point = np.zeros((201, 201))
    point[100, 100] = 1.0
    m = hpc_map(point, 0.5, ref_pixel=(100, 100))
    g = degrade_to_gong(m)
    kernel = optics.psf_kernel(0.5 * u.arcsec)
    g_explicit = degrade_to_gong(m, psf=kernel)
    assert np.allclose(g.data, g_explicit.data, equal_nan=True)
    assert np.nansum(g.data) * 2.5**2 == pytest.approx(0.25 * kernel[50:-50, 50:-50].sum() / kernel.sum(),
                                                        rel=0.02)
    # Airy (D = 2.8 cm) + 3.6" seeing: wider than seeing alone, narrower than a 4x wider PSF.
    seeing = degrade_to_gong(m, psf=gaussian_kernel(3.6 / 2.3548))
    assert np.nanmax(g.data) < np.nanmax(seeing.data)
    # native_fwhm reduces the seeing: a sharper result, and a zero-seeing limit.
    sharper = degrade_to_gong(m, native_fwhm=3.0 * u.arcsec)
    airy_only = degrade_to_gong(m, native_fwhm=10 * u.arcsec)
    nothing = GONGInstrument().replace(seeing_fwhm=0 * u.arcsec)
    assert np.allclose(airy_only.data, degrade_to_gong(m, nothing).data, equal_nan=True)
    assert np.nanmax(g.data) < np.nanmax(sharper.data) < np.nanmax(airy_only.data)


def test_nan_sky_stays_out_of_the_disk():
    m = hpc_map(np.zeros((1100, 1100)), 2.0)
    rho, _ = disk_coordinates(m)
    data = np.where(rho < 1, 10.0, np.nan)
    g = degrade_to_gong(hpc_map(data, 2.0), psf=gaussian_kernel(2.0))
    rho_g, _ = disk_coordinates(g)
    # A uniform disk stays uniform up to the limb (normalised convolution), sky stays NaN.
    inside = rho_g < 0.99
    assert np.allclose(g.data[inside], 10.0, rtol=1e-9)
    assert np.all(np.isnan(g.data[rho_g > 1.01]))


def test_rotated_map_is_aligned_with_solar_north():
    n = 201
    yy, xx = np.mgrid[:n, :n]
    blob = np.exp(-0.5 * ((xx - 140) ** 2 + (yy - 80) ** 2) / 4.0**2)
    upright = hpc_map(blob, 1.0, ref_pixel=(100, 100))
    target = world_centroid(upright)
    # The same sky, stored upside down (an HMI-style 180-degree roll).
    flipped = hpc_map(blob[::-1, ::-1], 1.0, ref_pixel=(100, 100), rotation_angle=180 * u.deg)
    assert world_centroid(flipped) == pytest.approx(target, abs=1e-6)
    g = degrade_to_gong(flipped, psf=False)
    assert np.allclose(g.rotation_matrix, np.eye(2))
    assert world_centroid(g) == pytest.approx(target, abs=0.05)
    # Same grid on the sky as from the upright map (rotation pads the array: shifted by
    # whole pixels), and the same values there.
    g_up = degrade_to_gong(upright, psf=False)
    shift = np.array([g.reference_pixel.x.value - g_up.reference_pixel.x.value,
                      g.reference_pixel.y.value - g_up.reference_pixel.y.value])
    assert shift == pytest.approx(np.round(shift), abs=1e-9)
    dx, dy = np.round(shift).astype(int)
    ny, nx = g_up.data.shape
    common = g.data[dy:dy + ny, dx:dx + nx]
    ok = np.isfinite(common) & np.isfinite(g_up.data)
    assert ok.mean() > 0.95
    assert np.max(np.abs(common[ok] - g_up.data[ok])) < 1e-6


def test_degrade_bad_input():
    m = hpc_map(np.zeros((50, 50)), 0.5)
    with pytest.raises(TypeError, match="sunpy Map"):
        degrade_to_gong(np.zeros((10, 10)))
    with pytest.raises(ValueError, match="no finite pixel"):
        degrade_to_gong(hpc_map(np.full((50, 50), np.nan), 0.5))
    with pytest.raises(ValueError, match="psf must be a finite 2-D kernel"):
        degrade_to_gong(m, psf=np.ones(5))
    with pytest.raises(ValueError, match="psf must be a finite 2-D kernel"):
        degrade_to_gong(m, psf=np.full((3, 3), np.nan))
    with pytest.raises(ValueError, match="native_fwhm"):
        degrade_to_gong(m, psf=np.ones((3, 3)), native_fwhm=1 * u.arcsec)
    with pytest.raises(u.UnitsError, match="native_fwhm"):
        degrade_to_gong(m, native_fwhm=1 * u.km)
    with pytest.raises(ValueError, match="min_coverage"):
        degrade_to_gong(m, psf=False, min_coverage=0)
    with pytest.raises(ValueError, match="instrument must be one of"):
        degrade_to_gong(m, instrument="spectroheliograph")


# ----------------------------------------------------------------------------- real data


@pytest.fixture(scope="module")
def mdi():
    return load_observation(real_file(MDI_M))


@pytest.fixture(scope="module")
def mdi_gong(mdi):
    return degrade_to_gong(mdi)


def test_real_mdi_degraded_to_gong(mdi, mdi_gong):
    g = mdi_gong
    assert g.scale.axis1 == 2.5 * u.arcsec / u.pix
    assert g.unit == u.G
    assert g.date == mdi.date and g.reference_date == mdi.reference_date
    assert g.rsun_obs == mdi.rsun_obs
    # Same tangent point (disk centre); GONG pixel edges at whole multiples of 2.5" from it.
    assert g.reference_coordinate.Tx == mdi.reference_coordinate.Tx == 0 * u.arcsec
    ref = g.reference_pixel
    for value in (ref.x.value, ref.y.value):
        assert value + 0.5 == pytest.approx(round(value + 0.5), abs=1e-9)
    # The GONG grid covers MDI's field of view (1024 x 1.986") by less than one extra pixel.
    for axis, (n_in, ref_in, ref_out) in enumerate(((1024, mdi.reference_pixel.x.value, ref.x.value),
                                                    (1024, mdi.reference_pixel.y.value, ref.y.value))):
        low_in = (-0.5 - ref_in) * 1.98600817
        high_in = (n_in - 0.5 - ref_in) * 1.98600817
        low_out = (-0.5 - ref_out) * 2.5
        high_out = (g.data.shape[1 - axis] - 0.5 - ref_out) * 2.5
        assert low_out <= low_in < low_out + 2.5
        assert high_out - 2.5 < high_in <= high_out
    # The total signed flux over the disk is conserved (off-limb pixels are NaN).
    rho_m, _ = disk_coordinates(mdi)
    rho_g, _ = disk_coordinates(g)
    flux_m = np.nansum(np.where(rho_m < 0.9, mdi.data, 0)) * 1.98600817**2
    flux_g = np.nansum(np.where(rho_g < 0.9, g.data, 0)) * 2.5**2
    abs_m = np.nansum(np.where(rho_m < 0.9, np.abs(mdi.data), 0)) * 1.98600817**2
    assert abs(flux_g - flux_m) < 0.01 * abs_m
    # Noise: smoothing by the GONG PSF lowers the quiet-Sun noise well below MDI's 9.7 G.
    n_m = noise_estimate(mdi)
    n_g = noise_estimate(g)
    assert n_g.sigma < 0.5 * n_m.sigma
    # ... and correlates neighbours, so the pixel-difference method now reads low.
    assert n_g.difference < 0.8 * n_g.sigma


def test_real_hmi_postel_patch_degraded_to_gong():
    with pytest.warns(BadHeaderWarning):
        hmi = load_observation(real_file(HMI_M))
    g = degrade_to_gong(hmi)
    assert isinstance(g.coordinate_frame, frames.Helioprojective)
    assert local_pixel_scale(g).to_value(u.arcsec) == pytest.approx(2.5, rel=1e-6)
    assert g.date == hmi.date and g.reference_date == hmi.reference_date
    assert g.observer_coordinate.separation_3d(hmi.observer_coordinate) < 1 * u.km
    # About 1024 x 0.505" / 2.5" = 207 GONG pixels across, centred on disk centre.
    assert 200 <= g.data.shape[0] <= 212
    x, y = g.wcs.world_to_pixel(SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=g.coordinate_frame))
    assert float(x) == pytest.approx((g.data.shape[1] - 1) / 2, abs=1)
    assert float(y) == pytest.approx((g.data.shape[0] - 1) / 2, abs=1)
    # The mean field over the same 300" x 300" of sky is kept by the flux-conserving steps
    # (up to what the PSF carries across the box edges).
    means = []
    for smap in (hmi, g):
        c = sunpy.map.all_coordinates_from_map(smap).transform_to(g.coordinate_frame)
        box = (np.abs(c.Tx) < 150 * u.arcsec) & (np.abs(c.Ty) < 150 * u.arcsec)
        means.append(np.nanmean(smap.data[box]))
    assert means[1] == pytest.approx(means[0], abs=0.05 * np.nanmean(np.abs(hmi.data)))


# ----------------------------------------------------------------------------- compare


def test_compare_two_noise_maps_numbers():
    header_map = hpc_map(np.zeros((860, 860)), 2.5)
    rho, _ = disk_coordinates(header_map)
    rng = np.random.default_rng(3)
    a = np.where(rho < 1, rng.normal(0, 3.0, rho.shape), np.nan)
    b = np.where(rho < 1, rng.normal(0, 6.0, rho.shape), np.nan)
    report = compare(hpc_map(a, 2.5), hpc_map(b, 2.5), plot=False, statistics=False)
    assert isinstance(report, ComparisonReport)
    assert not report.sim.degraded and not report.obs.degraded
    assert report.ratios["noise_median_std"] == pytest.approx(0.5, rel=0.03)
    assert report.ratios["std"] == pytest.approx(0.5, rel=0.01)
    assert report.ratios["noise_sigma"] == pytest.approx(0.5, rel=0.10)
    # KS distance of N(0, 3) and N(0, 6): max |Phi(x/3) - Phi(x/6)| at x = 3 sqrt(8 ln2 / 3).
    from scipy.stats import norm

    x = 3 * math.sqrt(8 * math.log(2) / 3)
    assert report.cdf_distance == pytest.approx(norm.cdf(x / 3) - norm.cdf(x / 6), abs=0.02)
    assert report.figure is None
    data = json.loads(report.to_json())
    assert data["sim"]["std"] == pytest.approx(3.0, rel=0.01)
    assert "noise: robust sigma [G]" in str(report)


def test_compare_simulated_gong_format_with_real_mdi(tmp_path, mdi):
    rng = np.random.default_rng(8)
    sim_path = write_gong_fits(tmp_path / "sim.fits", rng.normal(0, 3.0, (860, 860)))
    sim = load_observation(sim_path)
    report = compare(sim, mdi, labels=("GONG-format", "MDI"), statistics=False)
    assert report.obs.degraded and not report.sim.degraded
    assert report.obs.pixel_scale.to_value(u.arcsec) == pytest.approx(2.5)
    assert report.sim.noise.sigma.to_value(u.G) == pytest.approx(3.0, rel=0.10)
    fig = report.figure
    assert len([ax for ax in fig.axes if ax.get_visible()]) >= 6
    assert any(ax.get_yscale() == "log" and ax.get_xscale() == "log" for ax in fig.axes)
    out = tmp_path / "cmp.png"
    fig.savefig(out, dpi=50)
    assert out.stat().st_size > 10_000


def test_compare_bad_input():
    m = hpc_map(np.zeros((100, 100)), 2.5)
    with pytest.raises(ValueError, match="labels"):
        compare(m, m, labels=("one",), plot=False)
    with pytest.raises(ValueError, match="degrade"):
        compare(m, m, degrade="sometimes", plot=False)
    intensity = sunpy.map.Map(np.ones((100, 100)), {**m.meta, "bunit": "ct"})
    with pytest.raises(ValueError, match="magnetogram in gauss"):
        compare(m, intensity, plot=False)


# ----------------------------------------------------------------------------- compare_files


def test_compare_files_writes_figure_and_refuses_overwrite(tmp_path):
    rng = np.random.default_rng(9)
    rho = gong_rho()
    sim = write_gong_fits(tmp_path / "sim.fits", rng.normal(0, 3.0, rho.shape))
    obs = write_gong_fits(tmp_path / "obs.fits", rng.normal(0, 5.0, rho.shape))
    out = tmp_path / "compare.png"
    report = compare_files(sim, obs, out=out, statistics=False)   # the table: test_command_line_compare
    assert out.stat().st_size > 10_000
    assert report.ratios["noise_median_std"] == pytest.approx(0.6, rel=0.05)
    assert "sim.fits" in report.sim.label and "obs.fits" in report.obs.label
    with pytest.raises(FileExistsError, match="overwrite"):
        compare_files(sim, obs, out=out)
    compare_files(sim, obs, out=out, overwrite=True, statistics=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["compare.png", "obs.fits", "sim.fits"]
    assert compare_files(sim, obs, statistics=False).figure is None
    with pytest.raises(FileNotFoundError, match="folder"):
        compare_files(sim, obs, out=tmp_path / "missing" / "c.png")


def test_compare_files_refuses_continuum(tmp_path):
    sim = write_gong_fits(tmp_path / "sim.fits", np.zeros((860, 860)))
    with pytest.raises(ObservationKindError, match="not a magnetogram"):
        compare_files(sim, real_file(MDI_IC))


# ----------------------------------------------------------------------------- count levels


def test_compare_limb_darkening_of_two_laws():
    m = hpc_map(np.zeros((300, 300)), 7.0)
    _, mu = disk_coordinates(m)
    laws = [(0.47, 0.23, 500.0), (0.55, 0.10, 2000.0)]
    maps = [hpc_map(np.nan_to_num(level * (1 - a * (1 - mu) - b * (1 - mu) ** 2)), 7.0)
            for a, b, level in laws]
    result = compare_limb_darkening(*maps, labels=("A", "B"))
    assert result.centre_ratio == pytest.approx(0.25, rel=1e-3)
    x = 1 - result.sim.mu
    expected = np.abs((laws[0][0] - laws[1][0]) * x + (laws[0][1] - laws[1][1]) * x**2)
    assert result.max_difference == pytest.approx(expected.max(), abs=2e-3)
    assert result.sim.coefficients == pytest.approx(laws[0][:2], abs=2e-3)
    assert result.obs.coefficients == pytest.approx(laws[1][:2], abs=2e-3)
    assert len(result.figure.axes) == 2


def test_real_mdi_continuum_limb_darkening_survives_degradation():
    ic = load_observation(real_file(MDI_IC), kind="continuum")
    result = compare_limb_darkening(ic, degrade_to_gong(ic), degrade=False, plot=False)
    # The PSF moves light only near the limb: profiles agree to < 1 % inside mu = 0.3.
    inner = result.sim.mu > 0.3
    assert np.max(np.abs(result.sim.intensity[inner] - result.obs.intensity[inner])) < 0.01
    assert result.centre_ratio == pytest.approx(1, abs=0.005)
    with pytest.raises(ValueError, match="degrade"):
        compare_limb_darkening(ic, ic, degrade="maybe")


# ----------------------------------------------------------------------------- gongsynth products


def test_gongsynth_product_file_compared_off_disk_centre(tmp_path):
    from gongsynth.geometry import field_centre
    from gongsynth.products import maps

    rng = np.random.default_rng(12)
    # A 120 x 120 field (300") at 60 degrees latitude: no quiet box near disk centre lies on it.
    centre, _ = field_centre(60 * u.deg)
    sim = maps.make_product_map(rng.normal(0, 3, (120, 120)) * u.G, centre=centre, scale=2.5 * u.arcsec,
                                product="magnetogram")
    path = tmp_path / "sim_magnetogram.fits"
    sim.save(path)
    loaded = load_observation(path)
    assert type(loaded).__name__ == "GONGSynthMap" and loaded.unit == u.G
    with pytest.raises(ValueError, match="no 24x24-pixel box"):
        noise_estimate(loaded)
    report = compare(loaded, loaded, plot=False, statistics=False)
    assert report.sim.noise.layout == "tiles"
    assert report.sim.noise.median_std.to_value(u.G) == pytest.approx(3.0, rel=0.05)
    cont = maps.make_product_map(np.ones((40, 40)) * u.adu, centre=centre, scale=2.5 * u.arcsec,
                                 product="continuum")
    cont_path = tmp_path / "sim_continuum.fits"
    cont.save(cont_path)
    with pytest.raises(ObservationKindError, match="PSEUDO-CONTINUUM"):
        load_observation(cont_path)


def test_command_line_compare(tmp_path, capsys):
    cli = pytest.importorskip("gongsynth.cli")
    rng = np.random.default_rng(13)
    sim = write_gong_fits(tmp_path / "sim.fits", rng.normal(0, 3.0, (860, 860)))
    obs = write_gong_fits(tmp_path / "obs.fits", rng.normal(0, 4.0, (860, 860)))
    out = tmp_path / "cmp.png"
    assert cli.main(["compare", str(sim), str(obs), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "noise: robust sigma [G]" in printed and "KS distance" in printed
    assert "KS, medians removed" in printed and "power ratio 5-100 Mm" in printed   # the statistics table
    assert out.stat().st_size > 10_000
    assert cli.main(["compare", str(sim), str(obs), "--out", str(out)]) == 3  # refuses to overwrite
    assert "overwrite" in capsys.readouterr().err
    continuum = real_file(MDI_IC)
    assert cli.main(["compare", str(sim), str(continuum)]) == 2
    assert "not a magnetogram" in capsys.readouterr().err
