"""
Benchmark: LTE Stokes synthesis (gongsynth.rt) against Lightweaver per column, and a large cube.

Times `gongsynth.rt.synthesize` on the MURaM test snapshot (64² columns × 192
heights × 51 wavelengths) and on FAL-C columns, each with the fast solver and
with the first, simple one (`~gongsynth.sun.rt.kernels.solve_columns_reference`)
in the same process (ratio = speed-up, and the largest |ΔI|, |ΔV| in units of
the continuum), and Lightweaver's LTE formal solution of one FAL-C column
(`gongsynth.sun.photosphere.reference.falc_stokes`, when installed); prints
columns per second.  ``--large N`` also times an N² × 100-height box (FAL-C
with 2 % temperature noise, B = 0) and extrapolates to 1024²; peak RSS.

Run:  python benchmarks/bench_rt.py [--large 256]
"""
import argparse
import contextlib
import resource
import time
from pathlib import Path

import astropy.units as u
import numba
import numpy as np

import gongsynth
from gongsynth.sun.rt import synthesis
from gongsynth.sun.rt.kernels import solve_columns_reference

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


def timed(fn, *args, **kwargs):
    t0 = time.perf_counter()
    out = fn(*args, **kwargs)
    return out, time.perf_counter() - t0


def uniform_field(atm, bz):
    """``atm`` with a vertical field of ``bz`` G."""
    field = np.array([0.0, 0.0, bz])[:, None, None, None] * np.ones((3,) + atm.shape)
    return atm.replace(magnetic_field=field * u.G)


@contextlib.contextmanager
def reference_solver():
    """Run `synthesize` with the first, simple solver."""
    fast = synthesis.solve_columns
    synthesis.solve_columns = solve_columns_reference
    try:
        yield
    finally:
        synthesis.solve_columns = fast


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--large", type=int, default=0, help="also time an N x N FAL-C box with 100 heights")
    args = parser.parse_args()
    print(f"numba threads: {numba.get_num_threads()}")
    falc = gongsynth.Atmosphere.from_1d(DATA / "real/models/FALC_82.atmos")
    gongsynth.rt.synthesize(falc, progress=False)                      # compile
    with reference_solver():
        gongsynth.rt.synthesize(uniform_field(falc, 100.0), progress=False)
    gongsynth.rt.synthesize(uniform_field(falc, 100.0), progress=False)
    muram = gongsynth.Atmosphere.from_muram(DATA / "mhd/muram-test3d-it000000")
    for mu in (1.0, 0.5):
        fast, t = timed(gongsynth.rt.synthesize, muram, mu=mu, azimuth=-90 * u.deg, progress=False)
        with reference_solver():
            ref, t_ref = timed(gongsynth.rt.synthesize, muram, mu=mu, azimuth=-90 * u.deg, progress=False)
        ic = ref.I.value[:, :, :1]
        di = np.abs(fast.I.value - ref.I.value).max() / ic.min()
        dv = np.abs(fast.V.value - ref.V.value).max() / ic.min()
        print(f"MURaM 64x64x192, mu={mu}: {t:6.2f} s = {64 * 64 / t:8.0f} columns/s; reference solver "
              f"{64 * 64 / t_ref:6.0f} columns/s: x{t_ref / t:4.2f}; max |dI|, |dV| = {di:.1e}, {dv:.1e} Ic")
    n = 32
    box = gongsynth.Atmosphere(np.broadcast_to(falc.temperature, (falc.shape[0], n, n)), falc.z, 96 * u.km,
                               gas_pressure=np.broadcast_to(falc.gas_pressure, (falc.shape[0], n, n)),
                               electron_density=np.broadcast_to(falc.electron_density, (falc.shape[0], n, n)))
    _, t = timed(gongsynth.rt.synthesize, box, progress=False)
    with reference_solver():
        _, t_ref = timed(gongsynth.rt.synthesize, box, progress=False)
    ours = n * n / t
    print(f"FAL-C {n}x{n} columns x 82 heights (B = 0): {ours:8.0f} columns/s; "
          f"reference solver x{t_ref / t:4.2f}")
    try:
        from gongsynth.sun.photosphere.reference import falc_stokes
        falc_stokes([0] * u.G)                                          # warm up
        _, t_lw = timed(falc_stokes, [0, 0, 0, 0] * u.G)
        print(f"Lightweaver (one LTE FAL-C column per call, incl. setup): {4 / t_lw:8.2f} columns/s; "
              f"gongsynth/Lightweaver per column: {ours * t_lw / 4:8.0f}x")
    except ImportError:
        print("Lightweaver not installed: no comparison")
    if args.large:
        n = args.large
        z = np.linspace(falc.z.value[0], 800, 100)
        col = {k: np.interp(z, falc.z.value, getattr(falc, k).value[:, 0, 0])[:, None, None]
               for k in ("temperature", "gas_pressure", "electron_density")}
        rng = np.random.default_rng(0)
        temp = (col["temperature"] * (1 + 0.02 * rng.standard_normal((1, n, n)))).astype(np.float32)
        pres = np.broadcast_to(col["gas_pressure"], temp.shape) * u.Unit("dyn cm-2")
        big = gongsynth.Atmosphere(temp * u.K, z * u.km, 96 * u.km, gas_pressure=pres,
                                   electron_density=np.broadcast_to(col["electron_density"], temp.shape)
                                   * u.Unit("cm-3"))
        _, t = timed(gongsynth.rt.synthesize, big, progress=False)
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        print(f"{n}x{n}x100 heights x 51 wavelengths: {t:7.1f} s = {n * n / t:8.0f} columns/s; "
              f"peak RSS {peak:.0f} MiB (1024^2 extrapolated: {t * (1024 / n) ** 2:7.0f} s)")
        mag = big.replace(magnetic_field=np.broadcast_to(np.array([30.0, -20.0, 100.0])[:, None, None, None],
                                                         (3,) + temp.shape) * u.G)
        _, t = timed(gongsynth.rt.synthesize, mag, progress=False)
        print(f"  the same with a uniform 107 G field (4x4 solve): {t:7.1f} s = {n * n / t:8.0f} columns/s "
              f"(1024^2 extrapolated: {t * (1024 / n) ** 2:7.0f} s)")


if __name__ == "__main__":
    main()
