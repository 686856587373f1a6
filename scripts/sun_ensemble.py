r"""
Measure the Sun-model ensemble against the observations, and each variant's weak-flux factor (issue 24).

Two parts, each optional:

``--constraints OUT.ecsv``
    For each variant (`gongsynth.sun.model_atmosphere.ensemble.VARIANTS`):
    `gongsynth.analysis.sun_constraints.sun_constraints` on a quiet box and a
    spot box (seeded); one table, a row per variant and constraint, with the
    observed value and accepted range beside each measured value.

``--weak-flux OUT.ecsv``
    For each variant, the default run of ``--instrument`` (GONG, HMI or MDI;
    `gongsynth.simulate`: 256² columns of 384 km, the instrument's detector
    and default duration) with the variant's ``[photosphere]``
    knobs at each latitude and seed, through `gongsynth.run_cache.cached_runs`
    (resumable with ``--cache``); the papers' quiet-Sun factor
    (`gongsynth.weak_flux_factor`) pooled over the seeds with its block
    bootstrap (the statistical part), the per-seed factors, and the paired
    change from the default Sun with the same seeds
    (`gongsynth.analysis.weak_flux.weak_flux_factor_difference`).  The
    systematic band is the spread of the variants that pass the constraints.

The numbers of ``docs/guide/sun_ensemble.rst`` came from::

    python scripts/sun_ensemble.py --rst --constraints docs/guide/sun_ensemble_constraints.ecsv
    python scripts/sun_ensemble.py --rst --weak-flux docs/guide/sun_ensemble_weak_flux.ecsv --cache runs \
        --latitudes 0 25 45 60 70 75 --variants default small-spot large-umbra plage-elements
    python scripts/sun_ensemble.py --rst --weak-flux docs/guide/sun_ensemble_weak_flux_hmi.ecsv --cache runs \
        --instrument hmi --seeds 1 2 --latitudes 0 25 45 60 70 75 \
        --variants default small-spot large-umbra plage-elements
    python scripts/sun_ensemble.py --rst --weak-flux docs/guide/sun_ensemble_weak_flux_mdi.ecsv --cache runs \
        --instrument mdi --seeds 1 2 --latitudes 0 25 45 60 70 75 \
        --variants default small-spot large-umbra plage-elements

(``--rst`` also writes the tables the guide page includes.)  The
constraints take ~30 s of CPU per variant; a GONG run ~18 s of CPU, an HMI run ~25 s, an MDI run
~21 s, one per variant, latitude and seed.
"""
import argparse
import datetime
import time
from pathlib import Path

import astropy.units as u
import numpy as np
from astropy.table import QTable, vstack

from gongsynth.analysis.sun_constraints import sun_constraints
from gongsynth.analysis.weak_flux import weak_flux_factor, weak_flux_factor_difference
from gongsynth.config import SimulationConfig
from gongsynth.run_cache import cached_runs, run_config
from gongsynth.sun.model_atmosphere.ensemble import variant, variant_names
from gongsynth.version import version

#: The constraints measured on the spot box (`gongsynth.analysis.sun_constraints.measure_spot`).
SPOT_ROWS = ("umbral_core_intensity", "penumbral_intensity", "umbral_area_fraction", "spot_area",
             "umbral_wilson_depression")


def _cpu():
    return time.process_time()


def constraints(names, args):
    """The constraints table of every variant."""
    tables = []
    default_quiet = None
    for name in names:
        start = _cpu()
        member = variant(name)
        # A spot-only variant's quiet box is the default's (same bits: SPOT_ARGUMENTS); a variant that
        # leaves the spot alone is measured on the quiet box only (its spot rows stay empty).
        quiet = member.spot_only and default_quiet is not None
        spot = not member.changes or member.spot_only
        table = sun_constraints(name, seed=args.seed, quiet_shape=None if quiet else (160, 160),
                                spot_shape=(128, 128) if spot else None)
        if name == "default":
            default_quiet = table[[c not in SPOT_ROWS for c in table["constraint"]]]
        if quiet:
            table = vstack([default_quiet, table])
        table.add_column(name, name="variant", index=0)
        tables.append(table)
        bad = [c for c, verdict in zip(table["constraint"], table["verdict"]) if verdict == "outside"]
        print(f"{name:>22s}: {_cpu() - start:5.1f} s CPU; outside: {', '.join(bad) or 'none'}", flush=True)
    out = vstack(tables)
    out.meta.update({"gongsynth_version": version, "seed": args.seed,
                     "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")})
    return out


