"""
Build the calibration tables shipped with gongsynth (``gongsynth/data/calibration_*.ecsv``).

What it runs: the default `gongsynth.simulate` configuration (the built-in
3-D model Sun through LTE radiative transfer: a 98 Mm box with a sunspot;
the instrument's detector, 10-minute integrations, blocks camera engine) at
the papers' viewing latitudes 0, 25, 45, 60, 70 and 75 deg, each with every
root seed, and fits the papers' quiet-Sun and sunspot curves
(`gongsynth.calibration_sweep.build_calibration_table`, 50 bootstrap
resamples).  Two grids of the Sun's columns:

- ``--grid paper`` (default): 1024² columns of 96 km, the papers' resolution
  (Rempel's run at 48 km binned ×2), seeds 1 2 3 4.  24 runs per
  instrument: 19-25 minutes of wall with ``--workers 2`` on two cores (the
  tables rebuilt with the network, 2026-11).
- ``--grid run``: 256² columns of 384 km (`gongsynth.simulate`'s default),
  seeds 1 2.  About 1 CPU-minute per run, 12 runs: ~15 minutes on 2 cores.

The factor and the curves are the fit pooled over the seeds; ``uncertainty``
is the statistical uncertainty from the seeds' scatter and the bootstrap
(`gongsynth.analysis.calibration_table.seed_uncertainty`); ``systematic`` the
band of the Sun-model ensemble of the same instrument (``--ensemble``,
default ``docs/guide/sun_ensemble_weak_flux.ecsv`` for GONG and
``docs/guide/sun_ensemble_weak_flux_hmi.ecsv`` for HMI: 256² runs at the six
angles, made by ``scripts/sun_ensemble.py``; members ``--members``, by
default those the guide's sun_ensemble page accepts; rule in
`gongsynth.analysis.calibration_table.SYSTEMATIC_RULE`).  The metadata name
the ensemble's instrument, grid and seeds.

Default output: ``calibration_default.ecsv`` (GONG, paper grid),
``calibration_run_grid.ecsv`` (GONG, run grid), ``calibration_hmi.ecsv``
(HMI, paper grid), ``calibration_hmi_run_grid.ecsv`` (HMI, run grid).

``--systematic-only TABLE`` fits nothing: it (re)computes the ``systematic``
column of a table already built, from the instrument's ensemble (how the
shipped tables got their per-angle bands once the ensembles were run).

How to regenerate the shipped tables from a cache of the runs (nothing is
simulated when the cache holds them all; ``--check-cache`` only lists what is
cached and what is missing)::

    python scripts/build_default_calibration_table.py --grid run --cache RUNS-256 --overwrite
    python scripts/build_default_calibration_table.py --instrument hmi --cache RUNS-1024 --overwrite
    python scripts/build_default_calibration_table.py --instrument gong --cache RUNS-1024 --overwrite \
        --rst docs/guide/calibration_tables.txt \
        --compare "run grid=gongsynth/data/calibration_run_grid.ecsv" \
                  "HMI, paper grid=gongsynth/data/calibration_hmi.ecsv"

(the last writes the guide's table of the quiet-Sun factors; leave out a
``--compare`` table not built yet).  The shipped tables of issue 24 were fitted
with ``--no-systematic`` and then given their bands without refitting::

    python scripts/build_default_calibration_table.py --instrument hmi --systematic-only TABLE \
        --out gongsynth/data/calibration_hmi.ecsv --overwrite
    python scripts/build_default_calibration_table.py --grid run --systematic-only TABLE \
        --out gongsynth/data/calibration_run_grid.ecsv --overwrite
    python scripts/build_default_calibration_table.py --systematic-only TABLE \
        --out gongsynth/data/calibration_default.ecsv --overwrite --rst docs/guide/calibration_tables.txt \
        --compare "run grid=gongsynth/data/calibration_run_grid.ecsv" \
                  "HMI, paper grid=gongsynth/data/calibration_hmi.ecsv" \
                  "MDI, paper grid=gongsynth/data/calibration_mdi.ecsv"

(MDI's table as HMI's, with ``--instrument mdi``; the tables of the Sun with
its network were made so, with ``--workers 2``.)  Same gongsynth version,
same seeds: the same numbers, bit for bit (only the ``created`` date in the
metadata differs), whatever the number of workers.
``--cache DIR`` keeps every run (one FITS file each, `gongsynth.run_cache`,
named by a hash of its configuration and the gongsynth version): started
again after an interruption, the build simulates only what is missing.
``--workers N`` runs N local Dask processes; ``--scheduler ADDRESS`` (or a
scheduler file) runs on a cluster already started, e.g. by dask-jobqueue (see
the calibration guide; the cache must then be on a shared file system).
``--sun milne-eddington`` builds the table of the Milne-Eddington toy Sun
instead (the table shipped before the 3-D Sun became the default).
"""
import argparse
import sys
from pathlib import Path

import astropy.units as u
import numpy as np
from astropy.table import QTable

