"""Tests of gongsynth.sun.photosphere: the Photosphere container, its geometry and the model photosphere."""
import astropy.units as u
import numpy as np
import pytest

from gongsynth.sun.photosphere import Photosphere, model_photosphere

KMS = u.km / u.s


def _ph(shape=(3, 4), **over):
    ones = np.ones(shape)
    args = dict(field_strength=1000 * ones * u.G, inclination=30 * ones * u.deg,
                azimuth=45 * ones * u.deg, velocity_x=0 * ones * KMS, velocity_y=0 * ones * KMS,
                velocity_z=0 * ones * KMS, continuum=ones, pixel_size=96 * u.km)
    args.update(over)
    return Photosphere(**args)


@pytest.fixture(scope="module")
def default_model():
    """The built-in photosphere at its default size (98 Mm box, 96 km)."""
    return model_photosphere()


def _radius_km(ph):
    ny, nx = ph.shape
    y, x = np.mgrid[0:ny, 0:nx]
    return np.hypot(x - (nx - 1) / 2, y - (ny - 1) / 2) * ph.pixel_size.to_value(u.km)


# ------------------------------------------------------------------ container
def test_photosphere_stores_float32_and_converts_units():
    ph = _ph(field_strength=np.full((3, 4), 0.1) * u.T, velocity_z=np.full((3, 4), 500.0) * u.m / u.s)
    assert ph.field_strength.unit == u.G and ph.field_strength.dtype == np.float32
    np.testing.assert_allclose(ph.field_strength.value, 1000.0)
    np.testing.assert_allclose(ph.velocity_z.value, 0.5)
    assert ph.shape == (3, 4) and not ph.periodic


def test_field_vector_and_from_components_round_trip():
    rng = np.random.default_rng(2)
    bx, by, bz = (rng.normal(0, 500, (5, 6)) for _ in range(3))
    zero = np.zeros((5, 6)) * KMS
    ph = Photosphere.from_components(bx * u.G, by * u.G, bz * u.G, zero, zero, zero, np.ones((5, 6)),
                                     48 * u.km)
    for got, want in zip(ph.field_vector(), (bx, by, bz)):
        np.testing.assert_allclose(got, want, atol=2e-3 * np.abs(want).max())
    assert ph.inclination.value.min() >= 0 and ph.inclination.value.max() <= 180


def test_los_field_and_velocity_follow_the_contract_geometry():
    theta = np.radians(60.0)
    # vertical 1 kG field, seen at mu = 0.5 from any azimuth: B·n = B mu
    ph = _ph(inclination=np.zeros((3, 4)) * u.deg)
    np.testing.assert_allclose(ph.los_field(0.5).value, 500.0, rtol=1e-6)
    np.testing.assert_allclose(ph.los_field(0.5, los_azimuth=30 * u.deg).value, 500.0, rtol=1e-6)
    # horizontal field pointing north (+y), region north of disk centre (observer toward -y)
    north = _ph(inclination=np.full((3, 4), 90.0) * u.deg, azimuth=np.full((3, 4), 90.0) * u.deg)
    np.testing.assert_allclose(north.los_field(0.5, -90 * u.deg).value, -1000 * np.sin(theta), rtol=1e-5)
    np.testing.assert_allclose(north.los_field(0.5, 90 * u.deg).value, 1000 * np.sin(theta), rtol=1e-5)
    np.testing.assert_allclose(north.los_field(1.0).value, 0.0, atol=1e-3)
    # an upflow at disk centre comes toward the observer: blueshift, v_LOS < 0
    up = _ph(velocity_z=np.full((3, 4), 2.0) * KMS)
    np.testing.assert_allclose(up.los_velocity().value, -2.0, rtol=1e-6)
    np.testing.assert_allclose(up.los_velocity(0.5).value, -1.0, rtol=1e-6)
    # per-column geometry
    mu = np.linspace(0.2, 1.0, 12).reshape(3, 4)
    np.testing.assert_allclose(up.los_velocity(mu).value, -2.0 * mu, rtol=1e-6)


