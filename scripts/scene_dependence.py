r"""
Measure the weak-flux factor against distance from strong fields and local flux density (issue 24, item 3).

What it runs: the shipped table's configuration (the default
`gongsynth.simulate`: the 3-D model Sun, 256² columns of 384 km with its
sunspot; GONG 860², 10 minutes) at several viewing latitudes and seeds,
through `gongsynth.run_cache.cached_runs` (a rerun reads the runs from
``--cache``).  In each run, on the native-resolution quarter of the tiled field:

- **strong pixels**: :math:`|B_\mathrm{meas}| \ge 400\,\mathrm{G} \cos\theta`
  in the measured magnetogram itself
  (`gongsynth.analysis.scene_calibration.strong_field_mask`), the pixels
  `gongsynth.calibrate` gives the sunspot curve;
- **quiet pixels**: all the others (calibrate's quiet-Sun curve: here without
  the papers' 17.5″ dilation of the dark sunspot, because calibrate applies
  the quiet curve right up to the strong pixels), with finite truth through
  the PSF, and nearer to a strong pixel than to the edge of the quarter (so
  no strong pixel outside it could be nearer);
- each quiet pixel's **distance** on the Sun to the nearest strong pixel (in
  the tile, rows foreshortened by cos(latitude): `run_context`; on a real map
  `~gongsynth.analysis.scene_calibration.strong_field_distance` measures it
  from the pixels' heliographic positions) and its
  **local flux density**, the mean |B_meas| over 11 × 11 pixels (27.5″,
  20 Mm at disk centre; `~gongsynth.analysis.scene_calibration.local_flux_density`).

Per group (distance: `~gongsynth.analysis.scene_calibration.DISTANCE_EDGES`;
flux density: ``DENSITY_EDGES``) the papers' flux-conserving fit
(`gongsynth.analysis.weak_flux.flux_conserving_fit`, ``--bins`` bins in every
group) gives the quiet factor, and its ratio to the same fit over all the
run's quiet pixels.  Factor and ratio are averaged over the seeds, with the
seeds' standard error (each seed a different Sun; a pooled fit's bootstrap
error is 3-10 times smaller than that scatter).  The distance table goes to
``--table`` (shipped as ``gongsynth/data/scene_factors.ecsv``, which
``calibrate(..., scene="distance")`` applies); both measurements to ``--out``::

    python scripts/scene_dependence.py --latitudes 0 25 45 60 75 --seeds 1 2 3 4 --cache runs \
        --table gongsynth/data/scene_factors.ecsv --out docs/guide/scene_dependence.ecsv \
        --summary docs/guide/scene_dependence.txt

About 21 s of CPU per run (the 20 runs above: 7 CPU-minutes) and 3 s per run for the analysis.
"""
import argparse
import datetime
from pathlib import Path

import astropy.units as u
import numpy as np
import scipy.ndimage
from astropy.table import QTable

from gongsynth.analysis.calibration import gauss_values
from gongsynth.analysis.scene_calibration import (
    DISTANCE_EDGES,
    local_flux_density,
    scene_table,
    strong_field_mask,
)
from gongsynth.analysis.weak_flux import QUIET_LIMIT, flux_conserving_fit
from gongsynth.config import SimulationConfig
from gongsynth.run_cache import cached_runs, run_config
from gongsynth.version import version

#: Edges of the local flux density groups (G, mean |B_meas| over ``SIDE`` × ``SIDE`` pixels).
DENSITY_EDGES = (0, 10, 20, 40, 80, np.inf) * u.G

#: Side (pixels) of the local flux density's square.
SIDE = 11


