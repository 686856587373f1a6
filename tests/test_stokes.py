"""Tests of gongsynth.sun.stokes (StokesCube) and gongsynth.sun.stokes_files (FITS and RH 1.5D files)."""
import astropy.constants as const
import astropy.units as u
import h5py
import numpy as np
import pytest
from astropy.io import fits

from gongsynth.sun.stokes import RADIANCE_UNIT, StokesCube

LAM = np.linspace(676.73, 676.83, 51) * u.nm
RH_UNIT = u.Unit("J / (s m2 Hz sr)")


def _arrays(shape=(6, 8, 51), seed=0, dtype=np.float32):
    rng = np.random.default_rng(seed)
    I = (3e14 * (1 + 0.1 * rng.random(shape))).astype(dtype) * RADIANCE_UNIT
    Q, U, V = ((1e12 * rng.standard_normal(shape)).astype(dtype) * RADIANCE_UNIT for _ in range(3))
    return I, Q, U, V


def _cube(shape=(6, 8, 51), **kwargs):
    lam = np.linspace(676.73, 676.83, shape[-1]) * u.nm
    return StokesCube(*_arrays(shape), lam, 96 * u.km, **kwargs)


# ------------------------------------------------------------------ construction
def test_float32_input_is_not_copied():
    I, Q, U, V = _arrays()
    cube = StokesCube(I, Q, U, V, LAM, 96 * u.km)
    for name, arr in zip("IQUV", (I, Q, U, V)):
        assert np.shares_memory(getattr(cube, name), arr)
        assert getattr(cube, name).dtype == np.float32
    assert cube.shape == (6, 8, 51)
    assert cube.nbytes == 4 * 6 * 8 * 51 * 4


def test_copy_flag_and_float64_input_are_converted():
    I, Q, U, V = _arrays(dtype=np.float64)
    cube = StokesCube(I, Q, U, V, LAM, 96 * u.km)
    assert cube.I.dtype == np.float32
    assert not np.shares_memory(cube.I, I)
    np.testing.assert_allclose(cube.I.value, I.value, rtol=1e-7)
    I32 = I.astype(np.float32)
    copied = StokesCube(I32, I32, I32, I32, LAM, 96 * u.km, copy=True)
    assert not np.shares_memory(copied.I, I32)


def test_per_frequency_units_are_converted_with_c_over_lambda_squared():
    shape = (2, 3, 51)
    inu = np.full(shape, 4.6e-8, dtype=np.float32) * RH_UNIT
    zero = np.zeros(shape, dtype=np.float32) * RH_UNIT
    cube = StokesCube(inu, zero, zero, inu * 0.01, LAM, 48 * u.km)
    expected = (4.6e-8 * RH_UNIT * const.c / LAM**2).to_value(RADIANCE_UNIT)
    np.testing.assert_allclose(cube.I.value[1, 2], expected, rtol=1e-6)
    np.testing.assert_allclose(cube.V.value[0, 0], 0.01 * expected, rtol=1e-6)
    assert cube.I.unit == RADIANCE_UNIT
    # ~3e14 erg/s/cm2/sr/cm: the disk-centre continuum in RH's unit
    assert 2.9e14 < cube.I.value.mean() < 3.1e14


def test_wavelength_stored_in_nm_and_mu_viewing_angle():
    cube = StokesCube(*_arrays(), LAM.to(u.AA), 0.096 * u.Mm, mu=0.5)
    assert cube.wavelength.unit == u.nm
    np.testing.assert_allclose(cube.wavelength.value, LAM.value)
    assert cube.pixel_size == 96 * u.km
    assert cube.viewing_angle.to_value(u.deg) == pytest.approx(60.0)
    assert "mu=0.5" in repr(cube)


def test_from_array_is_a_view_of_a_stacked_array():
    data = np.stack([a.value for a in _arrays()])
    cube = StokesCube.from_array(data, LAM, 96 * u.km)
    assert np.shares_memory(cube.V, data)
    np.testing.assert_array_equal(cube.Q.value, data[1])
    with pytest.raises(ValueError, match=r"data must have shape \(4, ny, nx, nwavelength\)"):
        StokesCube.from_array(data[:3], LAM, 96 * u.km)


# --------------------------------------------------------------------- bad input
def test_nan_in_any_stokes_parameter_is_rejected():
    I, Q, U, V = _arrays()
    U = U.copy()
    U[2, 3, 10] = np.nan
    with pytest.raises(ValueError, match=r"U contains 1 non-finite"):
        StokesCube(I, Q, U, V, LAM, 96 * u.km)
    I = I.copy()
    I[0, 0, 0] = np.inf
    with pytest.raises(ValueError, match=r"I contains 1 non-finite"):
        StokesCube(I, Q, Q, V, LAM, 96 * u.km)


