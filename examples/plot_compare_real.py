"""
======================================================
A GONG-resolution magnetogram next to a real one (MDI)
======================================================

`gongsynth.compare` puts a simulated GONG magnetogram next to a real
observation, measured the same way.  The real map here is a SOHO/MDI 96-minute
full-disk magnetogram of 2010-10-15, taken in the same Ni I 676.8 nm line as
GONG but with 2″ pixels and less blur; `~gongsynth.compare.degrade_to_gong`
first brings it to GONG's view (the GONG PSF, then flux-conserving binning to
2.5″ pixels).  The real data files live in the project's ``shared/data/real``
folder (see its ``PROVENANCE.md``), outside the repository.

The simulated side is a full-disk GONG magnetogram of gongsynth's model
photosphere (``mode="full-disk"``), and a GONG-format file built on a real
GONG 860 × 860 header shows how real GONG files are read.
"""
# sphinx_gallery_thumbnail_number = 2
import os
import tempfile
from pathlib import Path

import astropy.units as u
import matplotlib.pyplot as plt
import numpy as np
import sunpy.data.test
from astropy.io import fits
from matplotlib.colors import Normalize

import gongsynth
from gongsynth.analysis.compare import compare
from gongsynth.analysis.degrade import degrade_to_gong
from gongsynth.analysis.disk import disk_coordinates
from gongsynth.analysis.limb import limb_darkening
from gongsynth.analysis.noise import noise_estimate
from gongsynth.analysis.observations import load_observation

# The real files: the project's shared/data/real (the docs build sets the variable).
REAL = Path(os.environ.get("GONGSYNTH_REAL_DATA", "shared/data/real"))

# %%
# The real observation
# --------------------
#
# `~gongsynth.compare.load_observation` checks the header (a wrong WCS would
# raise a ``BadHeaderWarning``), refuses files that are not magnetograms and
# returns the map in gauss.  Its quiet-Sun noise, measured as in
# ``PROVENANCE.md`` (the quietest of 29 boxes of 60″ within 0.35 R☉ of disk
# centre, robust sigma = 1.4826 × MAD), is the 9.7 G quoted there.

mdi = load_observation(REAL / "mdi" / "mdi.fd_m_96m_lev182.20101015_000000_TAI.data.fits")
noise_mdi = noise_estimate(mdi)
print(f"MDI at {mdi.scale.axis1:.3f}: quiet-Sun robust sigma {noise_mdi.sigma:.2f}, "
      f"std {noise_mdi.std:.2f} ({noise_mdi.box_pixels}-pixel boxes)")

# %%
# Degraded to GONG
# ----------------
#
# The GONG PSF (Airy pattern of the 2.8 cm aperture ⊗ 3.6″ seeing) and 2.5″
# pixels average the salt-and-pepper field of the quiet Sun: the noise drops
# several-fold, while the total flux is kept.  The PSF correlates neighbouring
# pixels, so the pixel-difference noise estimate now reads well below the box
# estimate: on smoothed data only the box estimate measures the noise.

mdi_gong = degrade_to_gong(mdi)
noise_gong = noise_estimate(mdi_gong)
print(f"MDI degraded to GONG: {mdi_gong.data.shape} pixels of {mdi_gong.scale.axis1:.2f}; "
      f"robust sigma {noise_gong.sigma:.2f}, pixel-difference {noise_gong.difference:.2f}")

fig, axes = plt.subplots(1, 2, figsize=(10, 4.8), subplot_kw={"projection": mdi}, layout="constrained")
axes[1].remove()
axes[1] = fig.add_subplot(1, 2, 2, projection=mdi_gong)
for ax, smap, title in ((axes[0], mdi, "MDI, 1.99″ pixels"), (axes[1], mdi_gong, "MDI degraded to GONG")):
    smap.plot(axes=ax, cmap="gray", norm=Normalize(-150, 150), title=title)
    ax.set_xlim(*(np.array([0.52, 0.82]) * smap.data.shape[1]))
    ax.set_ylim(*(np.array([0.22, 0.52]) * smap.data.shape[0]))

