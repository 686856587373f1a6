"""The weak field's power over the disk: its fall toward the limb, east-west excess and axis anisotropy."""
import astropy.units as u
import numpy as np
import pytest
import sunpy.map
from astropy.coordinates import SkyCoord
from sunpy.coordinates import frames

from gongsynth.analysis.limb_power import axis_anisotropy, limb_power_fit, weak_field
from gongsynth.analysis.map_statistics import compare_statistics

SCALE = 5.0      # arcsec per pixel: the whole disk in 400 pixels, 32 to a 160″ box
N = 400


def _map(data):
    ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective, observer="earth",
                   obstime="2009-09-05T18:54")
    header = sunpy.map.make_fitswcs_header(data.shape, ref, scale=[SCALE, SCALE] * u.arcsec / u.pix, unit=u.G)
    return sunpy.map.Map(data, header)


def _disk(exponent, excess, seed, n=N):
    """White noise on the disk (NaN off it) whose power goes as mu^exponent exp(excess (x² - y²))."""
    radius = _map(np.zeros((n, n))).rsun_obs.to_value(u.arcsec) / SCALE
    yy, xx = np.indices((n, n))
    x, y = (xx - (n - 1) / 2) / radius, (yy - (n - 1) / 2) / radius
    rho2 = x**2 + y**2
    mu = np.sqrt(np.clip(1 - rho2, 1e-6, None))
    # 2 G at most, far below the 15 G clip: the clip leaves the noise as it is.
    sigma = 2.0 * np.sqrt(mu**exponent * np.exp(excess * (x**2 - y**2 - 1)))
    data = np.random.default_rng(seed).normal(0.0, 1.0, (n, n)) * sigma
    return _map(np.where(rho2 < 1, data, np.nan))


@pytest.mark.parametrize("exponent, excess", [(1.0, 0.0), (2.0, 1.0)])
def test_a_known_fall_and_east_west_excess_are_read_back(exponent, excess):
    fit = limb_power_fit(_disk(exponent, excess, seed=5))
    # Errors small enough to tell these two cases apart, and the truth within 4 of them.
    assert fit.boxes > 60 and 0 < fit.mu_exponent_error < 0.3 and 0 < fit.east_west_excess_error < 0.3
    assert abs(fit.mu_exponent - exponent) < 4 * fit.mu_exponent_error
    assert abs(fit.east_west_excess - excess) < 4 * fit.east_west_excess_error


