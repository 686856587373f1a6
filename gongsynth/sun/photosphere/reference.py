"""
Optional true radiative transfer of Ni I 676.78 nm with lightweaver: the independent reference.

`falc_stokes` solves the polarised transfer equation for the FAL-C model
atmosphere (Fontenla, Avrett & Loeser 1993) with a uniform magnetic field at
disk centre, using lightweaver (Osborne & Milić 2021; ``pip install
lightweaver``) and its RH Ni I model atom, in LTE as the paper ran RH.
`lightweaver_stokes` does the same for any 1-D `~gongsynth.Atmosphere` and any
μ, with both codes seeing the same atmosphere (see its notes), and
`heated_atmosphere` makes the temperature-offset models of the comparison.  The
Ni I 676.78 nm line is the a¹S₀ → z³P°₁ transition (J = 0 → 1): a normal Zeeman
triplet with g = 1.5 in LS coupling.  gongsynth does not need lightweaver; the
functions raise `ImportError` with an explanation when it is missing.
"""
from __future__ import annotations

import warnings

import astropy.units as u
import numpy as np

from gongsynth.instruments.gong.parameters import GONGInstrument
from gongsynth.sun.rt.atomic_data import NiLineData
from gongsynth.sun.rt.eos import solve_state
from gongsynth.sun.stokes import RADIANCE_UNIT, StokesCube
from gongsynth.validation import check_quantity, check_wavelength_grid

__all__ = ["falc_stokes", "lightweaver_stokes", "lightweaver_state", "lightweaver_partition_levels",
           "heated_atmosphere", "refined_atmosphere"]

_RH_UNIT = u.Unit("J / (s m2 Hz sr)")


def _lightweaver():
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")    # "No config file found" on first import
            import lightweaver
            import lightweaver.fal
            import lightweaver.rh_atoms
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError(
            "the lightweaver reference needs the optional dependency lightweaver (pip install lightweaver)"
        ) from exc
    return lightweaver


def _radiative_set(lw):
    """Lightweaver's RH atoms with Ni I in detailed static (LTE) and the 676.96 nm (vacuum) line."""
    atoms = lw.rh_atoms
    nickel = atoms.NiI_atom()
    target = None
    for line in nickel.lines:
        # Other Ni lines (outside the window) need some Zeeman pattern to be
        # polarisable at all; their J values do not allow LS coupling.
        ls = line.iLevel.lsCoupling and line.jLevel.lsCoupling
        if abs(line.iLevel.J - line.jLevel.J) > 1 or not ls:
            line.gLandeEff = 1.0
        if abs(line.lambda0 - 676.964) < 0.01:
            target = line
    if target is None:  # pragma: no cover - depends on the atom file
        raise ImportError("lightweaver's NiI_atom has no 676.96 nm (vacuum) line")
    aset = lw.RadiativeSet([atoms.H_6_atom(), atoms.C_atom(), atoms.O_atom(), atoms.Si_atom(),
                            atoms.Al_atom(), atoms.CaII_atom(), atoms.Fe_atom(), atoms.He_9_atom(),
                            atoms.MgII_atom(), atoms.N_atom(), atoms.Na_atom(), atoms.S_atom(), nickel])
    aset.set_detailed_static("Ni")
    return aset, float(target.lambda0)


