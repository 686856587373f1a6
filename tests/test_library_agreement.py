"""
The hand-written kernels against the library routines they stand in for.

gongsynth keeps its own FFT convolution (`gongsynth.stages.optics.convolve`:
one cached kernel transform for the six planes, float32 kept) and its own
exact-area binning (`gongsynth.analysis.degrade.degrade_to_gong`: a fixed grid
on the sky, a sparse operator per axis) because they are faster or exact where
the library is general.  These tests pin them to `astropy.convolution.convolve_fft`
and `reproject.reproject_exact`.
"""
import astropy.units as u
import numpy as np
import pytest
import sunpy.map
from astropy.convolution import convolve_fft
from astropy.coordinates import SkyCoord
from sunpy.coordinates import frames

from gongsynth.analysis.degrade import degrade_to_gong
from gongsynth.stages.optics import convolve
from gongsynth.stages.psf import psf_kernel


@pytest.fixture(scope="module")
def image():
    return np.random.default_rng(5).lognormal(0, 0.5, (96, 128))


@pytest.mark.parametrize("boundary, astropy_boundary", [("periodic", "wrap"), ("zero", "fill")])
def test_convolution_matches_astropy_convolve_fft(image, boundary, astropy_boundary):
    kernel = psf_kernel(1.0 * u.arcsec, shape=41)
    ours = convolve(image, kernel, boundary=boundary)
    theirs = convolve_fft(image, kernel, boundary=astropy_boundary, fill_value=0.0,
                          normalize_kernel=True, nan_treatment="fill")
    # Both are double-precision FFT convolutions of the same arrays: they agree
    # to rounding (~1e-15 of the image level), far below any physical effect.
    assert np.max(np.abs(ours - theirs)) < 1e-12 * image.max()


def test_convolution_of_an_asymmetric_kernel_has_the_same_orientation(image):
    # An asymmetric kernel catches a flipped or shifted kernel centre.
    kernel = np.zeros((5, 7))
    kernel[2, 3], kernel[0, 6], kernel[4, 1] = 1.0, 0.5, 0.25
    theirs = convolve_fft(image, kernel, boundary="wrap", normalize_kernel=True)
    assert np.max(np.abs(convolve(image, kernel) - theirs)) < 1e-12 * image.max()


def test_area_binning_matches_reproject_exact():
    reproject = pytest.importorskip("reproject")
    ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
                   observer="earth", obstime="2020-01-01")
    data = np.random.default_rng(7).normal(0, 100, (240, 250))
    fine = sunpy.map.Map(data, sunpy.map.make_fitswcs_header(
        data.shape, ref, reference_pixel=[117.3, 121.6] * u.pix, scale=[0.5, 0.5] * u.arcsec / u.pix,
        unit=u.G))
    ours = degrade_to_gong(fine, psf=False, min_coverage=1.0)
    theirs, footprint = reproject.reproject_exact(fine, ours.wcs, shape_out=ours.data.shape)
    inside = np.isfinite(ours.data) & (footprint > 0.999)
    assert inside.sum() > 0.8 * ours.data.size
    # reproject_exact intersects spherical polygons, ours plane rectangles in
    # the tangent plane; over this 2' field the two differ by the projection's
    # distortion, ~(60"/206265")^2 ~ 1e-7 relative (2e-7 G measured), far
    # below the 1e-4 G allowed here against binned values of ~20 G rms; a
    # shift of one fine pixel would differ by ~40 G.
    assert np.max(np.abs(ours.data[inside] - theirs[inside])) < 1e-4
