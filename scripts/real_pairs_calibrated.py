r"""
Calibrated HMI over calibrated GONG on three real synoptic pairs, the tables' uncertainties propagated.

If gongsynth's tables are right, a GONG map and an HMI map of the same Sun,
each calibrated to the truth, agree: their ratio is 1.  This script measures
that ratio on the GONG (``mrzqs``) and HMI (``hmi.Synoptic_Mr_small``)
Carrington synoptic maps of CR 2253-2255 (``shared/data/real/pairs``, see its
PROVENANCE.md), beside the raw ratio HMI/GONG.  Nothing is fitted to these
maps: they are the test.

Calibrations (`gongsynth.calibrate`, ``to="truth"``):

- **HMI**, two ways (column ``hmi_calibration``): ``factors``, its predicted
  factor to the truth at each pixel's viewing angle, from the shipped
  conversion table (``cross_calibration_default.ecsv``, rows ``hmi -> truth``
  over all field strengths); ``curves``, the papers' curves of HMI's own
  calibration table (``calibration_hmi.ecsv``, ``gongsynth.calibrate(hmi)``),
  paired with GONG's curves.
- **GONG**, two ways (column ``gong_calibration``): ``curves``, the papers'
  flux-conserving curves of the shipped calibration table
  (``calibration_default.ecsv``, ``gongsynth.calibrate(gong)``); ``factors``,
  GONG's predicted factor to the truth from the conversion table (the same
  kind of correction as HMI's); and ``curves_scene``, the curves with
  ``scene="distance"`` (each quiet cell also times the scene table's ratio at
  its distance from the map's own strong fields; the scene table's own
  uncertainty is not propagated).

Comparison: both maps on GONG's 1° CEA grid (HMI's 0.5° pixels averaged by
exact area weighting, `gongsynth.analysis.cross_calibration.common_grid`),
cells finite in both, grouped by |latitude| (all, 0-25°, 25-45°, 45-60°); per
group the unsigned-flux ratio Σ|HMI| / Σ|GONG| and the OLS-bisector slope of
HMI against GONG (`~gongsynth.analysis.cross_calibration.bisector_slope`), as
`gongsynth.cross_calibrate` computes them (the script checks it gets the same
numbers).

Uncertainty of the tables, propagated linearly.  Every calibrated map is a sum
of one term per table row, ``calibrate(smap, table with only row j kept)``:
both corrections are linear in each row's curve or factor (the curves are
interpolated linearly in θ between the rows; the factors too).  A row's
statistical uncertainty, as a relative error ε_j of its factor, scales its
term by (1 + ε_j), the curve rows as a whole (the calibration table carries
the uncertainty of the weak-flux factor only, not of each node).  The rows
are taken as independent (the tables give no covariance; GONG's and HMI's
factors to the truth come from the same simulated Sun and seeds, so the real
errors of the ratio are partly common and cancel: this overstates them).  The
derivative of each statistic along each row comes from a finite step
(ε = 10⁻⁴, exact for the flux ratio while no cell changes sign), and

    σ² = Σ_j (∂statistic / ∂ε_j)² σ_j².

Two sets of σ_j (columns ``*_table`` and ``*_seeds``): the ``uncertainty``
columns of the shipped tables as they are (the calibration table's is a
block bootstrap of its two seeds pooled); and the same with the quiet-Sun
curves' σ replaced by the seed-to-seed standard error of the 256² run grid's
weak-flux factor (``weak_flux_factors.ecsv``, three seeds, the nearest
tabulated angle), which the issue says is 10-20 times the bootstrap's.  The
statistical error of the real maps themselves is the bisector's
``slope_uncertainty`` (Isobe et al. 1990; it assumes independent cells).

The tables' ``systematic`` columns (the Sun-model ensemble, issue 24) are
propagated member by member where both maps are calibrated by their own
tables' curves (columns ``*_sys``): an accepted member m of both tables'
ensembles (``ensemble_members`` in their metadata) moves every quiet-Sun row j
of both tables at once, by its paired change over the row's factor,
δ_mj = change_mj / factor_j (``docs/guide/sun_ensemble_weak_flux*.ecsv``; the
sunspot rows are not moved: not measured), so the statistic moves by
Δ_m = Σ_j (∂statistic / ∂ε_j) δ_mj, and ``*_sys`` = max_m |Δ_m|.  A member
moves GONG's and HMI's factors the same way (a smaller spot lowers both), so
much of it cancels in the ratio: taking the two tables' bands as independent
would overstate it.

About 1 minute::

    python scripts/real_pairs_calibrated.py --out docs/guide/real_pairs_calibrated.ecsv \
        --summary docs/guide/real_pairs_calibrated.txt
"""
import argparse
import importlib.resources
import sys
import warnings
from pathlib import Path

