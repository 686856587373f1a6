"""The offset between the polarisation states' images, read back from a magnetogram and its Dopplergram."""
import astropy.units as u
import numpy as np
import pytest
import sunpy.map
from astropy.coordinates import SkyCoord
from scipy.ndimage import gaussian_filter
from sunpy.coordinates import frames

from gongsynth import GONGInstrument
from gongsynth.analysis.state_offset import offset_field, state_offset

N = 300
G_V = GONGInstrument().gauss_per_velocity.to_value(u.G / (u.m / u.s))


def _map(data, unit):
    ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective, observer="earth",
                   obstime="2020-01-01")
    header = sunpy.map.make_fitswcs_header(data.shape, ref, scale=[7, 7] * u.arcsec / u.pix, unit=unit)
    return sunpy.map.Map(data, header)


def _maps(offset, seed, stretch_xx=0.0):
    """
    A flow field (m/s), and 3-G noise plus the field an offset between the states makes of it.

    The x offset grows by ``stretch_xx`` pixels per solar radius from disk centre.
    """
    rng = np.random.default_rng(seed)
    velocity = 4000.0 * gaussian_filter(rng.normal(size=(N, N)), 3.0)        # ~230 m/s rms
    grad_y, grad_x = np.gradient(velocity)
    radius = _map(velocity, u.m / u.s).rsun_obs.to_value(u.arcsec)
    x_sun = (np.arange(N) - (N - 1) / 2)[None, :] * 7.0 / radius
    offset_x = offset[0] + stretch_xx * x_sun
    field = rng.normal(0.0, 3.0, (N, N)) + 0.5 * G_V * (offset_x * grad_x + offset[1] * grad_y)
    return _map(field, u.G), _map(velocity, u.m / u.s)


@pytest.mark.parametrize("offset", [(0.0, 0.0), (0.1, -0.05)])
def test_a_known_offset_is_read_back_within_its_jackknife_error(offset):
    row = state_offset(*_maps(offset, seed=1))[0]
    for axis, true in zip("xy", offset):
        value, error = row[f"offset_{axis}"].to_value(u.pix), row[f"offset_{axis}_error"].to_value(u.pix)
        assert 0 < error < 0.01                  # ~40 000 pixels of 3-G noise: a few thousandths of a pixel
        assert abs(value - true) < 4 * error
    assert row["offset_x_arcsec"].to_value(u.arcsec) == pytest.approx(7 * row["offset_x"].to_value(u.pix))


def test_a_stretch_is_told_from_a_shift():
    field, velocity = _maps((0.0, 0.0), seed=5, stretch_xx=0.2)
    row = state_offset(field, velocity, stretch=True)[0]
    fitted = {"offset_x": 0.0, "offset_y": 0.0, "stretch_xx": 0.2, "stretch_xy": 0.0, "stretch_yx": 0.0,
              "stretch_yy": 0.0}
    for name, true in fitted.items():
        value, error = row[name].value, row[f"{name}_error"].value
        assert 0 < error < 0.02 and abs(value - true) < 4 * error, name
    assert row["stretch_xx"].unit == u.pix / u.R_sun
    # Fitted as one shift, a stretch symmetric about disk centre reads none.
    shift = state_offset(field, velocity)[0]
    assert abs(shift["offset_x"].value) < 4 * shift["offset_x_error"].value
    assert "stretch_xx" not in shift.colnames


def test_the_jackknife_error_matches_the_scatter_over_seeds():
    values = np.array([state_offset(*_maps((0.05, 0.0), seed))[0]["offset_x"].to_value(u.pix)
                       for seed in range(2, 10)])
    error = state_offset(*_maps((0.05, 0.0), 2))[0]["offset_x_error"].to_value(u.pix)
    # Eight seeds' standard deviation scatters by ~1/sqrt(2 x 7) = 27 % about the true error.
    assert 0.4 * error < values.std(ddof=1) < 2.5 * error


