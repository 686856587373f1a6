"""Reading real GONG / MDI / HMI files: units, WCS, header repair and bad input."""
import math
import warnings

import astropy.units as u
import numpy as np
import pytest
import sunpy.map
from astropy.coordinates import SkyCoord
from astropy.io import fits
from sunpy.coordinates import frames
from sunpy.map.sources import GONGMagnetogramMap, HMIMap, MDIMap

from gongsynth.analysis.disk import disk_coordinates
from gongsynth.analysis.observations import (
    BadHeaderError,
    BadHeaderWarning,
    ObservationKindError,
    check_disk_footprint,
    load_observation,
)

from .realdata import gong_header, gong_rho, real_file, write_gong_fits

MDI_M = "mdi/mdi.fd_m_96m_lev182.20101015_000000_TAI.data.fits"
MDI_IC = "mdi/mdi.fd_ic.20101015_230100_TAI.data.fits"
MDI_SMALL = "mdi/mdi_fd_M_96m_01d.5874.0005_s.fits"
HMI_M = "hmi/JSOC_hmi.m_45s.20101020_000000_TAI.2.magnetogram.fits"


def _hpc(smap):
    return frames.Helioprojective(observer=smap.observer_coordinate, obstime=smap.reference_date,
                                  rsun=smap.rsun_meters)


def _small_map_file(tmp_path, name="m.fits", *, unit="G", shape=(64, 64), data=None, drop=(), extra=None):
    ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective, observer="earth",
                   obstime="2020-06-01")
    header = sunpy.map.make_fitswcs_header(shape, ref, scale=[40, 40] * u.arcsec / u.pix)
    hdr = fits.Header()
    for key, value in header.items():
        if key.upper() not in drop:
            hdr[key] = value
    if unit is not None:
        hdr["BUNIT"] = unit
    for key, value in (extra or {}).items():
        hdr[key] = value
    values = np.random.default_rng(0).normal(0, 5, shape) if data is None else data
    path = tmp_path / name
    fits.PrimaryHDU(values, hdr).writeto(path)
    return path


# ----------------------------------------------------------------------------- real MDI


def test_mdi_magnetogram_in_gauss_with_its_header_statistics():
    path = real_file(MDI_M)
    m = load_observation(path)
    assert isinstance(m, MDIMap)
    assert m.unit == u.G
    assert isinstance(m.coordinate_frame, frames.Helioprojective)
    header = fits.getheader(path, 1)
    finite = m.data[np.isfinite(m.data)]
    # The RICE-compressed integers are scaled back to the values JSOC summarised.
    assert finite.size == header["DATAVALS"]
    assert np.mean(finite) == pytest.approx(header["DATAMEAN"], abs=1e-3)
    assert np.sqrt(np.mean(finite**2)) == pytest.approx(header["DATARMS"], rel=1e-4)
    # Disk centre is where X0/Y0 (0-based) say it is.
    x, y = m.wcs.world_to_pixel(SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=m.coordinate_frame))
    assert float(x) == pytest.approx(header["X0"], abs=1e-3)
    assert float(y) == pytest.approx(header["Y0"], abs=1e-3)
    assert "history" not in m.meta or "load_observation" not in str(m.meta["history"])


def test_mdi_continuum_is_refused_as_magnetogram_and_read_as_continuum():
    path = real_file(MDI_IC)
    with pytest.raises(ObservationKindError, match="not a magnetogram") as info:
        load_observation(path)
    message = str(info.value)
    assert path.name in message and "Arbitrary intensity units" in message
    assert "MDI Full Disk Intensity Continuum" in message
    ic = load_observation(path, kind="continuum")
    assert isinstance(ic, MDIMap)
    assert np.nanmax(ic.data) == pytest.approx(14789, abs=1)


def test_magnetogram_refused_as_continuum():
    path = real_file(MDI_M)
    with pytest.raises(ObservationKindError, match="not a continuum"):
        load_observation(path, kind="continuum")


def test_old_mdi_header_with_solar_x_ctype():
    path = real_file(MDI_SMALL)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no sunpy deprecation warning for 'solar-x'
        m = load_observation(path)
    header = fits.getheader(path)
    assert header["CTYPE1"] == "solar-x"
    assert m.coordinate_system.axis1 == "HPLN-TAN"
    assert m.unit == u.G
    assert m.rsun_obs.to_value(u.arcsec) == pytest.approx(header["OBS_R0"])
    assert "solar-x" in m.meta["history"]
    # CRVAL is the world coordinate of CRPIX.
    c = m.pixel_to_world((header["CRPIX1"] - 1) * u.pix, (header["CRPIX2"] - 1) * u.pix)
    assert c.Tx.to_value(u.arcsec) == pytest.approx(header["CRVAL1"], abs=1e-6)
    assert c.Ty.to_value(u.arcsec) == pytest.approx(header["CRVAL2"], abs=1e-6)


