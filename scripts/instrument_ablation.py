"""
Why GONG and HMI disagree: the predicted GONG→HMI factor with each cause switched off in turn.

The conversion table (``gongsynth/data/cross_calibration_default.ecsv``,
``scripts/build_cross_calibration_table.py``) predicts how much more flux HMI
sees than GONG in the same Sun.  This script asks why: it reruns the table's
GONG and HMI observations (the same built-in Sun, seeds, 160″ field and 10″
common cells, `gongsynth.cross_calibration_sweep.cross_calibration_table`)
with one difference between the two instruments removed at a time, and once
with all of them removed:

``line``
    HMI observes GONG's line, Ni I 676.8 nm, instead of Fe I 617.3 nm.  Of
    the two swaps this is the physical one: HMI's filtergraph is tunable
    (its Michelsons and Lyot element E1 are set by the tuning, its six
    filtergrams sit at offsets from the line), it is the design of MDI, which
    observed Ni I 676.8 nm with the same kind of filters, while GONG's
    filters are fixed crystals and interferometers cut for 676.8 nm (its
    Lyot elements, its Michelson's 22 190 orders and the wave plate would all
    change for Fe I).  gongsynth's HMI on Ni I keeps every filter width and
    offset (in mÅ from the line: front window, blocker, Lyot and Michelson
    periods, the six tunings), takes Ni I's Gaussian look-up-table line from
    gongsynth's MDI (depth and width: `gongsynth.instruments.mdi`), and the
    reduction constant of GONG's and MDI's Ni I reductions (g = 1.5).
``psf``
    No point-spread function in either instrument: no diffraction, no
    scattered light (HMI's Wachter et al. 2012 wings), no seeing (GONG).
``pixels_seeing``
    GONG with HMI's 0.504″ pixels and without seeing, as if it were in space
    (its 2.8-cm aperture's diffraction stays).
``algorithm``
    Each reduction's Zeeman constant K_m from the Landé factor of the line it
    observes in the Sun (Ni I: 1.426, Bruls 1993; Fe I: 2.5) instead of the
    nominal one (GONG 1.5): the part of the algorithm gongsynth can switch
    off; GONG's phase and HMI's look-up-table responses to each line's shape
    stay (they belong to ``line`` here).
``noise``
    No photon and no read noise in either instrument.
``all``
    All five at once: both instruments on Ni I, without PSF, with 0.504″
    pixels, the Sun's Landé factor and no noise; what remains is the
    duration, the filters and the algorithms' response to the line.

For each variant the table gives the GONG→HMI factor (OLS bisector of HMI
against GONG on the common cells, mean over seeds with the seeds' standard
error; with one seed, the default, the bisector's own uncertainty) and each
instrument's factor to the truth; ``share`` is the part of the as-built
factor's logarithm that the switch removes,
ln(F_built / F_variant) / ln F_built: 1 if that cause alone made the whole
difference, 0 if it made none.  Causes interact, so the shares need not add
up to 1 (the ``all`` row says how much is left).  Nothing is tuned: the
instruments are the shipped ones, the switches are the ones above.

Usage (about 10 minutes on 2 cores; ``--cache`` resumes and shares the
as-built runs with the conversion table's build, which uses the same
configurations)::

    python scripts/instrument_ablation.py --out gongsynth/data/instrument_ablation.ecsv \
        --summary docs/guide/instrument_ablation.txt --cache DIR
"""
import argparse
import dataclasses
import datetime
from pathlib import Path

import astropy.units as u
import numpy as np
from astropy.table import QTable

from gongsynth import instruments as family
from gongsynth.analysis.cross_calibration_table import conversion_factors
from gongsynth.config import Effects
from gongsynth.instruments.hmi import HMIInstrument
from gongsynth.sun.rt.atomic_data import get_line
from gongsynth.version import git_commit, version

#: The viewing latitudes and seeds of the ablation (the table's disk centre, where the real pairs'
#: low-latitude cells are seen, and its first seed; ``--latitudes`` and ``--seeds`` add others).
LATITUDES = (0,) * u.deg
SEEDS = (1,)

#: The causes switched off in turn, then together.
CAUSES = ("line", "psf", "pixels_seeing", "algorithm", "noise")

#: What each variant changes (the table's ``switched_off`` column).
DESCRIPTIONS = {
    "as_built": "nothing: the instruments of the conversion table",
    "line": "HMI observes Ni I 676.8 nm (GONG's line) with its own filters, reference line and g = 1.5",
    "psf": "no PSF in either instrument (diffraction, scattered light, seeing)",
    "pixels_seeing": "GONG with HMI's 0.504 arcsec pixels and no seeing",
    "algorithm": "each reduction's K_m from the Sun's Lande factor of its line (Ni I 1.426, Fe I 2.5)",
    "noise": "no photon or read noise in either instrument",
    "all": "all five at once",
}


class NickelHMI(HMIInstrument):
    """HMI observing Ni I 676.8 nm: the radiative transfer synthesises GONG's line for it."""

    line = "Ni I 676.8"


def hmi_on_nickel(hmi):
    """HMI's filtergraph moved to Ni I 676.8 nm, every width and offset from the line kept (see notes)."""
    mdi = family.get("mdi")
    shift = mdi.line_wavelength - hmi.line_wavelength
    changes = {f.name: getattr(hmi, f.name) for f in dataclasses.fields(hmi)}
    changes.update(line_wavelength=mdi.line_wavelength, lande_g=family.get("gong").lande_g,
                   front_window_center=hmi.front_window_center + shift,
                   blocker_center=hmi.blocker_center + shift,
                   reference_line_depth=mdi.reference_line_depth,
                   reference_line_fwhm=mdi.reference_line_fwhm)
    return NickelHMI(**changes)


