"""
The large-scale field of the whole Sun: the synthetic Sun's cycle laws, measured on its maps, and
real maps remapped to the surface-field grid and back.
"""
import warnings

import astropy.units as u
import numpy as np
import pytest
import sunpy.map
from astropy.coordinates import SkyCoord
from scipy.stats import norm
from sunpy.coordinates import Helioprojective, frames, get_earth
from sunpy.map.header_helper import make_fitswcs_header

from gongsynth.sun.surface_field import (
    fill_unobserved,
    surface_field_at,
    surface_field_from_map,
    synthetic_surface_field,
)
from gongsynth.sun.surface_field.cycle import (
    JOY_SCATTER,
    ZONE_WIDTH,
    SolarCycle,
    active_latitude,
    cycle_of,
    leading_polarity,
)
from gongsynth.sun.surface_field.maps import (
    carrington_offset,
    cell_area,
    field_grid,
    make_surface_field,
    rotation_drift,
)
from gongsynth.sun.surface_field.quiet import QUIET_CORRELATION
from gongsynth.sun.surface_field.synthetic import active_regions

from .realdata import load_real

MAXIMUM = "2014-04-01"  # cycle 24 near its maximum: north leading polarity negative


# -- the synthetic Sun ------------------------------------------------------------------------


def test_the_quiet_field_has_its_width_and_adapts_correlation():
    # The quiet Sun alone (no regions), within 30 deg of the equator where the polar fields are < 0.02 G.
    lon, lat = field_grid((360, 720))
    band = np.abs(lat) < 30
    lags = np.array([2, 6, 12])                              # deg of longitude (0.5-deg cells)
    model = np.array([sum(a * np.exp(-0.5 * (r / w) ** 2) for w, a in QUIET_CORRELATION) for r in lags])
    widths, five_degree, measured = [], [], []
    for seed in (1, 2, 3):
        b = synthetic_surface_field("2009-09-05", seed=seed, active_regions_on=False).data[band]
        b = b - b.mean()
        widths.append(b.std())
        measured.append([np.mean(b * np.roll(b, 2 * k, axis=1)) / b.var() for k in lags])
        five_degree.append(b[:, :720].reshape(b.shape[0], 72, 10).mean(axis=2).std())
    # ~160 independent 6.5-deg patches in the band: one draw's width and correlations scatter by ~1/sqrt(160)
    # = 8 % (0.05 in the correlation); the mean of three by ~5 % (0.03).  Tolerances at ~2.5 sigma.
    assert np.mean(widths) == pytest.approx(3.0, rel=0.12)
    assert np.allclose(np.mean(measured, axis=0), model, atol=0.08)
    # Averaged over 5 deg of longitude the field keeps most of its width (ADAPT: 0.95 over 5 x 5 deg);
    # white 0.5-deg cells would keep 1/sqrt(10) = 0.32.
    assert np.mean(five_degree) / np.mean(widths) > 0.8


def test_same_seed_same_bits_and_the_quiet_sun_is_independent_of_the_regions():
    a = synthetic_surface_field(MAXIMUM, seed=5)
    b = synthetic_surface_field(MAXIMUM, seed=5)
    assert a.data.tobytes() == b.data.tobytes() and a.data.dtype == np.float32
    assert a.data.tobytes() != synthetic_surface_field(MAXIMUM, seed=6).data.tobytes()
    assert a.meta["seed"] == "5" and a.meta["cycle"] == 24
    # The network comes from its own stream: switching the regions off leaves it as it was,
    # so far from the regions (the polar caps, reached only by the far tails of old decayed
    # regions carried poleward) the two maps differ by less than 1 mG.
    quiet = synthetic_surface_field(MAXIMUM, seed=5, active_regions_on=False)
    _, lat = field_grid(a.data.shape)
    caps = np.abs(lat) > 75
    assert np.abs(a.data[caps] - quiet.data[caps]).max() < 1e-3
    assert np.median(np.abs(a.data - quiet.data)[np.abs(lat) < 40]) > 0.01
    assert quiet.meta["nregions"] == 0


