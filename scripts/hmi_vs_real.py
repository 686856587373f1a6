"""
A simulated full-disk HMI 45-s magnetogram next to a real one: noise, histogram, power spectrum.

The real map is ``../shared/data/real/hmi/JSOC_hmi.m_45s.20101020_000000_TAI.2.magnetogram.fits``:
a 1024² JSOC ``im_patch`` cut-out (Postel projection centred on the disk centre, 0.0301
heliographic degrees ≈ 365 km per pixel; its WCS keywords are wrong, see PROVENANCE.md).  The
simulated one is gongsynth's full-disk HMI run at the same date (``--date 2010-10-20T00:00``;
``--like`` reads GONG files only), whose 0.504″ pixels are 364 km at disk centre that day: its
central 1024² pixels cover the same area of the Sun to 0.3 % (the tangent and Postel projections
differ by < 1 % within 260″ of the centre).  Both are compared on the same statistics:

- the noise of the quietest 100 × 100 box (its standard deviation, the robust sigma of its values
  and the pixel-difference estimate of `gongsynth.analysis.statistics`);
- the histogram of the field in 5 G bins over ±300 G;
- the azimuthally averaged power spectrum of the field (the whole 1024² box, Hann window),
  in G² per (cycle/Mm)², against wavenumber.

Writes ``hmi_vs_real.json`` (the numbers) and ``hmi_vs_real.png`` into ``--out``::

    python scripts/hmi_vs_real.py --simulated RUN_FOLDER --out OUT
    python scripts/hmi_vs_real.py --out OUT        # runs the simulation first (minutes)
"""
import argparse
import json
from pathlib import Path

import numpy as np

REAL = (Path(__file__).resolve().parents[2] / "shared" / "data" / "real" / "hmi"
        / "JSOC_hmi.m_45s.20101020_000000_TAI.2.magnetogram.fits")
DATE = "2010-10-20T00:00"
# The real cut-out's pixel: 0.0301 heliographic degrees of a 696 Mm Sun.
REAL_PIXEL_MM = np.radians(0.0301) * 696.0
BOX = 100
SIDE = 1024


def real_map():
    """The real HMI cut-out, in G."""
    from astropy.io import fits

    with fits.open(REAL) as hdul:
        return np.array(hdul[1].data, dtype=float)


def simulated_map(folder, seed):
    """The central 1024² pixels of a saved run's magnetogram (running one if no folder is given)."""
    import astropy.units as u
    from astropy.io import fits

    if folder is None:
        import gongsynth

        folder = Path("hmi_vs_real_run")
        gongsynth.simulate(instrument="hmi", mode="full-disk", duration=0.75 * u.min, seed=seed,
                           obstime=DATE, progress=False).save(folder, overwrite=True)
    with fits.open(Path(folder) / "magnetogram.fits") as hdul:
        hdu = next(h for h in hdul if h.data is not None)
        data, header = np.array(hdu.data, dtype=float), hdu.header
    cy, cx = (int(round(header["CRPIX2"] - 1 - header["CRVAL2"] / header["CDELT2"])),
              int(round(header["CRPIX1"] - 1 - header["CRVAL1"] / header["CDELT1"])))
    half = SIDE // 2
    pixel_mm = (header["CDELT1"] * u.arcsec).to_value(u.rad) * header.get("DSUN_OBS", 1.496e11) / 1e6
    return data[cy - half:cy + half, cx - half:cx + half], pixel_mm


