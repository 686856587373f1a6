"""
===========================================================
A simulated full disk beside real GONG and MDI magnetograms
===========================================================

The full-disk mode fills the Sun's large-scale field with small scales from
a library of built-in photosphere patches (quiet Sun, enhanced network,
plage, strong-field columns), each seen at its own viewing angle, and moves
every spectrum by the Sun's differential rotation, the observer's motion and
the convective blueshift before the filters (see the scene guide).  This
example puts two such runs beside real data:

1. a seeded quiet Sun dated like the real GONG magnetogram from Big Bear of
   2009-09-05 18:54 (solar minimum), with that file's date, site, plate
   scale and pointing (``like``), its large-scale field the synthetic Sun of
   the date carried by a magnetic network on supergranular cells;
2. a run whose large-scale field is the SOHO/MDI full-disk magnetogram of
   2010-10-15 (same Ni I line), beside that magnetogram degraded to GONG.

To build the docs in minutes the runs use 3 × 3 samples per pixel instead of
5 × 5.  The real files live in the project's ``shared/data/real`` folder,
outside the repository.
"""
# sphinx_gallery_thumbnail_number = 1
import os
from pathlib import Path

import astropy.units as u
import matplotlib.pyplot as plt
import numpy as np
import scipy.ndimage
import scipy.stats
import sunpy.map
from astropy.coordinates import SkyCoord
from matplotlib.colors import Normalize
from scipy.interpolate import RegularGridInterpolator

import gongsynth
from gongsynth.analysis.compare import compare
from gongsynth.analysis.degrade import degrade_to_gong
from gongsynth.analysis.disk import disk_coordinates, disk_values
from gongsynth.analysis.network_clusters import network_clusters
from gongsynth.config import Effects, SimulationConfig
from gongsynth.geometry import disk_geometry
from gongsynth.observing import as_observed, like_gong, site_location
from gongsynth.seeding import child_sequence
from gongsynth.stages.scene.surface import large_scale_grid
from gongsynth.sun.rotation import disk_velocity
from gongsynth.sun.surface_field import surface_field_from_map
from gongsynth.sun.surface_field.network import SupergranularNetwork

REAL = Path(os.environ.get("GONGSYNTH_REAL_DATA", "shared/data/real"))
BIG_BEAR = REAL / "gong" / "bbbqa090905t1854.fits.gz"
MDI = REAL / "mdi" / "mdi.fd_m_96m_lev182.20101015_000000_TAI.data.fits"

# %%
# A quiet Sun on 2009-09-05 at Big Bear
# -------------------------------------
#
# ``like_gong`` reads the date, the site (Big Bear: its rotation adds to the
# observer's velocity), the plate scale (2.56″ per pixel) and the pointing
# (the disk's centre sits 11.6 pixels east and 1.9 south of the image's, so
# the simulated disk lies on the real one's pixels) from the real file's
# header.  The real map is the average of nine one-minute magnetograms
# (``N_USED = 9``), so the run takes 9 minutes.  ``as_observed`` adds what
# ``gongsynth simulate --like`` does by default in full-disk mode: the file's
# count level (its DIODE sums, ``like_counts``), seeing that changes from
# frame to frame, GONG's minute-by-minute reduction and averaging, and the
# image rotation of that reduction (the noise guide measures each).  Both
# maps are solar north up: GONG's reduction takes out the P angle (the
# header's ``PA``).

real = gongsynth.load_observation(BIG_BEAR)
settings, instrument = like_gong(BIG_BEAR)
settings, effects = as_observed(settings, {}, mode="full-disk", instrument_name=instrument.name)
config = SimulationConfig(mode="full-disk", duration=9 * u.min, seed=1, surface_field="synthetic",
                          instrument=instrument.replace(supersampling=3), effects=Effects(**effects),
                          **settings)
quiet = gongsynth.simulate(config=config, progress=False)


def side_by_side(panels, limit):
    """Two magnetograms next to each other on one grey scale of ±``limit`` G."""
    fig = plt.figure(figsize=(11, 5), layout="constrained")
    for number, (smap, title) in enumerate(panels, 1):
        ax = fig.add_subplot(1, 2, number, projection=smap)
        image = smap.plot(axes=ax, norm=Normalize(-limit, limit), cmap="gray", title=title)
    fig.colorbar(image, ax=fig.axes, label="B_LOS (G)", shrink=0.8)


report = compare(quiet.magnetogram, real, labels=("gongsynth", "GONG Big Bear"), plot=False)
side_by_side(((quiet.magnetogram, "gongsynth, 2009-09-05 18:54, Big Bear"),
              (real, "real GONG, Big Bear 2009-09-05 18:54")), 40)

