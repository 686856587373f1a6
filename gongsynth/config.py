"""
Run configuration: everything needed to repeat a simulation bit for bit.

A `SimulationConfig` maps one-to-one onto the keyword arguments of
`gongsynth.simulate` (the ``[simulation]`` table of a TOML file) plus a
`~gongsynth.GONGInstrument` (the ``[instrument]`` table).  Unknown keys and
quantities in the wrong units are errors that name the key.
"""
import dataclasses
import tomllib
from dataclasses import dataclass, field, fields
from pathlib import Path

import astropy.units as u
from astropy.time import Time

from gongsynth.instrument import GONGInstrument
from gongsynth.geometry import DEFAULT_OBSTIME as _DEFAULT_TIME
from gongsynth.seeding import root_seed
from gongsynth.tomlfmt import toml_value

__all__ = ["SimulationConfig", "ENGINES", "MODES", "DEFAULT_OBSTIME"]

#: Camera engines accepted by `SimulationConfig.engine`.
ENGINES = ("blocks", "frames")
#: Scene modes accepted by `SimulationConfig.mode`.
MODES = ("tiled", "full-disk")
#: Default observation time (B0 ≈ 0), as an ISO string.
DEFAULT_OBSTIME = _DEFAULT_TIME.isot

_QUANTITIES = {
    "latitude": (u.deg, "heliographic latitude of the field centre on the central meridian"),
    "duration": (u.min, "length of the observation (GONG magnetograms: 1 min; the paper: 10 min)"),
    "photosphere_pixel_size": (u.km, "pixel size of the built-in model photosphere"),
}
_DOCS = {
    "engine": "camera engine: 'blocks' (fast, statistically exact) or 'frames' (frame by frame)",
    "mode": "'tiled' (the paper's tiling at several resolutions) or 'full-disk'",
    "seed": "root random seed (int); recorded so a run can be repeated bit for bit",
    "detector_shape": "detector side in pixels (GONG: 860; smaller for quick runs)",
    "resolutions": "tiled mode: magnification of the tile in each quadrant (1 = GONG resolution)",
    "obstime": "observation time (ISO); sets the observer position and the map dates",
    "photosphere_shape": "pixels of the built-in model photosphere (ny, nx)",
    "workers": "threads for the frames engine (None: all cores)",
}


