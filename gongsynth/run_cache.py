"""
A resumable, distributed run of many simulations: one task per run, its products cached on disk.

The table sweeps (`gongsynth.calibration_sweep`, `gongsynth.cross_calibration_sweep`)
need only a few maps of each run: the magnetogram, its ground truth (pixel-averaged and
through the PSF), the continuum (the weak-flux fit's sunspot mask) and the tile
magnification of each pixel.  `cached_runs` runs every configuration as one task (in
this process, or on any `dask.distributed` client), keeps only those maps, and writes
them as one FITS file per run, named by a hash of the run's full configuration and the
gongsynth version (`run_key`).  The file is written by the task itself, to a temporary
name that is renamed into place when complete (`gongsynth.files.atomic_path`), so an
entry is complete or absent: a rerun after an interruption, a lost worker or a failed
run simulates only what is missing.

The products travel from the task to the caller as the bytes of that very file, and are
read back from them whether they come from the cache or were just computed: a table
built from them is the same bits whatever the number of workers, the order in which
runs finish, or how many restarts it took (each run's result depends on its
configuration and seed only, design §5).  One condition: the thread count.
scipy.fft (its ducc backend) batches the one-dimensional transforms of an image
differently with one thread than with several, so a run's last bits depend on
how many threads its transforms used (``config.workers``; None: every core the
process may use, and a Dask worker's environment allows one).  `cached_runs`
therefore runs a configuration that leaves ``workers`` unset with
``RUN_THREADS`` threads, on every machine: the parallelism of a sweep is across
its runs.
"""
import hashlib
import io
import warnings
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import astropy.units as u
import numpy as np
import sunpy.map
import tomlkit
from astropy.io import fits

from gongsynth.config import SimulationConfig
from gongsynth.files import atomic_path
from gongsynth.pipeline import simulate, simulate_each
from gongsynth.version import version as __version__

__all__ = ["RUN_MAPS", "RUN_THREADS", "INERT_KNOBS", "CachedRun", "run_config", "run_key", "entry_path",
           "run_entry", "read_entry", "cached_runs"]

#: The maps of a run that a cache entry keeps (`~gongsynth.pipeline.SimulationResult` attributes).
RUN_MAPS = ("magnetogram", "continuum", "truth", "truth_psf")

#: Threads of a run whose configuration leaves ``workers`` unset (see the module notes).
RUN_THREADS = 1

#: Sun knobs (``[photosphere]``) added after runs were cached, with the value at which each leaves a
#: run's output as it was before it existed, and the knobs that act only through it: the tiled 3-D
#: Sun's supergranular network (off by default) and its cell size.  `run_key` leaves them out at that
#: value, so runs cached before the switch existed keep their keys.
INERT_KNOBS = {"network": (False, ("supergranule_size",))}

#: FITS structure keywords of an extension, dropped from a map's metadata when it is read back.
_STRUCTURE = ("XTENSION", "PCOUNT", "GCOUNT", "EXTNAME")


@dataclass(repr=False)
class CachedRun:
    """
    The products of one run that a table needs, as cached (a light `~gongsynth.pipeline.SimulationResult`).

    It has the attributes `gongsynth.analysis.weak_flux.weak_flux_factor` reads,
    so a list of them stands in for the full results.

    Attributes
    ----------
    magnetogram, continuum, truth, truth_psf : `~sunpy.map.GenericMap`
        As in `~gongsynth.pipeline.SimulationResult`, in float64.
    resolution_map : `numpy.ndarray`
        Tile magnification of each detector pixel.
    config : `~gongsynth.config.SimulationConfig`
        The run's configuration.
    """

    magnetogram: object
    continuum: object
    truth: object
    truth_psf: object
    resolution_map: np.ndarray
    config: SimulationConfig

    def __repr__(self):
        return f"<CachedRun {_describe(self.config)}>"


def run_config(config):
    """
    The configuration a sweep runs: ``config`` with `RUN_THREADS` threads if it leaves ``workers`` unset.

    Parameters
    ----------
    config : `~gongsynth.config.SimulationConfig`

    Returns
    -------
    `~gongsynth.config.SimulationConfig`

    Examples
    --------
    >>> from gongsynth.config import SimulationConfig
    >>> run_config(SimulationConfig()).workers, run_config(SimulationConfig(workers=4)).workers
    (1, 4)
    """
    return config if config.workers is not None else config.replace(workers=RUN_THREADS)