import astropy.units as u
import numpy as np
from astropy.table import QTable
from sunpy.util.exceptions import SunpyMetadataWarning

import gongsynth
from gongsynth.analysis.calibration_table import read_calibration_table
from gongsynth.analysis.cross_calibration import bisector_slope, common_grid
from gongsynth.analysis.cross_calibration_table import read_cross_calibration_table

sys.path.insert(0, str(Path(__file__).resolve().parent))
from build_default_calibration_table import ENSEMBLES  # noqa: E402
from real_pairs_cross_calibration import REAL, ROTATIONS, load_pair  # noqa: E402

#: |latitude| groups (deg) of the comparison.
BANDS = ((0, 90), (0, 25), (25, 45), (45, 60))

#: The finite step of the relative error of one table row.
STEP = 1e-4


def curve_terms(table):
    """Per row of a calibration table: (copy keeping only that row's curve, row label, relative σ)."""
    terms = []
    for j, row in enumerate(table):
        only = table.copy()
        keep = np.arange(len(table)) == j
        only["values"] = only["values"] * keep[:, None]
        label = f"curves {row['region']} {row['latitude'].to_value(u.deg):g} deg"
        terms.append((only, label, float(row["uncertainty"] / row["factor"])))
    return terms


def factor_terms(conversion, instrument):
    """Each ``instrument -> truth`` row over all strengths: (the table with it alone, label, σ)."""
    rows = ((np.asarray(conversion["instrument"]) == instrument)
            & (np.asarray(conversion["target"]) == "truth")
            & (conversion["strength_min"].to_value(u.G) == 0)
            & np.isinf(conversion["strength_max"].to_value(u.G)))
    terms = []
    for j in np.nonzero(rows)[0]:
        only = conversion.copy()
        only["factor"] = np.where(rows & (np.arange(len(conversion)) != j), 0.0, only["factor"])
        row = conversion[j]
        label = f"{instrument} -> truth {row['latitude'].to_value(u.deg):g} deg"
        terms.append((only, label, float(row["uncertainty"] / row["factor"])))
    return terms


def seed_sigmas(terms, weak_flux=None):
    """The terms' σ with the quiet curves' replaced by the seed scatter of the run grid's weak-flux factor."""
    if weak_flux is None:
        weak_flux = QTable.read(importlib.resources.files("gongsynth") / "data" / "weak_flux_factors.ecsv")
    rows = weak_flux[(np.asarray(weak_flux["label"]) == "model-atmosphere")]
    latitudes = rows["latitude"].to_value(u.deg)
    sigmas = []
    for _, label, sigma in terms:
        if label.startswith("curves quiet"):
            angle = float(label.split()[2])
            nearest = rows[int(np.argmin(np.abs(latitudes - angle)))]
            sigma = max(sigma, float(nearest["uncertainty"] / nearest["factor"]))
        sigmas.append(sigma)
    return np.array(sigmas)


def member_shifts(table, ensemble):
    """
    Per accepted ensemble member of ``table``: each row's relative factor change (curve_terms' order).

    Quiet rows move by the member's paired change at the row's latitude over the row's factor;
    sunspot rows by 0 (the ensemble measures the quiet-Sun factor only).
    """
    latitudes = ensemble["latitude"].to_value(u.deg)
    shifts = {}
    for member in table.meta.get("ensemble_members", []):
        relative = []
        for row in table:
            angle = row["latitude"].to_value(u.deg)
            hit = ensemble[(np.asarray(ensemble["variant"]) == member) & np.isclose(latitudes, angle)]
            if row["region"] != "quiet":
                relative.append(0.0)
            elif len(hit) == 1:
                relative.append(float(hit["change"][0] / row["factor"]))
            else:
                raise ValueError(f"ensemble member {member!r} has no single row at {angle:g} deg")
        shifts[member] = np.array(relative)
    return shifts


def statistics(a, b, valid, latitude):
    """Per |latitude| band: (cells, Σ|b|/Σ|a|, bisector slope, its σ) over valid cells (CEA: equal areas)."""
    out = []
    for lo, hi in BANDS:
        sel = valid & (latitude >= lo) & ((latitude < hi) | (hi == 90))
        slope, sigma, _ = bisector_slope(a[sel], b[sel])
        out.append((int(sel.sum()), float(np.sum(np.abs(b[sel])) / np.sum(np.abs(a[sel]))), slope, sigma))
    return out


def _quiet(function, *args, **kwargs):
    with warnings.catch_warnings():  # HMI's charts have no observer; load_observation places it at Earth
        warnings.simplefilter("ignore", SunpyMetadataWarning)
        return function(*args, **kwargs)


