"""
What a coarser light costs a full-disk HMI magnetogram: supersampling 2 (HMI's) against 1.

The same 45-s full-disk run (seed 1, the real HMI map's date, the Milne-Eddington Sun, the central
``--shape``² pixels of 0.504″: all on the disk) is made with ``supersampling`` 2 and 1, each with
and without photon and read noise.  Printed for B_LOS and the Doppler velocity: the RMS and the
50/90/99/99.9th percentiles of |x| of the noise-free map (the signal), of its photon noise (noisy
minus noise-free, same supersampling) and of the difference between the two supersamplings
(noise-free), the difference's power over the noise's power in ten bins of spatial frequency
(0 to 0.5 cycles per pixel), the truths' difference, each run's error against its PSF-smoothed
truth and its flux ratio sum|B| / sum|B_true|, and each run's CPU time.

    python benchmarks/bench_hmi_supersampling.py [--shape 1024]
"""
import argparse
import gc
import time

import astropy.units as u
import numpy as np

import gongsynth
from gongsynth.config import Effects
from gongsynth.instruments.hmi import HMIInstrument


def run(shape, factor, noise):
    effects = Effects() if noise else Effects(photon_noise=False, read_noise=False)
    cpu = time.process_time()
    result = gongsynth.simulate(instrument=HMIInstrument().replace(supersampling=factor), mode="full-disk",
                                duration=0.75 * u.min, seed=1, detector_shape=shape,
                                obstime="2010-10-20T00:00", sun="milne-eddington", effects=effects,
                                progress=False)
    cpu = time.process_time() - cpu
    maps = {"B": result.magnetogram.data, "v": result.doppler.data, "truth": result.truth.data,
            "truth_psf": result.truth_psf.data}
    return {k: np.asarray(v, dtype=float) for k, v in maps.items()}, cpu


def stats(x):
    x = x[np.isfinite(x)]
    return f"rms {np.sqrt(np.mean(x ** 2)):8.2f}  |x| p50/90/99/99.9 " + " ".join(
        f"{p:7.2f}" for p in np.percentile(np.abs(x), [50, 90, 99, 99.9]))


def power(x, bins=10):
    x = np.nan_to_num(x - np.nanmean(x))
    spectrum = np.abs(np.fft.rfft2(x)) ** 2
    k = np.hypot(np.fft.fftfreq(x.shape[0])[:, None], np.fft.rfftfreq(x.shape[1])[None, :])
    which = np.digitize(k, np.linspace(0, 0.5, bins + 1))
    return np.array([spectrum[which == i].mean() for i in range(1, bins + 1)])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--shape", type=int, default=1024)
    args = parser.parse_args()
    runs = {}
    for factor in (2, 1):
        for noise in (False, True):
            runs[factor, noise], cpu = run(args.shape, factor, noise)
            print(f"supersampling {factor}, noise {noise}: {cpu:.1f} s CPU", flush=True)
            gc.collect()
    for q, unit in (("B", "G"), ("v", "m/s")):
        noise = runs[2, True][q] - runs[2, False][q]
        diff = runs[2, False][q] - runs[1, False][q]
        print(f"{q} ({unit}) signal        {stats(runs[2, False][q])}")
        print(f"{q} ({unit}) photon noise  {stats(noise)}")
        ratio = np.sqrt(np.nanmean(diff ** 2) / np.nanmean(noise ** 2))
        print(f"{q} ({unit}) ss2 - ss1     {stats(diff)}  ({ratio:.2f} x the noise's RMS)")
        print(f"{q} difference power / noise power, 0-0.5 cycles/pixel:",
              np.round(power(diff) / power(noise), 2))
    for name in ("truth", "truth_psf"):
        print(f"{name} (G) ss2 - ss1  {stats(runs[2, False][name] - runs[1, False][name])}")
    for factor in (2, 1):
        r = runs[factor, False]
        print(f"ss{factor}: B - truth_psf {stats(r['B'] - r['truth_psf'])}; "
              f"sum|B| / sum|B_true| {np.nansum(np.abs(r['B'])) / np.nansum(np.abs(r['truth'])):.4f}")


if __name__ == "__main__":
    main()
