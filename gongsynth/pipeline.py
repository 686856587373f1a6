"""
Running a simulation: `simulate` (one observation) and `simulate_many` (a sweep).

`simulate` builds the run's `~gongsynth.chain.Chain` of stages from its
configuration (photosphere → spectra → channels → scene → optics → camera →
reduction → maps) and runs it.  `simulate_many` runs a sweep (latitudes, seeds)
serially or on Dask, with results identical to the serial runs because every
random stream is derived from the run's seed and the stage name only.
"""
import inspect
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

import astropy.units as u
import numpy as np

from gongsynth.chain import build_chain
from gongsynth.config import IN_MEMORY, SURFACE_FIELD_NAMES, Effects, SimulationConfig
from gongsynth.files import fingerprint
from gongsynth.optional import import_optional
from gongsynth.resources import check_resources
from gongsynth.sun.atmosphere import Atmosphere
from gongsynth.version import version as __version__

__all__ = ["SimulationResult", "Sweep", "simulate", "simulate_many", "simulate_each", "check_scene",
           "record_input_file"]

# What a SimulationResult is made of: the chain releases every other quantity once used (the
# expected counts too, a diagnostic made again on demand: 0.8 GB for a full-disk HMI run).
_RESULT_STATE = ("magnetogram_map", "doppler_map", "continuum_map", "truth_map", "truth_psf_map", "raw",
                 "light")

@dataclass
class SimulationResult:
    """
    The products of one simulated observation (GONG, or another instrument of the family).

    Attributes
    ----------
    magnetogram : `~gongsynth.products.maps.GONGSynthMap`
        Measured line-of-sight flux density (G).
    doppler : `~gongsynth.products.maps.GONGSynthMap`
        Measured line-of-sight velocity (m/s, positive away from the observer).
    continuum : `~gongsynth.products.maps.GONGSynthMap`
        (Pseudo-)continuum (DN; GONG: the sum of the six planes).
    truth : `~gongsynth.products.maps.GONGSynthMap` or None
        True B_LOS of the input averaged over each detector pixel (G; design §3.13).
    truth_psf : `~gongsynth.products.maps.GONGSynthMap` or None
        The same seen through the instrument PSF first.
    raw : `~gongsynth.stages.camera.integrate.RawPlanes`
        The instrument's K accumulated raw planes (GONG: six).
    expected_counts : `~astropy.units.Quantity`
        Expected electrons per frame per pixel, shape (K, ny, nx), before noise: a diagnostic,
        not held by the run (12 × 4096² values for a full-disk HMI run) but made again from
        ``chain`` on first access (the stages up to the optics, deterministic: the same
        numbers), then kept.
    resolution_map : `numpy.ndarray`
        Tile magnification of each detector pixel (1 = the instrument's resolution).
    config : `~gongsynth.config.SimulationConfig`
        Everything needed to repeat the run bit for bit.
    timings : dict
        Wall-clock seconds of each stage.
    chain : `~gongsynth.chain.Chain`
        The stages that ran, in order.
    """

    magnetogram: object
    doppler: object
    continuum: object
    truth: object
    truth_psf: object
    raw: object
    resolution_map: np.ndarray
    config: SimulationConfig
    timings: dict = field(default_factory=dict)
    chain: object = None
    _expected_counts: object = field(default=None, repr=False)

    @property
    def expected_counts(self):
        """The expected electrons per frame (K, ny, nx), made again by the chain on first access."""
        if self._expected_counts is None and self.chain is not None:
            state = self.chain.run(until="optics", progress=False, keep=("expected_counts",))
            self._expected_counts = state["expected_counts"]
        return self._expected_counts

    def summary(self):
        """
        A few lines describing the run and its products.

        Returns
        -------
        str
        """
        cfg = self.config
        b = self.magnetogram.data
        lines = [
            f"gongsynth {__version__}: {cfg.mode} scene"
            + (f" at latitude {cfg.latitude:.1f}" if cfg.mode == "tiled" else "")
            + f", {cfg.duration:.1f}, engine {cfg.engine}, seed {cfg.seed}",
            f"  magnetogram {b.shape[1]}x{b.shape[0]} px: mean {np.nanmean(b):+.2f} G, "
            f"std {np.nanstd(b):.1f} G, range {np.nanmin(b):+.0f} .. {np.nanmax(b):+.0f} G",
        ]
        if self.timings:
            lines.append("  stage times: " + ", ".join(f"{k} {v:.1f} s" for k, v in self.timings.items()))
        return "\n".join(lines)

    def save(self, directory, *, overwrite=False, quicklook=True):
        """
        Write the products as FITS (and a PNG quick-look) into ``directory``.

        Every file is written atomically (temporary name, then rename), and
        nothing is written at all if any target exists and ``overwrite`` is
        false.

        Parameters
        ----------
        directory : path-like
        overwrite : bool
            Replace existing files.
        quicklook : bool
            Also write ``quicklook.png``.

        Returns
        -------
        list of `pathlib.Path`
            The files written.
        """
        from gongsynth.products.output import save_result

        return save_result(self, directory, overwrite=overwrite, quicklook=quicklook)


