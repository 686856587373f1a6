"""
`synthesize`: LTE Stokes synthesis of a spectral line (Ni I 676.78 nm, Fe I 617.33 nm), Atmosphere → Stokes.

Work is done in blocks of output rows (about `BLOCK_COLUMNS` rays at a time):
sample every field along the block's rays (`~gongsynth.sun.rt.rays`), compute
the opacities per point (`~gongsynth.sun.rt.opacity`: from its (T, P) table
for T and P atmospheres, else after completing the thermodynamic state with
`~gongsynth.sun.rt.eos`), solve the transfer equation per ray and
wavelength (`~gongsynth.sun.rt.kernels`) and take the truth
(`~gongsynth.sun.rt.truth`).  Memory besides the output: ~20 float64 values
per ray point of one block (~30 MB for 100 heights), never the whole opacity cube.
"""
from __future__ import annotations

import astropy.units as u
import numpy as np

from gongsynth.geometry import check_geometry, los_basis
from gongsynth.sun.rt.atomic_data import get_line
from gongsynth.sun.rt.eos import solve_state
from gongsynth.sun.rt.kernels import solve_columns
from gongsynth.sun.rt.opacity import column_opacity, line_constants, tabulated_opacity
from gongsynth.sun.rt.rays import ray_offsets, rays_are_vertical, sample_rays
from gongsynth.sun.rt.truth import los_field_at_depth, truth_definition
from gongsynth.sun.stokes import RADIANCE_UNIT, StokesCube
from gongsynth.validation import check_wavelength_grid

__all__ = ["synthesize", "reference_height", "default_wavelength", "BLOCK_COLUMNS", "WINDOW_HALF_WIDTH",
           "WINDOW_POINTS"]

#: Rays per block.
BLOCK_COLUMNS = 8192


#: Half width (nm) and points of the default wavelength grid: the paper's 51 points over ±0.05 nm.
WINDOW_HALF_WIDTH = 0.05
WINDOW_POINTS = 51


def default_wavelength(line=None):
    """
    The default spectral grid of a line: `WINDOW_POINTS` air wavelengths, ±`WINDOW_HALF_WIDTH` nm about it.

    For Ni I 676.78 nm this is the paper's grid, 676.73–676.83 nm in 2 pm steps.

    Parameters
    ----------
    line : str or `~gongsynth.sun.rt.atomic_data.LineData`, optional
        Default ``"Ni I 676.8"``.

    Returns
    -------
    `~astropy.units.Quantity`
        nm.

    Examples
    --------
    >>> w = default_wavelength("Fe I 617.3")
    >>> w.size, round(float(w[25].value), 5)
    (51, 617.33433)
    """
    lam0 = get_line(line).wavelength_nm
    # Rounded ends: the paper's grid bit for bit for Ni (676.78 - 0.05 is not 676.73 in floating point).
    return np.linspace(round(lam0 - WINDOW_HALF_WIDTH, 9), round(lam0 + WINDOW_HALF_WIDTH, 9),
                       WINDOW_POINTS) * u.nm


def _opacity(atm, sample, vturb, const, pf):
    """
    (ncol, nz) κ_c, κ_L, Δλ_D, a, B_λ of a block's points (`~gongsynth.sun.rt.opacity.column_opacity`).

    An atmosphere of T and P_gas only (the 3-D Sun) takes them from the (T, P) table of
    `~gongsynth.sun.rt.opacity.tabulated_opacity`; with ρ or n_e the state is solved per point.
    """
    temp = sample("temperature")
    out = [np.empty(temp.shape) for _ in range(5)]
    rho = sample("density") if atm.raw("density") is not None else None
    ne = sample("electron_density") if atm.raw("electron_density") is not None else None
    p = sample("gas_pressure") if atm.raw("gas_pressure") is not None and rho is None else None
    if rho is None and ne is None and p is not None:
        tabulated_opacity(temp, p, vturb, const, pf, *out)
        return out
    st = solve_state(temp, gas_pressure=p, density=rho, electron_density_=ne)
    ne, nh = (np.ascontiguousarray(st[k]) for k in ("electron_density", "hydrogen_density"))
    column_opacity(temp, ne, nh, vturb, const, pf, *out)
    return out


