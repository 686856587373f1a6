"""
Validation of the HMI instrument model, with timings.

Prints, for the default `HMIInstrument`:

1. each filtergram's peak position, FWHM and largest secondary lobes;
2. the Doppler velocity and B_LOS recovered on the reference line and on Zeeman
   triplets (g = 2.5) shifted by 0 and ±3 km/s, from 0 to 5 kG: linear range and
   the onset of saturation;
3. the photon noise of 45-s and 720-s magnetograms (analytic and Monte Carlo)
   next to Liu et al. (2012);
4. the wall time and peak memory of `reduce_hmi` on an N × N frame (``--size``;
   4096 is a full-disk HMI frame);

and, with ``--plot FILE``, draws the filter profiles with the reference line,
the magnetogram response curves and the look-up table.

Usage::

    python benchmarks/validate_hmi.py [--size 1024] [--plot hmi.png]
"""
import argparse
import resource
import time

import astropy.units as u
import numpy as np
from scipy.signal import argrelmax

from gongsynth.instruments.hmi import HMIInstrument
from gongsynth.instruments.hmi.filters import filter_quadrature, filtergram_weights, profile_width
from gongsynth.instruments.hmi.noise import LIU_2012_NOISE, magnetogram_noise
from gongsynth.instruments.hmi.observables import lookup_table, reduce_hmi
from gongsynth.instruments.hmi.profiles import gaussian_line, zeeman_shift, zeeman_triplet

MA = u.Unit("mAA")


def filters(hmi):
    offset, _, responses = filter_quadrature(hmi)
    print("filtergram  nominal   peak    FWHM   lobes (offset from peak: height / peak)")
    for k, nominal in enumerate(hmi.tuning_offsets.to_value(MA)):
        r = responses[k]
        peak, fwhm = profile_width(offset, r)
        lobes = sorted((i for i in argrelmax(r)[0] if abs(offset[i] - peak) > fwhm), key=lambda i: -r[i])
        text = ", ".join(f"{offset[i] - peak:+.0f}: {r[i] / r.max():.3f}" for i in lobes[:3])
        print(f"I{k}        {nominal:+7.1f} {peak:+8.2f} {fwhm:7.2f}   {text}")


def response(hmi, x, weights, v, b, gamma=0.0, depth=None, fwhm=None):
    depth = hmi.reference_line_depth.to_value(u.one) if depth is None else depth
    fwhm = hmi.reference_line_fwhm.to_value(MA) if fwhm is None else fwhm
    per_ma = hmi.velocity_per_wavelength.to_value(u.m / u.s / MA)
    split = zeeman_shift(np.asarray(b) * u.G, 2.5, hmi.line_wavelength).to_value(MA)
    planes = []
    for s in np.atleast_1d(split):
        i, vv = zeeman_triplet(x, v / per_ma, s, gamma, depth, fwhm)
        planes.append(np.concatenate([weights @ (i + vv), weights @ (i - vv)]))
    obs = reduce_hmi(np.array(planes).T, hmi)
    return obs.doppler.to_value(u.m / u.s), obs.magnetogram.to_value(u.G), obs.wrapped


def recovery(hmi, x, weights):
    fields = np.arange(0.0, 5001.0, 250.0)
    curves = {}
    print("\nv_in (m/s)  B_in (G): v_out, B_out (flag = outside the table)")
    for v in (-3000.0, 0.0, 3000.0):
        doppler, magnetogram, wrapped = response(hmi, x, weights, v, fields)
        curves[v] = magnetogram
        bad = np.abs(magnetogram - fields) > 1
        onset = fields[np.argmax(bad)] if bad.any() else np.inf
        error = np.abs(magnetogram - fields)[~bad].max()
        print(f"{v:+7.0f}  max |B err| below {onset:.0f} G: {error:.3f} G; first under-read at {onset:.0f} G")
        for b in (1000.0, 3000.0, 4000.0, 5000.0):
            j = np.searchsorted(fields, b)
            flag = " flag" if wrapped[j] else ""
            print(f"          {b:6.0f}: {doppler[j]:9.1f} {magnetogram[j]:8.1f}{flag}")
    print("\nanother line (depth 0.55, FWHM 110 mÅ), B = 1 kG: B_out / (B cos γ)")
    for gamma in (0, 30, 60):
        _, magnetogram, _ = response(hmi, x, weights, 0.0, 1000.0, np.radians(gamma), 0.55, 110.0)
        print(f"   γ = {gamma:2d}°: {magnetogram[0] / (1000 * np.cos(np.radians(gamma))):.4f}")
    return fields, curves


def noise(hmi):
    print("\nphoton noise of B_LOS at disk centre (G)   analytic  Monte Carlo   Liu et al. 2012")
    for product in ("45s", "720s"):
        analytic = magnetogram_noise(product, hmi)
        mc = magnetogram_noise(product, hmi, method="montecarlo", n_trials=20000, seed=1)
        print(f"  {product:>4}                                 {analytic.value:6.2f}    {mc.value:6.2f}"
              f"        {LIU_2012_NOISE[product].value:5.1f}")


def timing(hmi, size):
    rng = np.random.default_rng(0)
    planes = 1e4 * (1 + 0.01 * rng.standard_normal((12, size, size)))
    reduce_hmi(planes[:, :2, :2], hmi)
    start = time.perf_counter()
    reduce_hmi(planes, hmi)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024**2
    print(f"\nreduce_hmi on {size}²: {time.perf_counter() - start:.2f} s, peak RSS {peak:.2f} GiB")


def plot(hmi, path, fields, curves):
    import matplotlib.pyplot as plt

    offset, _, responses = filter_quadrature(hmi)
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    core = np.abs(offset) < 800
    for k in range(6):
        axes[0].plot(offset[core], responses[k, core], label=f"I{k}")
    line = gaussian_line(offset[core], hmi.reference_line_depth.value, hmi.reference_line_fwhm.to_value(MA))
    axes[0].plot(offset[core], line * responses.max(), "k--", label="reference line (scaled)")
    axes[0].set(xlabel="λ − λ0 (mÅ)", ylabel="transmission", title="HMI filtergrams")
    axes[0].legend(fontsize=7)
    for v, curve in curves.items():
        axes[1].plot(fields, curve, label=f"v = {v / 1000:+.0f} km/s")
    axes[1].plot(fields, fields, "k:", label="1:1")
    axes[1].set(xlabel="B_LOS in (G)", ylabel="HMI magnetogram (G)", title="Magnetogram response")
    axes[1].legend()
    table = lookup_table(hmi)
    axes[2].plot(table.velocity / 1000, (table.raw1 - table.velocity), label="raw v1 − v")
    axes[2].plot(table.velocity / 1000, (table.raw2 - table.velocity), label="raw v2 − v")
    axes[2].set(xlabel="input velocity (km/s)", ylabel="m/s", title="Look-up table")
    axes[2].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"\nfigure written to {path}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--size", type=int, default=1024, help="side of the frame to time")
    parser.add_argument("--plot", help="write a figure to this file")
    args = parser.parse_args()
    hmi = HMIInstrument()
    x = np.arange(-1200.0, 1200.01, 1.0)
    weights = filtergram_weights(hmi.line_wavelength + x * MA, hmi).to_value(MA)
    filters(hmi)
    fields, curves = recovery(hmi, x, weights)
    noise(hmi)
    timing(hmi, args.size)
    if args.plot:
        plot(hmi, args.plot, fields, curves)


if __name__ == "__main__":
    main()
