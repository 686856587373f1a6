"""
Network flux clusters of real GONG, MDI and HMI maps and of gongsynth's runs of their dates, at GONG's pixels.

One Sun model seen by three instruments, each against its own real map: if
the model's network were too weak (or too strong), all three simulated maps
would show too few (or too many) clusters.  The real maps:

- GONG Big Bear, 2009-09-05 18:54 (10-minute average), as it is;
- MDI 96-minute level-1.8 magnetogram, 2010-10-15 00:00, degraded to GONG;
- HMI 45-s magnetogram, 2010-10-20 00:00 (the 1024² Postel cut-out), degraded to GONG.

The simulated maps (seeds ``--seeds``, run once and kept in ``--cache``): the
Big Bear run of the gallery (``like`` the real file, GONG's real-noise effects
on, 9 minutes, 3 × 3 samples per pixel), MDI's full disk of 2010-10-15 (5 ×
1 minute, the 96-minute product) and HMI's 45-s full disk of 2010-10-20, all
with the synthetic Sun of their date, MDI and HMI degraded to GONG like their
real maps.  `gongsynth.analysis.network_clusters.network_clusters` measures
every map the same way: within 0.35 R☉, quiet pixels only, thresholds
``--thresholds`` (G).  Writes ``--table`` (ECSV) and prints it::

    python scripts/network_clusters_vs_real.py --cache /tmp/clusters \
        --table docs/guide/network_clusters_vs_real.ecsv

About 3 minutes of CPU for two seeds on two cores (HMI's 4096² runs are most of it).
"""
import argparse
import os
import warnings
from pathlib import Path

REAL = Path(os.environ.get("GONGSYNTH_REAL_DATA", Path(__file__).resolve().parents[2] / "shared" / "data"
                           / "real"))
REAL_MAPS = {
    "gong": ("2009-09-05T18:54", REAL / "gong" / "bbbqa090905t1854.fits.gz"),
    "mdi": ("2010-10-15T00:00", REAL / "mdi" / "mdi.fd_m_96m_lev182.20101015_000000_TAI.data.fits"),
    "hmi": ("2010-10-20T00:00", REAL / "hmi" / "JSOC_hmi.m_45s.20101020_000000_TAI.2.magnetogram.fits"),
}


def simulated(instrument, seed, cache, chain_length=None, doppler=False):
    """
    The run of ``instrument``'s real map: its magnetogram and truth ⊗ PSF (run and saved first if missing).

    ``chain_length`` (a length) sets the run's ``network_chain_length`` (default: the configuration's);
    ``doppler`` adds the run's Dopplergram (a cache without it is run again: the same seed, the same
    maps).

    Also used by ``scripts/limb_signal_vs_real.py``, ``scripts/power_spectrum_seeds.py`` and
    ``scripts/limb_anisotropy.py`` (the same runs, the same cache).
    """
    import astropy.units as u
    import sunpy.map

    paths = {"magnetogram": Path(cache) / f"{instrument}_seed{seed}.fits",
             "truth_psf": Path(cache) / f"{instrument}_seed{seed}_truth_psf.fits"}
    if doppler:
        paths["doppler"] = Path(cache) / f"{instrument}_seed{seed}_doppler.fits"
    if not all(p.exists() for p in paths.values()):
        import gongsynth
        from gongsynth.config import Effects, SimulationConfig
        from gongsynth.observing import as_observed, like_gong

        date = REAL_MAPS[instrument][0]
        if instrument == "gong":
            settings, gong = like_gong(REAL_MAPS["gong"][1])
            settings, effects = as_observed(settings, {}, mode="full-disk", instrument_name=gong.name)
            config = SimulationConfig(mode="full-disk", duration=9 * u.min, seed=seed,
                                      surface_field="synthetic", instrument=gong.replace(supersampling=3),
                                      effects=Effects(**effects), **settings)
        else:
            duration = 5 * u.min if instrument == "mdi" else 0.75 * u.min
            config = SimulationConfig(instrument=instrument, mode="full-disk", duration=duration, seed=seed,
                                      obstime=date, surface_field="synthetic")
        if chain_length is not None:
            config = config.replace(network_chain_length=chain_length)
        Path(cache).mkdir(parents=True, exist_ok=True)
        result = gongsynth.simulate(config=config, progress=False)
        for kind, path in paths.items():
            getattr(result, kind).save(path, overwrite=True)
    return {kind: sunpy.map.Map(path) for kind, path in paths.items()}