def _measure_bipoles(field, regions, young):
    """Leading sign and tilt (deg, + when the leading polarity is equatorward) measured on the map."""
    lon_grid, lat_grid = field_grid(field.data.shape)
    data = np.asarray(field.data, float)
    signs, tilts = [], []
    for k in np.nonzero(young)[0]:
        lon0, lat0 = regions["longitude"][k], regions["latitude"][k]
        rows = np.abs(lat_grid - lat0) < 5
        dlon = (lon_grid - lon0 + 180) % 360 - 180
        cols = np.abs(dlon) * np.cos(np.radians(lat0)) < 6
        box = data[np.ix_(rows, cols)]
        x = dlon[cols][None, :] * np.cos(np.radians(lat0)) + 0 * box
        y = lat_grid[rows][:, None] + 0 * box
        pos, neg = box > 30, box < -30
        if pos.sum() == 0 or neg.sum() == 0:
            signs.append(0)
            tilts.append(np.nan)
            continue
        xp, yp = np.average(x[pos], weights=box[pos]), np.average(y[pos], weights=box[pos])
        xn, yn = np.average(x[neg], weights=-box[neg]), np.average(y[neg], weights=-box[neg])
        lead_is_pos = xp > xn
        signs.append(1 if lead_is_pos else -1)
        (xl, yl), (xt, yt) = ((xp, yp), (xn, yn)) if lead_is_pos else ((xn, yn), (xp, yp))
        hemisphere = np.sign(lat0)
        tilts.append(np.degrees(np.arctan2(hemisphere * (yt - yl), xl - xt)))
    return np.array(signs), np.array(tilts)


def test_hale_and_joy_measured_on_the_maps():
    signs, tilts, drawn, expected, latitudes = [], [], [], [], []
    for seed in range(60):
        kwargs = dict(seed=seed, history=5 * u.day)
        field = synthetic_surface_field(MAXIMUM, **kwargs)
        regions = active_regions(MAXIMUM, **kwargs)
        # Compact bipoles (separation 3-8 deg) that have not moved far since they emerged.
        young = (regions["flux"] > 2e21) & (regions["flux"] < 5e22)
        s, t = _measure_bipoles(field, regions, young)
        signs.append(s * np.sign(regions["latitude"][young]))
        tilts.append(t)
        drawn.append(regions["tilt"][young])
        expected.append(leading_polarity(regions["cycle"][young], 1))
        latitudes.append(regions["latitude"][young])
    signs, tilts, drawn = np.concatenate(signs), np.concatenate(tilts), np.concatenate(drawn)
    expected, latitudes = np.concatenate(expected), np.concatenate(latitudes)
    assert signs.size > 150
    # Hale: the leading polarity times the hemisphere's sign is the cycle's northern sign
    # (-1 for cycle 24); a few bipoles overlap a neighbour and are measured wrong.
    assert np.mean(signs == expected) > 0.9
    # The tilts measured on the map are the drawn ones, to the centroiding error on a
    # 0.5-degree grid (a few degrees)...
    ok = np.isfinite(tilts) & (signs == expected)
    assert np.median(np.abs(tilts[ok] - drawn[ok])) < 3
    # ... and Joy's law holds on the map: the leading polarity is equatorward, the mean tilt is
    # 32.1 sin|latitude| averaged over these regions, within 3 standard errors (scatter
    # JOY_SCATTER), and positive by more than 3.
    standard_error = JOY_SCATTER / np.sqrt(ok.sum())
    law = np.mean(32.1 * np.sin(np.radians(np.abs(latitudes[ok]))))
    assert abs(np.mean(tilts[ok]) - law) < 3 * standard_error
    assert np.mean(tilts[ok]) > 3 * standard_error


def _folded_mean(mu, sigma):
    """Mean of |X| for X ~ N(mu, sigma)."""
    return sigma * np.sqrt(2 / np.pi) * np.exp(-mu**2 / (2 * sigma**2)) + mu * (1 - 2 * norm.cdf(-mu / sigma))


@pytest.mark.parametrize("phase", [0.15, 0.35, 0.55, 0.75])
def test_active_latitudes_drift_toward_the_equator(phase):
    # Regions of the cycle in progress that emerged in the last 60 days: their mean |latitude|
    # is Spörer's law at that time, folded at the equator, within 4 standard errors.
    lats, model = [], []
    cycle = SolarCycle(24)
    for seed in range(4):
        r = active_regions(MAXIMUM, seed=seed, cycle_phase=phase, history=60 * u.day)
        own = r["cycle"] == 24
        lats.append(np.abs(r["latitude"][own]))
        years = phase * cycle.length - r["age"][own] / 365.25
        model.append(_folded_mean(active_latitude(years).to_value(u.deg), ZONE_WIDTH))
    lats, model = np.concatenate(lats), np.concatenate(model)
    assert lats.size > 20
    assert abs(lats.mean() - model.mean()) < 4 * ZONE_WIDTH / np.sqrt(lats.size)


