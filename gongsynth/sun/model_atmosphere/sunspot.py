r"""
A round sunspot: umbra and penumbra weights, base-plane field, Evershed and moat flows.

After Borrero & Ichimoto (2011) and Rempel (2015), positive polarity, at the
box centre.  The umbra's thermodynamics follow Maltby et al. (1986) model M
and the penumbra's del Toro Iniesta et al. (1994) (the builder places both
by pressure balance: the umbral Wilson depression).  Here only the
horizontal structure:

- weights s_u (umbra) and s_p (penumbra) with 300 km / 500 km soft edges;
- B_z on the spot's base plane (the umbral τ = 1 level): B_u (1 − 0.3 ρ²) in
  the umbra (ρ = r / R_u), and in the penumbra the vertical component of a
  field of strength B_p (1.35 − 0.7 q)(1.15 − 0.3 s) inclined by
  40-65° (spines) to 55-100° (intraspines), q the fractional distance
  across the penumbra and s ∈ [0, 1] the intraspine fraction of a random
  filamentary pattern (~0.3 Mm wide, radially elongated); the potential
  continuation (`~gongsynth.sun.model_atmosphere.flux_elements`) gives the
  horizontal field that fans out with height;
- the Evershed outflow, radial, along the intraspines, growing outward to
  ``evershed_speed`` and ending at the spot edge, and the moat flow
  (``moat_speed``, peaking just outside the spot and decaying over 0.8 R_p).
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["spot_structure"]


def _filaments(grid, rng, r, theta, r_u, r_p):
    """Intraspine fraction s ∈ [0, 1] from a random field long in r and narrow in θ."""
    n_r, n_t = 96, 2048
    r_max = 1.2 * r_p
    fil = rng.standard_normal((n_r, n_t))
    f = np.fft.rfft(fil, axis=1)
    k_t = np.fft.rfftfreq(n_t, d=2 * math.pi / n_t)
    width = 120.0 / (0.5 * (r_u + r_p))
    fil = np.fft.irfft(f * np.exp(-2 * math.pi ** 2 * width ** 2 * k_t ** 2)[None, :], n=n_t, axis=1)
    kr = np.fft.rfftfreq(n_r, d=r_max / n_r)
    fil = np.fft.irfft(np.fft.rfft(fil, axis=0) * np.exp(-2 * math.pi ** 2 * 1500.0 ** 2 * kr ** 2)[:, None],
                       n=n_r, axis=0)
    fil = (fil - fil.mean()) / (fil.std() or 1.0)
    inside = r < r_max
    ri = np.clip(r[inside] / r_max * n_r - 0.5, 0, n_r - 1.0001)
    ti = ((theta[inside] + math.pi) / (2 * math.pi) * n_t) % n_t
    r0, t0 = ri.astype(int), ti.astype(int)
    fr, ft = ri - r0, ti - t0
    t1, r1 = (t0 + 1) % n_t, np.minimum(r0 + 1, n_r - 1)
    val = ((1 - fr) * ((1 - ft) * fil[r0, t0] + ft * fil[r0, t1])
           + fr * ((1 - ft) * fil[r1, t0] + ft * fil[r1, t1]))
    s = np.zeros_like(r)
    s[inside] = 1.0 / (1.0 + np.exp(-val / 0.35))
    return s


def spot_structure(grid, rng, *, r_umbra, r_penumbra, b_umbra, b_penumbra, v_evershed, v_moat):
    """
    Horizontal structure of the spot at the box centre.

    Parameters
    ----------
    grid : `~gongsynth.sun.model_atmosphere.granulation.PeriodicGrid`
    rng : `numpy.random.Generator`
    r_umbra, r_penumbra : float
        km.
    b_umbra, b_penumbra : float
        G.
    v_evershed, v_moat : float
        km/s.

    Returns
    -------
    dict
        ``umbra``, ``penumbra`` (weights), ``bz`` (G, base plane), ``vx``, ``vy``
        (horizontal flow at τ = 1, km/s), ``evershed`` (its share of that flow, for its
        height profile), ``r`` (km).

    Examples
    --------
    >>> from gongsynth.sun.model_atmosphere.granulation import PeriodicGrid
    >>> g = PeriodicGrid(128, 128, 384.0)
    >>> sp = spot_structure(g, np.random.default_rng(0), r_umbra=7e3, r_penumbra=16e3, b_umbra=3000.0,
    ...                     b_penumbra=1500.0, v_evershed=2.0, v_moat=0.8)
    >>> bool(sp["bz"].max() > 2500), bool(sp["umbra"].max() > 0.99)
    (True, True)
    """
    dx, dy = grid.offset(grid.Lx / 2, grid.Ly / 2)
    r = np.hypot(dx, dy)
    theta = np.arctan2(dy, dx)
    s = _filaments(grid, rng, r, theta, r_umbra, r_penumbra)
    q = np.clip((r - r_umbra) / (r_penumbra - r_umbra), 0.0, 1.0)
    w_u = 0.5 * (1 - np.tanh((r - r_umbra) / 300.0))
    mask = 0.5 * (1 - np.tanh((r - r_penumbra) / 500.0))
    rho = np.minimum(r / r_umbra, 1.2)
    b_u = b_umbra * (1 - 0.3 * rho ** 2)
    g_u = np.radians(40.0 * rho ** 2)
    b_p = b_penumbra * (1.35 - 0.7 * q) * (1.15 - 0.3 * s)
    g_p = np.radians((40.0 + 25.0 * q) * (1 - s) + (55.0 + 45.0 * q) * s)
    bz = mask * (w_u * b_u * np.cos(g_u) + (1 - w_u) * b_p * np.cos(g_p))
    v_e = v_evershed * s * np.sqrt(q) * (1 - w_u) * mask
    outside = np.maximum(r - r_penumbra, 0.0)
    v_m = v_moat * (1 - mask) * np.exp(-outside / (0.8 * r_penumbra)) * np.minimum(outside / 1000.0, 1.0)
    cos_t, sin_t = np.cos(theta), np.sin(theta)
    return dict(umbra=w_u * mask, penumbra=(1 - w_u) * mask, bz=bz, vx=(v_e + v_m) * cos_t,
                vy=(v_e + v_m) * sin_t, evershed=v_e, moat=v_m, cos=cos_t, sin=sin_t, r=r, mask=mask)
