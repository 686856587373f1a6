"""The measurements of two comparison scripts: published cross-calibration factors, network polarity."""
import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"


def _script(name):
    path = SCRIPTS / f"{name}.py"
    if not path.exists():
        pytest.skip("needs a source checkout")
    sys.path.insert(0, str(SCRIPTS))      # the polarity script imports its sibling's runs
    try:
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(str(SCRIPTS))
    return module


def _fulldisk_table(path, slopes):
    from astropy.table import Table

    rows = [(a, b, 0.0, 90.0, 0.0, np.inf, slope) for (a, b), slope in slopes.items()]
    rows.append(("gong", "hmi", 0.0, 15.0, 0.0, np.inf, 99.0))     # a band row: must not be read
    Table(rows=rows, names=("map_a", "map_b", "angle_min", "angle_max", "strength_min", "strength_max",
                            "slope")).write(path, format="ascii.ecsv")


def test_one_shared_factor_is_read_back_from_both_ratios(tmp_path):
    published = _script("published_cross_calibration")
    ratios = published.published_ratios()
    assert ratios["mdi/gong"] == pytest.approx(ratios["hmi/gong"] * ratios["mdi/hmi"])
    # A model whose Ni I instruments both read 1.2 times more, against HMI, than the published factors.
    shared = 1.2
    _fulldisk_table(tmp_path / "run.ecsv", {("gong", "hmi"): ratios["hmi/gong"] / shared,
                                            ("mdi", "hmi"): 1 / (ratios["mdi/hmi"] * shared),
                                            ("gong", "mdi"): ratios["mdi/gong"]})
    model = published.modelled_ratios(tmp_path / "run.ecsv")
    assert ratios["hmi/gong"] / model["hmi/gong"] == pytest.approx(shared)
    assert model["mdi/hmi"] / ratios["mdi/hmi"] == pytest.approx(shared)
    assert model["mdi/gong"] == pytest.approx(ratios["mdi/gong"])


def test_the_guide_shows_the_shipped_tables_comparison():
    published = _script("published_cross_calibration")
    shipped = published.GUIDE / "published_cross_calibration.txt"
    if not shipped.exists():
        pytest.skip("needs a source checkout")
    table = published.comparison_table()
    assert shipped.read_text() == published.summary(table)
    from astropy.table import Table

    drawn = Table.read(published.GUIDE / "published_cross_calibration.ecsv", format="ascii.ecsv")
    assert list(drawn["run"]) == list(table["run"])
    assert np.allclose(drawn["hmi_over_gong"], table["hmi_over_gong"])


def _peaks(rng, shape, n, plateau=0.0):
    """Isolated 60 G peaks of random sign, each on a same-signed disc of ``plateau`` G, in a 2-G noise."""
    field = rng.normal(0.0, 2.0, shape)
    rows = rng.integers(25, shape[0] - 25, n)
    cols = rng.integers(25, shape[1] - 25, n)
    yy, xx = np.mgrid[:shape[0], :shape[1]]
    for row, col in zip(rows, cols):
        sign = rng.choice((-1.0, 1.0))
        near = (yy - row) ** 2 + (xx - col) ** 2
        field += sign * np.where(near <= 20 ** 2, plateau, 0.0)
        field[row, col] += sign * 60.0
    return field


@pytest.mark.parametrize("plateau", [0.0, 3.0])
def test_the_polarity_halo_reads_a_same_signed_neighbourhood(plateau):
    polarity = _script("network_polarity_vs_real")
    rng = np.random.default_rng(3)
    shape = (300, 300)
    field = _peaks(rng, shape, 12, plateau)
    good = np.ones(shape, dtype=bool)
    radius = np.zeros(shape)
    used, halo = polarity.polarity_halo(field, good, radius, 1.0, peaks=(25.0, 80.0), bands=((7.0, 14.0),))
    assert used >= 10
    # The noise's mean over a ring of ~460 pixels, over >= 10 peaks: 2 / sqrt(4600) = 0.03 G (5 sigma).
    assert halo[0] == pytest.approx(plateau, abs=0.15)