def _emergent(lw, aset, spect, atmos, polarised, lte_scattering, lam_out):
    """Emergent (I, Q, U, V) of a 1-D lightweaver atmosphere with one ray, at vacuum ``lam_out`` (nm)."""
    pops = aset.compute_eq_pops(atmos)
    ctx = lw.Context(atmos, spect, pops, Nthreads=1, conserveCharge=False)
    wl = np.asarray(ctx.spect.wavelength)
    # J = B_ν(T): the background scattering emits the Planck function, so S = B
    # everywhere (gongsynth's LTE treatment of Thomson and Rayleigh scattering).
    # Set before each formal solution: one ray of zero weight resets J to 0.
    mean_j = lw.planck(np.asarray(atmos.temperature)[None, :], wl[:, None]) if lte_scattering else 0.0
    ctx.spect.J[:] = mean_j
    ctx.formal_sol_gamma_matrices()
    if polarised:
        ctx.spect.J[:] = mean_j
        ctx.single_stokes_fs()
    i = np.asarray(ctx.spect.I).reshape(wl.size, -1)[:, 0]
    quv = (np.asarray(ctx.spect.Quv).reshape(3, wl.size, -1)[:, :, 0] if polarised
           else np.zeros((3, wl.size)))
    order = np.argsort(wl)
    return [np.interp(lam_out, wl[order], s[order]) for s in (i, *quv)]


def _falc(lw, field_tesla, inclination_rad):
    fal = lw.fal
    n = fal.temp.size
    return lw.Atmosphere.make_1d(
        lw.ScaleType.ColumnMass,
        depthScale=(fal.cmass << u.Unit("g cm-2")).to_value("kg m-2"),
        temperature=np.copy(fal.temp),
        ne=(fal.ne << u.Unit("cm-3")).to_value("m-3"),
        vlos=np.zeros(n),
        vturb=(fal.vturb << u.Unit("km/s")).to_value("m/s"),
        hydrogenPops=(fal.nh << u.Unit("cm-3")).to_value("m-3"),
        B=np.full(n, field_tesla), gammaB=np.full(n, inclination_rad), chiB=np.zeros(n),
    )


def _check_fields(field, inclination):
    check_quantity(field, u.G, "field")
    check_quantity(inclination, u.deg, "inclination")
    fields = np.atleast_1d(field.to_value(u.G)).astype(float)
    if fields.ndim != 1 or np.any(fields < 0) or not np.isfinite(fields).all():
        raise ValueError(f"field must be non-negative finite strengths (scalar or 1-D), got {field}")
    return fields, float(inclination.to_value(u.rad))


def _default_wavelength():
    from gongsynth.sun.photosphere.synthesis import default_wavelength
    return default_wavelength()


def falc_stokes(field, *, inclination=0 * u.deg, wavelength=None, instrument=None):
    """
    LTE Stokes I and V of Ni I 676.78 nm at disk centre for FAL-C with uniform fields.

    Parameters
    ----------
    field : `~astropy.units.Quantity`, scalar or (n,)
        Field strengths (G); one column per value.
    inclination : `~astropy.units.Quantity`, optional
        Inclination of the field from the vertical (the line of sight), same for all.
    wavelength : `~astropy.units.Quantity`, optional
        Air wavelengths to interpolate onto (default: the paper's 51 points).
    instrument : `~gongsynth.GONGInstrument`, optional
        Source of the rest (air) wavelength: lightweaver's vacuum grid is
        shifted so that its line centre falls on ``instrument.line_wavelength``.

    Returns
    -------
    `~gongsynth.sun.stokes.StokesCube`
        Shape (1, n, nλ), μ = 1, ``blos`` = B cos(inclination).  Q and U are
        set to zero (only I and V are compared with the ME synthesis).

    Raises
    ------
    ImportError
        If lightweaver is not installed.

    Notes
    -----
    Lightweaver's own FAL-C (column-mass scale, its n_e and n_H), one formal
    solution with the mean intensity of the background scattering left at
    zero.  `lightweaver_stokes` is the general form used for the validation.

    Examples
    --------
    >>> import astropy.units as u
    >>> cube = falc_stokes([0, 100] * u.G)        # doctest: +SKIP
    >>> cube.shape                                 # doctest: +SKIP
    (1, 2, 51)
    """
    lw = _lightweaver()
    instrument = GONGInstrument() if instrument is None else instrument
    fields, gamma = _check_fields(field, inclination)
    wavelength = _default_wavelength() if wavelength is None else wavelength
    check_wavelength_grid(wavelength, instrument.line_wavelength)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        aset, lam0_vac = _radiative_set(lw)
        window = np.linspace(lam0_vac - 0.12, lam0_vac + 0.12, 481)
        spect = aset.compute_wavelength_grid(extraWavelengths=window)
        shift = lam0_vac - instrument.line_wavelength.to_value(u.nm)   # vacuum - air at the line
        lam_out = wavelength.to_value(u.nm) + shift
        stokes_i, stokes_v = [], []
        for b in fields:
            atmos = _falc(lw, b * 1e-4, gamma)
            atmos.rays([1.0])
            i, _, _, v = _emergent(lw, aset, spect, atmos, b > 0, False, lam_out)
            stokes_i.append(i)
            stokes_v.append(v)
    I = np.array(stokes_i, dtype=np.float32)[None] * _RH_UNIT
    V = np.array(stokes_v, dtype=np.float32)[None] * _RH_UNIT
    zero = np.zeros_like(I)
    blos = (fields * np.cos(gamma))[None].astype(np.float32) * u.G
    meta = {"origin": "gongsynth.sun.photosphere.reference.falc_stokes",
            "code": f"lightweaver {getattr(lw, '__version__', '?')}", "atmosphere": "FAL-C",
            "lte": True, "inclination_deg": float(np.degrees(gamma))}
    return StokesCube(I, zero, zero, V, wavelength, 96 * u.km, blos=blos, meta=meta)


