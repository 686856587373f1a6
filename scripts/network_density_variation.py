"""
How much the network's flux density varies from one ~60 Mm box to the next, on real maps and on runs.

The four-box power spectra of the Big Bear runs have 0.56-0.63 of the real
map's power at 27-66 Mm, with as many network clusters and as much cluster
flux as the real map near disk centre (noise guide).  One way a network can
hold its clusters' numbers and fluxes but lack power at those scales is a
flux density that is too uniform from cell group to cell group: the real
network is enhanced in some regions and sparse in others.  This script
measures that directly, at GONG's pixels (MDI and HMI degraded to GONG):
square boxes of ``--box`` Mm (in the plane of the sky) that lie wholly on
the disk within ``--radius`` solar radii (HMI's cut-out: within 0.27 R☉,
its extent), quiet ones only (mean |B − median| below the cluster
measure's 15 G, `gongsynth.analysis.network_clusters.QUIET_BELOW`), and in
each the network flux density: the mean over the box of |B − median| where
it exceeds 20 G (the clusters' threshold), zero elsewhere.  It reports the
boxes' mean, their coefficient of variation and 10th-90th percentiles, for
the real maps and the runs of ``scripts/network_clusters_vs_real.py``
(the same cache)::

    python scripts/network_density_variation.py --cache runs --table docs/guide/network_density_variation.ecsv

Seconds once the runs are cached.
"""
import sys
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from network_clusters_vs_real import real_and_simulated_maps, runs_parser  # noqa: E402  (the same runs)

#: The clusters' threshold (G) and the radius within which HMI's cut-out lies (solar radii).
THRESHOLD_G, HMI_RADIUS = 20.0, 0.27


def box_densities(smap, box_mm, radius):
    """Network flux density (G) of every quiet box of ``box_mm`` lying within ``radius`` of disk centre."""
    import astropy.units as u
    import numpy as np

    from gongsynth.analysis.disk import disk_coordinates
    from gongsynth.analysis.network_clusters import QUIET_BELOW

    field = smap.data.astype(float)
    field = field - np.nanmedian(field)
    rho = disk_coordinates(smap)[0]
    mm_per_pixel = (smap.scale.axis1 * u.pix).to_value(u.arcsec) * 6.957e2 / smap.rsun_obs.to_value(u.arcsec)
    side = int(round(box_mm / mm_per_pixel))
    densities = []
    for y0 in range(0, field.shape[0] - side + 1, side):
        for x0 in range(0, field.shape[1] - side + 1, side):
            box, where = field[y0:y0 + side, x0:x0 + side], rho[y0:y0 + side, x0:x0 + side]
            if not (np.isfinite(box).all() and np.all(where < radius)):
                continue
            if np.abs(box).mean() >= QUIET_BELOW.to_value(u.G):
                continue
            densities.append(np.where(np.abs(box) > THRESHOLD_G, np.abs(box), 0.0).mean())
    return np.array(densities)


def main(argv=None):
    """Measure every map, write the table and print it."""
    parser = runs_parser(__doc__, seeds=(1, 2, 3, 4))
    parser.add_argument("--box", type=float, default=60.0, help="box side (Mm, plane of the sky)")
    parser.add_argument("--radius", type=float, default=0.6, help="boxes within this radius (solar radii)")
    args = parser.parse_args(argv)

    import astropy.units as u
    import numpy as np
    from astropy.table import QTable

    import gongsynth
    from gongsynth.analysis.degrade import degrade_if_finer

    warnings.simplefilter("ignore", category=UserWarning)
    rows = []
    for instrument, date, kind, seed, smap in real_and_simulated_maps(args.seeds, args.cache):
        radius = min(args.radius, HMI_RADIUS) if instrument == "hmi" else args.radius
        values = box_densities(degrade_if_finer(smap)[0], args.box, radius)
        rows.append((instrument, date, kind, seed, values.size, values.mean(), values.std() / values.mean(),
                     np.percentile(values, 10), np.percentile(values, 90)))
    names = ["instrument", "date", "kind", "seed", "boxes", "mean", "cv", "p10", "p90"]
    table = QTable(rows=rows, names=names)
    for name in ("mean", "p10", "p90"):
        table[name].unit = u.G
        table[name].info.format = ".2f"
    table["cv"].info.format = ".2f"
    table.meta["description"] = (f"network flux density (|B - median| > {THRESHOLD_G:g} G, else 0) in "
                                 f"quiet {args.box:g} Mm boxes within {args.radius:g} Rsun (HMI "
                                 f"{HMI_RADIUS} Rsun), GONG's pixels; scripts/network_density_variation.py")
    table.meta["gongsynth_version"] = gongsynth.__version__
    args.table.parent.mkdir(parents=True, exist_ok=True)
    table.write(args.table, overwrite=True)
    table.pprint(max_lines=-1, max_width=-1)


if __name__ == "__main__":
    main()
