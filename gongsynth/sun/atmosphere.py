"""
`Atmosphere`: a 3-D model atmosphere on a horizontally periodic grid.

Arrays are (nz, ny, nx) with heights ``z`` increasing upward; vectors are
(3, nz, ny, nx) with components (x, y, z), z up.  Everything is stored as
float32 (a 1024² × 100 field takes 400 MiB); fields given as a scalar or a
(nz,) profile are stored as broadcast views and cost nothing.  Readers:
`Atmosphere.from_muram`, `Atmosphere.from_1d`, `Atmosphere.from_art`,
`Atmosphere.from_file` (gongsynth's HDF5 format, written by `Atmosphere.to_file`).
"""
from __future__ import annotations

from pathlib import Path

import astropy.units as u
import numpy as np

from gongsynth.sun import atmosphere_files as files
from gongsynth.validation import check_quantity

__all__ = ["Atmosphere"]

_UNITS = {"temperature": u.K, "gas_pressure": u.Unit("dyn cm-2"), "density": u.Unit("g cm-3"),
          "electron_density": u.Unit("cm-3"), "velocity": u.km / u.s, "magnetic_field": u.G,
          "microturbulence": u.km / u.s}
_POSITIVE = ("temperature", "gas_pressure", "density", "electron_density")
#: Largest magnitude of each component accepted (physical ranges; beyond them the input is an error):
#: velocity 300 km/s, twice the fastest chromospheric flows (type II spicules, 50-150 km/s,
#: De Pontieu et al. 2007, PASJ 59, S655) and the range over which the fast solver is tested against
#: the reference one (tests/test_faults.py); magnetic field 20 kG, over twice the strongest field
#: measured on the Sun (8.2 kG, Okamoto & Sakurai 2018, ApJL 852, L16); microturbulence 50 km/s,
#: twice the largest of the FAL models (FAL-B, 25 km/s, Fontenla et al. 1993, ApJ 406, 319).
_LIMITS = {"velocity": 300.0, "magnetic_field": 2.0e4, "microturbulence": 50.0}


def _as_array(value, name, unit):
    if isinstance(value, u.Quantity):
        check_quantity(value, unit, name)
        return value.to_value(unit)
    return np.asarray(value)


