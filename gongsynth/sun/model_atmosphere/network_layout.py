r"""
The 3-D Sun's magnetic network: where its kG elements sit on a periodic supergranular pattern.

With ``network`` on (`gongsynth.sun.model_atmosphere.builder`; by default
in every box of at least two cells a side) the kG elements are not clustered
by a noise field but laid on supergranular cell boundaries, the same picture as the disk-scale network
(`gongsynth.sun.surface_field.network`, whose numbers are reused here):

- **Cells**: periodic Voronoi cells (`gongsynth.sun.photosphere.voronoi.cell_walls`)
  of round(box area / s²) centres, s the requested mean spacing
  (`~gongsynth.sun.surface_field.network.SUPERGRANULE_SIZE`, 30 Mm;
  supergranules are 20-35 Mm across, Rieutord & Rincon 2010, Living Rev.
  Sol. Phys. 7, 2), placed at random but no two closer than
  `MIN_SEPARATION` × s: supergranules tile the surface more evenly than a
  Poisson pattern would (chosen, not fitted), and a box of ~10 cells keeps
  its cell count (a Poisson count would vary by ±30 %).  The default 98 Mm
  box holds 11 of them.
- **Network**: the element fluxes of the builder (N(Φ) ∝ Φ^−1.85,
  Parnell et al. 2009) are placed with probability ∝ lanes × exp(−w²/2σ²),
  w the distance to the nearest cell wall, σ = `LANE_WIDTH_KM` (the disk
  network's lane width): in the intergranular lanes along the boundaries,
  where the supergranular outflow collects the flux.
- **Ephemeral regions**: bipoles emerging inside the cells (placement ∝
  1 − exp(−w²/2σ²)), `~gongsynth.sun.surface_field.network.EPHEMERAL_FLUX_DENSITY`
  of unsigned flux (1.5 G), fluxes per polarity exponentially distributed about
  `~gongsynth.sun.surface_field.network.EPHEMERAL_FLUX` (1.1e19 Mx; Hagenaar
  2001, ApJ 555, 448; emergence rates in Hagenaar et al. 2003, ApJ 584,
  1107), footpoints `~gongsynth.sun.surface_field.network.EPHEMERAL_SEPARATION`
  (7 Mm) apart, each footpoint one kG element.
- **Internetwork**: unchanged, the builder's mixed-polarity divergence-free
  field (Lites et al. 2008, `gongsynth.sun.model_atmosphere.flux_elements`).
- **Plage**: the same layout at a higher ``element_flux_density`` (and
  ``element_model="plage"``): the boundaries fill up first.

Not modelled: the cells' flows and evolution (a snapshot; the granular flow
is unchanged).
"""
from __future__ import annotations

import math

import astropy.units as u
import numpy as np

from gongsynth.sun.photosphere.voronoi import cell_walls
from gongsynth.sun.surface_field.network import (
    EPHEMERAL_FLUX,
    EPHEMERAL_FLUX_DENSITY,
    EPHEMERAL_SEPARATION,
    SupergranularNetwork,
)
from gongsynth.sun.surface_field.supergranulation import HORIZONTAL_RMS, VERTICAL_RMS, cell_flow_profile

__all__ = ["network_layout", "cell_centres", "cell_flow", "LANE_WIDTH_KM", "MIN_SEPARATION"]

#: Gaussian sigma (km) of the network lanes about the cell walls: the disk network's (1.5 Mm).
LANE_WIDTH_KM = float(SupergranularNetwork.lane_width.to_value(u.km))
#: Closest approach of two cell centres, in mean spacings (random sequential packing jams near 0.8).
MIN_SEPARATION = 0.6


def cell_centres(grid, rng, spacing_km):
    """
    Round(box area / spacing²) (at least 2) random centres in the periodic box, none closer than
    `MIN_SEPARATION` × ``spacing_km`` to another (minimum image).

    Parameters
    ----------
    grid : `~gongsynth.sun.model_atmosphere.granulation.PeriodicGrid`
    rng : `numpy.random.Generator`
    spacing_km : float

    Returns
    -------
    `numpy.ndarray`
        (n, 2) centres (x, y), km.

    Examples
    --------
    >>> from gongsynth.sun.model_atmosphere.granulation import PeriodicGrid
    >>> cell_centres(PeriodicGrid(256, 256, 384.0), np.random.default_rng(1), 30000.0).shape
    (11, 2)
    """
    n = max(2, round(grid.Lx * grid.Ly / spacing_km ** 2))
    box = np.array([grid.Lx, grid.Ly])
    d_min = MIN_SEPARATION * spacing_km
    centres = np.empty((0, 2))
    for _ in range(1000 * n):
        if len(centres) == n:
            return centres
        c = rng.uniform(0, 1, 2) * box
        off = (centres - c + box / 2) % box - box / 2
        if not len(centres) or np.min(np.hypot(off[:, 0], off[:, 1])) >= d_min:
            centres = np.vstack([centres, c])
    raise ValueError(f"supergranule_size: could not place {n} cells {d_min:.0f} km apart")


