"""Tests of gongsynth.stages.channels: Mueller matrices and the filter-first collapse."""
import astropy.units as u
import numpy as np
import pytest

from gongsynth import GONGInstrument, instruments
from gongsynth.geometry import Pointing, viewing_geometry
from gongsynth.stages import channels as polarimetry
from gongsynth.stages.channels import (
    CHANNEL_UNIT,
    analyser_coefficients,
    channel_images,
    polarized_spectra,
)
from gongsynth.stages.filters import channel_responses, channel_weights
from gongsynth.stages.optics import observe
from gongsynth.stages.scene.scene import radiance_at_earth
from gongsynth.stages.scene.tiled import tile, tiled_scenes
from gongsynth.sun.photosphere import DeferredStokes, Photosphere, synthesize
from gongsynth.sun.stokes import RADIANCE_UNIT, StokesCube

LAM = np.linspace(676.73, 676.83, 51) * u.nm


def random_photosphere(shape, seed, pixel_size=400 * u.km):
    rng = np.random.default_rng(seed)
    return Photosphere(rng.uniform(0, 2500, shape) * u.G, rng.uniform(0, 180, shape) * u.deg,
                       rng.uniform(-180, 180, shape) * u.deg, rng.normal(0, 1.5, shape) * u.km / u.s,
                       rng.normal(0, 1.5, shape) * u.km / u.s, rng.normal(0, 1.5, shape) * u.km / u.s,
                       rng.uniform(0.3, 1.2, shape), pixel_size, periodic=True)


def random_cube(shape=(3, 4), seed=0):
    rng = np.random.default_rng(seed)
    arrays = [rng.normal(0, 1e13, shape + (LAM.size,)) for _ in range(4)]
    arrays[0] = np.abs(arrays[0]) + 3e14
    return StokesCube(*(a.astype(np.float32) * RADIANCE_UNIT for a in arrays), LAM, 96 * u.km)


def test_ideal_analyser_is_i_plus_and_minus_v():
    assert np.array_equal(analyser_coefficients(), [[1, 0, 0, 1], [1, 0, 0, -1]])


def test_flat_spectrum_gives_the_integrated_channel_response():
    inst = GONGInstrument()
    level = 3.0e14 * RADIANCE_UNIT
    one = np.ones((2, 2, LAM.size), dtype=np.float32)
    cube = StokesCube(level * one, 0 * level * one, 0 * level * one, 0.1 * level * one, LAM, 96 * u.km)
    planes = channel_images(cube, instrument=inst)
    assert planes.unit == CHANNEL_UNIT and planes.shape == (6, 2, 2)
    # Independent: the responses integrated on a fine grid over λ0 ± 3 nm.
    fine = np.linspace(676.78 - 3, 676.78 + 3, 60001) * u.nm
    integral = np.trapezoid(channel_responses(fine, inst).value, fine.to_value(u.cm), axis=1)
    want = np.concatenate([1.1 * integral, 0.9 * integral]) * level.value
    assert np.allclose(planes[:, 0, 0].value, want, rtol=1e-4)


def test_channel_images_is_the_weighted_sum_of_the_polarised_spectra():
    cube = random_cube()
    weights = channel_weights(LAM).to_value(u.cm)
    spectra = polarized_spectra(cube).to_value(RADIANCE_UNIT)
    want = np.einsum("cl,pyxl->pcyx", weights, spectra).reshape(6, 3, 4)
    got = channel_images(cube).to_value(CHANNEL_UNIT)
    assert np.allclose(got, want, rtol=1e-12, atol=0)
    # I+V and I-V from the cube's own arrays.
    i, v = cube.I.value.astype(float), cube.V.value.astype(float)
    assert np.allclose(spectra[0], i + v) and np.allclose(spectra[1], i - v)


