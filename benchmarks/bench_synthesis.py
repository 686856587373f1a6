"""
Benchmark: Milne–Eddington synthesis of the full default cube (1024² × 51).

Times `gongsynth.sun.photosphere.model_photosphere` and `synthesize` (numba kernel)
on the default photosphere, the plain-numpy reference (same formulae,
vectorised, exact Faddeeva function) on a block of rows of the same input, and
prints the speed ratio, the largest difference between the two and the peak
memory (tracemalloc of the synthesis, and the process's peak RSS).

Run:  python benchmarks/bench_synthesis.py [--rows 64] [--full-numpy]
"""
import argparse
import resource
import time
import tracemalloc

import numba
import numpy as np

from gongsynth.sun.photosphere import model_photosphere, synthesize


def timed(fn, *args, **kwargs):
    t0 = time.perf_counter()
    out = fn(*args, **kwargs)
    return out, time.perf_counter() - t0


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--rows", type=int, default=64,
                        help="rows of the default photosphere for the numba/numpy comparison")
    parser.add_argument("--full-numpy", action="store_true",
                        help="also run the numpy reference on the whole cube (slow)")
    args = parser.parse_args()

    print(f"numba threads: {numba.get_num_threads()}")
    photosphere, t_model = timed(model_photosphere)
    print(f"model_photosphere() {photosphere.shape}: {t_model:6.2f} s")

    # Compile (or load the cached kernel) outside the timings.
    _, t_compile = timed(synthesize, photosphere[:2, :2])
    print(f"first call (JIT compile or cache load): {t_compile:6.2f} s")

    tracemalloc.start()
    cube, t_full = timed(synthesize, photosphere, mu=1.0)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    ny, nx, nl = cube.shape
    print(f"synthesize numba, full cube {ny}x{nx}x{nl}: {t_full:6.2f} s "
          f"({ny * nx * nl / t_full / 1e6:.1f} M spectral points/s), cube {cube.nbytes / 2**20:.0f} MiB, "
          f"traced peak {peak / 2**20:.0f} MiB")
    del cube

    # Geometry with per-column mu (full-disk mode) costs the same kernel.
    mu = np.clip(np.linspace(0.2, 1.0, nx)[None, :] * np.ones((ny, 1)), 0.2, 1.0)
    _, t_mu = timed(synthesize, photosphere, mu=mu)
    print(f"synthesize numba, per-column mu:           {t_mu:6.2f} s")

    block = photosphere[: args.rows]
    fast, t_fast = timed(synthesize, block, mu=0.5)
    ref, t_ref = timed(synthesize, block, mu=0.5, method="numpy")
    diff = max(float(np.abs(getattr(fast, s).value - getattr(ref, s).value).max()) for s in "IQUV")
    ic = float(ref.I.value[..., 0].mean())
    print(f"block of {args.rows} rows: numba {t_fast:6.3f} s, numpy reference {t_ref:6.3f} s, "
          f"ratio numpy/numba = {t_ref / t_fast:5.1f}; max |difference| = {diff / ic:.1e} of the continuum")
    print(f"numpy reference extrapolated to the full cube: {t_ref * ny / args.rows:6.1f} s")
    if args.full_numpy:
        _, t_np_full = timed(synthesize, photosphere, method="numpy")
        print(f"numpy reference, full cube: {t_np_full:6.1f} s (ratio {t_np_full / t_full:5.1f})")
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**10
    print(f"process peak RSS: {rss:.0f} MiB")


if __name__ == "__main__":
    main()