def test_slicing_keeps_columns_and_drops_periodicity():
    ph = model_photosphere(shape=(32, 32), pixel_size=3072 * u.km)
    assert ph.periodic
    sub = ph[4:10, 3]
    assert sub.shape == (6, 1) and not sub.periodic
    np.testing.assert_array_equal(sub.field_strength.value[:, 0], ph.field_strength.value[4:10, 3])
    assert np.shares_memory(sub.velocity_x, ph.velocity_x)
    assert ph[:, :].periodic
    idx = np.array([1, 5, 7])
    np.testing.assert_array_equal(ph[idx[:, None], idx[None, :]].continuum.value,
                                  ph.continuum.value[np.ix_(idx, idx)])


def test_photosphere_bad_input():
    with pytest.raises(ValueError, match="azimuth contains non-finite"):
        _ph(azimuth=np.full((3, 4), np.nan) * u.deg)
    with pytest.raises(ValueError, match="field_strength must be non-negative"):
        _ph(field_strength=-np.ones((3, 4)) * u.G)
    with pytest.raises(ValueError, match=r"inclination must be within \[0, 180\]"):
        _ph(inclination=np.full((3, 4), 200.0) * u.deg)
    with pytest.raises(u.UnitsError, match="velocity_y must have units convertible to km / s"):
        _ph(velocity_y=np.zeros((3, 4)) * u.G)
    with pytest.raises(ValueError, match=r"continuum has shape \(3, 3\) but field_strength has shape"):
        _ph(continuum=np.ones((3, 3)))
    with pytest.raises(ValueError, match="continuum must be non-negative"):
        _ph(continuum=-np.ones((3, 4)))
    with pytest.raises(TypeError, match="inclination must be an astropy Quantity"):
        _ph(inclination=np.zeros((3, 4)))
    with pytest.raises(ValueError, match=r"mu must be in \(0, 1\]"):
        _ph().los_field(mu=1.5)


# --------------------------------------------------------------- the model: basics
def test_model_is_seeded_and_reproducible():
    a = model_photosphere(shape=(48, 48), pixel_size=2048 * u.km, seed=7)
    b = model_photosphere(shape=(48, 48), pixel_size=2048 * u.km, seed=7)
    c = model_photosphere(shape=(48, 48), pixel_size=2048 * u.km, seed=8)
    gen = model_photosphere(shape=(48, 48), pixel_size=2048 * u.km, seed=np.random.default_rng(7))
    for name in ("field_strength", "inclination", "velocity_z", "continuum"):
        np.testing.assert_array_equal(getattr(a, name).value, getattr(b, name).value)
        assert not np.array_equal(getattr(a, name).value, getattr(c, name).value)
    assert gen.shape == a.shape
    assert a.meta["seed_entropy"] == "7"
    # switching an ingredient off leaves the others' random streams untouched
    nospot = model_photosphere(shape=(48, 48), pixel_size=2048 * u.km, seed=7, spot=False)
    r = _radius_km(a)
    far = r > 30000
    np.testing.assert_allclose(nospot.velocity_z.value[far], a.velocity_z.value[far], atol=0.2)


def test_model_is_periodic(default_model):
    ph = default_model
    for field in (ph.continuum.value, ph.velocity_z.value):
        interior = np.mean((field[:, 1:] - field[:, :-1]) ** 2)
        wrap_x = np.mean((field[:, 0] - field[:, -1]) ** 2)
        wrap_y = np.mean((field[0] - field[-1]) ** 2)
        assert 0.6 < wrap_x / interior < 1.6
        assert 0.6 < wrap_y / interior < 1.6


def test_default_box_matches_the_paper_snapshot(default_model):
    ph = default_model
    assert ph.shape == (1024, 1024)
    assert ph.pixel_size == 96 * u.km
    assert ph.periodic
    bz = ph.bz.value
    pixel_area = (96e5) ** 2
    net = bz.sum() * pixel_area
    assert net > 5e21                                # net positive flux, dominated by the spot
    r = _radius_km(ph)
    spot_flux = bz[r < 17000].sum() * pixel_area
    assert 0.7e22 < spot_flux < 1.3e22                # Rempel (2015): 1e22 Mx
    outside = r > 20000
    assert (bz[outside] > 800).sum() > 300            # kG elements of both polarities
    assert (bz[outside] < -800).sum() > 300


