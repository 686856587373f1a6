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

``--voxels N`` (issue 26): the default run's 3-D Sun (`model_atmosphere`, N²
columns × 80 heights, the run's 384 km columns scaled to N) through the whole
`synthesize` for both lines of `gongsynth.rt.LINES`, with its field and with
B = 0: ns per column·height·wavelength per core (process CPU time, the
minimum of ``--repeat`` runs: the figure that holds on a shared machine),
each stage's share, the ratio to a plain baseline timed in the same process
(one Humlíček W4 evaluation per voxel-wavelength, `~gongsynth.sun.rt.voigt.faddeeva`)
and the hardware limit estimated from this core's measured FMA throughput and
the fast solver's operation count (`FLOPS_PER_VW`).

Run:  python benchmarks/bench_rt.py [--large 256] [--voxels 128 [--repeat 3] [--only-voxels]]
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
from gongsynth.sun.rt.voigt import faddeeva

#: Floating-point operations per voxel-wavelength of the fast solver, counted from
#: `gongsynth.sun.rt.kernels._solve_rays` in float64 equivalents (a float32 operation fills half a float64
#: one's SIMD width, so it counts ½): x (2), w(z) by Weideman's form in float32 (~114 → 57), the σ profiles
#: at a field above 0.006 Doppler widths (most points of the 3-D Sun) from w(x ± v_B) (~114 → 57 each)
#: and their sums (6), the absorption-matrix elements (~20 → 10), Δτ and e^-Δτ (~22 → 11), the DELO
#: weights (~10 → 5), the right-hand side (~40 → 20) and the 4 × 4 elimination (~45 → 23); divisions
#: counted as 4 operations each.
FLOPS_PER_VW = 248

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


@numba.njit(parallel=True, cache=True)
def _baseline(x, y, out):
    """The plain baseline: one W4 evaluation per element."""
    for p in numba.prange(x.size):
        out[p] = faddeeva(x[p], y)[0]


@numba.njit(cache=True, fastmath={"contract"})
def _fma_rate(x, reps):
    """Eight independent multiply-add chains per element (the compiler vectorises across elements)."""
    acc = np.zeros_like(x)
    for _ in range(reps):
        for j in range(x.size):
            a = x[j]
            b = a + 1.0
            c = a + 2.0
            d = a + 3.0
            e = a + 4.0
            f = a + 5.0
            g = a + 6.0
            h = a + 7.0
            for _ in range(16):
                a = a * 0.999 + 0.001
                b = b * 0.999 + 0.001
                c = c * 0.999 + 0.001
                d = d * 0.999 + 0.001
                e = e * 0.999 + 0.001
                f = f * 0.999 + 0.001
                g = g * 0.999 + 0.001
                h = h * 0.999 + 0.001
            acc[j] += a + b + c + d + e + f + g + h
    return acc


def cpu_timed(fn, *args, repeat=3, **kwargs):
    """Minimum process CPU time (s) and wall time of that run over ``repeat`` calls (after one warm-up)."""
    fn(*args, **kwargs)
    best = (np.inf, np.inf)
    for _ in range(repeat):
        t0, w0 = time.process_time(), time.perf_counter()
        fn(*args, **kwargs)
        best = min(best, (time.process_time() - t0, time.perf_counter() - w0))
    return best


def peak_flops_per_ns():
    """Measured multiply-add throughput of one core (flop per ns, float64; the hardware limit's yardstick)."""
    x = np.linspace(0.0, 1.0, 256)
    reps = 2000
    cpu, _ = cpu_timed(_fma_rate, x, reps)
    return x.size * reps * 16 * 8 * 2 / (cpu * 1e9)


class StageClock:
    """CPU seconds spent in each of `synthesize`'s stage functions (patched in `synthesis` while active)."""

    NAMES = ("_opacity", "solve_columns", "sample_component", "los_field_at_depth",
             "reference_height")

    def __init__(self):
        self.seconds = {}

    def __enter__(self):
        self.saved = {name: getattr(synthesis, name) for name in self.NAMES}
        for name, fn in self.saved.items():
            def timed_stage(*args, _fn=fn, _name=name, **kwargs):
                t0 = time.process_time()
                try:
                    return _fn(*args, **kwargs)
                finally:
                    self.seconds[_name] = self.seconds.get(_name, 0.0) + time.process_time() - t0
            setattr(synthesis, name, timed_stage)
        return self

    def __exit__(self, *exc):
        for name, fn in self.saved.items():
            setattr(synthesis, name, fn)


def voxel_benchmark(n, repeat):
    """ns per column·height·wavelength per core of the default 3-D Sun, both lines, with and without field."""
    from gongsynth.sun.model_atmosphere import model_atmosphere

    atm = model_atmosphere((n, n), 384 * u.km * 256 / n, seed=1)
    nz = atm.shape[0]
    calm = atm.replace(magnetic_field=np.zeros((3,) + atm.shape, np.float32) * u.G)
    peak = peak_flops_per_ns()
    rng = np.random.default_rng(0)
    xs = rng.uniform(-20, 20, n * n * nz * 51)
    base_cpu, _ = cpu_timed(_baseline, xs, 0.05, np.empty_like(xs), repeat=repeat)
    nvw = xs.size
    print(f"3-D Sun {n}^2 columns x {nz} heights x 51 wavelengths, mu = 0.8, {numba.get_num_threads()} "
          f"threads; baseline (one W4 per voxel-wavelength) {base_cpu / nvw * 1e9:.2f} ns/vw/core; "
          f"measured FMA rate {peak:.1f} flop/ns/core -> hardware limit ~{FLOPS_PER_VW / peak:.1f} "
          f"ns/vw/core for the solver's {FLOPS_PER_VW} operations")
    for line in gongsynth.rt.LINES:
        for label, box in (("field", atm), ("B = 0", calm)):
            best = None
            gongsynth.rt.synthesize(box, mu=0.8, progress=False, line=line)
            for _ in range(repeat):
                with StageClock() as clock:
                    t0, w0 = time.process_time(), time.perf_counter()
                    gongsynth.rt.synthesize(box, mu=0.8, progress=False, line=line)
                    cpu, wall = time.process_time() - t0, time.perf_counter() - w0
                if best is None or cpu < best[0]:
                    best = (cpu, wall, dict(clock.seconds))
            cpu, wall, stages = best
            share = ", ".join(f"{k.strip('_')} {v / nvw * 1e9:.1f}" for k, v in stages.items())
            print(f"  {line:11s} {label:6s}: {cpu / nvw * 1e9:6.1f} ns/vw/core (CPU; wall {wall:.2f} s), "
                  f"{cpu / base_cpu:5.2f} x baseline; stages ns/vw: {share}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--large", type=int, default=0, help="also time an N x N FAL-C box with 100 heights")
    parser.add_argument("--voxels", type=int, default=0,
                        help="also time the default 3-D Sun on N x N columns, both lines, with and without "
                             "field")
    parser.add_argument("--repeat", type=int, default=3,
                        help="runs per --voxels figure (the minimum is kept)")
    parser.add_argument("--only-voxels", action="store_true", help="skip the other measurements")
    args = parser.parse_args()
    print(f"numba threads: {numba.get_num_threads()}")
    if args.voxels:
        voxel_benchmark(args.voxels, args.repeat)
        if args.only_voxels:
            return
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
