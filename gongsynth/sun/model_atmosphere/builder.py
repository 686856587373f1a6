r"""
`model_atmosphere`: the built-in, seeded 3-D model Sun (granulation, kG elements, internetwork, a sunspot).

Every column is a blend of 1-D semi-empirical stratifications, each in
hydrostatic equilibrium on its own τ₅₀₀ scale and placed on the common
geometric grid (`~gongsynth.sun.model_atmosphere.stratification`):

- **quiet Sun**: T(log τ) = T_HSRA + a ΔT with ΔT half the granule −
  intergranule difference of a two-component model (Ruiz Cobo et al. 1995:
  +180 K at τ = 1, ~0 at log τ = −1, weakly reversed above; or Borrero &
  Bellot Rubio 2002), scaled by ``granulation_amplitude`` (1.5: the models
  come from ~1″ data), and a the granulation's thermal weight
  (`~gongsynth.sun.model_atmosphere.granulation`); each member is shifted so
  that all have the HSRA's gas pressure at its log τ = 1 depth (horizontal
  pressure balance below the surface), which raises the granules' τ = 1
  above the lanes' (the corrugation, reported in ``meta``);
- **kG elements**: the network (or plage) flux-tube model of Solanki, sunk by
  the Wilson depression W that pressure balance P_int + B₀²/8π = P_ext at
  equal geometric height gives at the tube's τ = 1; weight f = |B_z|/B₀ of
  the element field on that plane (a filling factor, ≤ 1); placed in the lanes,
  on supergranular cell boundaries (``network``: by default in boxes of at
  least two cells a side; `~gongsynth.sun.model_atmosphere.network_layout`)
  or clustered by a noise field;
- **sunspot**: Maltby et al. (1986) M umbra and the del Toro Iniesta et al.
  (1994) penumbra, each placed by the same pressure balance with the umbral /
  penumbral field strength.

T and ln P are blended with these weights (a weighted geometric mean of
hydrostatic pressures).  The field is the potential continuation of the
element and spot base planes plus the divergence-free internetwork field
(`~gongsynth.sun.model_atmosphere.flux_elements`); the granular flow is
anelastic and is suppressed inside elements and the spot, where the Evershed
and moat flows of `~gongsynth.sun.model_atmosphere.sunspot` take over.
"""
from __future__ import annotations

import functools
import inspect
import math

import astropy.units as u
import numpy as np

from gongsynth.seeding import as_seed_sequence, stage_generator
from gongsynth.sun.model_atmosphere import flux_elements as fe
from gongsynth.sun.model_atmosphere import stratification as st
from gongsynth.sun.model_atmosphere._rows import blend_rows, flow_rows, internetwork_rows
from gongsynth.sun.model_atmosphere.granulation import PeriodicGrid, anelastic_profile, granulation_pattern
from gongsynth.sun.model_atmosphere.network_layout import cell_flow, network_layout
from gongsynth.sun.model_atmosphere.sunspot import spot_structure
from gongsynth.sun.rt.eos import solve_state
from gongsynth.sun.surface_field.supergranulation import GRANULAR_FLOW_SCALE
from gongsynth.threads import run_chunks
from gongsynth.validation import check_quantity, check_scalar

__all__ = ["model_atmosphere", "model_sun", "assemble_rows", "reference_stratifications",
           "GRANULATION_MODELS", "ELEMENT_MODELS", "UMBRA_MODELS"]

GRANULATION_MODELS = {"brc": ("granule_brc", "intergranule_brc"), "bbr": ("granule_bbr", "intergranule_bbr")}
ELEMENT_MODELS = {"network": "network", "plage": "plage", "quiet": "hsra"}
UMBRA_MODELS = {"maltby-m": "umbra_m", "maltby-e": "umbra_e"}

#: Thermal weights a tabulated (interpolated linearly in between; a is clipped to this range).
_A_TABLE = np.linspace(-4.0, 4.0, 33)
# Random sub-streams: each ingredient its own, so switching one off leaves the others unchanged.
_GRANULES, _ELEMENTS, _INTERNETWORK, _SPOT, _NETWORK = range(5)


