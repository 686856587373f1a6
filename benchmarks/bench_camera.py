"""
Benchmark of the camera engines on a GONG-sized detector.

Runs, in one process and on the same input (an 860 × 860 quiet-Sun disk with
limb darkening at 1.2e5 e⁻ per frame per channel at disk centre, dark sky
around it, the default synthetic flat and dark):

1. the plain-numpy baseline: the paper's per-frame loop written with numpy
   (one Poisson and one normal array per frame), on a strip of rows for one
   minute; its cost per pixel-frame is extrapolated to the full run;
2. the ``frames`` engine on the same strip and minute (ratio against 1);
3. the ``blocks`` engine on the full detector for 10 minutes (target < 2 s);
4. the ``frames`` engine on the full detector for 10 minutes (target < 10 min
   on 2 cores; skipped with ``--quick``);
5. with ``--lam``, the ``frames`` engine on a uniform 64 × 256 field of each
   given mean (unity flat, no dark), 1 minute, on one thread and on
   ``--workers`` threads: CPU and wall ns per pixel-frame at that λ;

and prints wall times, ratios and the peak resident memory of the process.

Usage::

    python benchmarks/bench_camera.py [--quick] [--rows 16] [--workers N] [--lam 1e5 3e4]
"""
import argparse
import os
import resource
import time

import astropy.units as u
import numpy as np

from gongsynth import GONGInstrument
from gongsynth.stages.camera.detector import synthetic_dark, synthetic_flat
from gongsynth.stages.camera.integrate import integrate
from gongsynth.stages.camera.schedule import frame_schedule
from gongsynth.stages.filters import channel_weights


def disk_scene(n=860, continuum=1.2e5, radius=0.45):
    """Expected electrons per frame (6, n, n): a limb-darkened quiet-Sun disk."""
    inst = GONGInstrument()
    lam = np.linspace(676.6, 676.96, 721) * u.nm
    w = channel_weights(lam, inst).value
    sigma = 10e-3 / 2.3548
    line = 1 - 0.6 * np.exp(-0.5 * ((lam.value - 676.78) / sigma) ** 2)
    planes = continuum * (w @ line) / w.sum(axis=1).mean()
    y, x = (np.mgrid[:n, :n] + 0.5) / n - 0.5
    r = np.hypot(x, y) / radius
    mu = np.sqrt(np.clip(1 - r**2, 0, None))
    limb = np.where(r < 1, 1 - 0.6 * (1 - mu), 0.0)  # linear limb darkening, u = 0.6
    return np.concatenate([planes, planes])[:, None, None] * limb * u.electron


def numpy_loop(expected, flat, dark, duration, inst, seed):
    """The paper's per-frame algorithm in plain numpy: the baseline."""
    s = frame_schedule(duration, inst)
    lam = expected.to_value(u.electron) * flat / np.median(flat) + dark.to_value(u.electron)
    gain = inst.gain.to_value(u.electron / u.adu)
    sigma = inst.read_noise.to_value(u.adu)
    dither = s.dither.to_value(u.adu).astype(np.int64)
    rng = np.random.default_rng(seed)
    acc = np.zeros(lam.shape, dtype=np.int64)
    for k in range(s.n_frames):
        p = s.plane[k]
        x = rng.poisson(lam[p]) / gain + sigma * rng.standard_normal(lam.shape[1:])
        acc[p] += np.floor(x + 0.5).astype(np.int64) + dither[k]
    scale = 2**inst.truncate_bits
    return (acc >> inst.truncate_bits) + (scale - 1) / (2 * scale) - (s.dither_sum / scale)[:, None, None]


def per_lambda(lam, workers, inst, repeats=3):
    """(CPU, wall) ns per pixel-frame of the frames engine on a uniform field of mean ``lam`` (best of 3)."""
    field = np.full((6, 64, 256), lam) * u.electron
    pf = field[0].size * frame_schedule(1 * u.min, inst).n_frames
    best = (np.inf, np.inf)
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        integrate(field, duration=1 * u.min, engine="frames", seed=1, flat=False, dark=False, workers=workers,
                  progress=False)
        t, c = time.perf_counter() - t0, time.process_time() - c0
        best = min(best[0], c / pf * 1e9), min(best[1], t / pf * 1e9)
    return best


