"""
Validation: gongsynth.rt.synthesize against Lightweaver (LTE) over issue 13's whole matrix.

Atmospheres: FAL-C (``FALC_82.atmos``), HSRA (``hsra11.1d``, put in hydrostatic
equilibrium by `gongsynth.Atmosphere.from_1d`), FAL-C + 500 K and + 1000 K
(`~gongsynth.sun.photosphere.reference.heated_atmosphere`: same heights and gas
pressure, n_e and n_H from gongsynth's equation of state at the new T, given to
both codes).  μ = 1, 0.5, 0.25; B = 0, 100 G, 1 kG, 2 kG, vertical and inclined
45° (in the plane of the ray, towards the observer).  Both codes get the same
column (`~gongsynth.sun.photosphere.reference.lightweaver_state`), the same Ni I
atom (gongsynth's partition functions from the atom's levels) and S = B for the
scattering; ``--refine 1 4`` also repeats the matrix with every height interval
split in four for both codes, which separates the formal solvers'
discretisation from the physics.

Printed per case: max |ΔI| / I_c over the 51 wavelengths (each code normalised
to its own I_c at 676.73 nm), the relative difference of the V/I_c peaks (the
worse of the two lobes), max |ΔQ| / I_c (informative), and the absolute
continuum difference I_c(gongsynth) / I_c(Lightweaver) − 1.  The issue's
tolerances: 1 % of I_c in I, 5 % in the V peaks.

Run:  python benchmarks/validate_rt_lightweaver.py [--refine 1 4] [--mu 1 0.5 0.25]
"""
import argparse
import time
import warnings
from pathlib import Path

import astropy.units as u
import numpy as np

import gongsynth
from gongsynth.sun.photosphere.reference import (
    heated_atmosphere,
    lightweaver_partition_levels,
    lightweaver_stokes,
    refined_atmosphere,
)
from gongsynth.sun.rt import NiLineData, synthesize
from gongsynth.sun.rt.atomic_data import LANDE_LS

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
MODELS = DATA / "real" / "models"
FIELDS = (100.0, 1000.0, 2000.0)
INCLINATIONS = (0.0, 45.0)
LAM = np.linspace(676.73, 676.83, 51) * u.nm
TOL_I, TOL_V = 0.01, 0.05


def atmospheres():
    """The four models of the matrix, by name."""
    falc = gongsynth.Atmosphere.from_1d(MODELS / "FALC_82.atmos")
    return {"FAL-C": falc, "HSRA": gongsynth.Atmosphere.from_1d(MODELS / "hsra11.1d"),
            "FAL-C+500K": heated_atmosphere(falc, 500 * u.K),
            "FAL-C+1000K": heated_atmosphere(falc, 1000 * u.K)}


def with_field(atm, field, inclination_deg):
    """``atm`` with the uniform field (B sin γ, 0, B cos γ) that lightweaver_stokes models."""
    g = np.radians(inclination_deg)
    vec = np.array([field * np.sin(g), 0.0, field * np.cos(g)])
    return atm.replace(magnetic_field=vec[:, None, None, None] * np.ones((1, atm.shape[0], 1, 1)) * u.G)


def compare(ours, ref, k):
    """(max |ΔI|/I_c, V-peak relative difference, max |ΔQ|/I_c, I_c ratio − 1) of column k."""
    i = ours.I.value[0, 0].astype(float)
    ri = ref.I.to_value(ours.I.unit)[0, k].astype(float)
    d_i = np.abs(i / i[0] - ri / ri[0]).max()
    v = ours.V.value[0, 0] / i[0]
    rv = ref.V.to_value(ours.I.unit)[0, k] / ri[0]
    if np.abs(rv).max() > 0:
        d_v = max(abs(v.max() / rv.max() - 1.0), abs(v.min() / rv.min() - 1.0))
    else:
        d_v = float(np.abs(v).max())          # B = 0: both must be zero
    d_q = np.abs(ours.Q.value[0, 0] / i[0] - ref.Q.to_value(ours.I.unit)[0, k] / ri[0]).max()
    return d_i, d_v, d_q, i[0] / ri[0] - 1.0


def run_case(atm, mu, line):
    """Rows (B, γ, dI, dV, dQ, dIc) for one atmosphere and μ."""
    rows = []
    for gamma in INCLINATIONS:
        fields = ((0.0,) if gamma == 0 else ()) + FIELDS
        ref = lightweaver_stokes(atm, np.array(fields) * u.G, inclination=gamma * u.deg, mu=mu,
                                 wavelength=LAM)
        for k, b in enumerate(fields):
            ours = synthesize(with_field(atm, b, gamma), mu=mu, wavelength=LAM, progress=False, line=line)
            rows.append((b, gamma, *compare(ours, ref, k)))
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--refine", type=int, nargs="+", default=[1, 4],
                        help="height refinement factors to run (1 = the models' own grids)")
    parser.add_argument("--mu", type=float, nargs="+", default=[1.0, 0.5, 0.25])
    args = parser.parse_args()
    warnings.simplefilter("ignore")          # lightweaver's import and atom warnings
    line = NiLineData(lande_g=LANDE_LS, partition_levels=lightweaver_partition_levels())   # the atom's LS g
    models = atmospheres()
    print(f"{'atmosphere':12s} {'nz':>4s} {'mu':>4s} {'B/G':>5s} {'incl':>4s} {'max|dI|/Ic':>10s} "
          f"{'dVpeak':>7s} {'max|dQ|/Ic':>10s} {'dIc':>7s}")
    worst = {}
    t0 = time.perf_counter()
    for factor in args.refine:
        for name, base in models.items():
            atm = refined_atmosphere(base, factor) if factor > 1 else base
            for mu in args.mu:
                for b, gamma, d_i, d_v, d_q, d_c in run_case(atm, mu, line):
                    flag = " FAIL" if d_i > TOL_I or d_v > TOL_V else ""
                    print(f"{name:12s} {atm.shape[0]:4d} {mu:4.2f} {b:5.0f} {gamma:4.0f} {100 * d_i:9.2f}% "
                          f"{100 * d_v:6.2f}% {100 * d_q:9.2f}% {100 * d_c:+6.2f}%{flag}", flush=True)
                    w = worst.setdefault((factor, name), [0.0, 0.0, 0.0, np.inf, -np.inf])
                    w[:] = max(w[0], d_i), max(w[1], d_v), max(w[2], d_q), min(w[3], d_c), max(w[4], d_c)
    print(f"\nworst per atmosphere and grid ({time.perf_counter() - t0:.0f} s):")
    print(f"{'refine':>6s} {'atmosphere':12s} {'max|dI|/Ic':>10s} {'dVpeak':>7s} {'max|dQ|/Ic':>10s} "
          f"{'dIc range':>16s}")
    for (factor, name), (d_i, d_v, d_q, c_lo, c_hi) in worst.items():
        print(f"{factor:6d} {name:12s} {100 * d_i:9.2f}% {100 * d_v:6.2f}% {100 * d_q:9.2f}% "
              f"{100 * c_lo:+6.2f}..{100 * c_hi:+5.2f}%")


if __name__ == "__main__":
    main()