def test_a_box_of_strong_field_is_left_out():
    smap = _disk(1.0, 0.0, seed=6)
    boxes = limb_power_fit(smap).boxes
    strong = np.array(smap.data)
    strong[N // 2 - 10:N // 2 + 10, N // 2 - 10:N // 2 + 10] = 100.0      # an active region at disk centre
    assert limb_power_fit(_map(strong)).boxes < boxes
    # Allowing any fraction of strong pixels keeps it.
    assert limb_power_fit(_map(strong), strong_fraction=1.0).boxes == boxes


def test_a_map_that_holds_too_little_of_the_disk_is_refused():
    with pytest.raises(ValueError, match="boxes"):
        limb_power_fit(_map(np.random.default_rng(0).normal(0, 2, (60, 60))))


@pytest.mark.parametrize("kwargs, name", [({"box": -160 * u.arcsec}, "box"), ({"box": 160 * u.G}, "box"),
                                          ({"band": (50 * u.Mm, 20 * u.Mm)}, "band"),
                                          ({"band": (20 * u.Mm,)}, "band"),
                                          ({"strong_fraction": 2.0}, "strong_fraction"),
                                          ({"disk_edge": 0.0}, "disk_edge"), ({"clip": 0 * u.G}, "clip")])
def test_bad_arguments_are_refused_by_name(kwargs, name):
    with pytest.raises((TypeError, ValueError, u.UnitsError), match=name):
        limb_power_fit(_map(np.zeros((N, N))), **kwargs)


def test_the_weak_field_is_clipped_about_the_median():
    data = np.full((20, 20), 3.0)
    data[0, 0], data[0, 1], data[0, 2] = 40.0, -80.0, np.nan
    weak, is_strong = weak_field(_map(data))
    assert weak.data[0, 0] == 15.0 and weak.data[0, 1] == -15.0 and np.isnan(weak.data[0, 2])
    assert weak.data[5, 5] == 0.0 and is_strong.sum() == 1 and weak.unit == u.G
    # In kG: the same field.  A Dopplergram is refused.
    kg = sunpy.map.Map(data / 1000, {**_map(data).meta, "bunit": "kG"})
    assert np.allclose(weak_field(kg)[0].data, weak.data, equal_nan=True)
    with pytest.raises(ValueError, match="magnetogram"):
        limb_power_fit(sunpy.map.Map(data, {**_map(data).meta, "bunit": "m/s"}))


@pytest.mark.parametrize("along, excess_in", [("x", "x"), ("y", "y")])
def test_stripes_put_their_power_in_their_axis(along, excess_in):
    # Stripes of 4 pixels: 14.5 Mm at disk centre, in the 7-15 Mm band.
    wave = 5.0 * np.sin(2 * np.pi * np.arange(N) / 4)
    data = np.tile(wave, (N, 1)) if along == "x" else np.tile(wave[:, None], (1, N))
    table = axis_anisotropy(_map(data), bands=((7 * u.Mm, 15 * u.Mm),))
    assert list(table["axis"]) == ["east-west", "north-south"]
    ratio = np.asarray(table["xy_ratio"])
    assert np.all(ratio > 100) if excess_in == "x" else np.all(ratio < 0.01)


def test_the_anisotropy_of_isotropic_noise_is_one_within_its_scatter():
    # 7.5-15 Mm: 5″ pixels resolve nothing finer (3.7-7 Mm reads NaN, beyond their Nyquist wavelength).
    table = axis_anisotropy(_disk(0.0, 0.0, seed=7), bands=((7.5 * u.Mm, 15 * u.Mm),))
    # Each direction of a box holds ~50 independent modes once the window has correlated its neighbours; a
    # ratio of two such means scatters by ~sqrt(2/50) = 0.2, and 4 boxes average it to ~0.1 (0.10-0.11 over
    # 20 seeds): 4 of those.
    assert np.all(np.abs(np.asarray(table["xy_ratio"]) - 1) < 0.42)
    assert np.all(np.isnan(np.asarray(axis_anisotropy(_disk(0.0, 0.0, seed=7))["xy_ratio"])[::2]))


def test_the_anisotropy_refuses_a_map_without_its_boxes():
    with pytest.raises(ValueError, match="does not hold"):
        axis_anisotropy(_map(np.zeros((100, 100))))
    with pytest.raises(ValueError, match="radii"):
        axis_anisotropy(_map(np.zeros((N, N))), radii=(1.2,))
    with pytest.raises(ValueError, match="band"):
        axis_anisotropy(_map(np.zeros((N, N))), bands=((15 * u.Mm, 7 * u.Mm),))


def test_compare_reports_each_maps_fit_and_nan_where_it_cannot():
    stats = compare_statistics(_disk(2.0, 1.0, seed=8), _disk(0.0, 0.0, seed=9))
    t = stats.table
    for row, (exponent, excess) in ((0, (2.0, 1.0)), (1, (0.0, 0.0))):
        assert abs(t["limb_exponent"][row] - exponent) < 4 * t["limb_exponent_error"][row]
        assert abs(t["east_west_excess"][row] - excess) < 4 * t["east_west_excess_error"][row]
    assert "east-west excess c" in stats.summary()
    small = [_map(np.random.default_rng(s).normal(0, 3, (60, 60))) for s in (1, 2)]
    assert np.all(np.isnan(np.asarray(compare_statistics(*small).table["limb_exponent"], dtype=float)))
