"""
Build the calibration table shipped with gongsynth (``gongsynth/data/calibration_default.ecsv``).

What it runs: the default `gongsynth.simulate` configuration (the built-in
3-D model Sun through LTE radiative transfer: a 98 Mm box with a sunspot in
256² columns of 384 km; GONG's 860 x 860 detector, 10-minute integrations,
blocks camera engine) at the papers' viewing latitudes 0, 25, 45, 60, 70 and
75 deg, each with root seeds 1 and 2, and fits the papers' quiet-Sun and
sunspot curves (`gongsynth.calibration_sweep.build_calibration_table`, 50
bootstrap resamples).

How to regenerate it (about 15 minutes on 2 cores)::

    python scripts/build_default_calibration_table.py --overwrite

Same gongsynth version, same seeds: the same numbers, bit for bit (only the
``created`` date in the metadata differs), whatever the number of workers.
``--cache DIR`` keeps every run (one FITS file each, `gongsynth.run_cache`):
started again after an interruption, the build simulates only what is
missing.  ``--workers N`` runs N local Dask processes; ``--scheduler ADDRESS``
(or a scheduler file) runs on a cluster already started, e.g. by dask-jobqueue
(see the calibration guide; the cache must then be on a shared file system).  ``--sun milne-eddington`` builds
the table of the Milne-Eddington toy Sun instead (the table shipped before the
3-D Sun became the default).
"""
import argparse
import subprocess
from pathlib import Path

import astropy.units as u

from gongsynth.analysis.calibration_table import DEFAULT_TABLE, TABLE_LATITUDES, write_calibration_table
from gongsynth.calibration_sweep import build_calibration_table

SEEDS = (1, 2)


def main(argv=None):
    """Build the table and write it (refusing to overwrite unless asked)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--out", type=Path,
                        default=Path(__file__).resolve().parents[1] / "gongsynth" / "data" / DEFAULT_TABLE)
    parser.add_argument("--overwrite", action="store_true")
    parser.add_argument("--sun", choices=("model-atmosphere", "milne-eddington"), default="model-atmosphere")
    parser.add_argument("--cache", type=Path, help="folder of the finished runs (resumable build)")
    parser.add_argument("--workers", type=int, help="local Dask worker processes")
    parser.add_argument("--scheduler", help="address or scheduler file of a running Dask cluster")
    args = parser.parse_args(argv)
    client = None
    if args.scheduler:
        from dask.distributed import Client

        client = (Client(scheduler_file=args.scheduler) if Path(args.scheduler).is_file()
                  else Client(args.scheduler))
    table = build_calibration_table(TABLE_LATITUDES, seeds=SEEDS, n_boot=50, progress=True, sun=args.sun,
                                    cache=args.cache, workers=args.workers, client=client)
    # An editable install's version string does not follow later commits: record the commit too.
    here = Path(__file__).resolve().parent
    commit = subprocess.run(["git", "describe", "--always", "--dirty"], cwd=here, capture_output=True,
                            text=True).stdout.strip()
    if commit:
        table.meta["git_commit"] = commit
    write_calibration_table(table, args.out, overwrite=args.overwrite)
    for row in table:
        print(f"{row['latitude'].to_value(u.deg):4.0f} deg  {row['region']:8s} "
              f"factor {row['factor']:.3f} +- {row['uncertainty']:.3f}  ({row['n_pixels']} px)")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
