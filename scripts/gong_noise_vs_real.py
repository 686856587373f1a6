"""
A simulated Big Bear full disk beside the real GONG map of 2009-09-05 18:54: the noise statistics.

The run takes the real file's date, site, plate scale and pointing (``like``),
9 minutes (``N_USED = 9``), seed 1, 3 × 3 samples per pixel (the gallery's),
and the effects given on the command line switched off; it is compared with
`gongsynth.compare` (`gongsynth.analysis.map_statistics`).  Writes
``OUT/<name>.json`` (the statistics, with and without the noise matched, and
the count levels of `gongsynth.analysis.count_levels`) and
``OUT/<name>_magnetogram.fits``::

    python scripts/gong_noise_vs_real.py --out OUT --name all-on
    python scripts/gong_noise_vs_real.py --out OUT --name before \
        --off frame_seeing minute_average image_rotation
    python scripts/gong_noise_vs_real.py --out OUT --name bilinear --interpolant linear
    python scripts/gong_noise_vs_real.py --out OUT --name kolmogorov --seeing-profile kolmogorov
    python scripts/gong_noise_vs_real.py --out OUT --collect docs/guide/gong_noise_vs_real.ecsv

Takes about 2-4 minutes on two cores.
"""
import argparse
import dataclasses
import json
import os
from pathlib import Path

REAL = Path(os.environ.get("GONGSYNTH_REAL_DATA", Path(__file__).resolve().parents[2] / "shared" / "data"
                           / "real"))
BIG_BEAR = REAL / "gong" / "bbbqa090905t1854.fits.gz"
BIG_BEAR_INTENSITY = REAL / "gong" / "bbiqa090905t1854.fits.gz"


def main(argv=None):
    """Run the simulation, compare it with the real map, write the numbers."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--name", default="run")
    parser.add_argument("--off", nargs="*", default=[], help="effects to switch off")
    parser.add_argument("--effective-area", type=float, default=None, help="cm2 (default the instrument's)")
    parser.add_argument("--like-counts", action="store_true",
                        help="the file's count level (like_counts: its DIODE sums) instead of an area")
    parser.add_argument("--interpolant", default=None, help="image_interpolant (default the instrument's)")
    parser.add_argument("--seeing-profile", default=None, help="seeing_profile (default the instrument's)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--collect", type=Path, default=None,
                        help="write the runs' numbers in OUT/*.json to this ECSV table (no run)")
    args = parser.parse_args(argv)
    if args.collect is not None:
        return collect(args.out, args.collect)

    import astropy.units as u
    import numpy as np

    import gongsynth
    from gongsynth.analysis.compare import compare
    from gongsynth.analysis.count_levels import count_levels
    from gongsynth.config import Effects, SimulationConfig
    from gongsynth.observing import like_gong

    real = gongsynth.load_observation(BIG_BEAR)
    settings, instrument = like_gong(BIG_BEAR)
    instrument = instrument.replace(supersampling=3)
    if args.effective_area is not None:
        instrument = instrument.replace(effective_area=args.effective_area * u.cm**2)
    if args.interpolant is not None:
        instrument = instrument.replace(image_interpolant=args.interpolant)
    if args.seeing_profile is not None:
        instrument = instrument.replace(seeing_profile=args.seeing_profile)
    # GONG's real noise on (opt-in in gongsynth's defaults), then what the command line switches off.
    effects = Effects(**{"frame_seeing": True, "minute_average": True, "image_rotation": True,
                         **dict.fromkeys(args.off, False)})
    config = SimulationConfig(mode="full-disk", duration=9 * u.min, seed=args.seed, surface_field="synthetic",
                              instrument=instrument, effects=effects, like_counts=args.like_counts,
                              **settings)
    result = gongsynth.simulate(config=config, progress=False)
    args.out.mkdir(parents=True, exist_ok=True)
    result.magnetogram.save(args.out / f"{args.name}_magnetogram.fits", overwrite=True)
    report = compare(result.magnetogram, real, labels=("gongsynth", "GONG Big Bear"), plot=False)
    stats = report.statistics
    print(stats.summary())
    table = stats.table
    numbers = {key: [float(v) for v in np.asarray(getattr(table[key], "value", table[key]))]
               for key in table.colnames if key != "map"}
    levels = count_levels(gongsynth.load_observation(BIG_BEAR_INTENSITY, kind="continuum"), result)
    out = {"name": args.name, "effects_off": args.off, "effective_area_cm2": instrument.effective_area.value,
           "image_interpolant": instrument.image_interpolant, "seeing_profile": instrument.seeing_profile,
           "like_counts": args.like_counts,
           "effarea_header": result.raw.header.get("EFFAREA"),
           "image_rotation_angle_deg": instrument.image_rotation_angle.to_value(u.deg),
           "rows": list(table["map"]), "numbers": numbers,
           "power_ratio_5_100": stats.spectrum_ratio_range(),
           "power_ratio_5_100_matched": stats.spectrum_ratio_range(matched=True),
           "rings": {"r_inner": [float(r) for r in stats.rings["r_inner"]],
                     "sim": [float(v) for v in stats.rings["sim"].to_value(u.G)],
                     "obs": [float(v) for v in stats.rings["obs"].to_value(u.G)]},
           "count_levels": {str(r["quantity"]): [float(r["real"].value), float(r["simulated"].value),
                                                 float(r["effective_area"].value)] for r in levels},
           "summary": stats.summary()}
    (args.out / f"{args.name}.json").write_text(json.dumps(out, indent=1))
    print(levels)
    return dataclasses.asdict(effects)


def collect(folder, table_path):
    """One row per run saved in ``folder`` (and the real map's), written as an ECSV table."""
    import astropy.units as u
    import numpy as np
    from astropy.table import QTable

    runs = [json.loads(p.read_text()) for p in sorted(Path(folder).glob("*.json"))]
    if not runs:
        raise SystemExit(f"no run's .json in {folder}")
    keys = ("ks", "ks_centred", "mean_abs", "mean_abs_centred", "noise_box", "noise_difference", "p99",
            "p999")
    rows = [{"run": "real (Big Bear 2009-09-05 18:54)", "effective_area": np.nan, "like_counts": False,
             "effects_off": "", "interpolant": "", "seeing_profile": "",
             **{k: runs[0]["numbers"][k][1] if k not in ("ks", "ks_centred") else np.nan for k in keys},
             "power_ratio_min": np.nan, "power_ratio_max": np.nan}]
    for r in runs:
        rows.append({"run": r["name"], "effective_area": r.get("effarea_header") or r["effective_area_cm2"],
                     "like_counts": bool(r.get("like_counts")), "effects_off": " ".join(r["effects_off"]),
                     "interpolant": r.get("image_interpolant", ""),
                     "seeing_profile": r.get("seeing_profile", "gaussian"),
                     **{k: r["numbers"][k][0] for k in keys},
                     "power_ratio_min": r["power_ratio_5_100"][0],
                     "power_ratio_max": r["power_ratio_5_100"][1]})
    table = QTable(rows=[[row[c] for c in rows[0]] for row in rows], names=list(rows[0]))
    table["effective_area"].unit = u.cm**2
    for k in ("mean_abs", "mean_abs_centred", "noise_box", "noise_difference", "p99", "p999"):
        table[k].unit = u.G
    table.meta["description"] = ("gongsynth like runs against the real Big Bear GONG map, 9 minutes, seed 1, "
                                 "frame seeing and averaging on; scripts/gong_noise_vs_real.py")
    table.write(table_path, format="ascii.ecsv", overwrite=True)
    return table


if __name__ == "__main__":
    main()