@functools.lru_cache(maxsize=8)
def reference_stratifications(z_grid, granulation="brc", amplitude=1.0, element_model="network",
                              element_field=1500.0, umbra_model="maltby-m", umbra_field=3000.0,
                              penumbra_field=1500.0, element_depression=True, spot=True):
    """
    The 1-D components on the height grid (cached: they depend only on these arguments).

    Parameters
    ----------
    z_grid : tuple of float
        Heights (km).
    granulation, element_model, umbra_model : str
        Keys of `GRANULATION_MODELS`, `ELEMENT_MODELS`, `UMBRA_MODELS`.
    amplitude : float
        Scale of the granulation's ΔT.
    element_field, umbra_field, penumbra_field : float
        G at each model's own τ = 1 (for the pressure balance).
    element_depression : bool
        False (an ablation only): the element model is not sunk, its τ = 1 stays at z = 0.
    spot : bool
        Compute the umbra and penumbra (False: they are left out, zero arrays).

    Returns
    -------
    dict
        ``quiet_t``, ``quiet_lnp`` (na, nz) on the thermal weights ``a``; ``tube_*``,
        ``umbra_*``, ``penumbra_*``, ``mean_*`` (nz,); the heights of each component's τ = 1
        (``z_tau1_quiet`` per a, ``z_tube``, ``z_umbra``, ``z_penumbra``) and ``density`` (mean ρ̄(z)).

    Examples
    --------
    >>> ref = reference_stratifications(tuple(np.linspace(-600, 700, 66)))
    >>> bool(ref["z_tube"] < 0), bool(ref["z_umbra"] < -200)
    (True, True)
    """
    zg = np.asarray(z_grid, dtype=np.float64)
    lt = st.LOG_TAU
    t_mean = st.model_temperature("hsra")
    gran, inter = GRANULATION_MODELS[granulation]
    delta = 0.5 * (st.model_temperature(gran) - st.model_temperature(inter)) * amplitude
    t_q = t_mean[None, :] + _A_TABLE[:, None] * delta[None, :]
    names = [ELEMENT_MODELS[element_model], UMBRA_MODELS[umbra_model], "penumbra"]
    t_all = np.concatenate([t_mean[None], t_q, np.stack([st.model_temperature(n) for n in names])])
    z, p, _ = st.tau_scale_family(t_all, lt)
    # Horizontal pressure balance at the mean model's log tau = 1 depth fixes each quiet member's height
    # (found on the hydrostatically extended grid: the hot members reach that pressure below their table).
    nq = 1 + _A_TABLE.size
    lnp_match = math.log(p[0, 0])
    _, lnp0 = st.place_on_grid(zg, z[:nq], t_all[:nq], p[:nq])
    shift_q = np.array([z[0, 0] - np.interp(lnp_match, lp[::-1], zg[::-1]) for lp in lnp0[1:]])
    t_grid, lnp_grid = st.place_on_grid(zg, z[:nq], t_all[:nq], p[:nq], np.concatenate([[0.0], shift_q]))
    mean_lnp = lnp_grid[0]
    out = dict(a=_A_TABLE.copy(), mean_t=t_grid[0], mean_lnp=mean_lnp, quiet_t=t_grid[1:],
               quiet_lnp=lnp_grid[1:], z_tau1_quiet=shift_q)
    for i, (key, field, arg) in enumerate((("tube", element_field, "element_field"),
                                           ("umbra", umbra_field, "umbra_field"),
                                           ("penumbra", penumbra_field, "penumbra_field"))):
        j = nq + i
        if key != "tube" and not spot:
            out[f"{key}_t"], out[f"{key}_lnp"], out[f"z_{key}"] = np.zeros(zg.size), np.zeros(zg.size), 0.0
            continue
        p_tau1 = float(np.exp(np.interp(0.0, z[j], np.log(p[j]))))
        try:
            depth = st.pressure_balance_depth(zg, mean_lnp, p_tau1, field)
        except ValueError as err:
            raise ValueError(f"height_range: {err} (lower the bottom or reduce {arg})") from None
        if key == "tube" and not element_depression:
            depth = 0.0
        t_k, lnp_k = st.place_on_grid(zg, z[j:j + 1], t_all[j:j + 1], p[j:j + 1], depth)
        out[f"{key}_t"], out[f"{key}_lnp"], out[f"z_{key}"] = t_k[0], lnp_k[0], depth
    out["density"] = solve_state(out["mean_t"], gas_pressure=np.exp(mean_lnp))["density"]
    for v in out.values():
        if isinstance(v, np.ndarray):
            v.flags.writeable = False
    return out


