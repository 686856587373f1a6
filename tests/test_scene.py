"""Tests of gongsynth.stages.scene.tiled: tiling, geometry, WCS and radiometry."""
import math

import astropy.units as u
import numpy as np
import pytest
import sunpy.map
from sunpy.coordinates import HeliographicStonyhurst, sun
from sunpy.sun.constants import radius as R_SUN

from gongsynth.geometry import DEFAULT_OBSTIME, Pointing, field_centre, viewing_geometry
from gongsynth.stages.channels import channel_images
from gongsynth.stages.optics import convolve, psf_kernel
from gongsynth.stages.scene import tiled as scene_mod
from gongsynth.stages.scene.scene import EARTH_RADIANCE_UNIT, radiance_at_earth, sky_grid
from gongsynth.stages.scene.tiled import tile, tiled_scenes
from gongsynth.sun.stokes import RADIANCE_UNIT, StokesCube

CHANNEL = u.Unit("erg / (s cm2 sr)")


def sinusoid_tile(n=64, axis=1):
    """One period of a cosine along ``axis``: f(u) = cos(2π u / n) at sample centres u = i + 0.5."""
    phase = 2 * np.pi * (np.arange(n) + 0.5) / n
    return np.cos(phase)[None, :].repeat(n, 0) if axis == 1 else np.cos(phase)[:, None].repeat(n, 1)


def fit_amplitude(x, values, period):
    """Least-squares amplitude and phase of a sinusoid of known period."""
    design = np.stack([np.cos(2 * np.pi * x / period), np.sin(2 * np.pi * x / period), np.ones_like(x)], 1)
    (a, b, _), *_ = np.linalg.lstsq(design, values, rcond=None)
    return math.hypot(a, b), math.atan2(b, a)


def mtf(nu):
    """Analytic MTF of Airy (D = 2.8 cm at 676.78 nm) times Gaussian seeing of 3.6″ FWHM."""
    nu_c = 0.028 / 676.78e-9 * math.pi / 648000
    s = min(nu / nu_c, 1.0)
    airy = 2 / math.pi * (math.acos(s) - s * math.sqrt(1 - s * s))
    sigma = 3.6 / (2 * math.sqrt(2 * math.log(2)))
    return airy * math.exp(-2 * math.pi**2 * sigma**2 * nu**2)


def test_default_obstime_has_b0_near_zero():
    assert abs(sun.B0(DEFAULT_OBSTIME).to_value(u.arcsec)) < 1
    mu, azimuth = viewing_geometry(60 * u.deg)
    assert mu == pytest.approx(0.5, abs=1e-5)
    assert azimuth == -90 * u.deg
    assert viewing_geometry(-30 * u.deg)[1] == 90 * u.deg


def test_radiance_at_earth_units():
    one_sr = 1 * u.Unit("erg / (s cm2 sr)")
    per_arcsec2 = radiance_at_earth(one_sr)
    assert per_arcsec2.unit == EARTH_RADIANCE_UNIT
    assert per_arcsec2.value == pytest.approx((math.pi / 648000) ** 2, rel=1e-12)
    spectral = radiance_at_earth(1 * u.Unit("W / (m2 sr nm)"))
    assert spectral.unit == u.Unit("erg / (s cm3 arcsec2)")
    assert spectral.value == pytest.approx(1e3 * 1e7 * (math.pi / 648000) ** 2, rel=1e-12)
    with pytest.raises(u.UnitsError, match="radiance"):
        radiance_at_earth(1 * u.Unit("erg / (s cm2)"))
    with pytest.raises(TypeError, match="Quantity"):
        radiance_at_earth(1.0)