def run_key(config):
    """
    The cache key of a run: a hash of its full configuration (`run_config`'s) and of the gongsynth version.

    Parameters
    ----------
    config : `~gongsynth.config.SimulationConfig`

    Returns
    -------
    str
        20 hex digits.

    Examples
    --------
    >>> import astropy.units as u
    >>> from gongsynth.config import SimulationConfig
    >>> base = SimulationConfig(seed=1)
    >>> run_key(base) == run_key(SimulationConfig(seed=1)), run_key(base) == run_key(base.replace(seed=2))
    (True, False)
    """
    text = f"gongsynth {__version__}\n{_keyed(run_config(config).to_toml(comments=False))}"
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def _keyed(toml):
    """A run's configuration TOML without the `INERT_KNOBS` at their inert values (what identifies a run)."""
    document = tomlkit.parse(toml)
    knobs = document.get("photosphere", {})
    for name, (inert, dependents) in INERT_KNOBS.items():
        if name in knobs and knobs[name] == inert:
            for key in (name, *dependents):
                knobs.pop(key, None)
    return tomlkit.dumps(document)


def entry_path(folder, config):
    """
    The file of a run in a cache folder (named for people by instrument, latitude and seed, and by `run_key`).

    Parameters
    ----------
    folder : path-like
    config : `~gongsynth.config.SimulationConfig`

    Returns
    -------
    `pathlib.Path`
    """
    return Path(folder) / (f"{config.instrument.name}_lat{config.latitude.to_value(u.deg):g}_"
                           f"seed{config.seed}_{run_key(config)}.fits")


def run_entry(config, folder=None):
    """
    Simulate one run and return its cache entry, writing it into ``folder`` first if given (the task).

    Parameters
    ----------
    config : `~gongsynth.config.SimulationConfig`
        The run (as `run_config` makes it).
    folder : path-like, optional
        Cache folder (on a cluster: one every worker can write).

    Returns
    -------
    bytes
        The entry: a FITS file (see `read_entry`).
    """
    config = run_config(config)
    result = simulate(config=config, progress=False)
    missing = [name for name in RUN_MAPS if getattr(result, name) is None]
    if missing:
        raise ValueError(f"the run has no {missing} (a sweep needs the ground truth: a built-in Sun)")
    primary = fits.PrimaryHDU()
    primary.header["GSKEY"] = (run_key(config), "hash of configuration and version")
    primary.header["GSVERS"] = (__version__, "gongsynth version")
    text = config.to_toml(comments=False)
    hdus = [primary, fits.ImageHDU(np.frombuffer(text.encode(), np.uint8), name="CONFIG")]
    for name in RUN_MAPS:
        smap = getattr(result, name)
        # float64: what is read back is what the table is built from, whatever the maps' own dtype.
        hdus.append(fits.ImageHDU(np.asarray(smap.data, np.float64), header=smap.fits_header, name=name))
    hdus.append(fits.ImageHDU(np.asarray(result.resolution_map, np.float64), name="RESOLUTION"))
    buffer = io.BytesIO()
    fits.HDUList(hdus).writeto(buffer)
    entry = buffer.getvalue()
    if folder is not None:
        # Replacing is safe: two tasks of one configuration (a retried task) write the same bytes.
        with atomic_path(entry_path(folder, config), overwrite=True) as tmp:
            tmp.write_bytes(entry)
    return entry


def read_entry(entry, config):
    """
    The run a cache entry holds, checked against the configuration it should belong to.

    Parameters
    ----------
    entry : bytes or path-like
        What `run_entry` returned or wrote.
    config : `~gongsynth.config.SimulationConfig`

    Returns
    -------
    `CachedRun`

    Raises
    ------
    ValueError
        If the entry is not a complete entry of ``config`` by this gongsynth version.
    """
    data = entry if isinstance(entry, bytes) else Path(entry).read_bytes()
    try:
        with warnings.catch_warnings():
            # astropy only warns about a truncated or damaged file: here that makes it no entry.
            warnings.simplefilter("error")
            with fits.open(io.BytesIO(data)) as hdus:
                stored = _keyed(hdus["CONFIG"].data.tobytes().decode())
                expected = _keyed(run_config(config).to_toml(comments=False))
                if hdus[0].header.get("GSVERS") != __version__ or stored != expected:
                    raise ValueError("it belongs to another configuration or gongsynth version")
                planes = {name: (hdus[name].data.astype(np.float64), hdus[name].header.copy())
                          for name in (*RUN_MAPS, "RESOLUTION")}
    except (OSError, KeyError, TypeError, ValueError, UnicodeDecodeError, Warning) as exc:
        raise ValueError(f"not a cache entry of run {_describe(config)}: {exc}") from exc
    maps = {}
    for name in RUN_MAPS:
        array, header = planes[name]
        for keyword in _STRUCTURE:
            header.remove(keyword, ignore_missing=True)
        maps[name] = sunpy.map.Map(array, header)
    return CachedRun(resolution_map=planes["RESOLUTION"][0], config=config, **maps)