# %%
# A GONG-format file
# ------------------
#
# Real GONG magnetograms (``*zqa*`` files) store 16-bit integers with
# BSCALE = 0.09504 G and the sky at SKYVALUE.  We write such a file around the
# real header that sunpy ships (white noise of 3 G on the disk as data);
# ``load_observation`` reads it as sunpy's ``GONGMagnetogramMap``, in gauss,
# with the sky blanked.

header_file = sunpy.data.test.get_test_filepath("gong_magnetogram.header")
header = fits.Header.fromtextfile(header_file)
geometry = sunpy.data.test.get_dummy_map_from_header(header_file)
rho, _ = disk_coordinates(geometry)
values = np.random.default_rng(7).normal(0.0, 3.0, (860, 860))
values[~(rho < 1)] = header["SKYVALUE"]
hdu = fits.PrimaryHDU(values.astype(np.float32), header)
hdu.scale("int16", bscale=header["BSCALE"], bzero=0)
path = Path(tempfile.mkdtemp()) / "gong_format_zqa.fits"
hdu.writeto(path)
gong_format = load_observation(path)
sigma = noise_estimate(gong_format).sigma
print(type(gong_format).__name__, gong_format.unit, f"quiet-Sun noise {sigma:.2f}")

# %%
# The simulated GONG magnetogram
# ------------------------------
#
# gongsynth fills the large-scale field of the date (the seeded synthetic
# Sun, with its supergranular network) with patches of its 3-D model Sun,
# quiet Sun to plage and sunspot columns, each point seen at its own viewing
# angle (the full disk's patch library).  A one-minute
# magnetogram, as GONG takes them; ``supersampling=2`` keeps this example
# quick (the default 5 changes the field by ~10 G rms, see
# `~gongsynth.stages.scene.fulldisk.full_disk_scene`).

sim = gongsynth.simulate(mode="full-disk", duration=1 * u.min, seed=2, progress=False,
                         instrument=gongsynth.GONGInstrument(supersampling=2)).magnetogram

# %%
# Side by side
# ------------
#
# `~gongsynth.compare.compare` measures both maps the same way: the maps on
# a ±150 G grey scale with the noise boxes marked (the quietest in yellow), the
# noise per box, the on-disk histograms of B and of |B| on log axes, and a table
# of the numbers.  The synthetic Sun is seeded for its date, not observed: its
# active regions are not the real Sun's of that day.

report = compare(sim, mdi, labels=("gongsynth full disk", "MDI at GONG resolution"),
                 fig=plt.figure(figsize=(13, 8)), statistics=False)
print(report.summary())

# %%
# Count levels: limb darkening of the continuum
# ---------------------------------------------
#
# For intensity images, `~gongsynth.compare.limb_darkening` normalises the map
# to its disk-centre level and bins it in μ = cos θ; the simulated GONG
# pseudo-continuum can be laid on the same axes.

continuum = load_observation(REAL / "mdi" / "mdi.fd_ic.20101015_230100_TAI.data.fits", kind="continuum")
profile = limb_darkening(degrade_to_gong(continuum))
a, b = profile.coefficients
mu = np.linspace(0.15, 1, 100)
fig, ax = plt.subplots(figsize=(6, 4), layout="constrained")
ax.fill_between(profile.mu, profile.intensity - profile.scatter, profile.intensity + profile.scatter,
                color="C0", alpha=0.2, lw=0, label="pixel scatter in each μ bin")
ax.plot(profile.mu, profile.intensity, "o", ms=4, label="MDI continuum at GONG resolution")
ax.plot(mu, profile.law(mu), "k-", lw=1, label=f"1 - {a:.2f}(1-μ) - {b:.2f}(1-μ)²")
ax.set_xlabel("μ = cos θ")
ax.set_ylabel("I(μ) / I(disk centre)")
ax.set_title(f"Disk-centre level {profile.centre_level.value:.0f} (MDI units)")
ax.legend()

plt.show()
