"""
Build the conversion table shipped with gongsynth (``gongsynth/data/cross_calibration_default.ecsv``).

What it runs (`gongsynth.cross_calibration_sweep.cross_calibration_table`):
the default built-in Sun (the 3-D model atmosphere through LTE radiative
transfer: a 98 Mm box with a sunspot in 256² columns of 384 km, the Sun of
the shipped calibration table) observed by GONG (its default: 10-minute
magnetogram, 2.5″ pixels), by HMI (its default: the 45-s magnetogram,
0.504″ pixels) and by MDI (its default: the 1-minute level-1.8 magnetogram,
1.986″ pixels), each on a detector covering the same 160″ field at the
papers' viewing latitudes 0, 25, 45, 60, 70 and 75 deg, with root seeds 1 and
2 (36 runs).  The magnetograms and their pixel-averaged truths are binned,
flux-preserving, onto common 10″ cells anchored at the field centre, where
`gongsynth.cross_calibrate` gives the OLS-bisector factor between the
instruments and from each to the truth (over all field strengths and in
groups of field strength), averaged over the seeds with their standard error.

How to regenerate it (about 10 minutes on 2 cores; longer on a busy machine)::

    python scripts/build_cross_calibration_table.py --overwrite [--cache DIR]

``--cache DIR`` keeps every run's maps (one float64 FITS file per run named
by a hash of the run's configuration and the gongsynth version:
`gongsynth.run_cache`), so an interrupted build resumes where it stopped,
with the same bits.  Same gongsynth version, same seeds: the same
numbers, bit for bit (only the ``created`` date in the metadata differs).
"""
import argparse
from pathlib import Path

import astropy.units as u
import numpy as np

from gongsynth.analysis.calibration_table import TABLE_LATITUDES, write_calibration_table
from gongsynth.analysis.cross_calibration_table import DEFAULT_CROSS_TABLE
from gongsynth.cross_calibration_sweep import cross_calibration_table
from gongsynth.version import git_commit

SEEDS = (1, 2)
INSTRUMENTS = ("gong", "hmi", "mdi")


def main(argv=None):
    """Build the table and write it (refusing to overwrite unless asked)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--out", type=Path,
                        default=Path(__file__).resolve().parents[1] / "gongsynth" / "data"
                        / DEFAULT_CROSS_TABLE)
    parser.add_argument("--overwrite", action="store_true")
    parser.add_argument("--cache", type=Path, help="folder for the runs' maps (resumable build)")
    args = parser.parse_args(argv)
    table = cross_calibration_table(INSTRUMENTS, TABLE_LATITUDES, seeds=SEEDS, cache=args.cache,
                                    progress=True)
    # An editable install's version string does not follow later commits: record the commit too.
    commit = git_commit()
    if commit:
        table.meta["git_commit"] = commit
    write_calibration_table(table, args.out, overwrite=args.overwrite)
    every = (table["strength_min"] == 0 * u.G) & np.isinf(table["strength_max"])
    for row in table[every]:
        print(f"{row['latitude'].to_value(u.deg):4.0f} deg  {row['instrument']:4s} -> {row['target']:5s} "
              f"factor {row['factor']:.3f} +- {row['uncertainty']:.3f} (fit {row['fit_uncertainty']:.3f})  "
              f"flux ratio {row['flux_ratio']:.3f}  ({row['n_pixels']} cells)")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
