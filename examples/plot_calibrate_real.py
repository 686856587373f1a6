"""
=====================================================
Calibrating real magnetograms: a synoptic map and HMI
=====================================================

`gongsynth.calibrate` turns measured line-of-sight fields into the true fields
they imply, with the papers' curves truth = g(measured) for the viewing angle
of each pixel (see the guide's calibration page).  Here it calibrates a real
GONG synoptic map and a real SDO/HMI magnetogram (a 31° × 31° cut-out at
disk centre) with the table
shipped with gongsynth, and shows what changed.

The shipped table was made from gongsynth's default Sun (the 3-D model
atmosphere through LTE radiative transfer, with a sunspot; two seeds per
angle).  Its disk-centre factor, about 1.2, stays below paper III's "more than
2" for the reasons the example "Why GONG under-measures weak fields" measures,
so the numbers below describe that Sun, not the final word on GONG.
The real files live in the project's ``shared/data/real`` folder, outside
the repository (see its ``PROVENANCE.md``).
"""
# sphinx_gallery_thumbnail_number = 2
import os
from pathlib import Path

import astropy.units as u
import matplotlib.pyplot as plt
import numpy as np
import sunpy.map

import gongsynth
from gongsynth.analysis.apply_calibration import viewing_angle, weak_flux_factor_map
from gongsynth.analysis.calibration_table import read_calibration_table

# The real files: the project's shared/data/real (the docs build sets the variable).
REAL = Path(os.environ.get("GONGSYNTH_REAL_DATA", "shared/data/real"))

# %%
# The table
# ---------
#
# One row per viewing angle and region: the weak-flux factor (true per
# measured flux at zero field) with its statistical uncertainty (the seeds'
# scatter and the bootstrap) and the Sun-model ensemble's systematic one
# (quiet Sun), and the curve.
table = read_calibration_table()
print(table["latitude", "region", "factor", "uncertainty", "systematic", "n_pixels"])

fig, ax = plt.subplots(figsize=(6, 4), layout="constrained")
for region, colour in (("quiet", "C0"), ("sunspot", "C3")):
    rows = table[np.asarray(table["region"]) == region]
    ax.errorbar(rows["latitude"].to_value(u.deg), rows["factor"], rows["uncertainty"], marker="o",
                color=colour, label=region)
ax.axhline(1, color="grey", lw=0.8)
ax.set(xlabel="viewing angle θ (deg)", ylabel="true / measured flux at B → 0",
       title="Weak-flux factor of the shipped table")
ax.legend()

# %%
# A GONG synoptic map
# -------------------
#
# Each longitude of a synoptic map was observed near central-meridian passage,
# so the viewing angle of a pixel is its latitude minus the B0 angle.
synoptic = sunpy.map.Map(REAL / "gong" / "mrbqs221029t0304c2263_067.fits")
calibrated = gongsynth.calibrate(synoptic)
factor = weak_flux_factor_map(synoptic)

fig = plt.figure(figsize=(7.5, 10), layout="constrained")
for number, (smap, title, kwargs) in enumerate([
        (synoptic, "GONG synoptic map (measured)", dict(vmin=-30, vmax=30, cmap="gray")),
        (calibrated, "calibrated with the shipped table", dict(vmin=-30, vmax=30, cmap="gray")),
        (factor, "weak-flux factor applied", dict(vmin=0.9, vmax=1.3, cmap="viridis"))], 1):
    ax = fig.add_subplot(3, 1, number, projection=smap)
    image = smap.plot(axes=ax, **kwargs)
    ax.set_title(title)
    fig.colorbar(image, ax=ax, label="G" if number < 3 else "factor", extend="both", shrink=0.8)

both = np.isfinite(synoptic.data) & np.isfinite(calibrated.data)
flux_ratio = np.abs(calibrated.data[both]).sum() / np.abs(synoptic.data[both]).sum()
print(f"unsigned flux, calibrated / measured: {flux_ratio:.3f}")

# %%
# An HMI magnetogram
# ------------------
#
# On a disk image the viewing angle follows from each pixel's distance to
# disk centre (this cut-out reaches θ ≈ 23°); beyond the table's last angle
# (75°) its curve is used.  ``calibrate`` reads the instrument from the header
# (TELESCOP ``SDO/HMI``) and applies HMI's own table
# (``calibration_hmi.ecsv``), whose quiet-Sun factors lie below 1: the curve
# is the expected truth given the measurement, and HMI's 45-s photon noise
# dilutes that regression (the calibration guide says more).
hmi = gongsynth.load_observation(REAL / "hmi" / "JSOC_hmi.m_45s.20101020_000000_TAI.2.magnetogram.fits")
hmi_calibrated = gongsynth.calibrate(hmi)
theta = viewing_angle(hmi).to_value(u.deg)
ratio = np.where(np.abs(hmi.data) > 20, hmi_calibrated.data / hmi.data, np.nan)

fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), layout="constrained")
edges = np.arange(0, np.nanmax(theta) + 2.5, 2.5)
centres = (edges[:-1] + edges[1:]) / 2
which = np.digitize(theta, edges) - 1
median = [np.nanmedian(ratio[which == k]) if np.any(np.isfinite(ratio[which == k])) else np.nan
          for k in range(centres.size)]
axes[0].plot(centres, median, "o-")
axes[0].set(xlabel="viewing angle θ (deg)", ylabel="calibrated / measured (|B| > 20 G)",
            title="HMI 2010-10-20: what the calibration did")
good = np.isfinite(hmi.data) & np.isfinite(hmi_calibrated.data)
axes[1].hist([hmi.data[good], hmi_calibrated.data[good]], bins=np.linspace(-100, 100, 81),
             histtype="step", label=["measured", "calibrated"], log=True)
axes[1].set(xlabel="B_LOS (G)", ylabel="pixels", title="field distribution")
axes[1].legend()
hmi_ratio = np.abs(hmi_calibrated.data[good]).sum() / np.abs(hmi.data[good]).sum()
print(f"HMI unsigned flux, calibrated / measured: {hmi_ratio:.3f}")

plt.show()
