r"""
Magnetic field: kG flux elements in the lanes, their potential spreading with height, internetwork field.

- **kG elements** (Stenflo 1973; Solanki 1993): fluxes from the power law
  N(Φ) ∝ Φ^−1.85 on [1e17, 1e19] Mx (Parnell et al. 2009), each a Gaussian
  of peak ``B0`` (the field at the element's own τ = 1, ~1.5 kG) and width
  σ = √(Φ / 2πB0), placed in intergranular lanes (with large-scale
  clustering, or on supergranular boundaries:
  `gongsynth.sun.model_atmosphere.network_layout`), both polarities.  The result is B_z on the
  element base plane: the element's Wilson-depressed τ = 1 level.
- **Spreading with height**: above its base plane a flux distribution is
  continued as a potential field, B̂(k, z) = B̂_z(k, z_b) e^{−k(z−z_b)} with
  B̂_x = −i k_x/k B̂_z, B̂_y = −i k_y/k B̂_z (div B = 0 and curl B = 0
  exactly); neighbouring elements merge into canopies that lie horizontal
  above granules.  Below the base the field is vertical and constant.
- **Internetwork** (Lites et al. 2008; horizontal ≈ 5× vertical flux
  density): the curl of the vector potential A = (A_x, A_y, A_z) c(z) of
  band-passed random fields (correlation 300 km), c(z) = exp(−z²/2H²),
  H = 300 km: B = (c ∂_y A_z − c' A_y, c' A_x − c ∂_x A_z,
  c(∂_x A_y − ∂_y A_x)), divergence-free by construction, mostly horizontal.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["power_law_fluxes", "render_elements", "potential_layer", "internetwork_profile",
           "internetwork_potentials", "INTERNETWORK_SCALE_KM", "INTERNETWORK_HEIGHT_KM"]

#: Correlation length of the internetwork field (km) and the e-folding of its height profile.
INTERNETWORK_SCALE_KM = 300.0
INTERNETWORK_HEIGHT_KM = 300.0


def power_law_fluxes(rng, total, lo=1e17, hi=1e19, index=1.85):
    """
    Element fluxes (Mx) from N(Φ) ∝ Φ^−index on [lo, hi] adding up to ~``total``.

    Parameters
    ----------
    rng : `numpy.random.Generator`
    total : float
        Mx.
    lo, hi, index : float

    Returns
    -------
    `numpy.ndarray`

    Examples
    --------
    >>> f = power_law_fluxes(np.random.default_rng(0), 1e21)
    >>> bool(f.min() >= 1e17 and f.max() <= 1e19), bool(0.7 < f.sum() / 1e21 < 1.3)
    (True, True)
    """
    a = 1.0 - index

    def draw(n):
        q = rng.uniform(size=n)
        return (lo ** a + q * (hi ** a - lo ** a)) ** (1.0 / a)

    mean = (a / (a + 1.0)) * (hi ** (a + 1) - lo ** (a + 1)) / (hi ** a - lo ** a)   # analytic <Φ>
    n = int(rng.poisson(total / mean)) if total > 0 else 0
    return draw(n)


def render_elements(grid, rng, weight, fluxes, signs, core_field, where=None):
    """
    B_z (G) of flux elements: Gaussians of flux Φ and peak ``core_field``, placed with probability ∝ weight.

    Unresolved elements (σ < 0.6 pixel) are spread over 0.6 pixel with the
    same flux (a lower peak: a filling factor).  Where elements overlap the sum
    is softly saturated at 1.4 × ``core_field`` (flux tubes do not exceed ~2 kG).

    Parameters
    ----------
    grid : `~gongsynth.sun.model_atmosphere.granulation.PeriodicGrid`
    rng : `numpy.random.Generator`
    weight : `numpy.ndarray`
        Non-negative placement weight.
    fluxes, signs : `numpy.ndarray`
        Mx and ±1.
    core_field : float
        G.
    where : `numpy.ndarray`, optional
        Flat pixel indices of the elements (then ``weight`` is not used and
        ``rng`` draws nothing); default: drawn with probability ∝ ``weight``.

    Returns
    -------
    `numpy.ndarray`
        B_z (G).
    """
    bz = np.zeros((grid.ny, grid.nx))
    if fluxes.size == 0:
        return bz
    if where is None:
        p = weight.ravel() / weight.sum()
        where = rng.choice(p.size, size=fluxes.size, p=p)
    pixel_area = (grid.dx * 1e5) ** 2
    sigma = np.maximum(np.sqrt(fluxes / (2 * math.pi * core_field)) / 1e5, 0.6 * grid.dx)
    cls = np.floor(np.log(sigma / sigma.min()) / np.log(1.25)).astype(int)   # size classes 25 % apart
    for c in np.unique(cls):
        sel = cls == c
        deposit = np.zeros(grid.ny * grid.nx)
        np.add.at(deposit, where[sel], signs[sel] * fluxes[sel] / pixel_area)
        bz += grid.smooth(deposit.reshape(grid.ny, grid.nx), float(np.sqrt(np.mean(sigma[sel] ** 2))))
    sat = 1.4 * core_field
    return bz / (1 + (np.abs(bz) / sat) ** 4) ** 0.25


def potential_layer(grid, spectra, heights, z, dtype=np.float32):
    """
    Potential field at height ``z`` of flux distributions given on base planes.

    Parameters
    ----------
    grid : `~gongsynth.sun.model_atmosphere.granulation.PeriodicGrid`
    spectra : list of `numpy.ndarray`
        rfft2 of B_z on each base plane.
    heights : list of float
        The base planes' heights (km); below its base a distribution is vertical and constant.
    z : float
        km.
    dtype : numpy dtype

    Returns
    -------
    bx, by, bz : `numpy.ndarray`
        G.

    Examples
    --------
    >>> from gongsynth.sun.model_atmosphere.granulation import PeriodicGrid
    >>> g = PeriodicGrid(32, 32, 96.0)
    >>> bz0 = np.zeros((32, 32)); bz0[16, 16] = 1000.0
    >>> bx, by, bz = potential_layer(g, [g.fft(bz0)], [0.0], 200.0)
    >>> round(float(bz.sum()), 3), bool(bz.max() < 1000)        # flux conserved, spread out
    (1000.0, True)
    """
    total_v = 0
    total_h = 0
    for spec, zb in zip(spectra, heights):
        if z <= zb:
            total_v = total_v + spec
        else:
            e = spec * np.exp(-grid.k * (z - zb)).astype(np.float32)
            total_v = total_v + e
            total_h = total_h + e
    bz = grid.ifft(total_v, dtype)
    if isinstance(total_h, int):
        zero = np.zeros_like(bz)
        return zero, zero.copy(), bz
    k = grid.k.copy()
    k[0, 0] = 1.0
    bx = grid.ifft((-1j * grid.kx / k).astype(np.complex64) * total_h, dtype)
    by = grid.ifft((-1j * grid.ky / k).astype(np.complex64) * total_h, dtype)
    return bx, by, bz


def internetwork_potentials(grid, rng, vertical_rms, horizontal_rms):
    """
    Vector potential (A_x, A_y, A_z) (G km) of the internetwork field, scaled to the requested RMS at z = 0.

    Parameters
    ----------
    grid : `~gongsynth.sun.model_atmosphere.granulation.PeriodicGrid`
    rng : `numpy.random.Generator`
    vertical_rms, horizontal_rms : float
        RMS B_z and RMS |B_h| (G) at z = 0.

    Returns
    -------
    tuple of `numpy.ndarray`
        A_x, A_y, A_z.
    """
    sig = max(INTERNETWORK_SCALE_KM, 0.6 * grid.dx)
    ax, ay, az = (grid.noise(rng, sig, band=True) for _ in range(3))
    dxy = grid.gradient(ay)[0] - grid.gradient(ax)[1]
    ax *= vertical_rms / (dxy.std() or 1.0)
    ay *= vertical_rms / (dxy.std() or 1.0)
    gx, gy = grid.gradient(az)
    az *= horizontal_rms / (np.sqrt(np.mean(gx ** 2 + gy ** 2)) or 1.0)
    return ax, ay, az


def internetwork_profile(z):
    """
    Height profile c(z) = exp(−z²/2H²) of the internetwork vector potential and its derivative.

    Parameters
    ----------
    z : array_like
        km.

    Returns
    -------
    c, dc : `numpy.ndarray`
        c and dc/dz (per km).

    Examples
    --------
    >>> c, dc = internetwork_profile([0.0, 300.0])
    >>> float(c[0]), float(dc[0])
    (1.0, -0.0)
    """
    z = np.asarray(z, dtype=np.float64)
    h = INTERNETWORK_HEIGHT_KM
    c = np.exp(-0.5 * (z / h) ** 2)
    return c, -z / h ** 2 * c
