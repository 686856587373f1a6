"""
Benchmark of the large-scale field: `synthetic_surface_field` and `surface_field_from_map`.

1. The synthetic Sun at 0.5° (360 × 720 cells) at a minimum, a maximum and the
   2024 maximum.  Baseline in the same process: the same regions' Gaussians
   evaluated over the whole grid (no windows, no separable products), which
   is what the windowed evaluation saves.
2. The remap of a 1024 × 1024 full-disk map (MDI-like, 1.98″/px) to 0.5°.
   Baseline in the same process: `reproject.reproject_interp` onto the same
   CEA grid (bilinear, no area weighting, no μ, no rotation), if installed.

Usage: python benchmarks/bench_surface_field.py [--repeat 3]
"""
import argparse
import math
import time

import astropy.units as u
import numpy as np
import sunpy.map
from astropy.coordinates import SkyCoord
from sunpy.coordinates import frames

from gongsynth.sun.surface_field import surface_field_from_map, synthetic_surface_field
from gongsynth.sun.surface_field.maps import field_grid, make_surface_field
from gongsynth.sun.surface_field.synthetic import active_regions


def best_of(repeat, func):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        out = func()
        times.append(time.perf_counter() - start)
    return min(times), out


def dense_regions(date, seed):
    """Baseline: every region's four Gaussians over the full grid (sunspot and plage sizes as a fixed 1°)."""
    regions = active_regions(date, seed=seed)
    lon, lat = field_grid((360, 720))
    lon2, lat2 = np.meshgrid(np.radians(lon), np.radians(lat))
    out = np.zeros(lon2.shape)
    for k in range(regions["age"].size):
        for sign, offset in ((1, 2.0), (-1, -2.0)):
            lon0 = math.radians(regions["longitude"][k] + offset)
            lat0 = math.radians(regions["latitude"][k])
            cosd = (np.sin(lat2) * math.sin(lat0) + np.cos(lat2) * math.cos(lat0) * np.cos(lon2 - lon0))
            d2 = np.arccos(np.clip(cosd, -1, 1)) ** 2
            for sigma in (0.5, 1.0):
                out += sign * np.exp(-d2 / (2 * math.radians(sigma) ** 2))
    return out


def disk_map(size=1024, scale=1.98):
    ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective, observer="earth",
                   obstime="2010-10-15")
    rng = np.random.default_rng(0)
    data = rng.normal(0, 10.0, (size, size))
    y, x = np.mgrid[:size, :size]
    c = (size - 1) / 2
    data[np.hypot(x - c, y - c) > 970 / scale] = np.nan
    return sunpy.map.Map(data, sunpy.map.make_fitswcs_header(
        data, ref, scale=[scale, scale] * u.arcsec / u.pix, unit=u.G))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    print("synthetic_surface_field, 0.5 deg grid")
    for date in ("2009-09-05", "2014-04-01", "2024-10-01"):
        t, field = best_of(args.repeat, lambda date=date: synthetic_surface_field(date, seed=1))
        tb, _ = best_of(1, lambda date=date: dense_regions(date, 1))
        print(f"  {date}: {t:.3f} s ({field.meta['nregions']} regions); dense baseline {tb:.2f} s; "
              f"ratio {tb / t:.1f}")
    smap = disk_map()
    t, field = best_of(args.repeat, lambda: surface_field_from_map(smap))
    line = f"surface_field_from_map, 1024^2 full disk -> 0.5 deg: {t:.2f} s"
    try:
        from reproject import reproject_interp
    except ImportError:
        print(line + " (reproject not installed: no baseline)")
        return
    target = make_surface_field(np.zeros((360, 720)), smap.date, source="grid").wcs
    tb, _ = best_of(args.repeat, lambda: reproject_interp(smap, target, shape_out=(360, 720)))
    print(line + f"; reproject_interp baseline {tb:.2f} s; ratio {t / tb:.2f} (ours / baseline)")


if __name__ == "__main__":
    main()
