"""Tests of gongsynth.stages.optics: PSF, convolution, pixelization and photometry."""
import math
from types import SimpleNamespace

import astropy.units as u
import numpy as np
import pytest
import scipy.ndimage
import scipy.signal
from scipy.special import j1

from gongsynth import GONGInstrument
from gongsynth.stages import optics
from gongsynth.stages.optics import (
    convolve,
    expected_counts,
    normalize_kernel,
    observe,
    photometric_factor,
    pixelize,
    psf_kernel,
    psf_profile,
)

ARCSEC = math.pi / 648000  # rad


def airy(r_arcsec, inst):
    """Analytic Airy pattern per arcsec², unit integral (independent of the Hankel route)."""
    nu_c = (inst.aperture / inst.line_wavelength).to_value(u.one) * ARCSEC  # cycles / arcsec
    x = math.pi * nu_c * np.asarray(r_arcsec, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        shape = np.where(x > 0, 2 * j1(x) / x, 1.0) ** 2
    return math.pi * nu_c**2 / 4 * shape


def brute_force_psf(inst, step=0.1, half=60.0):
    """Airy samples convolved numerically with Gaussian samples on a fine grid."""
    axis = np.arange(-half, half + step / 2, step)
    r = np.hypot(axis[:, None], axis[None, :])
    sigma = inst.seeing_fwhm.to_value(u.arcsec) / (2 * math.sqrt(2 * math.log(2)))
    gauss = np.exp(-0.5 * (r / sigma) ** 2)
    gauss /= gauss.sum()
    return axis, scipy.signal.fftconvolve(airy(r, inst), gauss, mode="same")


def fwhm(axis, profile):
    """Full width at half maximum of a peaked 1-D profile by linear interpolation."""
    peak = np.argmax(profile)
    half = profile[peak] / 2
    right = peak + np.argmax(profile[peak:] < half)
    left = peak - np.argmax(profile[peak::-1] < half)
    xr = np.interp(half, profile[right - 1:right + 1][::-1], axis[right - 1:right + 1][::-1])
    xl = np.interp(half, profile[left:left + 2], axis[left:left + 2])
    return xr - xl


# --------------------------------------------------------------------- PSF
def test_pure_airy_matches_analytic_pattern_and_first_zero():
    inst = GONGInstrument(seeing_fwhm=0 * u.arcsec)
    r = np.linspace(0, 80, 801)
    got = psf_profile(r * u.arcsec, inst).to_value(u.arcsec**-2)
    want = airy(r, inst)
    assert np.max(np.abs(got - want)) < 1e-7 * want[0]
    first_zero = 1.2196698912665045 * (inst.line_wavelength / inst.aperture).to_value(u.one) / ARCSEC
    assert first_zero == pytest.approx(6.08, abs=0.01)  # design §3.9
    assert psf_profile(first_zero * u.arcsec, inst).value < 1e-8 * want[0]


def test_profile_has_unit_integral_up_to_the_airy_wings():
    r = np.linspace(0, 400, 8001)
    p = psf_profile(r * u.arcsec).value
    enclosed = np.trapezoid(2 * np.pi * r * p, r)
    # Airy wings: 1 - EE(r) -> 2 / (π x) with x = π ν_c r, here ≈ 0.25 % beyond 400".
    nu_c = 0.20058
    assert enclosed == pytest.approx(1 - 2 / (math.pi**2 * nu_c * 400), abs=3e-4)


def test_kernel_matches_brute_force_airy_convolved_with_gaussian():
    inst = GONGInstrument()
    axis, ref = brute_force_psf(inst)
    centre = axis.size // 2  # reference sampled every 0.1" over ±60"
    k = psf_kernel(0.5 * u.arcsec, inst, shape=121)  # ±30" every 0.5"
    profile_k = k[60, 30:91] / k[60, 60]  # ±15"
    profile_ref = ref[centre, centre - 150:centre + 151:5] / ref[centre, centre]
    assert np.max(np.abs(profile_k - profile_ref)) < 2e-3
    width_ref = fwhm(axis, ref[centre])
    assert width_ref == pytest.approx(6.2, abs=0.3)  # Airy 5.13" ⊕ seeing 3.6"
    fine = np.arange(-15, 15.001, 0.05)
    width = fwhm(fine, psf_profile(np.abs(fine) * u.arcsec, inst).value)
    assert width == pytest.approx(width_ref, rel=5e-3)


def test_kernel_unit_sum_default_extent_and_centre():
    k = psf_kernel(0.5 * u.arcsec)
    assert k.shape == (401, 401)  # reaches PSF_RADIUS = 100"
    assert k.sum() == pytest.approx(1, abs=1e-12)
    assert np.unravel_index(np.argmax(k), k.shape) == (200, 200)
    even = psf_kernel(1 * u.arcsec, shape=(20, 30))
    assert np.unravel_index(np.argmax(even), even.shape) == (10, 15)
    assert np.allclose(k, k[::-1, ::-1]) and np.allclose(k, k.T)


def test_point_source_gives_the_psf_with_expected_fwhm():
    scale = 0.5
    img = np.zeros((256, 256))
    img[128, 128] = 1.0
    out = convolve(img, psf_kernel(scale * u.arcsec), boundary="periodic")
    axis_fine, ref = brute_force_psf(GONGInstrument())
    expected = fwhm(axis_fine, ref[ref.shape[0] // 2])
    axis = (np.arange(256) - 128) * scale
    assert fwhm(axis, out[128]) == pytest.approx(expected, rel=0.02)
    assert fwhm(axis, out[:, 128]) == pytest.approx(expected, rel=0.02)
    assert out.sum() == pytest.approx(1, abs=1e-12)


def test_seeing_broadens_the_psf():
    widths = []
    for seeing in (0, 2, 4):
        inst = GONGInstrument(seeing_fwhm=seeing * u.arcsec)
        r = np.arange(-15, 15.001, 0.05)
        widths.append(fwhm(r, psf_profile(np.abs(r) * u.arcsec, inst).value))
    assert widths[0] == pytest.approx(1.029 * 0.676780e-6 / 0.028 / ARCSEC, rel=5e-3)  # Airy FWHM
    assert widths[0] < widths[1] < widths[2]


def test_kolmogorov_seeing_keeps_the_fwhm_and_has_heavier_wings():
    """r0 = 0.976 λ/FWHM gives the Kolmogorov long-exposure profile the FWHM asked for, with heavier wings."""
    r = np.arange(0, 60.0001, 0.01)
    big = {"aperture": 1 * u.m, "seeing_fwhm": 3.6 * u.arcsec}       # the Airy core 0.14": seeing alone
    kolmogorov = psf_profile(r * u.arcsec, GONGInstrument(seeing_profile="kolmogorov", **big)).value
    gaussian = psf_profile(r * u.arcsec, GONGInstrument(**big)).value
    both = np.concatenate([-r[:0:-1], r])
    for profile in (kolmogorov, gaussian):
        assert fwhm(both, np.concatenate([profile[:0:-1], profile])) == pytest.approx(3.6, rel=0.02)
        assert np.trapezoid(2 * np.pi * r * profile, r) == pytest.approx(1, abs=2e-3)

    def beyond(profile, radius):
        inside = r <= radius
        return 1 - np.trapezoid(2 * np.pi * r[inside] * profile[inside], r[inside])

    # Beyond two FWHM a Gaussian keeps 2**-16 of its light (here the 1 m Airy wings' 0.4 %);
    # Kolmogorov's r^(-11/3) wings keep percents.
    assert beyond(gaussian, 7.2) < 0.006 and beyond(kolmogorov, 7.2) > 0.03
    # GONG's own PSF: the same seeing FWHM moves light from the core to the wings.
    core = [psf_profile(r * u.arcsec, GONGInstrument(seeing_profile=shape)).value for shape in ("gaussian",
                                                                                               "kolmogorov")]
    assert beyond(core[1], 5.0) > beyond(core[0], 5.0) + 0.03
    with pytest.raises(ValueError, match="seeing_profile"):
        GONGInstrument(seeing_profile="moffat")
    # The products say which: a Kolmogorov run's header, not the default's.
    from gongsynth.chain import run_header
    from gongsynth.config import SimulationConfig
    assert "seeprof" not in run_header(SimulationConfig())
    kolmogorov = SimulationConfig(instrument=GONGInstrument(seeing_profile="kolmogorov"))
    assert run_header(kolmogorov)["seeprof"][0] == "kolmogorov"


# ----------------------------------------------------------- convolution
@pytest.mark.parametrize("boundary, mode", [("periodic", "wrap"), ("zero", "constant"),
                                            ("reflect", "reflect")])
@pytest.mark.parametrize("shape", [(7, 5), (6, 9)])
def test_convolve_matches_direct_convolution(boundary, mode, shape):
    rng = np.random.default_rng(3)
    img = rng.random((2, 40, 50))
    k = rng.random(shape)
    got = convolve(img, k, boundary=boundary)
    for plane, out in zip(img, got):
        ref = scipy.ndimage.convolve(plane, k / k.sum(), mode=mode)
        assert np.max(np.abs(out - ref)) < 1e-13


def test_convolve_keeps_unit_dtype_and_wraps_large_kernels():
    img = np.ones((3, 16, 16), dtype=np.float32) * u.G
    out = convolve(img, psf_kernel(0.5 * u.arcsec), boundary="periodic")  # 401² kernel > field
    assert out.unit == u.G and out.dtype == np.float32
    assert np.allclose(out.value, 1, atol=1e-6)


def test_flux_conservation_through_psf_and_pixelization():
    """Periodic scene on the default grid (exactly 5 samples per pixel): exact."""
    rng = np.random.default_rng(4)
    inst = GONGInstrument()
    scene = rng.gamma(2.0, size=(6, 160, 160))  # 32 × 32 GONG pixels
    h = 0.5
    out = observe(scene, h * u.arcsec, instrument=inst, boundary="periodic")
    before = scene.sum(axis=(1, 2)) * h**2
    after = out.sum(axis=(1, 2)) * 2.5**2
    assert np.max(np.abs(after / before - 1)) < 1e-12
    # The paper's grid (4096 samples over 860 pixels, here 76 over 16): bilinear
    # resampling leaks the scene's Fourier mode at the beat of the two grids
    # (here 4 cycles per field, amplitude ~1/76 of the mean for white noise)
    # times the hat's sinc² side lobe (~3e-3): ~3e-5.  The "area" method is exact.
    n, det = 76, 16
    h = det * 2.5 / n
    scene = convolve(rng.gamma(2.0, size=(n, n)), psf_kernel(h * u.arcsec))
    for method, tol in (("bilinear", 1e-4), ("area", 1e-12)):
        out = pixelize(scene, h * u.arcsec, periodic=True, method=method)
        assert abs(out.sum() * 2.5**2 / (scene.sum() * h**2) - 1) < tol


def test_bilinear_pixelization_of_a_linear_ramp_is_exact():
    # The field (80 samples of 0.5") resampled onto a 76-sample grid first.
    n, det = 76, 16
    h = det * 2.5 / n
    x = (np.arange(n) + 0.5) * h  # sample centres, arcsec
    ramp = np.broadcast_to(3.0 + 0.2 * x, (n, n))
    out = pixelize(ramp, h * u.arcsec)
    centres = (np.arange(det) + 0.5) * 2.5
    interior = slice(1, -1)  # the edge pixels hold the edge value (clamped)
    assert np.allclose(out[0, interior], 3.0 + 0.2 * centres[interior], rtol=0, atol=1e-12)


def test_pixelize_identity_and_binning():
    img = np.arange(100.0).reshape(10, 10)
    out = pixelize(img * u.K, 0.5 * u.arcsec)
    assert out.unit == u.K
    assert np.allclose(out.value, img.reshape(2, 5, 2, 5).mean(axis=(1, 3)))
    inst = GONGInstrument(supersampling=2)
    out = pixelize(img, 1.25 * u.arcsec, instrument=inst)
    assert np.allclose(out, img.reshape(5, 2, 5, 2).mean(axis=(1, 3)))


def test_observe_without_psf_is_plain_pixel_average():
    rng = np.random.default_rng(5)
    img = rng.random((20, 30))
    assert np.allclose(observe(img, 0.5 * u.arcsec, psf=False),
                       img.reshape(4, 5, 6, 5).mean(axis=(1, 3)))
    user = np.zeros((3, 3))
    user[1, 1] = 7.0  # a delta kernel: normalised to 1, changes nothing
    assert np.allclose(observe(img, 0.5 * u.arcsec, psf=user), observe(img, 0.5 * u.arcsec, psf=False))


# -------------------------------------------------------------- photometry
def test_photometric_factor_by_hand():
    h, c = 6.62607015e-27, 2.99792458e10  # erg s, cm/s
    photon = h * c / 676.78e-7  # erg
    want = 2.5**2 * 0.6 * (1 / 60) * 0.16 / photon
    got = photometric_factor().to_value(u.electron * u.arcsec**2 * u.cm**2 * u.s / u.erg)
    assert got == pytest.approx(want, rel=1e-9)


def test_quiet_sun_disk_centre_counts():
    """Counts from a flat continuum follow design §3.10 step by step."""
    from gongsynth.stages.filters import channel_responses
    from gongsynth.stages.scene.scene import radiance_at_earth

    continuum = 3.0e14 * u.Unit("erg / (s cm2 sr cm)")  # Neckel & Labs, design §3.10
    lam = np.linspace(676.78 - 3, 676.78 + 3, 60001) * u.nm
    integral = np.trapezoid(channel_responses(lam).value, lam.to_value(u.cm), axis=1) * u.cm
    radiance = radiance_at_earth(continuum * integral)  # (3,) erg / (s cm2 arcsec2)
    planes = np.broadcast_to(np.concatenate([radiance, radiance]).value[:, None, None], (6, 20, 20))
    scene = SimpleNamespace(data=planes * radiance.unit, pixel_scale=0.5 * u.arcsec, boundary="periodic")
    counts = expected_counts(scene)
    assert counts.unit == u.electron and counts.shape == (6, 4, 4)
    assert np.allclose(counts.value, counts.value[:, :1, :1])
    # The design's rough photometry: ~1.2e5 e- per frame per pixel (3630 ADU at gain 33).
    assert counts[0, 0, 0].value == pytest.approx(1.2e5, rel=0.1)


# -------------------------------------------------------------- bad input
@pytest.mark.parametrize("kernel, match", [
    (np.zeros((3, 3)), "sum must be positive"),
    (-np.ones((3, 3)), "sum must be positive"),
    (np.full((3, 3), np.nan), "non-finite"),
    (np.ones(5), "2-D"),
    (np.array([[1.0, -1.0]]), "sum must be positive"),
])
def test_bad_kernels_are_rejected(kernel, match):
    with pytest.raises(ValueError, match=match):
        normalize_kernel(kernel)
    with pytest.raises(ValueError, match=match):
        observe(np.ones((10, 10)), 0.5 * u.arcsec, psf=kernel)


def test_bad_arguments():
    with pytest.raises(u.UnitsError):
        normalize_kernel(np.ones((3, 3)) * u.m)
    with pytest.raises(ValueError, match="boundary"):
        convolve(np.ones((4, 4)), np.ones((3, 3)), boundary="mirror")
    with pytest.raises(ValueError, match="whole number of detector pixels"):
        pixelize(np.ones((11, 10)), 0.5 * u.arcsec)
    with pytest.raises(ValueError, match="method"):
        pixelize(np.ones((10, 10)), 0.5 * u.arcsec, method="cubic")
    with pytest.raises(u.UnitsError):
        pixelize(np.ones((10, 10)), 0.5 * u.km)
    with pytest.raises(ValueError, match="positive"):
        psf_kernel(-1 * u.arcsec)
    with pytest.raises(ValueError, match="non-finite"):
        observe(np.full((10, 10), np.nan), 0.5 * u.arcsec)
    with pytest.raises(u.UnitsError):
        expected_counts(SimpleNamespace(data=np.ones((6, 5, 5)) * u.G, pixel_scale=0.5 * u.arcsec,
                                        boundary="periodic"))


def test_module_exports():
    for name in optics.__all__:
        assert hasattr(optics, name)


# ------------------------------------------------- band-limited operator
def reference_observe(stack, kernel, boundary, inst=None):
    """Today's (the paper's) order, kept as the reference: FFT convolution, then bilinear + binning."""
    conv = convolve(stack, kernel, boundary=boundary)
    return pixelize(conv, 0.5 * u.arcsec, instrument=inst, periodic=boundary == "periodic")


@pytest.mark.parametrize("boundary", ["periodic", "zero", "reflect"])
@pytest.mark.parametrize("shape", [(2, 60, 75), (1, 505, 510)])
def test_band_limited_operator_equals_convolution_then_binning(boundary, shape):
    """One transform per plane, folded onto the detector rows: the same numbers as the reference."""
    rng = np.random.default_rng(11)
    stack = rng.gamma(2.0, size=shape)
    kernel = psf_kernel(0.5 * u.arcsec)  # 401²: wider than the small field, narrower than the large
    got = observe(stack, 0.5 * u.arcsec, boundary=boundary, band_limited=False)
    want = reference_observe(stack, kernel, boundary)
    assert got.shape == want.shape == shape[:1] + (shape[1] // 5, shape[2] // 5)
    assert np.max(np.abs(got - want)) < 1e-13 * np.max(want)
    odd = rng.random((5, 8))  # an even, asymmetric user kernel
    got = observe(stack, 0.5 * u.arcsec, psf=odd, boundary=boundary)
    assert np.max(np.abs(got - reference_observe(stack, odd, boundary))) < 1e-13 * np.max(want)


def _left_out_bound(padded, kernel, factor):
    """
    Bound on what the band-limited operator leaves out: (1/N) Σ |P̂ K̂ B̂| over the
    frequencies beyond the detector's Nyquist (|f| ≥ M/2 on either axis), for a
    plane ``padded`` on the circular transform grid.
    """
    fy, fx = padded.shape
    spectrum = np.abs(np.fft.fft2(padded))
    ky, kx = kernel.shape
    wrapped = np.zeros((fy, fx))
    np.add.at(wrapped, np.ix_((np.arange(ky) - ky // 2) % fy, (np.arange(kx) - kx // 2) % fx), kernel)
    transfer = np.abs(np.fft.fft2(wrapped))
    for axis, n in ((0, fy), (1, fx)):
        f = np.fft.fftfreq(n, 1 / n)
        box = np.abs(np.exp(2j * np.pi * np.outer(f, np.arange(factor)) / n).mean(axis=1))
        transfer *= box[:, None] if axis == 0 else box[None, :]
    fyy, fxx = np.meshgrid(np.fft.fftfreq(fy, 1 / fy), np.fft.fftfreq(fx, 1 / fx), indexing="ij")
    left_out = (np.abs(fyy) >= fy / factor / 2) | (np.abs(fxx) >= fx / factor / 2)
    return float((spectrum * transfer)[left_out].sum() / (fy * fx))


@pytest.mark.parametrize("boundary", ["periodic", "reflect"])
@pytest.mark.parametrize("smooth", [False, True])
def test_band_limited_operator_leaves_out_only_what_lies_beyond_the_detector_nyquist(boundary, smooth):
    """
    The band-limited operator differs from the reference (convolution, then binning)
    by at most the sum of |transfer × spectrum| beyond the detector's Nyquist
    frequency, the part it leaves out, and agrees with the exact operator at it.
    """
    from gongsynth.stages.imagers import BandLimitedImager, ExactImager

    rng = np.random.default_rng(21)
    plane = rng.gamma(2.0, size=(300, 350))  # white: the worst case for aliases
    if smooth:  # granulation-like: most power at scales of a few arcsec
        plane = 1 + 0.1 * scipy.ndimage.gaussian_filter(rng.normal(size=plane.shape), 4, mode="wrap")
    kernel = psf_kernel(0.5 * u.arcsec)
    got = observe(plane, 0.5 * u.arcsec, boundary=boundary)
    want = reference_observe(plane, kernel, boundary)
    exact = ExactImager(plane.shape, kernel, boundary, 5, np.float64, 1)(plane)
    imager = BandLimitedImager(plane.shape, kernel, boundary, 5, np.float64, 1)
    # observe is this operator: the same bits with current numpy/scipy; with the oldest supported
    # (numpy 2.0, scipy 1.13) two constructions of it differ by about one ulp (8.9e-16 measured).
    assert np.max(np.abs(got - imager(plane))) <= 1e-14 * np.max(want)
    assert np.max(np.abs(exact - want)) < 1e-13 * np.max(want)
    if boundary == "periodic":
        padded = plane
    else:
        padded = np.zeros(imager.fshape)
        mirrored = np.pad(plane, ((200, 200), (200, 200)), mode="symmetric")
        padded[:mirrored.shape[0], :mirrored.shape[1]] = mirrored
    bound = _left_out_bound(padded, kernel, 5)
    diff = np.max(np.abs(got - want))
    assert 0 < diff <= bound + 1e-13 * np.max(want)
    # Photon noise of a 10-minute magnetogram pixel is ~3e-5 of the signal: far above even white input's.
    assert bound < 1e-4 * np.max(want)


def test_user_kernels_get_the_exact_operator():
    """A user kernel need not be band limited: a delta kernel leaves the plain pixel average."""
    rng = np.random.default_rng(22)
    img = rng.random((50, 60))
    delta = np.zeros((3, 3))
    delta[1, 1] = 1.0
    assert np.allclose(observe(img, 0.5 * u.arcsec, psf=delta), observe(img, 0.5 * u.arcsec, psf=False),
                       rtol=1e-12, atol=0)
    # An aperture whose cut-off lies beyond the detector's Nyquist frequency: exact operator too.
    wide = GONGInstrument(aperture=5.6 * u.cm)
    got = observe(img, 0.5 * u.arcsec, instrument=wide)
    want = reference_observe(img, psf_kernel(0.5 * u.arcsec, wide), "periodic", wide)
    assert np.max(np.abs(got - want)) < 1e-13 * np.max(want)


def test_float32_optics_leave_b_and_v_unchanged():
    """
    float32 planes are transformed in float32; B and v from them stay within 0.01 G and 0.01 m/s.

    The reference is the float64 convolution and binning of the same scene
    (a sunspot tile, 1 kG-class umbra, at latitude 0); the 1-minute noise is a few G.
    """
    from gongsynth.chain import build_chain
    from gongsynth.config import SimulationConfig
    from gongsynth.stages.reduction import reduce
    cfg = SimulationConfig(seed=3, sun="milne-eddington", detector_shape=120, photosphere_shape=(256, 256),
                           photosphere_pixel_size=384 * u.km)
    state = build_chain(cfg).run(until="scene", progress=False)
    light, truth = state["light"], state["truth_scene"]
    assert light.data.dtype == np.float32 and truth.data.dtype == np.float32
    inst = cfg.instrument
    kernel = psf_kernel(light.pixel_scale, inst)
    counts, truth_map, truth_psf = optics.image_scene(light, truth, inst)
    want = reference_observe(light.data.value.astype(np.float64), kernel, light.boundary, inst)
    want = (want * photometric_factor(inst).value)
    assert np.max(np.abs(counts.value - want)) < 1e-6 * want.max()
    got, ref = reduce(counts.value), reduce(want)
    d_b = np.abs(got.magnetogram - ref.magnetogram).to_value(u.G)
    d_v = np.abs(got.doppler - ref.doppler).to_value(u.m / u.s)
    assert np.max(np.abs(ref.magnetogram.to_value(u.G))) > 1000  # the spot is in the field
    assert d_b.max() < 0.01 and d_v.max() < 0.01
    b64 = truth.data.value.astype(np.float64)
    assert np.max(np.abs(truth_psf.value - reference_observe(b64, kernel, truth.boundary, inst))) < 0.01
    assert np.max(np.abs(truth_map.value - pixelize(b64, light.pixel_scale, instrument=inst))) < 0.01


def test_image_scene_matches_expected_counts_and_observe():
    rng = np.random.default_rng(12)
    radiance = rng.gamma(2.0, size=(6, 100, 100)) * 3e-5 * u.erg / (u.s * u.cm**2 * u.arcsec**2)
    light = SimpleNamespace(data=radiance, pixel_scale=0.5 * u.arcsec, boundary="reflect")
    truth = SimpleNamespace(data=rng.normal(size=(100, 100)) * u.G, pixel_scale=0.5 * u.arcsec,
                            boundary="reflect")
    counts, b, b_psf = optics.image_scene(light, truth)
    assert np.allclose(counts, expected_counts(light), rtol=1e-13, atol=0)
    assert np.allclose(b, observe(truth.data, 0.5 * u.arcsec, psf=False, boundary="reflect"), rtol=0,
                       atol=1e-13 * u.G)
    assert np.allclose(b_psf, observe(truth.data, 0.5 * u.arcsec, boundary="reflect"), rtol=0,
                       atol=1e-13 * u.G)
    counts, b, b_psf = optics.image_scene(light, truth, psf=False)
    assert np.array_equal(b, b_psf)
    assert optics.image_scene(light)[1:] == (None, None)
