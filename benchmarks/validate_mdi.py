"""
Validation of the SOHO/MDI instrument model, with timings.

Prints, for the default `MDIInstrument`:

1. each filtergram's peak position, FWHM and largest secondary lobes, next to
   the documented design (F1-F4 at ±37.8 and ±113.4 mÅ, Michelson FWHM 94 mÅ,
   Lyot FWHM 465 mÅ);
2. the Doppler velocity and B_LOS recovered on the reference line and on
   longitudinal Zeeman triplets (g = 1.5) shifted by 0 and ±3 km/s, from 0 to
   6 kG: linearity, the onset of saturation and what a saturated pixel reads;
   the response to other line widths and to the Sun's own Landé factor;
3. the photon noise of 1-minute and 5-minute (96-minute product) magnetograms
   (analytic and Monte Carlo, levels 1.5 and 1.8) next to the documented
   values and the quiet-Sun scatter of the real level-1.8 file in
   ``../shared/data/real/mdi``;
4. the wall time and peak memory of `reduce_mdi` on an N × N frame (``--size``;
   1024 is a full-disk MDI frame);

and, with ``--plot FILE``, draws the filter profiles with the reference line,
the magnetogram response curves and the look-up table.

Usage::

    python benchmarks/validate_mdi.py [--size 1024] [--plot mdi.png]
"""
import argparse
import resource
import time
from pathlib import Path

import astropy.units as u
import numpy as np
from scipy.signal import argrelmax

from gongsynth.instruments.hmi.filters import profile_width
from gongsynth.instruments.hmi.profiles import gaussian_line, zeeman_shift, zeeman_triplet
from gongsynth.instruments.mdi import MDIInstrument
from gongsynth.instruments.mdi.filters import filter_quadrature, lyot_narrowest_fsr, lyot_transmission
from gongsynth.instruments.mdi.noise import DOCUMENTED_NOISE, continuum_electrons, magnetogram_noise
from gongsynth.instruments.mdi.observables import lookup_table, reduce_mdi
from gongsynth.instruments.quadrature import channel_weights

MA = u.Unit("mAA")
REAL = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "real" / "mdi" / \
    "mdi.fd_m_96m_lev182.20101015_000000_TAI.data.fits"


def filters(mdi):
    offset, weights, responses = filter_quadrature(mdi)
    michelson = 0.5 * (1 + np.cos(2 * np.pi * offset / mdi.nb_fsr.to_value(MA)))
    core = np.abs(offset) < 100
    lyot = lyot_transmission(offset, lyot_narrowest_fsr(mdi).to_value(MA), mdi.lyot_elements)
    print(f"narrow Michelson alone: FWHM {profile_width(offset[core], michelson[core])[1]:.1f} mÅ "
          f"(documented 94 mÅ); Lyot: FWHM {profile_width(offset, lyot)[1]:.1f} mÅ (documented 465), "
          f"narrowest element FSR {lyot_narrowest_fsr(mdi).value:.0f} mÅ")
    print("filtergram  nominal    peak    FWHM   ∫R dλ   lobes (offset from peak: height / peak)")
    for k, nominal in enumerate(mdi.tuning_offsets.to_value(MA)):
        r = responses[k]
        near = np.abs(offset - nominal) < 150
        peak, fwhm = profile_width(offset[near], r[near])
        top = r[near].max()
        lobes = sorted((i for i in argrelmax(r)[0] if abs(offset[i] - peak) > fwhm), key=lambda i: -r[i])
        text = ", ".join(f"{offset[i] - peak:+.0f}: {r[i] / top:.3f}" for i in lobes[:3])
        print(f"F{k}         {nominal:+7.1f} {peak:+8.2f} {fwhm:7.2f} {r @ weights:7.2f}   {text}")


