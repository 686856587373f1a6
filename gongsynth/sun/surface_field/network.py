"""
The magnetic network at disk scale: flux concentrations on the boundaries of supergranular cells.

A real full-disk magnetogram of the quiet Sun is not speckle: mixed-polarity
flux outlines ~30 Mm cells all over the disk, and where the large-scale field
has a sign (unipolar regions, decayed plage) the network has that sign.  The
patch library of a full-disk scene (`gongsynth.stages.scene.library`) holds
the small scales of photosphere patches, each a few tens of Mm, laid with
random offsets cell by cell; a pattern continuous over the disk cannot come
from them.  `SupergranularNetwork` places it on the large-scale grid of the
scene instead (`gongsynth.stages.scene.surface.large_scale_grid`), as a
signed radial flux density at ~3 Mm resolution; the scene then fills each
sample with the library's kG elements at the filling that this flux density
asks for (enhanced network to plage levels on the boundaries, the quiet
level in the cell interiors), so that light and truth follow the network.

The ingredients and the numbers behind them (set once from published
statistics; where those leave a range, measured on the real maps of three
instruments, never fitted to one map):

- **Supergranular cells**: Voronoi cells of random centres on the sphere,
  mean spacing 30 Mm (supergranules are 20-35 Mm across, typically ~30 Mm;
  Rieutord & Rincon 2010, Living Rev. Sol. Phys. 7, 2, §2-3).  The flux
  lies in Gaussian lanes of 1.5 Mm sigma about the cell walls, where the
  supergranular outflow collects it (chosen: narrower than GONG's ~3.6 Mm
  resolution and the 3 Mm grid, so the grid sets the width).
- **Flux budget**: a mean unsigned network flux density of 5 G over the
  quiet Sun: the whole Sun's unsigned flux near cycle minimum, ≈ 2.5-3e23
  Mx in full-disk magnetograms of 1-2″ pixels (Schrijver & Harvey 1994,
  Sol. Phys. 150, 1; as recalled, not checked against the paper this
  session), over its 6.1e22 cm².  Budgets at MDI's and HMI's resolution
  are lower (abstracts: Jin et al. 2011, arXiv:1102.3485, quiet regions
  0.94e23 Mx at the cycle 23/24 minimum; Jin & Wang 2019, RAA 19, 69,
  network 39 % of 5.9e22 Mx): the noise guide's "amount" of the network.
- **Element fluxes**: network concentrations with N(Φ) ∝ Φ^-1.85 (Parnell
  et al. 2009, ApJ 698, 75: one power law from 2e17 to 1e23 Mx), here from
  1e18 Mx (below, GONG sees the internetwork of the patches) to 1e20 Mx
  (above, flux belongs to the large-scale field's plage).  Network patches
  follow a power law from 3e19 to ~1e21 Mx below the supergranular size
  (Meunier 2003, A&A 405, 1107), so the cut is above 3e19; where it sits was
  measured, as the shape of the distribution of cluster fluxes at GONG's
  resolution (`gongsynth.analysis.network_clusters`) on real MDI and HMI
  magnetograms of 2010 and on the Big Bear GONG map of 2009
  (``scripts/network_clusters_vs_real.py``, noise guide): a cut of 3e19 Mx
  gives too few large clusters on GONG's and HMI's (99th percentile 0.5-0.6
  of the real, power-law index 3.9-4.9 against 2.7-3.0; MDI's cannot tell
  3e19 from 1e20), 1e20 Mx matches all three (0.8-1.2, 2.8-3.2; with the
  cluster size below 0.9-1.2, 2.7-3.2), 3e20 and 1e21 give too many
  (1.1-1.5, 2.3-2.8).
- **Cluster size**: a concentration is laid in its grid cell unless that
  would make the cell denser than plage, `CLUSTER_FLUX_DENSITY` (300 G:
  plage averages 100-300 G over ~1″, Schrijver & Zwaan 2000, *Solar and
  Stellar Magnetic Activity*, ch. 4, the scene's plage level); a larger one
  spreads as a Gaussian of that peak flux density, σ = √(Φ / 2π B), about
  its place (2.3 Mm for 1e20 Mx): a large network cluster is many elements,
  not one.
- **Chains** (``chain_length``, `CHAIN_LENGTH` = 3 Mm by default): each
  concentration laid along its cell wall as a Gaussian of that sigma, rather
  than at one grid point.  The real network's clusters at GONG's resolution are elongated
  (median axis ratio 1.33-1.45 on real GONG, MDI and HMI maps) where
  concentrations at points give 1.25-1.27 (noise guide, "the outline"):
  the real network lies in chains of elements along the lanes.  Measured
  on those three maps, 3-4 Mm matches all of them, 3 Mm best over four
  seeds (docs, decisions: "the disk network's chains"); 0 lays every
  concentration at its point, as before.
- **Polarity**: the imbalance follows the large-scale field: a concentration
  is positive with probability (1 + f)/2, f = B_r / 5 G clipped to ±1,
  so that the network's mean flux density is the large-scale field's
  wherever |B_r| < 5 G; the rest of a stronger field stays smooth.  On top,
  each supergranule carries a random sign (±1), and a concentration on the
  wall between cells i and j leans to (s_i + s_j)/2 by the part of the
  polarity the imbalance leaves free (1 - |f|): network boundaries are
  mostly unipolar over a cell side, mixed where cells of both signs meet
  (chosen, from the look of quiet-Sun magnetograms, e.g. Schrijver & Zwaan
  2000, *Solar and Stellar Magnetic Activity*, ch. 4; not fitted).

- **Ephemeral regions**: bipoles emerging inside the cells, 1.5 G of
  unsigned flux on the Sun at any time, fluxes exponentially distributed
  about 1.1e19 Mx per polarity, footpoints 7 Mm apart (Hagenaar 2001, ApJ
  555, 448; see `EPHEMERAL_FLUX_DENSITY`).

Not modelled here: the cells' evolution and flows (a snapshot), and the
internetwork (in the library's patches: Lites et al. 2008,
Orozco Suárez & Bellot Rubio 2012, see `gongsynth.sun.photosphere.model`).
"""
import math
from dataclasses import dataclass