def reference_height(atmosphere, line=None, max_columns=4096):
    """
    Mean height (km) of continuum optical depth 1 at the line along the vertical.

    Parameters
    ----------
    atmosphere : `~gongsynth.Atmosphere`
    line : str or `~gongsynth.sun.rt.atomic_data.LineData`, optional
        The continuum is taken at its wavelength (default ``"Ni I 676.8"``).
    max_columns : int
        Columns used (a regular subsample of the box).

    Returns
    -------
    float
        km.
    """
    line = get_line(line)
    nz, ny, nx = atmosphere.shape
    step = max(1, int(np.ceil(np.sqrt(ny * nx / max_columns))))
    rows = np.arange(0, ny, step, dtype=np.int64)
    zero = np.zeros(nz)
    cols = np.arange(0, nx, step)

    def sample(name):
        out = np.empty((rows.size * nx, nz))
        sample_rays(atmosphere.raw(name), rows, zero, zero, out)
        return out.reshape(rows.size, nx, nz)[:, cols].reshape(-1, nz)

    const, pf = line_constants(line)
    k = _opacity(atmosphere, sample, np.zeros((rows.size * cols.size, nz)), const, pf)[0]
    z = atmosphere.z.to_value(u.cm)
    seg = 0.5 * (k[:, 1:] + k[:, :-1]) * np.diff(z)
    tau = np.concatenate([np.cumsum(seg[:, ::-1], axis=1)[:, ::-1], np.zeros((k.shape[0], 1))], axis=1)
    x = -np.log10(np.maximum(tau, 1e-30))                 # increases upward; the height where it is 0
    above = np.argmax(x >= 0.0, axis=1)
    lo = np.maximum(above - 1, 0)
    rr = np.arange(x.shape[0])
    x0, x1 = x[rr, lo], x[rr, above]
    w = np.where(x1 > x0, (0.0 - x0) / np.where(x1 > x0, x1 - x0, 1.0), 0.0)
    heights = np.where(x[:, 0] >= 0.0, z[0], z[lo] + w * (z[above] - z[lo]))
    return float(np.mean(heights)) * 1e-5


