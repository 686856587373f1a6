"""
The simulation as data: an ordered chain of named stages built from a run's configuration.

`build_chain` turns a `~gongsynth.config.SimulationConfig` into a `Chain`: a list
of `Stage` objects, each with a name, the quantities it reads and writes, and a
function that computes them.  `gongsynth.simulate` runs the whole chain; a user
(or a test) can run it up to any stage, look at what each stage made, or swap
a stage for their own:

>>> import astropy.units as u
>>> from gongsynth.config import SimulationConfig
>>> config = SimulationConfig(seed=1, detector_shape=16, resolutions=(1,), duration=1 * u.min,
...                           photosphere_shape=(64, 64), photosphere_pixel_size=1536 * u.km,
...                           sun="milne-eddington")
>>> chain = build_chain(config)
>>> chain.names
('photosphere', 'synthesis', 'channels', 'scene', 'optics', 'camera', 'reduction', 'maps')
>>> state = chain.run(until="synthesis", progress=False)
>>> state["stokes"].shape
(64, 64, 51)

Random streams are derived from the run's seed and the *stage name* only
(`gongsynth.seeding.child_sequence`), so a stage draws the same numbers
whatever ran before it, and a chain run in pieces gives the same bits as one
run in one go.  The instrument's physical effects that can be switched off
(PSF, seeing, flat, dark, photon noise, read noise, dither, truncation) are the
config's ``effects`` (TOML ``[effects]``), passed to the stages that hold them.
"""
import dataclasses
import sys
import time
from dataclasses import dataclass

import astropy.units as u
import numpy as np
from sunpy import log

from gongsynth import instruments, precompile
from gongsynth.geometry import Pointing, as_obstime, disk_geometry
from gongsynth.instruments.gong.header_counts import count_scale
from gongsynth.instruments.gong.ucor import from_camera, to_camera
from gongsynth.observing import site_location
from gongsynth.products.maps import PRODUCTS, make_product_map
from gongsynth.seeding import child_sequence
from gongsynth.stages import optics
from gongsynth.stages.averaging import average_observables, minutes_in, sum_planes
from gongsynth.stages.camera.integrate import integrate
from gongsynth.stages.channels import channel_images
from gongsynth.stages.psf import seeing_profile
from gongsynth.stages.reduction import BAND_PIXELS, reduce
from gongsynth.stages.scene.fulldisk import full_disk_scene
from gongsynth.stages.scene.library import LIBRARY_SEED, cached_library
from gongsynth.stages.scene.tiled import tiled_scenes
from gongsynth.stages.seeing import SeeingPlanes, frame_motion
from gongsynth.sun.atmosphere import Atmosphere
from gongsynth.sun.model_atmosphere import model_sun
from gongsynth.sun.model_atmosphere.transfer import DeferredTransfer
from gongsynth.sun.photosphere import DeferredStokes
from gongsynth.sun.rt.synthesis import synthesize as rt_synthesize
from gongsynth.sun.sampling import check_spectral_sampling
from gongsynth.suns import SUNS

__all__ = ["Stage", "Chain", "build_chain", "interactive", "run_header", "unmeasured", "large_scale_field",
           "line_of", "DEFAULT_RT_LINE", "SKY_FRACTION"]

#: A pixel whose light is below this fraction of the brightest pixel's is too
#: faint for a phase: every product is blanked there (see `unmeasured`).
SKY_FRACTION = 1e-3


@dataclass(frozen=True)
class Stage:
    """
    One step of the simulation.

    Parameters
    ----------
    name : str
        The stage's name (also the name of its random stream).
    inputs : tuple of str
        Names of the quantities it reads from the chain's state.
    outputs : tuple of str
        Names of the quantities it adds to the state.
    compute : callable
        ``compute(**inputs) -> dict`` of the outputs.
    description : str
        One line for listings and progress messages.
    """

    name: str
    inputs: tuple
    outputs: tuple
    compute: object
    description: str = ""

    def __call__(self, state):
        """
        Run the stage on ``state`` (a dict) and add its outputs to it.

        Parameters
        ----------
        state : dict

        Returns
        -------
        dict
            The same ``state``, with this stage's outputs added.
        """
        missing = [name for name in self.inputs if name not in state]
        if missing:
            raise KeyError(f"stage {self.name!r} needs {missing}, which no earlier stage made")
        made = self.compute(**{name: state[name] for name in self.inputs})
        unexpected = set(made) ^ set(self.outputs)
        if unexpected:
            raise RuntimeError(f"stage {self.name!r} made {sorted(made)}, promised {list(self.outputs)}")
        state.update(made)
        return state