import astropy.units as u
import numpy as np
from scipy.spatial import cKDTree
from sunpy.sun.constants import radius as solar_radius

from gongsynth.seeding import as_seed_sequence, stage_generator
from gongsynth.validation import check_quantity

__all__ = ["SupergranularNetwork", "NETWORK_FLUX_DENSITY", "SUPERGRANULE_SIZE", "CLUSTER_FLUX_DENSITY",
           "CHAIN_LENGTH", "EPHEMERAL_FLUX",
           "EPHEMERAL_FLUX_DENSITY", "EPHEMERAL_SEPARATION"]

#: Mean unsigned network flux density over the quiet Sun (see the module docstring).
NETWORK_FLUX_DENSITY = 5 * u.G
#: Mean spacing of supergranule centres (Rieutord & Rincon 2010).
SUPERGRANULE_SIZE = 30 * u.Mm
#: Densest flux a concentration lays on the grid before it spreads: plage's 100-300 G over ~1″
#: (Schrijver & Zwaan 2000, ch. 4; the scene's plage level, `gongsynth.stages.scene.library.LEVELS`).
CLUSTER_FLUX_DENSITY = 300 * u.G
#: Gaussian sigma along its cell wall over which a concentration is laid: the length that gives the
#: network's clusters the elongation of real GONG, MDI and HMI maps at GONG's resolution (median axis
#: ratios 1.41, 1.33, 1.45), least squares over four seeds of runs of those maps' dates
#: (``scripts/network_chain_length.py``, ``docs/guide/network_chain_length.ecsv``; 4 Mm nearly as good).
CHAIN_LENGTH = 3 * u.Mm

_CENTRES, _FLUXES, _PLACES, _SIGNS, _EPHEMERAL = range(5)

#: Ephemeral regions: mean flux of one polarity (Mx) and unsigned flux density present on the Sun (G).
#: Hagenaar 2001 (ApJ 555, 448, MDI full disk): mean ER flux 1.1e19 Mx, lifetime ~4.4 h and an
#: emergence rate of ~5e23 Mx per day over the Sun; rate × lifetime ≈ 9e22 Mx present, 1.5 G over
#: its 6.1e22 cm² (the flux and the rate as recalled).  Checked against the same study's first
#: report (Hagenaar 2000, BAAS 32, 1.23): lifetime 4.4 h and (1-2)e4 ERs on a quarter of the Sun in
#: 3.5 days, i.e. 2100-4200 present on the Sun, 0.75-1.5 G at 2 × 1.1e19 Mx each: 1.5 G is the top
#: of that range.
EPHEMERAL_FLUX = 1.1e19 * u.Mx
EPHEMERAL_FLUX_DENSITY = 1.5 * u.G
#: Footpoint separation of an ephemeral region (chosen: young ERs are 5-10 Mm across).
EPHEMERAL_SEPARATION = 7 * u.Mm


