"""
How much small-scale horizontal field survives GONG's resolution: the MURaM snapshot against the model Sun.

A horizontal field seen at an inclined view adds to the line-of-sight signal
by B_h sin θ; what a 5″ resolution element keeps of it is its large-scale
(k → 0) part.  For a random field whose correlation is much shorter than the
smoothing, a Gaussian smoothing of width σ keeps the fraction
f = √(A_eq / 4πσ²) of its rms, where A_eq = ∫ C(r) / C(0) d²r is the field's
equivalent white area (a field of independent patches of area A_eq).  This
script measures, on horizontal planes above the mean τ₅₀₀ = 1:

- in the real MURaM snapshot of ``shared/data/mhd`` (Apache-2.0, 96 km
  columns, 6.1 Mm periodic box: an independent MHD code's field), and
- in the builder's internetwork field (`gongsynth.model_atmosphere`, a box of
  the same size and spacing, no flux elements, seeds 1-4),

the rms of B_z and of each horizontal component, the fraction f kept by
periodic Gaussian smoothings of σ = 0.35 and 0.7 Mm (the box holds no larger),
A_eq from the 0.7 Mm fraction, and from it the line-of-sight rms that
GONG's resolution element (5″ FWHM, σ = 1.54 Mm at disk centre) would keep
at sin θ = 0.7, B_comp sin θ √(A_eq / 4πσ_G²) (for the model's field, whose
large scales fall faster than white, an upper bound)::

    python scripts/horizontal_field_muram.py --table docs/guide/horizontal_field_muram.ecsv

Seconds.
"""
import argparse
import os
from pathlib import Path

import numpy as np
from scipy.ndimage import gaussian_filter

MHD = Path(os.environ.get("GONGSYNTH_REAL_DATA", Path(__file__).resolve().parents[2] / "shared" / "data"
                          / "real")).parent / "mhd" / "muram-test3d-it000000"
HEIGHTS_KM = (0.0, 100.0, 200.0, 300.0)
SMOOTHINGS_MM = (0.35, 0.7)
#: GONG's resolution element: 5″ FWHM (paper I) at 725 km per arcsec.
GONG_SIGMA_MM = 5.0 * 0.725 / 2.3548
SIN_THETA = 0.7


def kept_fraction(plane, sigma_px):
    """The rms fraction of a periodic plane's fluctuation that a Gaussian smoothing of σ pixels keeps."""
    fluct = plane - plane.mean()
    return float(gaussian_filter(fluct, sigma_px, mode="wrap").std() / (fluct.std() or 1.0))


def plane_rows(label, z_km, bz, bx, by, pixel_mm):
    """One row per height: rms, kept fractions, A_eq and the line-of-sight rms at GONG's resolution."""
    rows = []
    for height in HEIGHTS_KM:
        k = int(np.argmin(np.abs(z_km - height)))
        planes = bz[k], bx[k], by[k]
        comp = float(np.sqrt(0.5 * (planes[1].var() + planes[2].var())))
        fractions = [float(np.sqrt(0.5 * (kept_fraction(planes[1], s / pixel_mm) ** 2
                                          + kept_fraction(planes[2], s / pixel_mm) ** 2)))
                     for s in SMOOTHINGS_MM]
        area = 4 * np.pi * SMOOTHINGS_MM[-1] ** 2 * fractions[-1] ** 2
        los = comp * SIN_THETA * np.sqrt(area / (4 * np.pi * GONG_SIGMA_MM ** 2))
        rows.append((label, float(z_km[k]), float(planes[0].std()), comp, *fractions, area, los))
    return rows


def muram_rows():
    """The MURaM snapshot, heights from the box's mean τ₅₀₀ = 1 plane."""
    import gongsynth

    atm = gongsynth.Atmosphere.from_muram(MHD)
    z = atm.z.to_value("km")
    tau = np.fromfile(MHD / "tau.000000", "<f4")
    nx, ny, nz = np.loadtxt(MHD / "Header.000000")[:3].astype(int)
    log_tau = np.log10(tau.reshape(nz, ny, nx).transpose(2, 1, 0)).mean(axis=(1, 2))
    z0 = float(np.interp(0.0, log_tau[::-1], z[::-1]))
    b = atm.raw("magnetic_field")
    return plane_rows("MURaM", z - z0, b[2], b[0], b[1], atm.pixel_size.to_value("Mm"))


def model_rows(seed):
    """The builder's internetwork on a box like MURaM's (no elements, no network, no spot)."""
    import astropy.units as u

    import gongsynth

    atm = gongsynth.model_atmosphere((64, 64), 96 * u.km, seed=seed, element_flux_density=0 * u.G,
                                     spot=False, network=False)
    b = atm.raw("magnetic_field")
    return plane_rows(f"model seed {seed}", atm.z.to_value("km"), b[2], b[0], b[1], 0.096)


def main(argv=None):
    """Print the table and, with ``--table``, write it."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--table", type=Path, help="ECSV file to write")
    args = parser.parse_args(argv)
    rows = muram_rows() + sum((model_rows(seed) for seed in (1, 2, 3, 4)), [])
    print(f"{'field':>13} {'z km':>6} {'Bz rms':>7} {'Bh comp':>8} "
          + " ".join(f"f({s} Mm)" for s in SMOOTHINGS_MM)
          + f" {'A_eq Mm2':>9} {'LOS G at GONG, sin 0.7':>23}")
    for label, z, bz, comp, f1, f2, area, los in rows:
        print(f"{label:>13} {z:6.0f} {bz:7.1f} {comp:8.1f} {f1:9.3f} {f2:8.3f} {area:9.3f} {los:23.2f}")
    if args.table:
        import astropy.units as u
        from astropy.table import QTable

        names = ["field", "height", "bz_rms", "bh_component_rms"] + [f"kept_{s}_Mm" for s in SMOOTHINGS_MM] \
            + ["white_area", "los_rms_at_gong"]
        table = QTable(rows=rows, names=names)
        for name, unit in (("height", u.km), ("bz_rms", u.G), ("bh_component_rms", u.G),
                           ("white_area", u.Mm ** 2), ("los_rms_at_gong", u.G)):
            table[name].unit = unit
        table.meta["comments"] = [f"Horizontal field kept at GONG's resolution (sigma {GONG_SIGMA_MM:.2f} "
                                  f"Mm, sin theta {SIN_THETA}): MURaM snapshot vs model. "
                                  "scripts/horizontal_field_muram.py"]
        table.write(args.table, overwrite=True)


if __name__ == "__main__":
    main()