def assemble_rows(plan, rows, magnetic_field=None):
    """
    The 3-D fields of some rows from `model_sun`'s plan (the same bits as those rows of the whole box).

    Parameters
    ----------
    plan : dict
        The whole-plane ingredients (``_plan``).
    rows : `numpy.ndarray` of int64
        Row indices in [0, ny).
    magnetic_field : `numpy.ndarray`, optional
        (3, nz, len(rows), nx) float32 holding the canopy's potential field of
        these rows (or zeros), completed in place with the internetwork; None:
        thermodynamics only.

    Returns
    -------
    temperature, pressure, velocity : `numpy.ndarray`
        float32, (nz, len(rows), nx) and (3, nz, len(rows), nx) (None with thermodynamics only).
    """
    nz, nr, nx = plan["z"].size, rows.size, plan["grid"].nx
    whole = nr == plan["grid"].ny and bool(np.array_equal(rows, np.arange(nr)))
    pick = (lambda plane: plane) if whole else (lambda plane: np.ascontiguousarray(plane[rows]))
    temp = np.empty((nz, nr, nx), dtype=np.float32)
    pres = np.empty_like(temp)
    run_chunks(blend_rows, nr, *(pick(p_) for p_ in plan["blend"]), *plan["blend_tables"], temp, pres)
    if magnetic_field is None:
        return temp, pres, None
    vel = np.empty((3,) + temp.shape, dtype=np.float32)
    h, s, flows = plan["flow_profiles"]
    run_chunks(flow_rows, nr, h, s, flows, *(pick(p_) for p_ in plan["flow"]), vel)
    if plan.get("supergranular") is not None:      # the cells' flow, the same at every height
        for component, plane in enumerate(plan["supergranular"]):
            vel[component] += pick(plane).astype(np.float32)[None]
    if plan["base_field"] is not None:
        magnetic_field[2] += pick(plan["base_field"]).astype(np.float32)
    run_chunks(internetwork_rows, nr, *plan["internetwork_profiles"],
               *(pick(p_) for p_ in plan["internetwork"]), magnetic_field)
    return temp, pres, vel


def _choice(value, options, name):
    if value not in options:
        raise ValueError(f"{name} must be one of {sorted(options)}, got {value!r}")
    return value


def _fraction(value, name, lo=0.0, hi=1.0):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not lo <= value <= hi:
        raise ValueError(f"{name} must be a number in [{lo}, {hi}], got {value!r}")
    return float(value)


