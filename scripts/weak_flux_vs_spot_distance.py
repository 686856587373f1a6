r"""
Measure the weak-flux factor of the quiet Sun against the distance from the sunspot (issue 24, item 3).

The question: does the papers' quiet-Sun factor (`gongsynth.weak_flux_factor`)
depend on where the pixels lie with respect to strong fields?  The ablation in
``gongsynth/data/weak_flux_factors.ecsv`` says the sunspot sets most of the
disk-centre factor (1.25 with it, 0.94 without), through its light and flux
spread by the blur, so a dependence on the distance from the spot is expected;
if it is larger than the uncertainties, one angle-only number describes one
scene, not the Sun.

What it runs: the shipped table's configuration (the default
`gongsynth.simulate`: the 3-D model Sun, 256² columns of 384 km with its
sunspot; GONG 860², 10 minutes) at one latitude, for several seeds, through
`gongsynth.run_cache.cached_runs` (resumable with ``--cache``, parallel with
``--workers``).  For every run the authors' sunspot mask (continuum at GONG's
resolution below 0.92 of the quiet median, dilated by 17.5″:
`gongsynth.analysis.weak_flux.paper_regions`) gives each quiet-Sun pixel its
distance to the nearest sunspot pixel (Euclidean, in arcsec); the quiet pixels
are grouped by distance and the factor fitted in each group with the same
number of bins, pooled over the seeds (block bootstrap), and per seed (mean and
standard error of the seeds: a different Sun each seed).

    python scripts/weak_flux_vs_spot_distance.py --seeds 1 2 3 4 --workers 2 --cache runs \
        --out docs/guide/weak_flux_vs_spot_distance.ecsv
"""
import argparse
import dataclasses
import datetime
from pathlib import Path

import astropy.units as u
import numpy as np
import scipy.ndimage
import sunpy.map
from astropy.table import QTable

from gongsynth.analysis.weak_flux import paper_regions, weak_flux_factor
from gongsynth.config import SimulationConfig
from gongsynth.run_cache import cached_runs, run_config
from gongsynth.version import version

#: Distance groups (arcsec from the nearest sunspot-mask pixel); the box repeats every ~135″.
EDGES = (0, 15, 30, 50, 100)


def spot_distance(run):
    """Each pixel's distance (arcsec) to the nearest pixel of the authors' sunspot mask."""
    _, sunspot = paper_regions(run.magnetogram, run.continuum, latitude=run.config.latitude)
    pixel = abs(u.Quantity(run.magnetogram.scale.axis1).to_value(u.arcsec / u.pix))
    if not sunspot.any():
        raise ValueError("no sunspot in the run: nothing to measure the distance from")
    return scipy.ndimage.distance_transform_edt(~sunspot) * pixel


def in_group(run, distance, low, high):
    """The run with its truth kept only at distances in [low, high) (the fit uses finite truth only)."""
    keep = (distance >= low) & (distance < high)
    truth_psf = sunpy.map.Map(np.where(keep, run.truth_psf.data, np.nan), run.truth_psf.meta)
    return dataclasses.replace(run, truth_psf=truth_psf)


def main(argv=None):
    """Run (or read from the cache), fit per distance group, print and write the table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--latitude", type=float, default=0.0, help="viewing latitude (deg)")
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3, 4])
    parser.add_argument("--bins", type=int, default=15, help="curve bins of every fit (same in each group)")
    parser.add_argument("--n-boot", type=int, default=100)
    parser.add_argument("--workers", type=int)
    parser.add_argument("--cache", type=Path)
    parser.add_argument("--out", type=Path)
    args = parser.parse_args(argv)

    base = SimulationConfig.from_arguments(latitude=args.latitude * u.deg)
    configs = [base.replace(seed=seed) for seed in args.seeds]
    runs = [None] * len(configs)
    for index, run in cached_runs(configs, cache=args.cache, workers=args.workers, desc="runs"):
        runs[index] = run
    distances = [spot_distance(run) for run in runs]

    groups = [(0, np.inf, "all quiet")] + [(lo, hi, f"{lo}-{hi}″") for lo, hi in zip(EDGES[:-1], EDGES[1:])]
    groups.append((EDGES[-1], np.inf, f">{EDGES[-1]}″"))
    rows = []
    for low, high, name in groups:
        members = [in_group(run, d, low, high) for run, d in zip(runs, distances)]
        try:
            pooled = weak_flux_factor(members, n_bins=args.bins, n_boot=args.n_boot)
            per_seed = [weak_flux_factor(m, n_bins=args.bins, n_boot=0).factor for m in members]
        except ValueError as exc:  # too few pixels for the bins
            print(f"{name:>10s}: {exc}")
            continue
        spread = float(np.std(per_seed, ddof=1) / np.sqrt(len(per_seed))) if len(per_seed) > 1 else np.nan
        rows.append(dict(group=name, low=low * u.arcsec, high=high * u.arcsec, n_pixels=pooled.n_pixels,
                         factor=pooled.factor, bootstrap=pooled.uncertainty,
                         seed_mean=float(np.mean(per_seed)), seed_error=spread))
        print(f"{name:>10s}: factor {pooled.factor:.3f} ± {pooled.uncertainty:.3f} (bootstrap), "
              f"seeds {np.mean(per_seed):.3f} ± {spread:.3f} [{', '.join(f'{f:.3f}' for f in per_seed)}], "
              f"{pooled.n_pixels} px")
    table = QTable(rows=rows)
    table.meta.update({
        "gongsynth_version": version, "latitude": f"{args.latitude} deg", "seeds": list(args.seeds),
        "bins": args.bins, "n_boot": args.n_boot,
        "config": run_config(base).to_toml(comments=False),
        "method": "quiet-Sun pixels (papers II/III) grouped by Euclidean distance to the nearest pixel "
                  "of the authors' sunspot mask; papers' flux-conserving fit per group with the same number "
                  "of bins; bootstrap = block bootstrap of the seeds pooled; seed_error = standard error of "
                  "the per-seed factors",
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
    })
    if args.out:
        table.write(args.out, format="ascii.ecsv", overwrite=True)
        print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
