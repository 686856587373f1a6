r"""
The parameter machinery of the instrument dataclasses.

`InstrumentParameters` is the machinery every instrument dataclass inherits:
fields declared with `quantity_field` / `plain_field` (unit and documented
source), unit and range checks naming the field, `replace`, equality and
hashing by value, and the TOML round trip (``[instrument]`` table whose
``name`` key says which instrument it is).

`gauss_per_zeeman_velocity` is the Zeeman conversion from a velocity shift of
the σ components to B_LOS that each instrument's reduction constant derives from.
"""
from __future__ import annotations

import dataclasses
import math
import numbers
import tomllib
from dataclasses import field, fields
from pathlib import Path
from typing import ClassVar

import astropy.constants as const
import astropy.units as u
import tomlkit

from gongsynth.tomlfmt import toml_table

__all__ = ["InstrumentParameters", "quantity_field", "plain_field", "field_unit", "gauss_per_zeeman_velocity"]

_UNIT = "unit"
_DOC = "doc"


def quantity_field(default, unit, doc):
    """
    A Quantity-valued dataclass field with its canonical unit and documented source.

    Parameters
    ----------
    default : float
        Default value in ``unit``.
    unit : str or `~astropy.units.UnitBase`
    doc : str
        One line: what it is and where the number comes from (the TOML comment).

    Returns
    -------
    `dataclasses.Field`
    """
    return field(default=u.Quantity(default, unit), metadata={_UNIT: u.Unit(unit), _DOC: doc})


def plain_field(default, kind, doc):
    """
    A plain (``int`` or ``str``) dataclass field with its documented source.

    Parameters
    ----------
    default : int or str
    kind : type
        ``int`` or ``str``.
    doc : str

    Returns
    -------
    `dataclasses.Field`
    """
    return field(default=default, metadata={_UNIT: kind, _DOC: doc})


def field_unit(cls, name):
    """
    The canonical unit (or ``int`` / ``str``) of a parameter of an instrument class.

    Parameters
    ----------
    cls : type
        An `InstrumentParameters` subclass.
    name : str

    Returns
    -------
    `~astropy.units.UnitBase` or type
    """
    return {f.name: f.metadata[_UNIT] for f in fields(cls)}[name]