class Sweep(list):
    """
    The results of `simulate_many`, in run order, with their maps as sunpy sequences.

    Examples
    --------
    >>> import astropy.units as u
    >>> sweep = simulate_many(latitudes=[0, 45] * u.deg, seed=2, detector_shape=16,
    ...                       duration=1 * u.min, resolutions=(1,), photosphere_shape=(64, 64),
    ...                       photosphere_pixel_size=1536 * u.km, sun="milne-eddington",
    ...                      progress=False)
    >>> len(sweep.map_sequence("magnetogram"))
    2
    """

    def map_sequence(self, product="magnetogram"):
        """
        One product of every run as a `sunpy.map.MapSequence`.

        Parameters
        ----------
        product : {"magnetogram", "doppler", "continuum", "truth", "truth_psf"}

        Returns
        -------
        `sunpy.map.MapSequence`
        """
        import sunpy.map

        names = ("magnetogram", "doppler", "continuum", "truth", "truth_psf")
        if product not in names:
            raise ValueError(f"product must be one of {names}, got {product!r}")
        return sunpy.map.Map([getattr(result, product) for result in self], sequence=True)


def simulate(stokes=None, *, latitude=0 * u.deg, duration=None, engine="blocks", seed=None,
             instrument=None, mode="tiled", detector_shape=None, resolutions=(1, 2, 4, 8),
             obstime=None, sun=None, photosphere_shape=None, photosphere_pixel_size=None,
             effects=None, photosphere=None, flat=None, dark=None, workers=None, progress=True,
             config=None, surface_field=None):
    """
    Simulate a magnetograph's observation end to end (GONG by default).

    Parameters
    ----------
    stokes : `~gongsynth.StokesCube` or `~gongsynth.Atmosphere`, optional
        Input spectra (e.g. RH output of an MHD snapshot) at the viewing angle
        of ``latitude``, or a model atmosphere (e.g. a MURaM snapshot) that
        `gongsynth.rt.synthesize` turns into spectra at that viewing angle.
        Default: the built-in Sun chosen by ``sun``, synthesised at that latitude.
    latitude : `~astropy.units.Quantity`
        Heliographic latitude of the field centre on the central meridian.
    duration : `~astropy.units.Quantity`, optional
        Observation length (10 min: the paper's; 1 min: a GONG magnetogram).
        Default: the instrument's standard product (``default_duration``:
        GONG 10 min, HMI 45 s).
    engine : {"blocks", "frames"}
        Camera engine (see `gongsynth.stages.camera.integrate`).
    seed : int, `numpy.random.SeedSequence`, `numpy.random.Generator` or None
        Root seed; ``None`` draws one and records it in ``result.config``.
    instrument : str or `~gongsynth.instruments.base.Instrument`, optional
        The magnetograph: a name of the family (``"gong"``, the default;
        `gongsynth.instruments.names`) or an instrument object such as
        ``GONGInstrument(seeing_fwhm=2 * u.arcsec)``.  The saved config
        records its name and every parameter.
    mode : {"tiled", "full-disk"}
        The paper's tiling, or the photosphere mapped over the visible disk.
    detector_shape : int, optional
        Detector side in pixels (default the instrument's: GONG 860; HMI 1024
        in tiled mode, its whole 4096 CCD over the full disk).
    resolutions : tuple of int
        Tiled mode: tile magnification of each quadrant.
    obstime : str or `~astropy.time.Time`, optional
        Observation time (default: a date with B0 ≈ 0).
    sun : {"model-atmosphere", "milne-eddington"}, optional
        The built-in Sun (used when ``stokes`` is None): the 3-D model
        atmosphere (`gongsynth.sun.model_atmosphere.model_atmosphere`) through
        LTE radiative transfer along the rays at ``latitude`` (over the full
        disk its patch library, `gongsynth.stages.scene.library_rt`), or the
        column photosphere through Milne-Eddington synthesis (fast; one line
        strength everywhere, a toy for calibration).  Default: the 3-D model
        in both modes (`gongsynth.suns.default_sun`).
    photosphere_shape : tuple of int, optional
        Columns of the built-in Sun (default: 1024 × 1024 for
        ``"milne-eddington"``, the model atmosphere's own default otherwise).
    photosphere_pixel_size : `~astropy.units.Quantity`, optional
        Their spacing (length; default 96 km like the paper's binned MURaM cube).
    effects : `~gongsynth.config.Effects` or dict, optional
        Instrument effects to switch off, e.g. ``{"photon_noise": False}``
        (default: all on).
    photosphere : dict, optional
        Knobs of the built-in Sun (`~gongsynth.sun.photosphere.model_photosphere`
        or `~gongsynth.sun.model_atmosphere.model_atmosphere`), e.g.
        ``{"spot": False}``.
    flat, dark : optional
        Detector flat field and dark map, arrays or FITS paths (see
        `gongsynth.stages.camera.integrate.integrate`); default the
        instrument's synthetic ones.  The config records a user-supplied one
        (path or ``"<array>"`` and its SHA-256), and repeating the run checks it.
    workers : int, optional
        Threads for the frames engine and the FFTs.
    progress : bool
        Show progress bars.
    config : `~gongsynth.config.SimulationConfig`, optional
        A complete configuration (e.g. ``result.config`` of an earlier run);
        it cannot be combined with the run arguments above (that is a
        TypeError), only with ``stokes``, ``flat``, ``dark``, ``progress``
        and ``surface_field``.
    surface_field : `sunpy.map.GenericMap` or path-like, optional
        Full-disk mode: the Sun's large-scale radial field that the small
        scales follow: a `gongsynth.sun.surface_field` map, any magnetogram
        or synoptic map (remapped by `~gongsynth.sun.surface_field.surface_field_from_map`
        to the run's date), a FITS path of one (recorded in the config as
        ``surface_field``), ``"synthetic"`` (the seeded synthetic Sun of the
        run's date: the default) or ``"quiet"`` (the quiet Sun everywhere).

    Returns
    -------
    `SimulationResult`

    Examples
    --------
    A small, quick run with the fast Milne–Eddington toy Sun (the defaults
    simulate the 3-D model Sun on GONG's full 860 × 860 detector for 10
    minutes):

    >>> import astropy.units as u
    >>> result = simulate(duration=1 * u.min, detector_shape=16, resolutions=(1,), seed=1,
    ...                   photosphere_shape=(64, 64), photosphere_pixel_size=1536 * u.km,
    ...                   sun="milne-eddington", progress=False)
    >>> result.magnetogram.unit, result.magnetogram.data.shape, result.config.seed
    (Unit("G"), (16, 16), 1)
    """
    arguments = dict(latitude=latitude, duration=duration, engine=engine, seed=seed, instrument=instrument,
                     mode=mode, detector_shape=detector_shape, resolutions=resolutions, obstime=obstime,
                     sun=sun, photosphere_shape=photosphere_shape,
                     photosphere_pixel_size=photosphere_pixel_size,
                     effects=effects, photosphere=photosphere, workers=workers)
    if config is None:
        given = _given(arguments)
        if isinstance(given.get("effects"), dict):
            given["effects"] = Effects.from_dict(given["effects"])
        config = SimulationConfig.from_arguments(**given)
    elif not isinstance(config, SimulationConfig):
        raise TypeError(f"config must be a SimulationConfig, got {type(config).__name__}")
    elif _given(arguments):
        raise TypeError(f"pass either config or the run's arguments, not both: {sorted(_given(arguments))}")
    check_resources(config)
    config, stokes = _input_atmosphere(config, stokes)
    check_scene(config, stokes)
    config, surface_field = _surface_field(config, surface_field)
    config, flat = _detector_map(config, "flat", flat)
    config, dark = _detector_map(config, "dark", dark)
    chain = build_chain(config, stokes=stokes, flat=flat, dark=dark, progress=progress,
                        surface_field=surface_field)
    timings = {}
    state = chain.run(progress=progress, timings=timings, keep=_RESULT_STATE)
    return SimulationResult(
        magnetogram=state["magnetogram_map"], doppler=state["doppler_map"],
        continuum=state["continuum_map"], truth=state["truth_map"], truth_psf=state["truth_psf_map"],
        raw=state["raw"], resolution_map=state["light"].resolution_map(), config=config, timings=timings,
        chain=chain)