def lightweaver_state(atmosphere):
    """
    The column both codes are given: heights, T, n_e, n_H, microturbulence and v_z.

    Parameters
    ----------
    atmosphere : `~gongsynth.Atmosphere`
        A horizontally uniform atmosphere (a 1-D model, e.g. from
        `~gongsynth.Atmosphere.from_1d`); column (0, 0) is used.

    Returns
    -------
    dict
        ``z`` (km, bottom to top), ``temperature`` (K), ``electron_density``
        and ``hydrogen_density`` (cm⁻³), ``microturbulence`` and ``vz`` (km/s,
        > 0 upward), float64 (nz,) arrays.  n_e and n_H are what
        `gongsynth.rt.synthesize` uses: n_H from the density (else the gas
        pressure) with gongsynth's equation of state, n_e as stored (else from
        that equation of state).

    Examples
    --------
    >>> import numpy as np, astropy.units as u
    >>> import gongsynth
    >>> t = np.full((3, 1, 1), 6000.0) * u.K
    >>> p = np.full((3, 1, 1), 1e5) * u.Unit("dyn cm-2")
    >>> atm = gongsynth.Atmosphere(t, [0, 50, 100] * u.km, 96 * u.km, gas_pressure=p)
    >>> state = lightweaver_state(atm)
    >>> sorted(state)
    ['electron_density', 'hydrogen_density', 'microturbulence', 'temperature', 'vz', 'z']
    """
    from gongsynth.sun.atmosphere import Atmosphere  # late: same layer, heavy import

    if not isinstance(atmosphere, Atmosphere):
        raise TypeError(f"atmosphere must be a gongsynth.Atmosphere, got {type(atmosphere).__name__}")

    def column(name):
        value = atmosphere.raw(name)
        return None if value is None else np.asarray(value[..., 0, 0], dtype=np.float64)

    for name in ("temperature", "gas_pressure", "density", "electron_density", "microturbulence"):
        value = atmosphere.raw(name)
        if value is not None and np.ptp(np.asarray(value, dtype=np.float64), axis=(-2, -1)).max() > 0:
            raise ValueError(f"lightweaver_stokes needs a horizontally uniform atmosphere ({name} varies)")
    vel = atmosphere.raw("velocity")
    if vel is not None and np.any(np.asarray(vel[:2]) != 0):
        raise ValueError("lightweaver_stokes (a 1-D code) takes vertical velocities only")
    temp = column("temperature")
    rho = column("density")
    state = solve_state(temp, gas_pressure=column("gas_pressure") if rho is None else None, density=rho,
                        electron_density_=column("electron_density"))
    vz = np.zeros_like(temp) if vel is None else np.asarray(vel[2, :, 0, 0], dtype=np.float64)
    return {"z": atmosphere.z.to_value(u.km).astype(np.float64), "temperature": temp,
            "electron_density": state["electron_density"], "hydrogen_density": state["hydrogen_density"],
            "microturbulence": column("microturbulence"), "vz": vz}


