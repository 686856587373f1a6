r"""
Hydrostatic equilibrium for 1-D models given on an optical-depth or column-mass scale.

On the τ₅₀₀ scale, dP/dτ = g / κ(T, P) with κ the continuum opacity per gram
at 500 nm (`~gongsynth.sun.rt.opacity.continuum_opacity`) and n_e from the
equation of state; the integration runs down from the top point (where
P = g τ/κ is solved by iteration) with a trapezoidal step iterated to
convergence.  Heights follow from dz = −dτ/(κρ), with z = 0 at τ₅₀₀ = 1.
On a column-mass scale z follows from dz = −dm/ρ (the pressure is g m).
Solar surface gravity g = 2.74 × 10⁴ cm s⁻².
"""
from __future__ import annotations

import numpy as np

from gongsynth.sun.rt.eos import solve_state
from gongsynth.sun.rt.opacity import continuum_opacity

__all__ = ["SOLAR_GRAVITY", "hydrostatic_tau_scale", "heights_from_column_mass", "tau500"]

#: Solar surface gravity, cm s⁻².
SOLAR_GRAVITY = 2.74e4


def _kappa_mass(t, p):
    s = solve_state(t, gas_pressure=p)
    return continuum_opacity(500.0, t, s["electron_density"], s["hydrogen_density"]) / s["density"], s


def hydrostatic_tau_scale(log_tau, temperature, gravity=SOLAR_GRAVITY):
    """
    Put a model T(log τ₅₀₀) in hydrostatic equilibrium.

    Parameters
    ----------
    log_tau : array_like
        log10 τ₅₀₀ (any order).
    temperature : array_like
        K.
    gravity : float
        cm s⁻².

    Returns
    -------
    z, gas_pressure, density : `numpy.ndarray`
        km (0 at τ₅₀₀ = 1, increasing upward), dyn cm⁻², g cm⁻³, in the input order.

    Examples
    --------
    >>> import numpy as np
    >>> z, p, rho = hydrostatic_tau_scale(np.linspace(-4, 1, 51), np.full(51, 5000.0))
    >>> bool(np.all(np.diff(z) < 0)) and bool(np.all(np.diff(p) > 0))
    True
    """
    lt = np.asarray(log_tau, dtype=np.float64)
    temp = np.asarray(temperature, dtype=np.float64)
    order = np.argsort(lt)
    lt, temp = lt[order], temp[order]
    tau = 10.0 ** lt
    p = np.empty_like(tau)
    guess = 1e2
    for _ in range(50):
        k, _ = _kappa_mass(temp[:1], np.array([guess]))
        new = gravity * tau[0] / k[0]
        if abs(new - guess) < 1e-8 * new:
            break
        guess = new
    p[0] = guess
    k_prev = _kappa_mass(temp[:1], p[:1])[0][0]
    for i in range(1, tau.size):
        dt = tau[i] - tau[i - 1]
        pi = p[i - 1] + gravity * dt / k_prev
        for _ in range(30):
            ki = _kappa_mass(temp[i:i + 1], np.array([pi]))[0][0]
            new = p[i - 1] + 0.5 * gravity * dt * (1.0 / k_prev + 1.0 / ki)
            if abs(new - pi) < 1e-10 * new:
                pi = new
                break
            pi = new
        p[i] = pi
        k_prev = _kappa_mass(temp[i:i + 1], p[i:i + 1])[0][0]
    kappa_m, state = _kappa_mass(temp, p)
    rho = state["density"]
    kappa = kappa_m * rho                                     # cm⁻¹
    dz = np.diff(tau) / (0.5 * (kappa[1:] + kappa[:-1]))      # cm, positive downward
    depth = np.concatenate([[0.0], np.cumsum(dz)])
    z = -(depth - np.interp(0.0, lt, depth)) * 1e-5
    inverse = np.empty_like(order)
    inverse[order] = np.arange(order.size)
    return z[inverse], p[inverse], rho[inverse]


def heights_from_column_mass(column_mass, density, temperature, electron_density, hydrogen_density):
    """
    Heights (km, 0 at τ₅₀₀ = 1) of a model on a column-mass scale.

    Parameters
    ----------
    column_mass : array_like
        g cm⁻², increasing inward.
    density, temperature, electron_density, hydrogen_density : array_like
        g cm⁻³, K, cm⁻³, cm⁻³.

    Returns
    -------
    `numpy.ndarray`
        z in km, in the input order.
    """
    m = np.asarray(column_mass, dtype=np.float64)
    rho = np.asarray(density, dtype=np.float64)
    order = np.argsort(m)
    m_s, rho_s = m[order], rho[order]
    depth = np.concatenate([[0.0], np.cumsum(np.diff(m_s) * 0.5 * (1 / rho_s[1:] + 1 / rho_s[:-1]))])
    tau = tau500(depth[::-1] * -1.0, temperature[order][::-1], electron_density[order][::-1],
                 hydrogen_density[order][::-1])[::-1]
    z0 = np.interp(0.0, np.log10(np.maximum(tau, 1e-30)), depth)
    z = -(depth - z0) * 1e-5
    out = np.empty_like(z)
    out[order] = z
    return out


def tau500(z_cm, temperature, electron_density, hydrogen_density):
    """
    Continuum optical depth at 500 nm along the vertical, from the top down.

    Parameters
    ----------
    z_cm : array_like
        Heights (cm), increasing.
    temperature, electron_density, hydrogen_density : array_like
        K, cm⁻³, cm⁻³ at those heights.

    Returns
    -------
    `numpy.ndarray`
        τ₅₀₀ at each height (0 at the top point).
    """
    k = continuum_opacity(500.0, temperature, electron_density, hydrogen_density)
    z = np.asarray(z_cm, dtype=np.float64)
    seg = 0.5 * (k[1:] + k[:-1]) * np.diff(z)
    return np.concatenate([np.cumsum(seg[::-1])[::-1], [0.0]])
