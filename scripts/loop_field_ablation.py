"""
Ablation only (not in gongsynth): the Big Bear bars with a field of small loops added to the simulated map.

The model Sun's horizontal internetwork field averages away over GONG's
resolution (noise guide: 600-fold over σ = 1.5 Mm); a field of small loops
with random azimuths would not.  This script adds to the simulated Big Bear
maps (``scripts/network_clusters_vs_real.py``'s cache) the line-of-sight part
of such a field, after the fact: Lites et al.'s (2008, ApJ 672, 1237)
apparent horizontal flux density of 55 G at 0.3″, independent from one 1″
patch to the next (the size of their horizontal patches; chosen), random in
azimuth (× 1/√2) and seen as sin θ, averaged over each 2.56″ pixel (6.5
patches) and through a 5″ Gaussian resolution element — a snapshot: the
transient horizontal fields live 1-10 minutes (Ishikawa & Tsuneta 2011), so
a 9-minute average would hold less of them.  It then compares each map with
the real one (`gongsynth.analysis.map_statistics.compare_statistics`)::

    python scripts/loop_field_ablation.py --cache runs --seeds 1 2

``--horizontal`` and ``--patch`` set another amplitude and patch size, e.g. the
MURaM snapshot's at 200 km (``--horizontal 31.3 --patch 0.45``: its rms per
component × √2 and the side of its equivalent white area,
``scripts/horizontal_field_muram.py``).

Seconds (the runs are cached).
"""
import argparse
import os
from pathlib import Path

import numpy as np

REAL = Path(os.environ.get("GONGSYNTH_REAL_DATA", Path(__file__).resolve().parents[2] / "shared" / "data"
                           / "real"))
BIG_BEAR = REAL / "gong" / "bbbqa090905t1854.fits.gz"
#: Lites et al. 2008: apparent horizontal flux density (G) at 0.3″, and the patches' size (arcsec; chosen).
HORIZONTAL_G, PATCH_ARCSEC, RESOLUTION_ARCSEC = 55.0, 1.0, 5.0


def loop_signal(shape, rho, pixel_arcsec, rng, horizontal=HORIZONTAL_G, patch=PATCH_ARCSEC):
    """The line-of-sight signal (G) of the loop field on a map's pixels (ρ in solar radii)."""
    from scipy.ndimage import gaussian_filter

    per_pixel = horizontal / np.sqrt(2) * patch / pixel_arcsec
    sigma = RESOLUTION_ARCSEC / 2.355 / pixel_arcsec
    smoothed = gaussian_filter(rng.standard_normal(shape) * per_pixel, sigma)
    return smoothed * np.clip(rho, 0, 1)          # sin θ = ρ on the disk


def main(argv=None):
    """Add the loop field to each cached run and compare it with the real map, before and after."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--cache", type=Path, required=True, help="network_clusters_vs_real.py's cache")
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--horizontal", type=float, default=HORIZONTAL_G,
                        help="rms |B_h| (G) of the patches (default: Lites et al.'s 55 G)")
    parser.add_argument("--patch", type=float, default=PATCH_ARCSEC,
                        help="side (arcsec) of the independent patches (default 1)")
    args = parser.parse_args(argv)

    import astropy.units as u
    import sunpy.map

    import gongsynth
    from gongsynth.analysis.disk import disk_coordinates
    from gongsynth.analysis.map_statistics import compare_statistics

    real = gongsynth.load_observation(BIG_BEAR)
    for seed in args.seeds:
        sim = sunpy.map.Map(args.cache / f"gong_seed{seed}.fits")
        rho = np.asarray(disk_coordinates(sim)[0])
        added = loop_signal(sim.data.shape, rho, sim.scale[0].to_value(u.arcsec / u.pix),
                            np.random.default_rng(100 + seed), args.horizontal, args.patch)
        ring = np.isfinite(sim.data) & (rho > 0.6) & (rho < 0.8)
        print(f"seed {seed}: loop field's line-of-sight rms at 0.6-0.8 R = {added[ring].std():.2f} G")
        with_loops = sunpy.map.Map(np.where(np.isfinite(sim.data), sim.data + added, np.nan), sim.meta)
        for label, smap in (("as simulated", sim), ("+ loop field", with_loops)):
            stats = compare_statistics(smap, real)
            t = stats.table
            ratio = {key: float((t[key][0] / t[key][1]).value) for key in ("mean_abs", "noise_box",
                                                                           "noise_difference")}
            print(f"  {label:>13}: KS {t['ks'][0]:.3f} ({t['ks_centred'][0]:.3f} medians removed), "
                  f"mean |B| {ratio['mean_abs']:.3f}, noise box {ratio['noise_box']:.2f} / pixel difference "
                  f"{ratio['noise_difference']:.2f}, mean |B| by ring "
                  + " ".join(f"{v:.2f}" for v in stats.rings["ratio"]))


if __name__ == "__main__":
    main()
