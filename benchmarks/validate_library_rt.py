"""
A coarser 3-D patch library than the full disk's default, against the tiled run's 384 km columns.

The full disk's default (`gongsynth.stages.scene.library_rt.atmosphere_grid`)
is the tiled run's 384 km columns for every instrument.  A coarser grid
(``--coarsen 2``: 768 km columns, 40² per patch) builds four times faster and
was GONG's default until it was found to be another Sun (the builder draws
its elements on its grid); this script measures what else it changes.  It
is compared with a library of the same seeds and levels at the tiled run's
resolution (384 km, the same patch side: 80² columns for a 30.7 Mm patch),
at the angles both share.
For each patch level and angle it prints

1. the continuum: mean stored continuum (the centre-to-limb variation divided
   by the Milne-Eddington limb darkening) of the coarse library relative to the
   reference;
2. the line depth in GONG's channels: 1 - sum_c P_c / (I_c sum_c T_c) of the
   patch-mean spectrum at rest (`ShiftBasis.channels`), coarse and reference;
3. the B response: the patch-mean V signal (the mean V channels projected on
   the plage reference's direction) per G of mean true B·n, coarse relative to
   reference (for the balanced quiet level the column-by-column regression
   slope instead);

each next to the same deviation between two 384 km libraries of different
seeds (``--seed``): the scatter from one patch per level, which every full-disk
library has (the disk lays one patch per level everywhere).  The coarse
library passes where each deviation is within that scatter or within the
tolerance `TOLERANCES`; the build times.

Usage::

    python benchmarks/validate_library_rt.py [--instrument gong] [--coarsen 2]
"""
import argparse
import time

import numpy as np

from gongsynth import instruments
from gongsynth.stages.scene.library_rt import TILED_COLUMN, atmosphere_grid, build_atmosphere_library

#: Tolerances the coarse library meets (fractions): mean continuum, line depth (relative), B response.
TOLERANCES = {"continuum": 0.005, "depth": 0.02, "response": 0.05}


def _channels(lib, rows, part):
    """Channel integrals (n, 3) at rest of ``rows`` (n, K) for a stored part (its offset)."""
    j1 = lib.rank + 1
    cont, coords = rows[:, part].astype(float), rows[:, part + 1:part + j1].astype(float)
    return cont, lib.basis.channels(cont, coords, 0.0)


def level_metrics(lib, level, t):
    """Mean continuum, line depth, mean V channels, mean B·n and column V-B pairs of a level at angle t."""
    lay = lib.layout()
    patch = lib.patches[lib.level_patches[level][0], :, :, t].reshape(-1, lib.row_size).astype(float)
    mean = patch.mean(axis=0, keepdims=True)
    cont, chan = _channels(lib, mean, lay["e"][0])
    totals = lib.basis.totals[lib.basis.velocity.size // 2]
    depth = 1 - chan.sum() / (cont[0] * totals.sum())
    _, v_mean = _channels(lib, mean, lay["v"])
    _, v_cols = _channels(lib, patch, lay["v"])
    mu = np.cos(np.radians(lib.theta[t]))
    b_cols = patch[:, lay["bz"]] * mu
    return {"continuum": float(cont[0]), "depth": float(depth), "v": v_mean[0], "b": float(b_cols.mean()),
            "v_cols": v_cols, "b_cols": b_cols}


def deviations(a, b, level, direction):
    """Relative deviations of metrics ``a`` from ``b`` (`level_metrics`), V projected on ``direction``."""
    if level == 0:      # balanced: the slope of V against B·n, column by column
        resp = [m["v_cols"] @ direction @ m["b_cols"] / (m["b_cols"] @ m["b_cols"]) for m in (a, b)]
    else:
        resp = [m["v"] @ direction / m["b"] for m in (a, b)]
    return {"continuum": a["continuum"] / b["continuum"] - 1, "depth": a["depth"] / b["depth"] - 1,
            "response": resp[0] / resp[1] - 1}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--instrument", default="gong")
    parser.add_argument("--seed", type=int, default=1, help="the second 384 km library's seed (default 1)")
    parser.add_argument("--coarsen", type=int, default=2, help="columns of 384 km per coarse column (2)")
    args = parser.parse_args()
    inst = instruments.get(args.instrument)
    (n_default, _), _ = atmosphere_grid()
    factor = args.coarsen
    n = -(-n_default // factor)
    t0 = time.perf_counter()
    fast = build_atmosphere_library(instrument=inst, shape=(n, n), pixel_size=factor * TILED_COLUMN)
    t1 = time.perf_counter()
    shared = tuple(float(a) for a in fast.theta[[0, 2, 4, 5]])
    fine = dict(instrument=inst, shape=(n * factor, n * factor), pixel_size=TILED_COLUMN, theta=shared)
    ref = build_atmosphere_library(**fine)
    t2 = time.perf_counter()
    other = build_atmosphere_library(seed=args.seed, **fine)
    print(f"coarse: {fast!r} in {t1 - t0:.1f} s; reference: {ref!r} in {t2 - t1:.1f} s")
    failed = []
    names = fast.meta["levels"]
    for level in range(len(fast.level_patches)):
        for tr, angle in enumerate(shared):
            tf = int(np.flatnonzero(fast.theta == angle)[0])
            b = level_metrics(ref, level, tr)
            plage = level_metrics(ref, 3, tr)["v"]
            dev = [deviations(level_metrics(lib, level, t), b, level, plage / np.linalg.norm(plage))
                   for lib, t in ((fast, tf), (other, tr))]
            print(f"{names[level]:>16s} θ={angle:4.0f}°  " + "  ".join(
                f"{key} {dev[0][key]:+.4f} (seeds {dev[1][key]:+.4f})" for key in TOLERANCES))
            failed += [(names[level], angle, key) for key, tol in TOLERANCES.items()
                       if abs(dev[0][key]) > max(tol, abs(dev[1][key]))]
    print(f"tolerances {TOLERANCES}; outside both the tolerance and the seeds' scatter: {failed or 'none'}")


if __name__ == "__main__":
    main()
