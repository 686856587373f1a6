r"""
1-D reference stratifications: semi-empirical T(log τ₅₀₀) models → T, P on a common geometric grid.

Each model of `~gongsynth.sun.model_atmosphere.tables` is put in hydrostatic
equilibrium on its own optical-depth scale with gongsynth's equation of state
and 500 nm continuum opacity (`~gongsynth.sun.rt.eos`,
`~gongsynth.sun.rt.opacity`): dP/dτ = g/κ(T, P), dz = −dτ/(κρ), z = 0 at
τ₅₀₀ = 1.  The solver here is vectorised over a family of models (a
relaxed fixed-point iteration on whole columns; it agrees with
`~gongsynth.sun.rt.hydrostatic.hydrostatic_tau_scale` to < 1 % and is
~100× faster, which the builder needs).

A model is then *placed* on the common grid by a vertical shift (the
granulation corrugation, a flux tube's or an umbra's Wilson depression, chosen
by pressure balance in `~gongsynth.sun.model_atmosphere.builder`) and
extended beyond its tabulated range:

- below its deepest point the temperature keeps rising with the bottom
  gradient G (capped at 40 K/km), saturating over ``DEEP_SCALE_KM``:
  T = T_b + G L (1 − e^{−(z_b − z)/L}), a stand-in for the nearly adiabatic
  convection zone (the MURaM snapshot's mean is 12.1 kK 500 km below τ = 1;
  tests compare);
- above its top it is isothermal;
- the gas pressure there follows dP/dz = −ρ(T, P) g, integrated on the grid.
"""
from __future__ import annotations

import functools

import numpy as np

from gongsynth.sun.model_atmosphere.tables import MODELS
from gongsynth.sun.rt.eos import solve_state
from gongsynth.sun.rt.hydrostatic import SOLAR_GRAVITY
from gongsynth.sun.rt.opacity import continuum_opacity

__all__ = ["LOG_TAU", "DEEP_SCALE_KM", "model_temperature", "tau_scale_family", "place_on_grid",
           "pressure_balance_depth"]

#: Common log τ₅₀₀ grid of the tabulated part (deepest first), 0.1 dex.
LOG_TAU = np.round(np.arange(1.0, -4.0001, -0.1), 2)
#: Saturation length of the sub-surface temperature rise (km).
DEEP_SCALE_KM = 100.0
_MAX_GRADIENT = 40.0   # K/km


def model_temperature(name, log_tau=LOG_TAU):
    """
    Temperature of a tabulated model on a log τ₅₀₀ grid (clamped beyond its range).

    Parameters
    ----------
    name : str
        A key of `~gongsynth.sun.model_atmosphere.tables.MODELS`.
    log_tau : array_like, optional
        Deepest first (default `LOG_TAU`).

    Returns
    -------
    `numpy.ndarray`
        K.

    Examples
    --------
    >>> float(model_temperature("hsra", [0.0])[0])
    6390.0
    """
    if name not in MODELS:
        raise ValueError(f"unknown reference model {name!r}; known: {sorted(MODELS)}")
    _, lt, t = MODELS[name]
    lt, t = np.asarray(lt), np.asarray(t)
    order = np.argsort(lt)
    return np.interp(np.asarray(log_tau, dtype=float), lt[order], t[order])


def _kappa(t, p):
    s = solve_state(t, gas_pressure=p)
    kappa = continuum_opacity(500.0, t, s["electron_density"], s["hydrogen_density"])
    return kappa / s["density"], s["density"]