def test_general_mueller_global_per_wavelength_and_per_pixel_agree():
    cube = random_cube(seed=1)
    rng = np.random.default_rng(2)
    m = np.eye(4) + 0.1 * rng.normal(size=(4, 4))
    ref = channel_images(cube, mueller=m).value
    per_wl = channel_images(cube, mueller=np.broadcast_to(m, (LAM.size, 4, 4))).value
    per_px = channel_images(cube, mueller=np.broadcast_to(m, (3, 4, 4, 4))).value
    assert np.allclose(per_wl, ref, rtol=1e-12) and np.allclose(per_px, ref, rtol=1e-12)
    # By hand: plane p, channel c = W_c · (row0 + s_p row3) · S.
    weights = channel_weights(LAM).to_value(u.cm)
    stokes = np.stack([cube.I.value, cube.Q.value, cube.U.value, cube.V.value]).astype(float)
    for p, sign in enumerate((1, -1)):
        row = m[0] + sign * m[3]
        spectrum = np.tensordot(row, stokes, axes=1)
        assert np.allclose(ref[3 * p:3 * p + 3], np.einsum("cl,yxl->cyx", weights, spectrum))


def test_crosstalk_mueller_moves_q_into_the_circular_signal():
    cube = random_cube(seed=3)
    m = np.eye(4)
    m[3, 1] = 0.05  # 5 % of Q leaks into V
    diff = channel_images(cube, mueller=m).value - channel_images(cube).value
    q = channel_images(StokesCube(cube.Q * 0 + cube.I, cube.Q * 0, cube.U * 0, cube.Q, LAM, 96 * u.km)).value
    i_only = channel_images(StokesCube(cube.I, cube.Q * 0, cube.U * 0, cube.V * 0, LAM, 96 * u.km)).value
    q_integral = q[:3] - i_only[:3]  # channel integrals of Q
    assert np.allclose(diff[:3], 0.05 * q_integral, rtol=1e-5)
    assert np.allclose(diff[3:], -0.05 * q_integral, rtol=1e-5)


def test_per_pixel_mueller_acts_pixel_by_pixel():
    cube = random_cube(seed=4)
    m = np.broadcast_to(np.eye(4), (3, 4, 4, 4)).copy()
    m[1, 2] *= 2.0  # one pixel twice as bright
    got = channel_images(cube, mueller=m).value
    ref = channel_images(cube).value
    assert np.allclose(got[:, 1, 2], 2 * ref[:, 1, 2])
    mask = np.ones((3, 4), bool)
    mask[1, 2] = False
    assert np.array_equal(got[:, mask], ref[:, mask])


@pytest.mark.parametrize("name", instruments.names())
def test_filter_first_equals_the_papers_literal_order(name):
    """Mueller → PSF → pixelize → filter, per wavelength, on a small tiled scene, for every instrument."""
    inst = instruments.get(name)
    latitude = 60 * u.deg
    mu, azimuth = viewing_geometry(latitude)
    cube = synthesize(random_photosphere((16, 16), seed=5), mu=mu, los_azimuth=azimuth, instrument=inst)
    rng = np.random.default_rng(6)
    mueller = np.eye(4) + 0.02 * rng.normal(size=(cube.shape[2], 4, 4))  # chromatic cross-talk
    geometry = dict(pointing=Pointing(latitude), resolutions=(1, 2, 4, 8), detector_shape=12, instrument=inst)

    # Filter first (gongsynth's order).
    planes = channel_images(cube, mueller=mueller, instrument=inst)
    light, truth = tiled_scenes(planes, cube.blos, cube.pixel_size, **geometry)
    # The scene stores float32 (to float32 rounding the float64 tiling); the
    # comparison of the two orders is made in float64 throughout.
    sky64 = radiance_at_earth(tile(planes, cube.pixel_size, **geometry))
    assert light.data.dtype == np.float32
    assert np.allclose(light.data.value, sky64.value, rtol=1e-6, atol=0)
    fast = observe(sky64, light.pixel_scale, instrument=inst, boundary=light.boundary)

    # The paper's order, wavelength by wavelength.
    weights = channel_weights(cube.wavelength, inst).to_value(u.cm)
    spectra = polarized_spectra(cube, mueller=mueller)  # (2, ny, nx, nλ): I+V, I-V
    literal = np.zeros((len(inst.analysers),) + fast.shape[1:])
    for j in range(cube.shape[2]):
        sky = radiance_at_earth(tile(spectra[..., j], cube.pixel_size, **geometry))
        seen = observe(sky, light.pixel_scale, instrument=inst, boundary=light.boundary)
        seen = seen.to_value(u.erg / (u.s * u.cm**3 * u.arcsec**2))
        for k, (filtergram, sign) in enumerate(inst.analysers):
            literal[k] += weights[filtergram, j, None, None] * seen[0 if sign > 0 else 1]
    fast = fast.to_value(u.erg / (u.s * u.cm**2 * u.arcsec**2))
    assert np.max(np.abs(fast - literal)) < 1e-12 * np.max(np.abs(literal))


