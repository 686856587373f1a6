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
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args(argv)

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
           "image_interpolant": instrument.image_interpolant, "like_counts": args.like_counts,
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


if __name__ == "__main__":
    main()