@u.quantity_input(temperature_offset=u.K)
def heated_atmosphere(atmosphere, temperature_offset):
    """
    A 1-D atmosphere with T offset everywhere at the same heights and gas pressure.

    Parameters
    ----------
    atmosphere : `~gongsynth.Atmosphere`
        The model (needs its gas pressure, e.g. from `~gongsynth.Atmosphere.from_1d`).
    temperature_offset : `~astropy.units.Quantity`
        Added to the temperature at every height.

    Returns
    -------
    `~gongsynth.Atmosphere`
        Same z and P; T + ΔT; n_e, n_H and ρ from gongsynth's equation of state
        at (T + ΔT, P).  Not re-stratified: at the same pressure the hotter gas
        is less dense, and the comparison only needs both codes to see one
        atmosphere.

    Examples
    --------
    >>> import numpy as np, astropy.units as u
    >>> import gongsynth
    >>> t = np.full((3, 1, 1), 6000.0) * u.K
    >>> p = np.full((3, 1, 1), 1e5) * u.Unit("dyn cm-2")
    >>> atm = gongsynth.Atmosphere(t, [0, 50, 100] * u.km, 96 * u.km, gas_pressure=p)
    >>> hot = heated_atmosphere(atm, 500 * u.K)
    >>> float(hot.temperature[0, 0, 0].value)
    6500.0
    """
    p = atmosphere.raw("gas_pressure")
    if p is None:
        raise ValueError("heated_atmosphere needs the atmosphere's gas pressure")
    temp = np.asarray(atmosphere.raw("temperature"), dtype=np.float64) + temperature_offset.to_value(u.K)
    if np.any(temp <= 0):
        raise ValueError(f"temperature_offset {temperature_offset} makes the temperature non-positive")
    st = solve_state(temp, gas_pressure=np.asarray(p, dtype=np.float64))
    unit = {"gas_pressure": u.Unit("dyn cm-2"), "density": u.Unit("g cm-3"),
            "electron_density": u.Unit("cm-3")}
    return atmosphere.replace(temperature=temp * u.K, **{k: st[k] * unit[k] for k in unit})