def pair_rows(gong, hmi, rotation, calibration, conversion, weak_flux=None, hmi_calibration=None):
    """The table rows of one pair: raw and calibrated statistics per band and calibration pair, with σ."""
    if hmi_calibration is None:
        hmi_calibration = read_calibration_table(instrument="hmi")
    a_raw, b_raw, _ = _quiet(common_grid, gong, hmi)
    ny, nx = a_raw.data.shape
    y, x = np.mgrid[:ny, :nx]
    latitude = np.abs(a_raw.pixel_to_world(x * u.pix, y * u.pix).lat.to_value(u.deg))

    def on_grid(terms, smap, side, **options):
        """Each term's calibrated map on the common grid (side 0: GONG's, 1: HMI's)."""
        maps = []
        for table, _, _ in terms:
            kwargs = {"table": table} if "region" in table.colnames else {"table": table, "to": "truth"}
            calibrated = _quiet(gongsynth.calibrate, smap, **kwargs, **options)
            pair = (calibrated, hmi) if side == 0 else (gong, calibrated)
            maps.append(np.asarray(_quiet(common_grid, *pair)[side].data, float))
        return np.array(maps)

    gong_shifts = member_shifts(calibration, QTable.read(ENSEMBLES["gong"], format="ascii.ecsv"))
    hmi_shifts = member_shifts(hmi_calibration, QTable.read(ENSEMBLES["hmi"], format="ascii.ecsv"))
    members = [m for m in gong_shifts if m in hmi_shifts]
    hmi_by = {"factors": factor_terms(conversion, "hmi"), "curves": curve_terms(hmi_calibration)}
    hmi_maps = {name: on_grid(terms, hmi, 1) for name, terms in hmi_by.items()}
    raw = statistics(a_raw.data, b_raw.data, np.isfinite(a_raw.data) & np.isfinite(b_raw.data), latitude)
    rows = []
    for name, gong_terms, options, hmi_name in (
            ("curves", curve_terms(calibration), {}, "factors"),
            ("curves_scene", curve_terms(calibration), {"scene": "distance"}, "factors"),
            ("factors", factor_terms(conversion, "gong"), {}, "factors"),
            ("curves", curve_terms(calibration), {}, "curves")):
        hmi_terms, b_terms = hmi_by[hmi_name], hmi_maps[hmi_name]
        a_terms = on_grid(gong_terms, gong, 0, **options)
        a, b = a_terms.sum(axis=0), b_terms.sum(axis=0)
        valid = np.isfinite(a) & np.isfinite(b)
        nominal = statistics(a, b, valid, latitude)
        _check(gongsynth.calibrate(gong, **options) if name.startswith("curves")
               else gongsynth.calibrate(gong, table=conversion, to="truth"),
               gongsynth.calibrate(hmi, table=hmi_calibration) if hmi_name == "curves"
               else gongsynth.calibrate(hmi, table=conversion, to="truth"), nominal, gong, hmi)
        # Derivatives of every statistic along every row's relative error.
        steps = ([statistics(a + STEP * t, b, valid, latitude) for t in a_terms]
                 + [statistics(a, b + STEP * t, valid, latitude) for t in b_terms])
        sigma_table = np.array([s for *_, s in gong_terms] + [s for *_, s in hmi_terms])
        sigma_seeds = np.concatenate([seed_sigmas(gong_terms, weak_flux), sigma_table[len(gong_terms):]])
        for k, (lo, hi) in enumerate(BANDS):
            grad = np.array([[(s[k][1] - nominal[k][1]) / STEP, (s[k][2] - nominal[k][2]) / STEP]
                             for s in steps])
            err_table = np.sqrt((grad ** 2 * sigma_table[:, None] ** 2).sum(axis=0))
            err_seeds = np.sqrt((grad ** 2 * sigma_seeds[:, None] ** 2).sum(axis=0))
            err_sys = np.full(2, np.nan)
            if name == "curves" and hmi_name == "curves" and members:
                moved = [grad.T @ np.concatenate([gong_shifts[m], hmi_shifts[m]]) for m in members]
                err_sys = np.max(np.abs(moved), axis=0)
            rows.append(dict(
                rotation=rotation, gong_calibration=name, hmi_calibration=hmi_name, latitude_min=lo * u.deg,
                latitude_max=hi * u.deg,
                n_cells=nominal[k][0], raw_flux_ratio=raw[k][1], raw_slope=raw[k][2],
                raw_slope_uncertainty=raw[k][3], flux_ratio=nominal[k][1],
                flux_ratio_table=err_table[0], flux_ratio_seeds=err_seeds[0], flux_ratio_sys=err_sys[0],
                slope=nominal[k][2], slope_uncertainty=nominal[k][3], slope_table=err_table[1],
                slope_seeds=err_seeds[1], slope_sys=err_sys[1]))
    return rows


