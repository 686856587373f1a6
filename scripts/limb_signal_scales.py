"""
At which scales the real quiet Sun's signal exceeds the model's: disk centre against 0.7 R☉.

``scripts/limb_signal_vs_real.py`` found that on real GONG and MDI maps the
weak signal grows from disk centre to 0.6-0.8 R☉ and on gongsynth's runs it
does not.  A small-scale horizontal field (loops of granular size, Lites et
al. 2008) would add its signal at the few-arcsec scales of GONG's resolution
element, a deficit of network-scale flux at tens of Mm.  This script
measures where the difference lies: the power spectrum
(`gongsynth.analysis.power_spectrum.power_spectrum`) of a 240″ box at disk
centre and the mean of four such boxes centred at 0.7 R☉ (east, west, north,
south), in wavelength bands, on the real maps and on gongsynth's runs of their
dates and their noise-free truth through the PSF (MDI's at GONG's pixels);
once as they are and once clipped to ±15 G about the median, which leaves the
weak field and takes out the network clusters' peaks::

    python scripts/limb_signal_scales.py --cache runs --table docs/guide/limb_signal_scales.ecsv

Seconds once the runs are cached (the runs of ``scripts/network_clusters_vs_real.py``).
"""
import sys
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from network_clusters_vs_real import real_and_simulated_maps, runs_parser  # noqa: E402  (the same runs)

#: Side of each box (arcsec), where the off-centre boxes sit (solar radii), and the clip (G).
BOX_ARCSEC, LIMB_RADIUS, CLIP_G = 240.0, 0.7, 15.0
#: Wavelength bands (Mm).
BANDS = ((5, 10), (10, 20), (20, 50), (50, 100))


def band_powers(smap, offsets, clip):
    """Mean over the boxes at ``offsets`` (arcsec) of each band's power, the map clipped or not."""
    import astropy.units as u
    import numpy as np
    import sunpy.map

    from gongsynth.analysis.power_spectrum import power_spectrum

    if clip:
        data = smap.data - np.nanmedian(smap.data)
        smap = sunpy.map.Map(np.clip(data, -CLIP_G, CLIP_G), smap.meta)
    spectra = [power_spectrum(smap, box=BOX_ARCSEC * u.arcsec, bins=12, offset=offset * u.arcsec)
               for offset in offsets]
    return [float(np.mean([s.band_power(lo * u.Mm, hi * u.Mm).to_value(u.G ** 2 * u.Mm ** 2)
                           for s in spectra])) for lo, hi in BANDS]


def main(argv=None):
    """Measure the bands on every map, write the table and print the real/simulated ratios."""
    parser = runs_parser(__doc__)
    args = parser.parse_args(argv)

    import astropy.units as u
    import numpy as np
    from astropy.table import QTable

    from gongsynth.analysis.degrade import degrade_if_finer

    warnings.simplefilter("ignore", category=UserWarning)
    rows = []
    maps = real_and_simulated_maps(args.seeds, args.cache, instruments=("gong", "mdi"), truth=True)
    for instrument, date, kind, seed, smap in maps:
        smap = degrade_if_finer(smap)[0]
        radius = LIMB_RADIUS * smap.rsun_obs.to_value(u.arcsec)
        places = {"centre": [(0.0, 0.0)],
                  "0.7R": [(radius, 0.0), (-radius, 0.0), (0.0, radius), (0.0, -radius)]}
        for place, offsets in places.items():
            for clip in (False, True):
                rows.append((instrument, date, kind, seed, place, clip, *band_powers(smap, offsets, clip)))
    names = ["instrument", "date", "kind", "seed", "place", "clipped"] + [f"power_{lo}_{hi}_Mm"
                                                                          for lo, hi in BANDS]
    table = QTable(rows=rows, names=names)
    for name in names[6:]:
        table[name].unit = u.G ** 2 * u.Mm ** 2
    table.meta["comments"] = [f"Band powers of {BOX_ARCSEC:g} arcsec boxes at disk centre and (mean of four) "
                              f"at {LIMB_RADIUS} Rsun; clipped: to +-{CLIP_G:g} G about the median. "
                              "scripts/limb_signal_scales.py"]
    table.write(args.table, overwrite=True)
    for instrument in ("gong", "mdi"):
        for place in ("centre", "0.7R"):
            for clip in (False, True):
                pick = [(r["kind"], r["seed"], np.array([r[n].value for n in names[6:]]))
                        for r in table if r["instrument"] == instrument and r["place"] == place
                        and bool(r["clipped"]) == clip]
                real = [p for k, _, p in pick if k == "real"][0]
                ratios = "  ".join(f"seed {s}: " + " ".join(f"{v:5.2f}" for v in real / p)
                                   for k, s, p in pick if k == "simulated")
                print(f"{instrument} {place:>6} {'clipped' if clip else 'as is':>7}  real/simulated by band "
                      f"{BANDS}: {ratios}")


if __name__ == "__main__":
    main()
