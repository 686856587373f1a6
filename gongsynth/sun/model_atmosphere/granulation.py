r"""
Horizontal patterns on the periodic grid: the granulation, its flow, and Fourier helpers.

The granulation is a Voronoi tessellation of random granule centres (mean
spacing ~1.2-1.4 Mm; Bahng & Schwarzschild 1961, Hirzberger et al. 1997):
flat-topped bright cell interiors that drop steeply into narrow lanes, rounded
by a smoothing of 7 % of the spacing.  Two fields come out of it:

- ``a``, the *thermal* weight used to interpolate between the granule and
  intergranule models (a = +1 on average over the granules — where a > 0 —
  and −1 on average over the lanes, the definition of a two-component model);
- ``V``, the vertical velocity pattern at τ = 1 (zero mean, unit RMS), with
  the asymmetry of real convection: broad slow upflows, narrow fast downflows
  (a log-normal transform puts ~60 % of the area in upflows).

The flow is anelastic, ∇·(ρ̄ v) = 0 with the mean density ρ̄(z): with
v_z = V(x, y) h(z) and v_h = s(z) ∇φ, ∇²φ = V, continuity fixes
s = −(ρ̄ h)'/ρ̄ (`anelastic_profile`), so granules flow out of their
centres and the outflow weakens with height as h does.
"""
from __future__ import annotations

import math

import numpy as np
import scipy.fft
from scipy.spatial import cKDTree

__all__ = ["PeriodicGrid", "granulation_pattern", "anelastic_profile"]


class PeriodicGrid:
    """
    A periodic (ny, nx) grid of spacing ``dx`` km with Fourier helpers.

    Parameters
    ----------
    ny, nx : int
    dx : float
        km.

    Examples
    --------
    >>> g = PeriodicGrid(8, 16, 96.0)
    >>> g.Lx, g.k.shape
    (1536.0, (8, 9))
    """

    def __init__(self, ny, nx, dx):
        self.ny, self.nx, self.dx = int(ny), int(nx), float(dx)
        self.Ly, self.Lx = self.ny * self.dx, self.nx * self.dx
        self.ky = (2 * math.pi * np.fft.fftfreq(self.ny, d=self.dx))[:, None]      # rad/km
        self.kx = (2 * math.pi * np.fft.rfftfreq(self.nx, d=self.dx))[None, :]
        self.k = np.sqrt(self.kx ** 2 + self.ky ** 2)

    def fft(self, field):
        """rfft2 (threaded)."""
        return scipy.fft.rfft2(field, workers=-1)

    def ifft(self, spectrum, dtype=np.float64):
        """irfft2 back to the grid (threaded)."""
        return scipy.fft.irfft2(spectrum, s=(self.ny, self.nx), workers=-1).astype(dtype, copy=False)

    def coords(self):
        """Cell-centre coordinates (y column, x row), km."""
        y = (np.arange(self.ny) + 0.5) * self.dx
        x = (np.arange(self.nx) + 0.5) * self.dx
        return y[:, None], x[None, :]

    def offset(self, xc, yc):
        """Minimum-image offsets x − xc, y − yc (km)."""
        y, x = self.coords()
        return (x - xc + self.Lx / 2) % self.Lx - self.Lx / 2, (y - yc + self.Ly / 2) % self.Ly - self.Ly / 2

    def smooth(self, field, sigma_km):
        """Periodic Gaussian smoothing (flux-conserving)."""
        return self.ifft(self.fft(field) * np.exp(-0.5 * sigma_km ** 2 * self.k ** 2))

    def high_pass(self, field, wavelength_km):
        """The field without its scales beyond ``wavelength_km``: spectrum × (1 − exp(−(k λ / 2π)²))."""
        x = (self.k * wavelength_km / (2 * math.pi)) ** 2
        return self.ifft(self.fft(field) * -np.expm1(-x))

    def gradient(self, field):
        """(∂/∂x, ∂/∂y) per km, spectrally."""
        f = self.fft(field)
        return self.ifft(1j * self.kx * f), self.ifft(1j * self.ky * f)

    def inverse_laplacian(self, field):
        """φ with ∇²φ = field − mean(field) (periodic, zero-mean φ)."""
        f = self.fft(field)
        k2 = self.k ** 2
        k2[0, 0] = 1.0
        f = -f / k2
        f[0, 0] = 0.0
        return self.ifft(f)

    def noise(self, rng, sigma_km, band=False):
        """Zero-mean unit-variance Gaussian random field, correlation ~σ (band-pass: no large scales)."""
        f = self.fft(rng.standard_normal((self.ny, self.nx)))
        x = 0.5 * sigma_km ** 2 * self.k ** 2
        f *= np.exp(-x) * (x if band else 1.0)
        g = self.ifft(f)
        g -= g.mean()
        return g / (g.std() or 1.0)


