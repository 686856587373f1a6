"""
======================================================
LTE Stokes synthesis of a MURaM snapshot at 0° and 60°
======================================================

`gongsynth.rt.synthesize` solves the polarised transfer equation of Ni I
676.78 nm along straight rays through a 3-D MURaM box (the MURaM code's own
test snapshot, 6 Mm × 6 Mm at 96 km), here at disk centre and at 60°
(μ = 0.5), and stores the paper's truth (B·n at τ_c = 1 + 175 km ± 75 km
along the ray) as the cube's ``blos``.
"""
import os
from pathlib import Path

import astropy.units as u
import matplotlib.pyplot as plt
import numpy as np

import gongsynth

# %%
# The snapshot lives in the shared data folder (``GONGSYNTH_REAL_DATA`` points
# at ``../shared/data/real`` in the docs build; the MHD data sits beside it).
real = Path(os.environ.get("GONGSYNTH_REAL_DATA", "../shared/data/real"))
atmosphere = gongsynth.Atmosphere.from_muram(real.parent / "mhd" / "muram-test3d-it000000")
print(atmosphere)

# %%
# Synthesise at μ = 1 and μ = 0.5 (line of sight tilted toward −y).
cubes = {mu: gongsynth.rt.synthesize(atmosphere, mu=mu, azimuth=-90 * u.deg, progress=False)
         for mu in (1.0, 0.5)}

fig, axes = plt.subplots(2, 4, figsize=(12, 6), layout="constrained")
for row, (mu, cube) in zip(axes, cubes.items()):
    i = cube.I.value
    ic = i[:, :, 0]
    core = i.min(axis=2) / ic.mean()
    vmax = np.abs(cube.V.value).max(axis=2) / ic.mean()
    panels = [(ic / ic.mean(), "continuum / mean", "gray"), (core, "line core / mean Ic", "gray"),
              (vmax, "max |V| / mean Ic", "magma"), (cube.blos.value, "truth B_LOS (G)", "RdBu_r")]
    for ax, (img, title, cmap) in zip(row, panels):
        lim = {"RdBu_r": dict(vmin=-300, vmax=300)}.get(cmap, {})
        im = ax.imshow(img, origin="lower", cmap=cmap, **lim)
        ax.set_title(f"{title}, μ={mu:g}", fontsize=9)
        fig.colorbar(im, ax=ax, shrink=0.8)
    print(f"mu={mu}: continuum contrast {ic.std() / ic.mean():.3f}, mean |truth| "
          f"{np.abs(cube.blos.value).mean():.1f} G")
plt.show()

# %%
# The mean profile at both angles: the line weakens toward the limb.
fig, ax = plt.subplots()
for mu, cube in cubes.items():
    mean = cube.I.value.mean(axis=(0, 1))
    ax.plot(cube.wavelength.to_value(u.nm), mean / mean[0], label=f"μ = {mu:g}")
ax.set_xlabel("wavelength (nm)")
ax.set_ylabel("I / I_c (spatial mean)")
ax.legend()
plt.show()