def _mueller(kind, shape):
    """A non-trivial Mueller matrix of each kind (global, per wavelength, per pixel)."""
    m = np.eye(4)
    m[0, 3], m[3, 1], m[3, 2] = 0.002, 0.01, -0.004
    if kind == "global":
        return m
    if kind == "spectral":
        out = np.broadcast_to(m, (LAM.size, 4, 4)).copy()
        out[:, 3, 2] = np.linspace(-0.01, 0.01, LAM.size)
        return out
    out = np.broadcast_to(m, shape + (4, 4)).copy()
    out[..., 3, 1] = np.linspace(0, 0.02, shape[0] * shape[1]).reshape(shape)
    return out


@pytest.mark.parametrize("kind", [None, "global", "spectral", "spatial"])
def test_deferred_synthesis_gives_the_whole_cubes_channel_images(kind):
    """
    Synthesis contracted with the channel weights column by column (never stored)
    equals the channel images of the stored float32 cube to that cube's rounding:
    |difference| <= 2^-24 Σ_j |W_cj| Σ_s |c_ps| |S_s(λ_j)| (+ float64 round-off).
    """
    shape = (24, 20)
    photosphere = random_photosphere(shape, seed=31)
    mueller = None if kind is None else _mueller(kind, shape)
    geometry = dict(mu=0.7, los_azimuth=-60 * u.deg)
    deferred = DeferredStokes(photosphere, **geometry)
    got = channel_images(deferred, mueller=mueller).value
    cube = synthesize(photosphere, **geometry)
    want = channel_images(cube, mueller=mueller).value
    assert deferred._cube is None  # the cube was never made
    stokes = np.abs(np.stack([getattr(cube, n).value for n in "IQUV"]).astype(np.float64))  # (4, ny, nx, nλ)
    coeff = np.abs(analyser_coefficients(mueller if mueller is not None else np.eye(4)))
    if coeff.ndim == 2:
        coeff = np.broadcast_to(coeff, (LAM.size,) + coeff.shape)
    w = np.abs(channel_weights(LAM).to_value(u.cm))
    if kind == "spatial":
        bound = np.einsum("yxps,syxl,cl->pcyx", coeff, stokes, w)
    else:
        bound = np.einsum("lps,syxl,cl->pcyx", coeff, stokes, w)
    bound = bound.reshape(want.shape) * 2.0**-24 + 1e-12 * np.abs(want).max()
    assert np.all(np.abs(got - want) <= bound)
    assert np.array_equal(deferred.blos, cube.blos)


def test_contraction_kernel_is_independent_of_threads():
    import numba

    photosphere = random_photosphere((40, 33), seed=32)
    results = []
    previous = numba.get_num_threads()
    try:
        for threads in (1, numba.config.NUMBA_NUM_THREADS):
            numba.set_num_threads(threads)
            results.append(channel_images(DeferredStokes(photosphere, mu=0.8)).value)
    finally:
        numba.set_num_threads(previous)
    assert np.array_equal(results[0], results[1])


@pytest.mark.parametrize("mueller, error, match", [
    (np.eye(3), ValueError, "shape"),
    (np.full((4, 4), np.nan), ValueError, "non-finite"),
    (np.ones((5, 4, 4)), ValueError, "per-wavelength"),
    (np.ones((2, 2, 4, 4)), ValueError, "per-pixel"),
    (np.eye(4) * u.m, u.UnitsError, "dimensionless"),
])
def test_bad_mueller_matrices(mueller, error, match):
    with pytest.raises(error, match=match):
        channel_images(random_cube(), mueller=mueller)


def test_module_exports():
    for name in polarimetry.__all__:
        assert hasattr(polarimetry, name)
