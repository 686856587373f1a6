"""
The real Big Bear map's zero point across the disk, and what taking it out of both maps does to the bars.

GONG's zero-point correction fits low-order Zernike polynomials to the
difference between each 10-minute average and a daily reference magnetogram;
before it the zero point varies across the image by 5-10 G (NSO, *Zero point
correction*, presentation).  The Big Bear file of 2009-09-05 is a site file
before that correction.  Without the reference magnetogram, this script fits
the same polynomials (radial orders 0 to ``--orders``) to each map itself,
on the disk within 0.95 R☉, iteratively leaving out pixels beyond 3 robust σ
of the fit (the network), and reports the fitted surface's rms and range on
the real map and on simulated ones (where it is the Sun's own large-scale
field and noise: the yardstick).  It then takes each map's own surface out
of it and compares the maps again (`gongsynth.analysis.map_statistics`)::

    python scripts/zero_point_surface.py --simulated runs/gong_seed1.fits runs/gong_seed2.fits

(the maps of ``scripts/network_clusters_vs_real.py``'s cache).  Seconds.
"""
import argparse
import os
from math import factorial
from pathlib import Path

import astropy.units as u
import numpy as np

REAL = Path(os.environ.get("GONGSYNTH_REAL_DATA", Path(__file__).resolve().parents[2] / "shared" / "data"
                           / "real"))
BIG_BEAR = REAL / "gong" / "bbbqa090905t1854.fits.gz"


def zernike(r, theta, order):
    """The Zernike polynomials of radial order ≤ ``order`` at (r, θ) on the unit disk, (terms, points)."""
    terms = []
    for n in range(order + 1):
        for m in range(-n, n + 1, 2):
            up, down = (n + abs(m)) // 2, (n - abs(m)) // 2
            radial = sum((-1) ** k * factorial(n - k) * r ** (n - 2 * k)
                         / (factorial(k) * factorial(up - k) * factorial(down - k)) for k in range(down + 1))
            terms.append(radial * (np.cos(abs(m) * theta) if m >= 0 else np.sin(abs(m) * theta)))
    return np.array(terms)


def zero_point_surface(smap, order, max_radius=0.95, clip=3.0, iterations=8):
    """The fitted surface (G, NaN off the disk) and the fraction of pixels it kept."""
    from astropy.coordinates import SkyCoord

    data = np.asarray(smap.data, dtype=float)
    centre = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=smap.coordinate_frame)
    cx, cy = smap.wcs.world_to_pixel(centre)
    radius = (smap.rsun_obs / smap.scale[0]).to_value(u.pix)
    y, x = np.indices(data.shape)
    r, theta = np.hypot(x - cx, y - cy) / radius, np.arctan2(y - cy, x - cx)
    fit_here = np.isfinite(data) & (r < max_radius)
    basis, values = zernike(r[fit_here], theta[fit_here], order), data[fit_here]
    keep = np.ones(values.size, dtype=bool)
    for _ in range(iterations):
        coefficients = np.linalg.lstsq(basis[:, keep].T, values[keep], rcond=None)[0]
        residual = values - coefficients @ basis
        sigma = 1.4826 * np.median(np.abs(residual[keep] - np.median(residual[keep])))
        keep = np.abs(residual) < clip * sigma
    surface = np.full(data.shape, np.nan)
    disk = np.isfinite(data) & (r < 1)
    surface[disk] = coefficients @ zernike(r[disk], theta[disk], order)
    return surface, float(keep.mean())


def main(argv=None):
    """Fit, print the surfaces' sizes, compare the maps with and without them."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--simulated", type=Path, nargs="+", required=True, help="simulated magnetograms")
    parser.add_argument("--orders", type=int, default=4, help="highest radial order fitted")
    args = parser.parse_args(argv)

    import sunpy.map

    import gongsynth
    from gongsynth.analysis.disk import disk_coordinates
    from gongsynth.analysis.map_statistics import compare_statistics

    real = gongsynth.load_observation(BIG_BEAR)
    maps = {"real": real, **{path.stem: sunpy.map.Map(path) for path in args.simulated}}
    print("zero-point surface within 0.95 R: rms about its mean, 1st-99th percentile range, mean [G]")
    fitted = {}
    for name, smap in maps.items():
        inner = np.asarray(disk_coordinates(smap)[0]) < 0.95
        for order in range(args.orders + 1):
            surface, kept = zero_point_surface(smap, order)
            fitted[name, order] = surface
            s = surface[inner & np.isfinite(surface)]
            spread = np.ptp(np.percentile(s, [1, 99]))
            print(f"  {name:>14} order {order}: rms {s.std():5.2f}  range {spread:5.2f}"
                  f"  mean {s.mean():6.2f}  (fit kept {kept:.3f} of the pixels)")
    print("bars with each map's own surface taken out (sim / real; KS as measured and medians removed)")
    for name in list(maps)[1:]:
        for order in [None] + list(range(args.orders + 1)):
            pair = [maps[key] if order is None else
                    sunpy.map.Map(np.where(np.isfinite(maps[key].data), maps[key].data
                                           - np.nan_to_num(fitted[key, order]), np.nan), maps[key].meta)
                    for key in (name, "real")]
            t = compare_statistics(*pair).table
            label = "as they are" if order is None else f"order ≤ {order} out"
            print(f"  {name:>14} {label:>12}: KS {t['ks'][0]:.3f} ({t['ks_centred'][0]:.3f}), mean |B| "
                  f"{(t['mean_abs'][0] / t['mean_abs'][1]).value:.3f}, 99.9 % "
                  f"{(t['p999'][0] / t['p999'][1]).value:.2f}")


if __name__ == "__main__":
    main()