def network_layout(grid, rng, cell_size_km, lanes, keep_out, ephemeral_flux_density=None):
    """
    Placement weight of the network elements and the ephemeral regions' footpoints on periodic cells.

    Parameters
    ----------
    grid : `~gongsynth.sun.model_atmosphere.granulation.PeriodicGrid`
    rng : `numpy.random.Generator`
        Draws the cells and the ephemeral regions.
    cell_size_km : float
        Mean spacing of the cell centres (km); the box must hold at least one
        cell of that size each way.
    lanes : `numpy.ndarray`
        Intergranular-lane indicator (1 in the lanes), (ny, nx).
    keep_out : `numpy.ndarray`
        1 where elements may sit, → 0 on and around a sunspot, (ny, nx).
    ephemeral_flux_density : float, optional
        Unsigned flux density (G) of the ephemeral regions over the box
        (default `~gongsynth.sun.surface_field.network.EPHEMERAL_FLUX_DENSITY`; 0: none).

    Returns
    -------
    dict
        ``weight`` (ny, nx): the network elements' placement weight;
        ``wall`` (ny, nx): distance to the nearest cell wall (km);
        ``cells``: number of cells; ``centres``: their (x, y) in km;
        ``where``, ``fluxes``, ``signs``: flat
        pixel index, flux (Mx) and sign of each ephemeral footpoint
        (positive and negative footpoints of one region alternate).

    Raises
    ------
    ValueError
        ``cell_size_km`` not positive, or larger than the box.

    Examples
    --------
    >>> from gongsynth.sun.model_atmosphere.granulation import PeriodicGrid
    >>> g = PeriodicGrid(128, 128, 384.0)
    >>> one = np.ones((128, 128))
    >>> lay = network_layout(g, np.random.default_rng(1), 30000.0, one, one)
    >>> bool(lay["weight"].max() <= 1.0), lay["cells"] >= 3, float(lay["signs"].sum())
    (True, True, 0.0)
    """
    if isinstance(cell_size_km, bool) or not isinstance(cell_size_km, (int, float)) or not cell_size_km > 0:
        raise ValueError(f"supergranule_size must be a positive length, got {cell_size_km!r} km")
    if cell_size_km > min(grid.Lx, grid.Ly):
        raise ValueError(f"supergranule_size ({cell_size_km / 1e3:g} Mm) must fit in the box "
                         f"({grid.Lx / 1e3:.1f} x {grid.Ly / 1e3:.1f} Mm): enlarge the box or shrink "
                         f"the cells")
    b_er = (EPHEMERAL_FLUX_DENSITY.to_value(u.G) if ephemeral_flux_density is None
            else float(ephemeral_flux_density))
    if not b_er >= 0:
        raise ValueError(f"ephemeral_flux_density must be >= 0 G, got {ephemeral_flux_density!r}")
    centres = cell_centres(grid, rng, float(cell_size_km))
    wall, _, _ = cell_walls(grid, centres)
    n_cells = len(centres)
    boundary = np.exp(-0.5 * (wall / LANE_WIDTH_KM) ** 2)
    # Ephemeral regions: centres uniform over the cell interiors, both footpoints of one region.
    mean = EPHEMERAL_FLUX.to_value(u.Mx)
    n = int(rng.poisson(b_er * grid.Lx * grid.Ly * 1e10 / (2 * mean)))
    interior = ((1 - boundary) * keep_out).ravel()
    at = rng.choice(interior.size, size=n, p=interior / interior.sum()) if n else np.zeros(0, dtype=np.int64)
    phi = rng.exponential(mean, size=n)
    angle = rng.uniform(0, 2 * math.pi, size=n)
    half = 0.5 * EPHEMERAL_SEPARATION.to_value(u.km) / grid.dx            # pixels
    iy, ix = np.divmod(at, grid.nx)
    feet = []
    for sign in (1.0, -1.0):
        fy = np.floor(iy + 0.5 + sign * half * np.sin(angle)).astype(np.int64) % grid.ny
        fx = np.floor(ix + 0.5 + sign * half * np.cos(angle)).astype(np.int64) % grid.nx
        feet.append(fy * grid.nx + fx)
    return dict(weight=lanes * boundary * keep_out + 1e-12, wall=wall, cells=n_cells, centres=centres,
                where=np.column_stack(feet).ravel(), fluxes=np.repeat(phi, 2),
                signs=np.tile([1.0, -1.0], n))


def cell_flow(grid, centres, horizontal_rms=HORIZONTAL_RMS, vertical_rms=VERTICAL_RMS):
    """
    The supergranular flow of the periodic cells: outflow from each centre to its walls, up in the middle.

    The disk's cells' shape and scaling (`~gongsynth.sun.surface_field.supergranulation.cell_flow_profile`),
    its rms values over the box (whose columns have equal areas).

    Parameters
    ----------
    grid : `~gongsynth.sun.model_atmosphere.granulation.PeriodicGrid`
    centres : `numpy.ndarray`
        (n, 2) cell centres (x, y), km (``network_layout``'s ``centres``).
    horizontal_rms, vertical_rms : `~astropy.units.Quantity`
        RMS horizontal speed and vertical velocity over the box.

    Returns
    -------
    vx, vy, vz : `numpy.ndarray`
        (ny, nx) m/s; vz positive up.

    Examples
    --------
    >>> from gongsynth.sun.model_atmosphere.granulation import PeriodicGrid
    >>> g = PeriodicGrid(128, 128, 384.0)
    >>> centres = cell_centres(g, np.random.default_rng(1), 30000.0)
    >>> vx, vy, vz = cell_flow(g, centres)
    >>> round(float(np.sqrt(np.mean(vx ** 2 + vy ** 2)))), round(float(vz.std())), bool(abs(vz.mean()) < 1e-9)
    (350, 25, True)
    """
    wall, centre, cell = cell_walls(grid, centres)
    y, x = grid.coords()
    dx = (x - centres[cell, 0] + grid.Lx / 2) % grid.Lx - grid.Lx / 2
    dy = (y - centres[cell, 1] + grid.Ly / 2) % grid.Ly - grid.Ly / 2
    norm = np.maximum(np.hypot(dx, dy), 1e-300)
    s = centre / np.maximum(centre + wall, 1e-300)
    along, rise = cell_flow_profile(s, s, horizontal_rms, vertical_rms)       # the columns: equal areas
    return along * dx / norm, along * dy / norm, rise
