"""
How mixed the network's polarities are, and how balanced its large scales, on real and simulated maps.

Two measurements on the maps of ``scripts/network_clusters_vs_real.py`` (the
real GONG, MDI and HMI maps and gongsynth's runs of their dates, MDI and HMI
degraded to GONG's pixels, the same cache), each map's median taken out:

- **Polarity halo.**  Around every peak of the network (a local maximum of
  :math:`|B|` over 7 × 7 pixels within 0.5 R☉, in two groups of peak field,
  25-80 G and 80-400 G), the field times the peak's sign, averaged over rings
  and over the peaks: its mean at 7-14 Mm and at 14-36 Mm from the peak says
  whether a network concentration sits among flux of its own sign (a
  unipolar neighbourhood, > 0) or among mixed polarities (≈ 0).
- **Large-scale balance.**  The map clipped to ±25 G (the weak field: the
  clusters' peaks cut) and smoothed by Gaussians of σ = 27, 54 and 108 Mm
  (15, 30, 60 GONG pixels), its rms within 0.7 R☉: how much signed flux the
  weak field holds at the scales of cells, groups of cells and unipolar
  patches.

Writes ``--table`` (ECSV) and prints it::

    python scripts/network_polarity_vs_real.py --cache /tmp/clusters \
        --table docs/guide/network_polarity_vs_real.ecsv

Seconds with the runs cached (network_clusters_vs_real.py makes them).
"""
import warnings

import numpy as np
from network_clusters_vs_real import real_and_simulated_maps, runs_parser

#: Peak-field groups (G) and ring bands (Mm from the peak) of the polarity halo.
PEAK_GROUPS = ((25.0, 80.0), (80.0, 400.0))
HALO_BANDS = ((7.0, 14.0), (14.0, 36.0))
#: Smoothing sigmas (Mm) of the large-scale balance, and the clip (G) that keeps the weak field.
SMOOTHING = (27.0, 54.0, 108.0)
CLIP = 25.0


def disk_field(smap):
    """
    (field with the disk's median out and 0 elsewhere, quiet on-disk mask, r / R☉, Mm per pixel).

    Quiet: `~gongsynth.analysis.network_clusters.quiet_mask`, as the cluster census takes it (active
    regions and plage left out).
    """
    import astropy.units as u

    from gongsynth.analysis.disk import disk_coordinates
    from gongsynth.analysis.network_clusters import quiet_mask
    from gongsynth.analysis.power_spectrum import km_per_arcsec

    data = np.array(smap.data, dtype=float)
    radius = disk_coordinates(smap)[0]
    good = np.isfinite(data) & (radius < 0.97)
    field = np.where(good, data - np.median(data[good]), 0.0)
    good &= quiet_mask(field, smap.scale.axis1 * u.pix)
    mm_per_pixel = km_per_arcsec(smap).to_value(u.Mm / u.arcsec) * smap.scale.axis1.to_value(u.arcsec / u.pix)
    return field, good, radius, mm_per_pixel


def polarity_halo(field, good, radius, mm_per_pixel, peaks=(25.0, 80.0), bands=HALO_BANDS):
    """Number of peaks and the mean sign-corrected field (G) in each ring band around them."""
    from scipy import ndimage

    reach = int(np.ceil(max(b[1] for b in bands) / mm_per_pixel))
    magnitude = np.abs(field)
    at_peak = ((magnitude == ndimage.maximum_filter(magnitude, size=7)) & good & (radius < 0.5)
               & (magnitude > peaks[0]) & (magnitude < peaks[1]))
    rows, cols = np.nonzero(at_peak)
    inside = ((rows >= reach) & (cols >= reach) & (rows < field.shape[0] - reach)
              & (cols < field.shape[1] - reach))
    rows, cols = rows[inside], cols[inside]
    dy, dx = np.mgrid[-reach:reach + 1, -reach:reach + 1]
    distance = np.hypot(dy, dx) * mm_per_pixel
    rings = [(distance >= lo) & (distance < hi) for lo, hi in bands]
    sums, used = np.zeros(len(bands)), 0
    for row, col in zip(rows, cols):
        window = (slice(row - reach, row + reach + 1), slice(col - reach, col + reach + 1))
        if not good[window].all():
            continue
        signed = field[window] * np.sign(field[row, col])
        sums += [signed[ring].mean() for ring in rings]
        used += 1
    return used, sums / max(used, 1)


def large_scale_balance(field, good, radius, mm_per_pixel, sigmas=SMOOTHING, clip=CLIP):
    """Rms (G) within 0.7 R☉ of the clipped field smoothed by each Gaussian sigma (Mm), edges normalised."""
    from scipy import ndimage

    clipped = np.clip(field, -clip, clip) * good
    inside = good & (radius < 0.7)
    out = []
    for sigma in sigmas:
        weight = ndimage.gaussian_filter(good.astype(float), sigma / mm_per_pixel)
        smooth = ndimage.gaussian_filter(clipped, sigma / mm_per_pixel) / np.maximum(weight, 1e-3)
        out.append(float(np.std(smooth[inside])))
    return out


def main(argv=None):
    """Measure the real and simulated maps, write the table."""
    args = runs_parser(__doc__, seeds=(1, 2, 3)).parse_args(argv)

    import astropy.units as u
    from astropy.table import QTable

    import gongsynth
    from gongsynth.analysis.degrade import degrade_if_finer

    warnings.simplefilter("ignore", category=UserWarning)
    rows = []
    for instrument, date, kind, seed, smap in real_and_simulated_maps(args.seeds, args.cache):
        measured = disk_field(degrade_if_finer(smap)[0])
        row = {"instrument": instrument, "date": date, "kind": kind, "seed": seed}
        for lo, hi in PEAK_GROUPS:
            number, halo = polarity_halo(*measured, peaks=(lo, hi))
            row[f"peaks_{lo:.0f}_{hi:.0f}_G"] = number
            for (near, far), value in zip(HALO_BANDS, halo):
                row[f"halo_{lo:.0f}_{hi:.0f}_G_{near:.0f}_{far:.0f}_Mm"] = value * u.G
        for sigma, value in zip(SMOOTHING, large_scale_balance(*measured)):
            row[f"smooth_{sigma:.0f}_Mm"] = value * u.G
        rows.append(row)
    table = QTable(rows=rows)
    table.meta["description"] = ("polarity halo around network peaks (within 0.5 Rsun) and rms of the "
                                 f"±{CLIP:.0f} G clipped field smoothed (within 0.7 Rsun), real and "
                                 "simulated maps at GONG resolution; scripts/network_polarity_vs_real.py")
    table.meta["gongsynth_version"] = gongsynth.__version__
    args.table.parent.mkdir(parents=True, exist_ok=True)
    table.write(args.table, overwrite=True)
    for name in table.colnames[4:]:
        table[name].info.format = ".3g"
    table.pprint(max_lines=-1, max_width=-1)
    return table


if __name__ == "__main__":
    main()
