"""
Readers and the writer of model-atmosphere files; each reader returns `~gongsynth.Atmosphere` arguments.

Formats:

* **MURaM** native snapshot folders (``read_muram``): ``Header.NNNNNN`` and
  ``result_prim_0..7.NNNNNN`` (ρ, v, internal energy, B/√4π; float32, x
  vertical and fastest in the file), plus ``eosT``, ``eosP``, ``eosne`` when
  written.  MURaM's (x vertical, y, z) becomes gongsynth's (z up, x = MURaM y,
  y = MURaM z), a right-handed frame.
* **1-D models** (``read_1d``): SIR ``.mod`` (log τ₅₀₀, T, P_e, v_mic, B, v_LOS,
  inclination, azimuth, z, P_g, ρ), Hazel ``.1d`` (log τ₅₀₀, T, P_e, v_mic, v, B_x,
  B_y, B_z; put in hydrostatic equilibrium) and RH ``.atmos`` (column mass, T,
  n_e, v, v_turb and hydrogen populations).  Velocities in these files are
  line-of-sight velocities at disk centre, positive away from the observer
  (v_z = −v).
* **ART / Bifrost HDF5** (``read_art``): ``temperature``, ``dens``, ``xne``, ``z``
  (cm), ``dx`` ``dy`` (coordinates, cm) stored [1, y, x, z]; no velocity or field.
* **gongsynth HDF5** (``write_hdf5`` / ``read_hdf5``): datasets ``temperature`` (K),
  ``gas_pressure`` (dyn cm⁻²), ``density`` (g cm⁻³), ``electron_density``
  (cm⁻³), each (nz, ny, nx) and each optional except the temperature;
  ``velocity`` (3, nz, ny, nx) km/s and ``magnetic_field`` (3, nz, ny, nx) G with
  components (x, y, z), z up; ``microturbulence`` (km/s, broadcastable);
  ``z`` (nz,) km increasing upward; attribute ``pixel_size_km``; attribute
  ``format = "gongsynth-atmosphere-1"``.  A Bifrost, CO5BOLD or MANCHA cube
  written in this form (cgs, z up) is read as is.
"""
from __future__ import annotations

import math
import os
import warnings
from pathlib import Path

import numpy as np

from gongsynth.optional import import_optional
from gongsynth.sun.rt.eos import AMU, K_BOLTZMANN, MEAN_MASS_PER_H, PARTICLES_PER_H, electron_density
from gongsynth.sun.rt.hydrostatic import heights_from_column_mass, hydrostatic_tau_scale

__all__ = ["read_muram", "read_1d", "read_art", "read_hdf5", "write_hdf5", "FORMAT_TAG", "muram_temperature",
           "UNIFORM_PIXEL_KM"]

#: The ``format`` attribute of gongsynth's HDF5 atmosphere files.
FORMAT_TAG = "gongsynth-atmosphere-1"
#: The column spacing (km) given to a 1-D model: one horizontally uniform column, so any spacing is the
#: same atmosphere; this one (about 14 solar radii) makes the column cover a detector pixel at any viewing
#: angle down to μ = 1e-3 (14 arcsec there), so that a 1-D model tiles any field.
UNIFORM_PIXEL_KM = 1.0e7
_FIELDS = ("temperature", "gas_pressure", "density", "electron_density", "velocity", "magnetic_field",
           "microturbulence")


def _muram_file(folder, stem, iteration):
    return folder / f"{stem}.{iteration:06d}"