def test_km_per_arcsec_is_the_distance_to_the_surface_point():
    from sunpy.coordinates import get_earth
    for latitude in (0, 60):
        _, kpa = field_centre(latitude * u.deg)
        earth = get_earth(DEFAULT_OBSTIME).radius.to_value(u.km)
        lat = math.radians(latitude)
        r = R_SUN.to_value(u.km)
        distance = math.sqrt((earth - r * math.cos(lat)) ** 2 + (r * math.sin(lat)) ** 2)
        assert kpa.to_value(u.km / u.arcsec) == pytest.approx(distance * math.pi / 648000, rel=1e-6)


@pytest.mark.parametrize("latitude", [60, -35])
def test_wcs_puts_the_field_centre_at_the_latitude(latitude):
    tile_img = np.ones((6, 64, 64)) * 1e6 * CHANNEL
    light, _ = tiled_scenes(tile_img, None, 96 * u.km, pointing=Pointing(latitude * u.deg), detector_shape=40)
    for header, shape in ((light.header, light.shape[1:]), (light.detector_header, light.detector_shape)):
        smap = sunpy.map.Map(np.zeros(shape), header)
        ny, nx = shape
        centre = smap.pixel_to_world((nx - 1) / 2 * u.pix, (ny - 1) / 2 * u.pix)
        hgs = centre.transform_to(HeliographicStonyhurst(obstime=DEFAULT_OBSTIME))
        assert hgs.lat.to_value(u.deg) == pytest.approx(latitude, abs=1e-6)
        assert hgs.lon.to_value(u.deg) == pytest.approx(0, abs=1e-6)


def test_wcs_and_tiling_agree_on_the_foreshortened_scale():
    """A small sky offset maps to the same heliographic displacement in the tiling and in sunpy."""
    from sunpy.coordinates import get_earth
    latitude = 60
    light, _ = tiled_scenes(np.ones((6, 64, 64)) * CHANNEL, None, 96 * u.km,
                            pointing=Pointing(latitude * u.deg), resolutions=(1,), detector_shape=40)
    kpa = light.meta["km_per_arcsec"].to_value(u.km / u.arcsec)
    smap = sunpy.map.Map(np.zeros(light.shape[1:]), light.header)
    c = (light.shape[1] - 1) / 2
    step = 4  # samples of 0.5": symmetric differences over ±2" cancel the curvature

    def hgs(dx, dy):
        return smap.pixel_to_world((c + dx) * u.pix, (c + dy) * u.pix).transform_to(
            HeliographicStonyhurst(obstime=DEFAULT_OBSTIME))

    offset = step * 0.5
    dlat = (hgs(0, step).lat - hgs(0, -step).lat).to_value(u.rad) / 2
    dlon = (hgs(step, 0).lon - hgs(-step, 0).lon).to_value(u.rad) / 2
    r = R_SUN.to_value(u.km)
    lat = math.radians(latitude)
    # East-west: no foreshortening on the central meridian.
    assert dlon * r * math.cos(lat) == pytest.approx(offset * kpa, rel=1e-4)
    # North-south: the true cosine of the viewing angle at the point, parallax
    # included (the line of sight from 1 au meets it at 60.23°, not 60°).
    earth = get_earth(DEFAULT_OBSTIME).radius.to_value(u.km)
    point = r * np.array([math.cos(lat), 0, math.sin(lat)])
    to_observer = np.array([earth, 0, 0]) - point
    mu_true = to_observer @ point / (np.linalg.norm(to_observer) * r)
    assert dlat * r * mu_true == pytest.approx(offset * kpa, rel=1e-3)
    # The tiling foreshortens by cos(latitude) (the paper's and the cube's μ):
    # 0.7 % from the true value at 60°.
    assert light.meta["mu"] == pytest.approx(0.5, abs=1e-5)
    assert mu_true / light.meta["mu"] == pytest.approx(1, abs=0.01)