def real_and_simulated_maps(seeds, cache, instruments=tuple(REAL_MAPS), truth=False):
    """
    (instrument, date, kind, seed, map) of each real map and of gongsynth's runs of its date.

    ``kind`` is "real" (seed -1), "simulated" and, with ``truth``, "truth_psf" (the runs' noise-free
    truth through the PSF).
    """
    import gongsynth

    maps = []
    for instrument in instruments:
        date, path = REAL_MAPS[instrument]
        maps.append((instrument, date, "real", -1, gongsynth.load_observation(path)))
        for seed in seeds:
            runs = simulated(instrument, seed, cache)
            maps.append((instrument, date, "simulated", seed, runs["magnetogram"]))
            if truth:
                maps.append((instrument, date, "truth_psf", seed, runs["truth_psf"]))
    return maps


def runs_parser(doc, seeds=(1, 2)):
    """
    The command line of a script that measures these runs: ``--cache``, ``--seeds`` and ``--table``.

    Also used by ``scripts/limb_signal_vs_real.py``, ``scripts/limb_signal_scales.py``,
    ``scripts/power_spectrum_seeds.py`` and ``scripts/limb_anisotropy.py``.
    """
    parser = argparse.ArgumentParser(description=doc.splitlines()[1])
    parser.add_argument("--cache", type=Path, default=Path("network_clusters_runs"),
                        help="folder of the simulated maps (made if missing; network_clusters_vs_real.py's)")
    parser.add_argument("--seeds", type=int, nargs="+", default=list(seeds))
    parser.add_argument("--table", type=Path, required=True, help="ECSV file to write")
    return parser


def main(argv=None):
    """Measure the real and simulated maps, write the table."""
    parser = runs_parser(__doc__)
    parser.add_argument("--thresholds", type=float, nargs="+", default=[20.0, 40.0], help="G")
    args = parser.parse_args(argv)

    import astropy.units as u
    from astropy.table import QTable

    import gongsynth
    from gongsynth.analysis.degrade import degrade_if_finer
    from gongsynth.analysis.network_clusters import network_clusters

    warnings.simplefilter("ignore", category=UserWarning)
    rows = []
    for instrument, date, kind, seed, smap in real_and_simulated_maps(args.seeds, args.cache):
        gong_map = degrade_if_finer(smap)[0]        # MDI's and HMI's maps; GONG's as they are
        for threshold in args.thresholds:
            found = network_clusters(gong_map, threshold=threshold * u.G)
            s = found.summary()
            rows.append({"instrument": instrument, "date": date, "kind": kind, "seed": seed,
                         "threshold": threshold * u.G, "region_area": found.region_area,
                         "number": s["number"],
                         "number_per_1e4_Mm2": s["number_density"].to_value(u.Mm**-2) * 1e4,
                         "flux_density": s["flux_density"], "p50": s["p50"], "p90": s["p90"], "p99": s["p99"],
                         "above_3e19": s["above_index_flux"], "above_1e20": s["above_1e20"],
                         "index": s["index"], "index_error": s["index_error"],
                         "elongation": s["elongation"], "shaped": s["shaped"]})
    table = QTable(rows=rows)
    table.meta["description"] = ("network clusters (connected pixels of one sign beyond the threshold, quiet "
                                 "pixels within 0.35 Rsun) of real and simulated maps at GONG resolution; "
                                 "scripts/network_clusters_vs_real.py")
    table.meta["gongsynth_version"] = gongsynth.__version__
    args.table.parent.mkdir(parents=True, exist_ok=True)
    table.write(args.table, overwrite=True)
    for col in ("region_area", "flux_density", "p50", "p90", "p99", "number_per_1e4_Mm2", "index",
                "index_error", "elongation"):
        table[col].info.format = ".3g"
    table.pprint(max_lines=-1, max_width=-1)
    return table


if __name__ == "__main__":
    main()
