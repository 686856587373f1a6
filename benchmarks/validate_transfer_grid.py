"""
GONG's channel integrals, v and B_LOS of the 3-D Sun on a thinned wavelength grid against the default one.

The thinned grid (`thinned_wavelength`) keeps 39 of the default 51
wavelengths: every point within ±26 pm of Ni I 676.8 nm (2 pm steps), every
other one beyond (4 pm steps, to ±50 pm).  This script synthesises the same
columns on both grids and on a converged one (0.5 pm over ±100 pm), times the
first two (the radiative transfer of the same columns, same process), and
prints, per set of columns,
the largest relative change of the six channel integrals, and of the
Doppler velocity and B_LOS (`gongsynth.instruments.gong.reduction.three_phase`,
noise-free) per column and over 16 × 16 columns:

- two strips of 16 rows of the 1024² × 96 km Sun of the papers' run (seed 1,
  GONG's default pointing): through the umbra's centre and through quiet
  granulation and network;
- a whole 64² × 96 km box (seed 1).

    python benchmarks/validate_transfer_grid.py            # ~3 minutes of CPU
    python benchmarks/validate_transfer_grid.py --quick    # the 64² box only
"""
import argparse
import os
import time

import astropy.units as u
import numpy as np

import gongsynth
from gongsynth import instruments
from gongsynth.config import SimulationConfig
from gongsynth.geometry import Pointing
from gongsynth.instruments.gong.reduction import three_phase
from gongsynth.seeding import child_sequence
from gongsynth.stages.channels import channel_images
from gongsynth.sun.model_atmosphere import DeferredTransfer, model_sun

GONG = instruments.get("gong")

#: Half width of the thinned grid's core, where every point of the default grid is kept (nm).
CORE_HALF_WIDTH = 0.026


def thinned_wavelength():
    """The default grid's points within ±`CORE_HALF_WIDTH` of the line and every other one beyond."""
    full = gongsynth.rt.default_wavelength()
    offset = np.abs(np.arange(full.size) - full.size // 2)
    core = int(round(CORE_HALF_WIDTH / (full[1] - full[0]).to_value(u.nm)))
    return full[(offset <= core) | ((offset - core) % 2 == 0)]


def grids():
    """{name: wavelengths} of the three grids."""
    lam0 = gongsynth.rt.default_wavelength()[25]
    return {"default (51)": gongsynth.rt.default_wavelength(), "thinned (39)": thinned_wavelength(),
            "converged (401)": lam0 + np.linspace(-0.1, 0.1, 401) * u.nm}


def planes(sun, rows, mu, azimuth, wavelength):
    """The six channel planes of some rows (with their halo, at the whole box's ray anchor)."""
    deferred = DeferredTransfer(sun, mu=mu, azimuth=azimuth, wavelength=wavelength)
    z_ref = deferred._reference_height()
    below, above = deferred._halo(z_ref)
    n = rows.stop - rows.start
    box = sun.rows(np.arange(rows.start - below, rows.stop + above)) if n < sun.shape[1] else sun.atmosphere()
    keep = slice(below, below + n) if n < sun.shape[1] else slice(None)
    cube = gongsynth.rt.synthesize(box, mu=mu, azimuth=azimuth, wavelength=wavelength, progress=False,
                                   anchor_height=z_ref * u.km)[keep]
    return channel_images(cube, instrument=GONG).value


def observables(ch, b=1):
    """(v m/s, B G) of channel planes, binned b × b first."""
    if b > 1:
        k, ny, nx = ch.shape
        ch = ch.reshape(k, ny // b, b, nx // b, b).mean(axis=(2, 4))
    obs = three_phase(ch, GONG)
    return obs.doppler.to_value(u.m / u.s), obs.magnetogram.to_value(u.G)


def compare(name, results):
    ref = results["default (51)"]
    v0, b0 = observables(ref)
    v16, b16 = observables(ref, 16)
    print(f"{name}: |B| up to {np.abs(b0).max():.0f} G; against the default grid")
    for grid, ch in results.items():
        if ch is ref:
            continue
        v, b = observables(ch)
        vb, bb = observables(ch, 16)
        rel = ch / ref - 1
        print(f"  {grid:16s} channels: max {np.abs(rel).max():.1e} rms {np.sqrt(np.mean(rel ** 2)):.1e} "
              f"relative | per column: v {np.abs(v - v0).max():.2f} m/s, B {np.abs(b - b0).max():.2f} G | "
              f"16 x 16 columns: v {np.abs(vb - v16).max():.2f} m/s, B {np.abs(bb - b16).max():.2f} G")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--quick", action="store_true", help="the 64² box only")
    args = parser.parse_args()
    print(f"gongsynth {gongsynth.__version__}; load average {os.getloadavg()[0]:.1f}")
    cases = [("64² x 96 km box, seed 1, disk centre", model_sun((64, 64), 96 * u.km, seed=1), slice(0, 64),
              1.0, 0 * u.deg)]
    if not args.quick:
        config = SimulationConfig(photosphere_shape=(1024, 1024), photosphere_pixel_size=96 * u.km, seed=1)
        pointing = Pointing(config.latitude, config.obstime)
        sun = model_sun(seed=child_sequence(1, "photosphere"), **config.sun_arguments())
        for what, start in (("umbra", 504), ("quiet Sun and network", 100)):
            cases.append((f"1024² x 96 km Sun (the papers' run), rows {start}-{start + 15}: {what}", sun,
                          slice(start, start + 16), pointing.mu, pointing.los_azimuth))
    for name, sun, rows, mu, azimuth in cases:
        results = {}
        for grid, wavelength in grids().items():
            cpu = time.process_time()
            results[grid] = planes(sun, rows, mu, azimuth, wavelength)
            print(f"  ({grid}: {time.process_time() - cpu:.1f} s CPU)")
        compare(name, results)


if __name__ == "__main__":
    main()
