"""
GONG, HMI and MDI full-disk magnetograms of one Sun, compared as synoptic maps would see them.

The conversion table compares the instruments on 10″ cells of a small field;
synoptic maps compare them on 1° Carrington cells built from strips near the
central meridian.  This script observes one full-disk Sun (the seeded
synthetic Sun of ``DATE``, the default full-disk Sun of
`gongsynth.simulate`: the Milne–Eddington patch library over the large-scale
field, the same seed for every instrument) with GONG (its 860² detector, a
1-minute magnetogram), MDI (its 1024² detector, the 1-minute magnetogram) and
HMI (the central 2048² of its 4096² CCD, ±516″, one 45-s sequence: the whole
CCD costs four times more and the strip's cells poleward of about 30° are
what it would add), then for each map and its truth:

1. bins it flux-preserving onto 5″ helioprojective cells
   (`gongsynth.analysis.degrade.degrade_to_gong` without PSF: pixels only),
2. remaps the cells onto a 1° Carrington grid (cylindrical equal area, 360 ×
   180, GONG's synoptic grid) with `reproject`'s exact, area-weighted
   algorithm (sunpy's ``reproject_to``: flux-preserving, as in
   `gongsynth.cross_calibrate`),
3. divides by μ (radial field, as GONG's ``mrzqs`` and HMI's synoptic charts)
   and keeps the cells within ``STRIP`` of the central meridian,

and compares every pair with `gongsynth.cross_calibrate` on those cells (by
|latitude| band), each instrument with its truth, and GONG with itself put on
HMI's and MDI's scales by the shipped conversion table
(``calibrate(gong, to=...)``: the predicted factor averaged over the same
cells, to read beside the measured one).  Nothing is fitted.

Usage (several minutes on 2 cores; ``--cache DIR`` keeps the three runs' maps)::

    python scripts/fulldisk_cross_calibration.py --out docs/guide/fulldisk_cross_calibration.ecsv \
        --summary docs/guide/fulldisk_cross_calibration.txt [--cache DIR] [--sun S] [--date D] \
        [--gong-seeing kolmogorov]
"""
import argparse
import datetime
import warnings
from pathlib import Path

import astropy.units as u
import numpy as np
import sunpy.map
from astropy.table import QTable, vstack
from sunpy.coordinates import sun
from sunpy.map.header_helper import make_heliographic_header
from sunpy.util.exceptions import SunpyMetadataWarning

import gongsynth
from gongsynth import instruments as family
from gongsynth.analysis.apply_calibration import viewing_angle
from gongsynth.analysis.degrade import degrade_to_gong
from gongsynth.version import git_commit

#: The date (solar maximum: active regions on the disk) and seed of the three runs.
DATE = "2014-04-01T18:00"
SEED = 1

#: Detector sides (None: the instrument's own full-disk detector).
DETECTORS = {"gong": None, "hmi": 2048, "mdi": None}

#: Half-width in Carrington longitude of the strip kept around the central meridian.
STRIP = 10 * u.deg

#: Side of the helioprojective cells each map is binned onto before the remapping.
CELL = 5 * u.arcsec

#: |latitude| bands of the comparison (deg).
BANDS = [0, 15, 30, 45, 60, 90] * u.deg

#: (map_a, map_b) pairs compared: ratios are b over a.
PAIRS = (("gong", "hmi"), ("gong", "mdi"), ("mdi", "hmi"), ("gong", "truth_gong"), ("hmi", "truth_hmi"),
         ("mdi", "truth_mdi"), ("gong", "gong_on_hmi"), ("gong", "gong_on_mdi"))


def observe(name, *, date=DATE, seed=SEED, progress=False, cache=None, sun=None, gong_seeing=None):
    """
    One instrument's full-disk magnetogram and truth of the Sun of ``date`` (kept in ``cache``).

    ``gong_seeing``: GONG's ``seeing_profile`` (default the instrument's).
    """
    paths = None if cache is None else [Path(cache) / f"{name}_{w}.fits" for w in ("magnetogram", "truth")]
    if paths and all(path.exists() for path in paths):
        return tuple(sunpy.map.Map(path) for path in paths)
    instrument = name
    if name == "gong" and gong_seeing is not None:
        instrument = family.get("gong").replace(seeing_profile=gong_seeing)
    result = gongsynth.simulate(instrument=instrument, mode="full-disk", seed=seed, obstime=date,
                                detector_shape=DETECTORS[name], progress=progress,
                                **({} if sun is None else {"sun": sun}))
    maps = (result.magnetogram, result.truth)
    for smap, path in zip(maps, paths or ()):
        path.parent.mkdir(parents=True, exist_ok=True)
        sunpy.map.Map(np.asarray(smap.data, np.float64), smap.meta).save(path, overwrite=True)
    return maps


def carrington_grid(date):
    """GONG's synoptic grid: 360 × 180 cylindrical-equal-area Carrington cells (1° in longitude)."""
    header = make_heliographic_header(date, "earth", (180, 360), frame="carrington", projection_code="CEA")
    header["bunit"] = "G"
    return header


