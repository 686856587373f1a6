"""
`Photosphere`: the magnetic field, velocity and brightness of photospheric columns.

One value per column at the height where Ni I 676.8 nm forms: the input of the
Milne–Eddington synthesis and the source of the ground truth (B·n).
"""
from __future__ import annotations

import numbers

import astropy.units as u
import numpy as np

from gongsynth.geometry import check_geometry, los_basis
from gongsynth.validation import check_quantity

__all__ = ["Photosphere"]

_FIELDS = (
    ("field_strength", u.G),
    ("inclination", u.deg),
    ("azimuth", u.deg),
    ("velocity_x", u.km / u.s),
    ("velocity_y", u.km / u.s),
    ("velocity_z", u.km / u.s),
    ("continuum", u.one),
)


class Photosphere:
    """
    Vector magnetic field, plasma velocity and continuum brightness per column.

    Frame: x = west, y = north, z = up (toward the observer at disk centre);
    arrays are indexed [y, x].

    Parameters
    ----------
    field_strength : `~astropy.units.Quantity`, shape (ny, nx)
        |B| in G (any magnetic flux density unit), ≥ 0.
    inclination : `~astropy.units.Quantity`, shape (ny, nx)
        Angle of B from +z, in [0°, 180°] (90° = horizontal).
    azimuth : `~astropy.units.Quantity`, shape (ny, nx)
        Angle of the horizontal field from +x toward +y.
    velocity_x, velocity_y, velocity_z : `~astropy.units.Quantity`, shape (ny, nx)
        Plasma velocity vector (velocity_z > 0 is an upflow), km/s.
    continuum : `~astropy.units.Quantity` or array_like, shape (ny, nx)
        Continuum brightness relative to the quiet-Sun disk-centre continuum
        (dimensionless, ≥ 0); it scales the source function.
    pixel_size : `~astropy.units.Quantity`
        Horizontal size of one column (length; stored in km).
    periodic : bool, optional
        True if the horizontal boundaries wrap around (a simulation box).
    meta : dict, optional
        Provenance.

    All arrays are stored as float32 Quantities (a view when already float32
    in the storage unit).

    Examples
    --------
    >>> import numpy as np, astropy.units as u
    >>> ones = np.ones((2, 3))
    >>> ph = Photosphere(1000 * ones * u.G, 0 * ones * u.deg, 0 * ones * u.deg,
    ...                  0 * ones * u.km / u.s, 0 * ones * u.km / u.s, -1 * ones * u.km / u.s,
    ...                  ones, 96 * u.km)
    >>> ph.los_field(mu=0.5)[0, 0]                # vertical field seen at 60°
    <Quantity 500. G>
    >>> ph.los_velocity()[0, 0]                   # a downflow moves away: redshift
    <Quantity 1. km / s>
    """

    def __init__(self, field_strength, inclination, azimuth, velocity_x, velocity_y, velocity_z,
                 continuum, pixel_size, *, periodic=False, meta=None):
        values = dict(zip([f for f, _ in _FIELDS],
                          (field_strength, inclination, azimuth, velocity_x, velocity_y, velocity_z,
                           continuum)))
        if not isinstance(values["continuum"], u.Quantity):
            values["continuum"] = u.Quantity(np.asarray(values["continuum"]), u.one, copy=False)
        shape = None
        for name, unit in _FIELDS:
            q = check_quantity(values[name], unit, name)
            if q.ndim != 2:
                raise ValueError(f"{name} must be a 2-D array (ny, nx), got shape {q.shape}")
            if shape is None:
                shape = q.shape
            elif q.shape != shape:
                raise ValueError(f"{name} has shape {q.shape} but field_strength has shape {shape}")
            if q.unit != unit or q.dtype != np.float32:
                q = u.Quantity(np.asarray(q.to_value(unit), dtype=np.float32), unit, copy=False)
            if not np.isfinite(q.value).all():
                raise ValueError(f"{name} contains non-finite value(s) (NaN or inf)")
            setattr(self, "_" + name, q)
        if self._field_strength.value.min() < 0:
            raise ValueError("field_strength must be non-negative (the direction is in inclination/azimuth)")
        inc = self._inclination.value
        if inc.min() < 0 or inc.max() > 180:
            raise ValueError(f"inclination must be within [0, 180] deg, got [{inc.min()}, {inc.max()}]")
        if self._continuum.value.min() < 0:
            raise ValueError("continuum must be non-negative")
        check_quantity(pixel_size, u.km, "pixel_size")
        if np.ndim(pixel_size) != 0 or not pixel_size.value > 0:
            raise ValueError(f"pixel_size must be a positive scalar length, got {pixel_size}")
        self._pixel_size = pixel_size.to(u.km)
        self.periodic = bool(periodic)
        self.meta = dict(meta or {})

    @classmethod
    def from_components(cls, bx, by, bz, velocity_x, velocity_y, velocity_z, continuum, pixel_size,
                        *, periodic=False, meta=None):
        """
        Build from Cartesian field components (e.g. an MHD snapshot at τ ≈ 0.1).

        Parameters
        ----------
        bx, by, bz : `~astropy.units.Quantity`, shape (ny, nx)
            Field components in the local frame (G).
        velocity_x, velocity_y, velocity_z, continuum, pixel_size, periodic, meta
            As for `Photosphere`.

        Returns
        -------
        `Photosphere`
        """
        for name, q in (("bx", bx), ("by", by), ("bz", bz)):
            check_quantity(q, u.G, name)
        bx, by, bz = (np.asarray(q.to_value(u.G), dtype=np.float64) for q in (bx, by, bz))
        bh = np.hypot(bx, by)
        strength = np.hypot(bh, bz)
        inclination = np.degrees(np.arctan2(bh, bz))
        azimuth = np.degrees(np.arctan2(by, bx))
        return cls(strength * u.G, inclination * u.deg, azimuth * u.deg, velocity_x, velocity_y,
                   velocity_z, continuum, pixel_size, periodic=periodic, meta=meta)

    # ---------------------------------------------------------------- access
    field_strength = property(lambda self: self._field_strength, doc="|B|, Quantity (ny, nx) G.")
    inclination = property(lambda self: self._inclination, doc="Inclination from +z, Quantity (ny, nx) deg.")
    azimuth = property(lambda self: self._azimuth, doc="Azimuth from +x toward +y, Quantity (ny, nx) deg.")
    velocity_x = property(lambda self: self._velocity_x, doc="Plasma velocity x, Quantity (ny, nx) km/s.")
    velocity_y = property(lambda self: self._velocity_y, doc="Plasma velocity y, Quantity (ny, nx) km/s.")
    velocity_z = property(lambda self: self._velocity_z,
                          doc="Plasma velocity z (up), Quantity (ny, nx) km/s.")
    continuum = property(lambda self: self._continuum,
                         doc="Continuum relative to quiet-Sun disk centre, Quantity (ny, nx).")
    pixel_size = property(lambda self: self._pixel_size, doc="Column size, Quantity km.")

    @property
    def shape(self):
        """(ny, nx)."""
        return self._field_strength.shape

    def field_vector(self):
        """
        Cartesian field components (B_x, B_y, B_z) in the local frame.

        Returns
        -------
        tuple of `numpy.ndarray`
            float64 arrays (ny, nx) in G.
        """
        b = self._field_strength.value.astype(np.float64)
        inc = np.radians(self._inclination.value, dtype=np.float64)
        az = np.radians(self._azimuth.value, dtype=np.float64)
        bh = b * np.sin(inc)
        return bh * np.cos(az), bh * np.sin(az), b * np.cos(inc)

    @property
    def bz(self):
        """Vertical field B_z (positive up), Quantity (ny, nx) G."""
        return self.field_vector()[2] * u.G

    def los_field(self, mu=1.0, los_azimuth=-90 * u.deg):
        """
        Line-of-sight field B·n (positive toward the observer).

        Parameters
        ----------
        mu : float or array_like (ny, nx)
            Cosine of the viewing angle, in (0, 1].
        los_azimuth : `~astropy.units.Quantity`, angle, scalar or (ny, nx)
            Azimuth of the observer direction (−90° for a region north of disk centre).

        Returns
        -------
        `~astropy.units.Quantity`
            (ny, nx) in G.
        """
        mu, az = check_geometry(mu, los_azimuth, self.shape)
        n, _, _ = los_basis(mu, az)
        bx, by, bz = self.field_vector()
        return (bx * n[0] + by * n[1] + bz * n[2]) * u.G

    def los_velocity(self, mu=1.0, los_azimuth=-90 * u.deg):
        """
        Line-of-sight velocity −v·n (positive away from the observer: redshift).

        Parameters
        ----------
        mu, los_azimuth
            As for `los_field`.

        Returns
        -------
        `~astropy.units.Quantity`
            (ny, nx) in km/s.
        """
        mu, az = check_geometry(mu, los_azimuth, self.shape)
        n, _, _ = los_basis(mu, az)
        vx, vy, vz = (getattr(self, f"_velocity_{c}").value.astype(np.float64) for c in "xyz")
        return -(vx * n[0] + vy * n[1] + vz * n[2]) * u.km / u.s

    def __getitem__(self, key):
        """Spatial slice ``ph[y, x]`` (slices, or index arrays for resampling); not periodic."""
        if not isinstance(key, tuple):
            key = (key,)
        if len(key) > 2:
            raise IndexError(f"Photosphere takes at most 2 indices (y, x), got {len(key)}")
        key = tuple(slice(k, k + 1 if k != -1 else None) if isinstance(k, numbers.Integral) else k
                    for k in key)
        new = Photosphere.__new__(Photosphere)
        for name, _ in _FIELDS:
            value = getattr(self, "_" + name)[key]
            if value.ndim != 2 or value.size == 0:
                raise IndexError(f"index {key} does not give a non-empty 2-D set of columns")
            setattr(new, "_" + name, value)
        new._pixel_size = self._pixel_size
        full = all(isinstance(k, slice) and k == slice(None) for k in key)
        new.periodic = self.periodic and full
        new.meta = dict(self.meta)
        return new

    def __repr__(self):
        ny, nx = self.shape
        return (f"<Photosphere {ny}×{nx} columns of {self._pixel_size:g} "
                f"({ny * self._pixel_size.to_value(u.Mm):.1f}×{nx * self._pixel_size.to_value(u.Mm):.1f} Mm"
                f"{', periodic' if self.periodic else ''})>")
