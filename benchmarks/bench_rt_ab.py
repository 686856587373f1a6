"""
Benchmark: the fast solver of a base revision against this checkout's, interleaved in one process.

`~gongsynth.sun.rt.kernels.solve_columns` of ``--base`` (its ``kernels.py`` and ``voigt.py``, read
with ``git show`` into a temporary module pair) and of this checkout, on the arguments
`gongsynth.rt.synthesize` passes for the default 3-D Sun (`model_atmosphere`, N² columns × 80
heights, the run's 384 km columns scaled to N, μ = 0.8, 51 wavelengths), both lines of
`gongsynth.rt.LINES`, with the field and with B = 0.  The two solvers alternate (which goes first
swaps every round) and each keeps the minimum of ``--repeat`` runs: the process CPU time per
column·height·wavelength, the figure that holds on a shared machine.  Also the largest difference
of I, Q, U, V (in each ray's continuum) against `solve_columns_reference` and between the two.
Run it with one numba thread for per-core figures (``NUMBA_NUM_THREADS=1``).

Run:  NUMBA_NUM_THREADS=1 python benchmarks/bench_rt_ab.py --base main [--columns 48] [--repeat 11]
"""
import argparse
import importlib
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import astropy.units as u
import numpy as np

import gongsynth
from gongsynth.sun.rt import kernels, synthesis

ROOT = Path(__file__).resolve().parents[1]


def base_kernels(rev, folder):
    """The ``kernels`` module of revision ``rev`` (importing that revision's ``voigt``)."""
    for name in ("voigt", "kernels"):
        text = subprocess.run(["git", "-C", str(ROOT), "show", f"{rev}:gongsynth/sun/rt/{name}.py"],
                              check=True, capture_output=True, text=True).stdout
        text = text.replace("from gongsynth.sun.rt.voigt import", "from base_voigt import")
        (Path(folder) / f"base_{name}.py").write_text(text)
    sys.path.insert(0, str(folder))
    return importlib.import_module("base_kernels")


def solver_arguments(n):
    """solve_columns' arguments of the 3-D Sun (all blocks' rays stacked), per (line, field or B = 0)."""
    from gongsynth.sun.model_atmosphere import model_atmosphere

    atm = model_atmosphere((n, n), 384 * u.km * 256 / n, seed=1)
    calm = atm.replace(magnetic_field=np.zeros((3,) + atm.shape, np.float32) * u.G)
    cases, fast = {}, synthesis.solve_columns
    try:
        for line in gongsynth.rt.LINES:
            for label, box in (("field", atm), ("B = 0", calm)):
                calls = []
                synthesis.solve_columns = lambda *a, _c=calls: (_c.append(a), fast(*a))   # the truth needs τ
                gongsynth.rt.synthesize(box, mu=0.8, progress=False, line=line)
                cases[line, label] = [np.concatenate([c[i] for c in calls]) if i >= 5 else a
                                      for i, a in enumerate(calls[0])]
    finally:
        synthesis.solve_columns = fast
    return cases


def run(solver, args):
    """(CPU seconds, [I, Q, U, V]) of one call."""
    n, nl = args[5].shape[0], args[0].size
    out = [np.empty((n, nl), np.float32) for _ in range(4)] + [np.empty(args[5].shape, np.float32)
                                                              for _ in range(2)]
    t0 = time.process_time()
    solver(*args[:14], *out)
    return time.process_time() - t0, out[:4]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--base", required=True, help="git revision of the base solver")
    parser.add_argument("--columns", type=int, default=48, help="N of the N x N 3-D Sun (default 48)")
    parser.add_argument("--repeat", type=int, default=11, help="runs of each solver (the minimum is kept)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        base = base_kernels(args.base, folder)
        cases = solver_arguments(args.columns)
        print(f"base {args.base} against this checkout; {os.environ.get('NUMBA_NUM_THREADS', 'all')} "
              f"numba threads; ns per column·height·wavelength (CPU, min of {args.repeat})")
        solvers = {"base": base.solve_columns, "this": kernels.solve_columns}
        for (line, label), a in cases.items():
            best, out = {"base": np.inf, "this": np.inf}, {}
            for name in solvers:           # compile (or load) both first
                run(solvers[name], [x[:2] if isinstance(x, np.ndarray) and x.ndim == 2 else x for x in a])
            for r in range(args.repeat):
                for name in (("base", "this") if r % 2 == 0 else ("this", "base")):
                    cpu, out[name] = run(solvers[name], a)
                    best[name] = min(best[name], cpu)
            _, ref = run(kernels.solve_columns_reference, a)
            ic = ref[0][:, :1]
            dref = " ".join(f"{np.abs((o - r) / ic).max():.1e}" for o, r in zip(out["this"], ref))
            dbase = " ".join(f"{np.abs((o - b) / ic).max():.1e}" for o, b in zip(out["this"], out["base"]))
            nvw = a[5].size * a[0].size
            print(f"  {line:11s} {label:6s} base {best['base'] / nvw * 1e9:6.2f} this "
                  f"{best['this'] / nvw * 1e9:6.2f} ratio {best['this'] / best['base']:.3f}; "
                  f"max |this - reference| / I_c (I Q U V) {dref}; |this - base| {dbase}", flush=True)
    print(f"load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