# --------------------------------------------------------------- the model: the spot
def test_umbra_is_strong_vertical_and_dark(default_model):
    ph = default_model
    r = _radius_km(ph)
    umbra = r < 3000
    assert ph.field_strength.value[umbra].mean() > 2700
    assert ph.inclination.value[umbra].max() < 15
    assert 0.15 < ph.continuum.value[umbra].mean() < 0.35


def test_penumbra_is_inclined_weaker_with_evershed_outflow(default_model):
    ph = default_model
    r = _radius_km(ph)
    pen = (r > 9000) & (r < 14000)
    B = ph.field_strength.value[pen]
    inc = ph.inclination.value[pen]
    assert 1100 < B.mean() < 1900
    assert 50 < inc.mean() < 85
    assert 0.7 < ph.continuum.value[pen].mean() < 0.9
    ny, nx = ph.shape
    y, x = np.mgrid[0:ny, 0:nx]
    rx, ry = (x - (nx - 1) / 2), (y - (ny - 1) / 2)
    v_r = (ph.velocity_x.value * rx + ph.velocity_y.value * ry) / np.maximum(np.hypot(rx, ry), 1e-9)
    assert v_r[pen].mean() > 0.4                      # outward
    # the flow lives in the more inclined, weaker-field intraspines
    intraspine = inc > np.median(inc)
    assert v_r[pen][intraspine].mean() > 2 * v_r[pen][~intraspine].mean()
    # the field points outward (positive polarity spot): azimuth ≈ position angle
    pa = np.degrees(np.arctan2(ry, rx))[pen]
    dpa = (ph.azimuth.value[pen] - pa + 180) % 360 - 180
    assert np.abs(dpa).max() < 1.0


# ------------------------------------------------------------- the model: quiet Sun
@pytest.fixture(scope="module")
def quiet():
    return model_photosphere(shape=(256, 256), pixel_size=96 * u.km, spot=False, plage=False,
                             network_flux_density=0 * u.G, seed=4)


def test_granulation_statistics(quiet):
    c = quiet.continuum.value.astype(float)
    vz = quiet.velocity_z.value.astype(float)
    vh = np.hypot(quiet.velocity_x.value, quiet.velocity_y.value)
    assert 0.06 < c.std() / c.mean() < 0.10           # "a few per cent" RMS contrast at 96 km
    assert 0.8 < vz.std() < 1.2                        # km/s
    assert abs(vz.mean()) < 0.05                        # mass balance
    assert np.corrcoef(c.ravel(), vz.ravel())[0, 1] > 0.4   # upflows are bright
    assert 1.2 < np.sqrt(np.mean(vh ** 2)) < 2.0
    # downflows in narrow lanes: the strongest flows are down, most of the area goes up
    assert (vz > 0).mean() > 0.5
    assert -vz.min() > vz.max()
    # granular scale: the azimuthally integrated spectrum E(k) = 2πk P(k) of the
    # continuum peaks at ~1-2 Mm
    p = np.abs(np.fft.fft2(c - c.mean())) ** 2
    k = np.hypot(*np.meshgrid(np.fft.fftfreq(256, 0.096), np.fft.fftfreq(256, 0.096)))  # cycles/Mm
    bins = np.linspace(0.05, 3.0, 60)
    centres = 0.5 * (bins[:-1] + bins[1:])
    power = np.array([p[(k >= lo) & (k < hi)].mean() for lo, hi in zip(bins[:-1], bins[1:])])
    peak = centres[np.argmax(centres * power)]
    assert 0.8 < 1 / peak < 2.5


