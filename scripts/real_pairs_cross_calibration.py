"""
The measured HMI/GONG ratio on the three real synoptic pairs, raw and after gongsynth's calibrations.

Reads the GONG (``mrzqs``) and HMI (``hmi.Synoptic_Mr_small``) Carrington
synoptic maps of the same rotations, CR 2253-2255 (``shared/data/real/pairs``,
see its PROVENANCE.md), with `gongsynth.load_observation`, and compares them
with `gongsynth.cross_calibrate` on GONG's 1° grid (HMI's 0.5° pixels averaged
2 x 2, flux-preserving), by |latitude| band and field strength.  Each row is
one comparison (``scale``):

- ``raw``: HMI against GONG as published;
- ``gong_truth_curves``: HMI against GONG calibrated to the truth with the
  papers' curves of the shipped calibration table (``gongsynth.calibrate(gong)``);
- ``both_truth_factors``: HMI and GONG each put on the truth with their
  predicted factors of the shipped conversion table
  (``calibrate(m, to="truth", table=read_cross_calibration_table())``): 1 if
  both predictions are right;
- ``gong_on_hmi``: HMI against GONG put on HMI's scale
  (``gongsynth.calibrate(gong, to="hmi")``): 1 if the prediction is right;
- ``predicted``: GONG on HMI's scale against GONG itself, i.e. the predicted
  GONG→HMI factor averaged over the same cells, to read beside ``raw``.

Nothing here is fitted to the real maps: they are the test of the prediction.
The numbers are deterministic (about 30 s)::

    python scripts/real_pairs_cross_calibration.py --out docs/guide/real_pairs_cross_calibration.ecsv \
        --summary docs/guide/real_pairs_summary.txt --factors docs/guide/cross_calibration_factors.txt

``--summary`` and ``--factors`` write the reStructuredText tables the
cross-calibration guide includes: the all-strength ratios per pair and
scale, and the predicted factors of the conversion table.
"""
import argparse
import warnings
from pathlib import Path

import astropy.units as u
import numpy as np
from astropy.table import QTable, vstack
from sunpy.util.exceptions import SunpyMetadataWarning

import gongsynth
from gongsynth.analysis.cross_calibration_table import read_cross_calibration_table

REAL = Path(__file__).resolve().parents[2] / "shared" / "data" / "real"

#: The Carrington rotations of the pairs.
ROTATIONS = (2253, 2254, 2255)


def load_pair(root, rotation):
    """The GONG and HMI synoptic maps of one rotation."""
    with warnings.catch_warnings():  # HMI's charts have no observer; load_observation places it at Earth
        warnings.simplefilter("ignore", SunpyMetadataWarning)
        gong = gongsynth.load_observation(root / "pairs" / f"gong_mrzqs_c{rotation}.fits")
        hmi = gongsynth.load_observation(root / "pairs" / f"hmi.Synoptic_Mr_small.{rotation}.fits")
    return gong, hmi


def comparisons(gong, hmi, conversion):
    """The (scale, map_a, map_b) pairs of the module notes."""
    to_truth = {"table": conversion, "to": "truth"}
    on_hmi = gongsynth.calibrate(gong, to="hmi", table=conversion)
    return (("raw", gong, hmi),
            ("gong_truth_curves", gongsynth.calibrate(gong), hmi),
            ("both_truth_factors", gongsynth.calibrate(gong, **to_truth),
             gongsynth.calibrate(hmi, **to_truth)),
            ("gong_on_hmi", on_hmi, hmi),
            ("predicted", gong, on_hmi))


def build_table(root=REAL, rotations=ROTATIONS, conversion=None):
    """All comparisons of all pairs in one QTable (`gongsynth.cross_calibrate`'s columns, rotation, scale)."""
    conversion = read_cross_calibration_table() if conversion is None else conversion
    tables = []
    for rotation in rotations:
        gong, hmi = load_pair(root, rotation)
        for scale, a, b in comparisons(gong, hmi, conversion):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", SunpyMetadataWarning)
                table = gongsynth.cross_calibrate(a, b)
            table.add_column(rotation, name="rotation", index=0)
            table.add_column(scale, name="scale", index=1)
            meta = dict(table.meta)
            tables.append(table)
    out = vstack(tables, metadata_conflicts="silent")
    out.meta.update({k: v for k, v in meta.items() if k not in ("map_a", "map_b")})
    out.meta.update({
        "maps": "shared/data/real/pairs: GONG mrzqs (zero-point corrected) and HMI hmi.Synoptic_Mr_small, "
                "CR 2253-2255, radial field (B_LOS / mu) on CEA grids",
        "ratio": "map_b / map_a: HMI over GONG on each scale (predicted: GONG on HMI's scale over GONG)",
        "conversion_table": str(conversion.meta.get("source", "in-memory table")),
        "gongsynth_version": gongsynth.__version__,
    })
    return out