from gongsynth.analysis.calibration_table import (
    TABLE_LATITUDES,
    add_systematic,
    read_calibration_table,
    write_calibration_table,
)
from gongsynth.calibration_sweep import build_calibration_table, sweep_configs
from gongsynth.run_cache import entry_path, run_config

ROOT = Path(__file__).resolve().parents[1]

#: The two grids: Sun columns, their size, and the seeds.
GRIDS = {
    "paper": {"columns": 1024, "column_size": 96 * u.km, "seeds": (1, 2, 3, 4)},
    "run": {"columns": 256, "column_size": 384 * u.km, "seeds": (1, 2)},
}

#: The ensemble members within their observational constraints (docs/guide/sun_ensemble.rst, "What the
#: constraints allow"): plage-elements (within everything), large-umbra, and small-spot on the edge of
#: the umbral-area range like the default; maltby-e-umbra is excluded (Wilson depression, umbral area).
MEMBERS = ("plage-elements", "large-umbra", "small-spot")

#: Each instrument's ensemble table (``scripts/sun_ensemble.py --weak-flux``).
ENSEMBLES = {"gong": ROOT / "docs" / "guide" / "sun_ensemble_weak_flux.ecsv",
             "hmi": ROOT / "docs" / "guide" / "sun_ensemble_weak_flux_hmi.ecsv",
             "mdi": ROOT / "docs" / "guide" / "sun_ensemble_weak_flux_mdi.ecsv"}

#: Paper III's statement on the quiet-Sun factor (more than 2 at disk centre, about 1 near the limb).
PAPER_III = {0.0: "> 2", 75.0: "≈ 1"}


def _cell(row, table):
    """'factor ± stat ± sys' of a quiet-Sun row (the parts a table has)."""
    text = f"{row['factor']:.3f} ± {row['uncertainty']:.3f}"
    if "systematic" in table.colnames and np.isfinite(row["systematic"]):
        text += f" ± {row['systematic']:.3f}"
    return text


def tables_rst(tables):
    """
    An RST list-table of the quiet-Sun factors of several tables (label: table), beside paper III.

    Each cell is factor ± statistical (± systematic where the table has it).
    """
    def label(table):
        grid = table.meta.get("grid")
        seeds = ", ".join(map(str, table.meta.get("seeds", [])))
        where = (f"{grid['columns'][0]}² × {grid['column_size']}" if grid
                 else table.meta.get("input_sun", "grid not recorded"))
        return f"{table.meta.get('instrument_name', 'gong').upper()}, {where}, seeds {seeds}"

    lines = [".. list-table:: Quiet-Sun weak-flux factor: factor ± statistical ± systematic",
             "   :header-rows: 1", "", "   * - latitude"]
    lines += [f"     - {name} ({label(table)})" for name, table in tables.items()]
    lines += ["     - paper III"]
    quiet = {name: table[np.asarray(table["region"]) == "quiet"] for name, table in tables.items()}
    first = next(iter(quiet.values()))
    for latitude in first["latitude"].to_value(u.deg):
        lines.append(f"   * - {latitude:.0f}°")
        for name, rows in quiet.items():
            match = np.isclose(rows["latitude"].to_value(u.deg), latitude)
            lines.append(f"     - {_cell(rows[match][0], tables[name]) if match.any() else '—'}")
        lines.append(f"     - {PAPER_III.get(float(latitude), '—')}")
    return "\n".join(lines) + "\n"


def default_out(instrument, grid):
    """The shipped file of an instrument's table on a grid."""
    name = "calibration_" + ("default" if instrument == "gong" else instrument)
    if grid == "run":
        name = "calibration_run_grid" if instrument == "gong" else f"{name}_run_grid"
    return ROOT / "gongsynth" / "data" / f"{name}.ecsv"


def _arguments(args):
    """The `build_calibration_table` keywords of the command line (only what differs from a plain run)."""
    grid = GRIDS[args.grid]
    kwargs = {"instrument": args.instrument, "photosphere_shape": (args.columns or grid["columns"],) * 2,
              "photosphere_pixel_size": (args.column_size or grid["column_size"].value) * u.km}
    if args.sun is not None:
        kwargs["sun"] = args.sun
    return kwargs