@dataclass(frozen=True)
class SupergranularNetwork:
    """
    A seeded network of flux concentrations on supergranular cell walls, laid on a heliographic grid.

    Parameters
    ----------
    seed : int or `numpy.random.SeedSequence`
        The cells, the fluxes, their places and polarities.
    cell_size : `~astropy.units.Quantity`
        Mean spacing of supergranule centres (default `SUPERGRANULE_SIZE`, 30 Mm).
    flux_density : `~astropy.units.Quantity`
        Mean unsigned flux density of the network (default `NETWORK_FLUX_DENSITY`, 5 G).
    flux_range : `~astropy.units.Quantity`
        Smallest and largest concentration flux (Mx; default 1e18, 1e20).
    flux_index : float
        N(Φ) ∝ Φ^-flux_index (Parnell et al. 2009: 1.85).
    lane_width : `~astropy.units.Quantity`
        Gaussian sigma of the lanes about the cell walls (1.5 Mm).
    coherence : float
        Weight in [0, 1] of the cells' own signs in the free part of the polarity (1).
    cluster_flux_density : `~astropy.units.Quantity` or None
        Densest mean flux density a concentration lays in one grid cell
        (`CLUSTER_FLUX_DENSITY`, 300 G); a larger concentration spreads over
        its neighbours as a Gaussian of this peak.  ``None``: every
        concentration in one cell.
    chain_length : `~astropy.units.Quantity`
        Gaussian sigma along the cell wall over which each concentration's
        flux is laid (`CHAIN_LENGTH`, 3 Mm, by default; 0: at its grid
        point, or spread as above).
        Across the wall a concentration keeps its point (or its spread).
    ephemeral_flux_density : `~astropy.units.Quantity`
        Unsigned flux density of the ephemeral regions, bipoles inside the
        cells (`EPHEMERAL_FLUX_DENSITY`, 1.5 G; 0: none).  Their fluxes are
        exponentially distributed about `EPHEMERAL_FLUX`, their footpoints
        `EPHEMERAL_SEPARATION` apart in a random direction.

    Examples
    --------
    >>> import numpy as np, astropy.units as u
    >>> net = SupergranularNetwork(seed=1)
    >>> lon, lat = np.linspace(-180, 180, 721), np.linspace(-90, 90, 361)
    >>> quiet = net.on_grid(lon, lat, np.zeros((361, 721)))
    >>> bool(abs(quiet).max() > 50), bool(abs(quiet.mean()) < 0.5)   # strong lanes, balanced
    (True, True)
    """

    seed: object = 0
    cell_size: u.Quantity = SUPERGRANULE_SIZE
    flux_density: u.Quantity = NETWORK_FLUX_DENSITY
    flux_range: u.Quantity = (1e18, 1e20) * u.Mx
    flux_index: float = 1.85
    lane_width: u.Quantity = 1.5 * u.Mm
    coherence: float = 1.0
    ephemeral_flux_density: u.Quantity = EPHEMERAL_FLUX_DENSITY
    cluster_flux_density: u.Quantity = CLUSTER_FLUX_DENSITY
    chain_length: u.Quantity = CHAIN_LENGTH

    def __post_init__(self):
        for name, unit in (("cell_size", u.km), ("flux_density", u.G), ("lane_width", u.km)):
            value = check_quantity(getattr(self, name), unit, name)
            if np.ndim(value) or not value.value > 0:
                raise ValueError(f"{name} must be a positive scalar, got {value}")
        rng = check_quantity(self.flux_range, u.Mx, "flux_range").to_value(u.Mx)
        if np.shape(rng) != (2,) or not 0 < rng[0] < rng[1]:
            raise ValueError(f"flux_range must be two increasing positive fluxes, got {self.flux_range}")
        if not 1 < float(self.flux_index) < 3:
            raise ValueError(f"flux_index must be in (1, 3), got {self.flux_index!r}")
        if not 0 <= float(self.coherence) <= 1:
            raise ValueError(f"coherence must be in [0, 1], got {self.coherence!r}")
        if self.cluster_flux_density is not None:
            dense = check_quantity(self.cluster_flux_density, u.G, "cluster_flux_density")
            if np.ndim(dense) or not dense.value > 0:
                raise ValueError(f"cluster_flux_density must be a positive scalar or None, got {dense}")
        chain = check_quantity(self.chain_length, u.km, "chain_length")
        if np.ndim(chain) or not chain.value >= 0:
            raise ValueError(f"chain_length must be a scalar length >= 0, got {chain}")
        er = check_quantity(self.ephemeral_flux_density, u.G, "ephemeral_flux_density")
        if np.ndim(er) or not er.value >= 0:
            raise ValueError(f"ephemeral_flux_density must be a scalar >= 0, got {er}")

    def cells(self):
        """
        The supergranules: their centres and their own signs.

        Returns
        -------
        centres : `numpy.ndarray`
            (n, 3) unit vectors of the cell centres (Stonyhurst axes: x to the
            central meridian, z to the north pole), uniform on the sphere, n
            the Sun's area over the square of ``cell_size``.
        signs : `numpy.ndarray`
            (n,) ±1: the polarity each cell's network leans to.

        Examples
        --------
        >>> centres, signs = SupergranularNetwork(seed=1).cells()
        >>> centres.shape, sorted(set(signs.tolist()))
        ((6758, 3), [-1.0, 1.0])
        """
        r_km = solar_radius.to_value(u.km)
        rng = stage_generator(as_seed_sequence(self.seed), "network", _CENTRES)
        spacing = self.cell_size.to_value(u.km)
        n_cells = max(4, int(round(4 * math.pi * r_km ** 2 / spacing ** 2)))
        centres = rng.standard_normal((n_cells, 3))
        centres /= np.linalg.norm(centres, axis=1)[:, None]
        return centres, np.where(rng.uniform(size=n_cells) < 0.5, -1.0, 1.0)

    def on_grid(self, longitude, latitude, large_scale, where=None):
        """
        The radial flux density of the large-scale field with its quiet part carried by the network.

        Parameters
        ----------
        longitude, latitude : `numpy.ndarray`
            1-D, uniform grid axes in deg (Stonyhurst; longitude may span 360° with both ends).
        large_scale : `numpy.ndarray`
            (nlat, nlon) radial flux density of the large-scale field, G.
        where : `numpy.ndarray`, optional
            (nlat, nlon) bool: the grid points to lay the network on (e.g. the
            visible hemisphere: half the work); the others keep the large-scale
            field.  The budget is the region's area times ``flux_density``.
            Default: everywhere.

        Returns
        -------
        `numpy.ndarray`
            (nlat, nlon) G: the network concentrations (each the grid cell's
            mean flux density) plus what of the large-scale field the network
            does not carry; its mean over any region of many cells is the
            large-scale field's.
        """
        lon = np.radians(np.asarray(longitude, dtype=float))
        lat = np.radians(np.asarray(latitude, dtype=float))
        field = np.asarray(large_scale, dtype=float)
        if field.shape != (lat.size, lon.size):
            raise ValueError(f"large_scale must have shape {(lat.size, lon.size)}, got {field.shape}")
        r_km = solar_radius.to_value(u.km)
        root = as_seed_sequence(self.seed)
        centres, cell_sign = self.cells()
        # Distance of every grid point to the nearest cell wall (chords: the cells are small).
        glat, glon = np.meshgrid(lat, lon, indexing="ij")
        inside = np.ones(field.shape, dtype=bool) if where is None else np.asarray(where, dtype=bool)
        if inside.shape != field.shape:
            raise ValueError(f"where must have shape {field.shape}, got {inside.shape}")
        glat, glon = glat[inside], glon[inside]
        points = np.stack([np.cos(glat) * np.cos(glon), np.cos(glat) * np.sin(glon), np.sin(glat)], axis=-1)
        d, idx = cKDTree(centres).query(points, k=2)
        sep = np.linalg.norm(centres[idx[:, 1]] - centres[idx[:, 0]], axis=1)
        wall = r_km * (d[:, 1] ** 2 - d[:, 0] ** 2) / (2 * sep)
        # Grid-cell areas (cm²): equal-angle cells shrink as cos(latitude); a cell that reaches a pole
        # is the polar cap r² Δλ (1 − sin φ_edge) (not the zero area of cos 90°, which would turn its
        # flux into an unbounded field).
        step_lon = abs(lon[1] - lon[0]) if lon.size > 1 else 2 * math.pi
        step_lat = abs(lat[1] - lat[0]) if lat.size > 1 else math.pi
        edge = np.abs(glat) - step_lat / 2
        polar = np.abs(glat) + step_lat / 2 > math.pi / 2
        area = (r_km * 1e5) ** 2 * step_lon * np.where(polar, 1 - np.sin(edge), step_lat * np.cos(glat))
        # Avoid laying flux twice on a longitude that the grid holds at both ends (-180 and 180).
        unique = np.ones(lon.size, dtype=bool)
        if lon.size > 1 and math.isclose(lon[-1] - lon[0], 2 * math.pi, rel_tol=1e-9):
            unique[-1] = False
        weight = np.exp(-0.5 * (wall / self.lane_width.to_value(u.km)) ** 2) * area
        weight *= np.broadcast_to(unique, field.shape)[inside]
        # The concentrations' fluxes (Parnell et al. 2009) for the whole Sun's budget.
        b_net = self.flux_density.to_value(u.G)
        lo, hi = self.flux_range.to_value(u.Mx)
        a = 1.0 - float(self.flux_index)
        rng = stage_generator(root, "network", _FLUXES)
        mean_flux = (a / (a + 1)) * (hi ** (a + 1) - lo ** (a + 1)) / (hi ** a - lo ** a)
        total = b_net * np.sum(area * np.broadcast_to(unique, field.shape)[inside])
        q = rng.uniform(size=int(round(total / mean_flux)))
        fluxes = (lo ** a + q * (hi ** a - lo ** a)) ** (1.0 / a)
        where = stage_generator(root, "network", _PLACES).choice(weight.size, size=fluxes.size,
                                                                 p=weight / weight.sum())
        # Polarities: the large-scale imbalance, then the cells' own signs in what it leaves free.
        f = np.clip(field[inside][where] / b_net, -1.0, 1.0)
        lean = float(self.coherence) * 0.5 * (cell_sign[idx[where, 0]] + cell_sign[idx[where, 1]])
        p_positive = 0.5 * (1.0 + f + (1.0 - np.abs(f)) * lean)
        signs = np.where(stage_generator(root, "network", _SIGNS).uniform(size=fluxes.size) < p_positive,
                         1.0, -1.0)
        tangent = None
        if self.chain_length.to_value(u.km) > 0:
            tangent = _wall_tangents(points[where], centres[idx[where, 0]], centres[idx[where, 1]])
        flux = self._lay(where, signs * fluxes, area, inside, lat, lon, unique, r_km, tangent)
        flux += self._ephemeral(root, centres, points, area, wall, lon, lat, inside, r_km)
        network = np.zeros(field.shape)
        network[inside] = flux / area
        if not unique[-1]:
            network[:, -1] = network[:, 0]
        carried = np.where(inside, np.clip(field, -b_net, b_net), 0.0)
        return field - carried + network

    def _lay(self, at, flux, area, inside, lat, lon, unique, r_km, tangent=None):
        """Signed flux (Mx) per grid point of the region: each concentration at its point, or spread.

        ``tangent`` ((n, 2) east and north components of each concentration's wall direction) lays
        every concentration along its wall over ``chain_length`` as well.
        """
        if self.cluster_flux_density is None and tangent is None:
            return np.bincount(at, weights=flux, minlength=area.size).astype(float)
        densest = math.inf if self.cluster_flux_density is None else self.cluster_flux_density.to_value(u.G)
        plage = np.abs(flux) > densest * area[at]               # denser than plage in one cell: spread
        spread = plage if tangent is None else np.ones(flux.size, dtype=bool)   # chains: every one
        out = np.bincount(at[~spread], weights=flux[~spread], minlength=area.size).astype(float)
        if not spread.any():
            return out
        chain = self.chain_length.to_value(u.km)
        rows, cols = np.nonzero(inside)
        index = _region_index(inside)
        periodic = not unique[-1]                       # 360° with both ends: wrap over lon.size - 1
        n_lon = lon.size - 1 if periodic else lon.size
        step_lat = abs(lat[1] - lat[0]) * r_km if lat.size > 1 else math.inf
        step_lon = abs(lon[1] - lon[0]) * r_km if lon.size > 1 else math.inf
        targets, weights = [], []
        for n in np.flatnonzero(spread):
            k, phi = at[n], flux[n]
            i0, j0 = rows[k], cols[k]
            # A point across its wall: a sigma a quarter of the grid's, so that the cells its line crosses
            # take the flux (unless the plage limit spreads it wider).
            floor = 0.0 if tangent is None else 0.25 * min(step_lat, step_lon * math.cos(lat[i0]))
            sigma = max(math.sqrt(abs(phi) / (2 * math.pi * densest)) / 1e5 if plage[n] else 0.0, floor)  # km
            along = math.hypot(sigma, chain) if tangent is not None else sigma
            dx_step = max(step_lon * math.cos(lat[i0]), 1e-9)
            ki = min(int(math.ceil(3 * along / step_lat)), lat.size)
            kj = min(int(math.ceil(3 * along / dx_step)), n_lon // 2)
            di, dj = np.arange(-ki, ki + 1), np.arange(-kj, kj + 1)
            i = i0 + di
            keep_i = (i >= 0) & (i < lat.size)
            j = (j0 + dj) % n_lon if periodic else j0 + dj
            keep_j = (j >= 0) & (j < lon.size)
            i, di, j, dj = i[keep_i], di[keep_i], j[keep_j], dj[keep_j]
            target = index[i[:, None], j[None, :]]
            # The Gaussian's flux per area (local tangent plane) times each cell's area.
            north, east = (di * step_lat)[:, None], (dj * dx_step)[None, :]
            if tangent is None:
                g = np.exp(-0.5 * (north ** 2 + east ** 2) / sigma ** 2)
            else:
                te, tn = tangent[n]
                g = np.exp(-0.5 * ((east * te + north * tn) ** 2 / along ** 2
                                   + (north * te - east * tn) ** 2 / sigma ** 2))
            ok = target >= 0
            w = g[ok] * area[target[ok]]
            targets.append(target[ok])
            weights.append(phi * w / w.sum())
        # One pass over the grid for all of them, each cell's shares added in the concentrations' order.
        np.add.at(out, np.concatenate(targets), np.concatenate(weights))
        return out

    def _ephemeral(self, root, centres, points, area, wall, lon, lat, inside, r_km):
        """Signed flux (Mx) per grid point of the region: bipoles emerging inside the cells."""
        b_er = self.ephemeral_flux_density.to_value(u.G)
        flux = np.zeros(points.shape[0])
        if b_er == 0:
            return flux
        rng = stage_generator(root, "network", _EPHEMERAL)
        mean = EPHEMERAL_FLUX.to_value(u.Mx)
        n = int(rng.poisson(b_er * area.sum() / (2 * mean)))
        # Inside the cells: away from the lanes, uniform in area.
        interior = area * (1 - np.exp(-0.5 * (wall / self.lane_width.to_value(u.km)) ** 2))
        at = rng.choice(points.shape[0], size=n, p=interior / interior.sum())
        phi = rng.exponential(mean, size=n)
        angle = rng.uniform(0, 2 * math.pi, size=n)
        p = points[at]
        east = np.cross([0.0, 0.0, 1.0], p)
        east /= np.maximum(np.linalg.norm(east, axis=1), 1e-12)[:, None]
        north = np.cross(p, east)
        half = 0.5 * EPHEMERAL_SEPARATION.to_value(u.km) / r_km
        offset = half * (np.cos(angle)[:, None] * east + np.sin(angle)[:, None] * north)
        # Each footpoint to its nearest grid point of the region (uniform axes: index arithmetic).
        index = _region_index(inside)
        for sign, foot in ((1.0, p + offset), (-1.0, p - offset)):
            foot /= np.linalg.norm(foot, axis=1)[:, None]
            f_lat = np.arcsin(np.clip(foot[:, 2], -1, 1))
            f_lon = np.arctan2(foot[:, 1], foot[:, 0])
            i = np.clip(np.rint((f_lat - lat[0]) / (lat[1] - lat[0])).astype(np.int64), 0, lat.size - 1)
            j = np.clip(np.rint((f_lon - lon[0]) / (lon[1] - lon[0])).astype(np.int64), 0, lon.size - 1)
            k = index[i, j]
            keep = k >= 0
            flux += np.bincount(k[keep], weights=sign * phi[keep], minlength=flux.size).astype(float)
        return flux


def _wall_tangents(points, first, second):
    """(n, 2) east and north components of the direction along the wall between two cells at each point."""
    normal = second - first
    normal -= np.sum(normal * points, axis=1)[:, None] * points
    along = np.cross(points, normal)
    east = np.cross([0.0, 0.0, 1.0], points)
    east /= np.maximum(np.linalg.norm(east, axis=1), 1e-12)[:, None]
    north = np.cross(points, east)
    out = np.stack([np.sum(along * east, axis=1), np.sum(along * north, axis=1)], axis=1)
    return out / np.maximum(np.linalg.norm(out, axis=1), 1e-12)[:, None]


def _region_index(inside):
    """(nlat, nlon) int: each grid point's index among the region's points (row-major), -1 outside."""
    index = -np.ones(inside.shape, dtype=np.int64)
    index[inside] = np.arange(np.count_nonzero(inside))
    return index
