r"""
Measure the papers' weak-flux calibration factor of a built-in Sun at several latitudes.

Each latitude runs `gongsynth.simulate` once per seed and fits the papers'
quiet-Sun curve to the pooled runs (`gongsynth.weak_flux_factor`).  The
numbers in the issue-14 notes came from, e.g.::

    python scripts/weak_flux_factors.py --sun model-atmosphere --shape 1024 --latitudes 0 60 --seeds 1
    python scripts/weak_flux_factors.py --shape 1024 --latitudes 0 --seeds 1 --knobs '{"canopy": false}'
    python scripts/weak_flux_factors.py --shape 1024 --latitudes 60 --seeds 1 --rays vertical
    python scripts/weak_flux_factors.py --sun milne-eddington --shape 256 --detector 430 \
        --knobs '{"spot": false}'

A 1024² model-atmosphere run takes 5-9 minutes on 2 cores (the radiative transfer).
"""
import argparse
import json
import time

import astropy.units as u
import numpy as np

import gongsynth
from gongsynth.config import SUNS, SimulationConfig
from gongsynth.geometry import Pointing
from gongsynth.seeding import child_sequence


def run(args, latitude, seed):
    """One simulation; with vertical rays the same atmosphere is synthesised column by column."""
    settings = dict(sun=args.sun, photosphere_shape=(args.shape, args.shape), detector_shape=args.detector,
                    photosphere_pixel_size=args.pixel * u.km, latitude=latitude, duration=10 * u.min,
                    seed=seed, photosphere=args.knobs, effects=args.effects)
    if args.rays == "inclined":
        return gongsynth.simulate(**settings, progress=False)
    if args.sun != "model-atmosphere":
        raise SystemExit("--rays vertical needs --sun model-atmosphere")
    config = SimulationConfig.from_arguments(**settings)
    atmosphere = SUNS[config.sun](seed=child_sequence(config.seed, "photosphere"), **config.sun_arguments())
    pointing = Pointing(config.latitude, config.obstime)
    cube = gongsynth.rt.synthesize(atmosphere, mu=pointing.mu, azimuth=pointing.los_azimuth, rays="vertical",
                                   progress=False)
    for name in ("sun", "photosphere_shape", "photosphere_pixel_size", "photosphere"):
        settings.pop(name)
    return gongsynth.simulate(cube, **settings, progress=False)


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
    parser.add_argument("--effects", type=json.loads, default={},
                        help='JSON: effects to switch off, e.g. \'{"psf": false, "seeing": false}\'')
    parser.add_argument("--pixel", type=float, default=96.0, help="column spacing of the built-in Sun (km)")
    parser.add_argument("--rays", choices=("inclined", "vertical"), default="inclined",
                        help="model atmosphere: rays through the 3-D box, or each column alone (ablation)")
    parser.add_argument("--record", help="append one JSON line per latitude to this file")
    args = parser.parse_args(argv)
    for latitude in args.latitudes:
        start = time.perf_counter()
        results = [run(args, latitude * u.deg, seed) for seed in args.seeds]
        fit = gongsynth.weak_flux_factor(results, region="quiet")
        # The seed-to-seed scatter (a different Sun each time) is the honest
        # uncertainty; the pooled fit's bootstrap only sees pixel noise.
        per_seed = [gongsynth.weak_flux_factor(r, region="quiet").factor for r in results]
        scatter = np.std(per_seed, ddof=1) / np.sqrt(len(per_seed)) if len(per_seed) > 1 else np.nan
        seconds = time.perf_counter() - start
        print(f"{args.sun} {args.shape}² {args.pixel:g} km {args.knobs or ''} {args.effects or ''} "
              f"{args.rays} latitude {latitude:4.0f} deg: "
              f"factor {fit.factor:.3f} ± {fit.uncertainty:.3f} (pooled), "
              f"per seed {', '.join(f'{f:.3f}' for f in per_seed)}, "
              f"mean {np.mean(per_seed):.3f} ± {scatter:.3f} "
              f"(seeds {args.seeds}, {seconds:.0f} s)", flush=True)
        if args.record:
            with open(args.record, "a") as record:
                record.write(json.dumps({
                    "sun": args.sun, "rays": args.rays, "shape": args.shape, "pixel_km": args.pixel,
                    "detector": args.detector, "knobs": args.knobs, "effects": args.effects,
                    "latitude": latitude, "seeds": args.seeds, "pooled": fit.factor,
                    "pooled_uncertainty": fit.uncertainty, "per_seed": per_seed,
                    "seconds": seconds, "version": gongsynth.__version__}) + "\n")


if __name__ == "__main__":
    main()
