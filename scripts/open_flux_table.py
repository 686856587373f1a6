"""
The PFSS open flux of every real synoptic map, raw and calibrated, beside the in-situ value.

Reads the GONG and HMI Carrington synoptic maps of ``shared/data/real/gong`` and
``shared/data/real/pairs`` (see their PROVENANCE.md) with `gongsynth.load_observation`,
computes `gongsynth.open_flux` (source surface 2.5 R_sun, the defaults of
`gongsynth.analysis.open_flux`) of each map as observed and, for GONG, after
`gongsynth.calibrate` (the table shipped with gongsynth: the true field), and writes
the QTable as ECSV and as the reStructuredText table (.txt) included by the user guide::

    python scripts/open_flux_table.py --out docs/guide/open_flux_table

(about 2 minutes on 2 cores; the numbers are deterministic).  HMI maps are not
calibrated: the shipped table is GONG's.  When HMI's scale exists
(``gongsynth.calibrate(smap, to="hmi")``, issue 22) it is one more entry of ``SCALES``.

The in-situ value: Badman et al. (2021, A&A 650, A18), from Parker Solar Probe,
STEREO-A and Wind, best estimate of the heliospheric flux |B_R| R² ≈ 2.5 nT AU²
(PSP encounters 1-5, Nov 2018 - Jun 2020, at perihelion where folded flux is
negligible), turned into a total unsigned flux as 4π (1 AU)² |B_R| R²
(`gongsynth.analysis.open_flux.in_situ_open_flux`, the Ulysses result that
|B_R| R² does not depend on latitude).  No published in-situ open flux for the
maps' own rotations (CR 2253-2263, 2022) was found; the open flux rose with solar
cycle 25 after 2020, so the 2022 value is probably higher and the ratios in the
table are lower bounds of the gap.
"""
import argparse
import time
import warnings
from pathlib import Path

import astropy.units as u
import numpy as np
from astropy.table import QTable
from sunpy.util.exceptions import SunpyMetadataWarning

import gongsynth
from gongsynth.analysis.open_flux import in_situ_open_flux, prepare_synoptic_map

REAL = Path(__file__).resolve().parents[2] / "shared" / "data" / "real"

#: The real Carrington synoptic maps (relative to shared/data/real).
MAPS = (
    "gong/mrbqs221029t0304c2263_067.fits",
    "gong/SWMF_util_fitsfile_GONG_synoptic_20220302t0614.fits",
    "pairs/gong_mrzqs_c2253.fits",
    "pairs/gong_mrzqs_c2254.fits",
    "pairs/gong_mrzqs_c2255.fits",
    "pairs/hmi.Synoptic_Mr_small.2253.fits",
    "pairs/hmi.Synoptic_Mr_small.2254.fits",
    "pairs/hmi.Synoptic_Mr_small.2255.fits",
)

#: The scales each GONG map is put on before the extrapolation (HMI's: issue 22, when it lands).
SCALES = {"raw": None, "calibrated": gongsynth.calibrate}

#: Badman et al. 2021 (A&A 650, A18): |B_R| R² at PSP perihelia, 2018-11 to 2020-06.
IN_SITU_BR_R2 = 2.5 * u.nT
IN_SITU_SOURCE = "Badman et al. 2021 (A&A 650, A18): |B_R|R^2 = 2.5 nT AU^2, PSP E1-E5 2018-2020"


def load(relpath, root):
    """A real map through `gongsynth.load_observation`."""
    with warnings.catch_warnings():  # HMI's charts have no observer; sunpy assumes the Earth (right here)
        warnings.simplefilter("ignore", SunpyMetadataWarning)
        return gongsynth.load_observation(root / relpath)


def unsigned_surface_flux(smap):
    """Unsigned photospheric flux of the prepared (filled, balanced) map, in Mx."""
    ready = prepare_synoptic_map(smap)
    pixel = 4 * np.pi * (1 * u.R_sun) ** 2 / ready.data.size
    return (np.abs(ready.data).sum() * u.G * pixel).to(u.Mx)