def variant(causes):
    """The GONG and HMI instruments and the effects with ``causes`` switched off."""
    gong, hmi = family.get("gong"), family.get("hmi")
    effects = {}
    if "line" in causes:
        hmi = hmi_on_nickel(hmi)
    if "psf" in causes:
        effects["psf"] = False
    if "pixels_seeing" in causes:
        gong = gong.replace(plate_scale=hmi.plate_scale, seeing_fwhm=0 * u.arcsec)
    if "algorithm" in causes:
        gong = gong.replace(lande_g=get_line(gong.line).lande * u.one)
        hmi = hmi.replace(lande_g=get_line(hmi.line).lande * u.one)
    if "noise" in causes:
        effects.update(photon_noise=False, read_noise=False)
    return gong, hmi, Effects(**effects)


def ablation_table(latitudes=LATITUDES, seeds=SEEDS, *, cache=None, progress=True):
    """One row per (variant, latitude): the GONG→HMI factor, the factors to the truth, the share removed."""
    from gongsynth.cross_calibration_sweep import cross_calibration_table  # the simulation chain: only here

    variants = [("as_built", ())] + [(cause, (cause,)) for cause in CAUSES] + [("all", CAUSES)]
    rows = []
    built = {}
    for name, causes in variants:
        gong, hmi, effects = variant(causes)
        table = cross_calibration_table((gong, hmi), latitudes, seeds=seeds, cache=cache, progress=progress,
                                        strength_bins=[0, np.inf] * u.G, effects=effects)
        factors = {(source, target): conversion_factors(table, source, target)
                   for source, target in (("gong", "hmi"), ("gong", "truth"), ("hmi", "truth"))}
        latitude, to_hmi, sigma = factors[("gong", "hmi")]
        if len(seeds) == 1:  # no seed scatter: the bisector's own uncertainty
            rows_of = ((table["instrument"] == "gong") & (table["target"] == "hmi")
                       & np.isinf(table["strength_max"]))
            order = np.argsort(table["latitude"][rows_of])
            sigma = np.asarray(table["fit_uncertainty"][rows_of])[order]
        for k, lat in enumerate(latitude):
            if name == "as_built":
                built[float(lat.value)] = to_hmi[k]
            reference = built[float(lat.value)]
            rows.append((name, DESCRIPTIONS[name], lat, to_hmi[k], sigma[k], factors[("gong", "truth")][1][k],
                         factors[("hmi", "truth")][1][k], np.log(reference / to_hmi[k]) / np.log(reference)))
    out = QTable(rows=rows, names=("variant", "switched_off", "latitude", "gong_to_hmi", "uncertainty",
                                   "gong_to_truth", "hmi_to_truth", "share"))
    commit = git_commit()
    out.meta.update({
        "gongsynth_version": version, "git_commit": commit, "seeds": list(seeds),
        "method": "scripts/instrument_ablation.py: the conversion table's GONG and HMI runs "
                  "(cross_calibration_table, 160 arcsec field, 10 arcsec cells) with one cause switched off; "
                  "gong_to_hmi = OLS-bisector slope of HMI against GONG, mean over seeds, uncertainty = "
                  "standard error of the seeds (one seed: the bisector's own, Isobe et al. 1990); "
                  "share = ln(F_as_built / F_variant) / ln(F_as_built)",
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
    })
    return out


def summary(table):
    """The ablation as a small table of strings (the guide includes it)."""
    labels = {"as_built": "nothing (as built)", "pixels_seeing": "pixels & seeing"}
    rows = [[f"{row['latitude'].to_value(u.deg):g}", labels.get(str(row["variant"]), str(row["variant"])),
             f"{row['gong_to_hmi']:.3f} ± {row['uncertainty']:.3f}", f"{row['gong_to_truth']:.3f}",
             f"{row['hmi_to_truth']:.3f}", "" if row["variant"] == "as_built" else f"{row['share']:+.2f}"]
            for row in table]
    return QTable(rows=rows, names=["latitude (deg)", "switched off", "GONG -> HMI", "GONG -> truth",
                                    "HMI -> truth", "share"])


def main(argv=None):
    """Command line: compute the ablation, print it and (with --out) write it as ECSV."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--out", type=Path, help="write the table as ECSV")
    parser.add_argument("--summary", type=Path, help="write the guide's table (reStructuredText)")
    parser.add_argument("--cache", type=Path, help="folder for the runs' maps (resumable)")
    parser.add_argument("--latitudes", type=float, nargs="+", default=LATITUDES.to_value(u.deg),
                        help="viewing latitudes (deg)")
    parser.add_argument("--seeds", type=int, nargs="+", default=SEEDS, help="root seeds")
    args = parser.parse_args(argv)
    table = ablation_table(args.latitudes * u.deg, args.seeds, cache=args.cache)
    for row in table:
        print(f"{row['variant']:14s} {row['latitude'].to_value(u.deg):3.0f} deg  GONG->HMI "
              f"{row['gong_to_hmi']:.3f} +- {row['uncertainty']:.3f}  "
              f"GONG->truth {row['gong_to_truth']:.3f}  "
              f"HMI->truth {row['hmi_to_truth']:.3f}  share {row['share']:+.2f}")
    if args.summary:
        summary(table).write(args.summary, format="ascii.rst", overwrite=True)
    if args.out:
        table.write(args.out, format="ascii.ecsv", overwrite=True)
        print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