def _check(gong_cal, hmi_cal, nominal, gong, hmi):
    """The sum of the terms is the calibration itself: the same statistics as `gongsynth.cross_calibrate`."""
    table = _quiet(gongsynth.cross_calibrate, gong_cal, hmi_cal, angle_bins=[0, 25, 45, 60, 90] * u.deg,
                   strength_bins=[0, np.inf] * u.G)
    for k, (lo, hi) in enumerate(BANDS[1:], start=1):
        row = table[(table["angle_min"] == lo * u.deg) & (table["angle_max"] == hi * u.deg)][0]
        if not np.isclose(row["flux_ratio"], nominal[k][1], rtol=1e-6):
            raise RuntimeError(f"the terms do not add up to the calibration: flux ratio {nominal[k][1]} "
                               f"against cross_calibrate's {row['flux_ratio']} at {lo}-{hi} deg")


def build_table(root=REAL, rotations=ROTATIONS):
    """All pairs' rows as one QTable, with the method in its metadata."""
    calibration, conversion = read_calibration_table(), read_cross_calibration_table()
    rows = []
    for rotation in rotations:
        gong, hmi = load_pair(root, rotation)
        rows += pair_rows(gong, hmi, rotation, calibration, conversion)
    table = QTable(rows=rows)
    table.meta.update({
        "maps": "shared/data/real/pairs: GONG mrzqs (zero-point corrected) and HMI hmi.Synoptic_Mr_small, "
                "CR 2253-2255, radial field (B_LOS / mu) on CEA grids; compared on GONG's 1 deg grid",
        "ratio": "HMI / GONG, both calibrated to the truth (raw_*: as published); 1 if both calibrations are "
                 "right",
        "hmi_calibration": "factors: the conversion table's hmi -> truth factor at each pixel's viewing "
                           "angle; curves: HMI's own calibration table's curves (calibration_hmi.ecsv)",
        "gong_calibration": "curves: the calibration table's flux-conserving curves; curves_scene: the same "
                            "with scene='distance'; factors: the conversion table's gong -> truth factor",
        "calibration_table": str(calibration.meta.get("source", "")),
        "conversion_table": str(conversion.meta.get("source", "")),
        "uncertainty": "*_table: the tables' uncertainty columns propagated linearly (rows independent); "
                       "*_seeds: the same with the quiet curves' sigma raised to the run grid's seed scatter "
                       "(weak_flux_factors.ecsv); slope_uncertainty: the real maps' (bisector, Isobe et al. "
                       "1990); *_sys: the Sun-model ensemble, member by member over both tables at once "
                       "(max |change| over the members accepted by both; own curves on both sides only)",
        "gongsynth_version": gongsynth.__version__,
    })
    return table


def _sys(value):
    """`` ± σ (sys)`` where the ensemble's band was propagated, else nothing."""
    return f" ± {value:.3f} (sys)" if np.isfinite(value) else ""


def summary(table):
    """The all-latitude and 0-25° rows as strings: raw ratio, calibrated ratio ± table ± seeds."""
    rows = []
    for row in table[np.isin(table["latitude_max"].to_value(u.deg), (90, 25))]:
        band = f"{row['latitude_min'].to_value(u.deg):g}-{row['latitude_max'].to_value(u.deg):g}"
        rows.append([f"CR {row['rotation']}", band, row["gong_calibration"], row["hmi_calibration"],
                     f"{row['raw_flux_ratio']:.3f}",
                     f"{row['raw_slope']:.3f} ± {row['raw_slope_uncertainty']:.3f}",
                     f"{row['flux_ratio']:.3f} ± {row['flux_ratio_table']:.3f} "
                     f"({row['flux_ratio_seeds']:.3f}){_sys(row['flux_ratio_sys'])}",
                     f"{row['slope']:.3f} ± {row['slope_uncertainty']:.3f} ± {row['slope_table']:.3f} "
                     f"({row['slope_seeds']:.3f}){_sys(row['slope_sys'])}"])
    return QTable(rows=rows, names=["pair", "latitudes (deg)", "GONG by", "HMI by", "raw flux ratio",
                                    "raw slope", "calibrated flux ratio", "calibrated slope"])


def main(argv=None):
    """Command line: build the table, print it, and write it (ECSV) and its summary (reStructuredText)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--real", type=Path, default=REAL, help="shared/data/real folder")
    parser.add_argument("--out", type=Path, help="write the table as ECSV")
    parser.add_argument("--summary", type=Path, help="write the summary (reStructuredText)")
    args = parser.parse_args(argv)
    table = build_table(args.real)
    small = summary(table)
    small.pprint(max_lines=-1, max_width=-1)
    if args.summary:
        small.write(args.summary, format="ascii.rst", overwrite=True)
        print(f"wrote {args.summary}")
    if args.out:
        table.write(args.out, format="ascii.ecsv", overwrite=True)
        print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