def peak_rss_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--quick", action="store_true", help="skip the full 10-minute frames run")
    parser.add_argument("--rows", type=int, default=16, help="rows of the baseline strip")
    parser.add_argument("--workers", type=int, default=None, help="threads (default: all cores)")
    parser.add_argument("--lam", type=float, nargs="*", default=[], help="means for the per-λ runs")
    args = parser.parse_args()

    inst = GONGInstrument()
    n = inst.detector_shape
    expected = disk_scene(n)
    flat = synthetic_flat((n, n))
    dark = synthetic_dark((n, n))
    full_pf = n * n * frame_schedule(10 * u.min, inst).n_frames
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} "
          "(other work slows every timing below)")
    print(f"input: {n}x{n} quiet-Sun disk, max {expected.max():.4g}/frame; 10 min = "
          f"{full_pf:.3g} pixel-frames; peak RSS so far {peak_rss_mb():.0f} MB")

    # Strip through disk centre for the baseline comparison.
    rows = slice(n // 2 - args.rows // 2, n // 2 - args.rows // 2 + args.rows)
    strip = (expected[:, rows], flat[rows], dark[rows])
    strip_pf = args.rows * n * frame_schedule(1 * u.min, inst).n_frames
    t0, c0 = time.perf_counter(), time.process_time()
    base = numpy_loop(*strip, 1 * u.min, inst, seed=0)
    t_base, c_base = time.perf_counter() - t0, time.process_time() - c0
    ns_base = t_base / strip_pf * 1e9
    print(f"\nplain-numpy per-frame loop, {args.rows}x{n} px, 1 min: {t_base:.2f} s "
          f"({ns_base:.1f} ns per pixel-frame; full 10-min run extrapolated: "
          f"{ns_base * full_pf / 1e9:.0f} s)")

    integrate(expected[:, :2, :2], duration=1 * u.s, engine="frames", seed=0, flat=flat[:2, :2],
              dark=dark[:2, :2], progress=False)  # compile / load the numba cache first
    t0, c0 = time.perf_counter(), time.process_time()
    raw = integrate(strip[0], duration=1 * u.min, engine="frames", seed=0, flat=strip[1], dark=strip[2],
                    workers=args.workers, progress=False)
    t_frames, c_frames = time.perf_counter() - t0, time.process_time() - c0
    diff = raw.data - base
    z = diff.mean() / (diff.std() / np.sqrt(diff.size))
    print(f"frames engine, same strip: {t_frames:.2f} s ({t_frames / strip_pf * 1e9:.1f} ns per "
          f"pixel-frame): {t_base / t_frames:.1f}x faster than the numpy loop "
          f"(mean difference {z:+.1f} sigma); in CPU time (all threads) {c_base / c_frames:.1f}x less "
          f"({c_frames / strip_pf * 1e9:.1f} vs {c_base / strip_pf * 1e9:.1f} ns per pixel-frame)")

    t0 = time.perf_counter()
    integrate(expected, duration=10 * u.min, engine="blocks", seed=0, flat=flat, dark=dark,
              workers=args.workers, progress=False)
    t_blocks = time.perf_counter() - t0
    print(f"\nblocks engine, full {n}x{n}, 10 min: {t_blocks:.2f} s (target < 2 s); "
          f"{ns_base * full_pf / 1e9 / t_blocks:.0f}x faster than the extrapolated numpy loop; "
          f"peak RSS {peak_rss_mb():.0f} MB")

    if not args.quick:
        t0 = time.perf_counter()
        integrate(expected, duration=10 * u.min, engine="frames", seed=0, flat=flat, dark=dark,
                  workers=args.workers, progress=True)
        t_full = time.perf_counter() - t0
        print(f"frames engine, full {n}x{n}, 10 min: {t_full:.0f} s (target < 600 s); "
              f"{ns_base * full_pf / 1e9 / t_full:.1f}x faster than the extrapolated numpy loop; "
              f"peak RSS {peak_rss_mb():.0f} MB (target < 2048 MB); load average now "
              f"{os.getloadavg()[0]:.1f}")


    for lam in args.lam:
        cpu1, wall1 = per_lambda(lam, 1, inst)
        cpu, wall = per_lambda(lam, args.workers or os.cpu_count(), inst)
        print(f"frames engine, uniform λ = {lam:g}: 1 thread {cpu1:.2f} ns CPU ({wall1:.2f} wall) per "
              f"pixel-frame; {args.workers or os.cpu_count()} threads {wall:.2f} ns wall ({cpu:.2f} CPU); "
              f"load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