def test_a_dopplergram_in_km_per_s_reads_the_same_and_strong_field_is_left_out():
    field, velocity = _maps((0.1, 0.0), seed=3)
    in_km = _map(velocity.data / 1e3, u.km / u.s)
    assert state_offset(field, in_km)[0]["offset_x"] == state_offset(field, velocity)[0]["offset_x"]
    in_kilogauss = _map(field.data / 1e3, u.kG)
    assert state_offset(in_kilogauss, velocity)[0]["offset_x"].to_value(u.pix) == pytest.approx(
        state_offset(field, velocity)[0]["offset_x"].to_value(u.pix), rel=1e-9)
    with pytest.raises(ValueError, match="doppler"):
        state_offset(field, _map(velocity.data, u.G))
    spot = np.array(field.data)
    spot[140:160, 140:160] = 1500.0
    fitted = state_offset(_map(spot, u.G), velocity)[0]
    assert fitted["pixels"] < state_offset(field, velocity)[0]["pixels"]
    assert abs(fitted["offset_x"].to_value(u.pix) - 0.1) < 4 * fitted["offset_x_error"].to_value(u.pix)


def test_bad_input_is_refused_naming_the_argument():
    field, velocity = _maps((0.0, 0.0), seed=4)
    with pytest.raises(ValueError, match="doppler"):
        state_offset(field, _map(np.zeros((N, N + 1)), u.m / u.s))
    with pytest.raises(ValueError, match="highpass"):
        state_offset(field, velocity, highpass=0)
    with pytest.raises(ValueError, match="max_radius"):
        state_offset(field, velocity, max_radius=1.5)
    with pytest.raises(ValueError, match="blocks"):
        state_offset(field, velocity, blocks=1)
    with pytest.raises((TypeError, u.UnitsError), match="weak"):
        state_offset(field, velocity, weak=50)
    with pytest.raises((TypeError, u.UnitsError), match="gauss_per_velocity"):
        state_offset(field, velocity, gauss_per_velocity=0.7 * u.G)


def test_the_forward_model_is_half_g_v_times_the_offset_along_the_gradient():
    ramp = _map(50.0 * np.arange(N)[:, None] * np.ones((1, N)), u.km / u.s)     # 50 km/s per pixel along y
    field = offset_field(ramp, 0.3, -0.2)
    assert field.unit == u.G
    # Along y only: 0.5 x g_v x (-0.2 pixel) x 50 000 m/s per pixel; nothing from the x offset.
    assert np.allclose(field.data[1:-1, 1:-1], 0.5 * G_V * -0.2 * 5e4)
    with pytest.raises(ValueError, match="offset_y"):
        offset_field(ramp, 0.1, np.nan)


def test_a_stretch_from_the_forward_model_is_read_back_exactly_without_noise():
    rng = np.random.default_rng(11)
    velocity = _map(4000.0 * gaussian_filter(rng.normal(size=(N, N)), 3.0), u.m / u.s)
    stretch = [[0.2, 0.05], [-0.03, 0.1]]
    field = offset_field(velocity, 0.02, -0.01, stretch=stretch)
    row = state_offset(field, velocity, stretch=True)[0]
    assert row["offset_x"].to_value(u.pix) == pytest.approx(0.02, abs=1e-6)
    assert row["offset_y"].to_value(u.pix) == pytest.approx(-0.01, abs=1e-6)
    for name, true in zip(("stretch_xx", "stretch_xy", "stretch_yx", "stretch_yy"), np.ravel(stretch)):
        assert row[name].to_value(u.pix / u.R_sun) == pytest.approx(true, abs=1e-5), name
    # No stretch is the shift alone; a matrix of the wrong shape is refused by name.
    assert np.array_equal(offset_field(velocity, 0.02, stretch=np.zeros((2, 2))).data,
                          offset_field(velocity, 0.02).data)
    with pytest.raises(ValueError, match="stretch"):
        offset_field(velocity, 0.0, stretch=[0.1, 0.2])