def test_latitude_60_is_foreshortened_by_two_north_south():
    n, pixel = 64, 192 * u.km
    y, x = np.mgrid[:n, :n] + 0.5
    blob = np.exp(-((x - n / 2) ** 2 + (y - n / 2) ** 2) / (2 * 6.0**2))
    sky = tile(blob, pixel, pointing=Pointing(60 * u.deg), resolutions=(1,), detector_shape=24)
    ny, nx = sky.shape
    yy, xx = np.mgrid[:ny, :nx] - (ny - 1) / 2
    window = (np.abs(yy) < 8) & (np.abs(xx) < 16)  # half a period (16.7 × 33.5 samples)
    w = sky * window
    _, kpa = field_centre(60 * u.deg)
    column = 192 / kpa.to_value(u.km / u.arcsec) / 0.5  # tile column in samples along x
    # Remove the variance that sampling adds: the 1-sample footprint box (1/12)
    # and the tile's linear interpolation (column²/6, foreshortened along y).
    sy = math.sqrt((w * yy**2).sum() / w.sum() - 1 / 12 - (column / 2) ** 2 / 6)
    sx = math.sqrt((w * xx**2).sum() / w.sum() - 1 / 12 - column**2 / 6)
    assert sy / sx == pytest.approx(0.5, rel=3e-3)
    # Blob sigma: 6 tile pixels of 192 km, in 0.5" samples.
    assert sx == pytest.approx(6 * 192 / kpa.to_value(u.km / u.arcsec) / 0.5, rel=0.01)


@pytest.mark.parametrize("axis", [0, 1])
def test_quadrants_magnify_the_tile_by_their_resolution(axis):
    n, pixel = 64, 92 * u.km
    latitude = 60 * u.deg
    sky = tile(sinusoid_tile(n, axis), pixel, pointing=Pointing(latitude), resolutions=(1, 2, 4, 8),
               detector_shape=128)
    _, kpa = field_centre(latitude)
    mu, _ = viewing_geometry(latitude)
    scale = 0.5
    size = sky.shape[0]
    coord = (np.arange(size) + 0.5 - size / 2) * scale  # arcsec from the field centre
    half = size // 2
    quadrants = [(slice(0, half), slice(0, half)), (slice(0, half), slice(half, size)),
                 (slice(half, size), slice(0, half)), (slice(half, size), slice(half, size))]
    for (rows, cols), mag in zip(quadrants, (1, 2, 4, 8)):
        period = mag * n * pixel.to_value(u.km) / kpa.to_value(u.km / u.arcsec) * (mu if axis == 0 else 1)
        line = sky[rows, cols].mean(axis=1 - axis)
        # Each sample averages its footprint: a box of 0.5" damps the cosine by sinc.
        damping = np.sinc(scale / period)
        want = damping * np.cos(2 * np.pi * (n / 2 + coord[rows if axis == 0 else cols] / period * n) / n)
        assert np.max(np.abs(line - want)) < 0.01


def test_higher_resolution_quadrants_keep_proportionally_finer_structure():
    """After the PSF each quadrant's contrast is the MTF at the tile's sky frequency there."""
    n, pixel = 64, 92 * u.km
    sky = tile(sinusoid_tile(n, axis=1), pixel, resolutions=(1, 2, 4, 8), detector_shape=128)
    seen = convolve(sky, psf_kernel(0.5 * u.arcsec), boundary="reflect")
    _, kpa = field_centre(0 * u.deg)
    size = sky.shape[0]
    x = (np.arange(size) + 0.5 - size / 2) * 0.5
    half = size // 2
    contrasts = []
    for mag, cols in ((1, slice(40, half - 120)), (2, slice(half + 120, size - 40))):
        period = mag * n * pixel.to_value(u.km) / kpa.to_value(u.km / u.arcsec)
        amp, _ = fit_amplitude(x[cols], seen[40:half - 40, cols].mean(axis=0), period)
        contrasts.append(amp)
        assert amp == pytest.approx(mtf(1 / period), abs=0.02)
    assert contrasts[1] > 2 * contrasts[0]


