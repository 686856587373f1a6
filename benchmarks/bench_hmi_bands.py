"""
The optics of a full-disk HMI light made by bands: the rows made a band ahead on a thread, or in line.

A full-disk HMI scene (3-D Sun's library, cached; seed 1, the real HMI map's date) at ``--shape``²
detector pixels is forced into bands (`gongsynth.stages.scene.disk_render.LIGHT_BYTES` set below its
light) and imaged by `gongsynth.stages.optics.image_scene`: the render of the light and truth, the
banded transforms, the truth after them.  The two ways, in one process and interleaved, ``--repeats``
times each: the rows made ahead (`gongsynth.stages.imagers.made_ahead`, the default) and made in line
(the same calls, one after the other, on the calling thread).  Printed per way: min and median of the
wall and CPU seconds, and whether the expected counts and truth have the same bits; the load average.

    python benchmarks/bench_hmi_bands.py [--shape 2048] [--repeats 3]
"""
import argparse
import os
import statistics
import time

import numpy as np

from gongsynth import instruments
from gongsynth.stages import imagers
from gongsynth.stages.optics import image_scene
from gongsynth.stages.scene import disk_render
from gongsynth.stages.scene.library import LIBRARY_SEED, cached_library


def in_line(make, ranges, ahead):
    """`imagers.made_ahead` without the thread: the same calls, in order, on the caller's thread."""
    for start, stop in ranges:
        yield make(start, stop)


def one(library, inst, shape):
    light, truth = disk_render.library_scene(library, instrument=inst, detector_shape=shape, seed=1,
                                             obstime="2010-10-20T00:00")
    return image_scene(light, truth, inst)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--shape", type=int, default=2048)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    inst = instruments.get("hmi")
    library = cached_library(seed=LIBRARY_SEED, knobs={}, instrument=inst, sun="model-atmosphere")
    disk_render.LIGHT_BYTES = 2**20     # every grid by bands
    ahead = imagers.made_ahead
    times, results = {"ahead": [], "in line": []}, {}
    one(library, inst, 256)             # compile / warm
    for _ in range(args.repeats):
        for way, maker in (("ahead", ahead), ("in line", in_line)):
            imagers.made_ahead = maker
            wall, cpu = time.perf_counter(), time.process_time()
            counts, truth, truth_psf = one(library, inst, args.shape)
            times[way].append((time.perf_counter() - wall, time.process_time() - cpu))
            results[way] = [np.asarray(x.value) for x in (counts, truth, truth_psf)]
    imagers.made_ahead = ahead
    same = all(np.array_equal(a, b) for a, b in zip(results["ahead"], results["in line"]))
    for way, pairs in times.items():
        walls, cpus = [p[0] for p in pairs], [p[1] for p in pairs]
        print(f"{way:8s} wall min {min(walls):.1f} s median {statistics.median(walls):.1f} s, "
              f"CPU min {min(cpus):.1f} s median {statistics.median(cpus):.1f} s")
    print(f"same bits: {same}; {args.shape}² detector, load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