def check_scene(config, stokes=None):
    """
    Refuse, before any computing, a tiled scene whose tile is smaller than a detector pixel.

    Parameters
    ----------
    config : `~gongsynth.config.SimulationConfig`
    stokes : `~gongsynth.StokesCube` or `~gongsynth.Atmosphere`, optional
        The input Sun (default: the built-in one of ``config``).

    Raises
    ------
    ValueError
        As `gongsynth.stages.scene.tiled.check_tile_extent`.
    """
    from gongsynth.geometry import Pointing
    from gongsynth.stages.scene.tiled import check_tile_extent

    if config.mode != "tiled":
        return
    if isinstance(stokes, Atmosphere):
        shape, pixel = stokes.shape[1:], stokes.pixel_size
    elif stokes is not None:
        shape, pixel = stokes.I.shape[:2], stokes.pixel_size
    else:
        shape, pixel = config.photosphere_shape, config.photosphere_pixel_size
    check_tile_extent(shape, pixel, Pointing(config.latitude, config.obstime), config.resolutions,
                      config.instrument)


def _detector_map(config, name, given):
    """
    The flat or dark to use, with ``config`` recording it (path or "<array>", and SHA-256).

    A config that records a user-supplied map needs the same map again: read
    from its path when that still holds it, else passed by the caller.
    """
    recorded_file, recorded_sha = getattr(config, f"{name}_file"), getattr(config, f"{name}_sha256")
    if given is None:
        if recorded_file is None:
            return config, None
        if recorded_file != IN_MEMORY and Path(recorded_file).is_file():
            given = Path(recorded_file)
        else:
            raise ValueError(
                f"this configuration was run with a user-supplied {name} ({recorded_file}, sha256 "
                f"{recorded_sha[:12]}...): pass the same {name}= to repeat it")
    digest = fingerprint(given)
    if recorded_sha is not None and digest != recorded_sha:
        raise ValueError(f"the {name} given (sha256 {digest[:12]}...) is not the one this configuration "
                         f"recorded ({recorded_file}, sha256 {recorded_sha[:12]}...)")
    path = str(given) if isinstance(given, (str, Path)) else IN_MEMORY
    return config.replace(**{f"{name}_file": path, f"{name}_sha256": digest}), given


