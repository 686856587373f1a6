"""
A seeded, periodic model photosphere: a sunspot in its quiet and active surroundings.

It stands in for the paper's MURaM snapshot (Rempel 2015: a 1e22 Mx spot with a
penumbra in a 98 Mm × 98 Mm periodic box, net positive flux) for users without
their own MHD and radiative-transfer run.  Every column gets the field vector,
plasma velocity and continuum at the height where Ni I 676.8 nm forms.  The
ingredients, with the observations their default parameters are based on:

- **Granulation** (Voronoi cells of the granule centres, mean spacing 1.2 Mm;
  Bahng & Schwarzschild 1961, Hirzberger et al. 1997): bright upflows in
  the cell interiors, dark narrow downflow lanes, horizontal outflow from the
  cell centres; RMS continuum contrast 8 % (Hinode/SOT 7 %, DKIST 7.4 %, MURaM
  ~10-14 % at full resolution), RMS vertical velocity 1.0 km/s and horizontal
  1.5 km/s near the Ni I formation height (~200 km; Nordlund et al. 2009).
- **Supergranulation** (cells of 25 Mm, 0.3 km/s outflow; Rieutord & Rincon
  2010) whose boundaries collect the **network**: kG flux elements (1.5 kG
  cores; Stenflo 1973, Solanki 1993) with a power-law flux distribution
  N(Φ) ∝ Φ^-1.85 between 1e17 and 1e19 Mx (Parnell et al. 2009) sitting in
  intergranular lanes, both polarities, 8 G mean unsigned flux density.
- **Plage**: two patches of densely packed kG elements (200 G mean flux
  density, mostly one polarity each; negative and positive), with suppressed
  ("abnormal") granulation and bright points.
- **Internetwork**: mixed-polarity, sub-Mm (0.3 Mm) fields in the lanes, RMS
  B_z 25 G and horizontal field 60 G (Lites et al. 2008: horizontal ≈ 5×
  vertical flux density at 0.3″), cancelling in a GONG pixel.
- **Sunspot** at the box centre, positive polarity (Borrero & Ichimoto 2011):
  umbra radius 7 Mm, 3 kG at its centre, 0-40° inclination, continuum 0.25;
  penumbra to 16 Mm (total flux ≈ 1e22 Mx like Rempel 2015) with filaments:
  spines (stronger, 40-65°) and intraspines (weaker, 55-100°: field returning
  below the surface at the outer edge) carrying the Evershed outflow (2 km/s
  along the field), continuum 0.8 on average; moat outflow (0.8 km/s) around.

Fine structure is computed on an internal grid of at most ~100 km (and at
least 512 columns a side when the output is coarse) and block-averaged to
``pixel_size``: field components and velocities are area averages, so fluxes
are right whatever the sampling.
"""
from __future__ import annotations

import math

import astropy.units as u
import numpy as np
import scipy.fft

from gongsynth.seeding import as_seed_sequence, stage_generator
from gongsynth.sun.photosphere.columns import Photosphere
from gongsynth.sun.photosphere.voronoi import random_cells
from gongsynth.validation import check_scalar

__all__ = ["model_photosphere"]

# Sub-streams of the "photosphere" stage: each ingredient has its own, so that
# switching one off does not change the others.
_GRANULES, _SUPERGRANULES, _NETWORK, _PLAGE, _INTERNETWORK, _PENUMBRA = range(6)

_FINE_KM = 100.0          # target internal resolution
_MIN_INTERNAL = 512       # columns a side of the internal grid when the output is coarse
_ELEMENT_SCALE_KM = 100.0  # fanning-out length of flux elements: B_h = -l grad B_z
_SATURATION_G = 2200.0    # soft cap of the summed element field in dense plage


