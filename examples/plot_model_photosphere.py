"""
===================================================
The built-in model photosphere and its Ni I spectra
===================================================

gongsynth ships a model of the paper's MURaM box: a 98 Mm × 98 Mm periodic
patch of the Sun at 96 km with a sunspot, plage, network, internetwork field
and granulation.  Milne–Eddington synthesis turns every column into Stokes
spectra of Ni I 676.78 nm, at disk centre or at any viewing angle.
"""
import astropy.units as u
import matplotlib.pyplot as plt
import numpy as np

from gongsynth.sun.photosphere import model_photosphere, synthesize

# %%
# Build the default photosphere (seeded: the same every time) and look at the
# vertical field and the continuum brightness.
photosphere = model_photosphere()
print(photosphere)

ny, nx = photosphere.shape
box = ny * photosphere.pixel_size.to_value(u.Mm)
extent = [0, box, 0, box]
bz = photosphere.bz.to_value(u.G)
continuum = photosphere.continuum.value

# Columns to look at: umbra, penumbra, the strongest plage element, a quiet granule.
centre = ny // 2
strength = photosphere.field_strength.to_value(u.G)
quiet_region = np.where(strength[800:1000, 800:1000] < 30, continuum[800:1000, 800:1000], 0)
iq = np.unravel_index(np.argmax(quiet_region), quiet_region.shape)      # brightest weak-field granule
plage_region = np.abs(bz[650:850, 100:300])
ip = np.unravel_index(np.argmax(plage_region), plage_region.shape)
picks = {
    "umbra": (centre, centre),
    "penumbra": (centre, centre + int(12000 / 96)),
    "plage": (650 + ip[0], 100 + ip[1]),
    "quiet granule": (800 + iq[0], 800 + iq[1]),
}
colours = dict(zip(picks, ["k", "tab:orange", "tab:blue", "tab:green"]))

fig, axes = plt.subplots(1, 2, figsize=(11, 5), sharex=True, sharey=True)
im = axes[0].imshow(bz, origin="lower", extent=extent, cmap="gray", vmin=-500, vmax=500)
fig.colorbar(im, ax=axes[0], label="$B_z$ [G]")
im = axes[1].imshow(continuum, origin="lower", extent=extent, cmap="afmhot", vmin=0.2, vmax=1.2)
fig.colorbar(im, ax=axes[1], label="continuum / quiet Sun")
for name, (iy, ix) in picks.items():
    for ax in axes:
        ax.plot((ix + 0.5) * box / nx, (iy + 0.5) * box / ny, "o", mfc="none", ms=9,
                mec=colours[name], mew=2)
axes[0].set_ylabel("y [Mm]")
for ax in axes:
    ax.set_xlabel("x [Mm]")
axes[0].set_title("vertical field")
axes[1].set_title("continuum")
fig.tight_layout()

# %%
# Stokes I and V of the four columns at disk centre (μ = 1) and seen at 60°
# (μ = 0.5, the region north of disk centre).  The umbra's 3 kG field splits the
# line into its σ components; at 60° the vertical umbral field projects to half
# its line-of-sight value, the limb darkens the continuum, and the line weakens.
fig, axes = plt.subplots(2, 2, figsize=(11, 7), sharex=True)
for row, mu in enumerate([1.0, 0.5]):
    for name, (iy, ix) in picks.items():
        cube = synthesize(photosphere[iy, ix], mu=mu)
        lam = (cube.wavelength - 676.78 * u.nm).to_value(u.pm)
        i = cube.I.value[0, 0] / 3.0e14
        v = cube.V.value[0, 0] / 3.0e14
        label = f"{name}: $B_{{LOS}}$ = {cube.blos.value[0, 0]:.0f} G"
        axes[row, 0].plot(lam, i, color=colours[name], label=label)
        axes[row, 1].plot(lam, v, color=colours[name])
    angle = np.degrees(np.arccos(mu))
    axes[row, 0].set_ylabel(f"I / $I_c$(disk centre), {angle:.0f}°")
    axes[row, 1].set_ylabel(f"V / $I_c$(disk centre), {angle:.0f}°")
    axes[row, 0].legend(fontsize=8, loc="lower left")
for ax in axes[1]:
    ax.set_xlabel("λ − 676.78 nm [pm]")
fig.tight_layout()

# %%
# The spot in Stokes V, 10 pm to the blue of the line centre, at disk centre and
# at 60° (north of disk centre, so the limb is up).  At 60° the outward-pointing
# penumbral field on the disk-centre side turns toward the observer and on the
# limb side away from it: the positive spot shows an apparent negative
# penumbra on its limb side, as real spots do near the limb.
cut = photosphere[centre - 256:centre + 256, centre - 256:centre + 256]
fig, axes = plt.subplots(1, 2, figsize=(11, 5))
for ax, mu in zip(axes, [1.0, 0.5]):
    cube = synthesize(cut, mu=mu, wavelength=np.linspace(676.76, 676.80, 5) * u.nm)
    v = cube.V.value[:, :, 1] / 3.0e14                  # 676.77 nm
    half = 256 * cut.pixel_size.to_value(u.Mm)
    im = ax.imshow(v, origin="lower", cmap="RdBu_r", vmin=-0.15, vmax=0.15,
                   extent=[-half, half, -half * mu, half * mu])   # foreshortened north-south
    ax.set_title(f"Stokes V at 676.77 nm, μ = {mu:g}")
    ax.set_xlabel("x [Mm]")
axes[0].set_ylabel("y (projected) [Mm]")
fig.colorbar(im, ax=axes, label="V / $I_c$")

plt.show()
