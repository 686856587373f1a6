"""
Benchmark: the tiled scene at 4096² through PSF and pixelization.

Run ``python benchmarks/bench_optics.py [--literal-wavelengths N] [--tile N]``.

1. Filter first (gongsynth): Stokes cube → 6 channel images → tiled scene on
   gongsynth's 4300² grid (``--grid 4096``: the paper's, with bilinear
   resampling to 4300²) → PSF and 5×5 binning (on 4300²: one band-limited
   Fourier operator, float32) → expected electrons.  Times each step; peak
   memory of the optics step by tracemalloc, and the process's max RSS.  Also
   the exact operator (every alias) and the B and v difference it makes, and
   the pipeline's path (the scene streamed into the optics, never whole).
2. Plain scipy baseline of the same optics: `scipy.signal.fftconvolve` per
   plane, `scipy.ndimage.zoom` (order 1) and a reshape-mean binning.
3. The paper's literal order on the same input: per wavelength and
   polarisation, Mueller → tile → PSF → pixelize, then the filter sum.  Its
   cost is the same for every wavelength, so by default ``N`` = 3 of the 51
   wavelengths are timed and the total is extrapolated (``--literal-wavelengths
   51`` runs all of them, ~10 minutes).
"""
import argparse
import os
import resource
import time
import tracemalloc

import astropy.units as u
import numpy as np
import scipy.ndimage
import scipy.signal

from gongsynth import GONGInstrument
from gongsynth.geometry import Pointing
from gongsynth.stages.channels import channel_images, polarized_spectra
from gongsynth.stages.filters import channel_weights
from gongsynth.stages.optics import expected_counts, image_scene, observe, photometric_factor, psf_kernel
from gongsynth.stages.reduction import reduce
from gongsynth.stages.scene.scene import radiance_at_earth
from gongsynth.stages.scene.tiled import tile, tiled_scenes
from gongsynth.sun.photosphere import model_photosphere, synthesize


def timed(label, func, *args, **kwargs):
    start, cpu = time.perf_counter(), time.process_time()
    out = func(*args, **kwargs)
    elapsed = time.perf_counter() - start
    print(f"  {label:<42s} {elapsed:8.2f} s wall {time.process_time() - cpu:8.2f} s CPU")
    return out, elapsed