def _input_atmosphere(config, stokes):
    """
    The run's input Sun and its record: an atmosphere file named by the config is
    read; an `Atmosphere` passed in memory is recorded as such, so that a rerun
    from the saved config cannot silently fall back to the built-in Sun.
    """
    recorded = config.atmosphere_file
    if stokes is None and recorded is not None:
        if recorded == IN_MEMORY:
            raise ValueError("this configuration's input Sun was an Atmosphere passed in memory "
                             "(atmosphere_file = '<array>'): pass it again as simulate's first argument")
        config = record_input_file(config, "atmosphere_file", "atmosphere_sha256")
        return config, Atmosphere.read(config.atmosphere_file)
    if isinstance(stokes, Atmosphere) and recorded is None:
        return config.replace(atmosphere_file=IN_MEMORY), stokes
    return config, stokes


def _surface_field(config, given):
    """The full-disk run's large-scale field map and its record in the config (path or '<array>')."""
    import sunpy.map
    recorded = config.surface_field
    if isinstance(given, str) and given in SURFACE_FIELD_NAMES:
        return config.replace(surface_field=given), None
    if given is None:
        if recorded is None or recorded in SURFACE_FIELD_NAMES:   # the chain builds the synthetic Sun
            return config, None
        if recorded == IN_MEMORY:
            raise ValueError("this configuration's surface field was a map passed in memory "
                             "(surface_field = '<array>'): pass it again as surface_field=")
        given = recorded
    if isinstance(given, (str, Path)):
        from gongsynth.analysis.observations import load_observation

        config = record_input_file(config.replace(surface_field=str(given)), "surface_field",
                                   "surface_field_sha256", folder=False)
        try:   # the checks every observation gets: kind and unit, WCS, finite data
            return config, load_observation(config.surface_field, kind="magnetogram")
        except ValueError as exc:
            raise ValueError(f"surface_field {given}: {exc}") from exc
    if not isinstance(given, sunpy.map.GenericMap):
        raise TypeError(f"surface_field must be a sunpy Map or a FITS path, got {type(given).__name__}")
    return config.replace(surface_field=IN_MEMORY), given