def lightweaver_stokes(atmosphere, field, *, inclination=0 * u.deg, mu=1.0, wavelength=None, line=None,
                       lte_scattering=True):
    """
    Lightweaver's LTE Stokes spectra of Ni I 676.78 nm for a 1-D atmosphere at any μ.

    Parameters
    ----------
    atmosphere : `~gongsynth.Atmosphere`
        A horizontally uniform (1-D) model with vertical velocities only (v_z > 0
        upward, a blueshift at μ = 1 in both codes); its magnetic field is ignored.
    field : `~astropy.units.Quantity`, scalar or (n,)
        Uniform field strengths (G); one output column per value.
    inclination : `~astropy.units.Quantity`, optional
        Inclination of the field from the vertical, in the plane of the ray
        and tilted towards the observer.
    mu : float, optional
        cos θ of the ray (default 1).
    wavelength : `~astropy.units.Quantity`, optional
        Air wavelengths (default: the paper's 51 points).
    line : `~gongsynth.sun.rt.atomic_data.NiLineData`, optional
        Only its rest (air) wavelength is used: lightweaver's vacuum line centre
        is put there.  Everything else is the atom's.
    lte_scattering : bool, optional
        Give the background scattering the Planck function as mean intensity,
        so that the source function is B everywhere, as in gongsynth (default).
        False leaves lightweaver's mean intensity at zero (as `falc_stokes`).

    Returns
    -------
    `~gongsynth.sun.stokes.StokesCube`
        Shape (1, n, nλ) (per unit wavelength, converted at lightweaver's
        vacuum wavelengths), ``mu``, ``blos`` = the field
        along the ray.  It corresponds to ``gongsynth.rt.synthesize(atm, mu=mu,
        azimuth=0 * u.deg)`` with ``atm`` holding the field (B sin γ, 0, B cos γ):
        the same angle between field and ray, so the same I and V; Q and U are
        in lightweaver's frame (reference direction: the vertical projected on
        the sky; at μ = 1 the x axis).

    Raises
    ------
    ImportError
        If lightweaver is not installed.

    Notes
    -----
    Both codes see one atmosphere: lightweaver's is built on gongsynth's
    geometric height scale from `lightweaver_state` (T, n_e, n_H,
    microturbulence and v_z exactly as `gongsynth.rt.synthesize` uses them),
    with its RH atoms in LTE (Ni I held at its LTE populations, its own
    background opacities and its thermalised lower boundary), one ray at ``mu``
    (lightweaver's ``rays``), and its polarised formal solution.  For
    `gongsynth.rt.synthesize` to use the atom's Ni I partition functions too, pass
    it ``NiLineData(partition_levels=...)`` built from the atom's levels
    (`lightweaver_partition_levels`).

    Examples
    --------
    >>> import astropy.units as u
    >>> import gongsynth
    >>> atm = gongsynth.Atmosphere.from_1d("FALC_82.atmos")                 # doctest: +SKIP
    >>> cube = lightweaver_stokes(atm, [0, 1000] * u.G, mu=0.5)              # doctest: +SKIP
    >>> cube.shape                                                           # doctest: +SKIP
    (1, 2, 51)
    """
    lw = _lightweaver()
    fields, gamma = _check_fields(field, inclination)
    mu = float(mu)
    if not 0.0 < mu <= 1.0:
        raise ValueError(f"mu must be in (0, 1], got {mu}")
    line = NiLineData() if line is None else line
    wavelength = _default_wavelength() if wavelength is None else wavelength
    check_wavelength_grid(wavelength, line.wavelength_nm * u.nm)
    st = lightweaver_state(atmosphere)

    def top(a):                            # lightweaver wants the top first, contiguous
        return np.ascontiguousarray(a[::-1])

    n = st["z"].size

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        aset, lam0_vac = _radiative_set(lw)
        shift = lam0_vac - line.wavelength_nm                  # vacuum - air at the line
        lam_out = wavelength.to_value(u.nm) + shift
        window = np.linspace(lam0_vac - 0.12, lam0_vac + 0.12, 481)
        spect = aset.compute_wavelength_grid(extraWavelengths=np.union1d(window, lam_out))
        out = [[] for _ in range(4)]
        for b in fields:
            atmos = lw.Atmosphere.make_1d(
                lw.ScaleType.Geometric, depthScale=top(st["z"]) * 1e3,
                temperature=top(st["temperature"]), ne=top(st["electron_density"]) * 1e6,
                nHTot=top(st["hydrogen_density"]) * 1e6, vturb=top(st["microturbulence"]) * 1e3,
                vlos=top(st["vz"]) * 1e3,      # lightweaver's v_z is positive upward too (blueshift at μ = 1)
                B=np.full(n, b * 1e-4), gammaB=np.full(n, gamma), chiB=np.zeros(n), convertScales=False)
            atmos.rays([mu])
            for dst, src in zip(out, _emergent(lw, aset, spect, atmos, b > 0, lte_scattering, lam_out)):
                dst.append(src)
    # Per frequency -> per wavelength at lightweaver's (vacuum) wavelengths: I_λ = I_ν c / λ².
    per_lambda = (1.0 * _RH_UNIT).to_value(RADIANCE_UNIT, u.spectral_density(lam_out * u.nm))
    stokes = [(np.array(s) * per_lambda).astype(np.float32)[None] * RADIANCE_UNIT for s in out]
    blos = fields * (np.cos(gamma) * mu + np.sin(gamma) * np.sqrt(1.0 - mu * mu))
    meta = {"origin": "gongsynth.sun.photosphere.reference.lightweaver_stokes",
            "code": f"lightweaver {getattr(lw, '__version__', '?')}", "lte": True, "mu": mu,
            "inclination_deg": float(np.degrees(gamma)), "lte_scattering": bool(lte_scattering),
            "atmosphere": dict(atmosphere.meta)}
    return StokesCube(*stokes, wavelength, atmosphere.pixel_size, mu=mu,
                      blos=blos[None].astype(np.float32) * u.G, meta=meta)