def run_context(run):
    """Measured and true field, distance (Mm) and local flux density (G) of a run's usable quiet pixels.

    A tiled run's WCS places its field on a full disk, but the field is the model's box seen at
    ``config.latitude`` on the central meridian: the viewing angle is that latitude everywhere, and
    distances on the Sun are those in the tile with its north-south axis (rows) foreshortened by
    cos(latitude).  (`~gongsynth.analysis.scene_calibration.strong_field_distance` measures the same
    distance on a real map, from its pixels' heliographic positions.)
    """
    m = gauss_values(run.magnetogram, "magnetogram")
    t = gauss_values(run.truth_psf, "truth_psf")
    latitude = run.config.latitude.to(u.deg)
    usable = np.asarray(run.resolution_map) == 1
    strong = strong_field_mask(m, np.full(m.shape, latitude.value)) & usable
    pixel = abs(u.Quantity(run.magnetogram.scale.axis1).to_value(u.rad / u.pix))
    # The surface at disk centre lies one solar radius nearer than the Sun's centre.
    mm = (run.magnetogram.dsun - run.magnetogram.rsun_meters).to_value(u.Mm) * np.tan(pixel)
    sampling = (mm / np.cos(latitude.to_value(u.rad)), mm)
    distance = scipy.ndimage.distance_transform_edt(~strong, sampling=sampling)
    edge = scipy.ndimage.distance_transform_edt(usable, sampling=sampling)
    quiet = usable & ~strong & np.isfinite(m) & np.isfinite(t) & (distance < edge)
    density = local_flux_density(np.where(usable, m, np.nan), SIDE).to_value(u.G)
    return m[quiet], t[quiet], distance[quiet], density[quiet]


def group_factors(context, key, edges, n_bins):
    """Per group of ``context[key]`` in ``edges``: (factor, ratio to all, pixels, median key) of one run."""
    m, t = context[0], context[1]
    reference = flux_conserving_fit(m, t, n_bins).slope_at_zero
    out = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = (context[key] >= lo) & (context[key] < hi)
        try:
            factor = flux_conserving_fit(m[sel], t[sel], n_bins).slope_at_zero
        except ValueError:  # too few pixels for the bins
            factor = np.nan
        out.append((factor, factor / reference, int(sel.sum()),
                    float(np.median(context[key][sel])) if sel.any() else np.nan))
    return out


def _mean_error(values):
    values = np.asarray(values, float)
    values = values[np.isfinite(values)]
    if values.size == 0:
        return np.nan, np.nan, 0
    error = np.std(values, ddof=1) / np.sqrt(values.size) if values.size > 1 else np.nan
    return float(np.mean(values)), float(error), int(values.size)


def measure(runs_by_latitude, n_bins):
    """The distance and flux-density rows (dicts) of every latitude, seeds averaged."""
    distance_rows, density_rows = [], []
    for latitude, runs in runs_by_latitude.items():
        contexts = [run_context(run) for run in runs]
        for key, edges, rows in ((2, DISTANCE_EDGES.to_value(u.Mm), distance_rows),
                                 (3, DENSITY_EDGES.to_value(u.G), density_rows)):
            per_seed = [group_factors(c, key, edges, n_bins) for c in contexts]
            for g, (lo, hi) in enumerate(zip(edges[:-1], edges[1:])):
                factor, factor_error, n_seeds = _mean_error([s[g][0] for s in per_seed])
                ratio, ratio_error, _ = _mean_error([s[g][1] for s in per_seed])
                pooled = np.concatenate([c[key][(c[key] >= lo) & (c[key] < hi)] for c in contexts])
                rows.append(dict(latitude=latitude, low=lo, high=hi,
                                 median=float(np.median(pooled)) if pooled.size else np.nan,
                                 n_pixels=sum(s[g][2] for s in per_seed), n_seeds=n_seeds, factor=factor,
                                 factor_uncertainty=factor_error, ratio=ratio, uncertainty=ratio_error))
    return distance_rows, density_rows


def summary(distance_rows, density_rows):
    """Ratio ± seeds' standard error per group (rows) and latitude (columns), as strings."""
    latitudes = list(dict.fromkeys(r["latitude"] for r in distance_rows))
    table = []
    for name, rows, unit in (("distance", distance_rows, "Mm"), ("flux density", density_rows, "G")):
        for lo, hi in dict.fromkeys((r["low"], r["high"]) for r in rows):
            cells = {r["latitude"]: r for r in rows if (r["low"], r["high"]) == (lo, hi)}
            group = f"{name} {lo:g}-{hi:g} {unit}" if np.isfinite(hi) else f"{name} > {lo:g} {unit}"
            table.append([group] + [f"{cells[lat]['ratio']:.3f} ± {cells[lat]['uncertainty']:.3f}"
                                    for lat in latitudes])
    return QTable(rows=table, names=["group"] + [f"{lat:g} deg" for lat in latitudes])