def record_input_file(config, key, sha_key, *, folder=True):
    """
    ``config`` with an input file recorded by absolute path and SHA-256; a file that changed is refused.

    Parameters
    ----------
    config : `~gongsynth.config.SimulationConfig`
    key, sha_key : str
        The fields holding the path and its digest (``"atmosphere_file"``, ``"atmosphere_sha256"``).
    folder : bool, optional
        Whether the input may be a folder (a MURaM snapshot).

    Returns
    -------
    `~gongsynth.config.SimulationConfig`

    Raises
    ------
    FileNotFoundError
        If the path does not exist.
    ValueError
        If the file's SHA-256 differs from the one recorded.
    """
    text = getattr(config, key)
    if "://" in text:
        raise ValueError(f"{key} {text!r}: a URL; gongsynth reads local files only (download it first)")
    path = Path(text).absolute()
    if not text or not path.exists():
        raise FileNotFoundError(2, f"no such {key} file or folder", text)
    if path.is_dir() and not folder:
        raise IsADirectoryError(f"{key} {path} is a folder, not a FITS file")
    digest = fingerprint(path)
    recorded = getattr(config, sha_key)
    if recorded is not None and digest != recorded:
        raise ValueError(f"{key} {path} has changed since this configuration recorded it (sha256 "
                         f"{recorded[:12]}..., now {digest[:12]}...): restore it, or delete {sha_key} from "
                         f"the configuration to run with the new file")
    return config.replace(**{key: str(path), sha_key: digest})


def _given(arguments):
    """
    The run arguments that were passed to `simulate` (not its defaults).

    A default is the very object in `simulate`'s signature, so identity tells
    an untouched default from a value the caller passed (even an equal one).
    """
    defaults = inspect.signature(simulate).parameters
    return {name: value for name, value in arguments.items() if value is not defaults[name].default}


def simulate_many(*, latitudes=(0, 25, 45, 60, 70, 75) * u.deg, seeds=None, config=None,
                  client=None, workers=None, progress=True, **kwargs):
    """
    Run a sweep of simulations, in parallel with Dask when asked.

    Parameters
    ----------
    latitudes : `~astropy.units.Quantity`
        Latitudes to simulate (default: the paper's six viewing angles).
    seeds : sequence of int, optional
        One seed per run; default the config's seed for every run (same
        photosphere and camera streams at every latitude).
    config : `~gongsynth.config.SimulationConfig`, optional
        Base configuration; ``latitude`` and ``seed`` are replaced per run.
        Default: built from ``kwargs`` as for `simulate`.
    client : `dask.distributed.Client`, optional
        Run on this client (any cluster).
    workers : int, optional
        Without a client: start a local Dask cluster with this many worker
        processes (``None`` or 1: run serially, no Dask needed).
    progress : bool
        Show a progress bar over the runs.
    **kwargs
        `simulate` arguments for the base configuration.

    Returns
    -------
    `Sweep`
        A list of `SimulationResult` in the order of the runs, identical to
        running `simulate` on each configuration serially.

    Examples
    --------
    >>> import astropy.units as u
    >>> runs = simulate_many(latitudes=[0, 45] * u.deg, seed=2, detector_shape=16,
    ...                      duration=1 * u.min, resolutions=(1,), photosphere_shape=(64, 64),
    ...                      photosphere_pixel_size=1536 * u.km, sun="milne-eddington",
    ...                      progress=False)
    >>> [float(r.config.latitude.value) for r in runs], runs[0].config.seed == runs[1].config.seed
    ([0.0, 45.0], True)
    """
    latitudes = u.Quantity(latitudes, u.deg).ravel()
    if config is None:
        config = SimulationConfig.from_arguments(**_config_kwargs(kwargs))
    elif kwargs:
        raise TypeError(f"pass either config or simulate() arguments, not both: {sorted(kwargs)}")
    if seeds is None:
        seeds = [config.seed] * latitudes.size
    seeds = list(seeds)
    if len(seeds) != latitudes.size:
        raise ValueError(f"seeds must have one entry per latitude ({latitudes.size}), got {len(seeds)}")
    configs = [config.replace(latitude=lat, seed=int(s)) for lat, s in zip(latitudes, seeds)]
    check_resources(config)

    results = [None] * len(configs)
    for index, result in simulate_each(configs, client=client, workers=workers, progress=progress):
        if isinstance(result, BaseException):
            raise result
        results[index] = result
    return Sweep(results)