class InstrumentParameters:
    """
    Mixin of the instrument dataclasses: checks, `replace`, equality and TOML.

    A subclass is a frozen dataclass whose fields are made with
    `quantity_field` or `plain_field`; it sets the class attributes ``name``
    (the registry key), and ``RANGES`` (field name → interval such as
    ``"(0, inf)"`` in the field's canonical unit; ``pi`` is understood).
    """

    name: ClassVar[str] = ""
    RANGES: ClassVar[dict] = {}
    #: Detector side of a tiled run that names none; None: the whole detector
    #: (``detector_shape``).  The tiled scene repeats one small box, so a field of many
    #: boxes shows nothing new at a higher cost (HMI's 4096² CCD: 1024).
    tiled_detector_shape: ClassVar[int | None] = None

    def __post_init__(self):
        cls = type(self).__name__
        for f in fields(self):
            kind = f.metadata[_UNIT]
            value = getattr(self, f.name)
            if kind is int:
                if isinstance(value, numbers.Integral) and not isinstance(value, bool):
                    value = int(value)  # numpy integers too
                    object.__setattr__(self, f.name, value)
                if isinstance(value, bool) or not isinstance(value, int) or value < 0:
                    raise TypeError(f"{cls}.{f.name} must be a non-negative int, got {value!r}")
            elif kind is str:
                if not isinstance(value, str):
                    raise TypeError(f"{cls}.{f.name} must be a str, got {value!r}")
            else:
                object.__setattr__(self, f.name, _as_quantity(cls, f.name, value, kind))
        for name, interval in self.RANGES.items():
            _check_range(self, name, getattr(self, name), interval)

    @property
    def n_planes(self):
        """Number of raw planes K (int)."""
        return len(self.analysers)

    @classmethod
    def source(cls, name):
        """
        The documented source of a parameter (its TOML comment).

        Parameters
        ----------
        name : str

        Returns
        -------
        str

        Raises
        ------
        KeyError
            If the instrument has no parameter ``name``.
        """
        for f in fields(cls):
            if f.name == name:
                return f.metadata[_DOC]
        raise KeyError(f"{cls.__name__} has no parameter {name!r}")

    @classmethod
    def resolve(cls, instrument):
        """
        The instrument a function should use: the class's default for None, else the one given.

        Parameters
        ----------
        instrument : instance of this class or None

        Returns
        -------
        instance of this class

        Raises
        ------
        TypeError
            If ``instrument`` is neither None nor an instance of this class.
        """
        if instrument is None:
            return cls()
        if not isinstance(instrument, cls):
            raise TypeError(f"instrument must be an {cls.__name__} or None, got {type(instrument).__name__}")
        return instrument

    def replace(self, **changes):
        """
        Return a copy with some parameters changed.

        Parameters
        ----------
        **changes
            Field names and their new values (Quantities with compatible units).

        Returns
        -------
        The same class.
        """
        unknown = set(changes) - {f.name for f in fields(self)}
        if unknown:
            raise TypeError(f"{type(self).__name__} has no parameter(s) {sorted(unknown)}")
        return dataclasses.replace(self, **changes)

    def __eq__(self, other):
        if type(other) is not type(self):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self):
        return hash((type(self).__name__, self._key()))

    def _key(self):
        """A hashable tuple of (name, value, unit string) for every field."""
        key = []
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, u.Quantity):
                key.append((f.name, float(value.value), value.unit.to_string()))
            else:
                key.append((f.name, value))
        return tuple(key)

    def to_dict(self):
        """
        Every parameter as a TOML-ready value.

        Quantities become strings such as ``"676.78 nm"`` whose number is the
        shortest repr that round-trips exactly; ints and strings stay as they are.

        Returns
        -------
        dict
        """
        out = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, u.Quantity) and value.unit == u.dimensionless_unscaled:
                out[f.name] = float(value.value)
            elif isinstance(value, u.Quantity):
                out[f.name] = f"{float(value.value)!r} {value.unit.to_string()}"
            else:
                out[f.name] = value
        return out

    @classmethod
    def from_dict(cls, mapping, *, where="instrument"):
        """
        Build an instrument from a mapping such as a parsed TOML table.

        Parameters
        ----------
        mapping : dict
            Parameter names to values: Quantities, strings like ``"3.6 arcsec"``,
            plain numbers for dimensionless parameters, ints and strings.  A
            ``name`` key, if present, must be this instrument's.
        where : str
            Name of the table, used in error messages.

        Returns
        -------
        The class's instance.

        Raises
        ------
        KeyError
            If a key is not a parameter of the instrument.
        ValueError
            If ``name`` names another instrument.
        """
        mapping = dict(mapping)
        if "name" in mapping:
            name = mapping.pop("name")
            if name != cls.name:
                raise ValueError(f"[{where}] name = {name!r}, but {cls.__name__} is {cls.name!r}")
        known = {f.name: f for f in fields(cls)}
        unknown = [k for k in mapping if k not in known]
        if unknown:
            raise KeyError(f"unknown key(s) {unknown} in [{where}]; valid keys are {sorted(known)}")
        kwargs = {}
        for key, value in mapping.items():
            kind = known[key].metadata[_UNIT]
            if isinstance(kind, u.UnitBase) and isinstance(value, str):
                try:
                    value = u.Quantity(value)
                except (TypeError, ValueError) as exc:
                    raise ValueError(
                        f"[{where}] {key} = {value!r} is not a quantity such as '1.0 {kind}'"
                    ) from exc
            kwargs[key] = value
        return cls(**kwargs)

    def toml_table(self, *, comments=True):
        """
        The instrument as a tomlkit ``[instrument]`` table: its ``name``, then each parameter.

        Parameters
        ----------
        comments : bool
            Write the documentation comments.

        Returns
        -------
        `tomlkit.items.Table`
        """
        values = self.to_dict()
        rows = [("name", self.name, "the instrument (gongsynth.instruments.get)")]
        rows += [(f.name, values[f.name], f.metadata[_DOC]) for f in fields(self)]
        return toml_table(rows, comments=comments)

    def to_toml(self):
        """
        The instrument as a TOML ``[instrument]`` table, one commented line each.

        Returns
        -------
        str
        """
        doc = tomlkit.document()
        doc.add("instrument", self.toml_table())
        return tomlkit.dumps(doc)

    @classmethod
    def from_toml(cls, source):
        """
        Read an instrument from TOML text or a path to a TOML file.

        The parameters may sit at top level or in an ``[instrument]`` table.

        Parameters
        ----------
        source : str or `pathlib.Path`
            TOML text, or a path to a ``.toml`` file.

        Returns
        -------
        The class's instance.
        """
        if isinstance(source, Path) or (isinstance(source, str) and source.endswith(".toml")
                                        and "\n" not in source):
            text = Path(source).read_text()
        else:
            text = source
        table = tomllib.loads(text)
        if "instrument" in table:
            extra = [k for k in table if k != "instrument"]
            if extra:
                raise KeyError(f"unknown top-level key(s) {extra} next to [instrument]")
            table = table["instrument"]
        return cls.from_dict(table)


