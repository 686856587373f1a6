"""
How long the network's chains are: the clusters' elongation on three instruments against the chain length.

The real network's clusters at GONG's resolution are elongated (median axis
ratio 1.33-1.45 on the real GONG, MDI and HMI maps of
``scripts/network_clusters_vs_real.py``), the model's with concentrations at
points 1.25-1.27.  `~gongsynth.sun.surface_field.network.SupergranularNetwork`
can lay each concentration along its cell wall (``chain_length``, the
Gaussian sigma along the wall; a run's ``network_chain_length``, 0 by
default).  This script runs the three
instruments' full disks of their real maps' dates (the runs of
``network_clusters_vs_real.py``; the shipped table: seeds 1-4) for each chain length, measures the
clusters at GONG's resolution (`gongsynth.analysis.network_clusters`) and
writes, per instrument and length, the median elongation beside the real
map's, and the clusters' number, flux per area and 99th percentile over the
real map's::

    python scripts/network_chain_length.py --cache runs --lengths 0 2 3 4 5 --seeds 1 2 3 4 \
        --table docs/guide/network_chain_length.ecsv

About 1-2 minutes per length and seed on two cores once the 3-D library is cached.
"""
import argparse
import itertools
import sys
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from network_clusters_vs_real import REAL_MAPS, simulated  # noqa: E402  (the same runs)


def main(argv=None):
    """Run each chain length on the three instruments, measure, write the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--cache", type=Path, required=True, help="folder for the runs (one per length)")
    parser.add_argument("--lengths", type=float, nargs="+", default=[0, 2, 3, 4, 5], help="Mm")
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--table", type=Path, required=True, help="ECSV file to write")
    args = parser.parse_args(argv)

    import astropy.units as u
    from astropy.table import QTable

    import gongsynth
    from gongsynth.analysis.degrade import degrade_if_finer
    from gongsynth.analysis.network_clusters import network_clusters

    warnings.simplefilter("ignore", category=UserWarning)
    real = {name: network_clusters(degrade_if_finer(gongsynth.load_observation(path))[0]).summary()
            for name, (_, path) in REAL_MAPS.items()}
    rows = []
    for length, seed, name in itertools.product(args.lengths, args.seeds, REAL_MAPS):
        smap = simulated(name, seed, args.cache / f"chain{length:g}",
                         chain_length=length * u.Mm)["magnetogram"]
        s, r = network_clusters(degrade_if_finer(smap)[0]).summary(), real[name]
        rows.append({"instrument": name, "chain_length": length * u.Mm, "seed": seed,
                     "elongation": s["elongation"], "real_elongation": r["elongation"],
                     "shaped": s["shaped"], "real_shaped": r["shaped"],
                     "number_ratio": float(s["number_density"] / r["number_density"]),
                     "flux_density_ratio": float(s["flux_density"] / r["flux_density"]),
                     "p99_ratio": float(s["p99"] / r["p99"])})
        row = rows[-1]
        print(f"{length:4g} Mm, seed {seed}, {name}: elongation {s['elongation']:.3f} "
              f"(real {r['elongation']:.3f}), number {row['number_ratio']:.2f}, "
              f"flux {row['flux_density_ratio']:.2f}, 99 % {row['p99_ratio']:.2f} of the real", flush=True)
    table = QTable(rows=rows)
    table.meta["description"] = ("network clusters' median elongation (and number, flux per area, 99th "
                                 "percentile over the real map's) against the network's chain length; "
                                 "scripts/network_chain_length.py")
    table.meta["gongsynth_version"] = gongsynth.__version__
    table.write(args.table, overwrite=True)


if __name__ == "__main__":
    main()