def test_the_strong_field_moves_to_the_equator_on_the_maps():
    # Mean |latitude| of the strong field (|B| > 50 G, nearly 7 sigma of the network) on the
    # synthetic Sun's maps at three phases of cycle 24 (six seeds each; the phases avoid the
    # minimum, where the old and new cycles overlap): it moves toward the equator.
    centroid = []
    for phase in (0.2, 0.45, 0.7):
        latitudes = []
        for seed in range(6):
            field = synthetic_surface_field(MAXIMUM, seed=seed, cycle_phase=phase, history=60 * u.day)
            _, lat = field_grid(field.data.shape)
            strong = np.abs(field.data) > 50
            latitudes.append(np.broadcast_to(np.abs(lat)[:, None], field.data.shape)[strong])
        centroid.append(np.concatenate(latitudes).mean())
    assert np.all(np.diff(centroid) < -3), centroid


@pytest.mark.parametrize("date, north", [("2009-01-01", -1), ("2019-06-07", 1), ("2022-10-29", 1),
                                         ("2024-10-01", 0)])
def test_polar_field_sign_follows_the_cycle(date, north):
    field = synthetic_surface_field(date, seed=2)
    _, lat = field_grid(field.data.shape)
    north_cap = field.data[lat > 70].mean()
    south_cap = field.data[lat < -70].mean()
    # The network's contribution to a cap mean: per-cell rms / sqrt(cells).
    noise = np.std(field.data[np.abs(lat) < 5]) / np.sqrt((lat > 70).sum() * field.data.shape[1])
    if north == 0:  # near maximum the polar fields are reversing: weaker than 1/3 of full strength
        assert abs(north_cap) < 10 * np.mean(np.sin(np.radians(lat[lat > 70])) ** 8) / 3 + 5 * noise
    else:
        assert north * north_cap > 10 * noise and north * south_cap < -10 * noise
        # Full strength: B_p sin^8(latitude) averaged over the cap, 5-10 G poleward of 60 deg.
        assert 3 < abs(north_cap) < 10


def _adapt_map():
    """Realisation 0 of the ADAPT-GONG map of 2017-07-20 08:00 (1-deg Carrington CAR grid, gauss)."""
    from astropy.io import fits
    from sunpy.map.header_helper import make_heliographic_header

    from .realdata import real_file

    data = fits.getdata(real_file("gong/adapt40311_03k012_201707200800_i00015600n1.fts.gz"))[0]
    date = "2017-07-20T08:00:00"
    header = make_heliographic_header(date, get_earth(date), data.shape, frame="carrington",
                                      projection_code="CAR", map_center_longitude=180 * u.deg)
    return sunpy.map.Map(data, header)


@pytest.mark.parametrize("relpath, date", [
    ("gong/mrbqs221029t0304c2263_067.fits", "2022-10-29"),   # cycle 25 before its reversal
    ("mdi/mdi.fd_m_96m_lev182.20101015_000000_TAI.data.fits", "2010-10-15"),  # cycle 24 rising
    ("adapt", "2017-07-20"),  # cycle 24 declining, after its reversal
])
def test_polar_sign_agrees_with_real_maps(relpath, date):
    # The sign of the model's northern polar field against the real field poleward of 60 deg
    # (a synoptic map's B_r, or the full disk's B_LOS/mu where the north pole is seen).
    smap = _adapt_map() if relpath == "adapt" else load_real(relpath, "magnetogram")
    real = surface_field_from_map(smap, resolution=1 * u.deg)
    _, lat = field_grid(real.data.shape)
    real_north = np.nanmean(real.data[lat > 60])
    model_north = synthetic_surface_field(date, seed=0, active_regions_on=False).data
    _, mlat = field_grid(model_north.shape)
    assert np.sign(real_north) == np.sign(model_north[mlat > 60].mean())


