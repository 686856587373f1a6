"""
Benchmark of the default end-to-end run (what ``gongsynth simulate`` does).

Prints the wall-clock time of each stage, the total, and the peak resident
memory of the process.  The stage baselines (plain-numpy references) live in
the per-stage benchmarks (bench_synthesis, bench_optics, bench_camera).

``--process N`` instead times N whole ``gongsynth simulate`` processes (what a
user waits for: imports, the run, the saved files and the quick-look) with
their CPU time and peak memory, next to the floor every such process pays:
a Python that only imports sunpy.map and matplotlib (the same machine, the
same minute).

    python benchmarks/bench_pipeline.py [--shape 860] [--engine blocks] [--sun milne-eddington]
    python benchmarks/bench_pipeline.py --process 3 --sun milne-eddington
    python benchmarks/bench_pipeline.py --photosphere-shape 1024 --pixel-size 96   # the papers' grid

In-process runs print each stage's time and peak resident memory (sampled every 0.2 s), the CPU
time, and the peak as a ratio to the process's memory after its imports (the same process).
Before the run they time a baseline in the same process: `rt.synthesize` of a 64² × 80-height
3-D Sun at 51 wavelengths (its CPU and wall seconds; the run's are also given as multiples of it).
"""
import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time

import astropy.units as u

import gongsynth

_FLOOR = "import sunpy.map, matplotlib.figure, astropy.io.fits"


def _child(command):
    """(wall s, CPU s, peak RSS MB) of one child process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    # ru_maxrss of the children is the largest of any child so far (KiB on Linux).
    return wall, cpu, after.ru_maxrss / 1024


def processes(args):
    cli = [sys.executable, "-c", "import sys; from gongsynth.cli import main; sys.exit(main())"]
    print(f"gongsynth {gongsynth.__version__}: {args.process} whole processes; load average "
          f"{os.getloadavg()[0]:.2f} at the start")
    floor = [_child([sys.executable, "-c", _FLOOR]) for _ in range(2)]
    print(f"  floor ({_FLOOR}): {min(w for w, _, _ in floor):.2f} s wall, "
          f"{min(c for _, c, _ in floor):.2f} s CPU")
    with tempfile.TemporaryDirectory() as folder:
        for k in range(args.process):
            command = cli + ["simulate", "--seed", "1", "--quiet", "--out", os.path.join(folder, f"run{k}"),
                             "--duration", str(args.duration), "--mode", args.mode]
            command += ["--sun", args.sun] if args.sun else []
            command += ["--shape", str(args.shape)] if args.shape else []
            wall, cpu, peak = _child(command)
            print(f"  run {k + 1}: {wall:6.2f} s wall, {cpu:6.2f} s CPU, peak RSS (largest child so far) "
                  f"{peak:5.0f} MB, load {os.getloadavg()[0]:.2f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--shape", type=int, default=None, help="detector side (default 860)")
    parser.add_argument("--engine", default="blocks", choices=("blocks", "frames"))
    parser.add_argument("--duration", type=float, default=10.0, help="minutes")
    parser.add_argument("--mode", default="tiled", choices=("tiled", "full-disk"))
    parser.add_argument("--sun", default=None, choices=("milne-eddington", "model-atmosphere"),
                        help="the built-in Sun (default: the mode's)")
    parser.add_argument("--photosphere-shape", type=int, default=None, metavar="N",
                        help="columns of the built-in Sun, N x N (the papers' grid: 1024)")
    parser.add_argument("--pixel-size", type=float, default=None, metavar="KM",
                        help="column spacing of the built-in Sun in km (the papers' grid: 96)")
    parser.add_argument("--process", type=int, default=0, metavar="N",
                        help="time N whole 'gongsynth simulate' processes instead")
    args = parser.parse_args()
    if args.process:
        processes(args)
        return

    grid = {}
    if args.photosphere_shape:
        grid["photosphere_shape"] = (args.photosphere_shape,) * 2
    if args.pixel_size:
        grid["photosphere_pixel_size"] = args.pixel_size * u.km
    floor_mb = _rss_mb()       # the baseline: this process after its imports, before any stage
    base_wall, base_cpu = _baseline()
    peaks, cpus = _stage_peaks()
    start, cpu = time.perf_counter(), time.process_time()
    result = gongsynth.simulate(seed=1, detector_shape=args.shape, engine=args.engine, sun=args.sun,
                                duration=args.duration * u.min, mode=args.mode, progress=False, **grid)
    total, cpu = time.perf_counter() - start, time.process_time() - cpu
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"gongsynth {gongsynth.__version__}: {args.mode}, detector "
          f"{result.magnetogram.data.shape[0]} px, {args.duration:g} min, engine {args.engine}, "
          f"sun {result.config.sun}, photosphere {result.config.photosphere_shape} x "
          f"{result.config.photosphere_pixel_size}; load {os.getloadavg()[0]:.1f}")
    for stage, seconds in result.timings.items():
        print(f"  {stage:<16s} {seconds:7.2f} s wall {cpus.get(stage, 0):7.2f} s CPU   "
              f"peak RSS {peaks.get(stage, 0):6.0f} MB")
    print(f"  {'total':<16s} {total:7.2f} s wall, {cpu:.2f} s CPU (set-up outside the stages: "
          f"{total - sum(result.timings.values()):.2f} s)")
    print(f"  baseline         {base_wall:7.2f} s wall, {base_cpu:.2f} s CPU (rt.synthesize, 64² x 80 x 51, "
          f"before the run): the run is {total / base_wall:.1f} x its wall, {cpu / base_cpu:.1f} x its CPU")
    print(f"  peak memory      {peak_mb:7.0f} MB = {peak_mb / floor_mb:.2f} x the process after its imports "
          f"({floor_mb:.0f} MB)")


def _baseline():
    """(wall s, CPU s) of `rt.synthesize` of a 64² × 80-height 3-D Sun, μ = 0.8, 51 wavelengths."""
    from gongsynth.sun.model_atmosphere import model_atmosphere
    atm = model_atmosphere((64, 64), 96 * u.km, seed=1)
    gongsynth.rt.synthesize(atm[:2, :2], mu=0.8, progress=False)
    start, cpu = time.perf_counter(), time.process_time()
    gongsynth.rt.synthesize(atm, mu=0.8, azimuth=-90 * u.deg, progress=False)
    return time.perf_counter() - start, time.process_time() - cpu


def _rss_mb():
    """The resident set of this process now, MB."""
    with open("/proc/self/status") as status:
        return int(next(x for x in status if x.startswith("VmRSS")).split()[1]) / 1024


def _stage_peaks():
    """{stage name: peak RSS in MB while it ran} (a thread samples every 0.2 s), {stage name: CPU s}."""
    import threading

    import gongsynth.chain
    peaks, cpus, now = {}, {}, ["set-up"]
    run_stage = gongsynth.chain.Stage.__call__

    def named(self, state):
        now[0] = self.name
        cpu = time.process_time()
        try:
            return run_stage(self, state)
        finally:
            cpus[self.name] = time.process_time() - cpu

    def watch():
        while True:
            peaks[now[0]] = max(peaks.get(now[0], 0.0), _rss_mb())
            time.sleep(0.2)

    gongsynth.chain.Stage.__call__ = named
    threading.Thread(target=watch, daemon=True).start()
    return peaks, cpus


if __name__ == "__main__":
    main()
