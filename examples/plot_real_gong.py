"""
===============================================
A simulated GONG magnetogram next to a real one
===============================================

A real GONG 10-minute magnetogram from the Big Bear site, 2009-09-05 18:54
(solar minimum: quiet network, no active region), read from its site file in
the old GONG header (which sunpy alone refuses; `gongsynth.load_observation`
places it on the Sun from its RADIUS, limb fit and disk-centre keywords), next
to a simulated 10-minute GONG magnetogram of gongsynth's built-in Sun at disk
centre, both measured the same way by `gongsynth.compare`.

The two Suns differ on purpose: the simulated field (gongsynth's default 3-D
Sun, a 98 Mm box repeated over the field) holds a sunspot and network, the
real one is the quiet Sun of a solar minimum.  What should agree is
what the instrument adds: the noise in the quietest 60″ box near disk centre
(the real map's is 4.0 G in ``PROVENANCE.md``), and the pixel-to-pixel
noise.  That noise follows the number of photons, so the last section sets the
simulated count level next to the real one (from the intensity image of the
same minute and the header's ``ACCUM`` and ``DIODE1``-``DIODE3``).  The real
files live in the project's ``shared/data/real`` folder, outside the
repository.
"""
# sphinx_gallery_thumbnail_number = 1
import os
from pathlib import Path

import astropy.units as u
import matplotlib.pyplot as plt
from astropy.coordinates import SkyCoord
from matplotlib.colors import Normalize

import gongsynth
from gongsynth.analysis.compare import compare
from gongsynth.analysis.count_levels import count_levels
from gongsynth.analysis.noise import noise_estimate

# The real files: the project's shared/data/real (the docs build sets the variable).
REAL = Path(os.environ.get("GONGSYNTH_REAL_DATA", "shared/data/real"))

# %%
# The two magnetograms
# --------------------
real = gongsynth.load_observation(REAL / "gong" / "bbbqa090905t1854.fits.gz")
result = gongsynth.simulate(seed=1, duration=10 * u.min, progress=False)
simulated = result.magnetogram

fig = plt.figure(figsize=(11, 5), layout="constrained")
for number, (smap, title) in enumerate(((real, "real GONG, Big Bear 2009-09-05"),
                                        (simulated, "gongsynth, built-in Sun at disk centre")), 1):
    # The same 600″ × 600″ at disk centre from each.
    frame = smap.coordinate_frame
    cut = smap.submap(SkyCoord(-300 * u.arcsec, -300 * u.arcsec, frame=frame),
                      top_right=SkyCoord(300 * u.arcsec, 300 * u.arcsec, frame=frame))
    ax = fig.add_subplot(1, 2, number, projection=cut)
    image = cut.plot(axes=ax, norm=Normalize(-50, 50), cmap="gray")
    ax.set_title(title)
fig.colorbar(image, ax=fig.axes, label="B_LOS (G)", extend="both", shrink=0.8)

# %%
# Noise in the quietest boxes
# ---------------------------
#
# 29 boxes of 60″ within 0.35 R☉ of disk centre; the quietest one's robust
# sigma is the headline number (`gongsynth.analysis.noise.noise_estimate`).
for label, smap in (("real", real), ("simulated", simulated)):
    noise = noise_estimate(smap)
    print(f"{label:9s}: quietest box robust sigma {noise.sigma:.2f}, "
          f"pixel-difference noise {noise.difference:.2f}")

# %%
# Measured the same way
# ---------------------
report = compare(simulated, real, labels=("gongsynth", "GONG Big Bear"), fig=plt.figure(figsize=(13, 8)),
                 statistics=False)
print(report.summary())
plt.show()

# %%
# Count levels
# ------------
#
# One scale for both: adu per camera frame per pixel in one of the six planes.
# The real intensity image is the sum over the three phase planes of
# one-minute planes of ``ACCUM`` = 600 frames in DN (1 DN = 8 adu), so its
# disk-centre 146 000 counts are 146 000 × 8 / (3 × 600) ≈ 650 adu per frame;
# ``DIODE1``-``DIODE3`` are the per-frame sums of the three phase planes over
# the camera's pixels (`gongsynth.analysis.count_levels` explains the reading
# and the alternatives).  ``effective_area`` is the area at which gongsynth,
# per unit solid angle, would reach the real level: counts scale linearly
# with it.  The DIODE rows need a full-disk run (``mode="full-disk"``).
intensity = gongsynth.load_observation(REAL / "gong" / "bbiqa090905t1854.fits.gz", kind="continuum")
levels = count_levels(intensity, result)
for name in ("real", "simulated", "ratio", "effective_area"):
    levels[name].info.format = ".3g"
levels.pprint(max_width=120)
print(f"DIODE check, image sum / (ACCUM / 8 × ΣDIODE): {levels.meta['diode_check']:.4f}")
