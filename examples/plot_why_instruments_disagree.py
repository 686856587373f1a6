"""
==================================
Why GONG, HMI and MDI disagree
==================================

Cycle and space-weather studies splice GONG, HMI and MDI magnetograms with
factors fitted on overlapping data.  gongsynth predicts those factors from
physics: one simulated Sun, observed by each instrument, with the truth
known.  This example shows the three magnetograms of one Sun and their
truths, the predicted factors against viewing angle (the conversion table
shipped with gongsynth), the factor measured on three real GONG/HMI synoptic
pairs beside the prediction, and an ablation that switches off, one at a
time, each cause of the GONG/HMI difference.

The magnetograms here are small (a 37-Mm box of 96² columns without the
sunspot, about 120″ of sky) so that the example runs in seconds; the
factors, the real pairs and the ablation come from tables that scripts
compute on the default Sun (see the Cross-calibration guide).
"""
# sphinx_gallery_thumbnail_number = 4
from importlib.resources import files
from pathlib import Path

import astropy.units as u
import matplotlib.pyplot as plt
import numpy as np
from astropy.table import QTable

import gongsynth
from gongsynth.analysis.cross_calibration_table import conversion_factors, read_cross_calibration_table

# %%
# One Sun, three magnetographs
# ----------------------------
#
# The same seed builds the same 3-D Sun for every instrument; each observes
# it in its own line (GONG and MDI: Ni I 676.8 nm, HMI: Fe I 617.3 nm),
# through its own filters, optics and camera, for its own standard product
# (GONG 10 minutes, HMI one 45-s sequence, MDI one minute), and reduces it
# with its own algorithm.  Every detector covers about 120″ of sky at disk
# centre.  The truth (bottom row) is the same field averaged over each
# instrument's pixels.
SIDES = {"gong": 48, "hmi": 240, "mdi": 60}
runs = {name: gongsynth.simulate(instrument=name, seed=3, detector_shape=side, resolutions=(1,),
                                 photosphere_shape=(96, 96), photosphere={"spot": False}, progress=False)
        for name, side in SIDES.items()}

fig, axes = plt.subplots(2, 3, figsize=(10, 6.6), layout="constrained", sharex=True, sharey=True)
for column, (name, result) in enumerate(runs.items()):
    half = SIDES[name] * result.config.instrument.plate_scale.to_value(u.arcsec) / 2
    for row, (what, smap) in enumerate((("magnetogram", result.magnetogram), ("truth", result.truth))):
        image = axes[row, column].imshow(smap.data, origin="lower", cmap="gray", vmin=-300, vmax=300,
                                         extent=(-half, half, -half, half))
        mean = np.nanmean(np.abs(smap.data))
        axes[row, column].set_title(f"{result.config.instrument.label} {what}: ⟨|B|⟩ = {mean:.0f} G",
                                    fontsize=10)
for ax in axes[-1]:
    ax.set_xlabel("x from centre [arcsec]")
for ax in axes[:, 0]:
    ax.set_ylabel("y from centre [arcsec]")
fig.colorbar(image, ax=axes, shrink=0.8, label="B_LOS [G]", extend="both")

# %%
# The predicted factors against viewing angle
# -------------------------------------------
#
# The conversion table (``gongsynth/data/cross_calibration_default.ecsv``,
# built by ``scripts/build_cross_calibration_table.py`` on the default Sun:
# a 98-Mm box with a sunspot, two seeds, six latitudes) compares the
# instruments on common 10″ cells.  Left: the factor that puts one
# instrument on another's scale (target = factor × source); right: each
# instrument's factor to the truth.  GONG sees least, HMI most; MDI, on
# GONG's line with 2″ pixels from space, lies between.
table = read_cross_calibration_table()
fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4), layout="constrained", sharex=True)
for ax, pairs in ((left, (("gong", "hmi"), ("gong", "mdi"), ("mdi", "hmi"))),
                  (right, (("gong", "truth"), ("mdi", "truth"), ("hmi", "truth")))):
    for source, target in pairs:
        latitude, factor, sigma = conversion_factors(table, source, target)
        ax.errorbar(latitude.to_value(u.deg), factor, yerr=sigma, marker="o", capsize=3,
                    label=f"{source.upper()} → {target if target == 'truth' else target.upper()}")
    ax.axhline(1, color="0.6", lw=0.8)
    ax.set_xlabel("viewing angle θ [deg]")
    ax.legend()
left.set_ylabel("factor (target / source)")
left.set_title("between instruments")
right.set_title("to the truth")

# %%
# The real GONG/HMI pairs beside the prediction
# ---------------------------------------------
#
# ``scripts/real_pairs_cross_calibration.py`` compares the GONG (``mrzqs``)
# and HMI synoptic maps of Carrington rotations 2253–2255 on GONG's 1° grid:
# the bisector slope of HMI against GONG by |latitude| band (points), and the
# predicted factor averaged over the same cells (line).  Equatorward of 45°
# the measured ratio lies a few to 25 % above the prediction; poleward the
# two maps hardly correlate (the guide says why).
# The docs build runs the example from examples/; from the repository's root it is docs/guide.
GUIDE = next(path for path in (Path("../docs/guide"), Path("docs/guide")) if path.is_dir())
pairs = QTable.read(GUIDE / "real_pairs_cross_calibration.ecsv")
every = ((pairs["strength_min"] == 0 * u.G) & np.isinf(pairs["strength_max"])
         & (pairs["angle_max"] < 90 * u.deg))