def cached_runs(configs, *, cache=None, client=None, workers=None, progress=True, desc="runs"):
    """
    Run configurations (those not cached yet), one task each, and yield each run's products as it is ready.

    Runs already in ``cache`` are yielded first, without simulating; the
    others run on ``client`` (or serially) and are written into ``cache`` by
    their task as each finishes.  A run that fails does not stop the others
    (their entries are written, so a rerun does only the failed ones); the
    failure is raised once the rest are done.

    Parameters
    ----------
    configs : sequence of `~gongsynth.config.SimulationConfig`
        The runs; one that leaves ``workers`` unset runs with `RUN_THREADS`
        threads (the same bits on every machine and Dask worker).
    cache : path-like, optional
        Folder of finished runs (`entry_path`); created if needed.  On a
        cluster it must be a folder every worker can write (a shared file
        system).  Without it, nothing is written and everything runs.
    client : `dask.distributed.Client`, optional
        Run the missing runs on this client (any cluster: `dask.distributed.LocalCluster`,
        ``dask_jobqueue``'s HPC schedulers).
    workers : int, optional
        Without a client: a local Dask cluster of this many processes (``None`` or 1: serially).
    progress : bool
        A progress bar over all runs (cached ones count as done at once).
    desc : str
        The progress bar's label.

    Yields
    ------
    (int, `CachedRun`)
        The run's index in ``configs`` and its products (with the configuration
        that ran), in the order they are ready.

    Raises
    ------
    RuntimeError
        After the other runs, if a run failed: naming its configuration (instrument,
        latitude, seed, cache key), chained to the run's own exception.

    Examples
    --------
    >>> import astropy.units as u, tempfile
    >>> from gongsynth.config import SimulationConfig
    >>> config = SimulationConfig(seed=2, detector_shape=16, duration=1 * u.min, resolutions=(1,),
    ...                           photosphere_shape=(64, 64), photosphere_pixel_size=1536 * u.km,
    ...                           sun="milne-eddington")
    >>> folder = tempfile.mkdtemp()
    >>> [(i, run.magnetogram.data.shape) for i, run in cached_runs([config], cache=folder, progress=False)]
    [(0, (16, 16))]
    >>> entry_path(folder, config).exists()
    True
    """
    from tqdm.auto import tqdm

    configs = [run_config(config) for config in configs]
    folder = None if cache is None else Path(cache)
    if folder is not None:
        folder.mkdir(parents=True, exist_ok=True)
    failures = []
    with tqdm(total=len(configs), disable=not progress, desc=desc) as bar:
        todo = []
        for index, config in enumerate(configs):
            run = None if folder is None else _cached(entry_path(folder, config), config)
            if run is None:
                todo.append(index)
            else:
                bar.update()
                yield index, run
        bar.set_postfix(cached=len(configs) - len(todo), refresh=False)
        for position, entry in simulate_each([configs[i] for i in todo], client=client, workers=workers,
                                             progress=False, task=partial(run_entry, folder=folder)):
            index = todo[position]
            bar.update()
            if isinstance(entry, BaseException):
                failures.append((index, entry))
            else:
                yield index, read_entry(entry, configs[index])
    if failures:
        index, exc = min(failures, key=lambda failure: failure[0])
        others = f" ({len(failures) - 1} other run(s) failed too)" if len(failures) > 1 else ""
        kept = f"; the finished runs are cached in {folder}, a rerun does only the rest" if folder else ""
        raise RuntimeError(f"run {index} of the sweep, {_describe(configs[index])}, failed{others}: "
                           f"{type(exc).__name__}: {exc}{kept}") from exc


def _cached(path, config):
    """The run cached at ``path``, or None when there is none (or an unreadable one, with a warning)."""
    if not path.exists():
        return None
    try:
        return read_entry(path, config)
    except ValueError as exc:
        warnings.warn(f"ignoring the cache entry {path} ({exc}): the run is simulated again",
                      stacklevel=3)
        return None


def _describe(config):
    return (f"{config.instrument.name} at latitude {config.latitude.to_value(u.deg):g} deg, "
            f"seed {config.seed} (cache key {run_key(config)})")