def test_cycle_timing():
    # The brief's anchors: cycle 23 ended ~2008.9, 24 peaked ~2014.3, ended ~2019.9.
    assert cycle_of("2008-11-01")[0] == 23 and cycle_of("2009-01-01")[0] == 24
    assert cycle_of("2020-01-01")[0] == 25
    years = np.linspace(2008.9, 2019.9, 1101)
    peak = years[np.argmax(SolarCycle(24).sunspot_number(years))]
    assert 2012.5 < peak < 2014.5
    minimum = synthetic_surface_field("2009-09-05", seed=0)
    maximum = synthetic_surface_field(MAXIMUM, seed=0)
    assert minimum.meta["nregions"] < maximum.meta["nregions"] / 20
    # Strong field (|B| > 50 G): plage and spots cover a far larger area at maximum.
    assert (np.abs(minimum.data) > 50).sum() < (np.abs(maximum.data) > 50).sum() / 10


# -- real maps to the grid and back -------------------------------------------------------------


@pytest.fixture(scope="module")
def mdi():
    return load_real("mdi/mdi.fd_m_96m_lev182.20101015_000000_TAI.data.fits", "magnetogram")


def _disk_pixels(smap):
    """Stonyhurst coordinates, mu and area on the Sun (cm^2) of every pixel of a full-disk map."""
    ny, nx = smap.data.shape
    yy, xx = np.mgrid[0:ny, 0:nx]
    hgs = smap.wcs.pixel_to_world(xx, yy).transform_to(frames.HeliographicStonyhurst(obstime=smap.date))
    r = hgs.cartesian.xyz.to_value(u.cm)
    o = smap.observer_coordinate.transform_to(hgs.frame).cartesian.xyz.to_value(u.cm)[:, None, None]
    to_obs = o - r
    d2 = (to_obs**2).sum(axis=0)
    mu = (r * to_obs).sum(axis=0) / np.sqrt((r**2).sum(axis=0) * d2)
    omega = (abs(smap.scale.axis1 * u.pix) * abs(smap.scale.axis2 * u.pix)).to_value(u.sr)
    return hgs, mu, omega * d2 / mu


