"""
The whole chain: photosphere → spectra → filters → scene → optics → camera → reduction → Maps.

`simulate` runs one observation; `simulate_many` runs a sweep (latitudes,
seeds) serially or on Dask, with results identical to the serial runs because
every random stream is derived from the run's seed and the stage name only.
"""
import time
from dataclasses import dataclass, field

import astropy.units as u
import numpy as np

from gongsynth.version import version as __version__
from gongsynth.config import SimulationConfig
from gongsynth.products.maps import make_product_map
from gongsynth.stages.reduction import reduce
from gongsynth.seeding import child_sequence

__all__ = ["SimulationResult", "simulate", "simulate_many"]

@dataclass
class SimulationResult:
    """
    The products of one simulated GONG observation.

    Attributes
    ----------
    magnetogram : `~gongsynth.products.maps.GONGSynthMap`
        Measured line-of-sight flux density (G).
    doppler : `~gongsynth.products.maps.GONGSynthMap`
        Measured line-of-sight velocity (m/s, positive away from the observer).
    continuum : `~gongsynth.products.maps.GONGSynthMap`
        Pseudo-continuum, the sum of the six planes (DN).
    truth : `~gongsynth.products.maps.GONGSynthMap` or None
        True B_LOS of the input averaged over each detector pixel (G; design §3.13).
    truth_psf : `~gongsynth.products.maps.GONGSynthMap` or None
        The same seen through the instrument PSF first.
    raw : `~gongsynth.stages.camera.integrate.RawPlanes`
        The six accumulated raw planes.
    scene : `~astropy.units.Quantity`
        Expected electrons per frame per pixel, shape (6, ny, nx), before noise.
    resolution_map : `numpy.ndarray`
        Tile magnification of each detector pixel (1 = GONG resolution).
    config : `~gongsynth.config.SimulationConfig`
        Everything needed to repeat the run bit for bit.
    timings : dict
        Wall-clock seconds of each stage.
    """

    magnetogram: object
    doppler: object
    continuum: object
    truth: object
    truth_psf: object
    raw: object
    scene: u.Quantity
    resolution_map: np.ndarray
    config: SimulationConfig
    timings: dict = field(default_factory=dict)

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
            f"gongsynth {__version__}: {cfg.mode} scene at latitude {cfg.latitude:.1f}, "
            f"{cfg.duration:.1f}, engine {cfg.engine}, seed {cfg.seed}",
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


def simulate(stokes=None, *, latitude=0 * u.deg, duration=10 * u.min, engine="blocks", seed=None,
             instrument=None, mode="tiled", detector_shape=None, resolutions=(1, 2, 4, 8),
             obstime=None, photosphere_shape=(1024, 1024), photosphere_pixel_size=96 * u.km,
             flat=None, dark=None, workers=None, progress=True, config=None):
    """
    Simulate a GONG observation end to end.

    Parameters
    ----------
    stokes : `~gongsynth.StokesCube`, optional
        Input spectra (e.g. RH output of an MHD snapshot) at the viewing angle
        of ``latitude``.  Default: the built-in model photosphere, synthesised
        at that latitude.
    latitude : `~astropy.units.Quantity`
        Heliographic latitude of the field centre on the central meridian.
    duration : `~astropy.units.Quantity`
        Observation length (10 min: the paper's; 1 min: a GONG magnetogram).
    engine : {"blocks", "frames"}
        Camera engine (see `gongsynth.stages.camera.integrate`).
    seed : int, `numpy.random.SeedSequence`, `numpy.random.Generator` or None
        Root seed; ``None`` draws one and records it in ``result.config``.
    instrument : `~gongsynth.GONGInstrument`, optional
    mode : {"tiled", "full-disk"}
        The paper's tiling, or the photosphere mapped over the visible disk.
    detector_shape : int, optional
        Detector side in pixels (default the instrument's 860).
    resolutions : tuple of int
        Tiled mode: tile magnification of each quadrant.
    obstime : str or `~astropy.time.Time`, optional
        Observation time (default: a date with B0 ≈ 0).
    photosphere_shape : tuple of int
        Pixels of the built-in model photosphere (used when ``stokes`` is None).
    photosphere_pixel_size : `~astropy.units.Quantity`
        Its pixel size (length; 96 km like the paper's binned MURaM cube).
    flat, dark : optional
        Detector flat field and dark map (see `gongsynth.stages.camera.integrate.integrate`);
        default the synthetic GONG-like ones.
    workers : int, optional
        Threads for the frames engine and the FFTs.
    progress : bool
        Show progress bars.
    config : `~gongsynth.config.SimulationConfig`, optional
        A complete configuration (e.g. ``result.config`` of an earlier run);
        when given, the other keyword arguments except ``stokes``, ``flat``,
        ``dark`` and ``progress`` are ignored.

    Returns
    -------
    `SimulationResult`

    Examples
    --------
    A small, quick run (the defaults simulate GONG's full 860 × 860 detector
    for 10 minutes):

    >>> import astropy.units as u
    >>> result = simulate(duration=1 * u.min, detector_shape=16, resolutions=(1,), seed=1,
    ...                   photosphere_shape=(64, 64), photosphere_pixel_size=1536 * u.km,
    ...                   progress=False)
    >>> result.magnetogram.unit, result.magnetogram.data.shape, result.config.seed
    (Unit("G"), (16, 16), 1)
    """
    if config is None:
        kwargs = dict(latitude=latitude, duration=duration, engine=engine, mode=mode,
                      detector_shape=detector_shape, resolutions=tuple(resolutions),
                      photosphere_shape=tuple(photosphere_shape),
                      photosphere_pixel_size=photosphere_pixel_size, workers=workers)
        if obstime is not None:
            kwargs["obstime"] = obstime
        config = SimulationConfig.from_arguments(seed=seed, instrument=instrument, **kwargs)
    elif not isinstance(config, SimulationConfig):
        raise TypeError(f"config must be a SimulationConfig, got {type(config).__name__}")
    return _run(config, stokes=stokes, flat=flat, dark=dark, progress=progress)