fig, ax = plt.subplots(figsize=(6.4, 4), layout="constrained")
for k, rotation in enumerate(sorted(set(pairs["rotation"]))):
    for scale, style in (("raw", dict(marker="o", ls="none")),
                         ("predicted", dict(marker="_", ms=14, ls="none"))):
        pick = pairs[every & (pairs["rotation"] == rotation) & (pairs["scale"] == scale)]
        middle = (pick["angle_min"] + pick["angle_max"]).to_value(u.deg) / 2 + 1.2 * (k - 1)
        yerr = None if scale == "predicted" else pick["slope_uncertainty"]
        ax.errorbar(middle, pick["slope"], yerr=yerr, capsize=2, color=f"C{k}",
                    label=f"CR {rotation} {'measured' if scale == 'raw' else 'predicted'}", **style)
ax.set_xlabel("|latitude| band centre [deg]")
ax.set_ylabel("HMI / GONG (bisector slope)")
ax.legend(fontsize=8, ncols=2)

# %%
# Why: each cause switched off in turn
# ------------------------------------
#
# ``scripts/instrument_ablation.py`` reruns the table's GONG and HMI
# observations at disk centre with one difference removed at a time: HMI on
# GONG's line (Ni I; the physical swap: HMI's tunable filtergraph is MDI's
# design, which observed Ni I, while GONG's filters are cut for Ni I), no PSF
# or scattered light, GONG with HMI's pixels and no seeing, each reduction's
# Zeeman constant from the Sun's Landé factor of its line, no noise — and
# all five at once.  Each bar is the predicted GONG→HMI factor that is left;
# the shaded band is the real pairs' measured HMI/GONG slope equatorward of
# 25°.  Nothing here is tuned.
ablation = QTable.read(files("gongsynth") / "data" / "instrument_ablation.ecsv")
centre = ablation[ablation["latitude"] == 0 * u.deg]
fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
ax.bar(np.arange(len(centre)), centre["gong_to_hmi"], yerr=centre["uncertainty"], capsize=3,
       color=["0.4"] + ["C0"] * (len(centre) - 2) + ["C3"])
real = pairs[every & (pairs["scale"] == "raw") & (pairs["angle_max"] == 25 * u.deg)]["slope"]
ax.axhspan(real.min(), real.max(), color="C1", alpha=0.25, label="real pairs, |latitude| < 25°")
ax.axhline(1, color="0.6", lw=0.8)
labels = {"as_built": "as built", "pixels_seeing": "pixels & seeing", "all": "all five"}
ax.set_xticks(np.arange(len(centre)), [labels.get(str(v), str(v)) for v in centre["variant"]], rotation=20)
ax.set_ylabel("GONG → HMI factor at disk centre")
ax.legend(loc="upper right")
for k, row in enumerate(centre):
    if row["variant"] != "as_built":
        share = round(float(row["share"]), 2) + 0.0  # no "-0 %"
        ax.annotate(f"{share:+.0%}", (k, row["gong_to_hmi"]), textcoords="offset points",
                    xytext=(0, 8), ha="center", fontsize=8)
for row in centre:
    print(f"{row['variant']:14s} GONG→HMI {row['gong_to_hmi']:.3f} ± {row['uncertainty']:.3f}  "
          f"(share of ln F removed {row['share']:+.2f}): {row['switched_off']}")

# %%
# Read against the real pairs: the PSF (GONG's 2.8-cm diffraction and seeing,
# HMI's scattered light) makes most of the predicted factor, the line and
# the algorithm's Zeeman constant about 5 % each, noise nothing, and with all
# five switched off the two instruments agree (factor 0.99).  The real
# pairs' HMI/GONG ratio lies above the prediction; of these causes only a
# broader GONG PSF than the model's would move the prediction that far (the
# Cross-calibration guide discusses it, with the full-disk comparison on a
# Carrington grid).

# %%
# Three instruments against the published factors
# -----------------------------------------------
#
# Liu et al. (2025, Sol. Phys. 300, 8) put GONG's full-disk magnetograms on
# HMI's scale with a factor 1.438 and MDI's with 0.701.
# ``scripts/published_cross_calibration.py`` sets beside them the ratios of
# one full-disk Sun observed by gongsynth's three instruments (1° Carrington
# cells near the central meridian, the Cross-calibration guide's runs) and
# the shipped conversion table's at disk centre and 45°.  On the full-disk
# cells MDI/GONG, two instruments on the same Ni I line, agrees; HMI/GONG and
# MDI/HMI miss in opposite directions by one shared factor of about 1.2:
# gongsynth puts its two Ni I instruments about 20 % too high against HMI
# (the table's disk centre, where GONG's resolution weighs most, less so).
published = QTable.read(GUIDE / "published_cross_calibration.ecsv")
ratios = {"hmi_over_gong": "HMI / GONG", "mdi_over_hmi": "MDI / HMI", "mdi_over_gong": "MDI / GONG"}
fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
for k, row in enumerate(published):
    offset = 0.12 * (k - (len(published) - 1) / 2)
    style = (dict(marker="*", ms=14, color="k") if k == 0
             else dict(marker="o", ms=6, color=f"C{k - 1}"))
    ax.plot(np.arange(len(ratios)) + offset, [row[name] for name in ratios], ls="none",
            label=row["run"], **style)
ax.set_xticks(np.arange(len(ratios)), list(ratios.values()))
ax.set_xlim(-0.6, len(ratios) - 0.4)
ax.set_ylabel("ratio of the two instruments' readings")
ax.legend(fontsize=8, loc="upper left")
for row in published[1:]:
    print(f"{row['run']}: shared factor X = {row['x_from_hmi_gong']:.2f} (from HMI/GONG), "
          f"{row['x_from_mdi_hmi']:.2f} (from MDI/HMI)")

plt.show()
