"""
Run configuration: everything needed to repeat a simulation bit for bit.

A `SimulationConfig` maps one-to-one onto the keyword arguments of
`gongsynth.simulate` (the ``[simulation]`` table of a TOML file), plus the
`Effects` that can be switched off (``[effects]``), the knobs of the built-in
Sun chosen by ``sun`` (``[photosphere]``) and a `~gongsynth.GONGInstrument`
(``[instrument]``).  Unknown keys and quantities in the wrong units are errors
that name the key.
"""
import dataclasses
import datetime
import math
import numbers
import tomllib
from dataclasses import dataclass, field, fields
from pathlib import Path

import astropy.units as u
import numpy as np
import tomlkit
from astropy.time import Time

from gongsynth import instruments
from gongsynth.geometry import DEFAULT_OBSTIME as _DEFAULT_TIME
from gongsynth.geometry import Pointing
from gongsynth.observing import GONG_SITES, as_observed, check_site, like_gong
from gongsynth.seeding import root_seed
from gongsynth.stages.camera.integrate import ENGINES
from gongsynth.sun.surface_field.network import CHAIN_LENGTH
from gongsynth.suns import DEFAULT_SUNS, SUNS, default_sun, photosphere_defaults, run_grid_default
from gongsynth.tomlfmt import toml_table

__all__ = ["SimulationConfig", "Effects", "ENGINES", "MODES", "DEFAULT_OBSTIME", "DEFAULT_SURFACE_FIELD",
           "SURFACE_FIELD_NAMES", "IN_MEMORY"]

#: Scene modes accepted by `SimulationConfig.mode`.
MODES = tuple(DEFAULT_SUNS)
#: Default observation time (B0 ≈ 0), as an ISO string.
DEFAULT_OBSTIME = _DEFAULT_TIME.isot
#: The large-scale field of a full-disk run unless one is given: the seeded
#: synthetic Sun of the run's date (its activity follows the cycle phase).
DEFAULT_SURFACE_FIELD = "synthetic"
#: The named large-scale fields (anything else is a map's path or '<array>').
SURFACE_FIELD_NAMES = ("synthetic", "quiet")
#: The recorded "path" of a flat or dark that was passed as an array.
IN_MEMORY = "<array>"


_QUANTITIES = {
    "latitude": (u.deg, "heliographic latitude of the field centre on the central meridian"),
    "duration": (u.min, "length of the observation (GONG magnetograms: 1 min; the paper: 10 min)"),
    "photosphere_pixel_size": (u.km, "column spacing of the built-in Sun"),
    "pointing": (u.arcsec, "full-disk mode: helioprojective (Tx, Ty) of the detector's centre; "
                           "[0, 0]: the Sun's centre"),
    "network_chain_length": (u.Mm, "full-disk mode, with the network: Gaussian sigma along its cell wall "
                                   "over which each concentration is laid (0: at a point; 3-4 Mm matches "
                                   "real GONG, MDI and HMI maps)"),
}
_DOCS = {
    "engine": "camera engine: 'blocks' (fast, statistically exact) or 'frames' (frame by frame)",
    "mode": "'tiled' (the paper's tiling at several resolutions) or 'full-disk'",
    "seed": "root random seed (int); unset: fresh entropy each run, recorded in the run's config.toml",
    "detector_shape": "detector side in pixels; unset: the instrument's (GONG 860; HMI 1024 tiled, "
                      "4096 full disk)",
    "resolutions": "tiled mode: magnification of the tile in each quadrant (1 = true size)",
    "obstime": "observation time (ISO); sets the observer position and the map dates",
    "photosphere_shape": "columns of the built-in Sun (ny, nx); unset: that Sun's default",
    "sun": "the built-in Sun: 'milne-eddington' (columns, fast) or 'model-atmosphere' (3-D, LTE transfer)",
    "workers": "threads for the frames engine (None: all cores)",
    "atmosphere_file": "a model atmosphere as the input Sun (MURaM folder, HDF5 or 1-D model path; "
                       "'<array>': passed in memory); unset: the built-in Sun",
    "surface_field": "full-disk mode: the Sun's large-scale field: 'synthetic' (the seeded synthetic Sun of "
                     "the date; the default), 'quiet' (the quiet Sun everywhere), a magnetogram or synoptic "
                     "map's FITS path ('<array>': passed in memory)",
    "atmosphere_sha256": "SHA-256 of that atmosphere (a folder: of its files), checked when the run is "
                         "repeated",
    "surface_field_sha256": "SHA-256 of that surface-field map file, checked when the run is repeated",
    "flat_file": "a user-supplied flat: its FITS path, or '<array>' (unset: the synthetic flat)",
    "flat_sha256": "SHA-256 of that flat, checked when the run is repeated",
    "dark_file": "a user-supplied dark: its FITS path, or '<array>' (unset: the synthetic dark)",
    "dark_sha256": "SHA-256 of that dark, checked when the run is repeated",
    "site": f"the observer's ground site, a GONG site {sorted(GONG_SITES)}; unset: the Earth's centre",
    "like": "a real GONG full-disk FITS file whose date, site, plate scale and pointing the run takes",
    "like_counts": "with like: scale the expected counts to the file's count level (its DIODE sums), i.e. "
                   "the effective area of that observation (false: the instrument's effective_area)",
    "network": "full-disk mode: lay the magnetic network on supergranular cells over the large-scale field, "
               "and their flow in the Doppler shifts (true; false: the field as it is; unset: on for the "
               "synthetic and quiet Suns, off over an observed map, which holds the Sun's own network); "
               "tiled mode: see [photosphere] network",
}