def _run(config, *, stokes, flat, dark, progress):
    from gongsynth.geometry import Pointing
    from gongsynth.stages import channels as polarimetry
    from gongsynth.stages import optics
    from gongsynth.stages.camera import integrate as camera
    from gongsynth.stages.scene import tiled as scene_mod

    from tqdm.auto import tqdm

    inst = config.instrument
    timings = {}
    clock = time.perf_counter()
    n_stages = 7 if config.mode == "tiled" and stokes is None else 6
    bar = tqdm(total=n_stages, desc="gongsynth: spectra", disable=not progress, unit="stage",
               bar_format="{desc:<28s}{bar}| {n_fmt}/{total_fmt} [{elapsed}]")
    upcoming = {"photosphere": "spectra", "synthesis": "filters", "filters": "scene",
                "scene": "optics", "synthesis+scene": "optics", "optics": "camera",
                "camera": "reduction", "reduction": "maps", "maps": "done"}

    def lap(name):
        nonlocal clock
        now = time.perf_counter()
        timings[name] = now - clock
        clock = now
        bar.set_description_str(f"gongsynth: {upcoming[name]}")
        bar.update(1)

    if config.mode == "full-disk":
        if stokes is not None:
            raise ValueError("mode='full-disk' synthesises the built-in photosphere at every "
                             "point's own viewing angle; it does not take a stokes cube")
        from gongsynth.stages.scene import fulldisk
        photosphere = _photosphere(config)
        lap("photosphere")
        light, truth_scene = fulldisk.full_disk_scene(
            photosphere, detector_shape=config.detector_pixels, obstime=config.obstime,
            instrument=inst, progress=progress)
        lap("synthesis+scene")
    else:
        if stokes is None:
            from gongsynth.sun.photosphere import synthesize

            pointing = Pointing(config.latitude, config.obstime)
            stokes = synthesize(_photosphere(config), mu=pointing.mu, los_azimuth=pointing.los_azimuth,
                                instrument=inst)
            lap("synthesis")
        else:
            Pointing(config.latitude, config.obstime).check_mu(stokes.mu)
        channels = polarimetry.channel_images(stokes, instrument=inst)
        lap("filters")
        light, truth_scene = scene_mod.tiled_scenes(
            channels, stokes.blos, stokes.pixel_size, pointing=Pointing(config.latitude, config.obstime),
            detector_shape=config.detector_pixels,
            resolutions=config.resolutions, instrument=inst)
        lap("scene")

    counts = optics.expected_counts(light, inst, workers=config.workers)
    truth, truth_psf = None, None
    if truth_scene is not None:
        truth = optics.observe(truth_scene.data, truth_scene.pixel_scale, instrument=inst,
                               psf=False, boundary=truth_scene.boundary)
        truth_psf = optics.observe(truth_scene.data, truth_scene.pixel_scale, instrument=inst,
                                   boundary=truth_scene.boundary, workers=config.workers)
    lap("optics")

    raw = camera.integrate(counts, duration=config.duration, engine=config.engine,
                           seed=child_sequence(config.seed, "camera"), instrument=inst, flat=flat,
                           dark=dark, workers=config.workers, progress=progress)
    lap("camera")
    observed = reduce(raw, inst)
    # Where no sunlight falls (beyond the limb) the phases are noise: blank them
    # as real full-disk magnetograms do.  The continuum keeps its sky values.
    light_total = counts.sum(axis=0).value
    sky = light_total < 1e-3 * light_total.max()
    magnetogram, doppler = _blank(observed.magnetogram, sky), _blank(observed.doppler, sky)
    truth, truth_psf = _blank(truth, sky), _blank(truth_psf, sky)
    lap("reduction")

    centre = light.centre
    extra = _run_header(config)
    products = dict(
        magnetogram=make_product_map(magnetogram, centre=centre, scale=inst.plate_scale,
                                     product="magnetogram", extra=extra),
        doppler=make_product_map(doppler, centre=centre, scale=inst.plate_scale,
                                 product="doppler", extra=extra),
        continuum=make_product_map(observed.continuum, centre=centre, scale=inst.plate_scale,
                                   product="continuum", extra=extra),
        truth=None if truth is None else make_product_map(
            truth, centre=centre, scale=inst.plate_scale, product="truth",
            extra={**extra, "truthpsf": False}),
        truth_psf=None if truth_psf is None else make_product_map(
            truth_psf, centre=centre, scale=inst.plate_scale, product="truth",
            extra={**extra, "truthpsf": True}),
    )
    lap("maps")
    bar.close()
    return SimulationResult(raw=raw, scene=counts, resolution_map=light.resolution_map(inst),
                            config=config, timings=timings, **products)


