"""
==============================================
Quick start: a GONG magnetogram in three lines
==============================================

`gongsynth.simulate` runs the whole chain — the built-in 3-D model Sun
(granulation, kilogauss network elements, internetwork fields), LTE radiative
transfer of Ni I 676.8 nm along the rays of the viewing angle, GONG's filters,
optics and camera and the GONG reduction — and returns sunpy Maps.
"""
# sphinx_gallery_parallel = False
# %%
# Three lines: import, simulate, plot.  ``detector_shape=256`` keeps this
# example quick (the default is GONG's full 860 × 860 detector), and the
# 10-minute accumulation of the paper is the default duration.
import matplotlib.pyplot as plt

import gongsynth

result = gongsynth.simulate(seed=1, detector_shape=256, progress=False)
result.magnetogram.peek()

# %%
# The result also holds the ground truth: the input's line-of-sight field
# averaged over each GONG pixel.  The four quadrants show the same photosphere
# tile at GONG resolution (bottom left) and magnified 2×, 4× and 8×.
fig = plt.figure(figsize=(10, 4.6))
for i, smap in enumerate([result.magnetogram, result.truth]):
    ax = fig.add_subplot(1, 2, i + 1, projection=smap)
    smap.plot(axes=ax, title=("measured" if i == 0 else "true") + " B_LOS")
    ax.coords[1].set_ticklabel_visible(i == 0)
plt.colorbar(ax.images[0], ax=fig.axes, shrink=0.8, label="G")

# %%
# Every map carries its provenance in the header: engine, duration, seed and
# the package version, so the run can be repeated bit for bit.
print(result.summary())
print({k: result.magnetogram.meta[k] for k in ("engine", "simdur", "seed", "gsvers", "dtype")})

plt.show()
