"""Tests of gongsynth.stages.scene.fulldisk: disk geometry and full-disk scenes."""
import math

import astropy.units as u
import numpy as np
import pytest
import sunpy.map
from astropy.time import Time
from sunpy.coordinates import HeliographicStonyhurst, get_earth, sun

from gongsynth import GONGInstrument
from gongsynth.geometry import DEFAULT_OBSTIME, disk_geometry, wcs_header
from gongsynth.stages.channels import channel_images
from gongsynth.stages.optics import expected_counts
from gongsynth.stages.scene import fulldisk
from gongsynth.stages.scene.fulldisk import full_disk_scene
from gongsynth.stages.scene.scene import radiance_at_earth
from gongsynth.sun.photosphere import Photosphere, synthesize

# A coarse instrument that sees the whole disk on a small detector (fast tests).
COARSE = GONGInstrument(plate_scale=25 * u.arcsec)


def uniform_photosphere(shape=(8, 8), field=0.0, inclination=0.0, azimuth=0.0, pixel_size=500 * u.km):
    ones = np.ones(shape)
    zero = np.zeros(shape) * u.km / u.s
    return Photosphere(field * ones * u.G, inclination * ones * u.deg, azimuth * ones * u.deg,
                       zero, zero, zero, ones, pixel_size, periodic=True)


def random_photosphere(shape=(24, 24), seed=0, pixel_size=3000 * u.km):
    rng = np.random.default_rng(seed)
    return Photosphere(rng.uniform(0, 2000, shape) * u.G, rng.uniform(0, 180, shape) * u.deg,
                       rng.uniform(-180, 180, shape) * u.deg, rng.normal(0, 1, shape) * u.km / u.s,
                       rng.normal(0, 1, shape) * u.km / u.s, rng.normal(0, 1, shape) * u.km / u.s,
                       rng.uniform(0.5, 1.1, shape), pixel_size, periodic=True)


@pytest.mark.parametrize("obstime", [None, "2019-03-07T00:00"])  # B0 ≈ 0 and B0 = -7.2°
def test_geometry_matches_sunpy(obstime):
    shape, scale = (43, 47), 50 * u.arcsec
    g = disk_geometry(shape, scale, obstime=obstime)
    time = DEFAULT_OBSTIME if obstime is None else Time(obstime)
    from astropy.coordinates import SkyCoord
    from sunpy.coordinates import Helioprojective
    frame = Helioprojective(observer=get_earth(time), obstime=time)
    centre = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frame)
    smap = sunpy.map.Map(np.zeros(shape), wcs_header(shape, scale, centre))
    yy, xx = np.mgrid[:shape[0], :shape[1]]
    hgs = smap.pixel_to_world(xx * u.pix, yy * u.pix).transform_to(HeliographicStonyhurst(obstime=time))
    on = np.isfinite(hgs.lat.value)
    assert np.array_equal(on, g.on_disk) and on.sum() > 1000
    assert np.nanmax(np.abs(hgs.lat.deg - g.latitude)) < 1e-6
    assert np.nanmax(np.abs(hgs.lon.deg - g.longitude)) < 1e-6
    # μ: the angle between the local vertical and the direction to the observer.
    p = hgs.cartesian.xyz.to_value(u.km)
    to_obs = get_earth(time).cartesian.xyz.to_value(u.km)[:, None, None] - p
    mu = (to_obs * p).sum(0) / (np.linalg.norm(to_obs, axis=0) * np.linalg.norm(p, axis=0))
    assert np.nanmax(np.abs(mu - g.mu)) < 1e-8
    assert np.all(g.mu[~on] == 0)
    # The limb lies at the angular radius seen from Earth.
    r = np.hypot((xx - (shape[1] - 1) / 2), (yy - (shape[0] - 1) / 2)) * scale.value
    limb = sun.angular_radius(time).to_value(u.arcsec)
    assert np.all(g.on_disk[r < limb - 1]) and not np.any(g.on_disk[r > limb + 1])


def test_line_of_sight_azimuth_conventions():
    """CONTRACTS: north of disk centre on the central meridian a = -90°, south +90°."""
    g = disk_geometry((41, 41), 40 * u.arcsec)
    c = 20
    assert g.los_azimuth[c + 10, c] == pytest.approx(-90, abs=0.01)  # north
    assert g.los_azimuth[c - 10, c] == pytest.approx(90, abs=0.01)  # south
    assert abs(g.los_azimuth[c, c + 10]) == pytest.approx(180, abs=0.01)  # west limb side: observer east
    assert g.los_azimuth[c, c - 10] == pytest.approx(0, abs=0.01)  # east
    # On the central meridian μ = cos(latitude + parallax) ≈ cos(latitude).
    assert g.mu[c + 10, c] == pytest.approx(math.cos(math.radians(g.latitude[c + 10, c])), abs=5e-3)
    assert g.mu[c, c] == pytest.approx(1, abs=1e-12)