def lightweaver_partition_levels():
    """
    The Ni I and Ni II levels of lightweaver's RH Ni I atom, for `NiLineData`'s ``partition_levels``.

    Returns
    -------
    tuple
        ``((E_cm, g, stage), ...)``.

    Raises
    ------
    ImportError
        If lightweaver is not installed.

    Examples
    --------
    >>> from gongsynth.sun.rt import NiLineData
    >>> line = NiLineData(partition_levels=lightweaver_partition_levels())   # doctest: +SKIP
    """
    lw = _lightweaver()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return tuple((float(lv.E), float(lv.g), int(lv.stage)) for lv in lw.rh_atoms.NiI_atom().levels)


def refined_atmosphere(atmosphere, factor):
    """
    A 1-D atmosphere on a grid ``factor`` times finer in height (each interval split evenly).

    Parameters
    ----------
    atmosphere : `~gongsynth.Atmosphere`
        A horizontally uniform model (column (0, 0) is used).
    factor : int
        Sub-intervals per original interval (1 returns the column unchanged).

    Returns
    -------
    `~gongsynth.Atmosphere`
        (nz - 1) · factor + 1 heights, 1 × 1 column: T, microturbulence, velocity
        and field interpolated linearly in z; P, ρ and n_e linearly in their
        logarithm (exponential between the model's points, as in hydrostatic
        equilibrium).  Used to separate the formal solvers' discretisation from
        other differences: both codes are given the same refined atmosphere.

    Examples
    --------
    >>> import numpy as np, astropy.units as u
    >>> import gongsynth
    >>> t = np.full((3, 1, 1), 6000.0) * u.K
    >>> p = np.array([1e5, 1e4, 1e3])[:, None, None] * u.Unit("dyn cm-2")
    >>> atm = gongsynth.Atmosphere(t, [0, 100, 200] * u.km, 96 * u.km, gas_pressure=p)
    >>> fine = refined_atmosphere(atm, 2)
    >>> fine.shape, round(float(fine.gas_pressure[1, 0, 0].value))
    ((5, 1, 1), 31623)
    """
    factor = int(factor)
    if factor < 1:
        raise ValueError(f"factor must be a positive integer, got {factor}")
    z = atmosphere.z.to_value(u.km)
    zz = np.interp(np.linspace(0.0, z.size - 1.0, (z.size - 1) * factor + 1), np.arange(z.size), z)
    args = {}
    for name in ("temperature", "gas_pressure", "density", "electron_density", "microturbulence",
                 "velocity", "magnetic_field"):
        value = atmosphere.raw(name)
        if value is None:
            continue
        col = np.asarray(value[..., 0, 0], dtype=np.float64)
        unit = getattr(atmosphere, name).unit
        if name in ("gas_pressure", "density", "electron_density"):
            fine = np.exp(np.interp(zz, z, np.log(col)))
        elif col.ndim == 2:
            fine = np.stack([np.interp(zz, z, c) for c in col])
        else:
            fine = np.interp(zz, z, col)
        args[name] = fine[..., None, None] * unit
    from gongsynth.sun.atmosphere import Atmosphere  # late: same layer, heavy import
    return Atmosphere(args.pop("temperature"), zz * u.km, atmosphere.pixel_size, meta=dict(atmosphere.meta),
                      **args)