@u.quantity_input(azimuth=u.deg)
def synthesize(atmosphere, *, mu=1.0, azimuth=0 * u.deg, wavelength=None, truth="paper", progress=True,
               line=None, rays="inclined", anchor_height=None):
    """
    Polarised LTE synthesis of a spectral line along (inclined) rays through an Atmosphere.

    Parameters
    ----------
    atmosphere : `~gongsynth.Atmosphere`
        The model (horizontally periodic).
    mu : float, optional
        cos θ of the viewing angle, in (0, 1] (default 1, disk centre).
    azimuth : `~astropy.units.Quantity`, optional
        Line-of-sight azimuth of the observer direction from +x toward +y (the
        ``los_azimuth`` of `gongsynth.geometry`; the pipeline's region north of
        disk centre is −90°).  Default 0°.
    wavelength : `~astropy.units.Quantity`, optional
        Air wavelengths (default `default_wavelength` of the line: 51 points
        over ±0.05 nm, for Ni I the paper's 676.73–676.83 nm).
    truth : str or `~astropy.units.Quantity`, optional
        ``"paper"`` (default, for every line: B·n at τ_c = 1 along the ray +
        175 km, ±75 km mean, τ_c the continuum at the line's own wavelength),
        ``"tau0.1"``, ``"core"`` (the line's own formation height: B·n where
        the optical depth at its rest wavelength along the ray is 1) or a
        height; see `gongsynth.sun.rt.truth`.
    progress : bool, optional
        Show a progress bar over blocks of rays.
    line : str or `~gongsynth.sun.rt.atomic_data.LineData`, optional
        A name of `~gongsynth.sun.rt.atomic_data.LINES` (``"Ni I 676.8"``,
        the default, or ``"Fe I 617.3"``) or atomic data.  Each named line
        carries its measured effective Landé factor (Ni I 1.426, Fe I 2.5);
        the paper's Ni I synthesis used 1.5:
        ``line=NiLineData(lande_g=1.5)``.
    rays : {"inclined", "vertical"}, optional
        ``"inclined"`` (default): each ray crosses the 3-D box along the line
        of sight.  ``"vertical"``: each ray stays inside its own column, read
        as a plane-parallel atmosphere seen at ``mu`` (the 1.5-D
        approximation: path lengths dz/μ and the field projected on the line
        of sight as before, but no crossing of neighbouring structure) — an
        ablation, to measure what the inclined rays do.
    anchor_height : `~astropy.units.Quantity`, optional
        Height where the inclined rays cross their pixel centres (default:
        `reference_height` of this atmosphere, the mean τ_c = 1 height).  A
        block of a larger box passes the whole box's, so that its rays sample
        the same points as in the whole box.

    Returns
    -------
    `~gongsynth.StokesCube`
        (ny, nx, nλ) I, Q, U, V in erg s⁻¹ cm⁻² sr⁻¹ cm⁻¹ on the atmosphere's
        horizontal grid (each pixel holds the ray crossing the mean τ_c = 1
        height above its centre), ``mu``, ``blos`` = the truth, ``meta``.

    Examples
    --------
    >>> import numpy as np, astropy.units as u
    >>> import gongsynth
    >>> from gongsynth.sun.rt.hydrostatic import hydrostatic_tau_scale
    >>> lt = np.linspace(1.4, -4, 55)
    >>> t = 4400 + 2100 * (lt + 4) / 4                    # a crude photosphere T(log tau)
    >>> z, p, rho = hydrostatic_tau_scale(lt, t)
    >>> col = lambda a: a[:, None, None] * np.ones((1, 1, 2))
    >>> atm = gongsynth.Atmosphere(col(t) * u.K, z * u.km, 96 * u.km,
    ...                            gas_pressure=col(p) * u.Unit("dyn cm-2"))
    >>> cube = gongsynth.rt.synthesize(atm, progress=False)
    >>> cube.shape, bool((cube.V.value == 0).all())
    ((1, 2, 51), True)
    """
    from gongsynth.sun.atmosphere import Atmosphere  # late: the Atmosphere's readers use this package

    if not isinstance(atmosphere, Atmosphere):
        raise TypeError(f"atmosphere must be a gongsynth.Atmosphere, got {type(atmosphere).__name__}")
    line = get_line(line)
    wavelength = default_wavelength(line) if wavelength is None else wavelength
    check_wavelength_grid(wavelength, line.wavelength_nm * u.nm)
    mu_value, az = check_geometry(mu, azimuth, atmosphere.shape[1:])
    if np.ndim(mu_value) or np.ndim(az):
        raise ValueError("rt.synthesize takes one viewing geometry (scalar mu and azimuth) per call")
    mu_value, az = float(mu_value), float(az)
    if rays not in ("inclined", "vertical"):
        raise ValueError(f"rays must be 'inclined' or 'vertical', got {rays!r}")
    scale, level, offset, half, nsamp = truth_definition(truth)
    const, pf = line_constants(line)
    nz, ny, nx = atmosphere.shape
    z_km = atmosphere.z.to_value(u.km)
    pixel_km = atmosphere.pixel_size.to_value(u.km)
    inclined = rays == "inclined" and not rays_are_vertical(z_km, mu_value, pixel_km)
    if not inclined:
        z_ref = float("nan")
    elif anchor_height is None:
        z_ref = reference_height(atmosphere, line)
    else:
        z_ref = u.Quantity(anchor_height).to_value(u.km)
        if not np.isfinite(z_ref):
            raise ValueError(f"anchor_height must be a finite length, got {anchor_height}")
    dx, dy = ray_offsets(z_km, z_ref if inclined else 0.0, mu_value if inclined else 1.0, az,
                         atmosphere.pixel_size.to_value(u.km))
    ds = np.diff(z_km) * 1e5 / mu_value
    n, e1, e2 = los_basis(mu_value, az)
    lam_cm = wavelength.to_value(u.cm).astype(np.float64)
    core = int(np.argmin(np.abs(lam_cm - const[0])))
    out = [np.empty((ny, nx, lam_cm.size), dtype=np.float32) for _ in range(4)]
    blos = np.empty((ny, nx), dtype=np.float32)
    anchor = np.empty((ny, nx), dtype=np.float32)
    rows_per_block = max(1, BLOCK_COLUMNS // nx)
    starts = range(0, ny, rows_per_block)
    if progress:
        from tqdm.auto import tqdm
        starts = tqdm(starts, desc="rt.synthesize", unit="block")
    for start in starts:
        rows = np.arange(start, min(ny, start + rows_per_block), dtype=np.int64)
        ncol = rows.size * nx

        def sample(name, rows=rows, ncol=ncol):
            buf = np.empty((ncol, nz))
            sample_rays(atmosphere.raw(name), rows, dx, dy, buf)
            return buf

        opac = _opacity(atmosphere, sample, sample("microturbulence") * 1e5, const, pf)
        vel = atmosphere.raw("velocity")
        mag = atmosphere.raw("magnetic_field")
        comps = [sample_component(vel, c, rows, dx, dy, ncol, nz) for c in range(3)]
        vlos = -(comps[0] * n[0] + comps[1] * n[1] + comps[2] * n[2]) * 1e5
        comps = [sample_component(mag, c, rows, dx, dy, ncol, nz) for c in range(3)]
        bpar = comps[0] * n[0] + comps[1] * n[1] + comps[2] * n[2]
        b1 = comps[0] * e1[0] + comps[1] * e1[1] + comps[2] * e1[2]
        b2 = comps[0] * e2[0] + comps[1] * e2[1] + comps[2] * e2[2]
        del comps
        res = [np.empty((ncol, lam_cm.size), dtype=np.float32) for _ in range(4)]
        log_tc = np.empty((ncol, nz), dtype=np.float32)
        log_tl = np.empty((ncol, nz), dtype=np.float32)
        solve_columns(lam_cm, const[0], const[10], core if scale == "core" else -1, ds, *opac, vlos, bpar, b1,
                      b2, *res, log_tc, log_tl)
        tb = np.empty(ncol, dtype=np.float32)
        th = np.empty(ncol, dtype=np.float32)
        los_field_at_depth(z_km, log_tl if scale == "core" else log_tc, bpar, level, scale == "height",
                           offset, half, nsamp, tb, th)
        sl = slice(rows[0], rows[-1] + 1)
        for dst, src in zip(out, res):
            dst[sl] = src.reshape(rows.size, nx, -1)
        blos[sl] = tb.reshape(rows.size, nx)
        anchor[sl] = th.reshape(rows.size, nx)
    meta = {"origin": "gongsynth.rt.synthesize", "method": f"LTE, DELO-linear, {line.name}",
            "line": line.name, "line_wavelength_nm": float(line.wavelength_nm),
            "mu": mu_value, "los_azimuth_deg": float(np.degrees(az)), "truth": str(truth), "rays": rays,
            "reference_height_km": z_ref, "truth_anchor_mean_km": float(anchor.mean()),
            "lande_g": line.lande, "atmosphere": dict(atmosphere.meta)}
    return StokesCube(*(u.Quantity(a, RADIANCE_UNIT, copy=False) for a in out), wavelength,
                      atmosphere.pixel_size, mu=mu_value, blos=blos * u.G, meta=meta)


def sample_component(vector, c, rows, dx, dy, ncol, nz):
    """Component ``c`` of a (3, nz, ny, nx) field sampled along a block's rays, (ncol, nz) float64."""
    buf = np.empty((ncol, nz))
    sample_rays(vector[c], rows, dx, dy, buf)
    return buf