def response(mdi, x, weights, v, b, lande_g=1.5, depth=None, fwhm=None):
    depth = mdi.reference_line_depth.to_value(u.one) if depth is None else depth
    fwhm = mdi.reference_line_fwhm.to_value(MA) if fwhm is None else fwhm
    per_ma = mdi.velocity_per_wavelength.to_value(u.m / u.s / MA)
    split = zeeman_shift(np.asarray(b) * u.G, lande_g, mdi.line_wavelength).to_value(MA)
    planes = []
    for s in np.atleast_1d(split):
        i, vv = zeeman_triplet(x, v / per_ma, s, 0.0, depth, fwhm)
        planes.append(np.concatenate([weights @ (i + vv), weights @ (i - vv)]))
    obs = reduce_mdi(np.array(planes).T, mdi)
    return obs.doppler.to_value(u.m / u.s), obs.magnetogram.to_value(u.G), obs.wrapped


def recovery(mdi, x, weights):
    onboard = mdi.replace(level="1.5")
    table = lookup_table(mdi)
    print(f"\nlook-up table: α from {table.alpha[0]:.1f} to {table.alpha[-1]:.1f} over "
          f"{table.velocity[0]:+.0f} .. {table.velocity[-1]:+.0f} m/s (monotonic branch)")
    for v in (-3000.0, 0.0, 3000.0):
        doppler, b, _ = response(onboard, x, weights, v, 0.0)
        print(f"reference line at {v:+6.0f} m/s: Doppler {doppler[0]:+9.2f} m/s, B {b[0]:+.3f} G")
    fields = np.arange(0.0, 6001.0, 100.0)
    curves = {}
    print("\nlevel 1.5 (onboard), g = 1.5 triplets: B_out vs B_in (flag = outside the table)")
    for v in (-3000.0, 0.0, 3000.0):
        doppler, magnetogram, wrapped = response(onboard, x, weights, v, fields)
        curves[v] = magnetogram
        onset = fields[np.argmax(wrapped)] if wrapped.any() else np.inf
        error = np.abs(magnetogram - fields)[fields < onset].max()
        print(f"v = {v:+6.0f}: max |B_out − B_in| before saturation {error:.3f} G; saturates from "
              f"{onset:.0f} G (level 1.8: {onset * mdi.archive_factor:.0f} G)")
        for b in (1000.0, 2000.0, 3000.0, 4000.0, 5000.0, 6000.0):
            j = np.searchsorted(fields, b)
            flag = " flag" if wrapped[j] else ""
            print(f"        {b:6.0f} G: v {doppler[j]:+8.1f} m/s, B {magnetogram[j]:8.1f} G{flag}")
    ratio = response(mdi, x, weights, 0.0, 1000.0)[1][0] / response(onboard, x, weights, 0.0, 1000.0)[1][0]
    print(f"\nlevel 1.8 / level 1.5 at 1 kG: {ratio:.4f}")
    print("\nother lines, B = 300 G at rest, level 1.5: B_out / B_in")
    for depth, fwhm in ((0.6, 100.0), (0.6, 90.0), (0.6, 110.0), (0.67, 91.0), (0.45, 100.0)):
        b = response(onboard, x, weights, 0.0, 300.0, depth=depth, fwhm=fwhm)[1][0]
        print(f"   depth {depth:.2f}, FWHM {fwhm:5.1f} mÅ: {b / 300:.4f}")
    b = response(onboard, x, weights, 0.0, 300.0, lande_g=1.426)[1][0]
    print(f"   the Sun's Landé factor 1.426 against the reduction's 1.5: {b / 300:.4f} "
          f"(1.426 / 1.5 = {1.426 / 1.5:.4f})")
    return fields, curves