def muram_temperature(density, internal_energy):
    """
    Temperature and electron density from ρ and the internal energy per volume (gongsynth's EOS).

    e = 3/2 (n_H ΣA + n_e) kT + n_p χ_H (ideal gas with the ionisation energy of
    hydrogen; metals' ionisation energy and H₂ are left out), solved by bisection in T.

    Parameters
    ----------
    density, internal_energy : `numpy.ndarray`
        g cm⁻³ and erg cm⁻³.

    Returns
    -------
    (`numpy.ndarray`, `numpy.ndarray`)
        T (K) and n_e (cm⁻³).
    """
    rho = np.asarray(density, dtype=np.float64)
    eps = np.asarray(internal_energy, dtype=np.float64)
    nh = rho / (AMU * MEAN_MASS_PER_H)
    lo = np.full(rho.shape, 1000.0)
    hi = np.full(rho.shape, 3e7)
    chi = 13.5984 * 1.602176634e-12
    for _ in range(60):
        mid = np.sqrt(lo * hi)
        ne = electron_density(mid, hydrogen_density=nh)
        xh = np.clip(ne / nh, 0.0, 1.0)
        e_mid = 1.5 * (nh * PARTICLES_PER_H + ne) * K_BOLTZMANN * mid + nh * xh * chi
        high = e_mid > eps
        hi = np.where(high, mid, hi)
        lo = np.where(high, lo, mid)
    t = np.sqrt(lo * hi)
    return t, electron_density(t, hydrogen_density=nh)


def read_muram(directory, iteration=0):
    """
    Read a MURaM snapshot folder (see the module notes).

    Parameters
    ----------
    directory : str or path-like
        Folder with ``Header.NNNNNN`` and ``result_prim_*.NNNNNN``.
    iteration : int
        Snapshot number NNNNNN.

    Returns
    -------
    dict
        `~gongsynth.Atmosphere` keyword arguments (plain float32 arrays in
        K, dyn cm⁻², g cm⁻³, cm⁻³, km/s, G, km) and ``meta``.
    """
    folder = Path(directory)
    header = _muram_file(folder, "Header", iteration)
    if not header.is_file():
        raise FileNotFoundError(f"{folder}: no MURaM header {header.name} (is this a MURaM snapshot folder "
                                f"and is the iteration {iteration} right?)")
    values = np.loadtxt(header).ravel()
    if values.size < 6:
        raise ValueError(f"{header}: expected nx ny nz dx dy dz, got {values.tolist()}")
    nx, ny, nz = (int(v) for v in values[:3])
    dx, dy, dz = (float(v) for v in values[3:6])

    def read(stem, required=True):
        path = _muram_file(folder, stem, iteration)
        if not path.is_file():
            if required:
                raise FileNotFoundError(f"{folder}: MURaM file {path.name} is missing")
            return None
        data = np.fromfile(path, dtype="<f4")
        if data.size != nx * ny * nz:
            raise ValueError(f"{path}: {data.size} values, expected {nx} x {ny} x {nz} from {header.name}")
        # File order [z][y][x], x vertical: gongsynth (vertical, MURaM z, MURaM y) = (z, y, x).
        return np.ascontiguousarray(data.reshape(nz, ny, nx).transpose(2, 0, 1))

    rho = read("result_prim_0")
    vel = [read(f"result_prim_{i}") for i in (1, 2, 3)]        # MURaM vx (up), vy, vz in cm/s
    mag = [read(f"result_prim_{i}") for i in (5, 6, 7)]        # G / sqrt(4 pi)
    temp, pres, ne = read("eosT", False), read("eosP", False), read("eosne", False)
    derived = []
    if temp is None:
        temp, ne_eos = muram_temperature(rho, read("result_prim_4"))
        temp = temp.astype(np.float32)
        derived.append("temperature")
        if ne is None:
            ne = ne_eos.astype(np.float32)
            derived.append("electron_density")
    if derived:
        warnings.warn(f"{folder}: no MURaM eosT/eosP/eosne for iteration {iteration}; "
                      f"{', '.join(derived)} derived from density and internal energy with gongsynth's "
                      f"equation of state", stacklevel=3)
    scale = math.sqrt(4 * math.pi)
    velocity = np.stack([vel[1], vel[2], vel[0]]) * np.float32(1e-5)
    field = np.stack([mag[1], mag[2], mag[0]]) * np.float32(scale)
    z = (np.arange(nx) * dx * 1e-5).astype(np.float64)
    if abs(dy - dz) > 1e-6 * dy:
        raise ValueError(f"{header}: horizontal spacings differ ({dy} and {dz} cm); "
                         f"gongsynth needs square pixels")
    return dict(temperature=temp, gas_pressure=pres, density=rho, electron_density=ne, velocity=velocity,
                magnetic_field=field, z=z, pixel_size=dy * 1e-5,
                meta={"origin": "MURaM", "path": os.fspath(folder), "iteration": int(iteration),
                      "derived": derived})