def test_sinusoidal_projection_coordinates():
    g = disk_geometry((21, 21), 80 * u.arcsec)
    r = 695700.0
    on = g.on_disk
    lat = np.radians(g.latitude[on])
    lon = np.radians(g.longitude[on])
    assert np.allclose(g.x[on], r * lon * np.cos(lat)) and np.allclose(g.y[on], r * lat)


def test_uniform_quiet_sun_follows_local_synthesis_and_limb_darkening():
    ph = uniform_photosphere()
    light, truth = full_disk_scene(ph, instrument=COARSE, detector_shape=86, supersampling=1)
    assert light.shape == (6, 86, 86) and light.boundary == "zero"
    g = disk_geometry((86, 86), 25 * u.arcsec)
    values = light.data.value
    assert np.all(values[:, ~g.on_disk] == 0)  # nothing beyond the limb
    # Each sample equals the synthesis of that column at its own μ.
    samples = [(43, 43), (43, 70), (75, 40), (12, 50)]
    for iy, ix in samples:
        cube = synthesize(ph[:1, :1], mu=g.mu[iy, ix], los_azimuth=g.los_azimuth[iy, ix] * u.deg,
                          instrument=COARSE)
        want = radiance_at_earth(channel_images(cube, instrument=COARSE))[:, 0, 0]
        assert np.allclose(values[:, iy, ix], want.value, rtol=1e-6)
    # Limb darkening: the continuum-like plane falls off toward the limb.
    radial = values[0, 43, 43:]
    on_row = g.on_disk[43, 43:]
    assert np.all(np.diff(radial[on_row]) <= 1e-12 * radial[0])
    assert truth.data.unit == u.G and np.all(truth.data.value == 0)


def test_truth_is_b_dot_n():
    vertical = uniform_photosphere(field=800.0)
    _, truth = full_disk_scene(vertical, instrument=COARSE, detector_shape=60, supersampling=1)
    g = disk_geometry((60, 60), 25 * u.arcsec)
    assert np.allclose(truth.data.value, 800 * g.mu, rtol=1e-6, atol=1e-3)
    # A horizontal field pointing north: B·n = B × (n · north) = B sinθ sin(a).
    north = uniform_photosphere(field=800.0, inclination=90.0, azimuth=90.0)
    _, truth = full_disk_scene(north, instrument=COARSE, detector_shape=60, supersampling=1)
    sin_theta = np.sqrt(1 - g.mu**2)
    want = np.where(g.on_disk, 800 * sin_theta * np.sin(np.radians(np.nan_to_num(g.los_azimuth))), 0)
    assert np.allclose(truth.data.value, want, rtol=1e-5, atol=1e-2)
    assert truth.data[45, 30].value < 0  # north of centre: field points away from Earth


def test_light_truth_and_place_sample_the_same_columns():
    ph = random_photosphere()
    light, truth = full_disk_scene(ph, instrument=COARSE, detector_shape=40, supersampling=2)
    ny, nx = ph.shape
    label = (np.arange(ny)[:, None] * nx + np.arange(nx)[None, :]).astype(float)
    placed = light.place(label, ph.pixel_size)
    g = disk_geometry(light.shape[1:], light.pixel_scale)
    on = g.on_disk
    idx = placed[on].astype(int)
    iy, ix = idx // nx, idx % nx
    cube = synthesize(ph[iy[None, :], ix[None, :]], mu=g.mu[on][None, :],
                      los_azimuth=g.los_azimuth[on][None, :] * u.deg, instrument=COARSE)
    want = radiance_at_earth(channel_images(cube, instrument=COARSE)).value[:, 0]
    assert np.allclose(light.data.value[:, on], want, rtol=1e-6)
    assert np.allclose(truth.data.value[on], cube.blos.value[0], rtol=1e-6)


def test_results_do_not_depend_on_chunking():
    ph = random_photosphere(seed=1)
    a, ta = full_disk_scene(ph, instrument=COARSE, detector_shape=30, supersampling=2, chunk_size=50)
    b, tb = full_disk_scene(ph, instrument=COARSE, detector_shape=30, supersampling=2, chunk_size=10**6)
    # Identical up to the rounding of BLAS on differently sized blocks.
    assert np.allclose(a.data, b.data, rtol=1e-13, atol=0) and np.array_equal(ta.data, tb.data)