def _check_range(instrument, name, value, interval):
    """Raise ValueError naming the field unless ``value`` (in its canonical unit) lies in ``interval``."""
    unit = field_unit(type(instrument), name)
    number = value if isinstance(value, int) else float(value.to_value(unit))
    low, high = (float(x.replace("pi", str(math.pi))) for x in interval[1:-1].split(","))
    if (number < low or number > high or (interval[0] == "(" and number == low)
            or (interval[-1] == ")" and number == high)):
        shown = value if isinstance(value, int) else value.to(unit)
        unit_text = "" if isinstance(value, int) or unit == u.one else f" {unit}"
        raise ValueError(f"{type(instrument).__name__}.{name} must lie in {interval}{unit_text}, got {shown}")


def _as_quantity(cls, name, value, unit):
    """Check that ``value`` is a Quantity convertible to ``unit`` (or a number if dimensionless)."""
    if not isinstance(value, u.Quantity):
        if unit == u.dimensionless_unscaled and isinstance(value, (int, float)) \
                and not isinstance(value, bool):
            return u.Quantity(float(value))
        raise TypeError(
            f"{cls}.{name} must be an astropy Quantity in units of {unit} "
            f"(e.g. {name}=1.0 * u.Unit('{unit}')), got {value!r}"
        )
    if not value.unit.is_equivalent(unit):
        raise u.UnitsError(f"{cls}.{name} must have units convertible to '{unit}', got '{value.unit}'")
    if value.ndim != 0 or not math.isfinite(float(value.value)):
        raise ValueError(f"{cls}.{name} must be a finite scalar, got {value!r}")
    return value


def gauss_per_zeeman_velocity(line_wavelength, lande_g):
    """
    B_LOS per unit Doppler velocity of the Zeeman shift of a line's σ components.

    A field B shifts each σ component by Δλ_B = e λ0² g B / (4π m_e c²), a
    velocity Δv = c Δλ_B / λ0, so B = 4π m_e c / (e g λ0) × Δv (Gaussian units;
    GONG paper, Eq. 9).  An instrument whose two polarisations measure
    v± = v ± Δv divides their difference by 2 (GONG: B = this × (v⁺ − v⁻)/2;
    HMI: K_m = this / 2).

    Parameters
    ----------
    line_wavelength : `~astropy.units.Quantity`
        λ0 (length).
    lande_g : `~astropy.units.Quantity`
        The (effective) Landé factor g (dimensionless).

    Returns
    -------
    `~astropy.units.Quantity`
        In G / (m / s).

    Examples
    --------
    >>> import astropy.units as u
    >>> round(float(gauss_per_zeeman_velocity(676.78 * u.nm, 1.5 * u.one).value), 4)
    0.7038
    """
    m_e = const.m_e.cgs.value
    c = const.c.cgs.value
    e = const.e.gauss.value
    lam = line_wavelength.to_value(u.cm)
    g = u.Quantity(lande_g).to_value(u.one)
    per_cm_s = 4 * math.pi * m_e * c / (e * g * lam)
    return (per_cm_s * 100) * u.G / (u.m / u.s)