class _Grid:
    """Periodic internal grid: spacing, coordinates and Fourier helpers (threaded, same bits as numpy.fft)."""

    def __init__(self, ny, nx, dx):
        self.ny, self.nx, self.dx = ny, nx, dx
        self.Ly, self.Lx = ny * dx, nx * dx
        self.ky = np.fft.fftfreq(ny, d=dx)[:, None]
        self.kx = np.fft.rfftfreq(nx, d=dx)[None, :]
        self.k2 = self.kx ** 2 + self.ky ** 2

    def coords(self):
        y = (np.arange(self.ny) + 0.5) * self.dx
        x = (np.arange(self.nx) + 0.5) * self.dx
        return y[:, None], x[None, :]

    def offset(self, xc, yc):
        """Periodic (minimum-image) offsets x - xc, y - yc, in km."""
        y, x = self.coords()
        dx = (x - xc + self.Lx / 2) % self.Lx - self.Lx / 2
        dy = (y - yc + self.Ly / 2) % self.Ly - self.Ly / 2
        return dx, dy

    def smooth(self, field, sigma_km):
        """Gaussian smoothing (periodic, flux-conserving)."""
        f = scipy.fft.rfft2(field, workers=-1)
        f *= np.exp(-2 * math.pi ** 2 * sigma_km ** 2 * self.k2)
        return scipy.fft.irfft2(f, s=(self.ny, self.nx), workers=-1)

    def gradient(self, field):
        """(d/dx, d/dy) per km, spectrally."""
        f = scipy.fft.rfft2(field, workers=-1)
        gx = scipy.fft.irfft2(2j * math.pi * self.kx * f, s=(self.ny, self.nx), workers=-1)
        gy = scipy.fft.irfft2(2j * math.pi * self.ky * f, s=(self.ny, self.nx), workers=-1)
        return gx, gy

    def noise(self, rng, sigma_km, balanced=False):
        """
        Zero-mean, unit-variance Gaussian random field of correlation ~sigma_km.

        ``balanced``: band-pass instead of low-pass (spectrum ∝ k² e^{-2π²σ²k²}),
        so that the field has no power at large scales: flux balances within a
        few σ, like mixed-polarity internetwork field.
        """
        g = rng.standard_normal((self.ny, self.nx))
        f = scipy.fft.rfft2(g, workers=-1)
        f *= np.exp(-2 * math.pi ** 2 * sigma_km ** 2 * self.k2)
        if balanced:
            f *= 2 * math.pi ** 2 * sigma_km ** 2 * self.k2
        g = scipy.fft.irfft2(f, s=(self.ny, self.nx), workers=-1)
        g -= g.mean()
        return g / (g.std() or 1.0)


def _standardise(a):
    a = a - a.mean()
    return a / (a.std() or 1.0)


def _power_law_fluxes(rng, total, lo=1e17, hi=1e19, index=1.85):
    """Element fluxes (Mx) from N(Φ) ∝ Φ^-index on [lo, hi] adding up to ~total."""
    a = 1.0 - index

    def draw(n):
        q = rng.uniform(size=n)
        return (lo ** a + q * (hi ** a - lo ** a)) ** (1.0 / a)

    mean = draw(20000).mean()
    fluxes = draw(max(1, int(round(total / mean))))
    return fluxes


def _render_elements(grid, rng, weight, fluxes, signs, core_field):
    """
    Flux elements as Gaussians of flux Φ and peak ≈ core_field, placed with probability ∝ weight.

    Returns B_z (G) on the grid; the flux of every element is conserved.
    """
    bz = np.zeros((grid.ny, grid.nx))
    if fluxes.size == 0:
        return bz
    p = weight.ravel() / weight.sum()
    where = rng.choice(p.size, size=fluxes.size, p=p)
    pixel_area = (grid.dx * 1e5) ** 2                        # cm²
    sigma = np.sqrt(fluxes / (2 * math.pi * core_field)) / 1e5   # km
    sigma = np.maximum(sigma, 0.6 * grid.dx)
    # Size classes a factor 1.25 apart: one FFT convolution per class.
    cls = np.floor(np.log(sigma / sigma.min()) / np.log(1.25)).astype(int)
    for c in np.unique(cls):
        sel = cls == c
        deposit = np.zeros(grid.ny * grid.nx)
        np.add.at(deposit, where[sel], signs[sel] * fluxes[sel] / pixel_area)
        bz += grid.smooth(deposit.reshape(grid.ny, grid.nx), float(np.sqrt(np.mean(sigma[sel] ** 2))))
    return bz


