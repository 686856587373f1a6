"""
Benchmark of the full-disk scene: the patch library against the old per-sample synthesis.

Times, in one process (ratios, not absolute times: the machines are shared):

1. the old path, `full_disk_scene` of a periodic photosphere (every sample's
   spectrum synthesised at its own μ and azimuth): on the full 4300² grid,
   or with ``--quick`` on a band of rows through the disk centre, extrapolated
   per on-disk sample;
2. the library: building it (`build_library`, what a run does once per
   machine), loading it from the disk cache, and rendering the scene
   (`full_disk_scene` of the library: rays, cells, levels, angles, Doppler
   basis) on the same grid;
3. with ``--runs``: whole ``simulate(mode="full-disk", duration=1 min)`` runs
   in fresh processes, with an empty and with a filled library cache, and
   their peak resident memory;
4. with ``--rt``: the 3-D Sun's library (`build_atmosphere_library`, the
   defaults: GONG's 768 km grid, ~10-30 s; the full disk's default Sun),
   against the Milne-Eddington build of step 2.

    python benchmarks/bench_fulldisk.py [--quick] [--runs] [--rt]
"""
import argparse
import os
import resource
import subprocess
import sys
import tempfile
import textwrap
import time

import astropy.units as u


def timed(function, *args, **kwargs):
    wall, cpu = time.perf_counter(), time.process_time()
    out = function(*args, **kwargs)
    return out, time.perf_counter() - wall, time.process_time() - cpu


def whole_run(cache, seed):
    """Wall time, stage times and peak RSS of one run in a fresh process."""
    code = textwrap.dedent(f"""
        import time, json
        start = time.perf_counter()
        import astropy.units as u, gongsynth
        r = gongsynth.simulate(mode="full-disk", duration=1 * u.min, seed={seed}, progress=False)
        # VmHWM: this process's own peak (ru_maxrss would carry the parent's over the fork).
        hwm = [line for line in open("/proc/self/status") if line.startswith("VmHWM")][0]
        print(json.dumps({{"total": time.perf_counter() - start, "stages": r.timings,
                          "peak_mb": int(hwm.split()[1]) / 1024}}))
    """)
    env = {**os.environ, "GONGSYNTH_CACHE_DIR": cache}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    import json
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--quick", action="store_true",
                        help="old path on 400 rows through the centre, extrapolated")
    parser.add_argument("--runs", action="store_true", help="also time whole runs in fresh processes")
    parser.add_argument("--rt", action="store_true", help="also build the 3-D Sun's library (~10-30 s)")
    args = parser.parse_args()

    import gongsynth
    from gongsynth.geometry import disk_geometry
    from gongsynth.stages.scene.fulldisk import full_disk_scene
    from gongsynth.stages.scene.library import LIBRARY_SEED, build_library, cached_library
    from gongsynth.sun.photosphere import model_photosphere

    inst = gongsynth.GONGInstrument()
    grid = inst.detector_shape * inst.supersampling
    on_disk = int(disk_geometry((grid, grid), inst.plate_scale / inst.supersampling).on_disk.sum())
    print(f"gongsynth {gongsynth.__version__}: full disk, {grid}² samples, {on_disk / 1e6:.2f} M on the "
          f"disk; load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")

    # -- the library: build (cold), save and load (the cache), render
    library, wall, cpu = timed(build_library, seed=LIBRARY_SEED, instrument=inst)
    print(f"library build        {wall:6.2f} s wall {cpu:6.2f} s cpu   {library}")
    me_build = wall
    if args.rt:
        from gongsynth.stages.scene.library_rt import build_atmosphere_library
        # compile the kernels first
        build_atmosphere_library(shape=(8, 8), pixel_size=3 * u.Mm, theta=(0, 60), knobs={"nz": 40})
        rt_library, wall, cpu = timed(build_atmosphere_library, seed=LIBRARY_SEED, instrument=inst)
        print(f"3-D library build    {wall:6.2f} s wall {cpu:6.2f} s cpu   {rt_library}  "
              f"({wall / me_build:.0f}x the Milne-Eddington build)")
        del rt_library
    with tempfile.TemporaryDirectory() as cache:
        os.environ["GONGSYNTH_CACHE_DIR"] = cache
        cached_library(seed=LIBRARY_SEED, instrument=inst)               # builds and saves
        from gongsynth.stages.scene import library as module
        module._MEMO.clear()
        loaded, wall, cpu = timed(cached_library, seed=LIBRARY_SEED, instrument=inst)
        print(f"library cache load   {wall:6.2f} s wall {cpu:6.2f} s cpu")
        full_disk_scene(library, detector_shape=16, supersampling=1)      # compile the kernel
        (light, _), wall_new, cpu_new = timed(full_disk_scene, loaded, obstime="2009-09-05T18:54:16")
        del light, loaded
    print(f"library scene        {wall_new:6.2f} s wall {cpu_new:6.2f} s cpu   "
          f"({1e9 * cpu_new / on_disk:.0f} ns cpu per on-disk sample)")

    # -- the old path: a periodic photosphere synthesised at every sample
    photosphere = model_photosphere(shape=(256, 256), pixel_size=384 * u.km, seed=1, spot=False)
    if args.quick:
        band = 400
        det = (band // inst.supersampling, inst.detector_shape)
        (_, _), wall, cpu = timed(full_disk_scene, photosphere, detector_shape=det)
        samples = int(disk_geometry((band, grid), inst.plate_scale / inst.supersampling).on_disk.sum())
        wall_old, cpu_old = wall * on_disk / samples, cpu * on_disk / samples
        what = f"(extrapolated from {samples / 1e6:.2f} M samples)"
    else:
        (_, _), wall_old, cpu_old = timed(full_disk_scene, photosphere)
        what = ""
    print(f"per-sample synthesis {wall_old:6.2f} s wall {cpu_old:6.2f} s cpu   {what}")
    print(f"scene speed-up: {wall_old / wall_new:.1f}x wall, {cpu_old / cpu_new:.1f}x cpu "
          f"(library render against per-sample synthesis, same grid and process)")
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak memory of this process (both paths) {peak:.0f} MB")

    if args.runs:
        with tempfile.TemporaryDirectory() as cache:
            for label in ("empty cache (library built)", "filled cache (library loaded)"):
                r = whole_run(cache, seed=1)
                stages = ", ".join(f"{k} {v:.1f}" for k, v in r["stages"].items())
                print(f"simulate full-disk 1 min, {label}: {r['total']:.1f} s, peak {r['peak_mb']:.0f} MB "
                      f"[{stages}]")


if __name__ == "__main__":
    main()