def main(argv=None):
    """Build the table and write it (refusing to overwrite unless asked)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--instrument", choices=("gong", "hmi", "mdi"), default="gong")
    parser.add_argument("--grid", choices=sorted(GRIDS), default="paper")
    parser.add_argument("--columns", type=int, help="Sun columns per side (default: the grid's)")
    parser.add_argument("--column-size", type=float, help="column size in km (default: the grid's)")
    parser.add_argument("--seeds", type=int, nargs="+", help="root seeds (default: the grid's)")
    parser.add_argument("--latitudes", type=float, nargs="+", help="latitudes (deg); default the papers' six")
    parser.add_argument("--n-boot", type=int, default=50)
    parser.add_argument("--out", type=Path, help="output ECSV (default: the shipped file)")
    parser.add_argument("--overwrite", action="store_true")
    parser.add_argument("--sun", choices=("model-atmosphere", "milne-eddington"))
    parser.add_argument("--ensemble", type=Path,
                        help="ensemble weak-flux table (ECSV; default: the instrument's, ENSEMBLES)")
    parser.add_argument("--members", nargs="+", default=list(MEMBERS), help="accepted ensemble members")
    parser.add_argument("--no-systematic", action="store_true", help="leave out the systematic column")
    parser.add_argument("--systematic-only", type=Path, metavar="TABLE",
                        help="fit nothing: (re)write the systematic column of this built table from the "
                             "ensemble (to --out, default the table itself)")
    parser.add_argument("--cache", type=Path, help="folder of the finished runs (resumable build)")
    parser.add_argument("--check-cache", action="store_true",
                        help="only list the runs the cache holds and those missing; simulate nothing")
    parser.add_argument("--rst", type=Path, help="also write the quiet-Sun factors as an RST list-table here")
    parser.add_argument("--compare", nargs="+", default=[], metavar="LABEL=TABLE",
                        help="tables to show beside the new one in --rst")
    parser.add_argument("--label", help="the new table's column heading in --rst (default: '<grid> grid')")
    parser.add_argument("--workers", type=int, help="local Dask worker processes")
    parser.add_argument("--scheduler", help="address or scheduler file of a running Dask cluster")
    args = parser.parse_args(argv)
    seeds = tuple(args.seeds or GRIDS[args.grid]["seeds"])
    latitudes = TABLE_LATITUDES if args.latitudes is None else args.latitudes * u.deg
    kwargs = _arguments(args)
    if args.check_cache:
        if args.cache is None:
            parser.error("--check-cache needs --cache")
        missing = 0
        for config in sweep_configs(latitudes, seeds, **kwargs):
            path = entry_path(args.cache, run_config(config))
            missing += not path.exists()
            print(f"{'cached ' if path.exists() else 'MISSING'} {path.name}")
        print(f"{missing} of {len(latitudes) * len(seeds)} runs missing")
        return 1 if missing else 0
    out = args.out or args.systematic_only or default_out(args.instrument, args.grid)
    if out.exists() and not args.overwrite:
        parser.error(f"{out} exists: pass --overwrite to replace it")
    args.ensemble = args.ensemble or ENSEMBLES.get(args.instrument)
    if args.ensemble is None and not args.no_systematic:
        parser.error(f"{args.instrument.upper()} has no Sun-model ensemble yet: pass --ensemble TABLE or "
                     f"--no-systematic")
    changes = None if args.no_systematic else QTable.read(args.ensemble, format="ascii.ecsv")
    if changes is not None and changes.meta.get("instrument", "gong") != args.instrument:
        parser.error(f"--ensemble {args.ensemble} is a {changes.meta.get('instrument', 'gong').upper()} "
                     f"ensemble, not {args.instrument.upper()}'s")
    client = None
    if args.scheduler:
        from dask.distributed import Client

        client = (Client(scheduler_file=args.scheduler) if Path(args.scheduler).is_file()
                  else Client(args.scheduler))
    if args.systematic_only:
        table = read_calibration_table(args.systematic_only)
        table.meta.pop("source", None)  # read_calibration_table's note of the file read, not a property
        if table.meta.get("instrument_name", "gong") != args.instrument:
            parser.error(f"--systematic-only {args.systematic_only} is not a {args.instrument.upper()} table")
    else:
        table = build_calibration_table(latitudes, seeds=seeds, n_boot=args.n_boot, progress=True,
                                        cache=args.cache, workers=args.workers, client=client, **kwargs)
    if changes is not None:
        latitudes = " ".join(f"{x:g}" for x in sorted(set(changes["latitude"].to_value(u.deg))))
        source = (f"{args.ensemble.name}: {args.instrument.upper()} quiet-Sun factor, 256^2 columns of "
                  f"384 km, latitudes {latitudes} deg, seeds {list(changes.meta.get('seeds', []))}, "
                  f"gongsynth {changes.meta.get('gongsynth_version')}")
        add_systematic(table, changes, args.members, source=source)
    write_calibration_table(table, out, overwrite=args.overwrite)
    if args.rst:
        others = dict(item.split("=", 1) for item in args.compare)
        tables = {args.label or f"{args.grid} grid": table}
        tables |= {name: read_calibration_table(path) for name, path in others.items()}
        args.rst.write_text(tables_rst(tables))
        print(f"wrote {args.rst}")
    for row in table:
        systematic = f" +- {row['systematic']:.3f} (sys)" if "systematic" in table.colnames else ""
        print(f"{row['latitude'].to_value(u.deg):4.0f} deg  {row['region']:8s} "
              f"factor {row['factor']:.3f} +- {row['uncertainty']:.3f} (stat){systematic}  "
              f"seeds {row['seed_factors'].round(3).tolist()}  bootstrap {row['bootstrap']:.4f}  "
              f"({row['n_pixels']} px)")
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