def _standardise(a):
    a = a - a.mean()
    return a / (a.std() or 1.0)


def granulation_pattern(grid, rng, granule_size):
    """
    Thermal weight, vertical-velocity pattern and lane indicator of a seeded granulation.

    Parameters
    ----------
    grid : `PeriodicGrid`
    rng : `numpy.random.Generator`
    granule_size : float
        Mean spacing of granule centres (km).

    Returns
    -------
    a : `numpy.ndarray`
        Thermal weight (mean +1 over a > 0, −1 over a < 0).
    v : `numpy.ndarray`
        Vertical velocity pattern (zero mean, unit RMS, positive up in granules).
    lanes : `numpy.ndarray`
        1 in the lanes, → 0 in granule centres.

    Examples
    --------
    >>> g = PeriodicGrid(64, 64, 96.0)
    >>> a, v, lanes = granulation_pattern(g, np.random.default_rng(1), 1300.0)
    >>> round(float(a[a > 0].mean()), 6), round(float(v.std()), 6)
    (1.0, 1.0)
    """
    n = max(3, int(rng.poisson(grid.Lx * grid.Ly / granule_size ** 2)))
    seeds = np.column_stack([rng.uniform(0, grid.Lx, n), rng.uniform(0, grid.Ly, n)])
    tree = cKDTree(seeds, boxsize=[grid.Lx, grid.Ly])
    y, x = grid.coords()
    pts = np.column_stack([np.broadcast_to(x, (grid.ny, grid.nx)).ravel(),
                           np.broadcast_to(y, (grid.ny, grid.nx)).ravel()])
    d, idx = tree.query(pts, k=2, workers=-1)
    sep = seeds[idx[:, 1]] - seeds[idx[:, 0]]
    sep[:, 0] = (sep[:, 0] + grid.Lx / 2) % grid.Lx - grid.Lx / 2
    sep[:, 1] = (sep[:, 1] + grid.Ly / 2) % grid.Ly - grid.Ly / 2
    shape = (grid.ny, grid.nx)
    wall = ((d[:, 1] ** 2 - d[:, 0] ** 2) / (2 * np.hypot(sep[:, 0], sep[:, 1]))).reshape(shape)
    centre = d[:, 0].reshape(shape)
    cell = idx[:, 0].reshape(shape)
    strength = rng.lognormal(0.0, 0.25, n)          # granules differ in vigour
    profile = 1.0 - (centre / (centre + wall + 1e-9)) ** 3
    g = _standardise(grid.smooth(strength[cell] * profile, 0.07 * granule_size))
    lanes = np.exp(-wall / (0.1 * granule_size))
    # Broad upflows, narrow downflows: a skewing transform of the cell pattern.
    v = _standardise(-np.exp(-0.6 * _standardise(g + 0.3 * grid.noise(rng, 0.25 * granule_size))))
    t = _standardise(-np.exp(-0.4 * _standardise(g + 0.2 * grid.noise(rng, 0.25 * granule_size))))
    a = np.where(t > 0, t / t[t > 0].mean(), -t / t[t < 0].mean())
    return a, v, lanes


def anelastic_profile(z, density, decay_height):
    """
    Height profiles h(z) of v_z and s(z) of the horizontal flow, from anelastic continuity.

    h = 1 below z = 0 and e^{−z/H} above (overshooting convection decays over
    ~1.5-2 pressure scale heights; Nordlund, Stein & Asplund 2009);
    s = −(ρ̄ h)'/ρ̄ so that ∇·(ρ̄ v) = 0 for v_z = V h, v_h = s ∇φ, ∇²φ = V.

    Parameters
    ----------
    z : array_like
        Heights (km).
    density : array_like
        Mean density ρ̄(z) (any unit).
    decay_height : float
        H (km).

    Returns
    -------
    h, s : `numpy.ndarray`
        Dimensionless and per km.

    Examples
    --------
    >>> z = np.linspace(-500, 700, 121)
    >>> h, s = anelastic_profile(z, np.exp(-z / 150.0), 200.0)
    >>> bool(h[0] == 1.0), bool(np.all(s > 0))
    (True, True)
    """
    z = np.asarray(z, dtype=np.float64)
    h = np.exp(-np.maximum(z, 0.0) / decay_height)
    rho = np.asarray(density, dtype=np.float64)
    s = -np.gradient(rho * h, z) / rho
    return h, s