def test_interpolation_between_cubes_at_several_mu():
    ph = uniform_photosphere(field=500.0)
    cubes = [synthesize(ph, mu=m, instrument=COARSE) for m in (0.3, 1.0)]
    with pytest.warns(UserWarning, match="outside the cubes' range"):
        light, truth = full_disk_scene(cubes, instrument=COARSE, detector_shape=86, supersampling=1)
    g = disk_geometry((86, 86), 25 * u.arcsec)
    planes = [radiance_at_earth(channel_images(c, instrument=COARSE))[:, 0, 0].value for c in cubes]
    w = np.clip((g.mu - 0.3) / 0.7, 0, 1)
    inside = g.on_disk & (g.mu >= 0.3)
    want = (1 - w[inside]) * planes[0][:, None] + w[inside] * planes[1][:, None]
    assert np.allclose(light.data.value[:, inside], want, rtol=1e-9)
    assert np.allclose(truth.data.value[inside], 500 * (0.3 + 0.7 * w[inside]), rtol=1e-5)
    # Exactly reproduces the local synthesis where μ equals a cube's μ: at disk centre.
    assert np.allclose(light.data.value[:, 43, 43], planes[1], rtol=1e-3)
    # Beyond the range (near the limb) the nearest cube is used.
    limb = g.on_disk & (g.mu < 0.3)
    assert limb.any() and np.allclose(light.data.value[:, limb], planes[0][:, None], rtol=1e-12)


def test_full_disk_wcs_and_counts():
    ph = uniform_photosphere()
    light, _ = full_disk_scene(ph, detector_shape=16, supersampling=5)  # central 40" at 2.5"
    smap = sunpy.map.Map(np.zeros(light.detector_shape), light.detector_header)
    centre = smap.pixel_to_world(7.5 * u.pix, 7.5 * u.pix)
    assert abs(centre.Tx.to_value(u.arcsec)) < 1e-9 and abs(centre.Ty.to_value(u.arcsec)) < 1e-9
    counts = expected_counts(light)
    # Quiet-Sun disk centre through the Ni line: the design's ~1.2e5 e- per frame per pixel.
    assert counts[0, 8, 8].value == pytest.approx(1.2e5, rel=0.15)


def test_bad_input():
    ph = uniform_photosphere()
    with pytest.raises(ValueError, match="supersampling"):
        full_disk_scene(ph, supersampling=0, detector_shape=8)
    with pytest.raises(ValueError, match="chunk_size"):
        full_disk_scene(ph, chunk_size=0, detector_shape=8)
    with pytest.raises(TypeError, match="Photosphere"):
        full_disk_scene(np.ones((8, 8)), detector_shape=8)
    with pytest.raises(TypeError, match="Photosphere"):
        full_disk_scene([], detector_shape=8)
    cubes = [synthesize(ph, mu=0.5), synthesize(uniform_photosphere((4, 4)), mu=1.0)]
    with pytest.raises(ValueError, match="same"):
        full_disk_scene(cubes, detector_shape=8)
    with pytest.raises(ValueError, match="distinct"):
        full_disk_scene([synthesize(ph, mu=0.5)] * 2, detector_shape=8)


def test_module_exports():
    for name in fulldisk.__all__:
        assert hasattr(fulldisk, name)


def test_float32_full_disk_optics_leave_b_and_v_unchanged():
    """The float32 scene through the float32 optics: B and v within 0.01 G and 0.01 m/s of float64."""
    from gongsynth.stages import optics
    from gongsynth.stages.reduction import reduce
    from gongsynth.sun.photosphere import model_photosphere
    inst = GONGInstrument(plate_scale=20 * u.arcsec, psf_radius=150 * u.arcsec)
    ph = model_photosphere(shape=(128, 128), pixel_size=3000 * u.km, seed=2)
    light, truth = full_disk_scene(ph, instrument=inst, detector_shape=112)
    assert light.data.dtype == np.float32 and truth.data.dtype == np.float32
    counts, _, truth_psf = optics.image_scene(light, truth, inst)
    assert counts.min() >= 0  # float32 round-off beyond the limb is zeroed
    kernel = optics.psf_kernel(light.pixel_scale, inst)
    want = optics.pixelize(optics.convolve(light.data.value.astype(np.float64), kernel, boundary="zero"),
                           light.pixel_scale, instrument=inst) * optics.photometric_factor(inst).value
    on = disk_geometry((112, 112), inst.plate_scale).on_disk
    assert np.max(np.abs(counts.value - want)[:, on]) < 1e-6 * want.max()
    got, ref = reduce(counts.value), reduce(want)
    d_b = np.abs(got.magnetogram - ref.magnetogram).to_value(u.G)[on]
    d_v = np.abs(got.doppler - ref.doppler).to_value(u.m / u.s)[on]
    assert np.max(np.abs(ref.magnetogram.to_value(u.G))[on]) > 500
    assert d_b.max() < 0.01 and d_v.max() < 0.01
    b64 = optics.observe(truth.data.value.astype(np.float64), light.pixel_scale, instrument=inst,
                         boundary="zero")
    assert np.max(np.abs(truth_psf.value - b64)) < 0.01
