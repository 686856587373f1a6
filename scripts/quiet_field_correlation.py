"""
The correlation of the quiet Sun's large-scale field, measured on the ADAPT-GONG map of 2017-07-20.

Reads the ADAPT synchronic map in ``shared/data/real/gong`` (12 realizations
of B_r on a 1° latitude-longitude grid), keeps |latitude| < 30°, clips each
realization at 5 robust σ (1.4826 × MAD) about its median so that active
regions do not set the law, and measures the correlation of the clipped
field at lags of 0-20° along longitude and along latitude, averaged over the
realizations.  Then fits ``gongsynth.sun.surface_field.quiet``'s model, a
weighted sum of Gaussian correlations of fixed widths, by non-negative least
squares, and prints both beside the shipped `QUIET_CORRELATION`::

    python scripts/quiet_field_correlation.py

Takes a second.
"""
import os
from pathlib import Path

REAL = Path(os.environ.get("GONGSYNTH_REAL_DATA", Path(__file__).resolve().parents[2] / "shared" / "data"
                           / "real"))
ADAPT = REAL / "gong" / "adapt40311_03k012_201707200800_i00015600n1.fts.gz"
BAND = 30.0          # deg of latitude
CLIP = 5.0           # robust sigmas
LAGS = 21            # 0-20 deg
WIDTHS = (1.0, 3.0, 6.0, 12.0)   # correlation widths of the model's parts, deg


def measure(path=ADAPT):
    """Correlation of the clipped quiet band at 0..LAGS-1 degrees: (along longitude, along latitude)."""
    import numpy as np
    from astropy.io import fits

    with fits.open(path) as hdul:
        header, cube = hdul[0].header, hdul[0].data.astype(float)
    latitude = (np.arange(cube.shape[1]) + 1 - header["CRPIX2"]) * header["CDELT2"] + header["CRVAL2"]
    rows = np.nonzero(np.abs(latitude) < BAND)[0]
    along_lon, along_lat = np.zeros(LAGS), np.zeros(LAGS)
    for realization in cube:
        band = realization[rows]
        median = np.median(band)
        sigma = 1.4826 * np.median(np.abs(band - median))
        clipped = np.clip(realization, median - CLIP * sigma, median + CLIP * sigma)
        clipped -= clipped[rows].mean()
        variance = np.mean(clipped[rows] ** 2)
        for lag in range(LAGS):
            along_lon[lag] += np.mean(clipped[rows] * np.roll(clipped[rows], -lag, axis=1)) / variance
            along_lat[lag] += np.mean(clipped[rows] * clipped[rows + lag]) / variance
    return along_lon / len(cube), along_lat / len(cube)


def fit(correlation, widths=WIDTHS):
    """Non-negative weights of exp(-r²/2σ²) for each width σ, fitted to ``correlation`` at 0, 1, 2... deg."""
    import numpy as np
    from scipy.optimize import nnls

    lag = np.arange(len(correlation), dtype=float)
    design = np.stack([np.exp(-0.5 * (lag / w) ** 2) for w in widths], axis=1)
    weights, _ = nnls(design, correlation)
    return weights, float(np.max(np.abs(design @ weights - correlation)))


def main():
    """Measure, fit and print."""
    import numpy as np

    from gongsynth.sun.surface_field.quiet import QUIET_CORRELATION

    along_lon, along_lat = measure()
    mean = 0.5 * (along_lon + along_lat)
    print("lag (deg)       " + " ".join(f"{k:5d}" for k in range(LAGS)))
    rows = (("along longitude", along_lon), ("along latitude ", along_lat), ("mean           ", mean))
    for name, c in rows:
        print(name + " " + " ".join(f"{v:5.2f}" for v in c))
    weights, worst = fit(mean)
    print("fitted (width deg, weight):", [(w, round(float(a), 3)) for w, a in zip(WIDTHS, weights)],
          f"sum {weights.sum():.3f}, largest error {worst:.3f}")
    print("shipped QUIET_CORRELATION: ", list(QUIET_CORRELATION))
    shipped = sum(a * np.exp(-0.5 * (np.arange(LAGS) / w) ** 2) for w, a in QUIET_CORRELATION)
    print("shipped model   " + " ".join(f"{v:5.2f}" for v in shipped))


if __name__ == "__main__":
    main()