class Chain(list):
    """
    An ordered list of `Stage` objects; `run` executes them in order.

    Examples
    --------
    >>> chain = Chain([Stage("double", ("x",), ("y",), lambda x: {"y": 2 * x})])
    >>> chain.run({"x": 3}, progress=False)["y"]
    6
    """

    @property
    def names(self):
        """The stage names, in order."""
        return tuple(stage.name for stage in self)

    def __getitem__(self, key):
        if isinstance(key, str):
            for stage in self:
                if stage.name == key:
                    return stage
            raise KeyError(f"no stage named {key!r}; the chain has {self.names}")
        return super().__getitem__(key)

    def run(self, state=None, *, until=None, progress=True, timings=None, keep=None):
        """
        Run the stages in order.

        Parameters
        ----------
        state : dict, optional
            Quantities already known (e.g. a user's Stokes cube); default empty.
        until : str, optional
            Stop after this stage.
        progress : bool
            Show a progress bar over the stages.
        timings : dict, optional
            Filled with each stage's wall-clock seconds.
        keep : iterable of str, optional
            Keep only these quantities to the end: any other is released as
            soon as no later stage needs it (a full disk's 8192² truth scene,
            for one).  Default: keep everything.

        Returns
        -------
        dict
            The state: every quantity any stage made (or those in ``keep``).
        """
        from tqdm.auto import tqdm

        state = {} if state is None else state
        stop = len(self) if until is None else self.names.index(self[until].name) + 1
        # A bar on a terminal; plain one-line messages where the output is a log file.
        bar = tqdm(total=stop, disable=not (progress and interactive()), unit="stage", desc="gongsynth",
                   bar_format="{desc:<28s}{bar}| {n_fmt}/{total_fmt} [{elapsed}]")
        stages = self[:stop]
        # The last stage (index) that reads each quantity: after it, it may go.
        last_use = {name: index for index, stage in enumerate(stages) for name in stage.inputs}
        try:
            for number, stage in enumerate(stages, 1):
                bar.set_description_str(f"gongsynth: {stage.name}")
                if progress and bar.disable:
                    log.info(f"gongsynth: stage {number}/{stop} {stage.name}: {stage.description}")
                start = time.perf_counter()
                precompile.wait(stage.name, progress=progress)   # a first run: the kernels it needs
                stage(state)
                seconds = time.perf_counter() - start
                log.debug(f"gongsynth: stage {stage.name} took {seconds:.2f} s")
                if timings is not None:
                    timings[stage.name] = seconds
                if keep is not None:
                    for name in [n for n in state if n not in keep and last_use.get(n, -1) < number]:
                        del state[name]
                bar.update(1)
        finally:
            bar.close()
        return state

    def __repr__(self):
        rows = [f"{i}. {s.name}: {', '.join(s.inputs) or '-'} -> {', '.join(s.outputs)}"
                for i, s in enumerate(self, 1)]
        return "Chain(\n  " + "\n  ".join(rows) + "\n)"


def interactive():
    """
    Whether progress bars can be drawn: standard error is a terminal.

    Returns
    -------
    bool
    """
    return sys.stderr.isatty()