def main(argv=None):
    """Run (or read from the cache), measure, print and write the tables."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--latitudes", type=float, nargs="+", default=[0, 25, 45, 60])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--bins", type=int, default=15, help="curve bins of every fit (the same in each)")
    parser.add_argument("--workers", type=int)
    parser.add_argument("--cache", type=Path)
    parser.add_argument("--table", type=Path, help="write the distance table (the shipped scene table)")
    parser.add_argument("--out", type=Path, help="write both measurements (ECSV)")
    parser.add_argument("--summary", type=Path, help="write the ratios as a reStructuredText table")
    args = parser.parse_args(argv)

    configs = [SimulationConfig.from_arguments(latitude=lat * u.deg).replace(seed=seed)
               for lat in args.latitudes for seed in args.seeds]
    runs = [None] * len(configs)
    for index, run in cached_runs(configs, cache=args.cache, workers=args.workers, desc="runs"):
        runs[index] = run
    by_latitude = {lat: runs[i * len(args.seeds):(i + 1) * len(args.seeds)]
                   for i, lat in enumerate(args.latitudes)}
    distance_rows, density_rows = measure(by_latitude, args.bins)

    base = run_config(configs[0])
    metadata = {
        "gongsynth_version": version, "instrument": base.instrument.name,
        "grid": f"{base.photosphere_shape[0]}x{base.photosphere_shape[1]} columns of "
                f"{base.photosphere_pixel_size}, {base.sun} Sun; detector "
                f"{base.instrument.detector_shape}^2, {base.duration}",
        "seeds": list(args.seeds), "latitudes": [f"{lat:g} deg" for lat in args.latitudes], "bins": args.bins,
        "threshold": f"{QUIET_LIMIT.to_value(u.G)} G",
        "method": "strong pixels: |B_meas| >= threshold x cos(theta) in the measured map "
                  "(native-resolution quarter, theta = the run's latitude); quiet pixels: the others with "
                  "finite truth through the PSF, nearer to a strong pixel than to the quarter's edge; "
                  "distance: on the Sun to the nearest strong pixel (the tile's rows foreshortened by "
                  "cos(latitude)); per distance group the papers' flux-conserving fit "
                  "with the same bins, factor = slope at zero, ratio = factor / the same fit over all the "
                  "run's quiet pixels; mean and standard error over seeds",
        "script": "scripts/scene_dependence.py",
        "config": base.replace(latitude=0 * u.deg, seed=0).to_toml(comments=False),
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
    }
    for name, rows, unit in (("distance (Mm)", distance_rows, "Mm"), ("flux density (G)", density_rows, "G")):
        print(f"--- {name}")
        for r in rows:
            print(f"{r['latitude']:4.0f} deg  {r['low']:5.1f}-{r['high']:5.1f} {unit} "
                  f"(median {r['median']:6.1f}): "
                  f"factor {r['factor']:.3f} ± {r['factor_uncertainty']:.3f}, ratio {r['ratio']:.3f} ± "
                  f"{r['uncertainty']:.3f}  ({r['n_pixels']} px, {r['n_seeds']} seeds)")
    if args.table:
        table = scene_table([dict(latitude=r["latitude"], distance_min=r["low"], distance_max=r["high"],
                                  distance=r["median"], n_pixels=r["n_pixels"], n_seeds=r["n_seeds"],
                                  factor=r["factor"], factor_uncertainty=r["factor_uncertainty"],
                                  ratio=r["ratio"], uncertainty=r["uncertainty"])
                             for r in distance_rows if np.isfinite(r["ratio"])], metadata=metadata)
        table.write(args.table, format="ascii.ecsv", overwrite=True)
        print(f"wrote {args.table}")
    if args.summary:
        summary(distance_rows, density_rows).write(args.summary, format="ascii.rst", overwrite=True)
        print(f"wrote {args.summary}")
    if args.out:
        kinds = (("distance", distance_rows), ("flux_density", density_rows))
        both = QTable(rows=[dict(quantity=q, **r) for q, rows in kinds for r in rows])
        both["latitude"] = both["latitude"] * u.deg
        both.meta.update(metadata)
        both.meta["units"] = ("low, high, median: Mm for distance, G for flux_density (mean |B_meas| over "
                              "11x11 px)")
        both.write(args.out, format="ascii.ecsv", overwrite=True)
        print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