def _spot(grid, rng, *, xc, yc, r_umbra, r_penumbra, b_umbra, b_penumbra, i_umbra, i_penumbra,
          v_evershed, v_moat):
    """Sunspot fields: B, inclination, azimuth, velocity components, continuum and mask."""
    dx, dy = grid.offset(xc, yc)
    r = np.hypot(dx, dy)
    theta = np.arctan2(dy, dx)
    cos_t, sin_t = np.cos(theta), np.sin(theta)
    # Penumbral filaments: a random field in (r, theta), long in r, narrow in theta.
    n_r, n_t = 96, 2048
    r_max = 1.2 * r_penumbra
    r_mid = 0.5 * (r_umbra + r_penumbra)
    fil = rng.standard_normal((n_r, n_t))
    f = np.fft.rfft(fil, axis=1)
    k_t = np.fft.rfftfreq(n_t, d=2 * math.pi / n_t)                 # cycles per radian
    width_rad = 120.0 / r_mid                                        # ~0.3 Mm wide filaments
    f *= np.exp(-2 * math.pi ** 2 * width_rad ** 2 * k_t ** 2)[None, :]
    fil = np.fft.irfft(f, n=n_t, axis=1)
    kr = np.fft.rfftfreq(n_r, d=r_max / n_r)
    fil = np.fft.irfft(np.fft.rfft(fil, axis=0) * np.exp(-2 * math.pi ** 2 * 1500.0 ** 2 * kr ** 2)[:, None],
                       n=n_r, axis=0)
    fil = _standardise(fil)
    # Bilinear lookup (periodic in theta) for the columns inside r_max.
    inside = r < r_max
    ri = np.clip(r[inside] / r_max * n_r - 0.5, 0, n_r - 1.0001)
    ti = ((theta[inside] + math.pi) / (2 * math.pi) * n_t) % n_t
    r0, t0 = ri.astype(int), ti.astype(int)
    fr, ft = ri - r0, ti - t0
    t1 = (t0 + 1) % n_t
    r1 = np.minimum(r0 + 1, n_r - 1)
    val = ((1 - fr) * ((1 - ft) * fil[r0, t0] + ft * fil[r0, t1])
           + fr * ((1 - ft) * fil[r1, t0] + ft * fil[r1, t1]))
    s = np.zeros_like(r)                                             # intraspine fraction
    s[inside] = 1.0 / (1.0 + np.exp(-val / 0.35))
    q = np.clip((r - r_umbra) / (r_penumbra - r_umbra), 0.0, 1.0)   # 0..1 across the penumbra
    w_umbra = 0.5 * (1 - np.tanh((r - r_umbra) / 300.0))
    mask = 0.5 * (1 - np.tanh((r - r_penumbra) / 500.0))             # the whole spot
    # Umbra: 3 kG at the centre, 0.7 of it and 40 deg at the edge.
    rho = np.minimum(r / r_umbra, 1.2)
    b_u = b_umbra * (1 - 0.3 * rho ** 2)
    g_u = 40.0 * rho ** 2
    # Penumbra: spines / intraspines around a mean field falling 1.35 -> 0.65 of b_penumbra.
    b_p = b_penumbra * (1.35 - 0.7 * q) * (1.15 - 0.3 * s)
    g_spine = 40.0 + 25.0 * q
    g_intra = 55.0 + 45.0 * q
    g_p = g_spine * (1 - s) + g_intra * s
    strength = mask * (w_umbra * b_u + (1 - w_umbra) * b_p)
    incl = np.radians(w_umbra * g_u + (1 - w_umbra) * g_p)
    bh = strength * np.sin(incl)
    bx, by, bz = bh * cos_t, bh * sin_t, strength * np.cos(incl)
    # Evershed flow along the intraspine field, growing outward, ending at the edge.
    v_e = v_evershed * s * np.sqrt(q) * (1 - w_umbra) * mask
    g_i = np.radians(g_intra)
    v_r = v_e * np.sin(g_i)
    v_z = v_e * np.cos(g_i)
    # Moat flow: outward, peaking just outside the spot, decaying over ~0.8 R.
    out = np.maximum(r - r_penumbra, 0.0)
    v_r = v_r + v_moat * (1 - mask) * np.exp(-out / (0.8 * r_penumbra)) * np.minimum(out / 1000.0, 1.0)
    cont_p = i_penumbra * (0.85 + 0.3 * s)
    # Umbra darkest at the centre, with umbral dots (~0.25 Mm, +60 %) mostly in its outer part.
    n_dots = int(rng.poisson(3e-6 * math.pi * r_umbra ** 2))
    rr = r_umbra * np.sqrt(rng.uniform(0.05, 0.95, n_dots))
    tt = rng.uniform(0, 2 * math.pi, n_dots)
    deposit = np.zeros((grid.ny, grid.nx))
    iy = ((yc + rr * np.sin(tt)) / grid.dx).astype(int) % grid.ny
    ix = ((xc + rr * np.cos(tt)) / grid.dx).astype(int) % grid.nx
    np.add.at(deposit, (iy, ix), 1.0)
    sigma_dot = max(100.0, 0.6 * grid.dx)
    dots = grid.smooth(deposit, sigma_dot) * (2 * math.pi * sigma_dot ** 2 / grid.dx ** 2)
    cont_u = i_umbra * (0.8 + 0.4 * np.minimum(rho, 1) ** 2) * (1 + 0.6 * np.minimum(dots, 1.5))
    continuum = w_umbra * cont_u + (1 - w_umbra) * cont_p
    return dict(bx=bx, by=by, bz=bz, vx=v_r * cos_t, vy=v_r * sin_t, vz=v_z,
                continuum=continuum, mask=mask, r=r)