@dataclass(frozen=True)
class Effects:
    """
    The instrument's effects that a run can switch off (TOML ``[effects]``; CLI ``--no-<effect>``).

    Every effect is on by default (the real instrument).  Switching one off
    shows what it does to the measurement: e.g. ``photon_noise=False,
    read_noise=False`` gives the noiseless magnetogram of the same Sun.

    Parameters
    ----------
    psf : bool
        The optics' point-spread function (aperture diffraction and seeing).
    seeing : bool
        The atmospheric seeing part of the PSF (off: diffraction only).
    flat : bool
        The detector flat field (off: a perfectly uniform detector).
    dark : bool
        The dark current (off: none).
    photon_noise : bool
        Poisson noise of the photo-electrons (off: the expected counts).
    read_noise : bool
        Gaussian read noise per frame.
    dither : bool
        The dither added before truncation.
    truncation : bool
        Dropping the lowest bits after accumulation.
    frame_seeing : bool
        Seeing that changes from frame to frame: each plane accumulates its
        own image motion (`gongsynth.stages.seeing`; instruments with
        seeing only, and only with ``seeing`` on).
    minute_average : bool
        GONG's averaging: a run of several minutes is reduced minute by
        minute and the maps averaged (`gongsynth.stages.averaging`).
    image_rotation : bool
        GONG's reduction turns every one-minute image by the rotator's angle
        and so interpolates it once (`gongsynth.instruments.gong.ucor`;
        instruments with ``image_rotation_angle`` only).

    Examples
    --------
    >>> Effects(photon_noise=False).off
    ('photon_noise',)
    >>> Effects(minute_average=True).opted_in
    ('minute_average',)
    """

    psf: bool = True
    seeing: bool = True
    flat: bool = True
    dark: bool = True
    photon_noise: bool = True
    read_noise: bool = True
    dither: bool = True
    truncation: bool = True
    frame_seeing: bool = False
    minute_average: bool = False
    image_rotation: bool = False

    def __post_init__(self):
        for f in fields(self):
            if not isinstance(getattr(self, f.name), bool):
                raise TypeError(f"effects.{f.name} must be true or false, got {getattr(self, f.name)!r}")

    @property
    def off(self):
        """Names of the effects on by default that are switched off."""
        return tuple(f.name for f in fields(self) if f.default and not getattr(self, f.name))

    @property
    def opted_in(self):
        """Names of the opt-in effects (off by default) that are switched on."""
        return tuple(f.name for f in fields(self) if not f.default and getattr(self, f.name))

    @classmethod
    def from_dict(cls, table, *, where="effects"):
        """
        Build from a parsed TOML table, naming unknown keys.

        Parameters
        ----------
        table : dict
        where : str
            The table's name for messages.

        Returns
        -------
        `Effects`
        """
        known = [f.name for f in fields(cls)]
        bad = [k for k in table if k not in known]
        if bad:
            raise KeyError(f"unknown key(s) {bad} in [{where}]; valid keys are {known}")
        return cls(**table)