def simulate_each(configs, *, stokes=None, client=None, workers=None, progress=True, task=None):
    """
    Run several configurations and yield each result as soon as it is done (to save it at once).

    A run that fails does not stop the others: its exception is yielded in
    place of its result (Ctrl-C stops them all).

    Parameters
    ----------
    configs : sequence of `~gongsynth.config.SimulationConfig`
    stokes : `~gongsynth.StokesCube` or `~gongsynth.Atmosphere`, optional
        The input Sun of every run (then they run serially, in this process).
    client : `dask.distributed.Client`, optional
        Run on this client.
    workers : int, optional
        Without a client: this many local Dask worker processes (``None`` or 1: serially).
    progress : bool
        A progress bar over the runs.
    task : callable, optional
        Run ``task(config=config)`` in place of `simulate` (e.g. `gongsynth.run_cache.run_entry`,
        which keeps only what a table needs); on a cluster it must be picklable.

    Yields
    ------
    (int, `SimulationResult` or Exception)
        The run's index in ``configs`` and its result (``task``'s), in the order the runs finish.

    Examples
    --------
    >>> import astropy.units as u
    >>> from gongsynth.config import SimulationConfig
    >>> base = SimulationConfig(seed=2, detector_shape=16, duration=1 * u.min, resolutions=(1,),
    ...                         photosphere_shape=(64, 64), photosphere_pixel_size=1536 * u.km,
    ...                         sun="milne-eddington")
    >>> [i for i, r in simulate_each([base, base.replace(latitude=45 * u.deg)], progress=False)]
    [0, 1]
    """
    from tqdm.auto import tqdm

    configs = list(configs)
    if task is not None and stokes is not None:
        raise TypeError("pass either task or stokes, not both")
    run = partial(simulate, stokes, progress=False) if task is None else task  # run(config=...)
    bar = tqdm(total=len(configs), disable=not progress, desc="sweep")
    if stokes is not None or (client is None and (workers is None or workers <= 1)):
        for index, config in enumerate(configs):
            try:
                result = run(config=config)
            except Exception as exc:  # noqa: BLE001 - reported with its run; Ctrl-C still stops the sweep
                result = exc
            bar.update()
            yield index, result
        bar.close()
        return
    distributed = import_optional("dask.distributed", "dask")
    own = client is None
    if own:
        cluster = distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                           dashboard_address=None)
        client = distributed.Client(cluster)
    try:
        futures = {client.submit(run, config=c, pure=False): i for i, c in enumerate(configs)}
        for future in distributed.as_completed(futures):
            bar.update()
            yield futures[future], (future.exception() if future.status == "error" else future.result())
        bar.close()
    finally:
        if own:
            client.close()
            cluster.close()


def _config_kwargs(kwargs):
    """``simulate_many``'s run arguments, checked against `simulate`'s."""
    allowed = set(inspect.signature(simulate).parameters) - {"stokes", "flat", "dark", "progress", "config",
                                                               "latitude"}
    if isinstance(kwargs.get("effects"), dict):
        kwargs = {**kwargs, "effects": Effects.from_dict(kwargs["effects"])}
    bad = set(kwargs) - allowed
    if bad:
        raise TypeError(f"unknown simulate_many argument(s) {sorted(bad)}; valid: {sorted(allowed)}")
    return kwargs