def quiet_box(data):
    """The quietest BOX² box (smallest standard deviation) on a BOX/2 grid, and its noise numbers."""
    from gongsynth.analysis.statistics import pixel_difference_sigma, robust_sigma

    best = None
    for y in range(0, data.shape[0] - BOX + 1, BOX // 2):
        for x in range(0, data.shape[1] - BOX + 1, BOX // 2):
            box = data[y:y + BOX, x:x + BOX]
            if np.isfinite(box).all() and (best is None or box.std() < best[0]):
                best = (box.std(), y, x)
    _, y, x = best
    box = data[y:y + BOX, x:x + BOX]
    return {"box_origin": [y, x], "std_G": float(box.std()),
            "robust_sigma_G": float(robust_sigma(box.ravel())),
            "pixel_difference_G": float(pixel_difference_sigma(box))}


def power_spectrum(data, pixel_mm, bins=48):
    """Azimuthally averaged power (G² Mm²) against wavenumber (cycles per Mm) of a Hann-windowed map."""
    n = data.shape[0]
    window = np.outer(np.hanning(n), np.hanning(n))
    values = np.nan_to_num(data - np.nanmean(data)) * window
    power = np.abs(np.fft.fftshift(np.fft.fft2(values))) ** 2 / (window**2).sum() * pixel_mm**2
    k = np.fft.fftshift(np.fft.fftfreq(n, d=pixel_mm))
    kr = np.hypot(*np.meshgrid(k, k, indexing="ij"))
    edges = np.linspace(0, 0.5 / pixel_mm, bins + 1)
    which = np.digitize(kr.ravel(), edges) - 1
    keep = (which >= 0) & (which < bins)
    total = np.bincount(which[keep], power.ravel()[keep], bins)
    count = np.bincount(which[keep], minlength=bins)
    return 0.5 * (edges[1:] + edges[:-1]), total / np.maximum(count, 1)


def summary(data, pixel_mm):
    """The statistics of one map."""
    finite = data[np.isfinite(data)]
    k, p = power_spectrum(data, pixel_mm)
    hist, edges = np.histogram(finite, bins=np.arange(-300, 305, 5))
    return {"pixel_Mm": pixel_mm, "mean_G": float(finite.mean()), "std_G": float(finite.std()),
            "mean_abs_G": float(np.abs(finite).mean()),
            "p1_p99_G": [float(v) for v in np.percentile(finite, [1, 99])],
            "fraction_above_50G": float((np.abs(finite) > 50).mean()),
            "quiet_box": quiet_box(data), "power_k_per_Mm": k.tolist(), "power_G2_Mm2": p.tolist(),
            "histogram_edges_G": edges.tolist(), "histogram": hist.tolist()}


def figure(sim, real, numbers, path):
    """Both maps, their histograms and power spectra."""
    import matplotlib
    matplotlib.use("agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 4, figsize=(20, 5))
    for ax, data, name in ((axes[0], sim, "simulated HMI (gongsynth)"),
                           (axes[1], real, "real HMI 2010-10-20")):
        im = ax.imshow(data, origin="lower", cmap="gray", vmin=-100, vmax=100)
        ax.set_title(f"{name}: central 1024²")
        fig.colorbar(im, ax=ax, label="B_LOS [G]")
    for key, label in (("simulated", "simulated"), ("real", "real")):
        n = numbers[key]
        centres = 0.5 * (np.array(n["histogram_edges_G"][1:]) + np.array(n["histogram_edges_G"][:-1]))
        axes[2].semilogy(centres, np.array(n["histogram"]) / np.sum(n["histogram"]), label=label)
        axes[3].loglog(n["power_k_per_Mm"][1:], n["power_G2_Mm2"][1:], label=label)
    axes[2].set(xlabel="B_LOS [G]", ylabel="fraction per 5 G", title="histogram")
    axes[3].set(xlabel="k [cycles / Mm]", ylabel="power [G² Mm²]", title="azimuthal power spectrum")
    for ax in axes[2:]:
        ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=80)


def main():
    """Command line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--simulated", help="folder of a saved full-disk HMI run (default: run one)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--out", default=".")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    sim, pixel_mm = simulated_map(args.simulated, args.seed)
    real = real_map()
    numbers = {"simulated": summary(sim, pixel_mm), "real": summary(real, REAL_PIXEL_MM)}
    ratio = np.array(numbers["simulated"]["power_G2_Mm2"]) / np.array(numbers["real"]["power_G2_Mm2"])
    numbers["power_ratio_sim_over_real"] = ratio.tolist()
    (out / "hmi_vs_real.json").write_text(json.dumps(numbers, indent=1))
    figure(sim, real, numbers, out / "hmi_vs_real.png")
    for key in ("simulated", "real"):
        n = numbers[key]
        q = n["quiet_box"]
        print(f"{key:9s} pixel {n['pixel_Mm'] * 1000:.0f} km  mean {n['mean_G']:+.2f} G  "
              f"std {n['std_G']:.1f} G  "
              f"<|B|> {n['mean_abs_G']:.1f} G  p1/p99 {n['p1_p99_G'][0]:.1f}/{n['p1_p99_G'][1]:.1f} G  "
              f"|B|>50 G {100 * n['fraction_above_50G']:.2f} %  quiet box std {q['std_G']:.1f} G, "
              f"robust {q['robust_sigma_G']:.1f} G, pixel-difference {q['pixel_difference_G']:.1f} G")
    k = np.array(numbers["real"]["power_k_per_Mm"])
    for kk in (0.05, 0.2, 0.5, 1.0):
        i = int(np.argmin(np.abs(k - kk)))
        print(f"power ratio simulated/real at k = {k[i]:.2f} /Mm: {ratio[i]:.2f}")


if __name__ == "__main__":
    main()
