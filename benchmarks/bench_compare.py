"""
Benchmark of gongsynth.compare.degrade_to_gong on an HMI-like full-disk magnetogram.

A synthetic full-disk map (NaN sky, white noise plus a few bipoles) at HMI's
0.504″ sampling, stored rotated by 180° as HMI level-1.5 data are, is brought
to GONG's PSF and 2.5″ pixels.  The baseline, run in the same process on the
same (already upright) input, is the plain approach: full-size FFT convolution
(scipy.signal.fftconvolve) of the data and of the valid mask, then dense
area-weight matrices for the binning.  Prints wall times, the ratio and the
peak traced memory (tracemalloc: numpy buffers included).

Usage: python benchmarks/bench_compare.py [--size 4096] [--repeat 1]
"""
import argparse
import math
import time
import tracemalloc

import astropy.units as u
import numpy as np
import scipy.signal
import sunpy.map
from astropy.coordinates import SkyCoord
from sunpy.coordinates import frames

from gongsynth import GONGInstrument
from gongsynth.analysis.degrade import degrade_to_gong, overlap_operator
from gongsynth.analysis.statistics import disk_coordinates
from gongsynth.stages.optics import psf_kernel


def hmi_like(size, scale):
    """Upright data and a 180°-rotated HMI-like map of the same sky."""
    ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective, observer="earth",
                   obstime="2020-06-01")
    rng = np.random.default_rng(0)
    y, x = np.mgrid[:size, :size]
    c = (size - 1) / 2
    rsun = 945.0 / scale
    data = rng.normal(0, 8.0, (size, size))
    for _ in range(6):  # bipoles
        px, py = rng.uniform(0.3, 0.7, 2) * size
        data += 800 * (np.exp(-((x - px) ** 2 + (y - py) ** 2) / (2 * (8 / scale) ** 2))
                       - np.exp(-((x - px - 30 / scale) ** 2 + (y - py) ** 2) / (2 * (8 / scale) ** 2)))
    data[np.hypot(x - c, y - c) > rsun] = np.nan
    upright = sunpy.map.Map(data, sunpy.map.make_fitswcs_header(
        data, ref, scale=[scale, scale] * u.arcsec / u.pix, unit=u.G))
    rotated = sunpy.map.Map(data[::-1, ::-1].copy(), sunpy.map.make_fitswcs_header(
        data, ref, scale=[scale, scale] * u.arcsec / u.pix, unit=u.G, rotation_angle=180 * u.deg))
    return upright, rotated


def baseline(smap, kernel, plate):
    """Plain numpy/scipy: full FFT convolution of data and mask, dense area-weight binning."""
    data = np.asarray(smap.data, dtype=float)
    valid = np.isfinite(data)
    num = scipy.signal.fftconvolve(np.where(valid, data, 0.0), kernel, mode="same")
    den = scipy.signal.fftconvolve(valid.astype(float), kernel, mode="same")
    conv = np.where(valid & (den > 1e-6), num / np.where(den > 1e-6, den, 1), np.nan)
    scale = smap.scale.axis1.to_value(u.arcsec / u.pix)
    crpix = smap.reference_pixel
    wx = overlap_operator(data.shape[1], scale, crpix.x.value, plate)[0].toarray()
    wy = overlap_operator(data.shape[0], scale, crpix.y.value, plate)[0].toarray()
    ok = np.isfinite(conv)
    total = wy @ np.where(ok, conv, 0.0) @ wx.T
    cover = wy @ ok.astype(float) @ wx.T
    with np.errstate(invalid="ignore", divide="ignore"):
        out = total / cover
    out[~(cover >= 0.5)] = np.nan
    return out


def timed(fn, repeat):
    best = math.inf
    peak = 0
    for _ in range(repeat):
        tracemalloc.start()
        t0 = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - t0)
        peak = max(peak, tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    return result, best, peak


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--size", type=int, default=4096, help="map side in pixels (HMI: 4096)")
    parser.add_argument("--repeat", type=int, default=1)
    args = parser.parse_args()
    scale = 0.504 * 4096 / args.size
    upright, rotated = hmi_like(args.size, scale)
    inst = GONGInstrument()
    kernel = np.array(psf_kernel(scale * u.arcsec, inst))
    plate = inst.plate_scale.to_value(u.arcsec)
    print(f"input {args.size}x{args.size} at {scale:.3f} arcsec/pixel, PSF kernel {kernel.shape}")

    ours, t_ours, m_ours = timed(lambda: degrade_to_gong(upright, inst), args.repeat)
    rot, t_rot, m_rot = timed(lambda: degrade_to_gong(rotated, inst), args.repeat)
    base, t_base, m_base = timed(lambda: baseline(upright, kernel, plate), args.repeat)

    same = np.isfinite(base) & np.isfinite(ours.data)
    diff = np.max(np.abs(base[same] - ours.data[same]))
    # The rolled map is padded by the rotation: same sky grid, shifted by whole pixels.
    dx = int(round(rot.reference_pixel.x.value - ours.reference_pixel.x.value))
    dy = int(round(rot.reference_pixel.y.value - ours.reference_pixel.y.value))
    ny, nx = ours.data.shape
    inside = disk_coordinates(ours)[0] < 0.95  # sunpy's rotation grows the NaN sky by one pixel
    rot_diff = np.nanmax(np.abs(rot.data[dy:dy + ny, dx:dx + nx] - ours.data)[inside])
    print(f"degrade_to_gong (upright)      {t_ours:7.2f} s   peak {m_ours / 2**20:7.0f} MiB")
    print(f"degrade_to_gong (180° rolled)  {t_rot:7.2f} s   peak {m_rot / 2**20:7.0f} MiB")
    print(f"baseline fftconvolve + dense   {t_base:7.2f} s   peak {m_base / 2**20:7.0f} MiB")
    print(f"ratio baseline / degrade_to_gong: {t_base / t_ours:.2f}x time, {m_base / m_ours:.2f}x memory")
    print(f"output {ours.data.shape}; max |difference| to baseline {diff:.2e} G; "
          f"rolled vs upright (r < 0.95) {rot_diff:.2e} G")


if __name__ == "__main__":
    main()
