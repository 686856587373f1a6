r"""
Measure the papers' weak-flux calibration factor of a built-in Sun at several latitudes.

Each latitude runs `gongsynth.simulate` once per seed and fits the papers'
quiet-Sun curve to the pooled runs (`gongsynth.weak_flux_factor`).  The
numbers in the issue-14 notes came from, e.g.::

    python scripts/weak_flux_factors.py --sun model-atmosphere --shape 1024 --latitudes 0 60 --seeds 1
    python scripts/weak_flux_factors.py --shape 1024 --latitudes 0 --seeds 1 --knobs '{"canopy": false}'
    python scripts/weak_flux_factors.py --sun milne-eddington --shape 256 --detector 430 \
        --knobs '{"spot": false}'

A 1024² model-atmosphere run takes 5-9 minutes on 2 cores (the radiative transfer).
"""
import argparse
import json
import time

import astropy.units as u

import gongsynth
from gongsynth.config import SUNS


def main(argv=None):
    """Run the sweep and print one line per latitude."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--sun", choices=tuple(SUNS), default="model-atmosphere")
    parser.add_argument("--shape", type=int, default=256, help="columns of the built-in Sun (square)")
    parser.add_argument("--detector", type=int, default=860, help="detector side in pixels")
    parser.add_argument("--latitudes", type=float, nargs="+", default=[0, 25, 45, 60, 70, 75])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--knobs", type=json.loads, default={},
                        help='JSON: [photosphere] knobs of the Sun, e.g. \'{"spot": false}\'')
    args = parser.parse_args(argv)
    for latitude in args.latitudes:
        start = time.perf_counter()
        results = [gongsynth.simulate(sun=args.sun, photosphere_shape=(args.shape, args.shape),
                                      detector_shape=args.detector, latitude=latitude * u.deg,
                                      duration=10 * u.min, seed=seed, photosphere=args.knobs, progress=False)
                   for seed in args.seeds]
        fit = gongsynth.weak_flux_factor(results, region="quiet")
        print(f"{args.sun} {args.shape}² {args.knobs or ''} latitude {latitude:4.0f} deg: "
              f"factor {fit.factor:.3f} ± {fit.uncertainty:.3f} "
              f"(seeds {args.seeds}, {time.perf_counter() - start:.0f} s)", flush=True)


if __name__ == "__main__":
    main()