def test_negative_intensity_is_rejected_but_negative_v_is_fine():
    I, Q, U, V = _arrays()
    StokesCube(I, Q, U, -abs(V), LAM, 96 * u.km)
    I = I.copy()
    I[1, 1, 1] = -1.0 * RADIANCE_UNIT
    with pytest.raises(ValueError, match=r"I \(Stokes I\) must be non-negative"):
        StokesCube(I, Q, U, V, LAM, 96 * u.km)


@pytest.mark.parametrize("unit", ["G", "erg / (s cm2 cm)", "W / m2"])
def test_wrong_radiance_units_are_rejected(unit):
    I, Q, U, V = _arrays()
    with pytest.raises(u.UnitsError, match=r"I must have units convertible to"):
        StokesCube(I.value * u.Unit(unit), Q, U, V, LAM, 96 * u.km)


def test_plain_arrays_and_bad_wavelengths_are_rejected():
    I, Q, U, V = _arrays()
    with pytest.raises(TypeError, match=r"Q must be an astropy Quantity"):
        StokesCube(I, Q.value, U, V, LAM, 96 * u.km)
    bad = LAM.copy()
    bad[[20, 21]] = bad[[21, 20]]
    with pytest.raises(ValueError, match=r"wavelength must be strictly increasing; wavelength\[21\]"):
        StokesCube(I, Q, U, V, bad, 96 * u.km)
    with pytest.raises(u.UnitsError, match="wavelength"):
        StokesCube(I, Q, U, V, LAM.value * u.s, 96 * u.km)
    with pytest.raises(ValueError, match=r"I has 51 wavelength points but wavelength has 50"):
        StokesCube(I, Q, U, V, LAM[:50], 96 * u.km)


def test_shape_pixel_mu_and_blos_errors_name_the_argument():
    I, Q, U, V = _arrays()
    with pytest.raises(ValueError, match=r"V has shape \(6, 7, 51\) but I has shape \(6, 8, 51\)"):
        StokesCube(I, Q, U, V[:, :7], LAM, 96 * u.km)
    with pytest.raises(ValueError, match=r"I must be a 3-D array"):
        StokesCube(I[0], Q[0], U[0], V[0], LAM, 96 * u.km)
    with pytest.raises(ValueError, match="pixel_size must be a positive"):
        StokesCube(I, Q, U, V, LAM, -96 * u.km)
    with pytest.raises(u.UnitsError, match="pixel_size"):
        StokesCube(I, Q, U, V, LAM, 96 * u.s)
    with pytest.raises(ValueError, match=r"mu must be in \(0, 1\]"):
        StokesCube(I, Q, U, V, LAM, 96 * u.km, mu=0.0)
    with pytest.raises(ValueError, match=r"mu must be a scalar or have shape \(ny, nx\)"):
        StokesCube(I, Q, U, V, LAM, 96 * u.km, mu=np.ones((3, 3)))
    with pytest.raises(ValueError, match=r"blos must have shape"):
        StokesCube(I, Q, U, V, LAM, 96 * u.km, blos=np.zeros((6, 7)) * u.G)
    with pytest.raises(u.UnitsError, match="blos"):
        StokesCube(I, Q, U, V, LAM, 96 * u.km, blos=np.zeros((6, 8)) * u.km)


# ------------------------------------------------------------------ slicing, rebin
def test_slicing_returns_views_with_matching_mu_and_blos():
    mu = np.linspace(0.2, 1.0, 48).reshape(6, 8)
    blos = np.arange(48, dtype=np.float32).reshape(6, 8) * u.G
    cube = _cube(mu=mu, blos=blos)
    sub = cube[1:4, 2:8:2]
    assert sub.shape == (3, 3, 51)
    assert np.shares_memory(sub.I, cube.I)
    np.testing.assert_array_equal(sub.V.value, cube.V.value[1:4, 2:8:2])
    np.testing.assert_array_equal(sub.mu, mu[1:4, 2:8:2])
    np.testing.assert_array_equal(sub.blos.value, blos.value[1:4, 2:8:2])
    one = cube[3, -1]
    assert one.shape == (1, 1, 51)
    np.testing.assert_array_equal(one.I.value[0, 0], cube.I.value[3, 7])
    window = cube[:, :, 10:20]
    np.testing.assert_array_equal(window.wavelength, cube.wavelength[10:20])
    with pytest.raises(TypeError, match="int or a slice"):
        cube[[0, 1]]
    with pytest.raises(ValueError, match="positive step"):
        cube[:, :, ::-1]
    with pytest.raises(IndexError, match="empty"):
        cube[10:]


