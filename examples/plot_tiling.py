"""
===========================================
Tiling a simulation box at four resolutions
===========================================

A radiative-MHD snapshot covers ~100 Mm, a few percent of the GONG field.  The
paper (Sec. 3.2, Fig. 8) therefore repeats the box over the detector, once per
viewing angle, and shows it at four scales at once: quadrant k is magnified
2^k times (GONG resolution at the bottom left, 2×, 4× and 8× to the right and
top), which is the same as an instrument with 2^k times better resolution.

This example builds those scenes with `gongsynth.stages.scene.tiled` from the built-in
photosphere at disk centre and at 60° latitude, pushes them through the PSF
and the pixelization of `gongsynth.stages.optics`, and turns the noise-free expected
counts into magnetograms with the GONG reduction.
"""
# sphinx_gallery_thumbnail_number = 2
import astropy.units as u
import matplotlib.pyplot as plt
import numpy as np
import sunpy.map

from gongsynth import GONGInstrument
from gongsynth.geometry import Pointing
from gongsynth.stages.channels import channel_images
from gongsynth.stages.optics import expected_counts, observe
from gongsynth.stages.reduction import reduce
from gongsynth.stages.scene.tiled import tiled_scenes
from gongsynth.sun.photosphere import model_photosphere, synthesize

gong = GONGInstrument()

# %%
# The input tile
# --------------
#
# A 98 Mm periodic photosphere (sunspot, plage, network) sampled every 192 km.
# The paper's MURaM box is 1024² columns of 96 km; half the sampling keeps
# this example fast and changes nothing at GONG's 2.5″ pixels.

photosphere = model_photosphere(shape=(512, 512), pixel_size=192 * u.km, seed=3)
extent = np.array([0, 512, 0, 512]) * 0.192  # Mm

fig, ax = plt.subplots(figsize=(5, 4.5), layout="constrained")
im = ax.imshow(photosphere.bz.to_value(u.G), origin="lower", cmap="gray", vmin=-500, vmax=500,
               extent=extent)
ax.set(xlabel="x [Mm]", ylabel="y [Mm]", title="input tile: $B_z$")
fig.colorbar(im, ax=ax, label="G")

# %%
# Scenes at 0° and 60°
# --------------------
#
# Each viewing angle is a separate scene.  The spectra are synthesised at the
# μ and line-of-sight azimuth of a region on the central meridian
# (`gongsynth.geometry.Pointing`), collapsed to the six channel planes
# (filter first), tiled over a 430 × 430-pixel field (half of GONG's, to keep
# this example short) and placed on a helioprojective grid whose centre lies at
# the chosen latitude.  The 60° scene is foreshortened by cos 60° = 0.5
# north-south.

maps = {}
for latitude in (0, 60) * u.deg:
    pointing = Pointing(latitude)
    cube = synthesize(photosphere, mu=pointing.mu, los_azimuth=pointing.los_azimuth, instrument=gong)
    scene, _ = tiled_scenes(channel_images(cube, instrument=gong), cube.blos, cube.pixel_size,
                            pointing=pointing, resolutions=(1, 2, 4, 8), detector_shape=430,
                            instrument=gong)
    counts = expected_counts(scene)  # electrons per frame per pixel, 6 planes
    observed = reduce(counts.value, gong)
    truth = observe(scene.blos, scene.pixel_scale, instrument=gong, boundary=scene.boundary)
    header = scene.detector_header
    maps[latitude.value] = (sunpy.map.Map(observed.magnetogram.to_value(u.G), header),
                            sunpy.map.Map(truth.to_value(u.G), header), counts)
    print(f"latitude {latitude}: scene {scene.shape}, median counts in plane 0 "
          f"{np.median(counts[0].value):.3g} e-/frame/pixel")

# %%
# The paper's Fig. 8
# ------------------
#
# Noise-free GONG magnetograms of the two scenes.  Within each image the tile
# gets finer toward the top right; the spot's umbra is resolved only at 4× and
# 8×.  At 60° the line-of-sight field of the vertical spot field drops by μ and
# the penumbra's horizontal field shows up on the limb side.  The WCS is true
# for the GONG-resolution quadrant; like the paper's, the tiled field is flat
# and at 60° runs past the limb (it is a tangent plane, not the sphere: see
# the full-disk example for that).

fig = plt.figure(figsize=(11, 5.2), layout="constrained")
for i, latitude in enumerate((0, 60)):
    magnetogram = maps[latitude][0]
    ax = fig.add_subplot(1, 2, i + 1, projection=magnetogram)
    magnetogram.plot(axes=ax, cmap="gray", vmin=-300, vmax=300, title=f"latitude {latitude}°")
fig.colorbar(ax.images[0], ax=fig.axes, label="$B_{LOS}$ [G]", shrink=0.8)

# %%
# Resolution and the calibration
# ------------------------------
#
# In the GONG-resolution quadrant the magnetogram follows the true flux
# density averaged by the PSF and the pixel; the ratio of their spreads shows
# how much of the signal survives the instrument.

fig, axes = plt.subplots(1, 2, figsize=(10, 4), layout="constrained")
for ax, latitude in zip(axes, (0, 60)):
    magnetogram, truth, _ = maps[latitude]
    quadrant = slice(5, 210)  # bottom-left, away from the quadrant edges
    x = truth.data[quadrant, quadrant].ravel()
    y = magnetogram.data[quadrant, quadrant].ravel()
    ax.plot(x, y, ",", alpha=0.3)
    lim = np.percentile(np.abs(x), 99.9)
    ax.plot([-lim, lim], [-lim, lim], "k--", lw=0.8)
    ax.set(xlabel="true $B_{LOS}$ ⊗ PSF ⊗ pixel [G]", ylabel="noise-free GONG [G]",
           title=f"latitude {latitude}°, GONG-resolution quadrant")
plt.show()