# %%
# The magnetic network: the simulated disk lays flux concentrations on the
# walls of ~30 Mm supergranular cells over the large-scale field
# (`~gongsynth.sun.surface_field.network.SupergranularNetwork`: a 5 G
# unsigned budget, Parnell et al. 2009's flux distribution, the imbalance of
# the large-scale field, whose quiet part has the ~80 Mm unipolar patches
# measured on ADAPT-GONG's quiet band, `gongsynth.sun.surface_field.quiet`).
# A 200″ quiet region south of disk centre in each map, on one grey scale:

box = {"bottom_left": (-100, -450) * u.arcsec, "top_right": (100, -250) * u.arcsec}
zooms = []
for smap in (quiet.magnetogram, real):
    corner = SkyCoord(*box["bottom_left"], frame=smap.coordinate_frame)
    zooms.append(smap.submap(corner, top_right=SkyCoord(*box["top_right"], frame=smap.coordinate_frame)))
side_by_side(((zooms[0], "gongsynth: 200″ quiet region"), (zooms[1], "real GONG: the same region")), 40)

# %%
# The network's outline: on the real map the network lies in chains along the
# cell walls.  `~gongsynth.analysis.network_clusters.network_clusters`
# measures each cluster's elongation (the axis ratio of its
# :math:`|B|`-weighted second moments): the median is 1.33-1.45 on real GONG,
# MDI and HMI maps.  Concentrations laid at single points of the 0.25° grid,
# seen through the PSF, are round spots (1.25); gongsynth lays each one along
# its cell wall, as a Gaussian of ``network_chain_length`` = 3 Mm (the
# default, measured on those three instruments: the decisions guide, "The
# disk network's chains").  The same run with the concentrations at points
# (``network_chain_length = 0``), the run above, and the real map:

points = gongsynth.simulate(config=config.replace(network_chain_length=0 * u.Mm), progress=False)
points_zoom = points.magnetogram.submap(
    SkyCoord(*box["bottom_left"], frame=points.magnetogram.coordinate_frame),
    top_right=SkyCoord(*box["top_right"], frame=points.magnetogram.coordinate_frame))
fig = plt.figure(figsize=(15, 5), layout="constrained")
for number, (smap, title) in enumerate(((points_zoom, "gongsynth: concentrations at points"),
                                        (zooms[0], "gongsynth: chains of 3 Mm (default)"),
                                        (zooms[1], "real GONG")), 1):
    ax = fig.add_subplot(1, 3, number, projection=smap)
    image = smap.plot(axes=ax, norm=Normalize(-40, 40), cmap="gray", title=title)
fig.colorbar(image, ax=fig.axes, label="B_LOS (G)", shrink=0.8)
for label, smap in (("points", points.magnetogram), ("chains of 3 Mm", quiet.magnetogram),
                    ("real GONG", real)):
    found = network_clusters(smap).summary()
    print(f"{label:>15}: median elongation {found['elongation']:.2f} over {found['shaped']} clusters, "
          f"{found['number_density'].to_value(u.Mm**-2) * 1e4:.1f} clusters per 1e4 Mm2")

# %%
# The numbers (`~gongsynth.analysis.map_statistics.compare_statistics`): the
# whole-disk histograms' KS distance (as they are, and with each map's
# median taken out: the real file is a site file, ``DTYPE = RW``, before
# GONG's zero-point correction, and its disk reads -2.4 G on average), the
# noise in the quietest 60″ box near disk centre and from pixel differences,
# the mean :math:`|B|`, the 99th and 99.9th percentiles of
# :math:`|B - \mathrm{median}|`, the mean :math:`|B|` from disk centre to the
# limb and the spatial power spectra of the central 640″ (and of the four 640″
# boxes that tile the central 1280″, dotted: one box's spectrum at network
# scales strays by a factor ~1.4 from one map of the same Sun to the next, see
# the noise guide), and in the rings' panel each map's fit of its weak
# field's power at 20-50 Mm over the disk, P ∝ μ^b exp[c (x² − y²)]
# (`~gongsynth.analysis.limb_power.limb_power_fit`: b how fast it falls toward
# the limb, c how much stronger it is east-west); each also with the
# two maps' noise matched (white noise added to the quieter one), since a KS
# distance alone mixes the Sun and the noise.