def test_rebin_is_the_block_average_of_spectra_and_blos():
    blos = np.random.default_rng(3).normal(0, 100, (6, 8)).astype(np.float32) * u.G
    cube = _cube(blos=blos, meta={"source": "test"})
    binned = cube.rebin(2)
    assert binned.shape == (3, 4, 51)
    assert binned.pixel_size == 192 * u.km
    expected = cube.V.value.astype(np.float64).reshape(3, 2, 4, 2, 51).mean(axis=(1, 3))
    np.testing.assert_allclose(binned.V.value, expected, rtol=1e-6, atol=1e-3)
    np.testing.assert_allclose(binned.blos.value, blos.value.reshape(3, 2, 4, 2).mean(axis=(1, 3)),
                               rtol=1e-6)
    # flux is conserved: mean of the map is unchanged
    assert binned.blos.value.mean() == pytest.approx(blos.value.mean(), rel=1e-5)
    assert binned.meta == {"source": "test", "rebin_factor": 2}
    assert _cube((8, 8, 5)).rebin(2).rebin(2).meta["rebin_factor"] == 4
    with pytest.raises(ValueError, match=r"factor 4 must divide"):
        cube.rebin(4)
    with pytest.raises(ValueError, match="positive int"):
        cube.rebin(1.5)


def test_rebin_averages_per_column_mu():
    mu = np.linspace(0.2, 1.0, 48).reshape(6, 8)
    binned = _cube(mu=mu).rebin(2)
    np.testing.assert_allclose(binned.mu, mu.reshape(3, 2, 4, 2).mean(axis=(1, 3)))


# ---------------------------------------------------------------------------- FITS
def test_fits_round_trip_is_exact(tmp_path):
    mu = np.linspace(0.2, 1.0, 48).reshape(6, 8)
    blos = np.random.default_rng(3).normal(0, 100, (6, 8)).astype(np.float32) * u.G
    lam = np.sort(np.random.default_rng(1).uniform(676.7, 676.9, 51)) * u.nm   # irregular grid
    cube = StokesCube(*_arrays(), lam, 96 * u.km, mu=mu, blos=blos,
                      meta={"source": "unit test", "seed": 7, "angles": [0, 60]})
    path = tmp_path / "cube.fits"
    cube.to_fits(path)
    back = StokesCube.from_fits(path)
    for name in "IQUV":
        np.testing.assert_array_equal(getattr(back, name).value, getattr(cube, name).value)
        assert getattr(back, name).dtype == np.float32
    np.testing.assert_array_equal(back.wavelength.value, lam.value)
    np.testing.assert_array_equal(back.mu, mu)
    np.testing.assert_array_equal(back.blos.value, blos.value)
    assert back.pixel_size == cube.pixel_size
    assert back.meta == cube.meta
    with fits.open(path) as hdul:
        assert hdul[0].header["ORIGIN"] == "gongsynth"
        assert "DTYPE" not in hdul[0].header


def test_fits_scalar_mu_without_blos(tmp_path):
    cube = _cube(mu=0.5)
    cube.to_fits(tmp_path / "c.fits")
    back = StokesCube.from_fits(tmp_path / "c.fits")
    assert back.mu == 0.5 and back.blos is None


def test_fits_refuses_to_overwrite(tmp_path):
    cube = _cube()
    path = tmp_path / "cube.fits"
    cube.to_fits(path)
    with pytest.raises(FileExistsError, match="overwrite"):
        cube.to_fits(path)
    cube[:2].to_fits(path, overwrite=True)
    assert StokesCube.from_fits(path).shape == (2, 8, 51)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cube.fits"]   # no temp files left


def test_malformed_fits_files_raise_clear_errors(tmp_path):
    junk = tmp_path / "junk.fits"
    junk.write_bytes(b"this is not a FITS file" * 200)
    with pytest.raises(ValueError, match="not a readable FITS file"):
        StokesCube.from_fits(junk)
    other = tmp_path / "other.fits"
    fits.PrimaryHDU(np.zeros((3, 3))).writeto(other)
    with pytest.raises(ValueError, match="not a gongsynth Stokes cube"):
        StokesCube.from_fits(other)
    good = tmp_path / "good.fits"
    _cube().to_fits(good)
    with fits.open(good) as hdul:
        del hdul["U"]
        hdul.writeto(tmp_path / "missing.fits")
    with pytest.raises(ValueError, match=r"missing extension\(s\) \['U'\]"):
        StokesCube.from_fits(tmp_path / "missing.fits")
    with pytest.raises(FileNotFoundError):
        StokesCube.from_fits(tmp_path / "nope.fits")