def test_the_large_scale_balance_of_white_noise_falls_as_the_smoothing_area():
    polarity = _script("network_polarity_vs_real")
    rng = np.random.default_rng(4)
    shape = (400, 400)
    field = rng.normal(0.0, 5.0, shape)
    good = np.ones(shape, dtype=bool)
    radius = np.zeros(shape)
    rms = polarity.large_scale_balance(field, good, radius, 1.0, sigmas=(4.0, 8.0))
    # White noise of 5 G smoothed by a Gaussian of sigma s pixels: 5 / (2 sqrt(pi) s).
    expected = [5.0 / (2 * np.sqrt(np.pi) * s) for s in (4.0, 8.0)]
    assert rms == pytest.approx(expected, rel=0.1)


def _disk_map(data, obstime="2009-09-05T18:54", unit="G"):
    """A full-disk map of ``data`` (in ``unit``) at 2.5″ pixels, centred on the disk; NaN off it."""
    import astropy.units as u
    import sunpy.map
    from astropy.coordinates import SkyCoord
    from sunpy.coordinates import frames

    centre = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective, observer="earth",
                      obstime=obstime)
    header = sunpy.map.make_fitswcs_header(data.shape, centre, scale=[2.5, 2.5] * u.arcsec / u.pix,
                                           unit=u.Unit(unit))
    smap = sunpy.map.Map(data, header)
    radius = smap.rsun_obs.to_value(u.arcsec) / 2.5
    yy, xx = np.indices(data.shape)
    rho = np.hypot(xx - (data.shape[1] - 1) / 2, yy - (data.shape[0] - 1) / 2) / radius
    return sunpy.map.Map(np.where(rho < 1, data, np.nan), header), rho, radius


def test_an_offset_between_the_states_turns_a_doppler_gradient_into_a_field():
    import astropy.units as u

    from gongsynth import GONGInstrument

    anisotropy = _script("limb_anisotropy")
    n = 64
    magnetogram, _, _ = _disk_map(np.full((n, n), 5.0))
    ramp = 100.0 * np.arange(n)[None, :] * np.ones((n, 1))                # 100 m/s per pixel
    doppler, _, _ = _disk_map(ramp, unit="m/s")
    shifted = anisotropy.with_state_offset(magnetogram, doppler, 0.1)
    per_velocity = GONGInstrument().gauss_per_velocity.to_value(u.G / (u.m / u.s))
    # B = (G per m/s) x (v+ - v-) / 2 with v+ - v- = 0.1 pixel x 100 m/s per pixel.
    assert np.allclose(shifted.data[1:-1, 1:-1], 5.0 + per_velocity * 0.1 * 100.0 / 2)


def test_frozen_flow_tilt_across_the_wind_is_three_halves_of_that_along_it():
    wind = _script("wind_seeing_anisotropy")
    # Kolmogorov between the outer scale and the aperture (κ0 = 6e-6, κ∥ = 6, 1/D = 1e4 per m):
    # Γ(3/2) Γ(1/3) / (√π Γ(4/3)) = 3/2.
    along, across = wind.tilt_spectra(1.0, 1.0, 1e-4, 1e6)
    assert across[0] / along[0] == pytest.approx(1.5, rel=0.01)
    # Far above the aperture's frequency the tilt along the wind is the larger.
    along, across = wind.tilt_spectra(2000.0, 1.0, 0.01, 20.0)
    assert across[0] < along[0]


def test_a_wind_from_the_suns_azimuth_at_transit_lies_along_celestial_north():
    import astropy.units as u
    from astropy.coordinates import AltAz, get_body
    from astropy.time import Time
    from sunpy.coordinates.sun import P

    from gongsynth.observing import site_location

    wind = _script("wind_seeing_anisotropy")
    site = site_location("BB")
    # Big Bear's local noon of 2009-09-05 (the Sun transits near 19:49 UT): find the transit.
    times = Time("2009-09-05T19:30") + np.linspace(0, 40, 81) * u.min
    altitude = get_body("sun", times, site).transform_to(AltAz(obstime=times, location=site)).alt.deg
    transit = times[int(np.argmax(altitude))]
    # At transit the Sun is due south; a wind from the south lies in the vertical, which is celestial
    # north, P east of solar north: 90° - P from the image's +x.
    angle = wind.projected_wind_angle(transit, site, 180.0)
    assert angle == pytest.approx((90.0 - P(transit).deg) % 180, abs=1.0)
    # A wind at right angles to it lies across it on the image.
    across = wind.projected_wind_angle(transit, site, 90.0)
    assert abs((across - angle) % 180 - 90) < 1.0