def test_mdi_full_disk_to_the_sphere_and_back(mdi):
    field = surface_field_from_map(mdi)
    hgs, mu, _ = _disk_pixels(mdi)
    back = surface_field_at(field, hgs.lon, hgs.lat).to_value(u.G) * mu
    original = np.asarray(mdi.data, float)
    good = np.isfinite(back) & np.isfinite(original) & (mu > 0.3)
    k = 8  # 16-arcsec bins
    ny, nx = original.shape
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # empty bins off the disk
        a = np.nanmean(np.where(good, original, np.nan).reshape(ny // k, k, nx // k, k), axis=(1, 3))
        b = np.nanmean(np.where(good, back, np.nan).reshape(ny // k, k, nx // k, k), axis=(1, 3))
    ok = np.isfinite(a) & np.isfinite(b)
    assert np.corrcoef(a[ok], b[ok])[0, 1] > 0.95
    # The far side and the limb beyond mu = 0.1 are unobserved: about half the sphere.
    finite = np.isfinite(field.data).mean()
    assert 0.43 < finite < 0.46  # the area seen at mu >= 0.1 is (1 - 0.1) / 2 of the sphere


def test_mdi_flux_is_kept_in_large_boxes(mdi):
    # Signed flux in 10 x 10 deg boxes of the observed hemisphere: the disk's pixels (B_LOS/mu
    # times their area on the Sun) against the remapped cells (B_r times the cell area).
    field = surface_field_from_map(mdi)
    hgs, mu, area = _disk_pixels(mdi)
    original = np.asarray(mdi.data, float)
    seen = np.isfinite(original) & (mu >= 0.1)
    pixel_flux = np.where(seen, original / np.where(seen, mu, 1) * area, 0.0)
    lon = np.where(seen, hgs.lon.to_value(u.deg) + carrington_offset(mdi.date).to_value(u.deg), 0)
    lat = np.where(seen, hgs.lat.to_value(u.deg), 0)
    lon_c, lat_c = field_grid(field.data.shape)
    cell_lon, cell_lat = np.meshgrid(lon_c, lat_c)
    cell_flux = np.nan_to_num(np.asarray(field.data, float)) * cell_area(field.data.shape).to_value(u.cm**2)

    def box_of(lo, la):
        row, column = np.floor((la + 90) / 10).astype(int), np.floor(np.mod(lo, 360) / 10).astype(int)
        return (row * 36 + column).ravel()

    def boxes(lo, la, flux):
        return np.bincount(box_of(lo, la), weights=flux.ravel(), minlength=18 * 36)

    disk, sphere = boxes(lon[seen], lat[seen], pixel_flux[seen]), boxes(cell_lon, cell_lat, cell_flux)
    mu_min = np.full(18 * 36, 2.0)
    np.minimum.at(mu_min, box_of(lon[seen], lat[seen]), mu[seen])
    inner = (mu_min > 0.3) & (mu_min <= 1)  # boxes wholly seen at mu > 0.3
    assert inner.sum() > 100
    slope = (disk[inner] * sphere[inner]).sum() / (disk[inner] ** 2).sum()
    assert abs(slope - 1) < 0.03
    assert np.corrcoef(disk[inner], sphere[inner])[0, 1] > 0.99


def test_a_synoptic_map_on_its_own_grid_is_unchanged():
    # GONG's synoptic grid is the product grid at 1 deg (CEA, 180 rows): with the pattern
    # rotating rigidly with the Carrington frame, every cell is the map's own pixel.
    gong = load_real("gong/mrbqs221029t0304c2263_067.fits", "magnetogram")
    field = surface_field_from_map(gong, resolution=1 * u.deg, rotation_model="rigid")
    lon_c, lat_c = field_grid(field.data.shape)
    x, y = gong.wcs.world_to_pixel(SkyCoord(lon_c * u.deg, 0 * lon_c * u.deg, frame=gong.coordinate_frame))
    columns = np.round(x).astype(int) % 360
    assert np.allclose(np.diff(columns) % 360, 1)
    assert np.allclose(field.data, np.asarray(gong.data)[:, columns], atol=1e-4, rtol=1e-5)
    # The default (differential rotation from each column's central-meridian passage) moves them.
    moved = surface_field_from_map(gong, resolution=1 * u.deg)
    assert not np.allclose(moved.data, field.data)
    assert "central-meridian" in moved.meta["history"]


def _blob_map(date, latitude):
    """A 128 x 128 full-disk map (16"/px) holding one 100 G patch at Stonyhurst (0, latitude)."""
    centre = SkyCoord(0 * u.arcsec, 0 * u.arcsec,
                      frame=Helioprojective(observer=get_earth(date), obstime=date))
    header = make_fitswcs_header((256, 256), centre, scale=[8, 8] * u.arcsec / u.pix, unit=u.G)
    smap = sunpy.map.Map(np.zeros((256, 256)), header)
    hgs = smap.wcs.pixel_to_world(*np.meshgrid(np.arange(256), np.arange(256))).transform_to(
        frames.HeliographicStonyhurst(obstime=smap.date))
    near = np.hypot(hgs.lon.to_value(u.deg), hgs.lat.to_value(u.deg) - latitude) < 4
    return sunpy.map.Map(np.where(near, 100.0, 0.0), header)


@pytest.mark.parametrize("latitude", [0.0, 40.0])
def test_differential_rotation_to_a_later_date(latitude):
    date = "2010-10-15T00:00"
    smap = _blob_map(date, latitude)
    now = surface_field_from_map(smap, resolution=0.5 * u.deg)
    later = surface_field_from_map(smap, "2010-10-25T00:00", resolution=0.5 * u.deg)
    lon_c, _ = field_grid(now.data.shape)

    def centroid(field):
        w = np.nan_to_num(np.asarray(field.data, float)).sum(axis=0)
        phase = np.angle(np.sum(w * np.exp(1j * np.radians(lon_c))))
        return np.degrees(phase)

    shift = (centroid(later) - centroid(now) + 180) % 360 - 180
    expected = rotation_drift(latitude * u.deg, 10 * u.day).to_value(u.deg)
    assert shift == pytest.approx(expected, abs=0.1)
    assert later.date.isot.startswith("2010-10-25")


def test_sampling_the_grid_at_its_own_cells_and_filling_the_far_side():
    field = synthetic_surface_field("2012-01-01", seed=4, resolution=2 * u.deg)
    lon_c, lat_c = field_grid(field.data.shape)
    lon, lat = np.meshgrid(lon_c, lat_c)
    stonyhurst = lon - carrington_offset(field.date).to_value(u.deg)
    assert np.allclose(surface_field_at(field, stonyhurst * u.deg, lat * u.deg).value, field.data,
                       atol=1e-4)
    holes = make_surface_field(np.where(lon < 180, field.data, np.nan), field.date, source="half")
    filled = fill_unobserved(holes, field)
    assert np.array_equal(filled.data, field.data)
    assert str(field.data[lon >= 180].size) in filled.meta["history"]