def tau_scale_family(temperature, log_tau=LOG_TAU, gravity=SOLAR_GRAVITY):
    """
    Hydrostatic equilibrium of a family of models T(log τ₅₀₀), all at once.

    Parameters
    ----------
    temperature : array_like, (nmod, ntau)
        K, on ``log_tau``.
    log_tau : array_like, (ntau,)
        Deepest first, regularly spaced.
    gravity : float
        cm s⁻².

    Returns
    -------
    z, gas_pressure, density : `numpy.ndarray`, (nmod, ntau)
        km (0 at τ₅₀₀ = 1, upward), dyn cm⁻², g cm⁻³.

    Examples
    --------
    >>> z, p, rho = tau_scale_family(model_temperature("hsra")[None])
    >>> bool(np.all(np.diff(z[0]) > 0)), f"{np.interp(0, z[0], np.log10(p[0])):.2f}"
    (True, '5.10')
    """
    t = np.atleast_2d(np.asarray(temperature, dtype=np.float64))
    lt = np.asarray(log_tau, dtype=np.float64)
    up = lt[::-1]                       # top first: integrate downward in tau
    tu = t[:, ::-1]
    tau = 10.0 ** up
    dtau = np.diff(tau)
    lnp = np.log(gravity * tau[None, :] / 1.0) + np.zeros_like(tu) + 4.0
    for _ in range(200):
        k, _ = _kappa(tu, np.exp(lnp))
        inv = 1.0 / k
        p = np.empty_like(tu)
        p[:, 0] = gravity * tau[0] * inv[:, 0]
        p[:, 1:] = p[:, :1] + np.cumsum(gravity * dtau * 0.5 * (inv[:, 1:] + inv[:, :-1]), axis=1)
        new = np.log(p)
        change = np.max(np.abs(new - lnp))
        lnp = lnp + (2.0 / 3.0) * (new - lnp)      # relaxed: κ ∝ ~P^½ makes plain iteration oscillate
        if change < 1e-9:
            break
    p = np.exp(lnp)
    k, rho = _kappa(tu, p)
    kr = k * rho
    depth = np.concatenate([np.zeros((t.shape[0], 1)),
                            np.cumsum(dtau / (0.5 * (kr[:, 1:] + kr[:, :-1])), axis=1)], axis=1) * 1e-5
    z0 = np.array([np.interp(0.0, up, d) for d in depth])
    z = -(depth - z0[:, None])
    return z[:, ::-1], p[:, ::-1], rho[:, ::-1]


@functools.lru_cache(maxsize=1)
def _mu_table():
    """Log of the mean mass per particle ρkT/P on a (ln T, ln P) grid, from the equation of state."""
    ln_t = np.linspace(np.log(1500.0), np.log(40000.0), 160)
    ln_p = np.linspace(np.log(1e-2), np.log(1e9), 120)
    tt, pp = np.meshgrid(np.exp(ln_t), np.exp(ln_p), indexing="ij")
    rho = solve_state(tt, gas_pressure=pp)["density"]
    return ln_t, ln_p, np.log(rho * tt / pp)


def _density(t, p):
    """ρ(T, P) (g cm⁻³) by bilinear interpolation of ln(ρkT/P) (error < 1e-3 against the EOS)."""
    ln_t, ln_p, tab = _mu_table()
    x = np.clip((np.log(t) - ln_t[0]) / (ln_t[1] - ln_t[0]), 0, ln_t.size - 1.000001)
    y = np.clip((np.log(p) - ln_p[0]) / (ln_p[1] - ln_p[0]), 0, ln_p.size - 1.000001)
    i, j = x.astype(int), y.astype(int)
    fx, fy = x - i, y - j
    val = ((1 - fx) * ((1 - fy) * tab[i, j] + fy * tab[i, j + 1])
           + fx * ((1 - fy) * tab[i + 1, j] + fy * tab[i + 1, j + 1]))
    return np.exp(val) * p / t


def _extend_pressure(z, t, lnp, gravity):
    """Fill the NaNs of ln P (rows: models) by dP/dz = −ρ g from the finite part, trapezoidal, iterated."""
    nz = z.size
    for direction, steps in ((-1, range(nz - 2, -1, -1)), (1, range(1, nz))):
        for i in steps:
            j = i - direction
            rows = np.flatnonzero(np.isnan(lnp[:, i]) & np.isfinite(lnp[:, j]))
            if rows.size == 0:
                continue
            dz = (z[i] - z[j]) * 1e5
            rho_j = _density(t[rows, j], np.exp(lnp[rows, j]))
            g_j = -rho_j * gravity / np.exp(lnp[rows, j])          # d ln P / dz
            guess = lnp[rows, j] + g_j * dz
            for _ in range(4):
                rho = _density(t[rows, i], np.exp(guess))
                guess = lnp[rows, j] + 0.5 * dz * (g_j - rho * gravity / np.exp(guess))
            lnp[rows, i] = guess
    return lnp