def model_atmosphere(shape=(1024, 1024), pixel_size=96 * u.km, *, seed, nz=80,
                     height_range=(-600, 700) * u.km, spot="auto", granule_size=1.3 * u.Mm,
                     granulation_models="brc", granulation_amplitude=1.5,
                     granulation_velocity=2.0 * u.km / u.s, velocity_decay_height=250 * u.km,
                     element_flux_density=20 * u.G, element_field=1500 * u.G, element_model="network",
                     element_depression=True, canopy=True,
                     positive_fraction=0.6, internetwork_field=10 * u.G,
                     internetwork_horizontal_field=50 * u.G, umbra_radius=7 * u.Mm,
                     penumbra_radius=16 * u.Mm, umbra_field=3000 * u.G, penumbra_field=1500 * u.G,
                     umbra_model="maltby-m", evershed_speed=2.0 * u.km / u.s, moat_speed=0.8 * u.km / u.s,
                     microturbulence=0.6 * u.km / u.s, network="auto", supergranule_size=30 * u.Mm,
                     flow_cutoff=0 * u.Mm, supergranulation=False):
    """
    A seeded, horizontally periodic 3-D model photosphere for LTE Stokes synthesis.

    The module docstring of `gongsynth.sun.model_atmosphere.builder` gives the
    construction and the sources.  Same arguments and seed → the same bits.

    Parameters
    ----------
    shape : tuple of int, optional
        (ny, nx) columns (default 1024 × 1024: 98 Mm, the papers' MURaM box
        binned to 96 km; a run's default is coarser, see
        `gongsynth.suns.RUN_GRIDS`).
    pixel_size : `~astropy.units.Quantity`, optional
        Horizontal spacing (default 96 km).
    seed : int, `numpy.random.SeedSequence` or `numpy.random.Generator`
        Randomness (required).
    nz : int, optional
        Number of heights (default 80).
    height_range : `~astropy.units.Quantity`, optional
        Bottom and top heights, relative to the quiet Sun's mean τ₅₀₀ = 1
        (default −600 to 700 km: the umbra's Wilson depression needs depth).
    spot : bool or "auto", optional
        A sunspot at the box centre; "auto" (default): when it fits
        (box ≥ 2.2 × ``penumbra_radius``).
    granule_size : `~astropy.units.Quantity`, optional
        Mean spacing of granule centres (1.3 Mm).
    granulation_models : {"brc", "bbr"}, optional
        The two-component quiet-Sun model pair giving the granular ΔT(log τ).
    granulation_amplitude : float, optional
        Scale of that ΔT (default 1.5).  The two-component models were inverted
        from ~1″ observations, which lower the contrast; 1.5 restores the
        resolved quiet Sun: 676.8 nm continuum contrast 13.6 % (observed
        13-15 % at full resolution), T rms 330 K at τ = 1 (Stein & Nordlund
        480 K, MURaM 650 K at 96 km), granule-lane τ = 1 corrugation 50 km.
        1 gives the models as published (contrast 9 %).
    granulation_velocity : `~astropy.units.Quantity`, optional
        RMS vertical velocity at τ = 1 in the quiet Sun (2 km/s).
    velocity_decay_height : `~astropy.units.Quantity`, optional
        e-folding height of the granular velocities above τ = 1 (200 km).
    element_flux_density : `~astropy.units.Quantity`, optional
        Mean unsigned flux density of the kG elements over the box (20 G).
    element_field : `~astropy.units.Quantity`, optional
        Field strength of an element at its own τ = 1 (1500 G).
    element_model : {"network", "plage", "quiet"}, optional
        Temperature stratification T(log τ) of the elements: Solanki's network
        or plage models, or (an ablation) the quiet HSRA: no hot tubes.
    element_depression : bool, optional
        Sink the elements by their Wilson depression (default); False is an
        ablation (no pressure balance).
    canopy : bool, optional
        Spread the element field with height as a potential field (default);
        False is an ablation: vertical tubes of constant field, no canopy.
    positive_fraction : float, optional
        Fraction of the element flux of positive polarity (0.6).
    internetwork_field, internetwork_horizontal_field : `~astropy.units.Quantity`, optional
        RMS vertical (10 G) and horizontal (50 G) internetwork field at τ = 1.
    umbra_radius, penumbra_radius : `~astropy.units.Quantity`, optional
        7 and 16 Mm.
    umbra_field, penumbra_field : `~astropy.units.Quantity`, optional
        Field at the umbral centre (3000 G) and mean penumbral field (1500 G).
    umbra_model : {"maltby-m", "maltby-e"}, optional
        Umbral temperature stratification.
    evershed_speed, moat_speed : `~astropy.units.Quantity`, optional
        Peak Evershed (2 km/s) and moat (0.8 km/s) outflows.
    microturbulence : `~astropy.units.Quantity`, optional
        Added unresolved velocity (default 0: the 3-D flow broadens the line).
    network : bool or "auto", optional
        True: lay the kG elements on the boundaries of periodic supergranular
        cells, with ephemeral bipoles inside the cells
        (`~gongsynth.sun.model_atmosphere.network_layout`); False: in the
        lanes, clustered by a ~5 Mm noise field; "auto" (default): True when
        the box is at least 2 × ``supergranule_size`` on each side (the
        default 98 Mm box is), False in smaller boxes.
    supergranule_size : `~astropy.units.Quantity`, optional
        With ``network``: mean spacing of the cell centres (30 Mm, Rieutord &
        Rincon 2010); it must fit in the box.
    flow_cutoff : `~astropy.units.Quantity`, optional
        The largest scale of the granular flow: the vertical-velocity
        pattern's Fourier components of wavelength λ beyond it are taken out
        (× 1 − exp(−(λ_cut/λ)²)) before the anelastic outflow is derived from
        it.  A granulation of random cells has a white tail of vertical
        velocity at large scales (~10-40 m/s over tens of Mm), which
        continuity turns into horizontal flows of hundreds of m/s there
        (v_h ~ v_z / kH); where a supergranular flow of its own is laid over
        the box (the full disk's library patches,
        `gongsynth.sun.surface_field.supergranulation`), these would be a
        second, random one.  0 (default): every scale the box holds.
    supergranulation : bool, optional
        With the network: its cells flow, as the full disk's do
        (`~gongsynth.sun.model_atmosphere.network_layout.cell_flow`: outflow
        from each centre to the walls, 350 m/s rms, 25 m/s up in the middles
        and down at the walls; Rincon & Rieutord 2018), the same at every
        height, stopped at a sunspot; the granulation's own flow then ends at
        ``flow_cutoff`` or, if that is 0,
        `~gongsynth.sun.surface_field.supergranulation.GRANULAR_FLOW_SCALE`
        (10 Mm).  Off by default: the shipped calibration tables were built
        without it.

    Returns
    -------
    `~gongsynth.Atmosphere`
        Temperature, gas pressure, velocity, magnetic field (float32); ``meta``
        holds the parameters, the Wilson depressions and the corrugation.

    Raises
    ------
    ValueError
        For arguments out of range (the message names the argument).

    Examples
    --------
    >>> import astropy.units as u
    >>> atm = model_atmosphere((32, 32), seed=1, nz=40)
    >>> atm.shape, bool(atm.meta["spot"])
    ((40, 32, 32), False)
    """
    # Late: the assembly imports this module's kernels.
    from gongsynth.sun.model_atmosphere.assembly import ModelSun

    return ModelSun(_plan(shape, pixel_size, seed, nz, height_range, spot, granule_size, granulation_models,
                          granulation_amplitude, granulation_velocity, velocity_decay_height,
                          element_flux_density, element_field, element_model, element_depression, canopy,
                          positive_fraction, internetwork_field, internetwork_horizontal_field,
                          umbra_radius, penumbra_radius, umbra_field, penumbra_field, umbra_model,
                          evershed_speed, moat_speed, microturbulence, network,
                          supergranule_size, flow_cutoff, supergranulation)).atmosphere()