# ----------------------------------------------------------------------------- real HMI cut-out


def test_hmi_postel_cutout_wrong_wcs_is_detected_and_rebuilt():
    path = real_file(HMI_M)
    with pytest.warns(BadHeaderWarning, match="Postel") as record:
        m = load_observation(path)
    assert "rebuilt as CRLN-ARC/CRLT-ARC" in str(record[0].message)
    assert path.name in str(record[0].message)
    assert isinstance(m, HMIMap)
    assert isinstance(m.coordinate_frame, frames.HeliographicCarrington)
    assert m.unit == u.G
    header = fits.getheader(path, 1)
    dsun = header["DSUN_OBS"] * u.m
    rsun = header["RSUN_REF"] * u.m
    step = header["CDELT1"] * u.deg  # the true scale: heliographic degrees per pixel

    # The patch centre is the sub-observer point: disk centre.
    centre = m.pixel_to_world(511.5 * u.pix, 511.5 * u.pix).transform_to(_hpc(m))
    assert abs(centre.Tx) < 0.01 * u.arcsec and abs(centre.Ty) < 0.01 * u.arcsec

    # Postel: n pixels from the centre lie n*step of great circle away on the sphere;
    # seen from distance D that point is at atan(R sin(rho) / (D - R cos(rho))).
    for n, axis in ((400, "x"), (-300, "x"), (350, "y")):
        rho = (abs(n) * step).to_value(u.rad)
        expect = math.copysign(math.degrees(math.atan2(rsun.value * math.sin(rho),
                                                       dsun.value - rsun.value * math.cos(rho))) * 3600, n)
        px, py = (511.5 + n, 511.5) if axis == "x" else (511.5, 511.5 + n)
        c = m.pixel_to_world(px * u.pix, py * u.pix).transform_to(_hpc(m))
        got, other = (c.Tx, c.Ty) if axis == "x" else (c.Ty, c.Tx)
        assert got.to_value(u.arcsec) == pytest.approx(expect, abs=0.05)
        assert abs(other) < 0.05 * u.arcsec


def test_hmi_without_repair_warns_and_keeps_header():
    path = real_file(HMI_M)
    with pytest.warns(BadHeaderWarning, match="repair=False"):
        m = load_observation(path, repair=False)
    assert isinstance(m.coordinate_frame, frames.Helioprojective)
    assert m.scale.axis1.to_value(u.arcsec / u.pix) == pytest.approx(0.0301)


def test_unrepairable_jsoc_projection_raises(tmp_path):
    path = _small_map_file(tmp_path, extra={"HISTORY": "MapProj=carree, LonHG=10.0, LatHG=0.0"})
    with pytest.raises(BadHeaderError, match="carree"):
        load_observation(path)


# ----------------------------------------------------------------------------- GONG format


@pytest.fixture(scope="module")
def gong_file(tmp_path_factory):
    rng = np.random.default_rng(11)
    data = rng.normal(0, 3.0, (860, 860))
    return write_gong_fits(tmp_path_factory.mktemp("gong") / "lezqa250109t0135.fits", data)


def test_gong_zqa_file_reads_as_gong_magnetogram(gong_file):
    m = load_observation(gong_file)
    assert isinstance(m, GONGMagnetogramMap)
    assert m.unit == u.G
    header = gong_header()
    rho = gong_rho()
    on_disk = rho < 0.99
    assert np.all(np.isfinite(m.data[on_disk]))
    assert np.all(np.isnan(m.data[rho > 1.01]))  # SKYVALUE pixels are blanked
    # Quantised as stored (BSCALE) but otherwise the values written.
    values = m.data[on_disk]
    assert np.allclose(values / header["BSCALE"], np.round(values / header["BSCALE"]), atol=1e-3)
    assert np.std(values) == pytest.approx(3.0, rel=0.01)
    # Disk centre at CRPIX (1-based) of the real header; radius from SEMIDIAM.
    x, y = m.wcs.world_to_pixel(SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=m.coordinate_frame))
    assert float(x) == pytest.approx(header["CRPIX1"] - 1, abs=1e-6)
    assert float(y) == pytest.approx(header["CRPIX2"] - 1, abs=1e-6)
    assert m.rsun_obs.to_value(u.arcsec) == pytest.approx(
        (header["SEMIDIAM"] * u.rad).to_value(u.arcsec))


