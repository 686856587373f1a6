r"""
What every instrument of the family provides, and what they share.

An instrument is *data*: a frozen dataclass of its parameters (Quantities with
their sources) plus a few methods that say what is its own — its line, its
filtergrams, how its camera takes frames, and its reduction algorithm.  The
shared stages (`gongsynth.stages`) never test which instrument they serve;
they ask it, through the `Instrument` protocol below.

The K planes
------------
An instrument records K raw planes.  Plane k is the light of filtergram
``f_k`` (a tuning position or a wave-plate sector, transmission
:math:`R_{f_k}(\lambda)`, `Instrument.responses`) seen through an analyser
that passes :math:`I + s_k V` (`Instrument.analysers` holds the pairs
:math:`(f_k, s_k)`).  With the instrument's Mueller matrix M, the channels
stage (filter first, DESIGN §1) computes

.. math::

    P_k(x, y) = \int R_{f_k}(\lambda)\,\big[(M S)_0 + s_k (M S)_3\big](x, y, \lambda)\,d\lambda .

GONG: 6 planes, k = polarisation × 3 + sector, polarisation 0 = I+V.
HMI: 12 planes, k = polarisation × 6 + tuning, polarisation 0 = LCP = I+V.

The camera asks for a `FrameSchedule` (which plane each frame is added to,
the dither it carries), the reduction for the instrument's algorithm
(`Instrument.algorithm`) after the shared dark and flat correction.  The
algorithm is named by ``"module:function"`` and imported by the reduction
stage: it may live at the reduction's place in the data flow (it returns the
stage's `Observables`) while the instrument's parameters sit early.

The parameters
--------------
`InstrumentParameters` is the machinery every instrument dataclass inherits:
fields declared with `quantity_field` / `plain_field` (unit and documented
source), unit and range checks naming the field, `replace`, equality and
hashing by value, and the TOML round trip (``[instrument]`` table whose
``name`` key says which instrument it is).
"""
from __future__ import annotations

import dataclasses
import math
import numbers
import tomllib
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import ClassVar, Protocol, runtime_checkable

import astropy.units as u
import numpy as np
import tomlkit

from gongsynth.instruments.frames import FrameSchedule, whole_frames
from gongsynth.tomlfmt import toml_table

__all__ = ["Instrument", "InstrumentParameters", "FrameSchedule", "Observables", "quantity_field",
           "plain_field", "field_unit", "whole_frames"]

# Field metadata keys.
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


@runtime_checkable
class Instrument(Protocol):
    """
    What a shared stage may ask of an instrument (GONG, HMI, MDI).

    Identity and line
        ``name`` (str, the registry key: ``"gong"``), ``label`` (for
        metadata: ``"GONG"``), ``line`` (the key of the line in the
        radiative-transfer line registry: ``"Ni I 676.8"``),
        ``line_wavelength`` (length).
    Optics
        ``aperture`` (length), ``seeing_fwhm`` (angle), ``psf_radius`` (angle),
        ``plate_scale`` (angle per pixel), ``detector_shape`` (int, side in
        pixels), ``supersampling`` (int).
    Photometry and camera
        ``effective_area`` (area), ``quantum_efficiency``, ``gain``
        (electron/adu), ``read_noise`` (adu), ``exposure_time`` (time of
        one frame), ``truncate_bits`` (int: low bits dropped after
        accumulation; 0 where none are), and ``detector_maps``: an object
        holding the synthetic flat and dark knobs read by
        `gongsynth.stages.camera.detector` (``detector_map_seed``, ``flat_*``,
        ``dark_*``; GONG: itself).
    Filtergrams
        ``responses(wavelength)`` → dimensionless (n_filtergrams, nλ)
        transmissions; ``integration_half_width`` and ``quadrature_step``
        (length): the window λ0 ± half width and step of the fine quadrature
        on which they are integrated against a spectrum
        (`gongsynth.instruments.quadrature`); ``analysers``: one
        ``(filtergram index, sign of Stokes V)`` pair per raw plane;
        ``plane_names``: a short name per plane.
    Schedule
        ``schedule(duration)`` → `FrameSchedule`: the plane of every frame,
        the dither it carries (zero where there is none); it raises
        ValueError naming ``duration`` when the duration is not a whole
        number of the instrument's frames (or, for an instrument that
        cycles through its planes, of its sequences).
        ``default_duration`` (time): the length of a run that names none
        (the instrument's standard product).
    Reduction
        ``algorithm``: ``"package.module:function"`` of
        ``function(planes, instrument, **options)`` → `Observables` from the
        dark- and flat-corrected planes (K, ...) (GONG:
        ``"gongsynth.instruments.gong.reduction:three_phase"``; HMI:
        ``reduce_hmi``); ``gauss_per_velocity`` (G per m/s);
        ``header_cards()`` → dict of FITS cards (≤ 8 characters: ``(value,
        comment)``) that record the instrument's own inversion constants in
        every product.
    Parameter machinery
        ``replace(**changes)``, ``to_dict()``, ``toml_table()`` and the class
        method ``from_dict(mapping)`` (`InstrumentParameters` provides them).
    """

    name: str
    label: str
    line: str
    line_wavelength: u.Quantity
    aperture: u.Quantity
    seeing_fwhm: u.Quantity
    plate_scale: u.Quantity
    detector_shape: int
    supersampling: int
    effective_area: u.Quantity
    quantum_efficiency: u.Quantity
    gain: u.Quantity
    read_noise: u.Quantity
    exposure_time: u.Quantity
    truncate_bits: int
    detector_maps: object
    analysers: tuple
    plane_names: tuple
    algorithm: str
    gauss_per_velocity: u.Quantity
    default_duration: u.Quantity

    def responses(self, wavelength):
        """(n_filtergrams, nλ) dimensionless transmissions at ``wavelength``."""

    def schedule(self, duration):
        """The `FrameSchedule` of an observation of ``duration``."""

    def header_cards(self):
        """FITS cards of the instrument's inversion constants."""


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


@dataclass(frozen=True)
class Observables:
    """
    What an instrument's reduction measures in each pixel.

    Attributes
    ----------
    magnetogram : `~astropy.units.Quantity`
        Line-of-sight flux density B_LOS, in G.
    doppler : `~astropy.units.Quantity`
        Line-of-sight velocity (positive = redshift, away from the observer), in m/s.
    continuum : `~astropy.units.Quantity`
        (Pseudo-)continuum of the dark- and flat-corrected planes, in DN (adu).
    velocity : `~astropy.units.Quantity`
        Shape (2, ...): velocities of the two polarisation states (I+V, I-V), in m/s.
    phase : `~astropy.units.Quantity`
        Shape (2, ...): measured phases of the two states, in rad.
    wrapped : `numpy.ndarray` of bool
        True where a measurement may have wrapped or saturated (design §3.5).
    """

    magnetogram: u.Quantity
    doppler: u.Quantity
    continuum: u.Quantity
    velocity: u.Quantity
    phase: u.Quantity
    wrapped: np.ndarray
