"""
The instrument family: GONG, HMI and MDI behind one protocol.

Each instrument is a frozen dataclass of its parameters in its own subpackage
(`gongsynth.instruments.gong`, ...) that implements the protocol of
`gongsynth.instruments.base`: its line, its filtergrams and analysers, its
frame schedule and its reduction algorithm.  The stages are shared; a run asks
for its instrument once, by name or as an object:

>>> from gongsynth import instruments
>>> instruments.get("gong").plate_scale
<Quantity 2.5 arcsec>
>>> instruments.get(None) == instruments.get("gong")   # GONG is the default
True
>>> instruments.names()
('gong', 'hmi', 'mdi')

New instruments are registered by module path (`register`), imported only
when first asked for.
"""
import importlib

from gongsynth.instruments.base import FrameSchedule, Instrument, InstrumentParameters, Observables
from gongsynth.instruments.gong.parameters import GONGInstrument

__all__ = ["get", "names", "register", "instrument_class", "from_dict", "DEFAULT", "Instrument",
           "InstrumentParameters", "FrameSchedule", "Observables", "GONGInstrument", "HMIInstrument",
           "MDIInstrument"]


def __getattr__(name):
    # HMI's and MDI's parameters, imported when first asked for.
    if name == "HMIInstrument":
        return instrument_class("hmi")
    if name == "MDIInstrument":
        return instrument_class("mdi")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

#: The instrument of a run that names none.
DEFAULT = "gong"

# Name -> "module:Class" (imported when first used).
_REGISTRY = {"gong": "gongsynth.instruments.gong.parameters:GONGInstrument",
             "hmi": "gongsynth.instruments.hmi.parameters:HMIInstrument",
             "mdi": "gongsynth.instruments.mdi.parameters:MDIInstrument"}


def register(name, target):
    """
    Add an instrument to the family.

    Parameters
    ----------
    name : str
        The key (lower case), e.g. ``"hmi"``.
    target : str
        ``"package.module:ClassName"`` of its dataclass.
    """
    if not isinstance(name, str) or not name or name != name.lower():
        raise ValueError(f"name must be a non-empty lower-case str, got {name!r}")
    if not isinstance(target, str) or ":" not in target:
        raise ValueError(f"target must be 'package.module:ClassName', got {target!r}")
    _REGISTRY[name] = target


def names():
    """
    The names of the registered instruments.

    Returns
    -------
    tuple of str
    """
    return tuple(_REGISTRY)


def instrument_class(name):
    """
    The dataclass of a registered instrument.

    Parameters
    ----------
    name : str

    Returns
    -------
    type

    Raises
    ------
    ValueError
        If ``name`` is not registered (the message lists the known names).
    """
    if name not in _REGISTRY:
        raise ValueError(f"instrument must be one of {names()} or an instrument object, got {name!r}")
    module, _, cls = _REGISTRY[name].partition(":")
    return getattr(importlib.import_module(module), cls)


def get(instrument=None):
    """
    An instrument of the family by name, or the instrument object itself.

    Parameters
    ----------
    instrument : str, `~gongsynth.instruments.base.Instrument` or None
        A registered name (``"gong"``; case-insensitive), an instrument
        object (returned as it is), or None (the default, GONG).

    Returns
    -------
    `~gongsynth.instruments.base.Instrument`
        The default parameters of the named instrument, or ``instrument``.

    Raises
    ------
    ValueError
        For an unknown name (the message lists the known names).
    TypeError
        For anything else.

    Examples
    --------
    >>> get("GONG").name
    'gong'
    >>> get("spectro...")
    Traceback (most recent call last):
    ...
    ValueError: instrument must be one of ('gong', 'hmi', 'mdi') or an instrument object, got 'spectro...'
    """
    if instrument is None:
        instrument = DEFAULT
    if isinstance(instrument, str):
        key = instrument.strip().lower()
        if key not in _REGISTRY:
            raise ValueError(f"instrument must be one of {names()} or an instrument object, "
                             f"got {instrument!r}")
        return instrument_class(key)()
    if isinstance(instrument, (InstrumentParameters, Instrument)):
        return instrument
    raise TypeError(f"instrument must be a name {names()}, an instrument object or None, "
                    f"got {type(instrument).__name__}")


def from_dict(table, *, where="instrument"):
    """
    An instrument from a parsed ``[instrument]`` TOML table.

    Parameters
    ----------
    table : dict
        ``name`` (default ``"gong"``) and any of that instrument's parameters.
    where : str
        The table's name, for error messages.

    Returns
    -------
    `~gongsynth.instruments.base.Instrument`
    """
    table = dict(table)
    name = table.pop("name", DEFAULT)
    if not isinstance(name, str):
        raise ValueError(f"[{where}] name must be one of {names()}, got {name!r}")
    return instrument_class(name.strip().lower()).from_dict(table, where=where)
