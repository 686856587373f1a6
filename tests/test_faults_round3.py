"""
Faults round 3 (issue 28): a segfault, inputs used without checks, caches trusted blindly, sweeps
that lost finished work, and errors that came after the computing.

One section per finding of the issue; each drives the command line (`gongsynth.cli.main`) where the
finding is the command line's, with the smallest runs that show it.
"""
import math
import re

import astropy.units as u
import numpy as np
import pytest

from gongsynth.cli import main
from gongsynth.sun.atmosphere import Atmosphere


def _column(nx=2, **fields):
    """
    A small photosphere, nx × 1 columns: T falls from 6500 K to 4500 K over 1.3 Mm, the pressure
    with a 130 km scale height from 1.2e5 dyn cm⁻² at z = 0 (roughly VAL-C's τ₅₀₀ = 1; built by hand,
    not hydrostatically, to stay fast).
    """
    z = np.linspace(-300.0, 1000.0, 40)
    t = 6500.0 - 2000.0 * (z + 300.0) / 1300.0
    p = 1.2e5 * np.exp(-z / 130.0)
    col = np.ones((1, 1, nx))
    return dict(temperature=t[:, None, None] * col, z=z, pixel_size=96.0,
                gas_pressure=p[:, None, None] * col, **fields)


# ----------------------------------------------------------------- 1 the segfault
@pytest.mark.parametrize(("name", "value", "words"), [
    ("velocity", 1e5, "velocity reaches 1e+05 km / s"),
    ("velocity", np.nan, "velocity contains non-finite"),
    ("magnetic_field", 1e6, "magnetic_field reaches 1e+06 G"),
    ("microturbulence", 500.0, "microturbulence reaches 500 km / s"),
])
def test_atmosphere_fields_out_of_physical_range_are_refused(name, value, words):
    nz = 40
    shape = (3, nz, 1, 2) if name != "microturbulence" else (nz, 1, 2)
    values = np.zeros(shape)
    values[-1] = value
    arrays = _column(**{name: values})
    with pytest.raises(ValueError, match=re.escape(words)):
        Atmosphere._from_arrays(arrays)


def test_cli_extreme_velocity_atmosphere_exits_2_naming_it(tmp_path, capsys):
    """The audit's case: v_z = 1e5 km/s everywhere crashed the transfer (exit 139)."""
    from gongsynth.sun import atmosphere_files

    arrays = _column(velocity=np.zeros((3, 40, 1, 2)))
    arrays["velocity"][2] = 1e5
    path = tmp_path / "v.h5"
    fields = {k: (None if arrays.get(k) is None else np.asarray(arrays[k], dtype=np.float32))
              for k in ("temperature", "gas_pressure", "density", "electron_density", "velocity",
                        "magnetic_field", "microturbulence")}
    atmosphere_files.write_hdf5(path, fields, arrays["z"], 96.0)
    code = main(["simulate", "--atmosphere", str(path), "--shape", "16", "--duration", "1", "--seed", "1",
                 "--quiet", "--out", str(tmp_path / "x")])
    err = capsys.readouterr().err
    assert code == 2 and "--atmosphere" in err and "velocity reaches" in err
    assert not (tmp_path / "x").exists()


def _kernel_inputs(ncol, velocity_cm_s, field_g):
    from gongsynth.sun.rt.atomic_data import NiLineData
    from gongsynth.sun.rt.eos import solve_state
    from gongsynth.sun.rt.opacity import column_opacity, line_constants

    a = _column(nx=ncol)
    temp = np.ascontiguousarray(a["temperature"][:, 0, :].T)
    st = solve_state(temp, gas_pressure=np.ascontiguousarray(a["gas_pressure"][:, 0, :].T))
    const, pf = line_constants(NiLineData())
    opac = [np.empty(temp.shape) for _ in range(5)]
    column_opacity(temp, np.ascontiguousarray(st["electron_density"]),
                   np.ascontiguousarray(st["hydrogen_density"]), np.zeros(temp.shape), const, pf, *opac)
    lam = np.linspace(676.73, 676.83, 21) * 1e-7
    ds = np.diff(a["z"]) * 1e5
    full = np.broadcast_to(np.asarray(velocity_cm_s, dtype=float)[:, None], temp.shape).copy()
    bpar = np.full(temp.shape, field_g)
    zero = np.zeros(temp.shape)
    out = [np.empty((ncol, lam.size), dtype=np.float32) for _ in range(4)]
    taus = [np.empty(temp.shape, dtype=np.float32) for _ in range(2)]
    return (lam, const[0], const[10], lam.size // 2, ds, *opac, full, bpar, 0.5 * bpar, zero, *out, *taus), out


def test_rt_kernel_stays_in_bounds_whatever_the_input():
    """Velocities no atmosphere may hold (1e5 km/s, 1e12 km/s, NaN) run without a crash."""
    from gongsynth.sun.rt.kernels import _exp_neg, solve_columns

    # The exponential's table index: a negative optical-depth step indexed before the table.
    assert math.isfinite(_exp_neg.py_func(-4067.0)) and _exp_neg.py_func(1e9) == 0.0
    args, out = _kernel_inputs(3, [1e15, 1e22, np.nan], 1000.0)
    solve_columns(*args)
    assert np.isfinite(out[0][:2]).all()


def test_fast_solver_matches_reference_up_to_the_velocity_limit():
    """The fast solver agrees with the reference at the largest velocity an Atmosphere may hold."""
    from gongsynth.sun.rt.kernels import solve_columns, solve_columns_reference

    results = []
    for solver in (solve_columns, solve_columns_reference):
        args, out = _kernel_inputs(2, [300e5, -300e5], 1500.0)
        solver(*args)
        results.append([o.astype(float) for o in out])
    scale = results[1][0].max()
    for fast, ref in zip(*results):
        assert np.abs(fast - ref).max() < 1e-4 * scale