def test_tiling_conserves_the_mean_over_whole_periods_and_is_periodic():
    det = 16
    _, kpa = field_centre(0 * u.deg)
    n = 50
    field = det * 2.5  # arcsec
    pixel = field / 2 * kpa.to_value(u.km / u.arcsec) / n * u.km  # two tiles across the field
    rng = np.random.default_rng(7)
    planes = rng.gamma(2.0, size=(6, n, n)) * 1e6 * CHANNEL
    kwargs = dict(pointing=Pointing(0 * u.deg), resolutions=(1,), detector_shape=det, shape=(76, 76))
    light, _ = tiled_scenes(planes, None, pixel, **kwargs)
    assert light.boundary == "periodic"  # whole tiles (μ = cos B0 = 1 - 1e-12)
    sky = tile(planes, pixel, **kwargs).value
    assert np.allclose(sky.mean(axis=(1, 2)), planes.value.mean(axis=(1, 2)), rtol=1e-9)
    # Quadrants, or a field that is not whole tiles: not periodic.
    assert tiled_scenes(planes, None, pixel, detector_shape=det)[0].boundary == "reflect"
    assert tiled_scenes(planes, None, pixel * 1.1, **kwargs)[0].boundary == "reflect"


def test_truth_is_placed_exactly_like_the_light():
    rng = np.random.default_rng(8)
    planes = rng.gamma(2.0, size=(6, 32, 32)) * 1e6 * CHANNEL
    blos = planes[2].value * 1e-4 * u.G
    light, truth = tiled_scenes(planes, blos, 150 * u.km, pointing=Pointing(30 * u.deg), detector_shape=20)
    factor = radiance_at_earth(1e4 * CHANNEL).value
    assert truth.data.unit == u.G and truth.shape == light.shape[1:]
    assert np.allclose(truth.data.value * factor, light.data[2].value, rtol=1e-12)
    assert truth.boundary == light.boundary and truth.header == light.header
    assert np.array_equal(light.place(blos, 150 * u.km), truth.data)
    assert np.array_equal(light.blos, truth.data)


def test_resolution_map_marks_the_quadrants():
    planes = np.ones((6, 32, 32)) * CHANNEL
    light, _ = tiled_scenes(planes, None, 150 * u.km, detector_shape=(10, 14))
    res = light.resolution_map()
    assert res.shape == (10, 14)
    assert np.all(res[:5, :7] == 1) and np.all(res[:5, 7:] == 2)
    assert np.all(res[5:, :7] == 4) and np.all(res[5:, 7:] == 8)
    uniform, _ = tiled_scenes(planes, None, 150 * u.km, resolutions=(1,), detector_shape=8)
    assert np.all(uniform.resolution_map() == 1)


def test_tiled_scene_from_a_stokes_cube():
    lam = np.linspace(676.73, 676.83, 51) * u.nm
    level = np.full((16, 16, 51), 3e14, dtype=np.float32) * RADIANCE_UNIT
    cube = StokesCube(level, 0 * level, 0 * level, 0 * level, lam, 300 * u.km, mu=0.5,
                      blos=np.full((16, 16), 100.0, dtype=np.float32) * u.G)
    pointing = Pointing(60 * u.deg)
    pointing.check_mu(cube.mu)
    scene, _ = tiled_scenes(channel_images(cube), cube.blos, cube.pixel_size, pointing=pointing,
                            detector_shape=12)
    assert scene.shape == (6, 60, 60)
    assert np.allclose(scene.blos.value, 100.0)
    assert np.allclose(scene.data[0].value, scene.data[0].value.mean())
    with pytest.raises(ValueError, match="mu"):
        Pointing(0 * u.deg).check_mu(cube.mu)
    with pytest.raises(ValueError, match="per-column mu"):
        Pointing(0 * u.deg).check_mu(np.ones((2, 2)))