def weak_flux(names, args):
    """Each variant's weak-flux factor at each latitude (pooled, per seed, paired change from the default)."""
    configs, keys = [], []
    for name in names:
        for latitude in args.latitudes:
            for seed in args.seeds:
                configs.append(SimulationConfig.from_arguments(latitude=latitude * u.deg, seed=seed,
                                                               instrument=args.instrument,
                                                               photosphere=variant(name).photosphere()))
                keys.append((name, latitude, seed))
    runs = {}
    start = _cpu()
    for index, run in cached_runs(configs, cache=args.cache, workers=args.workers, desc="ensemble runs"):
        runs[keys[index]] = run
    print(f"runs: {_cpu() - start:.1f} s CPU in this process", flush=True)
    rows = []
    for name in names:
        for latitude in args.latitudes:
            mine = [runs[(name, latitude, seed)] for seed in args.seeds]
            pooled = weak_flux_factor(mine, n_boot=args.n_boot)
            per_seed = [weak_flux_factor(run, n_boot=0).factor for run in mine]
            if name == "default":
                change, change_error = 0.0, 0.0
            else:
                base = [runs[("default", latitude, seed)] for seed in args.seeds]
                change, change_error = weak_flux_factor_difference(base, mine, n_boot=args.n_boot)
            rows.append(dict(variant=name, latitude=latitude * u.deg, n_seeds=len(mine), factor=pooled.factor,
                             bootstrap=pooled.uncertainty, seed_mean=float(np.mean(per_seed)),
                             seed_spread=float(np.std(per_seed, ddof=1)) if len(per_seed) > 1 else np.nan,
                             change=change, change_uncertainty=change_error))
            print(f"{name:>22s} {latitude:4.0f}°: factor {pooled.factor:.3f} ± {pooled.uncertainty:.3f} "
                  f"seeds [{', '.join(f'{f:.3f}' for f in per_seed)}] "
                  f"change {change:+.3f} ± {change_error:.3f}",
                  flush=True)
    table = QTable(rows=rows)
    table.meta.update({
        "gongsynth_version": version, "instrument": args.instrument, "seeds": list(args.seeds),
        "n_boot": args.n_boot,
        "config": run_config(SimulationConfig.from_arguments(instrument=args.instrument)).to_toml(
            comments=False),
        "method": f"default {args.instrument.upper()} run with each variant's [photosphere] knobs; factor = "
                  "papers' quiet-Sun fit pooled over the seeds (min_outer per run), bootstrap = its block "
                  "bootstrap; change = paired difference from "
                  "the default Sun with the same seeds (paired block bootstrap)",
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
    })
    return table


def _fmt(value):
    return "–" if not np.isfinite(value) else f"{value:.3g}" if abs(value) < 100 else f"{value:.0f}"


def constraints_rst(table):
    """The constraints table as RST: a row per constraint, a column per variant (value, * when outside)."""
    names = list(dict.fromkeys(table["variant"]))
    rows = list(dict.fromkeys(table["constraint"]))
    lines = [".. list-table:: Each variant's constraint values (* outside the accepted range)",
             "   :header-rows: 1", "   :stub-columns: 1", "",
             "   * - constraint", "     - accepted", *[f"     - {n}" for n in names]]
    for name in rows:
        first = table[table["constraint"] == name][0]
        low, high, unit = first["low"], first["high"], str(first["unit"])
        accepted = ("reported" if not (np.isfinite(low) or np.isfinite(high))
                    else f"≥ {_fmt(low)}" if not np.isfinite(high) else f"{_fmt(low)} – {_fmt(high)}")
        unit = f" ({unit})" if unit and accepted == "reported" else f" {unit}" if unit else ""
        lines += [f"   * - ``{name}``", f"     - {accepted}{unit}"]
        for variant_name in names:
            row = table[(table["variant"] == variant_name) & (table["constraint"] == name)]
            cell = "" if not len(row) else _fmt(row[0]["value"]) + ("\\*" if row[0]["verdict"] == "outside"
                                                                     else "")
            lines.append(f"     - {cell}")
    return "\n".join(lines) + "\n"