print(report.statistics.summary())
fig, axes = plt.subplots(1, 3, figsize=(14, 4), layout="constrained")
sim_values, real_values = report.sim.values, report.obs.values
bins = np.linspace(-60, 60, 121)
axes[0].hist(sim_values - np.median(sim_values), bins, histtype="step", density=True, label="gongsynth")
axes[0].hist(real_values - np.median(real_values), bins, histtype="step", density=True, label="real GONG",
             color="C3")
axes[0].set(yscale="log", xlabel="B_LOS − median (G)", ylabel="density", title="on-disk pixels")
axes[0].legend()
report.statistics.plot_spectra(axes[1], {"sim": "C0", "obs": "C3"})
report.statistics.plot_rings(axes[2], {"sim": "C0", "obs": "C3"})

# %%
# Where the real map's weak field exceeds the model's: clip both maps to
# ±15 G about their medians (the weak field, without the network's peaks),
# keep the scales of about 15-60 Mm (a difference of Gaussians of 1.5 and 6
# pixels), and look along the equator from the east limb to the west limb.
# The real map keeps its contrast out to both limbs, where its pattern is
# squeezed east-west as a pattern on the surface is.  The model's is weaker
# already at disk centre and fades toward the limbs, as a radial field's does.  The noise guide measures this
# over the whole disk (``scripts/limb_anisotropy.py``):
#
# - the real map's weak power at 20-50 Mm does not fall with μ, where the
#   model's falls as about μ^0.7-1.4 and MDI's real map's as μ^1.1;
# - it is stronger east-west than north-south at equal μ, which neither the
#   model nor MDI's real map shows.
#
# Its cause is open.  A fixed offset between the two polarisation states'
# images would leave part of that east-west fingerprint;
# `~gongsynth.analysis.state_offset.state_offset` measures such an offset
# from a magnetogram and the same observation's Dopplergram.

fig = plt.figure(figsize=(12, 5.5), layout="constrained")
for number, (smap, title) in enumerate(((quiet.magnetogram, "gongsynth: weak field, 15-60 Mm"),
                                        (real, "real GONG: weak field, 15-60 Mm")), 1):
    weak = np.clip(np.nan_to_num(smap.data - np.nanmedian(smap.data)), -15, 15)
    band = scipy.ndimage.gaussian_filter(weak, 1.5) - scipy.ndimage.gaussian_filter(weak, 6)
    band_map = sunpy.map.Map(np.where(disk_coordinates(smap)[0] < 0.97, band, np.nan), smap.meta)
    strip = band_map.submap(SkyCoord(-960 * u.arcsec, -200 * u.arcsec, frame=band_map.coordinate_frame),
                            top_right=SkyCoord(960 * u.arcsec, 200 * u.arcsec,
                                               frame=band_map.coordinate_frame))
    ax = fig.add_subplot(2, 1, number, projection=strip)
    image = strip.plot(axes=ax, norm=Normalize(-5, 5), cmap="RdBu_r", title=title)
fig.colorbar(image, ax=fig.axes, label="band-passed B_LOS (G)", shrink=0.8)

# %%
# The network's clusters
# ----------------------
#
# `~gongsynth.analysis.network_clusters.network_clusters` finds the network
# the way the eye does: connected pixels of one sign beyond 20 G (four to five
# times the noise), quiet pixels within 0.35 R☉ of disk centre, each cluster's
# flux on the sphere.  Their number and flux per area, and the distribution of
# their fluxes, compare the two Suns almost independently of the noise (the
# noise guide does the same for MDI and HMI maps).

fig, ax = plt.subplots(figsize=(6, 4.2), layout="constrained")
edges = np.logspace(18, 20.5, 16)
for smap, label, colour in ((quiet.magnetogram, "gongsynth", "C0"), (real, "real GONG", "C3")):
    found = network_clusters(smap)
    summary = found.summary()
    print(f"{label}: {summary['number']} clusters, "
          f"{summary['number_density'].to_value(u.Mm**-2) * 1e4:.1f} per 10^4 Mm2, "
          f"{summary['flux_density']:.2f} of flux per area, 99 % below {summary['p99']:.2e}, "
          f"index {summary['index']:.2f} ± {summary['index_error']:.2f} above 3e19 Mx")
    counts, _ = np.histogram(found.table["flux"].to_value(u.Mx), edges)
    density = counts / np.diff(edges) / found.region_area.to_value(u.Mm**2)
    ax.step(edges[:-1], np.where(counts > 0, density, np.nan), where="post", color=colour, label=label)
ax.set(xscale="log", yscale="log", xlabel="cluster flux (Mx)", ylabel="clusters per Mx per Mm²",
       title="network clusters within 0.35 R☉")
ax.legend()