# ------------------------------------------------------------------------ RH 1.5D
def _write_rh(path, nx=5, ny=4, lam=None, stokes=True, indata_dx=None):
    lam = np.linspace(676.70, 676.86, 81) if lam is None else lam
    rng = np.random.default_rng(11)
    inten = (4.6e-8 * (1 + 0.1 * rng.random((nx, ny, lam.size)))).astype(np.float32)
    with h5py.File(path, "w") as f:
        f["wavelength"] = lam
        f["intensity"] = inten
        if stokes:
            for k, s in (("stokes_Q", 1e-3), ("stokes_U", -2e-3), ("stokes_V", 3e-2)):
                f[k] = (s * inten).astype(np.float32)
        f.attrs["atmosID"] = b"muram test"
        f.attrs["nx"] = nx
        f.attrs["ny"] = ny
    if indata_dx is not None:
        with h5py.File(path.with_name("output_indata.hdf5"), "w") as f:
            f["atmos/x"] = np.arange(nx) * indata_dx
    return lam, inten


def test_rh15d_reader_transposes_converts_and_selects_wavelengths(tmp_path):
    path = tmp_path / "output_ray.hdf5"
    lam, inten = _write_rh(path, indata_dx=48e3)
    cube = StokesCube.from_rh15d(path, mu=0.5, wavelength_range=[676.73, 676.83] * u.nm)
    keep = (lam >= 676.73) & (lam <= 676.83)
    assert cube.shape == (4, 5, int(keep.sum()))
    assert cube.pixel_size == 48 * u.km
    assert cube.mu == 0.5
    factor = (1 * RH_UNIT * const.c / (lam[keep] * u.nm) ** 2).to_value(RADIANCE_UNIT)
    # file axes are (x, y, wavelength); the cube's are (y, x, wavelength)
    np.testing.assert_allclose(cube.I.value[3, 1], inten[1, 3, keep] * factor, rtol=1e-6)
    np.testing.assert_allclose(cube.V.value, 3e-2 * cube.I.value, rtol=1e-5)
    np.testing.assert_allclose(cube.U.value, -2e-3 * cube.I.value, rtol=1e-5)
    assert cube.meta["rh_atmosID"] == "muram test"
    assert cube.meta["rh_nx"] == 5


def test_rh15d_region_and_explicit_pixel_size(tmp_path):
    path = tmp_path / "output_ray.hdf5"
    lam, inten = _write_rh(path, nx=9, ny=7)
    full = StokesCube.from_rh15d(path, pixel_size=96 * u.km)
    part = StokesCube.from_rh15d(path, pixel_size=96 * u.km, region=(slice(2, 6), slice(1, 9, 2)))
    np.testing.assert_array_equal(part.I.value, full.I.value[2:6, 1:9:2])
    with pytest.raises(ValueError, match="pixel_size not given"):
        StokesCube.from_rh15d(path)


def test_rh15d_bad_files_raise_clear_errors(tmp_path):
    junk = tmp_path / "junk.hdf5"
    junk.write_bytes(b"\x00garbage" * 100)
    with pytest.raises(ValueError, match="not a readable HDF5 file"):
        StokesCube.from_rh15d(junk, pixel_size=96 * u.km)
    nostokes = tmp_path / "nostokes.hdf5"
    _write_rh(nostokes, stokes=False)
    with pytest.raises(ValueError, match=r"missing variable\(s\).*stokes_V.*NO_STOKES"):
        StokesCube.from_rh15d(nostokes, pixel_size=96 * u.km)
    filled = tmp_path / "filled.hdf5"
    _write_rh(filled)
    with h5py.File(filled, "r+") as f:
        f["stokes_V"][2, 1, :] = 9.9692e36
    with pytest.raises(ValueError, match=r"fill value in 1 column"):
        StokesCube.from_rh15d(filled, pixel_size=96 * u.km)
    badshape = tmp_path / "badshape.hdf5"
    _write_rh(badshape)
    with h5py.File(badshape, "r+") as f:
        del f["stokes_Q"]
        f["stokes_Q"] = np.zeros((5, 4, 3), dtype=np.float32)
    with pytest.raises(ValueError, match="stokes_Q has shape"):
        StokesCube.from_rh15d(badshape, pixel_size=96 * u.km)
    with pytest.raises(ValueError, match="holds 0 of the file's wavelengths"):
        StokesCube.from_rh15d(filled, pixel_size=96 * u.km, wavelength_range=[500, 501] * u.nm)
    with pytest.raises(FileNotFoundError):
        StokesCube.from_rh15d(tmp_path / "none.hdf5", pixel_size=96 * u.km)
