"""gongsynth.Atmosphere: validation, slicing, replace, readers and the HDF5 round trip."""
from pathlib import Path

import astropy.units as u
import numpy as np
import pytest

import gongsynth
from gongsynth import Atmosphere

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
MURAM = DATA / "mhd" / "muram-test3d-it000000"
needs_data = pytest.mark.skipif(not (MURAM / "Header.000000").is_file(), reason="needs ../shared/data")
P = u.Unit("dyn cm-2")


def small(**changes):
    args = dict(temperature=np.full((3, 2, 4), 5000.0) * u.K, z=[0, 50, 100] * u.km, pixel_size=96 * u.km,
                gas_pressure=np.full((3, 2, 4), 1e4) * P)
    args.update(changes)
    return Atmosphere(args.pop("temperature"), args.pop("z"), args.pop("pixel_size"), **args)


def test_fields_units_and_defaults():
    atm = small(microturbulence=[1, 1, 0.5] * u.km / u.s)
    assert atm.shape == (3, 2, 4)
    assert atm.temperature.unit == u.K and atm.temperature.dtype == np.float32
    assert atm.velocity.shape == (3, 3, 2, 4) and not atm.velocity.value.any()
    assert atm.magnetic_field.unit == u.G
    assert atm.microturbulence.shape == (3, 2, 4)
    assert atm.electron_density is None and atm.density is None
    assert "3 heights" in repr(atm)


@pytest.mark.parametrize("change,match", [
    (dict(temperature=np.full((3, 2, 4), -1.0) * u.K), "temperature must be positive"),
    (dict(temperature=np.full((2, 2, 4), 5000.0) * u.K), "nz = len"),
    (dict(z=[0, 100, 50] * u.km), "strictly increasing"),
    (dict(gas_pressure=None), "gas_pressure or density"),
    (dict(gas_pressure=np.full((3, 2, 4), np.nan) * P), "non-finite"),
    (dict(velocity=np.zeros((2, 3, 2, 4)) * u.km / u.s), "broadcast"),
    (dict(temperature=np.full((3, 2, 4), 5000.0) * u.m), "temperature"),
])
def test_invalid_fields_are_refused(change, match):
    with pytest.raises((ValueError, u.UnitsError, TypeError), match=match):
        small(**change)


def test_slicing_and_replace():
    atm = small(magnetic_field=np.arange(3 * 3 * 2 * 4, dtype=float).reshape(3, 3, 2, 4) * u.G)
    part = atm[1, 1:3]
    assert part.shape == (3, 1, 2)
    assert np.array_equal(part.magnetic_field.value, atm.magnetic_field.value[:, :, 1:2, 1:3])
    hot = atm.replace(temperature=atm.temperature + 100 * u.K)
    assert np.allclose(hot.temperature.value, 5100.0) and np.allclose(atm.temperature.value, 5000.0)
    with pytest.raises(TypeError, match="unknown"):
        atm.replace(pressure=1)


def test_hdf5_round_trip(tmp_path):
    pytest.importorskip("h5py")
    atm = small(electron_density=np.full((3, 2, 4), 1e12) * u.Unit("cm-3"),
                velocity=np.ones((3, 3, 2, 4)) * u.km / u.s)
    path = tmp_path / "atm.h5"
    atm.to_file(path)
    back = Atmosphere.from_file(path)
    for name in ("temperature", "gas_pressure", "electron_density", "velocity", "magnetic_field"):
        assert np.array_equal(getattr(back, name).value, getattr(atm, name).value)
    assert back.density is None
    assert np.array_equal(back.z.value, atm.z.value) and back.pixel_size == atm.pixel_size
    with pytest.raises(FileExistsError):
        atm.to_file(path)
    with pytest.raises(ValueError, match="not a gongsynth atmosphere"):
        import h5py
        with h5py.File(tmp_path / "other.h5", "w") as f:
            f["x"] = 1
        Atmosphere.from_file(tmp_path / "other.h5")


@needs_data
def test_muram_reader():
    atm = Atmosphere.from_muram(MURAM)
    assert atm.shape == (192, 64, 64) and atm.pixel_size.value == pytest.approx(96)
    assert atm.z[1] - atm.z[0] == 32 * u.km
    assert atm.magnetic_field[2].mean().value == pytest.approx(10.0, abs=0.5)   # PROVENANCE: net 10 G
    assert 2000 < atm.temperature.value.min() and atm.temperature.value.max() < 3e6
    with pytest.raises(FileNotFoundError, match="Header.000007"):
        Atmosphere.from_muram(MURAM, iteration=7)