def rotation(smap):
    """The map's Carrington rotation number (-1 if the header has none)."""
    return int(smap.meta.get("car_rot", smap.meta.get("carrot", -1)))


def build_table(root, maps=MAPS):
    """The QTable: one row per map, the open flux raw and calibrated beside the in-situ value."""
    rows = []
    in_situ = in_situ_open_flux(IN_SITU_BR_R2)
    for relpath in maps:
        smap = load(relpath, root)
        gong = "hmi" not in Path(relpath).name
        row = {"map": Path(relpath).name, "instrument": "GONG" if gong else "HMI", "rotation": rotation(smap),
               "date": smap.date.isot[:10]}
        for scale, convert in SCALES.items():
            if not gong and convert is not None:
                row[f"surface_{scale}"] = row[f"open_{scale}"] = np.nan * u.Mx
                continue
            scaled = smap if convert is None else convert(smap)
            row[f"surface_{scale}"] = unsigned_surface_flux(scaled)
            row[f"open_{scale}"] = gongsynth.open_flux(scaled)
        row["in_situ"] = in_situ
        row["gap_raw"] = (in_situ / row["open_raw"]).to(u.one)
        row["gap_calibrated"] = (in_situ / row["open_calibrated"]).to(u.one)
        rows.append(row)
        print(f"{row['map']:58s} CR {row['rotation']}  open raw {row['open_raw']:.3e}  "
              f"calibrated {row['open_calibrated']:.3e}  in situ / raw {row['gap_raw']:.2f}")
    table = QTable(rows=rows)
    for name in ("surface_raw", "surface_calibrated", "open_raw", "open_calibrated", "in_situ"):
        table[name] = table[name].to(1e22 * u.Mx)
        table[name].info.format = ".3f"
    for name in ("gap_raw", "gap_calibrated"):
        table[name].info.format = ".2f"
    table.meta.update({
        "description": "PFSS open flux (total unsigned, source surface 2.5 R_sun, nr 40, 90x180 CEA grid, "
                       "polar_fill nearest, zero_point subtract) of the real synoptic maps, raw and "
                       "calibrated to the truth with gongsynth's shipped table; surface_* is the "
                       "unsigned photospheric flux of the same prepared map",
        "in_situ_source": IN_SITU_SOURCE,
        "in_situ_conversion": "4 pi (1 AU)^2 |B_R| R^2 (latitude-independent |B_R| R^2, Ulysses)",
        "gongsynth_version": gongsynth.__version__,
    })
    return table


def resolution_check(root, relpath="pairs/gong_mrzqs_c2254.fits"):
    """The default grid against a finer one on one map (resolution error of the table)."""
    smap = load(relpath, root)
    base = gongsynth.open_flux(smap)
    fine_angle = gongsynth.open_flux(smap, shape=(180, 360))
    fine_radius = gongsynth.open_flux(smap, nr=80)
    print(f"{relpath}: 90x180 nr 40 {base:.4e}; 180x360 {fine_angle / base - 1:+.2%}; nr 80 "
          f"{fine_radius / base - 1:+.2%}")
    return {"resolution_check_map": relpath, "finer_angle_change": float(fine_angle / base - 1),
            "finer_radius_change": float(fine_radius / base - 1)}


def main():
    """Command line: build, print and (with --out) write the table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--real", type=Path, default=REAL, help="shared/data/real folder")
    parser.add_argument("--out", type=Path, help="write OUT.ecsv and OUT.txt (the table in reStructuredText)")
    args = parser.parse_args()
    start = time.perf_counter()
    table = build_table(args.real)
    table.meta.update(resolution_check(args.real))
    print(table)
    if args.out is not None:
        table.write(args.out.with_suffix(".ecsv"), overwrite=True)
        shown = table.copy()
        for name in ("surface_raw", "surface_calibrated", "open_raw", "open_calibrated", "in_situ"):
            shown[name] = shown[name].value
            shown[name].info.format = ".3f"
        shown.remove_column("date")
        shown.write(args.out.with_suffix(".txt"), format="ascii.rst", overwrite=True)
    print(f"{time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
