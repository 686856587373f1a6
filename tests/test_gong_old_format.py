"""
Real GONG site files in the old header (Big Bear, 2009-09-05): read, placed on the Sun, calibrated.

The old header has CTYPE GONGX/GONGY with CDELT = 0, the apparent radius as
RADIUS (radians), the fitted limb's semi-axes FNDLMBMI/FNDLMBMA (pixels), the
disk centre as CRPIX1/2, DATE-OBS and TIME-OBS apart, DTYPE RW and a sky of
about -2000 G; sunpy refuses it.  The expected numbers come from the header
itself and from shared/data/real/PROVENANCE.md.
"""
import warnings

import astropy.units as u
import numpy as np
import pytest
from astropy.io import fits
from sunpy.coordinates import sun

import gongsynth
from gongsynth.analysis.disk import disk_centre_pixel, disk_coordinates

from .realdata import load_real, real_file

MAGNETOGRAM = "gong/bbbqa090905t1854.fits.gz"
INTENSITY = "gong/bbiqa090905t1854.fits.gz"


@pytest.fixture(scope="module")
def magnetogram():
    return load_real(MAGNETOGRAM, "magnetogram")


def test_old_header_places_the_disk(magnetogram):
    header = fits.getheader(real_file(MAGNETOGRAM))
    # Disk centre: CRPIX1/2 (1-based) of the header, in 0-based pixels.
    x, y = disk_centre_pixel(magnetogram)
    assert (x, y) == pytest.approx((header["CRPIX1"] - 1, header["CRPIX2"] - 1), abs=1e-3)
    # Radius: RADIUS in radians = 952.06"; the plate scale puts it at FNDLMBMI pixels (371.5).
    assert magnetogram.rsun_obs.to_value(u.arcsec) == pytest.approx(
        (header["RADIUS"] * u.rad).to_value(u.arcsec), rel=1e-9)
    radius_px = magnetogram.rsun_obs / magnetogram.scale.axis1 / u.pix
    assert radius_px.decompose().value == pytest.approx(header["FNDLMBMI"], rel=1e-6)
    assert magnetogram.date.isot == "2009-09-05T18:54:16.000"
    # The observer is on Earth: B0 from the ephemeris (the header has none).
    assert magnetogram.observer_coordinate.lat.to_value(u.deg) == pytest.approx(
        sun.B0("2009-09-05T18:54:16").to_value(u.deg), abs=1e-6)
    # Orientation: the header's PA is the ephemeris P angle, which the GONG
    # reduction removes to put solar north up; the file agrees with the ephemeris.
    assert np.rad2deg(header["PA"]) == pytest.approx(sun.P("2009-09-05T18:54:16").to_value(u.deg), abs=0.05)


def test_old_magnetogram_values_match_provenance(magnetogram):
    rho, _ = disk_coordinates(magnetogram)
    assert magnetogram.unit == u.G
    inner = magnetogram.data[rho < 0.5]
    # PROVENANCE.md: inside 0.5 R mean -2.0 G, std 12.9 G, values in 0.27 G steps.
    assert np.mean(inner) == pytest.approx(-2.0, abs=0.05)
    assert np.std(inner) == pytest.approx(12.9, abs=0.05)
    steps = np.unique(np.round(np.diff(np.unique(inner)), 4))
    assert steps.min() == pytest.approx(0.27, abs=1e-3)
    # The -2000 G sky is NaN beyond the limb, nothing on the disk is.
    assert np.all(np.isnan(magnetogram.data[rho > 1.02]))
    assert not np.isnan(magnetogram.data[rho < 0.99]).any()


def test_old_intensity_image_reads_as_continuum():
    image = load_real(INTENSITY, "continuum")
    rho, _ = disk_coordinates(image)
    centre, limb = np.mean(image.data[rho < 0.2]), np.mean(image.data[(rho > 0.9) & (rho < 0.95)])
    # Limb darkening at 676.8 nm: I(μ≈0.36)/I(1) ≈ 0.6-0.7, well below 1.
    assert 0.5 < limb / centre < 0.8


def test_old_magnetogram_calibrates(magnetogram, tmp_path):
    calibrated = gongsynth.calibrate(magnetogram)
    both = np.isfinite(calibrated.data) & np.isfinite(magnetogram.data)
    assert both.sum() > 0.9 * np.isfinite(magnetogram.data).sum()
    ratio = np.abs(calibrated.data[both]).sum() / np.abs(magnetogram.data[both]).sum()
    assert 0.9 < ratio < 1.35 and ratio != 1


def test_rice_compressed_copy_reads_the_same(magnetogram, tmp_path):
    # The GONG archive also serves Rice-compressed .fits.fz files, the image
    # (16-bit integers with BSCALE) in the first extension.
    with fits.open(real_file(MAGNETOGRAM), do_not_scale_image_data=True) as hdul:
        raw, header = hdul[0].data.copy(), hdul[0].header.copy()
    compressed = fits.CompImageHDU(raw, header, compression_type="RICE_1")
    compressed.header["BSCALE"], compressed.header["BZERO"] = header["BSCALE"], header["BZERO"]
    path = tmp_path / "bbbqa090905t1854.fits.fz"
    fits.HDUList([fits.PrimaryHDU(), compressed]).writeto(path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", fits.verify.VerifyWarning)
        copy = gongsynth.load_observation(path)
    assert np.array_equal(copy.data, magnetogram.data, equal_nan=True)
    assert copy.wcs.wcs.compare(magnetogram.wcs.wcs)
