"""
================================
The three GONG channel responses
================================

GONG does not take spectra: it measures the Ni I 676.8 nm line through a tunable
filter whose transmission is modulated by a rotating half-wave plate.  This
example draws the filter chain of `gongsynth.filters` with the instrument's
default parameters, from the broad passband of the prefilter and Lyot filter
down to the three 30° wave-plate sectors that GONG records, and lays the Ni
line on top of them (the paper's Fig. 5, right).
"""
# sphinx_gallery_thumbnail_number = 2
import astropy.constants as const
import astropy.units as u
import matplotlib.pyplot as plt
import numpy as np

from gongsynth import GONGInstrument
from gongsynth.instruments.gong.reduction import measured_phase
from gongsynth.stages.filters import (
    channel_responses,
    channel_weights,
    lyot_transmission,
    modulation_amplitude,
    prefilter_transmission,
)

gong = GONGInstrument()
lam0 = gong.line_wavelength

# %%
# The passband: prefilter and Lyot filter
# ---------------------------------------
#
# The interference prefilter (FWHM 0.5 nm) and the three-element Lyot filter
# (central peak 0.08 nm wide) select a narrow band around the line.  The Lyot
# filter also transmits side orders 0.75 nm and 1.5 nm from the line, inside
# the prefilter's wings: this is why gongsynth integrates the chain over
# :math:`\lambda_0 \pm 3` nm and pads input spectra with their continuum.

wide = lam0 + np.linspace(-2, 2, 8001) * u.nm
prefilter = prefilter_transmission(wide, gong)
lyot = lyot_transmission(wide, gong)

fig, ax = plt.subplots(figsize=(8, 3.5), layout="constrained")
ax.plot((wide - lam0).to_value(u.nm), prefilter, color="0.5", label="prefilter $R_p$")
ax.plot((wide - lam0).to_value(u.nm), lyot, color="C0", lw=0.8, label="Lyot $R_L$")
ax.plot((wide - lam0).to_value(u.nm), prefilter * lyot, color="k", label="$R_p R_L$")
ax.set_xlabel(r"$\lambda - \lambda_0$ [nm]")
ax.set_ylabel("transmission")
ax.set_title(f"GONG passband around Ni I {lam0.to_value(u.nm):.2f} nm")
ax.legend(loc="upper right", fontsize="small")

# %%
# The three channels
# ------------------
#
# The Michelson interferometer adds a :math:`\cos^2` fringe with a period of
# :math:`\Delta\lambda_m` = 0.305 Å; the half-wave plate, turning 30° per frame,
# slides the fringe across the line.  Each frame averages one 30° sector, so the
# three distinct channel responses :math:`\bar R_0, \bar R_1, \bar R_2` are the
# fringe pattern shifted by a third of a period, with its contrast reduced from
# 1 to :math:`\mathrm{sinc}(\pi/3) = 0.827` by the averaging.
# The Ni line is drawn with the rest-line profile that the instrument uses as
# its velocity zero point (FWHM ``reference_line_fwhm``, depth
# ``reference_line_depth``).

near = lam0 + np.linspace(-0.1, 0.1, 2001) * u.nm
responses = channel_responses(near, gong)
sigma = gong.reference_line_fwhm / (2 * np.sqrt(2 * np.log(2)))
line = 1 - gong.reference_line_depth * np.exp(-0.5 * ((near - lam0) / sigma) ** 2)

dpm = (near - lam0).to_value(u.pm)
fig, ax = plt.subplots(figsize=(8, 4), layout="constrained")
for i, r in enumerate(responses):
    ax.plot(dpm, r, color=f"C{i}", label=rf"$\bar R_{i}$ (sector {'I' * (i + 1)})")
ax.set_xlabel(r"$\lambda - \lambda_0$ [pm]")
ax.set_ylabel("time-averaged transmission")
ax.set_ylim(0, 1)
ax_line = ax.twinx()
ax_line.plot(dpm, line, color="k", lw=2, alpha=0.6, label="Ni I line (rest)")
ax_line.set_ylabel("line intensity / continuum")
ax_line.set_ylim(0, 1.05)
handles = ax.get_legend_handles_labels()[0] + ax_line.get_legend_handles_labels()[0]
ax.legend(handles=handles, loc="lower left", fontsize="small")
ax.set_title("GONG channel responses and the Ni I 676.8 nm line")

print(f"modulation contrast after averaging a 30° sector: {modulation_amplitude(gong):.4f}")

# %%
# What the channels measure
# -------------------------
#
# Integrating a spectrum against the three responses gives three intensities;
# their phase, :math:`\phi = \operatorname{atan2}(\sqrt3 (I_1 - I_2),\ 2I_0 - I_1 - I_2)`,
# moves with the line.
# `~gongsynth.filters.channel_weights` turns a spectrum sampled on any grid
# (here the paper's 51 points over 676.73–676.83 nm) into the three integrals
# with one matrix product.  Shifting the line by ±200 m/s moves the phase by
# about ∓0.09 rad: GONG's velocity scale :math:`v_0` is about 2150 m/s per
# radian.  The slope this line actually has differs from :math:`v_0` by about
# 1 %, because the
# line is not infinitely narrow; this is the origin of the measured/true
# ratio of about 0.99 discussed in :ref:`decision-v0`.

grid = np.linspace(676.73, 676.83, 51) * u.nm
weights = channel_weights(grid, gong)
velocities = [-200, 0, 200] * u.m / u.s
phases = []
for v in velocities:
    centre = lam0 * (1 + (v / const.c).decompose())  # redshift for v > 0
    spectrum = 1 - gong.reference_line_depth * np.exp(-0.5 * ((grid - centre) / sigma) ** 2)
    channels = weights @ spectrum
    phases.append(measured_phase(channels))
    print(f"v = {v:+5.0f}: channels = {np.round(channels.to_value(u.pm), 3)} pm, "
          f"phase = {phases[-1]:+.4f} rad")
slope = -(velocities[-1] - velocities[0]) / ((phases[-1] - phases[0]) * u.rad)
print(f"velocity per radian of phase for this line: {slope:.1f}; v0 = {gong.v0}")

plt.show()