def _pointing(value, mode):
    """``pointing`` as a tuple of two angles in arcsec (equality-friendly), checked against the mode."""
    try:
        both = u.Quantity(value)
    except (TypeError, ValueError):
        both = None
    if both is None or both.shape != (2,) or not both.unit.is_equivalent(u.arcsec) \
            or not np.all(np.isfinite(both.value)):
        raise ValueError(f"pointing must be two finite angles (Tx, Ty), e.g. [30, -5] * u.arcsec, "
                         f"got {value!r}")
    if np.any(both.value != 0) and mode != "full-disk":
        raise ValueError(f"pointing (Tx, Ty) = {both} moves a full-disk detector; a tiled run points at "
                         f"its latitude (mode = {mode!r})")
    return tuple(both.to(u.arcsec))


def _check_timing(duration, instrument):
    """The duration and the instrument's timing give every accumulation plane frames (before computing)."""
    try:
        frames = instrument.schedule(duration).frames_per_plane
    except ValueError as exc:
        raise ValueError(f"duration = {duration} with this instrument's timing: {exc}") from exc
    if min(frames) < 1:
        raise ValueError(f"duration = {duration} leaves accumulation plane(s) without a frame "
                         f"(frames per plane {list(map(int, frames))} in {instrument.label}'s schedule): "
                         f"observe for longer")


def _check_dates(obstime, duration):
    """Start and end of the observation within the years a FITS date can hold (0001-9999)."""
    import warnings

    with warnings.catch_warnings():    # ERFA's "dubious year" far from now: the check below says more
        warnings.simplefilter("ignore")
        start = Time(obstime)
        years = start.ymdhms.year, (start + duration).ymdhms.year
    if not (1 <= years[0] and years[1] <= 9999):
        raise ValueError(f"obstime = {obstime!r} with duration {duration}: the observation must lie "
                         f"within the years 0001-9999 (the FITS date format)")


def _check_on_disk(pointing, obstime, instrument, pixels):
    """A full-disk detector pointed where it sees part of the solar disk."""
    from sunpy.coordinates import sun

    half = (instrument.plate_scale * pixels / 2).to_value(u.arcsec)
    radius = sun.angular_radius(Time(obstime)).to_value(u.arcsec)
    tx, ty = (abs(p.to_value(u.arcsec)) for p in pointing)
    gap = math.hypot(max(tx - half, 0.0), max(ty - half, 0.0))
    if gap >= radius:
        raise ValueError(f"pointing (Tx, Ty) = ({pointing[0]:g}, {pointing[1]:g}) puts the detector "
                         f"(±{half:.0f}″) off the solar disk (radius {radius:.0f}″): point within "
                         f"{half + radius:.0f}″ of the Sun's centre")


def _same(a, b):
    """Whether two knob values are equal (Quantities in any equivalent unit)."""
    try:
        return bool(np.all(a == b)) and type(a) is type(b)
    except (TypeError, ValueError, u.UnitsError):
        return False


def _photosphere_knobs(values, sun="model-atmosphere", where="photosphere"):
    """
    The knobs of ``values`` that differ from ``sun``'s defaults, each checked against
    its default's type and unit (the builder fills in the rest).
    """
    defaults = photosphere_defaults(sun)
    bad = [k for k in values if k not in defaults]
    if bad:
        raise KeyError(f"unknown key(s) {bad} in [{where}] for sun = {sun!r}; valid keys are "
                       f"{sorted(defaults)}")
    knobs = {}
    for name, value in values.items():
        default = defaults[name]
        if isinstance(default, u.Quantity):
            value = _quantity(name, value, default.unit, where)
        elif isinstance(default, bool):
            if not isinstance(value, bool):
                raise TypeError(f"[{where}] {name} must be true or false, got {value!r}")
        elif default == "auto":         # "auto" standing for true/false by the box
            if not (isinstance(value, bool) or value == "auto"):
                raise TypeError(f"[{where}] {name} must be true, false or \"auto\", got {value!r}")
        elif isinstance(default, str):  # a choice
            if not isinstance(value, (str, bool)):
                raise TypeError(f"[{where}] {name} must be a string or true/false, got {value!r}")
        elif isinstance(value, bool) or not isinstance(value, (int, float)):
            raise TypeError(f"[{where}] {name} must be a number, got {value!r}")
        if not _same(value, default):
            # An array Quantity (a height range) is held as a tuple of scalars, so that configs compare.
            knobs[name] = tuple(value) if isinstance(value, u.Quantity) and value.ndim else value
    return knobs


