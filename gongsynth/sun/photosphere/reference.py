"""
Optional true radiative transfer of Ni I 676.78 nm with lightweaver, to check the ME line.

`falc_stokes` solves the polarised transfer equation for the FAL-C model
atmosphere (Fontenla, Avrett & Loeser 1993) with a uniform magnetic field,
using lightweaver (Osborne & Milić 2021; ``pip install lightweaver``) and its
RH Ni I model atom, in LTE as the paper ran RH.  The Ni I 676.78 nm line is
the a¹S₀ → z³P°₁ transition (J = 0 → 1): a normal Zeeman triplet with
g = 1.5 in LS coupling.  gongsynth does not need lightweaver; this module
raises `ImportError` with an explanation when it is missing.
"""
from __future__ import annotations

import warnings

import astropy.units as u
import numpy as np

from gongsynth.instrument import GONGInstrument
from gongsynth.sun.stokes import StokesCube
from gongsynth.validation import check_quantity, check_wavelength_grid

__all__ = ["falc_stokes"]

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
            "falc_stokes needs the optional dependency lightweaver (pip install lightweaver)"
        ) from exc
    return lightweaver


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

    Examples
    --------
    >>> import astropy.units as u
    >>> cube = falc_stokes([0, 100] * u.G)        # doctest: +SKIP
    >>> cube.shape                                 # doctest: +SKIP
    (1, 2, 51)
    """
    lw = _lightweaver()
    instrument = GONGInstrument() if instrument is None else instrument
    check_quantity(field, u.G, "field")
    check_quantity(inclination, u.deg, "inclination")
    fields = np.atleast_1d(field.to_value(u.G)).astype(float)
    if fields.ndim != 1 or np.any(fields < 0) or not np.isfinite(fields).all():
        raise ValueError(f"field must be non-negative finite strengths (scalar or 1-D), got {field}")
    if wavelength is None:
        from gongsynth.sun.photosphere.synthesis import default_wavelength
        wavelength = default_wavelength()
    check_wavelength_grid(wavelength, instrument.line_wavelength)
    gamma = float(inclination.to_value(u.rad))

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
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
                                atoms.MgII_atom(), atoms.N_atom(), atoms.Na_atom(), atoms.S_atom(),
                                nickel])
        aset.set_detailed_static("Ni")
        lam0_vac = float(target.lambda0)
        window = np.linspace(lam0_vac - 0.12, lam0_vac + 0.12, 481)
        spect = aset.compute_wavelength_grid(extraWavelengths=window)
        shift = lam0_vac - instrument.line_wavelength.to_value(u.nm)   # vacuum - air at the line
        lam_out = wavelength.to_value(u.nm) + shift
        stokes_i, stokes_v = [], []
        for b in fields:
            atmos = _falc(lw, b * 1e-4, gamma)
            atmos.rays([1.0])
            pops = aset.compute_eq_pops(atmos)
            ctx = lw.Context(atmos, spect, pops, Nthreads=1, conserveCharge=False)
            ctx.formal_sol_gamma_matrices()
            if b > 0:
                ctx.single_stokes_fs()
            wl = np.asarray(ctx.spect.wavelength)
            i = np.asarray(ctx.spect.I).reshape(wl.size, -1)[:, 0]
            v = (np.asarray(ctx.spect.Quv).reshape(3, wl.size, -1)[2, :, 0] if b > 0
                 else np.zeros_like(i))
            order = np.argsort(wl)
            stokes_i.append(np.interp(lam_out, wl[order], i[order]))
            stokes_v.append(np.interp(lam_out, wl[order], v[order]))
    I = np.array(stokes_i, dtype=np.float32)[None] * _RH_UNIT
    V = np.array(stokes_v, dtype=np.float32)[None] * _RH_UNIT
    zero = np.zeros_like(I)
    blos = (fields * np.cos(gamma))[None].astype(np.float32) * u.G
    meta = {"origin": "gongsynth.sun.photosphere.reference.falc_stokes",
            "code": f"lightweaver {getattr(lw, '__version__', '?')}", "atmosphere": "FAL-C",
            "lte": True, "inclination_deg": float(np.degrees(gamma))}
    return StokesCube(I, zero, zero, V, wavelength, 96 * u.km, blos=blos, meta=meta)