@needs_data
def test_muram_without_eos_files_uses_gongsynth_eos(tmp_path):
    """gongsynth's energy equation is ideal gas + the ionisation energy of hydrogen only; MURaM's tables hold
    more (molecules, all ionisation stages), so the derived T runs high: median 19 % measured where
    4000 K < T < 12 000 K, correlation 0.69 with MURaM's eosT. A known limitation (use eosT when written);
    the test keeps it from growing (25 %, r > 0.6)."""
    # An 8 x 8-column corner of the snapshot keeps the bisection in T quick.
    (tmp_path / "Header.000000").write_text("192 8 8 32e5 96e5 96e5 0 0 0\n")
    for f in MURAM.glob("result_prim_*"):
        data = np.fromfile(f, "<f4").reshape(64, 64, 192)[:8, :8]
        data.tofile(tmp_path / f.name)
    with pytest.warns(UserWarning, match="derived from density and internal energy"):
        derived = Atmosphere.from_muram(tmp_path)
    ref = Atmosphere.from_muram(MURAM)[:8, :8].temperature.value
    sel = (ref > 4000) & (ref < 12000)
    assert np.median(np.abs(derived.temperature.value[sel] / ref[sel] - 1)) < 0.25
    assert np.corrcoef(derived.temperature.value[sel], ref[sel])[0, 1] > 0.6


@needs_data
@pytest.mark.parametrize("path", ["real/models/FALC_82.atmos", "real/models/falc82.1d",
                                  "real/models/hsra11.1d", "models-magnetic/sir/hsra11.mod",
                                  "models-magnetic/sir/hot11.mod",
                                  "models-magnetic/rh/FALP_80.atmos"])
def test_1d_readers(path):
    atm = Atmosphere.from_1d(DATA / path)
    assert atm.shape[1:] == (1, 1)
    photosphere = atm.z.value < 500
    assert np.all(np.diff(atm.gas_pressure.value[photosphere, 0, 0]) < 0)      # pressure falls with height
    assert atm.z.value.min() < 0 < atm.z.value.max()                 # z = 0 at tau_500 = 1 inside


@needs_data
def test_hydrostatic_equilibrium_matches_sir():
    """HSRA from the Hazel file (log tau, T only) put in HSE vs the SIR file's own P_gas: within 6 %
    at z = 0 and 200 km (measured 5.2 % and 0.2 %: opacity and EOS differences between the codes)."""
    hazel = Atmosphere.from_1d(DATA / "real/models/hsra11.1d")
    sir = Atmosphere.from_1d(DATA / "models-magnetic/sir/hsra11.mod")
    for z in (0.0, 200.0):
        ours = np.interp(z, hazel.z.value, hazel.gas_pressure.value[:, 0, 0])
        theirs = np.interp(z, sir.z.value, sir.gas_pressure.value[:, 0, 0])
        assert ours == pytest.approx(theirs, rel=0.06)


@needs_data
def test_art_reader_warns_about_missing_velocity_and_field():
    pytest.importorskip("h5py")
    with pytest.warns(UserWarning, match="no velocity or magnetic field"):
        atm = Atmosphere.from_art(DATA / "mhd/ART_bifrost_25x15x269_model.h5")
    assert atm.shape == (269, 25, 15)
    assert np.all(np.diff(atm.z.value) > 0)
    assert not atm.magnetic_field.value.any()


def test_bad_files_name_the_file(tmp_path):
    bad = tmp_path / "model.xyz"
    bad.write_text("nothing")
    with pytest.raises(ValueError, match="model.xyz"):
        Atmosphere.from_1d(bad)
    with pytest.raises(FileNotFoundError, match="missing.mod"):
        Atmosphere.from_1d(tmp_path / "missing.mod")


def test_exported():
    import importlib
    assert gongsynth.Atmosphere is Atmosphere
    rt = importlib.import_module("gongsynth.rt")
    assert rt.synthesize is importlib.import_module("gongsynth.sun.rt.synthesis").synthesize
