"""
===============================
The GONG camera, frame by frame
===============================

GONG's camera takes 60 frames a second while a half-wave plate turns 30° per
frame and a liquid-crystal retarder (LCVR) flips between I+V and I−V every
second.  Each frame is added to one of six accumulation planes, after Poisson
photon and dark noise, 4.8 adu read noise, conversion to adu at 33 e⁻/adu and a
dither offset; at the end the three lowest bits are dropped.  This example
shows the frame schedule of `gongsynth.stages.camera.schedule`, the six raw planes that
`gongsynth.stages.camera.integrate.integrate` makes of a small quiet-Sun scene with a bipolar
magnetic region, and how the magnetogram and Doppler noise fall with the
observing time.
"""
# sphinx_gallery_thumbnail_number = 3
import astropy.units as u
import matplotlib.pyplot as plt
import numpy as np

from gongsynth import GONGInstrument
from gongsynth.planes import PLANE_NAMES
from gongsynth.stages.camera.integrate import integrate
from gongsynth.stages.camera.schedule import frame_schedule
from gongsynth.stages.filters import channel_weights
from gongsynth.stages.reduction import reduce

gong = GONGInstrument()

# %%
# The frame schedule
# ------------------
#
# `~gongsynth.stages.camera.schedule.frame_schedule` returns, for every frame, its time,
# wave-plate angle, channel (sector mod 3), polarisation and plane, and the
# dither it carries.  The dither is a triangle wave: +2 adu every 12th frame in
# the first half of each minute, −2 in the second half, starting from 32; its
# mean over a minute is exactly 182 adu per frame.

schedule = frame_schedule(1 * u.min, gong)
t = schedule.time.to_value(u.s)
first = t < 2.5

fig, axes = plt.subplots(4, 1, figsize=(8, 7), sharex=False, layout="constrained")
axes[0].step(t[first], schedule.waveplate_angle[first], where="post", color="k", lw=0.8)
axes[0].set_ylabel("wave plate [deg]")
axes[1].step(t[first], schedule.channel[first], where="post", color="C0", lw=0.8)
axes[1].set_ylabel("channel")
axes[1].set_yticks([0, 1, 2])
axes[2].step(t[first], schedule.plane[first], where="post", color="C1", lw=0.8)
axes[2].set_yticks(range(6), PLANE_NAMES, fontsize="small")
axes[2].set_ylabel("plane")
axes[2].set_xlabel("time [s]")
for ax in axes[:3]:
    ax.set_xlim(0, 2.5)
axes[3].plot(t, schedule.dither, color="C3")
axes[3].axhline(schedule.dither.mean().value, color="0.5", ls="--",
                label=f"mean {schedule.dither.mean():.0f}")
axes[3].set_ylabel("dither [adu]")
axes[3].set_xlabel("time [s]")
axes[3].legend(loc="upper right", fontsize="small")
fig.suptitle("GONG magnetogram-mode frame schedule (first 2.5 s; dither over one minute)")

# %%
# A scene: expected electrons per frame
# -------------------------------------
#
# The camera starts from the expected number of photo-electrons per frame in
# each plane (normally made by `gongsynth.stages.optics`).  Here we make one by hand:
# a Gaussian Ni line (depth 0.6, FWHM 10 pm) seen through the three channels,
# with a continuum of 1.2e5 electrons per frame per pixel at disk centre, and a
# bipolar region of ±300 G that Zeeman-shifts the line in I+V and I−V.

lam = np.linspace(676.6, 676.96, 721) * u.nm
weights = channel_weights(lam, gong).value
sigma = (10 * u.pm / 2.3548).to_value(u.nm)
k_zeeman = 4.6686e-13 * gong.lande_g.value * gong.line_wavelength.to_value(u.AA) ** 2 / 10  # nm / G


def channels(shift_nm):
    """Channel integrals (3, n) of a continuum-normalised line shifted by shift_nm (n,)."""
    line = 1 - 0.6 * np.exp(-0.5 * ((lam.to_value(u.nm) - 676.78 - shift_nm[:, None]) / sigma) ** 2)
    return weights @ line.T