def baseline_optics(data, pixel_scale, inst):
    """The same PSF + bilinear + binning with plain scipy calls, plane by plane."""
    kernel = psf_kernel(pixel_scale * u.arcsec, inst)
    factor = inst.supersampling
    n_det = round(data.shape[-1] * pixel_scale / inst.plate_scale.to_value(u.arcsec))
    out = np.empty((data.shape[0], n_det, n_det))
    for i, plane in enumerate(data):
        padded = np.pad(plane, kernel.shape[0] // 2, mode="symmetric")
        conv = scipy.signal.fftconvolve(padded, kernel, mode="valid")
        fine = scipy.ndimage.zoom(conv, n_det * factor / conv.shape[0], order=1, grid_mode=True,
                                  mode="nearest")
        out[i] = fine.reshape(n_det, factor, n_det, factor).mean(axis=(1, 3))
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--grid", type=int, default=4300,
                        help="supersampled grid side (default 4300: gongsynth's 5 samples per pixel, "
                             "where the optics run as one band-limited Fourier operator; the paper's "
                             "4096 runs the reference convolution + bilinear resampling)")
    parser.add_argument("--tile", type=int, default=256, help="photosphere side in columns")
    parser.add_argument("--literal-wavelengths", type=int, default=3,
                        help="wavelengths timed in the literal order (51 = all)")
    parser.add_argument("--workers", type=int, default=None, help="FFT threads")
    args = parser.parse_args()

    inst = GONGInstrument()
    latitude = 60 * u.deg
    mu, azimuth = np.cos(latitude), -90 * u.deg
    pixel = 98304 / args.tile * u.km  # the paper-sized 98 Mm box at any sampling
    print(f"load average before start: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print(f"input: {args.tile}² columns of {pixel:.0f}, latitude {latitude}, "
          f"scene {args.grid}² over {inst.detector_shape}² GONG pixels")
    photosphere = model_photosphere(shape=(args.tile, args.tile), pixel_size=pixel, seed=1)
    cube, _ = timed("synthesis (not part of the comparison)", synthesize, photosphere,
                    mu=float(mu), los_azimuth=azimuth, instrument=inst)

    print("filter first (gongsynth):")
    tracemalloc.start()
    planes, t_filter = timed("channel_images (Mueller + filter)", channel_images, cube, instrument=inst)
    kwargs = dict(pointing=Pointing(latitude), shape=args.grid, instrument=inst)

    def whole_scene():
        light, truth = tiled_scenes(planes, cube.blos, cube.pixel_size, **kwargs)
        _ = light.data  # a deferred scene made whole, as the baseline needs it
        return light, truth

    (light, truth), t_tile = timed("tiled_scenes (4 resolutions), made whole", whole_scene)
    _, peak_scene = tracemalloc.get_traced_memory()
    tracemalloc.reset_peak()
    before, _ = tracemalloc.get_traced_memory()
    counts, t_optics = timed("PSF + pixelization + photometry", expected_counts, light, inst,
                             workers=args.workers)
    _, peak_optics = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    fast_total = t_filter + t_tile + t_optics
    print(f"  {'total':<42s} {fast_total:8.2f} s")
    print(f"  peak traced memory: scene build {peak_scene / 2**30:.2f} GiB, "
          f"optics {(peak_optics - before) / 2**30:.2f} GiB above the "
          f"{before / 2**30:.2f} GiB scene held")
    exact, t_exact = timed("the same with every alias (ExactImager)", expected_counts, light, inst,
                           workers=args.workers, band_limited=False)
    got, ref = reduce(counts.value), reduce(exact.value)
    d_b = np.nanmax(np.abs(got.magnetogram - ref.magnetogram).to_value(u.G))
    d_v = np.nanmax(np.abs(got.doppler - ref.doppler).to_value(u.m / u.s))
    print(f"  band-limited vs every alias, noise-free B and v: max |dB| {d_b:.4f} G, max |dv| {d_v:.4f} m/s; "
          f"{t_exact / t_optics:.2f}x faster")
    streamed = tiled_scenes(planes, cube.blos, cube.pixel_size, **kwargs)
    (flow, _, _), t_flow = timed("pipeline path: tiling streamed into optics", image_scene, *streamed, inst,
                                 workers=args.workers)
    print(f"  (light and truth, with and without PSF; max difference from the whole scene's "
          f"{np.max(np.abs(flow.value - counts.value)) / counts.value.max():.1e} of the peak)")

    print("plain scipy baseline of the optics (fftconvolve, ndimage.zoom, reshape-mean):")
    base, t_base = timed("PSF + bilinear + binning", baseline_optics, light.data.value,
                         light.pixel_scale.to_value(u.arcsec), inst)
    base_counts = base * photometric_factor(inst).value
    rel = np.max(np.abs(base_counts - counts.value)) / counts.value.max()
    print(f"  max difference vs gongsynth: {rel:.1e} of the peak")
    print(f"RATIO baseline / gongsynth optics (same process): {t_base / t_optics:.2f}x")

    print(f"literal order (per wavelength; {args.literal_wavelengths} of {cube.shape[2]} timed):")
    weights = channel_weights(cube.wavelength, inst).to_value(u.cm)
    literal = np.zeros((6,) + counts.shape[1:])
    chosen = np.linspace(0, cube.shape[2] - 1, args.literal_wavelengths).round().astype(int)
    start = time.perf_counter()
    spectra = polarized_spectra(cube)  # Mueller for every wavelength (float64 (2, ny, nx, nλ))
    t_mueller = time.perf_counter() - start
    start = time.perf_counter()
    for j in chosen:
        sky = radiance_at_earth(tile(spectra[..., j], cube.pixel_size, **kwargs))
        seen = observe(sky, light.pixel_scale, instrument=inst, boundary=light.boundary,
                       workers=args.workers).value
        for p in range(2):
            literal[3 * p:3 * p + 3] += weights[:, j, None, None] * seen[p]
    per_wavelength = (time.perf_counter() - start) / chosen.size
    literal_total = t_mueller + per_wavelength * cube.shape[2]
    print(f"  {'per wavelength (2 polarisations)':<42s} {per_wavelength:8.2f} s")
    print(f"  {'total for all wavelengths':<42s} {literal_total:8.2f} s"
          f"{'' if chosen.size == cube.shape[2] else ' (extrapolated)'}")
    if chosen.size == cube.shape[2]:
        lit_counts = literal * photometric_factor(inst).value
        print(f"  max difference vs filter first: "
              f"{np.max(np.abs(lit_counts - counts.value)) / counts.value.max():.1e} of the peak")
    print(f"RATIO literal / filter-first (whole stage): {literal_total / fast_total:.1f}x")
    print(f"RATIO literal / filter-first (tiling + optics): "
          f"{per_wavelength * cube.shape[2] / (t_tile + t_optics):.1f}x "
          f"(the work ratio is 2 x {cube.shape[2]} planes / 6 planes = {2 * cube.shape[2] / 6:.0f}x)")
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
    print(f"max RSS of the process: {rss:.2f} GiB (includes the literal order's spectra)")
    print(f"disk-centre-like check: median counts plane 0 = {np.median(counts[0].value):.4g} e-/frame/pixel")


if __name__ == "__main__":
    main()
