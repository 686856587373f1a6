"""
The 3-D Sun's supergranular network (``network=True``) measured against the observations it cites.

On the default run box (256² columns × 384 km = 98 Mm, no sunspot: the quiet
Sun), for each seed: the unsigned flux density at τ = 1 of the kG elements
(network and ephemeral regions, B_z on the elements' own τ = 1 plane) and of
the internetwork (B_z at z = 0), the part of the element flux within 3 Mm
(2 lane sigmas) of a cell wall and the area that zone covers, the power-law
index of the element fluxes (patches of |B_z| > 100 G of one sign; maximum
likelihood above 1e18 Mx; Parnell et al. 2009: 1.85), and the cell size from
the pattern: the wavelength of the peak of k·P(k) of |B_z| smoothed over
2 Mm and the lag of the secondary maximum of its autocorrelation.
Writes ``network_statistics.ecsv`` (the guide's table:
``--seeds 1 2 3 4 --out docs/guide``).  The guide's figure is the quick-look
of ``gongsynth simulate --config net.toml --out DIR`` with ``[photosphere]
network = true`` and seed 1, reduced to 40 % in size.

Usage: ``nice -n 5 python scripts/network_statistics.py [--seeds 1 2] [--out DIR]``
"""
import argparse
import math
from pathlib import Path

import astropy.units as u
import numpy as np
from astropy.table import QTable
from scipy import ndimage

from gongsynth.sun.model_atmosphere import model_sun
from gongsynth.sun.model_atmosphere.network_layout import LANE_WIDTH_KM


def radial_profile(field, grid):
    """Azimuthal mean of a (ny, nx) periodic array about [0, 0] in integer-pixel rings."""
    iy = np.fft.fftfreq(grid.ny) * grid.ny
    ix = np.fft.fftfreq(grid.nx) * grid.nx
    r = np.rint(np.hypot(iy[:, None], ix[None, :])).astype(int)
    n = min(grid.ny, grid.nx) // 2
    total = np.bincount(r.ravel(), field.ravel(), n + 1)[: n + 1]
    return total / np.bincount(r.ravel(), None, n + 1)[: n + 1]


def cell_scales(b_abs, grid):
    """Peak wavelength of k P(k) and the secondary-maximum lag of the autocorrelation (km)."""
    s = grid.smooth(b_abs, 2000.0)
    s = s - s.mean()
    power = np.abs(np.fft.fft2(s)) ** 2
    p_k = radial_profile(power, grid)
    k = np.arange(p_k.size)
    peak = 1 + int(np.argmax((k * p_k)[1:]))
    acf = radial_profile(np.real(np.fft.ifft2(power)), grid)
    acf /= acf[0]
    first_min = int(np.argmax(np.diff(acf) > 0))            # where the ACF stops falling
    second_max = first_min + int(np.argmax(acf[first_min:]))
    return grid.Lx / peak, second_max * grid.dx


def element_index(bz, grid, threshold=100.0, lo=1e18):
    """Maximum-likelihood power-law index of the fluxes of one-sign patches above ``threshold``."""
    area = (grid.dx * 1e5) ** 2
    fluxes = []
    for sign in (1, -1):
        labels, n = ndimage.label(sign * bz > threshold)
        fluxes.append(np.abs(ndimage.sum(bz, labels, np.arange(1, n + 1))) * area)
    f = np.concatenate(fluxes)
    f = f[f >= lo]
    return 1 + f.size / np.sum(np.log(f / lo)), f.size


def measure(seed):
    """One seed's row of the table."""
    sun = model_sun((256, 256), 384 * u.km, seed=seed, spot=False, network=True)
    plan = sun._plan                                          # the whole-plane ingredients
    grid = plan["grid"]
    bz_el = grid.ifft(plan["spectra"][0])
    bz_in = plan["internetwork"][4]                          # curl A at z = 0: the internetwork's B_z
    near = plan["network_wall"] < 2 * LANE_WIDTH_KM
    index, n_patches = element_index(bz_el, grid)
    spectrum_peak, acf_peak = cell_scales(np.abs(bz_el + bz_in), grid)
    return dict(seed=seed, cells=plan["meta"]["network"]["cells"],
                cell_spacing=math.sqrt(grid.Lx * grid.Ly / plan["meta"]["network"]["cells"]) / 1e3 * u.Mm,
                element_flux_density=np.abs(bz_el).mean() * u.G,
                internetwork_flux_density=np.abs(bz_in).mean() * u.G,
                total_flux_density=np.abs(bz_el + bz_in).mean() * u.G,
                imbalance=bz_el.sum() / np.abs(bz_el).sum(),
                flux_near_walls=np.abs(bz_el)[near].sum() / np.abs(bz_el).sum(),
                area_near_walls=near.mean(),
                ephemeral_regions=plan["meta"]["network"]["ephemeral_regions"],
                element_index=index, patches=n_patches,
                spectrum_peak=spectrum_peak / 1e3 * u.Mm, acf_peak=acf_peak / 1e3 * u.Mm)


def main(argv=None):
    """Measure, write the ECSV."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--out", type=Path, default=Path("."))
    args = parser.parse_args(argv)
    table = QTable(rows=[measure(s) for s in args.seeds])
    table.meta["comments"] = ["3-D Sun with network=True, 256^2 x 384 km, no spot",
                              "made by scripts/network_statistics.py"]
    table.write(args.out / "network_statistics.ecsv", overwrite=True)
    print(table)


if __name__ == "__main__":
    main()