ny = nx = 96
y, x = np.mgrid[:ny, :nx]
field = 300 * (np.exp(-((x - 36) ** 2 + (y - 48) ** 2) / 80) - np.exp(-((x - 60) ** 2 + (y - 48) ** 2) / 80))
shift = k_zeeman * field.ravel()
continuum = weights.sum(axis=1).mean()
expected = 1.2e5 / continuum * np.concatenate([channels(shift), channels(-shift)]).reshape(6, ny, nx)
expected = expected * u.electron

# %%
# The six raw planes
# ------------------
#
# One minute with the fast ``"blocks"`` engine (the ``"frames"`` engine gives
# statistically identical planes, frame by frame).  The planes carry the
# default synthetic flat field (a gradient, dust shadows and 1 % pixel
# response non-uniformity) and dark current; the field is barely visible in
# the raw planes: it is a shift of a few tenths of a picometre.

raw = integrate(expected, duration=1 * u.min, engine="blocks", seed=1, progress=False)
fig, axes = plt.subplots(2, 3, figsize=(9, 6), layout="constrained")
for p, ax in enumerate(axes.flat):
    im = ax.imshow(raw.data[p], origin="lower", cmap="gray")
    ax.set_title(PLANE_NAMES[p], fontsize="small")
    ax.set_axis_off()
    fig.colorbar(im, ax=ax, shrink=0.7, label="DN")
fig.suptitle(f"raw planes, 1 min ({raw.frames_per_plane[0]} frames each, ACCUM = {raw.header['ACCUM']})")

obs = reduce(raw)
fig, axes = plt.subplots(1, 2, figsize=(8, 3.6), layout="constrained")
im = axes[0].imshow(field, origin="lower", cmap="RdBu_r", vmin=-300, vmax=300)
axes[0].set_title("input B_LOS [G]")
fig.colorbar(im, ax=axes[0], shrink=0.8)
im = axes[1].imshow(obs.magnetogram.value, origin="lower", cmap="RdBu_r", vmin=-300, vmax=300)
axes[1].set_title("reduced magnetogram, 1 min [G]")
fig.colorbar(im, ax=axes[1], shrink=0.8)
for ax in axes:
    ax.set_axis_off()

# %%
# Noise against observing time
# ----------------------------
#
# A uniform quiet-Sun scene (no field) integrated for 0.5 to 10 minutes: the
# per-pixel noise of B_LOS and of the Doppler velocity falls as
# 1/√duration, photon noise dominating read noise by far.  One minute gives
# about 3 G per pixel, the level of real GONG+ one-minute magnetograms.

rest = np.concatenate([channels(np.zeros(1))] * 2).reshape(6, 1, 1)
quiet = 1.2e5 / continuum * rest * np.ones((6, 80, 80)) * u.electron
minutes = np.array([0.5, 1, 2, 5, 10])
noise_b, noise_v = [], []
for i, m in enumerate(minutes):
    o = reduce(integrate(quiet, duration=m * u.min, seed=10 + i, progress=False))
    noise_b.append(o.magnetogram.std().to_value(u.G))
    noise_v.append(o.doppler.std().to_value(u.m / u.s))

fig, ax = plt.subplots(figsize=(6, 4), layout="constrained")
ax.loglog(minutes, noise_b, "o", color="C0", label="B_LOS [G]")
ax.loglog(minutes, noise_v, "s", color="C1", label="Doppler [m/s]")
for values, color in ((noise_b, "C0"), (noise_v, "C1")):
    ax.loglog(minutes, values[1] / np.sqrt(minutes), color=color, lw=0.8, ls="--")
ax.set_xlabel("observing time [min]")
ax.set_ylabel("noise per pixel")
ax.set_title("quiet Sun at disk centre: noise ∝ 1/√t (dashed)")
ax.legend()
print(f"B_LOS noise: 1 min {noise_b[1]:.2f} G, 10 min {noise_b[-1]:.2f} G; "
      f"Doppler: 1 min {noise_v[1]:.2f} m/s, 10 min {noise_v[-1]:.2f} m/s")

plt.show()