#: The |latitude| bands of the summary (deg), besides all latitudes.
SUMMARY_BANDS = ((0, 25), (25, 45), (45, 60))


def _pm(value, sigma):
    return f"{value:.3f} ± {sigma:.3f}" if np.isfinite(sigma) else f"{value:.3f}"


def summary(table):
    """The all-strength rows as a small table of strings: flux ratio and slope, all latitudes and by band."""
    every = (table["strength_min"] == 0 * u.G) & np.isinf(table["strength_max"])
    rows = []
    for rotation in sorted(set(table["rotation"])):
        for scale in dict.fromkeys(table["scale"]):
            pick = table[every & (table["rotation"] == rotation) & (table["scale"] == scale)]
            bands = {(round(r["angle_min"].value), round(r["angle_max"].value)): r for r in pick}
            # The predicted rows compare a map with itself times a smooth factor: no scatter to quote.
            quote = (lambda r: f"{r['slope']:.3f}") if scale == "predicted" else (
                lambda r: _pm(r["slope"], r["slope_uncertainty"]))
            whole = bands[(0, 90)]
            rows.append([f"CR {rotation}", scale, f"{whole['flux_ratio']:.3f}", quote(whole)]
                        + [quote(bands[b]) for b in SUMMARY_BANDS])
    names = ["pair", "scale", "flux ratio", "slope"] + [f"slope {lo}-{hi} deg" for lo, hi in SUMMARY_BANDS]
    return QTable(rows=rows, names=names)


def factors(conversion):
    """The predicted factors over all field strengths, by latitude, as strings."""
    from gongsynth.analysis.cross_calibration_table import conversion_factors

    columns = {}
    pairs = (("gong", "hmi"), ("gong", "mdi"), ("mdi", "hmi"), ("gong", "truth"), ("hmi", "truth"),
             ("mdi", "truth"))
    present = set(conversion["instrument"])
    for source, target in ((a, b) for a, b in pairs if {a, b} - {"truth"} <= present):
        latitude, factor, sigma = conversion_factors(conversion, source, target)
        columns["latitude (deg)"] = [f"{v:g}" for v in latitude.to_value(u.deg)]
        columns[f"{source.upper()} -> {target if target == 'truth' else target.upper()}"] = [
            _pm(f, s) for f, s in zip(factor, sigma)]
    return QTable(columns)


def main(argv=None):
    """Command line: build the table, print the all-strength rows and (with --out) write it."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--real", type=Path, default=REAL, help="shared/data/real folder")
    parser.add_argument("--out", type=Path, help="write the table as ECSV")
    parser.add_argument("--summary", type=Path, help="write the all-strength summary (reStructuredText)")
    parser.add_argument("--factors", type=Path, help="write the predicted factors (reStructuredText)")
    args = parser.parse_args(argv)
    conversion = read_cross_calibration_table()
    table = build_table(args.real, conversion=conversion)
    every = (table["strength_min"] == 0 * u.G) & np.isinf(table["strength_max"])
    for row in table[every]:
        print(f"CR {row['rotation']} {row['scale']:19s} |lat| {row['angle_min'].value:2.0f}-"
              f"{row['angle_max'].value:2.0f}  flux ratio {row['flux_ratio']:.3f}  slope {row['slope']:.3f} "
              f"+- {row['slope_uncertainty']:.3f}  r {row['correlation']:.3f}  ({row['n_pixels']} cells)")
    for path, small in ((args.summary, summary(table)), (args.factors, factors(conversion))):
        if path:
            small.write(path, format="ascii.rst", overwrite=True)
            print(f"wrote {path}")
    if args.out:
        table.write(args.out, format="ascii.ecsv", overwrite=True)
        print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
