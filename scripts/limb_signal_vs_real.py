"""
The quiet Sun's signal from disk centre to the limb: real GONG and MDI maps beside gongsynth's runs.

For each map, in the rings of `gongsynth.analysis.statistics.ring_means`
(all at GONG's pixels: MDI's maps through `degrade_if_finer`), the mean
|B|, the robust width (1.4826 × MAD) and the robust pixel-difference noise;
for gongsynth's runs also their noise-free truth through the PSF
(``truth_psf``).  MDI is the check that needs no seeing: a space instrument,
so whatever its real map shows that the model's does not is the Sun's, not
the atmosphere's.

- GONG: the Big Bear map of 2009-09-05 18:54 and the gallery's ``like`` run
  (the file's date, site, pointing and count level, the real instrument's
  effects on, 9 minutes, 3 × 3 samples per pixel);
- MDI: the 96-minute level-1.8 magnetogram of 2010-10-15 00:00 and a 5-minute
  full-disk MDI run of that date.

Writes an ECSV table (one row per map, kind and ring)::

    python scripts/limb_signal_vs_real.py --cache runs --table docs/guide/limb_signal_vs_real.ecsv

Takes about 1-2 minutes on two cores.  The runs are those of
``scripts/network_clusters_vs_real.py`` (its ``simulated``, the same cache).
"""
import sys
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from network_clusters_vs_real import real_and_simulated_maps, runs_parser  # noqa: E402  (the same runs)


def main(argv=None):
    """Measure the rings of the real and simulated maps, write the table."""
    parser = runs_parser(__doc__)
    args = parser.parse_args(argv)

    import astropy.units as u
    import numpy as np
    from astropy.table import QTable, vstack

    import gongsynth
    from gongsynth.analysis.degrade import degrade_if_finer
    from gongsynth.analysis.statistics import ring_means

    warnings.simplefilter("ignore", category=UserWarning)
    maps = real_and_simulated_maps(args.seeds, args.cache, instruments=("gong", "mdi"), truth=True)
    tables = []
    for instrument, date, kind, seed, smap in maps:
        rings = ring_means(degrade_if_finer(smap)[0])      # MDI's maps at GONG's pixels; GONG's as they are
        n = len(rings)
        rings.add_columns([[instrument] * n, [date] * n, [kind] * n, np.full(n, seed)],
                          indexes=[0, 0, 0, 0], names=["instrument", "date", "kind", "seed"])
        tables.append(QTable(rings))
    table = vstack(tables)
    for name in ("mean_abs", "robust_sigma", "difference_sigma"):
        table[name] = table[name].to(u.G)
    table.meta["description"] = __doc__.splitlines()[1]
    table.meta["gongsynth_version"] = gongsynth.__version__
    args.table.parent.mkdir(parents=True, exist_ok=True)
    table.write(args.table, overwrite=True)
    table["instrument", "kind", "seed", "r_inner", "r_outer", "mean_abs", "robust_sigma",
          "difference_sigma"].pprint(max_lines=-1, max_width=-1)


if __name__ == "__main__":
    main()