class Atmosphere:
    """
    A 3-D model atmosphere (horizontally periodic) for LTE Stokes synthesis.

    Parameters
    ----------
    temperature : `~astropy.units.Quantity`, (nz, ny, nx)
        Temperature (K).
    z : `~astropy.units.Quantity`, (nz,)
        Heights, strictly increasing (upward).
    pixel_size : `~astropy.units.Quantity`
        Horizontal grid spacing (length, same in x and y).
    gas_pressure, density : `~astropy.units.Quantity`, (nz, ny, nx), optional
        dyn cm⁻² and g cm⁻³; at least one is required.
    electron_density : `~astropy.units.Quantity`, (nz, ny, nx), optional
        cm⁻³; when absent the synthesis computes it from the equation of state.
    velocity : `~astropy.units.Quantity`, (3, nz, ny, nx), optional
        (v_x, v_y, v_z) in km/s, v_z > 0 upward (default 0).
    magnetic_field : `~astropy.units.Quantity`, (3, nz, ny, nx), optional
        (B_x, B_y, B_z) in G (default 0).
    microturbulence : `~astropy.units.Quantity`, optional
        km/s, scalar, (nz,) or (nz, ny, nx) (default 0).
    meta : dict, optional
        Provenance.

    Examples
    --------
    >>> import numpy as np, astropy.units as u
    >>> t = np.full((3, 2, 2), 5000.0) * u.K
    >>> p = np.ones((3, 2, 2)) * 1e4 * u.Unit("dyn cm-2")
    >>> atm = Atmosphere(t, [0, 50, 100] * u.km, 96 * u.km, gas_pressure=p)
    >>> atm.shape, atm[:1, :].shape
    ((3, 2, 2), (3, 1, 2))
    """

    def __init__(self, temperature, z, pixel_size, *, gas_pressure=None, density=None,
                 electron_density=None, velocity=None, magnetic_field=None,
                 microturbulence=0 * u.km / u.s, meta=None):
        check_quantity(z, u.km, "z")
        check_quantity(pixel_size, u.km, "pixel_size")
        zz = np.asarray(z.to_value(u.km), dtype=np.float64)
        if zz.ndim != 1 or zz.size < 2 or not np.isfinite(zz).all() or np.any(np.diff(zz) <= 0):
            raise ValueError("z must be a 1-D strictly increasing (upward) array of >= 2 finite heights")
        px = float(np.asarray(pixel_size.to_value(u.km)))
        if not np.isfinite(px) or px <= 0:
            raise ValueError(f"pixel_size must be positive, got {pixel_size}")
        if gas_pressure is None and density is None:
            raise ValueError("an Atmosphere needs gas_pressure or density (or both)")
        temp = _as_array(temperature, "temperature", u.K)
        if temp.ndim != 3 or temp.shape[0] != zz.size:
            raise ValueError(f"temperature must have shape (nz, ny, nx) with nz = len(z) = {zz.size}, "
                             f"got {temp.shape}")
        shape = temp.shape
        self._z = zz
        self._pixel_size = px
        self._fields = {}
        given = dict(temperature=temperature, gas_pressure=gas_pressure, density=density,
                     electron_density=electron_density, velocity=velocity, magnetic_field=magnetic_field,
                     microturbulence=microturbulence)
        for name, value in given.items():
            if value is None:
                if name in ("velocity", "magnetic_field"):
                    value = np.zeros((3, 1, 1, 1), dtype=np.float32)
                else:
                    self._fields[name] = None
                    continue
            self._fields[name] = self._checked(name, value, shape)
        self.meta = dict(meta or {})

    @staticmethod
    def _checked(name, value, shape):
        arr = _as_array(value, name, _UNITS[name])
        if arr.dtype != np.float32:
            arr = arr.astype(np.float32)
        target = (3,) + shape if name in ("velocity", "magnetic_field") else shape
        if name == "microturbulence" and arr.ndim == 1:
            arr = arr[:, None, None]
        if name in ("velocity", "magnetic_field") and arr.ndim == 2:
            arr = arr[:, :, None, None]
        try:
            view = np.broadcast_to(arr, target)
        except ValueError:
            raise ValueError(f"{name} must broadcast to {target}, got shape {arr.shape}") from None
        if not np.isfinite(arr).all():
            raise ValueError(f"{name} contains non-finite value(s)")
        if name in _POSITIVE and not (arr > 0).all():
            raise ValueError(f"{name} must be positive everywhere")
        if name == "microturbulence" and (arr < 0).any():
            raise ValueError("microturbulence must be >= 0")
        limit = _LIMITS.get(name)
        if limit is not None and arr.size and max(float(arr.max()), -float(arr.min())) > limit:
            worst = max(float(arr.max()), -float(arr.min()))
            raise ValueError(f"{name} reaches {worst:.3g} {_UNITS[name]}; a solar atmosphere stays within "
                             f"{limit:g} {_UNITS[name]} (each component)")
        return view if view.shape != arr.shape else arr

    # --- readers ---------------------------------------------------------------------------------
    @classmethod
    def _from_arrays(cls, args):
        args = dict(args)
        meta = args.pop("meta", None)
        z = args.pop("z") * u.km
        px = args.pop("pixel_size") * u.km
        temp = args.pop("temperature") * u.K
        kw = {k: (None if v is None else v * _UNITS[k]) for k, v in args.items()}
        return cls(temp, z, px, meta=meta, **kw)

    @classmethod
    def from_muram(cls, directory, iteration=0):
        """
        Read a MURaM snapshot folder (see `gongsynth.sun.atmosphere_files`).

        Parameters
        ----------
        directory : str or path-like
        iteration : int

        Returns
        -------
        `Atmosphere`
        """
        return cls._from_arrays(files.read_muram(directory, iteration))

    @classmethod
    def from_1d(cls, path):
        """
        Read a 1-D SIR ``.mod``, Hazel ``.1d`` or RH ``.atmos`` model as a 1 × 1 column.

        The column is horizontally uniform; its spacing is
        `~gongsynth.sun.atmosphere_files.UNIFORM_PIXEL_KM`, so that it tiles any field.

        Parameters
        ----------
        path : str or path-like

        Returns
        -------
        `Atmosphere`
        """
        return cls._from_arrays(files.read_1d(path))

    @classmethod
    def from_art(cls, path):
        """
        Read the ART / Bifrost HDF5 model (no velocity or field: zero, with a warning).

        Parameters
        ----------
        path : str or path-like

        Returns
        -------
        `Atmosphere`
        """
        return cls._from_arrays(files.read_art(path))

    @classmethod
    def from_file(cls, path):
        """
        Read gongsynth's HDF5 atmosphere format.

        Parameters
        ----------
        path : str or path-like

        Returns
        -------
        `Atmosphere`
        """
        return cls._from_arrays(files.read_hdf5(path))

    @classmethod
    def read(cls, path):
        """
        Read an atmosphere with the reader its form calls for.

        A folder is a MURaM snapshot (`from_muram`); ``.h5``/``.hdf5`` is
        gongsynth's format (`from_file`) or else the ART/Bifrost layout
        (`from_art`); anything else a 1-D model (`from_1d`: SIR ``.mod``,
        Hazel ``.1d``, RH ``.atmos``).

        Parameters
        ----------
        path : str or path-like

        Returns
        -------
        `Atmosphere`
        """
        path = Path(path)
        if path.is_dir():
            return cls.from_muram(path)
        if not path.is_file():
            raise FileNotFoundError(2, "no such atmosphere file or folder", str(path))
        if path.suffix.lower() in (".h5", ".hdf5"):
            try:
                arrays = files.read_hdf5(path)
            except (KeyError, ValueError):  # not gongsynth's layout: the ART/Bifrost one
                return cls.from_art(path)
            return cls._from_arrays(arrays)  # its values checked: an error here is the file's
        return cls.from_1d(path)

    def to_file(self, path, *, overwrite=False):
        """
        Write gongsynth's HDF5 atmosphere format (atomically).

        Parameters
        ----------
        path : str or path-like
        overwrite : bool, optional
        """
        fields = {k: (None if v is None else np.ascontiguousarray(v)) for k, v in self._fields.items()}
        files.write_hdf5(path, fields, self._z, self._pixel_size, overwrite=overwrite)

    # --- access ----------------------------------------------------------------------------------
    def _quantity(self, name):
        value = self._fields[name]
        return None if value is None else u.Quantity(value, _UNITS[name], copy=False)

    temperature = property(lambda self: self._quantity("temperature"), doc="Temperature (K), (nz, ny, nx).")
    gas_pressure = property(lambda self: self._quantity("gas_pressure"), doc="Gas pressure or None.")
    density = property(lambda self: self._quantity("density"), doc="Mass density or None.")
    electron_density = property(lambda self: self._quantity("electron_density"), doc="n_e or None.")
    velocity = property(lambda self: self._quantity("velocity"), doc="(v_x, v_y, v_z), km/s.")
    magnetic_field = property(lambda self: self._quantity("magnetic_field"), doc="(B_x, B_y, B_z), G.")
    microturbulence = property(lambda self: self._quantity("microturbulence"), doc="km/s, (nz, ny, nx).")

    @property
    def z(self):
        """Heights (km), increasing upward."""
        return self._z * u.km

    @property
    def pixel_size(self):
        """Horizontal grid spacing (km)."""
        return self._pixel_size * u.km

    @property
    def shape(self):
        """(nz, ny, nx)."""
        return self._fields["temperature"].shape

    def raw(self, name):
        """The stored float32 array of a field (no copy; None if absent), in the units of the docs."""
        return self._fields[name]

    def __repr__(self):
        nz, ny, nx = self.shape
        have = [k for k, v in self._fields.items() if v is not None]
        return (f"<Atmosphere {nz} heights x {ny} x {nx}, {self._pixel_size:g} km pixels, "
                f"z {self._z[0]:.0f}..{self._z[-1]:.0f} km, fields: {', '.join(have)}>")

    def __getitem__(self, key):
        """Horizontal slice ``atm[y, x]`` (slices or integers kept as length-1 axes)."""
        if not isinstance(key, tuple):
            key = (key,)
        if len(key) > 2:
            raise IndexError("an Atmosphere is sliced horizontally only: atm[y, x]")
        key = tuple(slice(k, k + 1) if isinstance(k, (int, np.integer)) else k for k in key)
        key = key + (slice(None),) * (2 - len(key))
        out = object.__new__(Atmosphere)
        out._z, out._pixel_size, out.meta = self._z, self._pixel_size, dict(self.meta)
        out._fields = {}
        for name, value in self._fields.items():
            if value is None:
                out._fields[name] = None
            elif name in ("velocity", "magnetic_field"):
                out._fields[name] = value[(slice(None), slice(None)) + key]
            else:
                out._fields[name] = value[(slice(None),) + key]
        return out

    def replace(self, **fields):
        """
        A new Atmosphere with some fields replaced (validated like the constructor).

        Parameters
        ----------
        **fields
            Any constructor argument (Quantities), e.g. ``temperature=atm.temperature + 100 * u.K``.

        Returns
        -------
        `Atmosphere`
        """
        args = {k: self._quantity(k) for k in self._fields}
        args.update(z=self.z, pixel_size=self.pixel_size, meta=self.meta)
        unknown = set(fields) - set(args)
        if unknown:
            raise TypeError(f"unknown Atmosphere field(s): {sorted(unknown)}")
        args.update(fields)
        return Atmosphere(args.pop("temperature"), args.pop("z"), args.pop("pixel_size"), **args)