def on_carrington(smap, header):
    """A disk image's radial field on the Carrington grid: 5″ cells, exact reprojection, ÷ μ."""
    cells = degrade_to_gong(smap, family.get("gong").replace(plate_scale=CELL), psf=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SunpyMetadataWarning)
        remapped = cells.reproject_to(header, algorithm="exact")
    meta = dict(header)
    for key in ("telescop", "instrume", "content"):
        if key in smap.meta:
            meta[key] = smap.meta[key]
    chart = sunpy.map.Map(np.asarray(remapped.data, float), meta)
    mu = np.cos(viewing_angle(chart).to_value(u.rad))
    return sunpy.map.Map(chart.data / mu, meta)


def strip_mask(chart, half_width=STRIP):
    """Cells within ``half_width`` of the central meridian's Carrington longitude at the chart's date."""
    ny, nx = chart.data.shape
    y, x = np.mgrid[:ny, :nx]
    lon = chart.pixel_to_world(x * u.pix, y * u.pix).lon
    offset = (lon - sun.L0(chart.date)).wrap_at(180 * u.deg)
    return np.abs(offset) <= half_width


def charts(date=DATE, seed=SEED, progress=False, cache=None, sun=None, gong_seeing=None):
    """Every instrument's chart, its truth's, and GONG's put on HMI's and MDI's scales."""
    header = carrington_grid(date)
    out = {}
    for name in DETECTORS:
        magnetogram, truth = observe(name, date=date, seed=seed, progress=progress, cache=cache, sun=sun,
                                     gong_seeing=gong_seeing)
        out[name] = on_carrington(magnetogram, header)
        out[f"truth_{name}"] = on_carrington(truth, header)
    for target in ("hmi", "mdi"):
        out[f"gong_on_{target}"] = gongsynth.calibrate(out["gong"], to=target, instrument="gong")
    return out


def build_table(date=DATE, seed=SEED, progress=False, cache=None, sun=None, gong_seeing=None):
    """The comparisons of `PAIRS` on the central-meridian strip, one QTable."""
    maps = charts(date, seed, progress, cache, sun, gong_seeing)
    mask = strip_mask(maps["gong"])
    tables = []
    for a, b in PAIRS:
        table = gongsynth.cross_calibrate(maps[a], maps[b], angle_bins=BANDS, mask=mask)
        table.add_column(a, name="map_a", index=0)
        table.add_column(b, name="map_b", index=1)
        meta = dict(table.meta)
        tables.append(table)
    out = vstack(tables, metadata_conflicts="silent")
    out.meta.update({k: v for k, v in meta.items() if k not in ("map_a", "map_b", "mask_valid")})
    commit = git_commit()
    out.meta.update({
        "runs": {name: f"gongsynth.simulate(instrument={name!r}, mode='full-disk', seed={seed}, "
                       f"obstime={date!r}, detector_shape={side}"
                       + ("" if sun is None else f", sun={sun!r}") + ")" for name, side in DETECTORS.items()},
        "gong_seeing_profile": gong_seeing or family.get("gong").seeing_profile,
        "remap": f"each map binned onto {CELL} helioprojective cells (no PSF), reprojected (exact) onto "
                 f"360 x 180 CEA Carrington cells, divided by mu; cells within {STRIP} of the central "
                 "meridian",
        "ratio": "map_b / map_a (b = slope x a); gong_on_hmi / gong_on_mdi: calibrate(gong, to=...) with the "
                 "shipped conversion table",
        "gongsynth_version": gongsynth.__version__, "git_commit": commit,
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
    })
    return out


def summary(table):
    """The all-strength slopes by |latitude| band as a small table of strings."""
    every = (table["strength_min"] == 0 * u.G) & np.isinf(table["strength_max"])
    rows = []
    for a, b in PAIRS:
        pick = table[every & (table["map_a"] == a) & (table["map_b"] == b)]
        cells = [f"{r['slope']:.3f} ± {r['slope_uncertainty']:.3f} ({r['n_pixels']})"
                 if np.isfinite(r["slope"]) else f"— ({r['n_pixels']})" for r in pick]
        rows.append([f"{b} / {a}", f"{pick[0]['flux_ratio']:.3f}"] + cells)
    bands = [f"{lo:g}-{hi:g} deg" for lo, hi in zip(BANDS.value[:-1], BANDS.value[1:])]
    return QTable(rows=rows, names=["ratio", "flux ratio", "slope (cells), all"] + bands)


def main(argv=None):
    """Command line: observe, compare, print and (with --out, --summary) write."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--out", type=Path, help="write the table as ECSV")
    parser.add_argument("--summary", type=Path, help="write the slopes by band (reStructuredText)")
    parser.add_argument("--cache", type=Path, help="keep the runs' maps here (FITS): a rerun reads them")
    parser.add_argument("--sun", help="the full-disk Sun (default: simulate's, e.g. 'model-atmosphere')")
    parser.add_argument("--date", default=DATE, help=f"the synthetic Sun's date (default {DATE})")
    parser.add_argument("--gong-seeing", choices=("gaussian", "kolmogorov"),
                        help="GONG's seeing_profile (default the instrument's)")
    args = parser.parse_args(argv)
    table = build_table(date=args.date, progress=True, cache=args.cache, sun=args.sun,
                        gong_seeing=args.gong_seeing)
    small = summary(table)
    small.pprint(max_width=-1, max_lines=-1)
    if args.summary:
        small.write(args.summary, format="ascii.rst", overwrite=True)
    if args.out:
        table.write(args.out, format="ascii.ecsv", overwrite=True)
        print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