def test_gong_format_not_claimed_by_sunpy_gets_equivalent_wcs(tmp_path, gong_file):
    header = gong_header()
    header["DTYPE"] = "CALIB"  # sunpy's GONG source only claims DTYPE = 'OBSERVE'
    path = write_gong_fits(tmp_path / "calib.fits", np.zeros((860, 860)), header)
    m = load_observation(path)
    assert not isinstance(m, GONGMagnetogramMap)
    assert "GONGX" in m.meta["history"] or "GONG-format" in m.meta["history"]
    real = load_observation(gong_file)
    assert m.scale.axis1.to_value(u.arcsec / u.pix) == pytest.approx(
        real.scale.axis1.to_value(u.arcsec / u.pix), rel=1e-9)
    for px in ((100, 700), (430, 430), (800, 50)):
        a = m.pixel_to_world(*px * u.pix)
        b = real.pixel_to_world(*px * u.pix)
        assert a.Tx.to_value(u.arcsec) == pytest.approx(b.Tx.to_value(u.arcsec), abs=1e-6)
        assert a.Ty.to_value(u.arcsec) == pytest.approx(b.Ty.to_value(u.arcsec), abs=1e-6)


def test_gong_header_missing_limb_keywords(tmp_path):
    header = gong_header()
    del header["FNDLMBMI"]
    path = write_gong_fits(tmp_path / "bad.fits", np.zeros((860, 860)), header)
    with pytest.raises(BadHeaderError, match="FNDLMBMI"):
        load_observation(path)


# ----------------------------------------------------------------------------- wrong WCS


@pytest.mark.parametrize("change", ["crpix", "cdelt"])
def test_disk_footprint_disagreeing_with_wcs_warns(tmp_path, change):
    path = real_file(MDI_M)
    with fits.open(path) as hdul:
        header = hdul[1].header.copy()
        data = hdul[1].data.astype(np.float32)
    if change == "crpix":
        header["CRPIX1"] += 120
    else:
        header["CDELT1"] *= 1.25
        header["CDELT2"] *= 1.25
    for key in ("BSCALE", "BZERO", "BLANK"):
        header.remove(key, ignore_missing=True)
    bad = tmp_path / "bad.fits"
    fits.PrimaryHDU(data, header).writeto(bad)
    with pytest.warns(BadHeaderWarning, match="do not match the solar disk"):
        load_observation(bad)


def test_check_disk_footprint_accepts_true_disk_and_flags_shifted_one():
    ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective, observer="earth",
                   obstime="2020-06-01")
    m = sunpy.map.Map(np.zeros((120, 120)), sunpy.map.make_fitswcs_header(
        (120, 120), ref, scale=[20, 20] * u.arcsec / u.pix))
    rho, _ = disk_coordinates(m)
    assert check_disk_footprint(sunpy.map.Map(np.where(rho < 1, 1.0, np.nan), m.meta))
    shifted = np.where(np.roll(rho, 20, axis=1) < 1, 1.0, np.nan)
    with pytest.warns(BadHeaderWarning):
        assert not check_disk_footprint(sunpy.map.Map(shifted, m.meta), name="shifted")


# ----------------------------------------------------------------------------- bad input


@pytest.mark.parametrize("missing", [("CDELT1", "CDELT2"), ("CTYPE1",), ("CRPIX2",), ("DATE-OBS",)])
def test_missing_wcs_keywords(tmp_path, missing):
    path = _small_map_file(tmp_path, drop=missing)
    with pytest.raises(BadHeaderError, match="missing WCS keyword") as info:
        load_observation(path)
    assert missing[0].split("-")[0] in str(info.value)
    assert path.name in str(info.value)


def test_nan_only_map(tmp_path):
    path = _small_map_file(tmp_path, data=np.full((64, 64), np.nan))
    with pytest.raises(ValueError, match="no finite pixel"):
        load_observation(path)


def test_unit_conversion_to_gauss(tmp_path):
    data = np.full((64, 64), 1e-3)
    m = load_observation(_small_map_file(tmp_path, unit="T", data=data))
    assert m.unit == u.G
    assert np.allclose(m.data, 10.0)


def test_not_a_magnetogram_by_unit(tmp_path):
    with pytest.raises(ObservationKindError, match="m / s|m/s"):
        load_observation(_small_map_file(tmp_path, unit="m/s"))


def test_no_bunit_but_content_says_magnetogram(tmp_path):
    path = _small_map_file(tmp_path, unit=None, extra={"CONTENT": "MAGNETOGRAM"})
    m = load_observation(path)
    assert m.unit == u.G
    assert "values taken as gauss" in m.meta["history"]
    with pytest.raises(ObservationKindError, match="BUNIT = '\\(none\\)'"):
        load_observation(_small_map_file(tmp_path, "plain.fits", unit=None))


