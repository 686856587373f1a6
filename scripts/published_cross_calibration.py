"""
gongsynth's full-disk conversion factors between GONG, HMI and MDI beside the published ones.

Liu et al. (2025, Sol. Phys. 300, 8, "Toward a consensus for multi-sourced
photospheric line-of-sight magnetic field cross-calibration"; the abstract's
numbers) give the factors that put each instrument's full-disk magnetograms on
HMI's scale: 1.438 for GONG and 0.701 for MDI (their uncertainties ≤ 0.001;
the factors vary with the distance from disk centre and the field strength).
So HMI/GONG = 1.438, MDI/HMI = 1/0.701 and MDI/GONG = 1.438/0.701.  Liu et
al. (2012, Sol. Phys. 279, 295) found MDI about 1.4 times HMI.

gongsynth's numbers are the bisector slopes over every cell and field strength
of ``scripts/fulldisk_cross_calibration.py``'s tables (one Sun seen by the
three instruments, 1° Carrington cells within 10° of the central meridian),
and the shipped conversion table's factors (10″ cells of the default Sun, a
sunspot box) at disk centre and 45°.
If gongsynth's GONG and MDI, which observe the same Ni I 676.8 nm line, were
both off by one factor X against HMI (Fe I 617.3 nm), the published HMI/GONG
would be X times gongsynth's, the published MDI/HMI gongsynth's over X, and
MDI/GONG would agree; the table gives X from each of the first two.

Writes ``--summary`` (an RST table for the cross-calibration guide) and ``--table`` (the same as
ECSV, which the gallery draws)::

    python scripts/published_cross_calibration.py --summary docs/guide/published_cross_calibration.txt \
        --table docs/guide/published_cross_calibration.ecsv

Reads the tables in ``docs/guide``; takes a second.
"""
import argparse
import math
from pathlib import Path

GUIDE = Path(__file__).resolve().parents[1] / "docs" / "guide"
#: Liu et al. (2025): the factors that put GONG's and MDI's magnetograms on HMI's scale.
LIU_2025 = {"gong": 1.438, "mdi": 0.701}
#: The full-disk runs: table file and what distinguishes it.
RUNS = (("fulldisk_cross_calibration.ecsv", "Milne-Eddington Sun, 2014-04-01"),
        ("fulldisk_cross_calibration_3d.ecsv", "3-D Sun, 2014-04-01"),
        ("fulldisk_cross_calibration_3d_cr2254.ecsv", "3-D Sun, 2022-03-10 (CR 2254)"),
        ("fulldisk_cross_calibration_3d_kolmogorov.ecsv", "3-D Sun, 2014-04-01, Kolmogorov seeing"))
#: Latitudes (deg) at which the shipped conversion table (10″ cells of a sunspot box) is set beside them.
TABLE_LATITUDES = (0.0, 45.0)


def published_ratios():
    """HMI/GONG, MDI/HMI and MDI/GONG from Liu et al. (2025)."""
    return {"hmi/gong": LIU_2025["gong"], "mdi/hmi": 1 / LIU_2025["mdi"],
            "mdi/gong": LIU_2025["gong"] / LIU_2025["mdi"]}


def modelled_ratios(path):
    """The same three ratios from one full-disk table: bisector slopes over all cells and strengths."""
    from astropy.table import Table

    table = Table.read(path, format="ascii.ecsv")
    every = ((table["angle_min"] == 0) & (table["angle_max"] == 90) & (table["strength_min"] == 0)
             & (table["strength_max"] == float("inf")))

    def slope(a, b):
        row = table[every & (table["map_a"] == a) & (table["map_b"] == b)]
        if len(row) != 1:
            raise ValueError(f"{path} has no single all-cells row for {a} -> {b}")
        return float(row["slope"][0])

    return {"hmi/gong": slope("gong", "hmi"), "mdi/hmi": 1 / slope("mdi", "hmi"),
            "mdi/gong": slope("gong", "mdi")}


def table_ratios(latitudes):
    """(latitude, ratios) of the shipped conversion table (10″ cells of the default Sun) at each latitude."""
    import numpy as np

    from gongsynth.analysis.cross_calibration_table import conversion_factors, read_cross_calibration_table

    table = read_cross_calibration_table()
    factors = {}
    for source, target in (("gong", "hmi"), ("hmi", "mdi"), ("gong", "mdi")):
        latitude, factor, _ = conversion_factors(table, source, target)
        factors[source, target] = dict(zip(np.round(latitude.value, 6), factor))
    names = {"hmi/gong": ("gong", "hmi"), "mdi/hmi": ("hmi", "mdi"), "mdi/gong": ("gong", "mdi")}
    return [(latitude, {ratio: factors[pair][latitude] for ratio, pair in names.items()})
            for latitude in latitudes]


def comparison_table(guide=GUIDE):
    """
    An astropy Table: the published ratios, then each run's and the shared factor X from each ratio.

    Columns ``run``, ``hmi_over_gong``, ``mdi_over_hmi``, ``mdi_over_gong``, ``x_from_hmi_gong`` and
    ``x_from_mdi_hmi`` (NaN on the published row).
    """
    from astropy.table import Table

    published = published_ratios()
    rows = [("Liu et al. 2025 (published)", published["hmi/gong"], published["mdi/hmi"],
             published["mdi/gong"], float("nan"), float("nan"))]
    models = [(f"gongsynth: {label}", modelled_ratios(guide / name)) for name, label in RUNS]
    models += [(f"gongsynth: conversion table, 10″ cells, {latitude:.0f}°", ratios)
               for latitude, ratios in table_ratios(TABLE_LATITUDES)]
    for label, model in models:
        rows.append((label, model["hmi/gong"], model["mdi/hmi"], model["mdi/gong"],
                     published["hmi/gong"] / model["hmi/gong"], model["mdi/hmi"] / published["mdi/hmi"]))
    table = Table(rows=rows, names=("run", "hmi_over_gong", "mdi_over_hmi", "mdi_over_gong",
                                    "x_from_hmi_gong", "x_from_mdi_hmi"))
    table.meta["description"] = ("gongsynth's full-disk HMI/GONG, MDI/HMI and MDI/GONG beside Liu et al. "
                                 "(2025, Sol. Phys. 300, 8); scripts/published_cross_calibration.py")
    return table


def summary(table):
    """``comparison_table``'s rows as an RST simple table (three decimals, blank for NaN)."""
    header = ("run", "HMI/GONG", "MDI/HMI", "MDI/GONG", "X from HMI/GONG", "X from MDI/HMI")
    lines = [header] + [(row["run"],) + tuple("" if math.isnan(value) else f"{value:.3f}"
                                               for value in list(row)[1:]) for row in table]
    widths = [max(len(line[i]) for line in lines) for i in range(len(header))]
    rule = "  ".join("=" * w for w in widths)
    text = [rule, "  ".join(h.ljust(w) for h, w in zip(header, widths)), rule]
    text += ["  ".join(c.ljust(w) for c, w in zip(line, widths)).rstrip() for line in lines[1:]]
    text.append(rule)
    return "\n".join(text) + "\n"


def main(argv=None):
    """Print the comparison; write it to ``--summary`` (RST) and ``--table`` (ECSV) if given."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--summary", type=Path, help="RST file to write")
    parser.add_argument("--table", type=Path, help="ECSV file to write")
    args = parser.parse_args(argv)
    table = comparison_table()
    text = summary(table)
    print(text, end="")
    if args.summary is not None:
        args.summary.write_text(text)
    if args.table is not None:
        table.write(args.table, format="ascii.ecsv", overwrite=True)
    return table


if __name__ == "__main__":
    main()
