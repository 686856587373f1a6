"""
==============================
A synthetic full-disk GONG map
==============================

The paper avoided mapping its simulation onto the sphere.  `gongsynth.stages.scene.fulldisk`
does it: every supersampled point of GONG's 860 × 860 field is traced to the
solar surface and gets its own viewing angle μ; the Sun's large-scale field
there picks the small scales from a library of patches of the built-in 3-D
Sun (quiet Sun to plage and sunspot columns, synthesised once by LTE radiative
transfer at 7 viewing angles, on columns of 768 km: half a GONG pixel), laid in surface
cells with their own offsets and turns, and every spectrum is Doppler
shifted by the Sun's rotation, the observer's motion and the convective
blueshift.  The result is a full-disk scene that can stand beside a real GONG
magnetogram.

To run in seconds this example uses ``supersampling=1`` (one sample per
pixel); the default is 5 × 5 samples per pixel.  The library is built once
(~10-30 s on 2 cores) and cached.
"""
import astropy.units as u
import matplotlib.pyplot as plt
import numpy as np
import sunpy.map

from gongsynth import GONGInstrument
from gongsynth.geometry import disk_geometry
from gongsynth.stages.optics import expected_counts, observe
from gongsynth.stages.reduction import reduce
from gongsynth.stages.scene.fulldisk import full_disk_scene
from gongsynth.stages.scene.library import LIBRARY_SEED, cached_library
from gongsynth.sun.surface_field import synthetic_surface_field

# %%
# The library of patches (what a full-disk run builds, or loads from its cache)
# and the large-scale field: the seeded synthetic Sun of 2014-04-01, near the
# maximum of cycle 24.

gong = GONGInstrument()
library = cached_library(seed=LIBRARY_SEED, instrument=gong, sun="model-atmosphere")
print(library)
date = "2014-04-01T18:00"
field = synthetic_surface_field(date, seed=3)

# %%
# The scene and the expected counts
# ---------------------------------
#
# `full_disk_scene` returns the light (radiance at Earth per arcsec², six
# planes, zero beyond the limb) and the true line-of-sight field at the same
# points.  The optics then apply the PSF (with a dark sky beyond the
# field) and the pixelization.

light, truth = full_disk_scene(library, supersampling=1, instrument=gong, obstime=date, surface_field=field,
                               seed=1)
counts = expected_counts(light)
observed = reduce(counts.value, gong)
header = light.detector_header
geometry = disk_geometry(counts.shape[1:], gong.plate_scale, obstime=date)  # detector pixel centres
continuum = sunpy.map.Map(counts.value.mean(axis=0), header)
# Beyond the limb only the PSF wings remain: mask the magnetogram there.
magnetogram = sunpy.map.Map(np.where(geometry.on_disk, observed.magnetogram.to_value(u.G), np.nan),
                            header)
true_field = sunpy.map.Map(observe(truth.data, truth.pixel_scale, instrument=gong,
                                   boundary=truth.boundary).to_value(u.G), header)

fig = plt.figure(figsize=(12, 4.6), layout="constrained")
for i, (smap, kwargs, title) in enumerate([
        (continuum, dict(cmap="gray"), "mean of the 6 planes [e-/frame]"),
        (magnetogram, dict(cmap="gray", vmin=-100, vmax=100), "noise-free GONG $B_{LOS}$ [G]"),
        (true_field, dict(cmap="gray", vmin=-100, vmax=100), "true $B_{LOS}$ ⊗ PSF ⊗ pixel [G]")]):
    ax = fig.add_subplot(1, 3, i + 1, projection=smap)
    smap.plot(axes=ax, title=title, **kwargs)
    smap.draw_limb(axes=ax, color="C1", lw=0.5)

# %%
# Limb darkening
# --------------
#
# Each point is seen at its own μ, so the continuum falls toward the limb as
# the radiative transfer of the 3-D Sun gives it.  The counts of a channel plane are
# plotted against μ of the pixel centre; the spread at each μ is granulation,
# the darker spots and the Doppler shifts moving the line in the passband.

on = geometry.on_disk & (geometry.mu > 0.05)
mu = geometry.mu[on]
centre = np.median(counts[0].value[on][mu > 0.98])
fig, ax = plt.subplots(figsize=(6, 4), layout="constrained")
ax.plot(mu, counts[0].value[on] / centre, ",", alpha=0.3)
ax.set(xlabel="μ", ylabel="plane I+V ch0 / disk centre", title="limb darkening", ylim=(0, 1.2))
print(f"disk-centre counts, plane I+V ch0: {centre:.4g} e- per frame per pixel")
plt.show()
