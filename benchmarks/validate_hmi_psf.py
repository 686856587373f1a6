"""
Validation of HMI's PSF (`gongsynth.instruments.hmi.psf`): encircled energy, scattered light off the limb.

1. The fraction of a point source's light beyond 1, 2, 5, 10, 20, 60 and 100″ of the Wachter et
   al. (2012) PSF, analytic (`encircled_energy`) and from the sampled kernel the optics use
   (0.252″ samples, truncated at the instrument's ``psf_radius`` and normalised).
2. The limb of a full-disk continuum: a limb-darkened disk (Neckel & Labs 1994 at 617.3 nm,
   R = 960″) at the scene's 0.252″ samples through the optics stage (`gongsynth.stages.optics.observe`,
   HMI's PSF, 0.504″ pixels) on a 512″ strip across the west limb, against the same disk convolved
   with the PSF's line-spread function computed independently (the profile integrated along the
   limb, then along the ray): the scattered light outside the limb at 1, 2, 5, 10, 20 and 40″,
   relative to the disk centre.

    python benchmarks/validate_hmi_psf.py
"""
import astropy.units as u
import numpy as np
import scipy.integrate

from gongsynth import instruments
from gongsynth.instruments.hmi.psf import encircled_energy, psf_profile
from gongsynth.stages.optics import observe, psf_kernel
from gongsynth.sun.photosphere.line import NECKEL_LABS_617

RADIUS = 960.0      # arcsec
OFF_LIMB = (1.0, 2.0, 5.0, 10.0, 20.0, 40.0)


def limb_darkened(r):
    mu = np.sqrt(np.clip(1 - (r / RADIUS) ** 2, 0, 1))
    return np.where(r < RADIUS, np.polynomial.polynomial.polyval(mu, NECKEL_LABS_617), 0.0)


def line_spread(inst, truncation):
    """LSF(x) = ∫ PSF(√(x² + y²)) dy within the truncation radius, normalised to unit integral."""
    x = np.arange(0, truncation + 0.05, 0.05)
    lsf = np.array([2 * scipy.integrate.quad(lambda y, a=a: psf_profile(np.hypot(a, y), inst), 0,
                                             np.sqrt(max(truncation**2 - a * a, 0)), limit=400)[0]
                    for a in x])
    total = 2 * np.trapezoid(lsf, x)
    return x, lsf / total


def main():
    hmi = instruments.get("hmi")
    scale = hmi.plate_scale.to_value(u.arcsec) / hmi.supersampling
    kernel = psf_kernel(scale * u.arcsec, hmi)
    half = kernel.shape[0] // 2
    yy, xx = np.indices(kernel.shape) - half
    r = np.hypot(yy, xx) * scale
    print(f"HMI PSF (Wachter et al. 2012), kernel {kernel.shape[0]}² of {scale}″ "
          f"(psf_radius {hmi.psf_radius})")
    print("  radius   beyond (analytic)   beyond (sampled kernel)")
    for radius in (1, 2, 5, 10, 20, 60, 100):
        beyond = 1 - encircled_energy(radius, hmi)
        print(f"  {radius:5.0f}″   {beyond:8.4f}            {kernel[r > radius].sum():8.4f}")

    # A strip across the west limb: 1024 x 2048 samples (258″ by 516″), the limb at 3/4 of the width.
    ny, nx = 1024, 2048
    x = RADIUS - 0.75 * nx * scale + (np.arange(nx) + 0.5) * scale
    y = (np.arange(ny) - ny / 2 + 0.5) * scale
    disk = limb_darkened(np.hypot(x[None, :], y[:, None]))
    observed = observe(disk, scale * u.arcsec, instrument=hmi, boundary="zero")
    centre_row = observed[observed.shape[0] // 2]
    pixel_x = x.reshape(-1, hmi.supersampling).mean(axis=1)
    # The independent prediction along the central row: the disk's radial profile (locally a straight
    # limb) convolved with the line-spread function of the truncated PSF.
    truncation = hmi.psf_radius.to_value(u.arcsec)
    lx, lsf = line_spread(hmi, truncation)
    xs = np.arange(RADIUS - 300, RADIUS + 60, 0.05)
    profile = limb_darkened(xs)
    print("\n  off limb   simulated (optics)   predicted (LSF)   [fraction of the disk-centre intensity]")
    for d in OFF_LIMB:
        i = int(np.argmin(np.abs(pixel_x - (RADIUS + d))))
        at = pixel_x[i]
        pred = np.trapezoid(profile * np.interp(np.abs(at - xs), lx, lsf, right=0.0), xs)
        print(f"  {at - RADIUS:6.2f}″       {centre_row[i]:.5f}            {pred:.5f}")


if __name__ == "__main__":
    main()