def place_on_grid(z_grid, z_model, t_model, p_model, shift=0.0, gravity=SOLAR_GRAVITY):
    """
    T and ln P of tau-scale models on a geometric grid, shifted by ``shift`` km and extended.

    Parameters
    ----------
    z_grid : array_like, (nz,)
        km, increasing.
    z_model, t_model, p_model : array_like, (nmod, ntau)
        From `tau_scale_family` (deepest first).
    shift : float or array_like, (nmod,)
        Added to the model heights (negative: the model sinks).
    gravity : float
        cm s⁻².

    Returns
    -------
    temperature, ln_pressure : `numpy.ndarray`, (nmod, nz)
        K and ln(dyn cm⁻²).

    Examples
    --------
    >>> z, p, _ = tau_scale_family(model_temperature("hsra")[None])
    >>> t, lnp = place_on_grid(np.linspace(-600, 700, 66), z, model_temperature("hsra")[None], p)
    >>> bool(np.all(np.diff(lnp[0]) < 0)), bool(t[0, 0] > 11000)
    (True, True)
    """
    zg = np.asarray(z_grid, dtype=np.float64)
    zm = np.atleast_2d(z_model) + np.reshape(np.asarray(shift, dtype=np.float64), (-1, 1))
    tm, pm = np.atleast_2d(t_model), np.atleast_2d(p_model)
    nmod = zm.shape[0]
    temp = np.empty((nmod, zg.size))
    lnp = np.full((nmod, zg.size), np.nan)
    for m in range(nmod):
        zb, ztop = zm[m, 0], zm[m, -1]
        grad = min(max((tm[m, 0] - tm[m, 1]) / (zm[m, 1] - zm[m, 0]), 0.0), _MAX_GRADIENT)
        below = zg < zb
        temp[m] = np.interp(zg, zm[m], tm[m])
        temp[m, below] = tm[m, 0] + grad * DEEP_SCALE_KM * (1 - np.exp(-(zb - zg[below]) / DEEP_SCALE_KM))
        inside = (zg >= zb) & (zg <= ztop)
        lnp[m, inside] = np.interp(zg[inside], zm[m], np.log(pm[m]))
    if np.isnan(lnp).all(axis=1).any():
        raise ValueError("a reference model lies entirely outside the height grid: widen the height range")
    lnp = _extend_pressure(zg, temp, lnp, gravity)
    return temp, lnp


def pressure_balance_depth(z_grid, ln_p_ext, p_inside, field):
    """
    Height where the outside pressure equals ``p_inside + B²/8π`` (the Wilson-depressed τ = 1 level).

    Parameters
    ----------
    z_grid : array_like, (nz,)
        km.
    ln_p_ext : array_like, (nz,)
        ln of the field-free pressure on the grid (decreasing upward).
    p_inside : float
        Gas pressure of the magnetic model at its own τ₅₀₀ = 1 (dyn cm⁻²).
    field : float
        Field strength there (G).

    Returns
    -------
    float
        Height (km) of the magnetic model's τ = 1; negative = depressed.

    Examples
    --------
    >>> zg = np.linspace(-500, 500, 101)
    >>> round(pressure_balance_depth(zg, np.log(1e5) - zg / 100, 1e5, 0.0), 6)
    0.0
    """
    target = np.log(p_inside + field ** 2 / (8 * np.pi))
    lnp = np.asarray(ln_p_ext, dtype=np.float64)
    if not lnp[-1] <= target <= lnp[0]:
        raise ValueError(f"pressure balance for {field:.0f} G needs a deeper height grid (target "
                         f"{np.exp(target):.3g} dyn/cm² above the bottom pressure {np.exp(lnp[0]):.3g})")
    return float(np.interp(target, lnp[::-1], np.asarray(z_grid, dtype=np.float64)[::-1]))