def _blank(image, sky):
    """``image`` (a Quantity, or None) with NaN where ``sky`` is True."""
    if image is None:
        return None
    image = u.Quantity(image)
    return np.where(sky, np.nan, image.value) * image.unit


def _photosphere(config):
    from gongsynth.sun.photosphere import model_photosphere

    return model_photosphere(shape=config.photosphere_shape,
                             pixel_size=config.photosphere_pixel_size,
                             seed=child_sequence(config.seed, "photosphere"))


def _run_header(config):
    """Header cards recording the run (instrument parameters go in the saved config)."""
    inst = config.instrument
    return {
        "simlat": (config.latitude.to_value(u.deg), "[deg] field-centre latitude"),
        "simdur": (config.duration.to_value(u.s), "[s] observation length"),
        "engine": (config.engine, "camera engine"),
        "simmode": (config.mode, "scene mode"),
        "seed": (str(config.seed), "root random seed"),
        "seeing": (inst.seeing_fwhm.to_value(u.arcsec), "[arcsec] seeing FWHM"),
        "aeff": (inst.effective_area.to_value(u.cm**2), "[cm2] effective area"),
        "gain": (inst.gain.to_value(u.electron / u.adu), "[e/ADU] gain"),
        "rdnoise": (inst.read_noise.to_value(u.adu), "[ADU] read noise"),
        "landeg": (inst.lande_g.to_value(u.one), "Lande factor used in the inversion"),
        "v0": (inst.v0.to_value(u.m / u.s / u.rad), "[m/s/rad] Michelson velocity scale"),
    }


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
    list of `SimulationResult`
        In the order of the runs; identical to running `simulate` on each
        configuration serially.

    Examples
    --------
    >>> import astropy.units as u
    >>> runs = simulate_many(latitudes=[0, 45] * u.deg, seed=2, detector_shape=16,
    ...                      duration=1 * u.min, resolutions=(1,), photosphere_shape=(64, 64),
    ...                      photosphere_pixel_size=1536 * u.km, progress=False)
    >>> [float(r.config.latitude.value) for r in runs], runs[0].config.seed == runs[1].config.seed
    ([0.0, 45.0], True)
    """
    from tqdm.auto import tqdm

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

    if client is None and (workers is None or workers <= 1):
        return [simulate(config=c, progress=False) for c in tqdm(configs, disable=not progress,
                                                                 desc="sweep")]
    from dask.distributed import Client, LocalCluster, as_completed

    own = client is None
    if own:
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    try:
        futures = [client.submit(simulate, config=c, progress=False, pure=False) for c in configs]
        bar = tqdm(total=len(futures), disable=not progress, desc="sweep")
        for _ in as_completed(futures):
            bar.update()
        bar.close()
        return client.gather(futures)
    finally:
        if own:
            client.close()
            cluster.close()


def _config_kwargs(kwargs):
    allowed = {"duration", "engine", "seed", "instrument", "mode", "detector_shape", "resolutions",
               "obstime", "workers", "photosphere_shape", "photosphere_pixel_size"}
    bad = set(kwargs) - allowed
    if bad:
        raise TypeError(f"unknown simulate_many argument(s) {sorted(bad)}")
    return kwargs
