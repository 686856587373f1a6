"""
Benchmark of a full-disk HMI 45-s magnetogram (4096² at 0.504″): time and memory per stage.

Each run is a fresh process (``simulate(instrument="hmi", mode="full-disk", duration=0.75 min)`` at
the real HMI map's date, then ``save``), first with an empty library cache (the library is built:
the Milne-Eddington Sun's in seconds, the 3-D Sun's by radiative transfer in minutes), then with it
cached.  Printed: wall and CPU time, each stage's time, the peak resident memory of the process
(VmHWM) and of each stage (the resident set sampled every 0.2 s while it runs), and the load average
(the machine is shared: compare CPU times, or ratios within one run).  Baselines in the same
process: the wall time of one ``scipy.fft.rfft2`` of a supersampled plane (``wall_per_fft``), and
the bytes of the K detector planes in float64 (``peak_per_stack``: the peak in copies of the stack).

    python benchmarks/bench_fulldisk_hmi.py [--sun model-atmosphere] [--shape 4096] [--cached-only]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import textwrap

CODE = textwrap.dedent("""
    import json, sys, threading, time
    start = time.perf_counter()
    import astropy.units as u, gongsynth
    stage, peak, stage_cpu = ["import"], {}, {}

    def watch():
        while True:
            rss = int([x for x in open("/proc/self/status") if x.startswith("VmRSS")][0].split()[1]) / 2**20
            peak[stage[0]] = max(peak.get(stage[0], 0.0), rss)
            time.sleep(0.2)

    import gongsynth.chain
    run_stage = gongsynth.chain.Stage.__call__

    def named(self, state):     # the stage now running, for the sampler; its CPU time (both cores)
        stage[0] = self.name
        begin = time.process_time()
        try:
            return run_stage(self, state)
        finally:
            stage_cpu[self.name] = stage_cpu.get(self.name, 0.0) + time.process_time() - begin

    gongsynth.chain.Stage.__call__ = named
    threading.Thread(target=watch, daemon=True).start()
    cpu = time.process_time()
    result = gongsynth.simulate(instrument="hmi", mode="full-disk", duration=0.75 * u.min, seed=1,
                                obstime="2010-10-20T00:00", sun=sys.argv[1], detector_shape=int(sys.argv[2]),
                                progress=False)
    stage[0] = "save"
    begin = time.process_time()
    result.save(sys.argv[3], overwrite=True)
    stage_cpu["save"] = time.process_time() - begin
    hwm = int([x for x in open("/proc/self/status") if x.startswith("VmHWM")][0].split()[1]) / 2**20
    wall, cpu = time.perf_counter() - start, time.process_time() - cpu
    # Plain baselines in the same process: one real FFT of a supersampled plane (the optics' unit of
    # work), and the bytes of the K detector planes in float64 (what one copy of the stack costs).
    import numpy as np, scipy.fft
    n = int(sys.argv[2]) * result.config.instrument.supersampling
    plane = np.random.default_rng(0).random((n, n), dtype=np.float32)
    fft_start = time.perf_counter()
    scipy.fft.rfft2(plane, workers=2)
    fft_s = time.perf_counter() - fft_start
    stack_GB = len(result.raw.frames_per_plane) * int(sys.argv[2])**2 * 8 / 2**30
    print(json.dumps({"wall_s": round(wall, 1), "cpu_s": round(cpu, 1),
                      "stages_s": {k: round(v, 1) for k, v in result.timings.items()},
                      "stage_cpu_s": {k: round(v, 1) for k, v in stage_cpu.items()},
                      "peak_GB": round(hwm, 2), "stage_peak_GB": {k: round(v, 2) for k, v in peak.items()},
                      "baseline_fft_s": round(fft_s, 2), "wall_per_fft": round(wall / fft_s, 1),
                      "float64_stack_GB": round(stack_GB, 2), "peak_per_stack": round(hwm / stack_GB, 2)}))
""")


def run(sun, shape, cache, out):
    env = {**os.environ, "GONGSYNTH_CACHE_DIR": cache}
    done = subprocess.run([sys.executable, "-c", CODE, sun, str(shape), out], env=env, capture_output=True,
                          text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--sun", default="milne-eddington", choices=("milne-eddington", "model-atmosphere"))
    parser.add_argument("--shape", type=int, default=4096)
    parser.add_argument("--cached-only", action="store_true", help="skip the empty-cache run")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        cache = os.environ.get("GONGSYNTH_CACHE_DIR", tmp) if args.cached_only else tmp
        for label in (() if args.cached_only else ("empty cache",)) + ("cached library",):
            numbers = run(args.sun, args.shape, cache, os.path.join(tmp, "out"))
            print(f"{label:15s} load {os.getloadavg()[0]:.1f}: {json.dumps(numbers)}", flush=True)


if __name__ == "__main__":
    main()