def variants_rst():
    """The ensemble's variants as RST: name, changed arguments, source."""
    lines = [".. list-table:: The variants (arguments of ``model_atmosphere``; the rest at the defaults)",
             "   :header-rows: 1", "   :widths: 15 25 60", "",
             "   * - variant", "     - changes", "     - source"]
    for name in variant_names():
        member = variant(name)
        changes = ", ".join(f"``{k} = {v}``" for k, v in member.changes.items()) or "(none)"
        lines += [f"   * - {name}", f"     - {changes}", f"     - {member.source}"]
    return "\n".join(lines) + "\n"


def weak_flux_rst(table):
    """The weak-flux table as RST."""
    instrument = table.meta.get("instrument", "gong").upper()
    lines = [f".. list-table:: {instrument} weak-flux factor of each variant (default run, seeds pooled)",
             "   :header-rows: 1", "",
             "   * - variant", "     - latitude", "     - factor ± bootstrap",
             "     - per-seed mean ± spread", "     - change from default (paired)"]
    for row in table:
        lines += [f"   * - {row['variant']}", f"     - {row['latitude'].to_value(u.deg):.0f}°",
                  f"     - {row['factor']:.3f} ± {row['bootstrap']:.3f}",
                  f"     - {row['seed_mean']:.3f} ± {row['seed_spread']:.3f}",
                  f"     - {row['change']:+.3f} ± {row['change_uncertainty']:.3f}"]
    return "\n".join(lines) + "\n"


def main(argv=None):
    """Parse the arguments, measure, print and write the tables."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--variants", nargs="+", default=list(variant_names()), choices=variant_names())
    parser.add_argument("--constraints", type=Path, help="write the constraints table here (ECSV)")
    parser.add_argument("--weak-flux", type=Path, help="write the weak-flux table here (ECSV)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the constraint boxes")
    parser.add_argument("--latitudes", type=float, nargs="+", default=[0.0, 60.0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2], help="seeds of the runs")
    parser.add_argument("--instrument", choices=("gong", "hmi", "mdi"), default="gong",
                        help="instrument of the weak-flux runs (its default run otherwise)")
    parser.add_argument("--n-boot", type=int, default=50)
    parser.add_argument("--workers", type=int)
    parser.add_argument("--cache", type=Path)
    parser.add_argument("--rst", action="store_true", help="also write each table as RST (.txt beside it)")
    args = parser.parse_args(argv)
    if not (args.constraints or args.weak_flux):
        parser.error("nothing to do: give --constraints and/or --weak-flux")
    names = sorted(dict.fromkeys(args.variants), key=lambda n: n != "default")  # the default first
    if args.constraints:
        table = constraints(names, args)
        table.write(args.constraints, format="ascii.ecsv", overwrite=True)
        print(f"wrote {args.constraints}")
        if args.rst:
            args.constraints.with_suffix(".txt").write_text(constraints_rst(table))
            args.constraints.with_name("sun_ensemble_variants.txt").write_text(variants_rst())
    if args.weak_flux:
        if "default" not in names:
            names.insert(0, "default")  # the paired changes need the default Sun's runs
        table = weak_flux(names, args)
        table.write(args.weak_flux, format="ascii.ecsv", overwrite=True)
        print(f"wrote {args.weak_flux}")
        if args.rst:
            args.weak_flux.with_suffix(".txt").write_text(weak_flux_rst(table))


if __name__ == "__main__":
    main()
