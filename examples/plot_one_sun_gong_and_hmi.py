"""
==============================
One Sun seen by GONG and HMI
==============================

The same seed builds the same 3-D model Sun for every instrument; each
instrument then observes it in its own line (GONG: Ni I 676.8 nm, HMI:
Fe I 617.3 nm), through its own filters, optics and camera, for its own
standard product (GONG: 10 minutes, HMI: one 45-s sequence), and reduces it
with its own algorithm.  Here both look at the same box at disk centre and
at 60°, over the same patch of sky: 48 GONG pixels of 2.5″ and 240 HMI
pixels of 0.504″ (about 120″ each way), a uniform field (``resolutions=(1,)``)
of periodic copies of the box.

The sizes are reduced for the documentation (the gallery must run in
seconds): a box of 96² columns of 384 km (37 Mm, without the sunspot, which
would fill so small a box: kilogauss network elements and internetwork
field) instead of the default 256² with its sunspot, and small detectors
instead of GONG's 860² and HMI's tiled 1024².  The Instruments guide gives
both instruments' weak-flux factors measured on the default Sun.
"""
# %%
import astropy.units as u
import matplotlib.pyplot as plt
import numpy as np

import gongsynth

SEED = 3
FIELD = {"gong": 48, "hmi": 240}    # detector sides: ~120″ of sky for each instrument
LATITUDES = (0, 60)

runs = {(name, lat): gongsynth.simulate(instrument=name, latitude=lat * u.deg, seed=SEED,
                                        detector_shape=side, resolutions=(1,),
                                        photosphere_shape=(96, 96), photosphere={"spot": False},
                                        progress=False)
        for name, side in FIELD.items() for lat in LATITUDES}

# %%
# Magnetograms and truths
# -----------------------
#
# Rows: the viewing angle; columns: each instrument's magnetogram next to its
# truth (the input B_LOS averaged over its pixels).  Axes are arcseconds from
# the field's centre, so the same structure sits at the same place in every
# panel: HMI's five-times-smaller pixels resolve the kilogauss elements that
# GONG's 2.5″ pixels, seeing and 2.8-cm aperture spread into weak patches.
fig, axes = plt.subplots(len(LATITUDES), 4, figsize=(12, 6.4), layout="constrained", sharex=True,
                         sharey=True)
for row, lat in enumerate(LATITUDES):
    for pair, name in enumerate(FIELD):
        result = runs[name, lat]
        half = FIELD[name] * result.config.instrument.plate_scale.to_value(u.arcsec) / 2
        for offset, (what, smap) in enumerate((("magnetogram", result.magnetogram),
                                               ("truth", result.truth))):
            ax = axes[row, 2 * pair + offset]
            image = ax.imshow(smap.data, origin="lower", cmap="gray", vmin=-300, vmax=300,
                              extent=(-half, half, -half, half))
            ax.set_title(f"{result.config.instrument.label} {what}, {lat}°", fontsize=10)
for ax in axes[-1]:
    ax.set_xlabel("x from centre [arcsec]")
for ax in axes[:, 0]:
    ax.set_ylabel("y from centre [arcsec]")
fig.colorbar(image, ax=axes, shrink=0.8, label="B_LOS [G]", extend="both")

# %%
# What each instrument measures of the same Sun
# ---------------------------------------------
#
# The mean unsigned flux density ⟨|B|⟩ of the magnetogram and of the truth
# at each instrument's resolution, and their ratio: GONG sees far less of its
# own truth than HMI does, and its truth is itself smoother (larger pixels).
# HMI's measured ⟨|B|⟩ also holds its 45-s photon noise (about 9 G per pixel),
# which in so quiet a box lifts it to about its truth's; the papers' weak-flux
# factor (`gongsynth.weak_flux_factor`) separates signal from noise, and the
# Instruments guide gives it for both instruments on the default Sun.
for (name, lat), result in runs.items():
    measured = np.nanmean(np.abs(result.magnetogram.data))
    true = np.nanmean(np.abs(result.truth.data))
    print(f"{result.config.instrument.label:4s} {lat:2d}°: ⟨|B|⟩ measured {measured:6.1f} G, "
          f"truth {true:6.1f} G, truth / measured {true / measured:5.2f} "
          f"({result.config.duration.to(u.s):.0f}, {FIELD[name]}² pixels)")

plt.show()