def test_files_that_are_not_fits_images(tmp_path):
    jpeg = tmp_path / "quicklook.jpg"
    jpeg.write_bytes(b"\xff\xd8\xff\xe0" + bytes(2000))
    with pytest.raises(ValueError, match="not a readable FITS file"):
        load_observation(jpeg)
    table = tmp_path / "table.fits"
    fits.HDUList([fits.PrimaryHDU(), fits.BinTableHDU.from_columns(
        [fits.Column(name="a", format="E", array=np.arange(3.0))])]).writeto(table)
    with pytest.raises(ValueError, match="no image HDU"):
        load_observation(table)
    with pytest.raises(FileNotFoundError, match="no such file"):
        load_observation(tmp_path / "absent.fits")
    with pytest.raises(ValueError, match="kind must be one of"):
        load_observation(table, kind="doppler")
    with pytest.raises(TypeError, match="path must be"):
        load_observation(3)


def test_real_gong_quicklook_jpeg_is_refused():
    with pytest.raises(ValueError, match="not a readable FITS file"):
        load_observation(real_file("gong/bbzqa240209t1734_dim-860.jpg"))


def test_real_adapt_cube_is_refused():
    with pytest.raises(ValueError, match="3-D array of shape \\(12, 180, 360\\)"):
        load_observation(real_file("gong/adapt40311_03k012_201707200800_i00015600n1.fts.gz"))


@pytest.mark.remote_data
def test_real_gong_zqa_from_nso(tmp_path):
    """A real GONG 10-minute averaged magnetogram from the NSO archive (network)."""
    from astropy.utils.data import download_file

    url = "https://nispdata.nso.edu/ftp/oQR/zqa/202402/bbzqa240209/bbzqa240209t1734.fits.gz"
    path = download_file(url, cache=True, timeout=60)
    m = load_observation(path)
    assert isinstance(m, GONGMagnetogramMap)
    assert m.data.shape == (860, 860) and m.unit == u.G
    from gongsynth.analysis.noise import noise_estimate

    noise = noise_estimate(m)
    assert 0.5 * u.G < noise.sigma < 20 * u.G


def test_real_hmi_full_disk_continuum_rolled_180_degrees():
    """sunpy's resampled real HMI continuum (100 x 100, 20.66"/px, CROTA2 = 179.93 deg)."""
    import sunpy.data.test

    from gongsynth.analysis.compare import compare_limb_darkening, degrade_to_gong
    from gongsynth.analysis.noise import disk_centre_level

    path = sunpy.data.test.get_test_filepath("resampled_hmi.fits")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no BadHeaderWarning: the disk is where the WCS says
        m = load_observation(path, kind="continuum")
    assert isinstance(m, HMIMap)
    # astropy's VerifyWarning about its BLANK card is recorded, not re-emitted.
    assert "astropy fixed the header" in m.meta["history"] and "BLANK" in m.meta["history"]
    angle = math.degrees(math.atan2(m.rotation_matrix[1, 0], m.rotation_matrix[0, 0]))
    assert abs(angle) == pytest.approx(179.93, abs=0.01)
    # PROVENANCE.md: disk-centre mean about 60 500 DN/s.
    assert disk_centre_level(m).to_value(u.DN / u.s) == pytest.approx(60500, rel=0.05)
    # Turned upright onto 2.5" pixels, the centre-to-limb profile is unchanged.
    upright = degrade_to_gong(m, psf=False)
    assert np.allclose(upright.rotation_matrix, np.eye(2))
    result = compare_limb_darkening(m, upright, degrade=False, bins=8, plot=False)
    assert result.max_difference < 0.02
    assert result.centre_ratio == pytest.approx(1, abs=0.02)
    with pytest.raises(ObservationKindError, match="CONTINUUM INTENSITY"):
        load_observation(path)


@pytest.mark.parametrize("relpath", ["pairs/hmi.Synoptic_Mr_small.2253.fits", "pairs/gong_mrzqs_c2253.fits"])
def test_synoptic_map_without_observer_is_observed_from_earth(relpath):
    """HMI's synoptic charts carry no observer; the map gets Earth's at its date, without warnings."""
    path = real_file(relpath)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        smap = load_observation(path)
        observer = smap.observer_coordinate
        assert smap.wcs.wcs.ctype[0].startswith("CRLN")
    assert smap.unit == u.G
    assert abs(observer.radius.to_value(u.AU) - 1) < 0.02
    assert abs(observer.lat.to_value(u.deg)) < 7.3  # B0 never exceeds 7.25 deg
