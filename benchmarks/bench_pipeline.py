"""
Benchmark of the default end-to-end run (what ``gongsynth simulate`` does).

Prints the wall-clock time of each stage, the total, and the peak resident
memory of the process.  The stage baselines (plain-numpy references) live in
the per-stage benchmarks (bench_synthesis, bench_optics, bench_camera).

    python benchmarks/bench_pipeline.py [--shape 860] [--engine blocks]
"""
import argparse
import resource
import time

import astropy.units as u

import gongsynth


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--shape", type=int, default=None, help="detector side (default 860)")
    parser.add_argument("--engine", default="blocks", choices=("blocks", "frames"))
    parser.add_argument("--duration", type=float, default=10.0, help="minutes")
    parser.add_argument("--mode", default="tiled", choices=("tiled", "full-disk"))
    args = parser.parse_args()

    start = time.perf_counter()
    result = gongsynth.simulate(seed=1, detector_shape=args.shape, engine=args.engine,
                                duration=args.duration * u.min, mode=args.mode, progress=False)
    total = time.perf_counter() - start
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"gongsynth {gongsynth.__version__}: {args.mode}, detector "
          f"{result.magnetogram.data.shape[0]} px, {args.duration:g} min, engine {args.engine}")
    for stage, seconds in result.timings.items():
        print(f"  {stage:<16s} {seconds:7.2f} s")
    print(f"  {'total':<16s} {total:7.2f} s   (import and set-up included: "
          f"{total - sum(result.timings.values()):.2f} s outside the stages)")
    print(f"  peak memory      {peak_mb:7.0f} MB")


if __name__ == "__main__":
    main()