# %%
# The Dopplergram of the same run: the rotation's east-west signal, the
# observer's motion (the Earth approaching the Sun in September, Big Bear's
# daily rotation) and the convective blueshift.  Along the equator it follows
# the rotation model of `gongsynth.sun.rotation` (Snodgrass & Ulrich 1990)
# about 1 % low: GONG's phase moves a little more slowly with a line's shift
# than 1/v0 assumes.

doppler = quiet.doppler
g = disk_geometry(doppler.data.shape, instrument.plate_scale, obstime=config.obstime,
                  pointing=config.pointing)
row = doppler.data.shape[0] // 2
model = disk_velocity(g.longitude[row] * u.deg, g.latitude[row] * u.deg, g.mu[row], config.obstime,
                      site=site_location("BB"))
fig = plt.figure(figsize=(11, 4.5), layout="constrained")
ax = fig.add_subplot(1, 2, 1, projection=doppler)
doppler.plot(axes=ax, norm=Normalize(-2500, 2500), cmap="RdBu_r", title="gongsynth Dopplergram")
ax = fig.add_subplot(1, 2, 2)
ax.plot(doppler.data[row], ",", label="measured")
ax.plot(model.to_value(u.m / u.s), label="rotation + observer + blueshift")
ax.set(xlabel="pixel (the detector's central row)", ylabel="v (m/s)")
ax.legend()

# %%
# The supergranules flow too: the run's network cells
# (`~gongsynth.sun.surface_field.supergranulation`) flow out from their
# centres to their walls at 350 m/s rms, rising by 25 m/s in their middles and
# sinking at their walls (Rincon & Rieutord 2018).  Take the large-scale model
# out of the Dopplergram (and each ring's median in μ: the 3-D Sun's spectra
# carry their own convective blueshift, not the tabulated one) and smooth
# over 10″: what is left is the supergranulation, which grows away from disk
# centre as its horizontal outflows turn into the line of sight, beside what
# granules and noise leave in GONG's pixels.  The zooms, 300″ west of disk
# centre, show the flow the scene was given (the network's cells, stream
# ``"network"`` of the run's seed, along each line of sight) and what GONG
# measured: each cell's half toward the limb flows away from us (red), its half
# toward disk centre toward us (blue), so that, going west, blue turns red at a
# cell's centre and red turns blue on its wall, where the outflows of
# neighbouring cells meet and the magnetogram's network lies (contours of the
# smoothed :math:`|B|` at 20 G).

with np.errstate(invalid="ignore"):
    large_scale = disk_velocity(g.longitude * u.deg, g.latitude * u.deg, g.mu, config.obstime,
                                site=site_location("BB")).to_value(u.m / u.s)
    on = g.on_disk & (g.mu > 0.1)
    residual = np.where(on, doppler.data - large_scale, np.nan)
rings = np.digitize(g.mu, np.linspace(0.1, 1, 10))
for ring in np.unique(rings[on]):
    here = (rings == ring) & np.isfinite(residual)
    residual[here] -= np.median(residual[here])
run_network = SupergranularNetwork(seed=child_sequence(config.seed, "network"))
cells = large_scale_grid(config.obstime, network=run_network, rotation=False, observer=False, blueshift=None)
given = np.full(residual.shape, np.nan)
given[on] = RegularGridInterpolator((cells.latitude, cells.longitude), cells.velocity)(
    np.column_stack([g.latitude[on], g.longitude[on]]))


def smoothed(image, fwhm):
    """Gaussian smoothing (FWHM in arcsec) of an image with NaNs, normalised by the smoothed mask."""
    sigma = fwhm / 2.355 / instrument.plate_scale.to_value(u.arcsec)
    known = np.isfinite(image)
    total = scipy.ndimage.gaussian_filter(np.where(known, image, 0.0), sigma)
    weight = scipy.ndimage.gaussian_filter(known.astype(float), sigma)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(known, total / weight, np.nan)


measured, truth_flow = (sunpy.map.Map(smoothed(image, 10), doppler.meta) for image in (residual, given))
network = sunpy.map.Map(smoothed(np.abs(quiet.magnetogram.data), 2), quiet.magnetogram.meta)
corner = SkyCoord(300 * u.arcsec, -150 * u.arcsec, frame=measured.coordinate_frame)
top = SkyCoord(600 * u.arcsec, 150 * u.arcsec, frame=measured.coordinate_frame)
fig = plt.figure(figsize=(14, 4.8), layout="constrained")
for number, (smap, title) in enumerate(((measured, "GONG Dopplergram − large-scale model, 10″"),
                                        (truth_flow, "300″ zoom: the flow given, 10″"),
                                        (measured, "300″ zoom: GONG measured, 10″")), 1):
    view = smap if number == 1 else smap.submap(corner, top_right=top)
    ax = fig.add_subplot(1, 3, number, projection=view)
    image = view.plot(axes=ax, norm=Normalize(-300, 300), cmap="RdBu_r", title=title)
    if number == 1:
        view.draw_quadrangle(corner, top_right=top, axes=ax, edgecolor="k")
    else:
        network.submap(corner, top_right=top).draw_contours([20] * u.G, axes=ax, colors="k", linewidths=0.6)