def _is_int(value):
    """An integer (Python or numpy), not a bool."""
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


@dataclass(frozen=True)
class SimulationConfig:
    """
    The arguments of one `gongsynth.simulate` run.

    Parameters
    ----------
    latitude : `~astropy.units.Quantity`
        Heliographic latitude of the field centre, in (-90°, 90°).
    duration : `~astropy.units.Quantity`
        Observation length (time); default (None) the instrument's
        ``default_duration`` (GONG: 10 min, HMI: 45 s, MDI: 1 min).
    engine : str
        ``"blocks"`` or ``"frames"``.
    mode : str
        ``"tiled"`` or ``"full-disk"``.
    seed : int or None
        Root seed; ``None`` (the default) draws fresh entropy, reduced to an
        int that the config then holds, so the run can be repeated.
    detector_shape : int or None
        Detector side in pixels; ``None`` uses the instrument's: its whole
        detector (GONG 860, HMI 4096) or, in tiled mode, its
        ``tiled_detector_shape`` where it has one (HMI 1024).
    resolutions : tuple of int
        Tile magnifications of the quadrants in tiled mode.
    obstime : str
        ISO time of the observation.
    sun : str or None
        The built-in Sun (a key of `SUNS`): ``"model-atmosphere"`` (the 3-D
        model atmosphere through LTE radiative transfer; over the full disk
        its patch library takes ~10-30 s to build once, then is cached) or
        ``"milne-eddington"`` (the column photosphere: fast, one line strength
        everywhere, a toy for calibration).  None (default): the mode's
        default, `default_sun` (recorded).
    photosphere_shape : tuple of int or None
        Columns of the built-in Sun; None: that Sun's default (recorded).
    photosphere_pixel_size : `~astropy.units.Quantity` or None
        Their spacing (length); None: that Sun's default (recorded).
    workers : int or None
        Threads for the frames engine.
    effects : `Effects`
        The instrument effects that are on.
    photosphere : dict
        Knobs of the built-in Sun that differ from its defaults
        (`photosphere_defaults` lists them all).
    atmosphere_file : str or None
        A model atmosphere as the input Sun instead of the built-in one: its
        path (read by `gongsynth.Atmosphere.read`), or ``"<array>"`` when it
        was passed to `gongsynth.simulate` in memory.
    atmosphere_sha256, surface_field_sha256 : str or None
        The `~gongsynth.files.fingerprint` of the atmosphere file (or folder)
        and of the surface-field map file (their paths are recorded absolute);
        a repeat of the run refuses a file that has changed.
    surface_field : str or None
        Full-disk mode: the large-scale radial field the small scales follow:
        ``"synthetic"`` (`gongsynth.sun.surface_field.synthetic_surface_field`
        at the run's date and seed; the default, recorded), ``"quiet"`` (the
        quiet Sun everywhere), a magnetogram or synoptic map's FITS path, or
        ``"<array>"`` when a map was passed to `gongsynth.simulate`.  None in
        tiled mode.
    flat_file, dark_file : str or None
        A user-supplied flat or dark: its FITS path, or ``"<array>"`` when it
        was passed as an array (None: the instrument's synthetic one).
    flat_sha256, dark_sha256 : str or None
        Their `fingerprint`, checked when the run is repeated.
    site : str or None
        The observer's GONG site code (``"BB"``: Big Bear); None: the Earth's centre.
    like : str or None
        A real GONG file whose date, site, plate scale and pointing the run
        took (see `gongsynth.observing.like_gong`; keys given explicitly win).
    like_counts : bool
        With ``like`` (GONG, full disk): scale the expected counts to the
        file's count level, its ``DIODE1``-``DIODE3`` sums
        (`gongsynth.instruments.gong.header_counts`), i.e. observe with that
        observation's effective area (recorded as ``EFFAREA`` in the raw
        header); default False: the instrument's ``effective_area``.
    network : bool or None
        Full-disk mode: lay the magnetic network on supergranular cells
        (`gongsynth.sun.surface_field.network`) over the large-scale field,
        and shift the spectra by the same cells' flow
        (`gongsynth.sun.surface_field.supergranulation`).  Default (None): on
        for the ``"synthetic"`` and ``"quiet"`` surface fields, off over an
        observed map (it holds the Sun's own network; see `network_on`); no
        effect in tiled mode, whose 3-D Sun has its own switch,
        ``[photosphere] network`` (`gongsynth.sun.model_atmosphere.network_layout`).
    network_chain_length : `~astropy.units.Quantity`
        Full-disk mode, with the network: the Gaussian sigma along its cell
        wall over which each concentration is laid
        (`~gongsynth.sun.surface_field.network.SupergranularNetwork`'s
        ``chain_length``; default its `~gongsynth.sun.surface_field.network.CHAIN_LENGTH`,
        3 Mm; 0: at a point).  3-4 Mm gives the network clusters the
        elongation of real GONG, MDI and HMI maps (docs, decisions: "the
        disk network's chains").
    pointing : tuple of `~astropy.units.Quantity`
        Full-disk mode: helioprojective (Tx, Ty) of the detector's centre
        (default (0, 0): the Sun's centre on the detector's centre; a real
        GONG image is off centre by up to a few tens of arcsec).
    instrument : `~gongsynth.instruments.base.Instrument` or str
        The instrument: an object of the family (`gongsynth.instruments`) or
        its name (``"gong"``, the default), stored as the object.  TOML:
        ``[instrument]`` with ``name`` and every parameter.

    Examples
    --------
    >>> cfg = SimulationConfig(seed=3)
    >>> SimulationConfig().seed != SimulationConfig().seed   # fresh entropy when no seed is given
    True
    >>> SimulationConfig.from_toml(cfg.to_toml()) == cfg
    True
    """

    latitude: u.Quantity = 0 * u.deg
    duration: u.Quantity | None = None
    engine: str = "blocks"
    mode: str = "tiled"
    seed: int | None = None
    detector_shape: int | None = None
    resolutions: tuple = (1, 2, 4, 8)
    obstime: str = DEFAULT_OBSTIME
    sun: str | None = None
    photosphere_shape: tuple | None = None
    photosphere_pixel_size: u.Quantity | None = None
    workers: int | None = None
    effects: Effects = field(default_factory=Effects)
    photosphere: dict = field(default_factory=dict)
    atmosphere_file: str | None = None
    atmosphere_sha256: str | None = None
    surface_field: str | None = None
    surface_field_sha256: str | None = None
    flat_file: str | None = None
    flat_sha256: str | None = None
    dark_file: str | None = None
    dark_sha256: str | None = None
    site: str | None = None
    like: str | None = None
    like_counts: bool = False
    pointing: tuple = (0 * u.arcsec, 0 * u.arcsec)
    instrument: object = field(default_factory=instruments.get)
    network: bool | None = None
    network_chain_length: u.Quantity = CHAIN_LENGTH

    def __post_init__(self):
        if self.network is not None and not isinstance(self.network, bool):
            raise ValueError(f"network must be true, false or unset (None), got {self.network!r}")
        if self.sun is None and self.mode in MODES:
            object.__setattr__(self, "sun", default_sun(self.mode))
        if self.sun not in SUNS:
            raise ValueError(f"sun must be one of {tuple(SUNS)}, got {self.sun!r}")
        if self.photosphere_shape is None:
            object.__setattr__(self, "photosphere_shape", run_grid_default(self.sun, "shape"))
        if self.photosphere_pixel_size is None:
            object.__setattr__(self, "photosphere_pixel_size", run_grid_default(self.sun, "pixel_size"))
        object.__setattr__(self, "pointing", _pointing(self.pointing, self.mode))
        object.__setattr__(self, "instrument", instruments.get(self.instrument))  # a name, or the object
        if self.duration is None:   # the instrument's standard product (GONG: the paper's 10 min)
            object.__setattr__(self, "duration", self.instrument.default_duration.to(u.min))
        for name, (unit, _) in _QUANTITIES.items():
            value = getattr(self, name)
            value = value if name != "pointing" else u.Quantity(value)
            if not isinstance(value, u.Quantity) or not value.unit.is_equivalent(unit):
                raise u.UnitsError(f"{name} must be a Quantity convertible to {unit}, got {value!r}")
        if np.ndim(self.network_chain_length) or not self.network_chain_length.value >= 0:
            raise ValueError(f"network_chain_length must be one length >= 0, got {self.network_chain_length}")
        if isinstance(self.obstime, (datetime.date, Time)):   # TOML's native date-time, a Time
            object.__setattr__(self, "obstime", Time(self.obstime).isot)
        _check_timing(self.duration, self.instrument)
        if self.engine not in ENGINES:
            raise ValueError(f"engine must be one of {ENGINES}, got {self.engine!r}")
        if self.mode not in MODES:
            raise ValueError(f"mode must be one of {MODES}, got {self.mode!r}")
        if self.seed is None:
            object.__setattr__(self, "seed", root_seed(None))
        if not _is_int(self.seed) or self.seed < 0:
            raise TypeError(f"seed must be a non-negative int, got {self.seed!r}")
        object.__setattr__(self, "seed", int(self.seed))
        if self.detector_shape is not None:
            if not _is_int(self.detector_shape) or self.detector_shape < 8:
                raise ValueError(f"detector_shape must be an int >= 8 or None, got {self.detector_shape!r}")
            object.__setattr__(self, "detector_shape", int(self.detector_shape))
        resolutions = tuple(self.resolutions)
        if not resolutions or len(resolutions) > 4 or any(not _is_int(r) or r < 1 for r in resolutions):
            raise ValueError(f"resolutions must be 1 to 4 positive ints, got {self.resolutions!r}")
        object.__setattr__(self, "resolutions", tuple(int(r) for r in resolutions))
        shape = tuple(self.photosphere_shape)
        if len(shape) != 2 or any(not _is_int(n) or n < 4 for n in shape):
            raise ValueError(f"photosphere_shape must be two ints >= 4, got {self.photosphere_shape!r}")
        object.__setattr__(self, "photosphere_shape", tuple(int(n) for n in shape))
        Pointing(self.latitude, self.obstime)  # checks the latitude and the time, once, in one place
        _check_dates(self.obstime, self.duration)
        if self.mode == "full-disk":
            _check_on_disk(self.pointing, self.obstime, self.instrument, self.detector_pixels)
        if self.workers is not None:
            if not _is_int(self.workers) or self.workers < 1:
                raise ValueError(f"workers must be a positive int or None, got {self.workers!r}")
            object.__setattr__(self, "workers", int(self.workers))
        if not isinstance(self.effects, Effects):
            raise TypeError(f"effects must be an Effects, got {type(self.effects).__name__}")
        object.__setattr__(self, "photosphere", _photosphere_knobs(dict(self.photosphere), self.sun))
        object.__setattr__(self, "site", check_site(self.site))
        if self.like is not None and not isinstance(self.like, str):
            raise TypeError(f"like must be the path of a GONG FITS file or None, got {self.like!r}")
        if not isinstance(self.like_counts, bool):
            raise TypeError(f"like_counts must be true or false, got {self.like_counts!r}")
        if self.like_counts and (self.like is None or self.mode != "full-disk"
                                 or self.instrument.name != "gong"):
            raise ValueError(f"like_counts takes the count level of a real GONG file: it needs like (got "
                             f"{self.like!r}), mode = 'full-disk' (got {self.mode!r}) and a GONG instrument "
                             f"(got {self.instrument.name!r})")
        if self.surface_field is None and self.mode == "full-disk":
            object.__setattr__(self, "surface_field", DEFAULT_SURFACE_FIELD)
        if self.surface_field is not None and (not isinstance(self.surface_field, str)
                                               or self.mode != "full-disk"):
            raise ValueError(f"surface_field is 'synthetic', 'quiet' or a path (or '<array>') of a full-disk "
                             f"run, got {self.surface_field!r} with mode = {self.mode!r}")
        for name in ("flat", "dark"):
            path, digest = getattr(self, f"{name}_file"), getattr(self, f"{name}_sha256")
            if (path is None) != (digest is None):
                raise ValueError(f"{name}_file and {name}_sha256 go together: got {path!r} and {digest!r}")

    @classmethod
    def from_arguments(cls, *, seed=None, instrument=None, **kwargs):
        """
        Build a config from `gongsynth.simulate`-style arguments.

        ``seed=None`` draws fresh entropy, reduced to a 63-bit int so that it
        fits a FITS header and the run can be repeated from the saved config.

        Parameters
        ----------
        seed : None, int, `numpy.random.SeedSequence` or `numpy.random.Generator`
        instrument : `~gongsynth.instruments.base.Instrument` or str, optional
            An instrument of the family or its name (default GONG).
        **kwargs
            The other fields.

        Returns
        -------
        `SimulationConfig`
        """
        seed = root_seed(seed)
        instrument = instruments.get(instrument)
        if isinstance(kwargs.get("obstime"), Time):
            kwargs["obstime"] = kwargs["obstime"].isot
        return cls(seed=seed, instrument=instrument, **kwargs)

    @property
    def detector_pixels(self):
        """
        Detector side in pixels: ``detector_shape``, or if None the instrument's (see `SimulationConfig`).

        Examples
        --------
        >>> SimulationConfig(seed=1).detector_pixels
        860
        >>> [SimulationConfig(seed=1, instrument="hmi", mode=mode).detector_pixels
        ...  for mode in ("tiled", "full-disk")]
        [1024, 4096]
        """
        if self.detector_shape is not None:
            return self.detector_shape
        tiled = getattr(self.instrument, "tiled_detector_shape", None) if self.mode == "tiled" else None
        return self.instrument.detector_shape if tiled is None else tiled

    @property
    def network_on(self):
        """Whether a full-disk run lays the supergranular network: ``network``, or by default
        on unless the surface field is an observed map (bool).
        """
        if self.network is not None:
            return self.network
        return self.surface_field is None or self.surface_field in SURFACE_FIELD_NAMES

    def replace(self, **changes):
        """
        Return a copy with some fields changed (validated again).

        A change of ``mode`` moves ``sun`` and ``surface_field`` to the new
        mode's defaults where they held the old mode's (and were not changed
        too).  A change of ``sun``
        also moves ``photosphere_shape`` and ``photosphere_pixel_size`` to the
        new Sun's defaults where they held the old Sun's defaults (and were
        not changed too).

        Parameters
        ----------
        **changes
            Field names and new values.

        Returns
        -------
        `SimulationConfig`
        """
        if "mode" in changes and "sun" not in changes and self.sun == default_sun(self.mode):
            changes["sun"] = None      # the mode's default Sun follows the mode
        if "mode" in changes and "surface_field" not in changes \
                and self.surface_field == DEFAULT_SURFACE_FIELD:
            changes["surface_field"] = None  # so does the full disk's default field
        if changes.get("sun", self.sun) != self.sun:
            for name, key in (("photosphere_shape", "shape"), ("photosphere_pixel_size", "pixel_size")):
                if name not in changes and _same(getattr(self, name), run_grid_default(self.sun, key)):
                    changes[name] = None
        return dataclasses.replace(self, **changes)

    def sun_arguments(self):
        """
        The keyword arguments of the built-in Sun's builder (``SUNS[sun]``) but the seed.

        Returns
        -------
        dict
        """
        knobs = {name: u.Quantity(value) if isinstance(value, tuple) else value
                 for name, value in self.photosphere.items()}
        return {"shape": self.photosphere_shape, "pixel_size": self.photosphere_pixel_size, **knobs}

    def simulation_arguments(self):
        """
        The ``[simulation]`` table's fields and values.

        Returns
        -------
        dict
        """
        return {f.name: getattr(self, f.name) for f in fields(self)
                if f.name not in ("instrument", "effects", "photosphere")}

    def to_toml(self, *, comments=True, template=False):
        """
        The configuration as TOML: ``[simulation]``, ``[effects]``, ``[photosphere]`` and ``[instrument]``.

        Parameters
        ----------
        comments : bool
            Precede each key with a comment explaining it.
        template : bool
            Leave the seed unset (a run from the file then draws a fresh one and
            records it): for ``gongsynth config --print-defaults``.

        Returns
        -------
        str
        """
        doc = tomlkit.document()
        doc.add(tomlkit.comment("gongsynth run configuration"))
        simulation = self.simulation_arguments()
        if template:
            simulation["seed"] = None
        doc.add("simulation", toml_table(
            [(name, value, _QUANTITIES[name][1] if name in _QUANTITIES else _DOCS.get(name, ""))
             for name, value in simulation.items()], comments=comments))
        doc.add("effects", toml_table(
            [(name, value, "") for name, value in dataclasses.asdict(self.effects).items()],
            comments=comments))
        knobs = {**photosphere_defaults(self.sun), **self.photosphere}
        doc.add("photosphere", toml_table(
            [(name, value, "") for name, value in knobs.items()], comments=comments))
        doc.add("instrument", self.instrument.toml_table(comments=comments))
        return tomlkit.dumps(doc)

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
        path = _as_path(source)
        text = source if path is None else _read_text(path)
        try:
            table = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            where = "the TOML text" if path is None else str(path)
            raise ValueError(f"{where} is not valid TOML: {exc}") from exc
        return cls.from_dict(table)

    @classmethod
    def from_dict(cls, table):
        """
        Build a configuration from a parsed TOML document.

        Parameters
        ----------
        table : dict
            ``{"simulation": {...}, "effects": {...}, "photosphere": {...}, "instrument": {...}}``;
            every table optional.

        Returns
        -------
        `SimulationConfig`
        """
        tables = ("simulation", "effects", "photosphere", "instrument")
        unknown = [k for k in table if k not in tables]
        if unknown:
            raise KeyError(f"unknown table(s) {unknown}; expected {', '.join(f'[{t}]' for t in tables)}")
        sim = dict(table.get("simulation", {}))
        known = set(cls().simulation_arguments())
        bad = [k for k in sim if k not in known]
        if bad:
            raise KeyError(f"unknown key(s) {bad} in [simulation]; valid keys are {sorted(known)}")
        for name, (unit, _) in _QUANTITIES.items():
            if name in sim:
                if isinstance(sim[name], list) and name != "pointing":
                    raise ValueError(f"[simulation] {name} is one value, e.g. {name} = \"1 {unit}\", got the "
                                     f"list {sim[name]!r}" + ("; a sweep of latitudes: gongsynth simulate "
                                                               "--latitude 0 30 60, or simulate_many"
                                                               if name == "latitude" else ""))
                sim[name] = _quantity(name, sim[name], unit)
        for name, example in (("resolutions", "[1, 2, 4, 8]"), ("photosphere_shape", "[256, 256]")):
            if name in sim:
                if not isinstance(sim[name], (list, tuple)):
                    raise TypeError(f"[simulation] {name} is a list, e.g. {name} = {example}, "
                                    f"got {sim[name]!r}")
                sim[name] = tuple(sim[name])
        instrument = instruments.from_dict(table.get("instrument", {}))
        effects = table.get("effects", {})
        if sim.get("like") is not None:
            sim, instrument = like_gong(sim["like"], settings=sim, instrument=instrument,
                                        mode=sim.get("mode", cls.mode),
                                        fixed_plate_scale="plate_scale" in table.get("instrument", {}))
            sim, effects = as_observed(sim, effects, mode=sim.get("mode", cls.mode),
                                       instrument_name=instrument.name)
        return cls(instrument=instrument, effects=Effects.from_dict(effects),
                   photosphere=table.get("photosphere", {}), **sim)


