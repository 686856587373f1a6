r"""
The papers' weak-flux factor of every instrument of the family, on one Sun.

For each latitude, instrument and seed `gongsynth.simulate` runs the default
3-D Sun: the seed fixes the photosphere, so every instrument sees the same
Sun, each in its own line, for its own standard product (GONG 10 min, HMI
45 s) on its own default tiled detector (GONG 860², HMI 1024²).  The papers'
quiet-Sun estimator (`gongsynth.weak_flux_factor`, truth through the PSF,
the 1× quadrant) gives the factor of each seed, their mean and standard
error (a different Sun each seed), and one fit pooled over the seeds with
its block-bootstrap uncertainty (pixel noise only).  The docs' numbers came
from::

    python scripts/instrument_weak_flux.py --latitudes 0 60 --seeds 1 2 \
        --record iwf.jsonl --out docs/guide/instrument_weak_flux.ecsv
    python scripts/instrument_weak_flux.py --instruments hmi --latitudes 0 --seeds 1 2 \
        --duration 720 --record iwf.jsonl --out docs/guide/instrument_weak_flux.ecsv --append

Each run's factor is appended to ``--record`` as soon as it is known, so an
interrupted sweep keeps what it measured; ``--summarise iwf.jsonl --out T``
writes the table again from the records alone (without the pooled fits).
"""
import argparse
import datetime
import json
import time
from pathlib import Path

import astropy.units as u
import numpy as np
from astropy.table import QTable, vstack

import gongsynth
from gongsynth.version import git_commit


def measure(instrument, latitude, seeds, record, duration=None):
    """Run one instrument at one latitude for every seed; return its table row."""
    results, per_seed, seconds = [], [], []
    for seed in seeds:
        start = time.perf_counter()
        result = gongsynth.simulate(instrument=instrument, latitude=latitude * u.deg, seed=seed,
                                    duration=duration, progress=False)
        seconds.append(time.perf_counter() - start)
        fit = gongsynth.weak_flux_factor(result)
        per_seed.append(fit.factor)
        entry = {"instrument": instrument, "latitude": latitude, "seed": seed, "factor": fit.factor,
                 "bootstrap": fit.uncertainty, "n_pixels": fit.n_pixels, "seconds": seconds[-1],
                 "detector": result.config.detector_pixels,
                 "duration_s": float(result.config.duration.to_value(u.s)),
                 "version": gongsynth.__version__}
        print(json.dumps(entry), flush=True)
        if record:
            with open(record, "a") as out:
                out.write(json.dumps(entry) + "\n")
        results.append(result)
    pooled = gongsynth.weak_flux_factor(results)
    return {"instrument": instrument, "latitude": latitude, "seeds": list(seeds), "per_seed": per_seed,
            "pooled": pooled.factor, "pooled_uncertainty": pooled.uncertainty,
            "detector": entry["detector"], "duration_s": entry["duration_s"],
            "seconds": float(np.mean(seconds))}


def from_records(path):
    """Table rows from a record file (per-seed factors only; no pooled fit without the runs)."""
    groups = {}
    for line in Path(path).read_text().splitlines():
        if line.strip():
            entry = json.loads(line)
            groups.setdefault((entry["instrument"], entry["latitude"]), []).append(entry)
    return [{"instrument": name, "latitude": latitude, "seeds": [e["seed"] for e in entries],
             "per_seed": [e["factor"] for e in entries], "pooled": np.nan, "pooled_uncertainty": np.nan,
             "detector": entries[0]["detector"], "duration_s": entries[0]["duration_s"],
             "seconds": float(np.mean([e["seconds"] for e in entries]))}
            for (name, latitude), entries in groups.items()]


def write_table(rows, out, append=False):
    """The rows as an ECSV QTable with its provenance (after the rows already in ``out`` if ``append``)."""
    table = QTable()
    table["instrument"] = [r["instrument"] for r in rows]
    table["latitude"] = [r["latitude"] for r in rows] * u.deg
    table["n_seeds"] = [len(r["seeds"]) for r in rows]
    table["factor"] = [float(np.mean(r["per_seed"])) for r in rows]
    table["uncertainty"] = [float(np.std(r["per_seed"], ddof=1) / np.sqrt(len(r["per_seed"])))
                            if len(r["per_seed"]) > 1 else np.nan for r in rows]
    table["pooled"] = [r["pooled"] for r in rows]
    table["pooled_uncertainty"] = [r["pooled_uncertainty"] for r in rows]
    table["detector"] = [r["detector"] for r in rows]
    table["duration"] = [r["duration_s"] for r in rows] * u.s
    table["run_time"] = [r["seconds"] for r in rows] * u.s
    if append and Path(out).exists():
        old = QTable.read(out, format="ascii.ecsv")
        table.meta.update(old.meta)
        table = vstack([old, table], metadata_conflicts="silent")
    table.meta.update({
        "description": "The papers' quiet-Sun weak-flux factor (truth through the PSF, 1x quadrant) of each "
                       "instrument on the default 3-D Sun with the same seeds: factor = mean over seeds, "
                       "uncertainty = standard error over seeds, pooled = one fit to all seeds' pixels "
                       "(pooled_uncertainty: its block bootstrap, pixel noise only); duration: the "
                       "instrument's default unless given; each instrument's default tiled detector; "
                       "run_time = mean wall time of one run.",
        "seeds": sorted({int(s) for r in rows for s in r["seeds"]} | set(table.meta.get("seeds", []))),
        "script": "scripts/instrument_weak_flux.py",
        "commits": list(table.meta.get("commits", [])) + [
            git_commit()],
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
    })
    table.write(out, format="ascii.ecsv", overwrite=True)
    print(table)


def main(argv=None):
    """Measure (or summarise) and write the table."""
    parser = argparse.ArgumentParser(description=__doc__.strip().split("\n")[0])
    parser.add_argument("--instruments", nargs="+", default=list(gongsynth.instruments.names()))
    parser.add_argument("--latitudes", type=float, nargs="+", default=[0, 60])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--duration", type=float, help="seconds (default: each instrument's own)")
    parser.add_argument("--append", action="store_true", help="add the rows to those already in --out")
    parser.add_argument("--record", help="append one JSON line per run to this file")
    parser.add_argument("--summarise", metavar="JSONL", help="only write --out from these records")
    parser.add_argument("--out", required=True, help="the ECSV table")
    args = parser.parse_args(argv)
    if args.summarise:
        return write_table(from_records(args.summarise), args.out)
    duration = None if args.duration is None else args.duration * u.s
    rows = [measure(name, latitude, args.seeds, args.record, duration)
            for latitude in args.latitudes for name in args.instruments]
    write_table(rows, args.out, append=args.append)


if __name__ == "__main__":
    main()
