"""
How sharp the real GONG image is: the limb's edge in the Big Bear intensity image against gongsynth's PSF.

The limb is the one sharp edge on a full-disk image: its true width is a
fraction of an arcsec, so the width of its image is the PSF's (its line-spread
function) and the pixel's.  This script measures the 80-20 % width of the edge
in the real intensity image of the Big Bear file of 2009-09-05 18:54 (the
10-minute average beside the magnetogram; the azimuthal median of the
intensity against the distance from the limb fit in its header, in 0.25-pixel
bins, normalised 6 pixels inside the limb), and the same width for a straight
limb of gongsynth's limb darkening at 677 nm (Neckel & Labs 1994,
`gongsynth.sun.photosphere.line.NECKEL_LABS_676`; the width depends on its
last few arcsec, where I(μ) falls to 0.35 of disk centre: the linear laws
0.4 + 0.6 μ and 0.25 + 0.75 μ give 2.32 and 2.69 px at 3.6″ seeing, against
2.56 px for Neckel & Labs') through gongsynth's GONG PSF
(`gongsynth.stages.psf.psf_kernel`, Airy pattern of the 2.8 cm aperture ⊗
seeing) and the 2.56″ pixel, for several seeing FWHMs, with the paper's
Gaussian seeing and with Kolmogorov's long-exposure seeing of the same FWHM
(the instrument's ``seeing_profile``)::

    python scripts/limb_edge_width.py

Seconds.
"""
import os
from pathlib import Path

import numpy as np

REAL = Path(os.environ.get("GONGSYNTH_REAL_DATA", Path(__file__).resolve().parents[2] / "shared" / "data"
                           / "real"))
INTENSITY = REAL / "gong" / "bbiqa090905t1854.fits.gz"
SEEING_FWHMS = (0.0, 2.0, 3.0, 3.6, 4.0, 4.5, 5.5)
PIXEL_ARCSEC, INSIDE_PX = 2.56, 6.0


def edge_width(offset_px, intensity):
    """80-20 % width (pixels) of an edge profile sampled at ``offset_px`` from the limb (outward)."""
    level = intensity / np.interp(-INSIDE_PX, offset_px, intensity)
    crossings = []
    for fraction in (0.8, 0.2):
        j = np.where((level[:-1] >= fraction) & (level[1:] < fraction))[0][-1]
        crossings.append(offset_px[j] + (level[j] - fraction) / (level[j] - level[j + 1])
                         * (offset_px[j + 1] - offset_px[j]))
    return crossings[1] - crossings[0]


def real_width():
    """The edge width of the real intensity image, about its header's limb fit."""
    import gongsynth

    image = gongsynth.load_observation(INTENSITY, kind="continuum")
    meta = image.meta
    radius = 0.5 * (meta["fndlmbmi"] + meta["fndlmbma"])
    yy, xx = np.indices(image.data.shape)
    offset = np.hypot(xx - (meta["fndlmbxc"] - 1), yy - (meta["fndlmbyc"] - 1)) - radius
    data = np.asarray(image.data, dtype=float)
    keep = (offset > -12) & (offset < 8) & np.isfinite(data)
    bins = np.arange(-12, 8.01, 0.25)
    which = np.digitize(offset[keep], bins)
    profile = np.array([np.median(data[keep][which == k]) for k in range(1, bins.size)])
    return edge_width(0.5 * (bins[1:] + bins[:-1]), profile)


def model_width(seeing_fwhm, step=0.1, profile="gaussian"):
    """The edge width of a straight limb through gongsynth's GONG PSF of that seeing and the pixel."""
    import astropy.units as u
    from scipy.ndimage import uniform_filter1d

    import gongsynth
    from gongsynth.stages.psf import psf_kernel
    from gongsynth.sun.photosphere.line import NECKEL_LABS_676

    gong = gongsynth.GONGInstrument(seeing_profile=profile)
    if seeing_fwhm > 0:
        gong = gong.replace(seeing_fwhm=seeing_fwhm * u.arcsec)
    line_spread = psf_kernel(step * u.arcsec, gong, shape=801, seeing=seeing_fwhm > 0).sum(axis=0)
    x = np.arange(-200, 100, step)                   # arcsec from the limb, outward
    mu = np.sqrt(np.clip(1 - (1 + x / 952.0) ** 2, 0, 1))
    limb = np.where(x < 0, np.polynomial.polynomial.polyval(mu, NECKEL_LABS_676), 0.0)
    seen = uniform_filter1d(np.convolve(limb, line_spread, mode="same"), int(round(PIXEL_ARCSEC / step)))
    return edge_width(x / PIXEL_ARCSEC, seen)


def main():
    """Print the real width and the model's for each seeing."""
    print(f"real Big Bear intensity image: 80-20 % limb width {real_width():.2f} px")
    for fwhm in SEEING_FWHMS:
        print(f"gongsynth PSF, seeing FWHM {fwhm:.1f}″: {model_width(fwhm):.2f} px Gaussian, "
              f"{model_width(fwhm, profile='kolmogorov'):.2f} px Kolmogorov")


if __name__ == "__main__":
    main()