def _block_mean(a, k):
    if k == 1:
        return a
    ny, nx = a.shape
    return a.reshape(ny // k, k, nx // k, k).mean(axis=(1, 3))




def _fraction(value, name):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 <= value <= 2:
        raise ValueError(f"{name} must be a number in [0, 2], got {value!r}")
    return float(value)


def model_photosphere(*, shape=(1024, 1024), pixel_size=96 * u.km, seed=0, spot=True,
                      umbra_radius=7 * u.Mm, penumbra_radius=16 * u.Mm, umbra_field=3000 * u.G,
                      penumbra_field=1500 * u.G, umbra_continuum=0.25, penumbra_continuum=0.8,
                      evershed_speed=2.0 * u.km / u.s, moat_speed=0.8 * u.km / u.s,
                      granule_size=1.2 * u.Mm, granulation_contrast=0.08,
                      granulation_velocity=1.0 * u.km / u.s, horizontal_velocity=1.5 * u.km / u.s,
                      supergranule_size=25 * u.Mm, network_flux_density=8 * u.G, network_polarity=0.55,
                      plage=True,
                      plage_flux_density=200 * u.G, element_field=1500 * u.G,
                      internetwork_field=25 * u.G, internetwork_horizontal_field=60 * u.G):
    """
    The built-in photosphere: a periodic box with a sunspot, plage, network and quiet Sun.

    The defaults give a 98.3 Mm × 98.3 Mm box at 96 km (1024²), like the
    paper's MURaM snapshot binned to 96 km; the module docstring lists the
    ingredients and the observations behind each default.  The result depends
    only on the arguments and ``seed``.

    Parameters
    ----------
    shape : tuple of int, optional
        (ny, nx) columns (default (1024, 1024)).
    pixel_size : `~astropy.units.Quantity`, optional
        Column size (length; default 96 km).  A coarse grid of the same box,
        e.g. ``shape=(128, 128), pixel_size=768 * u.km``, is cheap and keeps
        area-averaged fields right.
    seed : int, `numpy.random.SeedSequence` or `numpy.random.Generator`, optional
        Randomness (default 0: the default photosphere is always the same).
    spot : bool, optional
        Include the sunspot (at the box centre); it must fit in the box.
    umbra_radius, penumbra_radius : `~astropy.units.Quantity`, optional
        Radii of the umbra (7 Mm) and of the spot's outer edge (16 Mm).
    umbra_field : `~astropy.units.Quantity`, optional
        Field strength at the umbral centre (3000 G).
    penumbra_field : `~astropy.units.Quantity`, optional
        Mean penumbral field strength at mid-penumbra (1500 G).
    umbra_continuum, penumbra_continuum : float, optional
        Continuum relative to the quiet Sun (0.25, 0.8).
    evershed_speed : `~astropy.units.Quantity`, optional
        Peak Evershed flow along intraspine field lines (2 km/s).
    moat_speed : `~astropy.units.Quantity`, optional
        Peak moat outflow around the spot (0.8 km/s).
    granule_size : `~astropy.units.Quantity`, optional
        Mean spacing of granule centres (1.2 Mm).
    granulation_contrast : float, optional
        RMS continuum contrast of quiet granulation (0.08).
    granulation_velocity, horizontal_velocity : `~astropy.units.Quantity`, optional
        RMS vertical (1.0 km/s) and horizontal (1.5 km/s) granular velocities.
    supergranule_size : `~astropy.units.Quantity`, optional
        Mean spacing of supergranule centres (25 Mm); the network lies on their edges.
    network_flux_density : `~astropy.units.Quantity`, optional
        Mean unsigned flux density of network elements over the box (8 G).
    network_polarity : float, optional
        Fraction of the network elements with positive polarity (0.55: the
        box's slight net positive flux; 0.5 balanced, 0.9 a unipolar
        enhanced network or plage).
    plage : bool, optional
        Include the two plage patches.
    plage_flux_density : `~astropy.units.Quantity`, optional
        Mean unsigned flux density within a plage patch (200 G).
    element_field : `~astropy.units.Quantity`, optional
        Core field strength of network and plage flux elements (1500 G).
    internetwork_field, internetwork_horizontal_field : `~astropy.units.Quantity`, optional
        RMS vertical (25 G) and horizontal (60 G) internetwork field.

    Returns
    -------
    `~gongsynth.sun.photosphere.Photosphere`
        Periodic; ``meta`` holds the parameters and the seed entropy.

    Raises
    ------
    ValueError
        For non-positive sizes, a spot that does not fit in the box, or
        parameters outside their ranges.

    Examples
    --------
    >>> import astropy.units as u
    >>> ph = model_photosphere(shape=(64, 64), pixel_size=1536 * u.km)   # the same 98 Mm box
    >>> ph
    <Photosphere 64×64 columns of 1536 km (98.3×98.3 Mm, periodic)>
    >>> bool(ph.bz.max() > 2000 * u.G), bool(ph.bz.mean() > 0 * u.G)   # a spot; net positive flux
    (True, True)
    """
    if (not isinstance(shape, (tuple, list)) or len(shape) != 2
            or not all(isinstance(n, (int, np.integer)) and n >= 8 for n in shape)):
        raise ValueError(f"shape must be two ints >= 8 (ny, nx), got {shape!r}")
    ny, nx = (int(n) for n in shape)
    px = check_scalar(pixel_size, u.km, "pixel_size")
    r_u = check_scalar(umbra_radius, u.km, "umbra_radius")
    r_p = check_scalar(penumbra_radius, u.km, "penumbra_radius")
    b_u = check_scalar(umbra_field, u.G, "umbra_field")
    b_p = check_scalar(penumbra_field, u.G, "penumbra_field")
    v_e = check_scalar(evershed_speed, u.km / u.s, "evershed_speed", positive=False)
    v_m = check_scalar(moat_speed, u.km / u.s, "moat_speed", positive=False)
    gran = check_scalar(granule_size, u.km, "granule_size")
    v_g = check_scalar(granulation_velocity, u.km / u.s, "granulation_velocity", positive=False)
    v_h = check_scalar(horizontal_velocity, u.km / u.s, "horizontal_velocity", positive=False)
    sg = check_scalar(supergranule_size, u.km, "supergranule_size")
    net = check_scalar(network_flux_density, u.G, "network_flux_density", positive=False)
    plage_b = check_scalar(plage_flux_density, u.G, "plage_flux_density", positive=False)
    b_el = check_scalar(element_field, u.G, "element_field")
    in_v = check_scalar(internetwork_field, u.G, "internetwork_field", positive=False)
    in_h = check_scalar(internetwork_horizontal_field, u.G, "internetwork_horizontal_field", positive=False)
    polarity = _fraction(network_polarity, "network_polarity")
    if polarity > 1:
        raise ValueError(f"network_polarity must be a number in [0, 1], got {network_polarity!r}")
    i_u = _fraction(umbra_continuum, "umbra_continuum")
    i_p = _fraction(penumbra_continuum, "penumbra_continuum")
    contrast = _fraction(granulation_contrast, "granulation_contrast")
    if spot and r_u >= r_p:
        raise ValueError(f"umbra_radius ({umbra_radius}) must be smaller than "
                         f"penumbra_radius ({penumbra_radius})")
    box = (ny * px, nx * px)
    if spot and 2.2 * r_p > min(box):
        raise ValueError(
            f"the spot (penumbra_radius {penumbra_radius}) does not fit in the {box[1] / 1e3:.1f} × "
            f"{box[0] / 1e3:.1f} Mm box: make the box larger than 2.2 × penumbra_radius, or pass spot=False"
        )

    root = as_seed_sequence(seed)      # draw once from a Generator; every stream derives from it
    # Internal grid: ~100 km, at least _MIN_INTERNAL columns a side when the output is coarse.
    sub = max(1, min(math.ceil(px / _FINE_KM), max(1, _MIN_INTERNAL // min(ny, nx))))
    grid = _Grid(ny * sub, nx * sub, px / sub)
    shape_int = (grid.ny, grid.nx)

    # ---- granulation: bright upflowing cell interiors, dark downflowing lanes
    rng = stage_generator(root, "photosphere", _GRANULES)
    wall, centre, cell, n_cells = random_cells(grid, rng, gran)
    amplitude = rng.lognormal(0.0, 0.25, n_cells)
    # Brightest at the cell centre, flat-topped, dropping steeply into the lanes.
    profile = 1.0 - (centre / (centre + wall)) ** 3
    # Smoothing rounds the Voronoi polygons and gives the lanes a finite width.
    g = grid.smooth(amplitude[cell] * profile, 0.07 * gran)
    lanes = np.exp(-wall / (0.1 * gran))                  # 1 in the lanes, 0 in granule centres
    # Lanes are narrow and fast: a log-normal transform puts ~60 % of the area in
    # (slower) upflows and the extremes in the downflows and dark lanes.
    g = _standardise(g)
    g_int = _standardise(-np.exp(-0.4 * _standardise(g + 0.2 * grid.noise(rng, 0.25 * gran))))
    g_vel = _standardise(-np.exp(-0.6 * _standardise(g + 0.6 * grid.noise(rng, 0.25 * gran))))
    gx, gy = grid.gradient(grid.smooth(g, 0.1 * gran))
    scale_h = np.sqrt(np.mean(gx ** 2 + gy ** 2)) or 1.0
    vx_g, vy_g = -v_h * gx / scale_h, -v_h * gy / scale_h
    vz_g = v_g * g_vel
    cont_g = 1.0 + contrast * g_int
    del g, g_int, g_vel, gx, gy, wall, centre, cell, profile

    # ---- supergranulation and network
    rng = stage_generator(root, "photosphere", _SUPERGRANULES)
    sg_wall, _, sg_cell, _ = random_cells(grid, rng, sg)
    sgx, sgy = grid.gradient(grid.smooth(-np.exp(-sg_wall / (0.15 * sg)), 0.05 * sg))
    norm = np.sqrt(np.mean(sgx ** 2 + sgy ** 2)) or 1.0
    vx_g -= 0.3 * sgx / norm          # 0.3 km/s outflow from the supergranule centres
    vy_g -= 0.3 * sgy / norm
    network_weight = np.exp(-0.5 * (sg_wall / 2000.0) ** 2) * (0.05 + lanes)
    del sgx, sgy, sg_cell

    # ---- the spot (or nothing)
    if spot:
        sp = _spot(grid, stage_generator(root, "photosphere", _PENUMBRA), xc=grid.Lx / 2,
                   yc=grid.Ly / 2, r_umbra=r_u, r_penumbra=r_p, b_umbra=b_u, b_penumbra=b_p,
                   i_umbra=i_u, i_penumbra=i_p, v_evershed=v_e, v_moat=v_m)
        spot_mask = sp["mask"]
        keep_out = 0.5 * (1 + np.tanh((sp["r"] - r_p - 1500.0) / 500.0))  # no elements on the spot
    else:
        zeros = np.zeros(shape_int)
        sp = dict(bx=zeros, by=zeros, bz=zeros, vx=zeros, vy=zeros, vz=zeros, continuum=zeros)
        spot_mask = zeros
        keep_out = np.ones(shape_int)

    # ---- network elements: both polarities, slightly more positive
    rng = stage_generator(root, "photosphere", _NETWORK)
    area = grid.Lx * grid.Ly * 1e10                                      # cm²
    fluxes = _power_law_fluxes(rng, net * area)
    signs = np.where(rng.uniform(size=fluxes.size) < polarity, 1.0, -1.0)
    bz_el = _render_elements(grid, rng, network_weight * keep_out, fluxes, signs, b_el)

    # ---- plage: a negative and a positive patch of dense elements
    plage_cover = np.zeros(shape_int)
    if plage:
        rng = stage_generator(root, "photosphere", _PLAGE)
        patches = ((0.2, 0.75, 0.10, -1.0), (0.8, 0.22, 0.07, 1.0))    # (x, y, radius) / box, polarity
        for fx, fy, fr, polarity in patches:
            radius = fr * min(grid.Lx, grid.Ly)
            ox, oy = grid.offset(fx * grid.Lx, fy * grid.Ly)
            env = np.exp(-0.5 * (ox ** 2 + oy ** 2) / (0.6 * radius) ** 2) * keep_out
            plage_cover = np.maximum(plage_cover, env)
            total = plage_b * math.pi * (radius * 1e5) ** 2
            fl = _power_law_fluxes(rng, total, lo=1e17, hi=1e19)
            sg_ = np.where(rng.uniform(size=fl.size) < 0.9, polarity, -polarity)
            bz_el += _render_elements(grid, rng, env * (0.1 + lanes), fl, sg_, b_el)
    # Soft saturation where elements pile up (flux tubes do not exceed ~2 kG at tau = 1).
    bz_el = bz_el / (1 + (np.abs(bz_el) / _SATURATION_G) ** 4) ** 0.25
    bx_el, by_el = grid.gradient(bz_el)
    bx_el *= -_ELEMENT_SCALE_KM
    by_el *= -_ELEMENT_SCALE_KM

    # ---- internetwork: mixed polarity, sub-Mm, in the lanes, weak
    rng = stage_generator(root, "photosphere", _INTERNETWORK)
    quiet = (1 - spot_mask) * (1 - plage_cover)
    corr = max(300.0, 0.5 * grid.dx)
    w_in = (0.4 + 0.6 * lanes) * quiet
    bz_in = grid.noise(rng, corr, balanced=True) * w_in
    bz_in *= in_v / (np.sqrt(np.mean(bz_in ** 2)) or 1.0) * math.sqrt(np.mean(quiet))
    bx_in = grid.noise(rng, corr, balanced=True) * quiet * in_h / math.sqrt(2)
    by_in = grid.noise(rng, corr, balanced=True) * quiet * in_h / math.sqrt(2)

    # ---- combine: convection suppressed by strong field (spot, plage)
    magnetic = grid.smooth(np.abs(bz_el), 500.0)
    convection = 1 - 0.6 * np.clip(magnetic / 600.0, 0, 1)      # abnormal granulation in plage
    suppress = (1 - spot_mask) * convection
    bright_points = 0.15 * np.clip(np.abs(bz_el) / b_el, 0, 1)
    quiet_continuum = 1 + (cont_g - 1) * convection + bright_points
    comps = dict(
        bx=sp["bx"] + (bx_el + bx_in) * (1 - spot_mask),
        by=sp["by"] + (by_el + by_in) * (1 - spot_mask),
        bz=sp["bz"] + (bz_el + bz_in) * (1 - spot_mask),
        vx=sp["vx"] + vx_g * suppress,
        vy=sp["vy"] + vy_g * suppress,
        vz=sp["vz"] + vz_g * suppress,
        continuum=spot_mask * sp["continuum"] + (1 - spot_mask) * quiet_continuum,
    )
    comps = {k: _block_mean(v, sub) for k, v in comps.items()}
    comps["continuum"] = np.maximum(comps["continuum"], 0.0)
    meta = {
        "origin": "gongsynth.sun.photosphere.model_photosphere",
        "seed_entropy": str(root.entropy),
        "internal_pixel_km": grid.dx,
        "params": {
            "shape": [ny, nx], "pixel_size_km": px, "spot": bool(spot), "umbra_radius_km": r_u,
            "penumbra_radius_km": r_p, "umbra_field_G": b_u, "penumbra_field_G": b_p,
            "umbra_continuum": i_u, "penumbra_continuum": i_p, "evershed_speed_km_s": v_e,
            "moat_speed_km_s": v_m, "granule_size_km": gran, "granulation_contrast": contrast,
            "granulation_velocity_km_s": v_g, "horizontal_velocity_km_s": v_h,
            "supergranule_size_km": sg, "network_flux_density_G": net, "network_polarity": polarity,
            "plage": bool(plage),
            "plage_flux_density_G": plage_b, "element_field_G": b_el, "internetwork_field_G": in_v,
            "internetwork_horizontal_field_G": in_h,
        },
    }
    kms = u.km / u.s
    return Photosphere.from_components(
        comps["bx"] * u.G, comps["by"] * u.G, comps["bz"] * u.G, comps["vx"] * kms, comps["vy"] * kms,
        comps["vz"] * kms, comps["continuum"], px * u.km, periodic=True, meta=meta)