fig.colorbar(image, ax=fig.axes, label="v (m/s)", shrink=0.8)
for lo, hi in ((0.9, 1.0), (0.7, 0.8), (0.5, 0.6), (0.3, 0.4)):
    ring = np.isfinite(measured.data) & (g.mu > lo) & (g.mu <= hi)
    r = np.corrcoef(measured.data[ring], truth_flow.data[ring])[0, 1]
    print(f"μ {lo}-{hi}: rms {np.std(residual[ring]):.0f} m/s measured, {np.std(given[ring]):.0f} m/s "
          f"of it the supergranular flow; measured and given flow correlate at {r:.2f} (10″)")

# %%
# A run driven by the MDI magnetogram
# -----------------------------------
#
# `~gongsynth.sun.surface_field.surface_field_from_map` turns the MDI
# line-of-sight field into the radial field on a heliographic grid; the run
# fills it with small scales at MDI's date (without the synthetic network:
# the observed map holds the Sun's own).  Beside it, the MDI map degraded to
# GONG (PSF and 2.5″ pixels, `~gongsynth.analysis.degrade.degrade_to_gong`).

mdi = gongsynth.load_observation(MDI)
field = surface_field_from_map(mdi, mdi.date)
# Two minutes: the large scales are the point here, and the run's cost grows with its length.
config = SimulationConfig(mode="full-disk", duration=2 * u.min, seed=2, obstime=mdi.date.isot,
                          instrument=gongsynth.GONGInstrument(supersampling=3), network=False)
driven = gongsynth.simulate(config=config, surface_field=field, progress=False)
degraded = degrade_to_gong(mdi)

side_by_side(((driven.magnetogram, "gongsynth driven by MDI 2010-10-15"),
              (degraded, "MDI 2010-10-15 degraded to GONG")), 100)

# %%
# The large-scale pixel correlation: the degraded MDI map is read at the
# simulated pixels' sky positions, both are smoothed by Gaussians of 0, 10 and
# 20″ FWHM within 0.95 R☉; then the disk mean, the mean |B| (unsigned flux
# density) and the histograms' KS distance.

sim = driven.magnetogram
yy, xx = np.mgrid[:sim.data.shape[0], :sim.data.shape[1]]
where = degraded.world_to_pixel(sim.pixel_to_world(xx * u.pix, yy * u.pix))
coords = [where.y.value, where.x.value]
observed = scipy.ndimage.map_coordinates(np.nan_to_num(degraded.data), coords, order=1, cval=np.nan)
covered = scipy.ndimage.map_coordinates(np.isfinite(degraded.data).astype(float), coords, order=1, cval=0)
use = np.isfinite(sim.data) & (covered > 0.99) & (disk_coordinates(sim)[0] < 0.95)


def smoothed(image, fwhm_pixels):
    if fwhm_pixels == 0:
        return image
    sigma = fwhm_pixels / 2.355
    weight = scipy.ndimage.gaussian_filter(use.astype(float), sigma)
    return scipy.ndimage.gaussian_filter(np.where(use, image, 0.0), sigma) / np.where(weight > 0, weight, 1)


for fwhm in (0, 4, 8):
    r = np.corrcoef(smoothed(np.nan_to_num(sim.data), fwhm)[use], smoothed(observed, fwhm)[use])[0, 1]
    print(f"pixel correlation, {2.5 * fwhm:4.0f}″ smoothing: {r:.3f}")
print(f"disk mean  gongsynth {sim.data[use].mean():+.2f} G   MDI→GONG {observed[use].mean():+.2f} G")
print(f"mean |B|   gongsynth {np.abs(sim.data[use]).mean():.2f} G   "
      f"MDI→GONG {np.abs(observed[use]).mean():.2f} G")
# The same KS distance as `~gongsynth.analysis.compare.compare` (on-disk pixels within 0.98 R☉).
ks = scipy.stats.ks_2samp(disk_values(sim, 0.98), disk_values(degraded, 0.98))
print(f"KS distance {ks.statistic:.3f}")
plt.show()