def build_chain(config, *, stokes=None, flat=None, dark=None, progress=False, surface_field=None):
    """
    The stages of one run, in order, for ``config``.

    Parameters
    ----------
    config : `~gongsynth.config.SimulationConfig`
    stokes : `~gongsynth.StokesCube` or `~gongsynth.Atmosphere`, optional
        Input spectra (their μ must match the latitude, their wavelengths cover
        what the channels need), or a model atmosphere synthesised by
        `gongsynth.rt.synthesize` at the pointing's μ and azimuth: replaces the
        built-in photosphere and its synthesis (tiled mode only).
    flat, dark : optional
        Detector flat and dark (see `gongsynth.stages.camera.integrate.integrate`);
        default the instrument's synthetic ones.
    progress : bool
        Progress bars inside long stages (only drawn on a terminal).
    surface_field : `sunpy.map.GenericMap`, optional
        Full-disk mode: the large-scale radial field (``config.surface_field``
        names where it came from); None: the quiet Sun.

    Returns
    -------
    `Chain`
    """
    verbose, progress = progress, progress and interactive()
    # Resolved once for every stage: the instrument object and the pointing with its Time.
    inst = instruments.get(config.instrument)
    pointing = Pointing(config.latitude, config.obstime)
    effects = config.effects
    for name, given in (("flat", flat), ("dark", dark)):
        if given is not None and given is not True and not getattr(effects, name):
            raise ValueError(f"a user {name} was given but effects.{name} is off: give one or the other")
    stages = Chain()

    if stokes is None and config.mode == "full-disk":
        def library():
            precompile.wait(progress=verbose)     # a first run's kernels, compiling in the background
            knobs = {k: v for k, v in config.sun_arguments().items() if k not in ("shape", "pixel_size")}
            # The library's own fixed seed: every run seed shares it (and its cache); the
            # run's seed lays the patches out in the scene stage.
            return {"photosphere": cached_library(seed=LIBRARY_SEED, knobs=knobs, instrument=inst,
                                                  sun=config.sun, progress=progress)}

        how = ("the 3-D model atmosphere by LTE radiative transfer" if config.sun == "model-atmosphere"
               else "Milne-Eddington columns")
        stages.append(Stage("photosphere", (), ("photosphere",), library,
                            f"the built-in Sun's patch library: quiet to sunspot, {how}, at a set of angles"))
    elif stokes is None:
        # The 3-D Sun as its whole-plane parts, assembled a block of rows at a time by the synthesis.
        build = model_sun if config.sun == "model-atmosphere" else SUNS[config.sun]

        def photosphere():
            return {"photosphere": build(seed=child_sequence(config.seed, "photosphere"),
                                         **config.sun_arguments())}

        what = "3-D model atmosphere" if config.sun == "model-atmosphere" else "model photosphere"
        stages.append(Stage("photosphere", (), ("photosphere",), photosphere,
                            f"the built-in {what} (seeded)"))
    elif config.mode == "full-disk":
        raise ValueError("mode='full-disk' synthesises the built-in photosphere at every point's own "
                         "viewing angle; it does not take a Stokes cube or an atmosphere")

    if config.mode == "full-disk":
        def disk_scene(photosphere):
            light, truth = full_disk_scene(photosphere, detector_shape=config.detector_pixels,
                                           obstime=pointing.obstime, instrument=inst, progress=progress,
                                           surface_field=large_scale_field(config, surface_field,
                                                                           obstime=pointing.obstime),
                                           seed=child_sequence(config.seed, "scene"),
                                           site=site_location(config.site), pointing=config.pointing,
                                           network=_network(config))
            return {"light": light, "truth_scene": truth}

        stages.append(Stage("scene", ("photosphere",), ("light", "truth_scene"), disk_scene,
                            "the large-scale field filled with the library's small scales, rotation and "
                            "the observer's motion in the spectra"))
    else:
        if stokes is None and config.sun == "model-atmosphere":
            def atmosphere_transfer(photosphere):
                precompile.wait(progress=verbose)
                # Deferred: the channels stage assembles and synthesises it block by block, never whole.
                return {"stokes": DeferredTransfer(photosphere, mu=pointing.mu, azimuth=pointing.los_azimuth,
                                                   progress=progress, **line_of(inst))}

            stages.append(Stage("synthesis", ("photosphere",), ("stokes",), atmosphere_transfer,
                                "LTE Stokes radiative transfer of the model atmosphere at the pointing's mu "
                                "(deferred)"))
        elif stokes is None:
            def synthesis(photosphere):
                # Deferred: the channels stage synthesises it block by block, never whole.
                return {"stokes": DeferredStokes(photosphere, mu=pointing.mu,
                                                 los_azimuth=pointing.los_azimuth, instrument=inst)}

            stages.append(Stage("synthesis", ("photosphere",), ("stokes",), synthesis,
                                "Milne-Eddington Stokes spectra at the pointing's mu (deferred)"))
        elif isinstance(stokes, Atmosphere):
            def radiative_transfer():
                precompile.wait(progress=verbose)
                return {"stokes": rt_synthesize(stokes, mu=pointing.mu, azimuth=pointing.los_azimuth,
                                                progress=progress, **line_of(inst))}

            stages.append(Stage("synthesis", (), ("stokes",), radiative_transfer,
                                "LTE Stokes radiative transfer of the atmosphere at the pointing's mu"))
        else:
            pointing.check_mu(stokes.mu)
            # Before any work: a window too narrow or too coarse for the channel integrals is refused.
            check_spectral_sampling(stokes.wavelength, inst, name="the Stokes cube's wavelength")

            def given():
                return {"stokes": stokes}

            stages.append(Stage("input", (), ("stokes",), given, "the user's Stokes cube"))

        def channels(stokes):
            return {"channels": channel_images(stokes, instrument=inst)}

        def scene(channels, stokes):
            light, truth = tiled_scenes(channels, stokes.blos, stokes.pixel_size, pointing=pointing,
                                        detector_shape=config.detector_pixels,
                                        resolutions=config.resolutions, instrument=inst)
            return {"light": light, "truth_scene": truth}

        stages.append(Stage("channels", ("stokes",), ("channels",), channels,
                            "Mueller matrix and filter weights: spectra -> the instrument's planes "
                            "(block by block)"))
        stages.append(Stage("scene", ("channels", "stokes"), ("light", "truth_scene"), scene,
                            "the planes tiled on the sky at the pointing"))

    def optics_stage(light, truth_scene):
        counts, truth, truth_psf = optics.image_scene(light, truth_scene, inst, psf=effects.psf,
                                                      seeing=effects.seeing, workers=config.workers)
        # The pixels no line is measured in, from the noise-free counts: made here, so that the
        # counts (12 × 4096² for a full-disk HMI run) can go once the camera has drawn from them.
        sky = unmeasured(counts, config, instrument=inst, obstime=pointing.obstime)
        return {"expected_counts": counts, "truth": truth, "truth_psf": truth_psf, "sky": sky}

    def camera(expected_counts):
        # GONG reduces every minute (minute_average); each plane sees its own image motion (frame_seeing).
        minutes = minutes_in(config.duration, inst) if effects.minute_average else 1
        area = None
        if config.like_counts:  # the real file's count level: that observation's effective area
            scale = count_scale(expected_counts, config.like, inst)
            expected_counts, area = expected_counts * scale, inst.effective_area * scale
            log.info(f"like_counts: {config.like} implies an effective area of {area:.4g}")
        if _rotates(effects, inst):  # the camera sees the Sun turned by the rotator; UCOR turns it back
            expected_counts = to_camera(expected_counts, inst)
        seen = None
        if (effects.frame_seeing and effects.psf and effects.seeing and hasattr(inst, "seeing_wind_speed")
                and inst.seeing_fwhm > 0 * u.arcsec and np.ndim(expected_counts) == 3):
            motion = frame_motion(inst.schedule(config.duration), np.shape(expected_counts)[1:], inst,
                                  child_sequence(config.seed, "frame-seeing"), groups=minutes)
            seen = SeeingPlanes(expected_counts, motion, inst)
        raws = []
        for minute in range(minutes):
            planes = expected_counts if seen is None else seen[minute]
            seed = child_sequence(config.seed, "camera", *((minute,) if minutes > 1 else ()))
            raws.append(integrate(planes, duration=config.duration / minutes, engine=config.engine, seed=seed,
                                  instrument=inst, flat=flat if effects.flat else False,
                                  dark=dark if effects.dark else False, photon_noise=effects.photon_noise,
                                  read_noise=effects.read_noise, dither=effects.dither,
                                  truncation=effects.truncation, workers=config.workers, progress=progress))
            if area is not None:
                raws[-1].header["EFFAREA"] = (round(area.to_value(u.cm**2), 5), "[cm2] like file's DIODEs")
            if minute:  # the same synthetic flat and dark every minute: hold one copy
                raws[-1] = dataclasses.replace(raws[-1], flat=raws[0].flat, dark=raws[0].dark)
        return {"raw": raws[0] if minutes == 1 else sum_planes(raws), "raw_minutes": raws}

    def reduction(raw, raw_minutes):
        observables = reduce(raw, inst, workers=config.workers)
        if len(raw_minutes) > 1:
            observables = average_observables((reduce(r, inst, workers=config.workers) for r in raw_minutes),
                                              observables)
        if _rotates(effects, inst):
            # The same linear interpolation every minute: turning the average is turning each minute.
            observables = from_camera(observables, inst)
        return {"observables": observables}

    def maps(observables, sky, truth, truth_psf, light):
        made = {"magnetogram": observables.magnetogram, "doppler": observables.doppler,
                "continuum": observables.continuum, "truth": truth, "truth_psf": truth_psf}
        header = run_header(config)
        products = {}
        for product, image in made.items():
            if image is not None:
                image = _blank(image, sky)
            products[f"{product}_map"] = None if image is None else make_product_map(
                image, centre=light.centre, scale=inst.plate_scale, product=product, instrument=inst,
                duration=config.duration, extra=header)
        return products

    stages.append(Stage("optics", ("light", "truth_scene"), ("expected_counts", "truth", "truth_psf", "sky"),
                        optics_stage, "PSF (aperture and seeing), resampling and binning to pixels; "
                        "the pixels without a measurable line"))
    stages.append(Stage("camera", ("expected_counts",), ("raw", "raw_minutes"), camera,
                        "frame seeing, frames, flat, dark, photon and read noise, dither, truncation "
                        "(minute by minute)"))
    stages.append(Stage("reduction", ("raw", "raw_minutes"), ("observables",),
                        reduction, "dark, flat, the instrument's algorithm: Doppler, B_LOS, continuum "
                        "(minutes averaged)"))
    stages.append(Stage("maps", ("observables", "sky", "truth", "truth_psf", "light"),
                        tuple(f"{p}_map" for p in PRODUCTS), maps,
                        "sunpy Maps with helioprojective WCS; sky blanked"))
    return stages