def _as_path(source):
    """``source`` as a path, or None when it is TOML text (a string holding '=' or a newline)."""
    if isinstance(source, Path):
        return source
    if not isinstance(source, str):
        raise TypeError(f"source must be TOML text or a path, got {type(source).__name__}")
    return None if ("=" in source or "\n" in source or source.lstrip().startswith("[")) else Path(source)


def _read_text(path):
    """The text of a configuration file, with errors that name it."""
    if path.is_dir():
        raise IsADirectoryError(f"the configuration {path} is a directory, not a TOML file")
    try:
        return path.read_text()
    except FileNotFoundError:
        raise FileNotFoundError(2, "no such configuration file", str(path)) from None
    except UnicodeDecodeError as exc:
        raise ValueError(f"{path} is not a text (TOML) file: {exc}") from exc


def _quantity(name, value, unit, where="simulation"):
    """A TOML value (a string such as "7 Mm", or a Quantity, or a list of them) as a Quantity in ``unit``."""
    if isinstance(value, (list, tuple)):
        return u.Quantity([_quantity(name, v, unit, where) for v in value])
    if isinstance(value, str):
        try:
            value = u.Quantity(value)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"[{where}] {name} = {value!r} is not a quantity like '1 {unit}'") from exc
    if not isinstance(value, u.Quantity):
        raise u.UnitsError(f"[{where}] {name} needs units, e.g. {name} = \"{value} {unit}\"")
    if not value.unit.is_equivalent(unit):
        raise u.UnitsError(f"[{where}] {name} must be in units convertible to {unit}, got {value.unit}")
    return value