def test_internetwork_salt_and_pepper_cancels_in_a_gong_pixel(quiet):
    bz = quiet.bz.value
    bh = np.hypot(*quiet.field_vector()[:2])
    assert 15 < np.abs(bz).mean() < 35                # tens of G at 96 km
    assert np.sqrt(np.mean(bh ** 2)) > 2 * np.sqrt(np.mean(bz ** 2))   # mostly horizontal
    # 19 × 96 km ≈ 1.8 Mm ≈ one GONG pixel (2.5″)
    n = 19 * (256 // 19)
    gong = bz[:n, :n].reshape(n // 19, 19, n // 19, 19).mean(axis=(1, 3))
    assert np.abs(gong).mean() < 0.2 * np.abs(bz).mean()


def test_coarse_grid_keeps_area_averaged_fluxes(default_model):
    coarse = model_photosphere(shape=(128, 128), pixel_size=768 * u.km)
    fine = default_model
    area_f, area_c = (96e5) ** 2, (768e5) ** 2
    assert coarse.bz.value.sum() * area_c == pytest.approx(fine.bz.value.sum() * area_f, rel=0.1)
    binned = fine.continuum.value.reshape(128, 8, 128, 8).mean(axis=(1, 3))
    assert coarse.continuum.value.mean() == pytest.approx(binned.mean(), rel=0.02)
    # granulation is averaged over the 768 km columns, not aliased: the coarse contrast is
    # that of the fine model binned 8 × 8 (~0.05), not that at 96 km (~0.08)
    far = _radius_km(coarse) > 35000
    assert coarse.continuum.value[far].std() == pytest.approx(binned[far].std(), rel=0.15)
    assert coarse.continuum.value[far].std() < 0.75 * fine.continuum.value[_radius_km(fine) > 35000].std()


def test_model_bad_input():
    with pytest.raises(ValueError, match="does not fit"):
        model_photosphere(shape=(128, 128), pixel_size=96 * u.km)
    with pytest.raises(ValueError, match="shape must be two ints"):
        model_photosphere(shape=(128,))
    with pytest.raises(ValueError, match="pixel_size must be a positive"):
        model_photosphere(shape=(32, 32), pixel_size=-3 * u.km, spot=False)
    with pytest.raises(u.UnitsError, match="umbra_field"):
        model_photosphere(shape=(32, 32), pixel_size=3072 * u.km, umbra_field=3 * u.km)
    with pytest.raises(ValueError, match="umbra_radius .* must be smaller"):
        model_photosphere(shape=(32, 32), pixel_size=3072 * u.km, umbra_radius=20 * u.Mm)
    with pytest.raises(ValueError, match="granulation_contrast"):
        model_photosphere(shape=(32, 32), pixel_size=3072 * u.km, granulation_contrast=-0.1)


@pytest.mark.parametrize("shape, spacing, dx", [((300, 200), 700.0, 50.0), ((128, 96), 25000.0, 768.0),
                                               ((64, 64), 1000.0, 400.0)])
def test_bucket_search_finds_the_same_two_nearest_seeds_as_a_kd_tree(shape, spacing, dx):
    """The nearest and second-nearest cell centres: the same answer as a periodic k-d tree."""
    from scipy.spatial import cKDTree

    from gongsynth.sun.photosphere.voronoi import nearest_two

    rng = np.random.default_rng(7)
    ny, nx = shape
    box = (nx * dx, ny * dx)
    n = max(3, int(rng.poisson(box[0] * box[1] / spacing**2)))
    seeds = np.column_stack([rng.uniform(0, box[0], n), rng.uniform(0, box[1], n)])
    y, x = np.meshgrid((np.arange(ny) + 0.5) * dx, (np.arange(nx) + 0.5) * dx, indexing="ij")
    want_d, want_i = cKDTree(seeds, boxsize=list(box)).query(np.column_stack([x.ravel(), y.ravel()]), k=2)
    got_d, got_i = nearest_two(seeds, shape, dx, box)
    assert np.array_equal(got_i, want_i)
    assert np.allclose(got_d, want_d, rtol=1e-14, atol=0)