def _rotates(effects, instrument):
    """Whether a run turns its images as GONG's reduction does (`gongsynth.instruments.gong.ucor`)."""
    return effects.image_rotation and hasattr(instrument, "image_rotation_angle")


def line_of(instrument):
    """
    The `gongsynth.rt.synthesize` keyword that selects the instrument's line.

    Parameters
    ----------
    instrument : `~gongsynth.instruments.base.Instrument`

    Returns
    -------
    dict
        ``{}`` for the radiative transfer's default line, Ni I 676.8 nm (so a
        GONG run calls it exactly as before), else ``{"line": instrument.line}``
        (the key of its line registry).
    """
    return {} if instrument.line == DEFAULT_RT_LINE else {"line": instrument.line}


def _network(config):
    """The full disk's supergranular network (stream ``"network"`` of the run's seed), or None."""
    if not config.network_on:
        return None
    from gongsynth.sun.surface_field.network import SupergranularNetwork
    return SupergranularNetwork(seed=child_sequence(config.seed, "network"),
                                chain_length=config.network_chain_length)


#: The radiative transfer's default line (its line registry's key).
DEFAULT_RT_LINE = "Ni I 676.8"


def large_scale_field(config, given=None, *, obstime=None):
    """
    The surface field a full-disk run follows (`gongsynth.sun.surface_field`).

    Parameters
    ----------
    config : `~gongsynth.config.SimulationConfig`
        ``surface_field = "synthetic"``: the seeded synthetic Sun at the run's
        date (stream ``"surface-field"`` of the run's seed); ``"quiet"``: none.
    given : `sunpy.map.GenericMap`, optional
        A map: a gongsynth surface field is used as it is; any other map (a
        full-disk magnetogram, a synoptic map) goes through
        `~gongsynth.sun.surface_field.surface_field_from_map` at the run's date.
    obstime : `~astropy.time.Time`, optional
        The run's date, resolved (default: ``config.obstime``).

    Returns
    -------
    `sunpy.map.GenericMap` or None
        None: the quiet Sun.
    """
    from gongsynth.sun.surface_field import surface_field_from_map, synthetic_surface_field
    from gongsynth.sun.surface_field.maps import check_surface_field
    time = as_obstime(config.obstime if obstime is None else obstime)
    if given is None:
        if config.surface_field == "synthetic":
            return synthetic_surface_field(time, seed=child_sequence(config.seed, "surface-field"))
        return None
    try:
        check_surface_field(given)
        return given
    except ValueError:
        return surface_field_from_map(given, time)


