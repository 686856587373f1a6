"""
====================================================================
Magnetograms at disk centre and at 60° (the paper's Figs. 11 and 12)
====================================================================

The paper simulates the same MURaM tile at six viewing angles, each as its own
image.  Here the built-in photosphere is seen at latitude 0° and 60° on the
central meridian: at 60° the tile is foreshortened by cos 60° = ½ north–south,
and the line-of-sight field of the (mostly vertical) flux is smaller by about
the same factor.  Only the GONG-resolution quadrant (bottom left) is shown.
"""
# %%
import astropy.units as u
import matplotlib.pyplot as plt
import numpy as np

import gongsynth

results = {lat: gongsynth.simulate(latitude=lat * u.deg, seed=7, detector_shape=256,
                                   progress=False) for lat in (0, 60)}

# %%
# Cut out the lower-left quadrant (GONG resolution) of each magnetogram and
# show it next to the truth.
fig, axes = plt.subplots(2, 2, figsize=(9, 9), layout="constrained")
for row, (lat, res) in enumerate(results.items()):
    n = res.magnetogram.data.shape[0] // 2
    for col, (name, smap) in enumerate([("measured", res.magnetogram), ("true", res.truth)]):
        im = axes[row, col].imshow(smap.data[:n, :n], origin="lower", cmap="gray",
                                   vmin=-300, vmax=300)
        axes[row, col].set_title(f"{name} B_LOS, latitude {lat}°")
fig.colorbar(im, ax=axes, shrink=0.6, label="G")

# %%
# Pixel statistics of the GONG-resolution quadrants.
for lat, res in results.items():
    n = res.magnetogram.data.shape[0] // 2
    b = res.magnetogram.data[:n, :n]
    t = res.truth.data[:n, :n]
    print(f"latitude {lat:2d}°: mean measured {np.mean(b):+6.1f} G, mean true {np.mean(t):+6.1f} G, "
          f"rms difference {np.std(b - t):5.1f} G")

plt.show()