def _read_rh_atmos(path):
    rows = [r for r in Path(path).read_text().splitlines() if r.strip() and not r.lstrip().startswith("*")]
    scale = rows[1].strip().lower()
    if not scale.startswith("mass"):
        raise ValueError(f"{path}: only RH atmospheres on a column-mass scale are read, got {rows[1]!r}")
    gravity = 10.0 ** float(rows[2].split()[0])
    n = int(rows[3].split()[0])
    data = np.array([r.split()[:5] for r in rows[4:4 + n]], dtype=np.float64)
    temp, ne, vel, vturb = data[:, 1], data[:, 2], data[:, 3], data[:, 4]
    cmass = 10.0 ** data[:, 0]
    nh = None
    if len(rows) >= 4 + 2 * n:
        pops = np.array([r.split() for r in rows[4 + n:4 + 2 * n]], dtype=np.float64)
        nh = pops.sum(axis=1)
    if nh is None:
        p = gravity * cmass
        nh = (p / (K_BOLTZMANN * temp) - ne) / PARTICLES_PER_H
    rho = nh * AMU * MEAN_MASS_PER_H
    pres = (nh * PARTICLES_PER_H + ne) * K_BOLTZMANN * temp
    z = heights_from_column_mass(cmass, rho, temp, ne, nh)
    return dict(temperature=temp, gas_pressure=pres, density=rho, electron_density=ne,
                vz=-vel, microturbulence=vturb, z=z)


