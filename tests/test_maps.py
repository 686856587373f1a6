import astropy.units as u
import numpy as np
import pytest
import sunpy.map
from astropy.io import fits
from sunpy.coordinates import frames

from gongsynth.geometry import field_centre
from gongsynth.products.maps import GONGSynthMap, make_product_map


def test_product_map_round_trips_through_sunpy(tmp_path):
    centre, _ = field_centre(60 * u.deg)
    data = np.arange(12.0).reshape(3, 4) * u.G
    smap = make_product_map(data, centre=centre, scale=2.5 * u.arcsec, product="magnetogram",
                            extra={"seed": ("42", "root random seed")})
    path = tmp_path / "m.fits"
    fits.PrimaryHDU(smap.data, fits.Header(smap.fits_header)).writeto(path)
    again = sunpy.map.Map(path)
    assert isinstance(again, GONGSynthMap)
    assert again.unit == u.G and again.measurement == "MAGNETOGRAM"
    assert again.meta["dtype"] == "SIMULATED" and again.meta["seed"] == "42"
    assert again.scale.axis1 == 2.5 * u.arcsec / u.pix
    assert np.array_equal(again.data, data.value)
    # The centre pixel maps back to the requested latitude.
    hgs = again.pixel_to_world(*(np.array(again.data.shape[::-1]) - 1) / 2 * u.pix).transform_to(
        frames.HeliographicStonyhurst(obstime=again.date))
    assert hgs.lat.to_value(u.deg) == pytest.approx(60, abs=1e-6)
    assert again.plot_settings["cmap"] == "gray"


def test_real_gong_header_is_not_claimed():
    from sunpy.data.test import get_dummy_map_from_header, get_test_filepath

    real = get_dummy_map_from_header(get_test_filepath("gong_magnetogram.header"))
    assert not isinstance(real, GONGSynthMap)


def test_unknown_product():
    with pytest.raises(ValueError, match="product"):
        make_product_map(np.zeros((2, 2)) * u.G, centre=field_centre(0 * u.deg)[0],
                         scale=2.5 * u.arcsec, product="velocity")
