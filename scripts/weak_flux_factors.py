r"""
Measure the papers' weak-flux calibration factor of a built-in Sun at several latitudes, and ablations.

Each latitude runs `gongsynth.simulate` once per seed; the factor is the
papers' quiet-Sun estimator (`gongsynth.weak_flux_factor`) per seed (their
mean and standard error: a different Sun each seed) and pooled over the seeds.
``--ablate`` also runs each ablation of the 3-D Sun with the same seeds and
reports its paired change (`gongsynth.analysis.weak_flux.weak_flux_factor_difference`).
The issue-14 numbers came from::

    python scripts/weak_flux_factors.py --seeds 1 2 3 --record factors.jsonl       # the default run's grid
    python scripts/weak_flux_factors.py --latitudes 0 60 --seeds 1 2 3 --ablate --record ablation.jsonl
    python scripts/weak_flux_factors.py --shape 1024 --pixel 96 --latitudes 0 60 --seeds 1 2
    python scripts/weak_flux_factors.py --sun milne-eddington --latitudes 0 60 --seeds 1 2
    python scripts/weak_flux_factors.py --summarise factors.jsonl ... \
        --out gongsynth/data/weak_flux_factors.ecsv

A run of the default grid (256² columns of 384 km) takes 30-60 s on 2 cores;
1024² columns of 96 km take 4-9 minutes (the radiative transfer).
"""
import argparse
import datetime
import json
import time
from pathlib import Path

import astropy.units as u
import numpy as np
from astropy.table import QTable

import gongsynth
from gongsynth.analysis.weak_flux import weak_flux_factor_difference
from gongsynth.config import Effects, SimulationConfig
from gongsynth.geometry import Pointing
from gongsynth.seeding import child_sequence
from gongsynth.suns import SUNS
from gongsynth.version import git_commit

#: What each ablation of the 3-D Sun switches off: [photosphere] knobs, instrument effects, or the rays.
ABLATIONS = {
    "no line weakening (kG elements at quiet-Sun temperature)": {"knobs": {"element_model": "quiet"}},
    "no Wilson depression": {"knobs": {"element_depression": False}},
    "no canopy (elements keep their width with height)": {"knobs": {"canopy": False}},
    "vertical rays only (each column alone)": {"rays": "vertical"},
    "no sunspot": {"knobs": {"spot": False}},
    "no blur (PSF and seeing off)": {"effects": {"psf": False, "seeing": False}},
}


def run(args, latitude, seed, *, knobs=None, effects=None, rays="inclined"):
    """One simulation; with vertical rays the same atmosphere is synthesised column by column."""
    settings = dict(sun=args.sun, detector_shape=args.detector, latitude=latitude, duration=10 * u.min,
                    seed=seed, photosphere={**args.knobs, **(knobs or {})},
                    effects=Effects(**{**args.effects, **(effects or {})}))
    if args.shape is not None:
        settings["photosphere_shape"] = (args.shape, args.shape)
    if args.pixel is not None:
        settings["photosphere_pixel_size"] = args.pixel * u.km
    if rays == "inclined":
        return gongsynth.simulate(**settings, progress=False)
    if args.sun != "model-atmosphere":
        raise SystemExit("vertical rays need --sun model-atmosphere")
    config = SimulationConfig.from_arguments(**settings)
    atmosphere = SUNS[config.sun](seed=child_sequence(config.seed, "photosphere"), **config.sun_arguments())
    pointing = Pointing(config.latitude, config.obstime)
    cube = gongsynth.rt.synthesize(atmosphere, mu=pointing.mu, azimuth=pointing.los_azimuth, rays="vertical",
                                   progress=False)
    for name in ("sun", "photosphere_shape", "photosphere_pixel_size", "photosphere"):
        settings.pop(name, None)
    return gongsynth.simulate(cube, **settings, progress=False)


def factors(label, latitude, results, args, seconds, baseline=None):
    """Print and return the record of one set of runs (and its paired change from ``baseline``)."""
    fit = gongsynth.weak_flux_factor(results, region="quiet")
    # The seed-to-seed scatter (a different Sun each time) is the honest
    # uncertainty; the pooled fit's bootstrap only sees pixel noise.
    per_seed = [gongsynth.weak_flux_factor(r, region="quiet").factor for r in results]
    scatter = float(np.std(per_seed, ddof=1) / np.sqrt(len(per_seed))) if len(per_seed) > 1 else float("nan")
    config = results[0].config
    record = {"label": label, "sun": config.sun, "shape": list(config.photosphere_shape),
              "pixel_km": float(config.photosphere_pixel_size.to_value(u.km)), "detector": args.detector,
              "latitude": latitude, "seeds": args.seeds, "per_seed": per_seed,
              "mean": float(np.mean(per_seed)), "standard_error": scatter, "pooled": fit.factor,
              "pooled_uncertainty": fit.uncertainty, "seconds": seconds}
    line = (f"{label:58s} {latitude:4.0f} deg: per seed {', '.join(f'{f:.3f}' for f in per_seed)}; "
            f"mean {record['mean']:.3f} ± {scatter:.3f}; pooled {fit.factor:.3f} ± {fit.uncertainty:.3f}")
    if baseline is not None:
        change, error = weak_flux_factor_difference(baseline, results)
        record.update(change=change, change_uncertainty=error)
        line += f"; change {change:+.3f} ± {error:.3f} (paired)"
    print(f"{line} ({seconds:.0f} s)", flush=True)
    return record