def read_1d(path):
    """
    Read a 1-D model atmosphere (SIR ``.mod``, Hazel ``.1d`` or RH ``.atmos``) as a 1 × 1 column.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    dict
        `~gongsynth.Atmosphere` keyword arguments, heights bottom to top (z = 0 at τ₅₀₀ = 1).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such model-atmosphere file")
    suffix = path.suffix.lower()
    if suffix == ".atmos":
        cols = _read_rh_atmos(path)
        bx = by = bz = np.zeros_like(cols["temperature"])
    elif suffix in (".mod", ".1d"):
        skip = 1 if suffix == ".mod" else 4
        try:
            data = np.loadtxt(path, skiprows=skip, ndmin=2)
        except ValueError as exc:
            raise ValueError(f"{path}: not a readable {suffix} model ({exc})") from exc
        need = 11 if suffix == ".mod" else 8
        if data.shape[1] < need:
            raise ValueError(f"{path}: {suffix} models need {need} columns, found {data.shape[1]}")
        logtau, temp, pe = data[:, 0], data[:, 1], data[:, 2]
        ne_file = pe / (K_BOLTZMANN * temp)
        if suffix == ".mod":
            vturb, vlos = data[:, 3] * 1e-5, data[:, 5] * 1e-5
            b, inc, azi = data[:, 4], np.radians(data[:, 6]), np.radians(data[:, 7])
            bx, by, bz = b * np.sin(inc) * np.cos(azi), b * np.sin(inc) * np.sin(azi), b * np.cos(inc)
            z, pres, rho = data[:, 8], data[:, 9], data[:, 10]
            if np.all(pres <= 0) or np.all(z == 0):
                z, pres, rho = hydrostatic_tau_scale(logtau, temp)
        else:
            vturb, vlos, bx, by, bz = (data[:, i] for i in range(3, 8))
            z, pres, rho = hydrostatic_tau_scale(logtau, temp)
        cols = dict(temperature=temp, gas_pressure=pres, density=rho, electron_density=ne_file, vz=-vlos,
                    microturbulence=vturb, z=z)
    else:
        raise ValueError(f"{path}: unknown model format {suffix!r} (expected .mod, .1d or .atmos)")
    order = np.argsort(cols["z"])
    col = {k: np.asarray(v, dtype=np.float64)[order] for k, v in cols.items()}
    bx, by, bz = (np.asarray(b, dtype=np.float64)[order] for b in (bx, by, bz))
    zero = np.zeros_like(col["temperature"])

    def grid(a):
        return a[:, None, None].astype(np.float32)

    return dict(temperature=grid(col["temperature"]), gas_pressure=grid(col["gas_pressure"]),
                density=grid(col["density"]), electron_density=grid(col["electron_density"]),
                velocity=np.stack([grid(zero), grid(zero), grid(col["vz"])]),
                magnetic_field=np.stack([grid(bx), grid(by), grid(bz)]),
                microturbulence=grid(col["microturbulence"]), z=col["z"], pixel_size=UNIFORM_PIXEL_KM,
                meta={"origin": f"1-D model ({suffix})", "path": os.fspath(path)})


def read_art(path):
    """
    Read the ART / Bifrost-like HDF5 model (thermodynamics only; v = B = 0, with a warning).

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    dict
        `~gongsynth.Atmosphere` keyword arguments.
    """
    h5py = import_optional("h5py", "h5py")
    with h5py.File(path, "r") as f:
        missing = [k for k in ("temperature", "dens", "xne", "z", "dx") if k not in f]
        if missing:
            raise ValueError(f"{path}: not an ART model file, missing dataset(s) {missing}")
        temp, rho, ne = (np.asarray(f[k][0], dtype=np.float32) for k in ("temperature", "dens", "xne"))
        zset = f["z"]
        z = np.asarray(zset[0, 0, 0, :] if zset.ndim == 4 else zset[...], dtype=np.float64).ravel() * 1e-5
        dx = np.diff(np.asarray(f["dx"][:], dtype=np.float64).ravel())
    pixel = float(np.median(dx)) * 1e-5 if dx.size else 1.0
    warnings.warn(f"{path}: the ART model has no velocity or magnetic field; both set to zero", stacklevel=3)
    order = np.argsort(z)

    def cube(a):
        return np.ascontiguousarray(np.moveaxis(a, -1, 0)[order])

    return dict(temperature=cube(temp), density=cube(rho), electron_density=cube(ne), z=z[order],
                pixel_size=pixel, meta={"origin": "ART/Bifrost HDF5", "path": os.fspath(path)})


def read_hdf5(path):
    """
    Read gongsynth's own HDF5 atmosphere format (see the module notes).

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    dict
        `~gongsynth.Atmosphere` keyword arguments.
    """
    h5py = import_optional("h5py", "h5py")
    with h5py.File(path, "r") as f:
        if f.attrs.get("format") != FORMAT_TAG:
            raise ValueError(f"{path}: not a gongsynth atmosphere file (attribute format != {FORMAT_TAG!r})")
        for key in ("temperature", "z"):
            if key not in f:
                raise ValueError(f"{path}: missing dataset {key!r}")
        out = {k: np.asarray(f[k][...]) for k in _FIELDS if k in f}
        out["z"] = np.asarray(f["z"][...], dtype=np.float64)
        out["pixel_size"] = float(f.attrs["pixel_size_km"])
        out["meta"] = {"origin": "gongsynth HDF5", "path": os.fspath(path)}
    return out


def write_hdf5(path, fields, z, pixel_size, *, overwrite=False):
    """
    Write gongsynth's HDF5 atmosphere format atomically.

    Parameters
    ----------
    path : str or path-like
    fields : dict
        Name → float32 array in the units of the module notes (None entries skipped).
    z : `numpy.ndarray`
        Heights (km).
    pixel_size : float
        km.
    overwrite : bool
        Replace an existing file.
    """
    h5py = import_optional("h5py", "h5py")
    path = Path(path)
    if path.exists() and not overwrite:
        raise FileExistsError(f"{path} exists (pass overwrite=True to replace it)")
    tmp = path.with_name(path.name + ".part")
    with h5py.File(tmp, "w") as f:
        f.attrs["format"] = FORMAT_TAG
        f.attrs["pixel_size_km"] = float(pixel_size)
        f.create_dataset("z", data=np.asarray(z, dtype=np.float64))
        for name, value in fields.items():
            if value is not None:
                f.create_dataset(name, data=np.asarray(value), compression="gzip", compression_opts=1)
    os.replace(tmp, path)