def _plan(shape, pixel_size, seed, nz, height_range, spot, granule_size, granulation_models,
          granulation_amplitude, granulation_velocity, velocity_decay_height, element_flux_density,
          element_field, element_model, element_depression, canopy, positive_fraction, internetwork_field,
          internetwork_horizontal_field, umbra_radius, penumbra_radius, umbra_field, penumbra_field,
          umbra_model, evershed_speed, moat_speed, microturbulence, network="auto",
          supergranule_size=30 * u.Mm, flow_cutoff=0 * u.Mm, supergranulation=False):
    """`model_atmosphere`'s arguments checked and its whole-plane (2-D) ingredients made, as a dict."""
    if (not isinstance(shape, (tuple, list)) or len(shape) != 2
            or not all(isinstance(n, (int, np.integer)) and not isinstance(n, bool) and n >= 8
                       for n in shape)):
        raise ValueError(f"shape must be two ints >= 8 (ny, nx), got {shape!r}")
    ny, nx = (int(n) for n in shape)
    if isinstance(nz, bool) or not isinstance(nz, (int, np.integer)) or nz < 16:
        raise ValueError(f"nz must be an int >= 16, got {nz!r}")
    px = check_scalar(pixel_size, u.km, "pixel_size")
    check_quantity(height_range, u.km, "height_range")
    if np.shape(height_range) != (2,):
        raise ValueError(f"height_range must be (bottom, top), got {height_range}")
    z_lo, z_hi = (float(v) for v in height_range.to_value(u.km))
    if not (z_lo <= -200 and z_hi >= 400):
        raise ValueError(f"height_range must reach at least 200 km below and 400 km above tau = 1, got "
                         f"{height_range}")
    for name, value in (("element_depression", element_depression), ("canopy", canopy),
                        ("supergranulation", supergranulation)):
        if not isinstance(value, (bool, np.bool_)):
            raise ValueError(f"{name} must be True or False, got {value!r}")
    if not (isinstance(network, (bool, np.bool_)) or network == "auto"):
        raise ValueError(f"network must be True, False or 'auto', got {network!r}")
    if spot not in (True, False, "auto"):
        raise ValueError(f"spot must be True, False or 'auto', got {spot!r}")
    gran = check_scalar(granule_size, u.km, "granule_size")
    _choice(granulation_models, GRANULATION_MODELS, "granulation_models")
    amp = _fraction(granulation_amplitude, "granulation_amplitude", 0.0, 3.0)
    v_g = check_scalar(granulation_velocity, u.km / u.s, "granulation_velocity", positive=False)
    h_v = check_scalar(velocity_decay_height, u.km, "velocity_decay_height")
    flux = check_scalar(element_flux_density, u.G, "element_flux_density", positive=False)
    b_el = check_scalar(element_field, u.G, "element_field")
    _choice(element_model, ELEMENT_MODELS, "element_model")
    pos = _fraction(positive_fraction, "positive_fraction")
    in_v = check_scalar(internetwork_field, u.G, "internetwork_field", positive=False)
    in_h = check_scalar(internetwork_horizontal_field, u.G, "internetwork_horizontal_field", positive=False)
    r_u = check_scalar(umbra_radius, u.km, "umbra_radius")
    r_p = check_scalar(penumbra_radius, u.km, "penumbra_radius")
    b_u = check_scalar(umbra_field, u.G, "umbra_field")
    b_p = check_scalar(penumbra_field, u.G, "penumbra_field")
    _choice(umbra_model, UMBRA_MODELS, "umbra_model")
    v_e = check_scalar(evershed_speed, u.km / u.s, "evershed_speed", positive=False)
    v_m = check_scalar(moat_speed, u.km / u.s, "moat_speed", positive=False)
    v_t = check_scalar(microturbulence, u.km / u.s, "microturbulence", positive=False)
    sg = check_scalar(supergranule_size, u.km, "supergranule_size")
    cut = check_scalar(flow_cutoff, u.km, "flow_cutoff", positive=False)
    for name, value in (("element_field", b_el), ("umbra_field", b_u), ("penumbra_field", b_p)):
        if value > 6000:
            raise ValueError(f"{name} must be <= 6000 G, got {value} G")
    if r_u >= r_p:
        raise ValueError(f"umbra_radius ({umbra_radius}) must be smaller than "
                         f"penumbra_radius ({penumbra_radius})")
    fits = 2.2 * r_p <= min(ny, nx) * px
    if spot is True and not fits:
        raise ValueError(f"spot=True: the spot (penumbra_radius {penumbra_radius}) does not fit in the "
                         f"{nx * px / 1e3:.1f} x {ny * px / 1e3:.1f} Mm box (needs 2.2 x penumbra_radius)")
    has_spot = bool(spot is True or (spot == "auto" and fits))
    # "auto": the network needs a few cells to form a pattern; boxes under 2 cells a side keep the
    # noise clustering (test boxes, the full disk's one-cell library patches).
    network = bool(network if isinstance(network, (bool, np.bool_)) else min(ny, nx) * px >= 2 * sg)
    if supergranulation and not network:
        raise ValueError("supergranulation needs the network's cells: network must be on (True, or 'auto' "
                         "in a box of at least 2 x supergranule_size a side; this one is "
                         f"{min(ny, nx) * px / 1e3:.1f} Mm)")
    if supergranulation and cut == 0:
        cut = GRANULAR_FLOW_SCALE.to_value(u.km)

    zg = np.linspace(z_lo, z_hi, int(nz))
    ref = reference_stratifications(tuple(zg), granulation_models, amp, element_model, b_el, umbra_model,
                                    b_u, b_p, bool(element_depression), has_spot)
    root = as_seed_sequence(seed)
    grid = PeriodicGrid(ny, nx, px)
    a, vpat, lanes = granulation_pattern(grid, stage_generator(root, "model_atmosphere", _GRANULES), gran)

    zeros = np.zeros((ny, nx))
    if has_spot:
        sp = spot_structure(grid, stage_generator(root, "model_atmosphere", _SPOT), r_umbra=r_u,
                            r_penumbra=r_p, b_umbra=b_u, b_penumbra=b_p, v_evershed=v_e, v_moat=v_m)
        keep_out = 0.5 * (1 + np.tanh((sp["r"] - r_p - 1500.0) / 500.0))
    else:
        sp = dict(umbra=zeros, penumbra=zeros, bz=zeros, vx=zeros, vy=zeros, evershed=zeros, moat=zeros,
                  cos=zeros, sin=zeros, mask=zeros)
        keep_out = np.ones((ny, nx))

    # kG elements in the lanes: on supergranular boundaries (network), or clustered on ~5 Mm scales.
    cells_flow = None
    rng = stage_generator(root, "model_atmosphere", _ELEMENTS)
    fluxes = fe.power_law_fluxes(rng, flux * grid.Lx * grid.Ly * 1e10)
    signs = np.where(rng.uniform(size=fluxes.size) < pos, 1.0, -1.0)
    if network:
        lay = network_layout(grid, stage_generator(root, "model_atmosphere", _NETWORK), sg, lanes, keep_out)
        # The cells' flow (m/s → km/s, the velocities' unit here), stopped at a sunspot as the granules' is.
        cells_flow = (None if not supergranulation else
                      tuple(1e-3 * v * (1 - sp["mask"]) for v in cell_flow(grid, lay["centres"])))
        bz_el = fe.render_elements(grid, rng, lay["weight"], fluxes, signs, b_el)
        bz_el += fe.render_elements(grid, rng, None, lay["fluxes"], lay["signs"], b_el, where=lay["where"])
    else:
        cluster = np.maximum(grid.noise(rng, 2500.0), 0.0) + 0.2
        bz_el = fe.render_elements(grid, rng, lanes * cluster * keep_out + 1e-12, fluxes, signs, b_el)
    spot_w = sp["umbra"] + sp["penumbra"]
    f_el = np.clip(np.abs(bz_el) / b_el, 0.0, 1.0) * (1 - spot_w)

    # The 2-D ingredients of the flows and the field (the 3-D assembly is `ModelSun.rows`).
    a_clip = np.clip(a, _A_TABLE[0], _A_TABLE[-1])
    h, s = anelastic_profile(zg, ref["density"], h_v)
    quiet = (1 - f_el) * (1 - sp["mask"])
    vz0 = vpat * quiet
    if cut > 0:
        vz0 = grid.high_pass(vz0, cut) * quiet     # the elements and the spot keep no granular flow
    vz0 -= vz0.mean()
    vz0 *= v_g / (np.sqrt(np.sum(vz0 ** 2) / max(quiet.sum(), 1.0)) or 1.0)
    gx, gy = grid.gradient(grid.inverse_laplacian(vz0))
    gx *= 1 - sp["mask"]          # the (non-local) granular outflow stops at the spot's edge
    gy *= 1 - sp["mask"]
    flows = np.exp(-np.maximum(zg, 0.0) / 150.0)          # Evershed/moat flows: strongest at tau = 1

    # Magnetic field: potential continuation of the element and spot base planes + internetwork.
    rng = stage_generator(root, "model_atmosphere", _INTERNETWORK)
    pots = fe.internetwork_potentials(grid, rng, in_v, in_h)
    quiet_in = (1 - sp["mask"])
    ax, ay, az = (p_ * quiet_in for p_ in pots)
    dazdx, dazdy = grid.gradient(az)
    curl = grid.gradient(ay)[0] - grid.gradient(ax)[1]
    spectra, bases = ([grid.fft(bz_el).astype(np.complex64)], [ref["z_tube"]]) if canopy else ([], [])
    if has_spot:
        spectra.append(grid.fft(sp["bz"]).astype(np.complex64))
        bases.append(ref["z_umbra"])
    c, dc = fe.internetwork_profile(zg)

    meta = {
        "origin": "gongsynth.model_atmosphere", "seed_entropy": str(root.entropy), "spot": has_spot,
        "wilson_depression_km": {"element": -ref["z_tube"], "umbra": -ref["z_umbra"],
                                 "penumbra": -ref["z_penumbra"]},
        "granule_corrugation_km": float(np.interp(1.0, _A_TABLE, ref["z_tau1_quiet"])
                                        - np.interp(-1.0, _A_TABLE, ref["z_tau1_quiet"])),
        "params": {"shape": [ny, nx], "pixel_size_km": px, "nz": int(nz), "height_range_km": [z_lo, z_hi],
                   "spot": spot, "granule_size_km": gran, "granulation_models": granulation_models,
                   "granulation_amplitude": amp, "granulation_velocity_km_s": v_g,
                   "velocity_decay_height_km": h_v, "element_flux_density_G": flux, "element_field_G": b_el,
                   "element_model": element_model, "element_depression": bool(element_depression),
                   "canopy": bool(canopy), "positive_fraction": pos, "internetwork_field_G": in_v,
                   "internetwork_horizontal_field_G": in_h, "umbra_radius_km": r_u, "penumbra_radius_km": r_p,
                   "umbra_field_G": b_u, "penumbra_field_G": b_p, "umbra_model": umbra_model,
                   "evershed_speed_km_s": v_e, "moat_speed_km_s": v_m, "microturbulence_km_s": v_t},
    }
    if network:     # only then: the default's metadata stays as it was
        meta["params"].update(network=True, supergranule_size_km=sg)
        meta["network"] = {"cells": lay["cells"], "ephemeral_regions": lay["fluxes"].size // 2}
    if cut > 0:
        meta["params"].update(flow_cutoff_km=cut)
    if supergranulation:
        meta["params"].update(supergranulation=True)
    # Per-row planes (indexed by the kernels' row j), then the height profiles and tables.
    return dict(grid=grid, z=zg, pixel_size=px, microturbulence=v_t, meta=meta, spectra=spectra, bases=bases,
                supergranular=cells_flow,
                base_field=None if canopy else bz_el,
                blend=(a_clip, f_el, sp["umbra"], sp["penumbra"]),
                blend_tables=(float(_A_TABLE[0]), float(_A_TABLE[1] - _A_TABLE[0]), ref["quiet_t"],
                              np.exp(ref["quiet_lnp"]), ref["tube_t"], np.exp(ref["tube_lnp"]),
                              ref["umbra_t"], np.exp(ref["umbra_lnp"]), ref["penumbra_t"],
                              np.exp(ref["penumbra_lnp"])),
                flow=(vz0, gx, gy, sp["vx"], sp["vy"]), flow_profiles=(h, s, flows),
                internetwork=(ax, ay, dazdx, dazdy, curl), internetwork_profiles=(c, dc),
                network_wall=lay["wall"] if network else None)


def model_sun(*args, **kwargs):
    """
    The model Sun of `model_atmosphere`, assembled a block of rows at a time when asked.

    Parameters
    ----------
    *args, **kwargs
        Those of `model_atmosphere` (checked the same way).

    Returns
    -------
    `~gongsynth.sun.model_atmosphere.assembly.ModelSun`

    Examples
    --------
    >>> sun = model_sun((32, 32), seed=1, nz=40)
    >>> whole = model_atmosphere((32, 32), seed=1, nz=40)
    >>> block = sun.rows(range(30, 36))                      # wraps: rows 30, 31, 0, ..., 3
    >>> b_block, b_whole = block.raw("magnetic_field"), whole.raw("magnetic_field")
    >>> block.shape, bool(np.array_equal(b_block[:, :, 2], b_whole[:, :, 0]))
    ((40, 6, 32), True)
    """
    bound = inspect.signature(model_atmosphere).bind(*args, **kwargs)
    bound.apply_defaults()
    from gongsynth.sun.model_atmosphere.assembly import ModelSun

    return ModelSun(_plan(**bound.arguments))