@dataclass(frozen=True)
class SimulationConfig:
    """
    The arguments of one `gongsynth.simulate` run.

    Parameters
    ----------
    latitude : `~astropy.units.Quantity`
        Heliographic latitude of the field centre, in (-90°, 90°).
    duration : `~astropy.units.Quantity`
        Observation length (time).
    engine : str
        ``"blocks"`` or ``"frames"``.
    mode : str
        ``"tiled"`` or ``"full-disk"``.
    seed : int
        Root seed.  `from_arguments` turns ``None`` into fresh recorded entropy.
    detector_shape : int or None
        Detector side in pixels; ``None`` uses the instrument's (860).
    resolutions : tuple of int
        Tile magnifications of the quadrants in tiled mode.
    obstime : str
        ISO time of the observation.
    photosphere_shape : tuple of int
        Shape of the built-in model photosphere.
    photosphere_pixel_size : `~astropy.units.Quantity`
        Pixel size of the built-in model photosphere (length).
    workers : int or None
        Threads for the frames engine.
    instrument : `~gongsynth.GONGInstrument`
        The instrument.

    Examples
    --------
    >>> cfg = SimulationConfig(seed=3)
    >>> SimulationConfig.from_toml(cfg.to_toml()) == cfg
    True
    """

    latitude: u.Quantity = 0 * u.deg
    duration: u.Quantity = 10 * u.min
    engine: str = "blocks"
    mode: str = "tiled"
    seed: int = 0
    detector_shape: int | None = None
    resolutions: tuple = (1, 2, 4, 8)
    obstime: str = DEFAULT_OBSTIME
    photosphere_shape: tuple = (1024, 1024)
    photosphere_pixel_size: u.Quantity = 96 * u.km
    workers: int | None = None
    instrument: GONGInstrument = field(default_factory=GONGInstrument)

    def __post_init__(self):
        for name, (unit, _) in _QUANTITIES.items():
            value = getattr(self, name)
            if not isinstance(value, u.Quantity) or not value.unit.is_equivalent(unit):
                raise u.UnitsError(f"{name} must be a Quantity convertible to {unit}, got {value!r}")
        if not -90 * u.deg < self.latitude < 90 * u.deg:
            raise ValueError(f"latitude must lie in (-90 deg, 90 deg), got {self.latitude}")
        if self.duration <= 0 * u.s:
            raise ValueError(f"duration must be positive, got {self.duration}")
        if self.engine not in ENGINES:
            raise ValueError(f"engine must be one of {ENGINES}, got {self.engine!r}")
        if self.mode not in MODES:
            raise ValueError(f"mode must be one of {MODES}, got {self.mode!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise TypeError(f"seed must be a non-negative int, got {self.seed!r}")
        if self.detector_shape is not None and (not isinstance(self.detector_shape, int)
                                                or self.detector_shape < 8):
            raise ValueError(f"detector_shape must be an int >= 8 or None, got {self.detector_shape!r}")
        resolutions = tuple(self.resolutions)
        if not resolutions or len(resolutions) > 4 or any(
                not isinstance(r, int) or r < 1 for r in resolutions):
            raise ValueError(f"resolutions must be 1 to 4 positive ints, got {self.resolutions!r}")
        object.__setattr__(self, "resolutions", resolutions)
        shape = tuple(self.photosphere_shape)
        if len(shape) != 2 or any(not isinstance(n, int) or n < 4 for n in shape):
            raise ValueError(f"photosphere_shape must be two ints >= 4, got {self.photosphere_shape!r}")
        object.__setattr__(self, "photosphere_shape", shape)
        try:
            Time(self.obstime)
        except ValueError as exc:
            raise ValueError(f"obstime must be an ISO time string, got {self.obstime!r}") from exc
        if self.workers is not None and (not isinstance(self.workers, int) or self.workers < 1):
            raise ValueError(f"workers must be a positive int or None, got {self.workers!r}")
        if not isinstance(self.instrument, GONGInstrument):
            raise TypeError(f"instrument must be a GONGInstrument, got {type(self.instrument).__name__}")

    @classmethod
    def from_arguments(cls, *, seed=None, instrument=None, **kwargs):
        """
        Build a config from `gongsynth.simulate`-style arguments.

        ``seed=None`` draws fresh entropy, reduced to a 63-bit int so that it
        fits a FITS header and the run can be repeated from the saved config.

        Parameters
        ----------
        seed : None, int, `numpy.random.SeedSequence` or `numpy.random.Generator`
        instrument : `~gongsynth.GONGInstrument`, optional
        **kwargs
            The other fields.

        Returns
        -------
        `SimulationConfig`
        """
        seed = root_seed(seed)
        instrument = GONGInstrument() if instrument is None else instrument
        if isinstance(kwargs.get("obstime"), Time):
            kwargs["obstime"] = kwargs["obstime"].isot
        return cls(seed=seed, instrument=instrument, **kwargs)

    @property
    def detector_pixels(self):
        """Detector side in pixels (the instrument's if ``detector_shape`` is None)."""
        return self.instrument.detector_shape if self.detector_shape is None else self.detector_shape

    def replace(self, **changes):
        """
        Return a copy with some fields changed (validated again).

        Parameters
        ----------
        **changes
            Field names and new values.

        Returns
        -------
        `SimulationConfig`
        """
        return dataclasses.replace(self, **changes)

    def simulation_arguments(self):
        """
        The fields except ``instrument``, as keyword arguments for `gongsynth.simulate`.

        Returns
        -------
        dict
        """
        return {f.name: getattr(self, f.name) for f in fields(self) if f.name != "instrument"}

    def to_toml(self, *, comments=True):
        """
        The configuration as TOML: a ``[simulation]`` and an ``[instrument]`` table.

        Parameters
        ----------
        comments : bool
            Precede each key with a comment explaining it.

        Returns
        -------
        str
        """
        lines = ["# gongsynth run configuration", "[simulation]"]
        for name, value in self.simulation_arguments().items():
            doc = _QUANTITIES[name][1] if name in _QUANTITIES else _DOCS.get(name, "")
            if value is None:
                # Unset: show the effective default, commented out.
                example = self.instrument.detector_shape if name == "detector_shape" else 2
                lines.append(f"# {doc}; unset by default")
                lines.append(f"# {name} = {example}")
                continue
            if comments:
                lines.append(f"# {doc}")
            lines.append(f"{name} = {toml_value(value)}")
        lines.append("")
        instrument = self.instrument.to_toml()
        if not comments:
            instrument = "\n".join(l for l in instrument.splitlines() if not l.startswith("#"))
        lines.append(instrument)
        return "\n".join(l for l in lines if l is not None) + "\n"

    @classmethod
    def from_toml(cls, source):
        """
        Read a configuration from TOML text or a ``.toml`` path.

        Parameters
        ----------
        source : str or `pathlib.Path`

        Returns
        -------
        `SimulationConfig`

        Raises
        ------
        KeyError
            For unknown tables or keys (the message names them).
        """
        if isinstance(source, Path) or (isinstance(source, str) and "\n" not in source
                                        and source.endswith(".toml")):
            text = Path(source).read_text()
        else:
            text = source
        table = tomllib.loads(text)
        return cls.from_dict(table)

    @classmethod
    def from_dict(cls, table):
        """
        Build a configuration from a parsed TOML document.

        Parameters
        ----------
        table : dict
            ``{"simulation": {...}, "instrument": {...}}``; both optional.

        Returns
        -------
        `SimulationConfig`
        """
        unknown = [k for k in table if k not in ("simulation", "instrument")]
        if unknown:
            raise KeyError(f"unknown table(s) {unknown}; expected [simulation] and [instrument]")
        sim = dict(table.get("simulation", {}))
        known = {f.name for f in fields(cls)} - {"instrument"}
        bad = [k for k in sim if k not in known]
        if bad:
            raise KeyError(f"unknown key(s) {bad} in [simulation]; valid keys are {sorted(known)}")
        for name, (unit, _) in _QUANTITIES.items():
            if name in sim:
                sim[name] = _quantity(name, sim[name], unit)
        for name in ("resolutions", "photosphere_shape"):
            if name in sim:
                sim[name] = tuple(sim[name])
        instrument = GONGInstrument.from_dict(table.get("instrument", {}))
        return cls(instrument=instrument, **sim)


def _quantity(name, value, unit):
    if isinstance(value, u.Quantity):
        return value
    if isinstance(value, str):
        try:
            return u.Quantity(value)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"[simulation] {name} = {value!r} is not a quantity like '1 {unit}'") from exc
    raise u.UnitsError(f"[simulation] {name} needs units, e.g. {name} = \"{value} {unit}\"")