def real_noise():
    """Robust σ in the quietest 30-px (60″) box within 0.35 R☉ of disk centre of the real level-1.8 file."""
    if not REAL.exists():
        return None
    from astropy.io import fits
    with fits.open(REAL) as hdul:
        hdu = next(h for h in hdul if h.data is not None)
        data, header = hdu.data.astype(float), hdu.header
    radius = header["RSUN_OBS"] / header["CDELT1"]
    cy, cx = header["CRPIX2"] - 1, header["CRPIX1"] - 1
    best = None
    for dy in np.linspace(-0.35, 0.35, 7) * radius:
        for dx in np.linspace(-0.35, 0.35, 7) * radius:
            if dx**2 + dy**2 > (0.35 * radius) ** 2:
                continue
            y, x = int(cy + dy), int(cx + dx)
            box = data[y - 15:y + 15, x - 15:x + 15]
            robust = 1.4826 * np.nanmedian(np.abs(box - np.nanmedian(box)))
            best = robust if best is None else min(best, robust)
    return best


def noise(mdi):
    electrons = continuum_electrons(mdi).value
    print(f"\nphoton budget: {electrons[0]:.3g} e⁻ per continuum filtergram (SOI-TN-132: (3000/5.48)² = "
          f"{(3000 / 5.48) ** 2:.3g}); effective area {mdi.effective_area:.4f}")
    print("photon noise of B_LOS at disk centre (G)    analytic  Monte Carlo   documented")
    for minutes in (1, 5):
        for level in ("1.5", "1.8"):
            inst = mdi.replace(level=level)
            analytic = magnetogram_noise(minutes, inst)
            mc = magnetogram_noise(minutes, inst, method="montecarlo", n_trials=10000, seed=1)
            print(f"  {minutes}-min, level {level}                          {analytic.value:6.2f}    "
                  f"{mc.value:6.2f}       {DOCUMENTED_NOISE[minutes].value:5.1f}")
    real = real_noise()
    if real is not None:
        print(f"real level-1.8 96-min file (2010-10-15): robust σ in the quietest 60″ box {real:.1f} G "
              f"(photon noise and solar signal)")


def timing(mdi, size):
    rng = np.random.default_rng(0)
    planes = 6000 * (1 + 0.01 * rng.standard_normal((10, size, size)))
    reduce_mdi(planes[:, :2, :2], mdi)
    start = time.perf_counter()
    reduce_mdi(planes, mdi)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024**2
    print(f"\nreduce_mdi on {size}²: {time.perf_counter() - start:.2f} s, peak RSS {peak:.2f} GiB")


def plot(mdi, path, fields, curves):
    import matplotlib.pyplot as plt

    offset, _, responses = filter_quadrature(mdi)
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    core = np.abs(offset) < 700
    for k in range(5):
        axes[0].plot(offset[core], responses[k, core], label=f"F{k}")
    line = gaussian_line(offset[core], mdi.reference_line_depth.value, mdi.reference_line_fwhm.to_value(MA))
    axes[0].plot(offset[core], line * responses.max(), "k--", label="reference line (scaled)")
    axes[0].set(xlabel="λ − λ0 (mÅ)", ylabel="transmission", title="MDI filtergrams")
    axes[0].legend(fontsize=7)
    for v, curve in curves.items():
        axes[1].plot(fields, curve, label=f"v = {v / 1000:+.0f} km/s")
    axes[1].plot(fields, fields, "k:", label="1:1")
    axes[1].set(xlabel="B_LOS in (G)", ylabel="MDI magnetogram, level 1.5 (G)", title="Magnetogram response")
    axes[1].legend()
    table = lookup_table(mdi)
    axes[2].plot(table.velocity / 1000, np.arcsinh(table.alpha))
    axes[2].set(xlabel="velocity (km/s)", ylabel="asinh(α)", title="Look-up table (α → v)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"\nfigure written to {path}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--size", type=int, default=1024, help="side of the frame to time")
    parser.add_argument("--plot", help="write a figure to this file")
    args = parser.parse_args()
    mdi = MDIInstrument()
    x = np.arange(-1500.0, 1500.01, 1.0)
    weights = channel_weights(mdi.line_wavelength + x * MA, mdi).to_value(MA)
    filters(mdi)
    fields, curves = recovery(mdi, x, weights)
    noise(mdi)
    timing(mdi, args.size)
    if args.plot:
        plot(mdi, args.plot, fields, curves)


if __name__ == "__main__":
    main()