def unmeasured(expected_counts, config, *, instrument=None, obstime=None):
    """
    Detector pixels where the line is not measured, to be blanked in every product.

    Two rules, documented in the guide's reduction page:

    - full-disk runs: every pixel whose centre's line of sight misses the Sun
      (beyond the limb).  Light scattered there by the PSF gives phases, but
      they measure the sky's scattered light, not a line at that place: a
      halo of several hundred G of noise out to 1.05 R☉ otherwise;
    - any run: pixels whose light is below `SKY_FRACTION` of the brightest
      pixel's, too faint for a meaningful phase;
    - any run: pixels whose expected photo-electrons over the whole
      observation are below their own noise (photon and read noise): no
      light reaches them (a prefilter far from the line, say), and the phase
      would be noise, a magnetogram of ±2 kG otherwise.

    A tiled field is a flat tile placed at one latitude (the paper's
    convention), so its pixels are not tested against the limb.

    Parameters
    ----------
    expected_counts : `~astropy.units.Quantity`
        (K, ny, nx) expected electrons per frame.
    config : `~gongsynth.config.SimulationConfig`
    instrument : `~gongsynth.instruments.base.Instrument`, optional
        The run's, resolved (default: ``config.instrument``).
    obstime : `~astropy.time.Time`, optional
        The run's date, resolved (default: ``config.obstime``).

    Returns
    -------
    `numpy.ndarray` of bool
        (ny, nx), True where the products are blanked.
    """
    light = expected_counts.sum(axis=0, dtype=np.float64).value
    inst = instruments.get(config.instrument if instrument is None else instrument)
    frames = int(np.sum(inst.schedule(config.duration).frames_per_plane))
    signal = light / expected_counts.shape[0] * frames          # each frame goes to one of the planes
    read = (inst.read_noise * inst.gain).to_value(u.electron) if config.effects.read_noise else 0.0
    faint = (light < SKY_FRACTION * light.max()) | (signal <= np.sqrt(signal + frames * read**2))
    if config.mode != "full-disk":
        return faint
    # The limb test a band of rows at a time: the whole disk's geometry of a 4096² frame is ~2 GB.
    step = max(1, BAND_PIXELS // light.shape[1])
    for start in range(0, light.shape[0], step):
        rows = slice(start, start + step)
        faint[rows] |= ~disk_geometry(light.shape, inst.plate_scale, rows=rows, pointing=config.pointing,
                                      obstime=config.obstime if obstime is None else obstime).on_disk
    return faint


def run_header(config):
    """
    FITS cards recording the run in every product (the instrument goes in the saved config).

    Parameters
    ----------
    config : `~gongsynth.config.SimulationConfig`

    Returns
    -------
    dict
        Card name to ``(value, comment)``.
    """
    inst = config.instrument
    cards = {
        "simdur": (config.duration.to_value(u.s), "[s] observation length"),
        "engine": (config.engine, "camera engine"),
        "simmode": (config.mode, "scene mode"),
        "seed": (str(config.seed), "root random seed"),
        "seeing": (inst.seeing_fwhm.to_value(u.arcsec), "[arcsec] seeing FWHM"),
        **({"seeprof": (seeing_profile(inst), "seeing profile")}      # only where not the paper's Gaussian
           if seeing_profile(inst) != "gaussian" else {}),
        "aeff": (inst.effective_area.to_value(u.cm**2), "[cm2] effective area"),
        "gain": (inst.gain.to_value(u.electron / u.adu), "[e/ADU] gain"),
        "rdnoise": (inst.read_noise.to_value(u.adu), "[ADU] read noise"),
        **inst.header_cards(),   # the instrument's own inversion constants (GONG: Lande factor, v0)
    }
    if config.mode == "tiled":  # a full-disk scene has no single field-centre latitude
        cards = {"simlat": (config.latitude.to_value(u.deg), "[deg] field-centre latitude"), **cards}
    elif config.network_on:
        cards["netchain"] = (config.network_chain_length.to_value(u.Mm), "[Mm] network chain sigma")
    return cards


def _blank(image, sky):
    """``image`` (a Quantity, or None) with NaN where ``sky`` is True."""
    if image is None:
        return None
    image = u.Quantity(image)
    return u.Quantity(np.where(sky, np.nan, image.value), image.unit, copy=False)   # one 4096² copy, not two