def summarise(paths, out):
    """One QTable of the recorded factors (ECSV, with provenance), for the docs and the gallery."""
    records, seen = [], set()
    for line in (line for path in paths for line in Path(path).read_text().splitlines() if line):
        record = json.loads(line)
        # An ablation sweep repeats its baseline: keep one row of each set of runs.
        key = (record["label"], record["latitude"], tuple(record["shape"]), record["pixel_km"],
               tuple(record["per_seed"]), record.get("change"))
        if key not in seen:
            seen.add(key)
            records.append(record)
    table = QTable()
    table["label"] = [r["label"] for r in records]
    table["sun"] = [r["sun"] for r in records]
    table["columns"] = [r["shape"][0] for r in records]
    table["column_size"] = [r["pixel_km"] for r in records] * u.km
    table["latitude"] = [r["latitude"] for r in records] * u.deg
    table["n_seeds"] = [len(r["seeds"]) for r in records]
    table["factor"] = [r["mean"] for r in records]
    table["uncertainty"] = [r["standard_error"] for r in records]
    table["pooled"] = [r["pooled"] for r in records]
    table["change"] = [r.get("change", np.nan) for r in records]
    table["change_uncertainty"] = [r.get("change_uncertainty", np.nan) for r in records]
    table.meta.update({
        "description": "The papers' weak-flux factor (quiet Sun, truth through the PSF per GONG pixel) of "
                       "simulated 10-minute GONG runs (860 x 860 px): factor = mean over seeds, "
                       "uncertainty = standard error over seeds, pooled = one fit to all seeds' pixels, "
                       "change = paired change from the baseline run of the same seeds (ablations).",
        "script": "scripts/weak_flux_factors.py",
        "run_versions": sorted({r.get("version", "?") for r in records}),
        "summarised_at_commit": git_commit(),
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
    })
    table.write(out, format="ascii.ecsv", overwrite=True)
    print(table)


def main(argv=None):
    """Run the sweep (and ablations) and print one line per latitude and case."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--sun", choices=tuple(SUNS), default="model-atmosphere")
    parser.add_argument("--shape", type=int, help="columns of the built-in Sun (square; default: a run's)")
    parser.add_argument("--pixel", type=float, help="their spacing in km (default: a run's)")
    parser.add_argument("--detector", type=int, default=860, help="detector side in pixels")
    parser.add_argument("--latitudes", type=float, nargs="+", default=[0, 25, 45, 60, 70, 75])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--knobs", type=json.loads, default={},
                        help='JSON: [photosphere] knobs of the Sun, e.g. \'{"spot": false}\'')
    parser.add_argument("--effects", type=json.loads, default={},
                        help='JSON: effects to switch off, e.g. \'{"psf": false, "seeing": false}\'')
    parser.add_argument("--ablate", action="store_true", help="also run every ablation in ABLATIONS")
    parser.add_argument("--record", help="append one JSON line per latitude and case to this file")
    parser.add_argument("--summarise", nargs="+", metavar="JSONL", help="only write --out from these records")
    parser.add_argument("--out", help="the ECSV table written by --summarise")
    args = parser.parse_args(argv)
    if args.summarise:
        return summarise(args.summarise, args.out)
    label = " ".join([args.sun] + [json.dumps(extra) for extra in (args.knobs, args.effects) if extra])
    for latitude in args.latitudes:
        start = time.perf_counter()
        baseline = [run(args, latitude * u.deg, seed) for seed in args.seeds]
        records = [factors(label, latitude, baseline, args, time.perf_counter() - start)]
        for name, change in (ABLATIONS.items() if args.ablate else ()):
            start = time.perf_counter()
            ablated = [run(args, latitude * u.deg, seed, **change) for seed in args.seeds]
            records.append(factors(name, latitude, ablated, args, time.perf_counter() - start, baseline))
            del ablated
        if args.record:
            with open(args.record, "a") as record:
                for entry in records:
                    record.write(json.dumps({**entry, "version": gongsynth.__version__}) + "\n")


if __name__ == "__main__":
    main()
