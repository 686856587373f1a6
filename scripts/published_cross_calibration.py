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
three instruments, 1° Carrington cells within 10° of the central meridian).
If gongsynth's GONG and MDI, which observe the same Ni I 676.8 nm line, were
both off by one factor X against HMI (Fe I 617.3 nm), the published HMI/GONG
would be X times gongsynth's, the published MDI/HMI gongsynth's over X, and
MDI/GONG would agree; the table gives X from each of the first two.

Writes ``--summary`` (an RST table for the cross-calibration guide)::

    python scripts/published_cross_calibration.py --summary docs/guide/published_cross_calibration.txt

Reads the tables in ``docs/guide``; takes a second.
"""
import argparse
from pathlib import Path

GUIDE = Path(__file__).resolve().parents[1] / "docs" / "guide"
#: Liu et al. (2025): the factors that put GONG's and MDI's magnetograms on HMI's scale.
LIU_2025 = {"gong": 1.438, "mdi": 0.701}
#: The full-disk runs: table file and what distinguishes it.
RUNS = (("fulldisk_cross_calibration.ecsv", "Milne-Eddington Sun, 2014-04-01"),
        ("fulldisk_cross_calibration_3d.ecsv", "3-D Sun, 2014-04-01"),
        ("fulldisk_cross_calibration_3d_cr2254.ecsv", "3-D Sun, 2022-03-10 (CR 2254)"),
        ("fulldisk_cross_calibration_3d_kolmogorov.ecsv", "3-D Sun, 2014-04-01, Kolmogorov seeing"))


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


def summary(guide=GUIDE):
    """The RST table: each run's three ratios, the published ones and the shared factor X of each."""
    published = published_ratios()
    header = ("run", "HMI/GONG", "MDI/HMI", "MDI/GONG", "X from HMI/GONG", "X from MDI/HMI")
    lines = [header, ("Liu et al. 2025 (published)", f"{published['hmi/gong']:.3f}",
                      f"{published['mdi/hmi']:.3f}", f"{published['mdi/gong']:.3f}", "", "")]
    for name, label in RUNS:
        model = modelled_ratios(guide / name)
        lines.append((f"gongsynth: {label}", f"{model['hmi/gong']:.3f}", f"{model['mdi/hmi']:.3f}",
                      f"{model['mdi/gong']:.3f}", f"{published['hmi/gong'] / model['hmi/gong']:.3f}",
                      f"{model['mdi/hmi'] / published['mdi/hmi']:.3f}"))
    widths = [max(len(line[i]) for line in lines) for i in range(len(header))]
    rule = "  ".join("=" * w for w in widths)
    text = [rule, "  ".join(h.ljust(w) for h, w in zip(header, widths)), rule]
    text += ["  ".join(c.ljust(w) for c, w in zip(line, widths)).rstrip() for line in lines[1:]]
    text.append(rule)
    return "\n".join(text) + "\n"


def main(argv=None):
    """Print the comparison, and write it to ``--summary`` if given."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--summary", type=Path, help="RST file to write")
    args = parser.parse_args(argv)
    text = summary()
    print(text, end="")
    if args.summary is not None:
        args.summary.write_text(text)
    return text


if __name__ == "__main__":
    main()