def test_sky_grid_sizes():
    assert sky_grid() == ((4300, 4300), 0.5 * u.arcsec, (860, 860))
    shape, scale, det = sky_grid(shape=4096)
    assert shape == (4096, 4096) and scale.value == pytest.approx(2150 / 4096)
    with pytest.raises(ValueError, match="different pixel scales"):
        sky_grid(detector_shape=(10, 20), shape=(50, 50))


@pytest.mark.parametrize("latitude", [90, -90, 95, -120])
def test_latitude_out_of_range(latitude):
    with pytest.raises(ValueError, match="latitude"):
        tile(np.ones((8, 8)), 1000 * u.km, pointing=Pointing(latitude * u.deg), detector_shape=8)


def test_tile_smaller_than_a_pixel_is_rejected():
    # 8 columns of 150 km = 1.6" < 2.5"
    with pytest.raises(ValueError, match="smaller than one"):
        tile(np.ones((8, 8)), 150 * u.km, detector_shape=8)
    # Big enough face-on, too small once foreshortened at 80 deg.
    with pytest.raises(ValueError, match="smaller than one"):
        tile(np.ones((8, 8)), 400 * u.km, pointing=Pointing(80 * u.deg), detector_shape=8)


def test_other_bad_input():
    with pytest.raises(ValueError, match="resolutions"):
        tile(np.ones((8, 8)), 1000 * u.km, resolutions=(1, 2, 4), detector_shape=8)
    with pytest.raises(ValueError, match="resolutions"):
        tile(np.ones((8, 8)), 1000 * u.km, resolutions=(1, 0, 4, 8), detector_shape=8)
    with pytest.raises(u.UnitsError):
        tile(np.ones((8, 8)), 1000 * u.arcsec, detector_shape=8)
    with pytest.raises(u.UnitsError):
        tiled_scenes(np.ones((6, 8, 8)) * u.G, None, 1000 * u.km, detector_shape=8)
    with pytest.raises(ValueError, match=r"\(6, ny, nx\)"):
        tiled_scenes(np.ones((5, 8, 8)) * CHANNEL, None, 1000 * u.km, detector_shape=8)
    with pytest.raises(ValueError, match="non-finite"):
        tile(np.full((8, 8), np.nan), 1000 * u.km, detector_shape=8)
    with pytest.raises(ValueError, match="blos"):
        tiled_scenes(np.ones((6, 8, 8)) * CHANNEL, np.ones((4, 4)) * u.G, 1000 * u.km, detector_shape=8)


def test_module_exports():
    for name in scene_mod.__all__:
        assert hasattr(scene_mod, name)


def test_deferred_scene_rows_are_the_whole_scene_bit_for_bit():
    """A tiled scene made a block of rows at a time (one thread) equals the whole one (threads), exactly."""
    from gongsynth.stages.scene.scene import DeferredStack

    rng = np.random.default_rng(8)
    planes = rng.uniform(1e6, 2e6, (6, 40, 48)) * u.Unit("erg / (s cm2 sr)")
    light, truth = tiled_scenes(planes, rng.normal(0, 100, (40, 48)) * u.G, 300 * u.km, detector_shape=64,
                                pointing=Pointing(30 * u.deg))
    assert isinstance(light.planes, DeferredStack) and isinstance(truth.planes, DeferredStack)
    assert light.shape == (6, 320, 320) and light.planes.unit == EARTH_RADIANCE_UNIT
    blocks = [np.concatenate([light.planes[i][r:r + 37] for r in range(0, 320, 37)]) for i in range(6)]
    eager = tile(radiance_at_earth(planes), 300 * u.km, detector_shape=64, pointing=Pointing(30 * u.deg),
                 dtype=np.float32)
    assert np.array_equal(np.stack(blocks), eager.value)
    with pytest.raises(TypeError, match="row slices"):
        light.planes[0][::2]
    assert np.array_equal(light.data.value, eager.value)  # made whole on first access, then kept
    assert light.data is light.data
    assert np.array_equal(light.blos, truth.data)
