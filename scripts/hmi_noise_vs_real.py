"""
A simulated HMI full disk beside the real HMI 45-s magnetogram: the statistics of `gongsynth.compare`.

The real map is the 1024² JSOC ``im_patch`` cut-out of 2010-10-20 00:00 in
``../shared/data/real/hmi`` (Postel projection about the disk centre,
0.0301 heliographic degrees ≈ 365 km per pixel; its WCS keywords are wrong,
see PROVENANCE.md).  The simulated map is gongsynth's full-disk HMI run of
that date (4096², 45 s, seed 1, the defaults), run once and cached in
``--cache`` (about 4 minutes of CPU unloaded; ``--simulated`` takes a saved
run's folder).  Its central 1024² pixels of 0.504″ (364 km at disk centre
that day) cover the cut-out's area to 0.3 % (tangent and Postel projections
differ by < 1 % within 260″ of the centre), so the real values are put on
the simulated crop's helioprojective grid, and both are measured by
`gongsynth.analysis.map_statistics.compare_statistics` at HMI's own
resolution (nothing is degraded): KS distances, quiet-box and
pixel-difference noise, mean |B|, percentiles of |B − median|, the mean |B|
in rings out to 0.4 R☉ (the crop's corners reach 0.38 R☉) and the power
spectrum of the central 500″, each also with the noise matched.  Writes
``--table`` (an ECSV of the statistics table with the rings and spectrum
ratios in its meta) and prints the summary::

    python scripts/hmi_noise_vs_real.py --cache /tmp/hmi_run --table docs/guide/hmi_noise_vs_real.ecsv
"""
import argparse
import os
from pathlib import Path

import numpy as np

REAL = (Path(os.environ.get("GONGSYNTH_REAL_DATA", Path(__file__).resolve().parents[2] / "shared" / "data"
                            / "real")) / "hmi" / "JSOC_hmi.m_45s.20101020_000000_TAI.2.magnetogram.fits")
DATE = "2010-10-20T00:00"
SIDE = 1024
RINGS = (0.0, 0.1, 0.2, 0.3, 0.4)


def simulated_run(cache, seed):
    """The saved full-disk HMI run's magnetogram (running and saving it first if ``cache`` has none)."""
    import astropy.units as u
    import sunpy.map

    cache = Path(cache)
    path = cache / "magnetogram.fits"
    if not path.exists():
        import gongsynth

        gongsynth.simulate(instrument="hmi", mode="full-disk", duration=0.75 * u.min, seed=seed,
                           obstime=DATE, progress=False).save(cache, overwrite=True)
    return sunpy.map.Map(path)


def central(smap, side=SIDE):
    """The central ``side``² pixels about the disk centre of a full-disk map."""
    import astropy.units as u
    from astropy.coordinates import SkyCoord

    centre = smap.wcs.world_to_pixel(SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=smap.coordinate_frame))
    x0, y0 = (int(round(float(c))) - side // 2 for c in centre)
    return smap.submap([x0, y0] * u.pix, top_right=[x0 + side - 1, y0 + side - 1] * u.pix)


def real_on(grid):
    """The real cut-out (G) on the helioprojective grid of ``grid`` (same shape)."""
    from astropy.io import fits

    with fits.open(REAL) as hdul:
        data = np.array(hdul[1].data, dtype=float)
    if data.shape != grid.data.shape:
        raise ValueError(f"the real cut-out is {data.shape}, the simulated crop {grid.data.shape}")
    meta = dict(grid.meta)
    meta.update({"bunit": "G", "history": "real hmi.M_45s 2010-10-20 Postel cut-out on this grid"})
    return type(grid)(data, meta)


def main(argv=None):
    """Run (or load) the simulation, compare it with the real cut-out, write the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--cache", type=Path, default=Path("hmi_noise_run"),
                        help="folder of the saved full-disk HMI run (made if missing)")
    parser.add_argument("--table", type=Path, required=True, help="ECSV file to write")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args(argv)

    import astropy.units as u

    from gongsynth.analysis.map_statistics import compare_statistics

    sim = central(simulated_run(args.cache, args.seed))
    sim = sim if sim.unit == u.G else type(sim)(sim.quantity.to_value(u.G), {**sim.meta, "bunit": "G"})
    real = real_on(sim)
    stats = compare_statistics(sim, real, box=500 * u.arcsec, ring_edges=RINGS)
    print(stats.summary())
    table = stats.table.copy()
    table.meta.update({
        "description": "simulated HMI full disk (central 1024², 2010-10-20, seed "
                       f"{args.seed}) vs real hmi.M_45s cut-out; scripts/hmi_noise_vs_real.py",
        "ring_r_inner": [float(r) for r in stats.rings["r_inner"]],
        "ring_mean_abs_sim_G": [float(v) for v in stats.rings["sim"].to_value(u.G)],
        "ring_mean_abs_obs_G": [float(v) for v in stats.rings["obs"].to_value(u.G)],
        "spectrum_wavelength_Mm": [float(v) for v in stats.spectra["wavelength"].to_value(u.Mm)],
        "spectrum_ratio": [float(v) for v in stats.spectra["ratio"]],
        "spectrum_ratio_matched": [float(v) for v in stats.spectra["ratio_matched"]],
        "power_ratio_5_100_Mm": list(stats.spectrum_ratio_range()),
        "power_ratio_5_100_Mm_matched": list(stats.spectrum_ratio_range(matched=True)),
    })
    args.table.parent.mkdir(parents=True, exist_ok=True)
    table.write(args.table, format="ascii.ecsv", overwrite=True)
    return stats


if __name__ == "__main__":
    main()
