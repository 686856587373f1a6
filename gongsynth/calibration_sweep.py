"""
Building a calibration table by simulation: the latitude sweep behind `gongsynth.calibrate`.

This is run-layer work (it runs the whole chain), so it sits beside
`gongsynth.pipeline`; the table format and its use live in
`gongsynth.analysis.calibration_table`.
"""
import datetime
import math

import astropy.units as u

from gongsynth.analysis.calibration_table import TABLE_LATITUDES, calibration_table
from gongsynth.analysis.weak_flux import weak_flux_factor
from gongsynth.config import SimulationConfig
from gongsynth.geometry import Pointing
from gongsynth.run_cache import cached_runs, run_config
from gongsynth.version import git_commit
from gongsynth.version import version as __version__

__all__ = ["PRESETS", "build_calibration_table", "sweep_configs"]

#: Instrument changes of each preset.  "paper": the authors' code convolves
#: with exp(-r²/2 (1.8″)²), which they call "width 3.6″" but whose FWHM is
#: 2√(2 ln 2) × 1.8″ = 4.24″; gongsynth's default ("default") takes the
#: paper's text, a 3.6″ FWHM.
PRESETS = {
    "default": {},
    "paper": {"seeing_fwhm": 2 * math.sqrt(2 * math.log(2)) * 1.8 * u.arcsec},
}


def _seed_factor(run, region):
    """One seed's own factor; NaN where its pixels alone are too few for the bins (not in the scatter)."""
    try:
        return weak_flux_factor(run, region=region, n_boot=0).factor
    except ValueError:
        return math.nan


def sweep_configs(latitudes=TABLE_LATITUDES, seeds=(1, 2), *, config=None, preset="default",
                  **simulate_kwargs):
    """
    The runs of a sweep, latitude by latitude and seed by seed (as `build_calibration_table` runs them).

    Parameters
    ----------
    latitudes, seeds, config, preset, **simulate_kwargs
        As for `build_calibration_table`.

    Returns
    -------
    list of `~gongsynth.config.SimulationConfig`
        ``len(latitudes) * len(seeds)`` configurations; with
        `gongsynth.run_cache.entry_path` they say which runs a cache holds.
    """
    latitudes = u.Quantity(latitudes, u.deg).ravel()
    seeds = [int(s) for s in seeds]
    if not seeds:
        raise ValueError("seeds must name at least one seed")
    if config is None:
        config = SimulationConfig.from_arguments(**simulate_kwargs)
    elif simulate_kwargs:
        raise TypeError(f"pass either config or simulate() arguments, not both: {sorted(simulate_kwargs)}")
    if preset not in PRESETS:
        raise ValueError(f"preset must be one of {sorted(PRESETS)}, got {preset!r}")
    if PRESETS[preset]:
        config = config.replace(instrument=config.instrument.replace(**PRESETS[preset]))
    return [config.replace(latitude=latitude, seed=seed) for latitude in latitudes for seed in seeds]


def _fit_latitude(runs, regions, n_boot):
    """The pooled fit of each region over the runs (one per seed), and each seed's own factor."""
    fits, per_seed = [], []
    for region in regions:
        fits.append(weak_flux_factor(runs, region=region, n_boot=n_boot))
        if len(runs) > 1:
            per_seed.append([_seed_factor(run, region) for run in runs])
        else:
            per_seed.append([fits[-1].factor])
    return fits, per_seed


def build_calibration_table(latitudes=TABLE_LATITUDES, seeds=(1, 2), *, regions=("quiet", "sunspot"),
                            config=None, preset="default", n_boot=50, client=None, workers=None,
                            cache=None, progress=True, input_sun=None, **simulate_kwargs):
    """
    Simulate a latitude sweep and tabulate the papers' calibration curves and weak-flux factors.

    Each latitude is simulated once per seed, each run one task
    (`gongsynth.run_cache.cached_runs`: serially, or on any Dask cluster) that
    keeps only the maps the fit needs; the seeds' pixels are pooled into one
    flux-conserving fit per region (`gongsynth.analysis.weak_flux.weak_flux_factor`),
    which gives the factor and the curve; each seed is also fitted alone, and
    the factor's statistical uncertainty combines the seeds' scatter with the
    pooled fit's block bootstrap
    (`gongsynth.analysis.calibration_table.seed_uncertainty`).  A latitude
    is fitted as soon as its runs are in, and they are dropped.  With
    ``cache``, every finished run is kept on disk, so a build that was
    interrupted (or lost a worker, or had a run fail) and is started again
    simulates only what is missing; the table is the same bits whatever the
    number of workers, the order the runs finish in, or the restarts.

    Parameters
    ----------
    latitudes : `~astropy.units.Quantity`
        Viewing latitudes (default the papers' 0, 25, 45, 60, 70, 75°).
    seeds : sequence of int
        Root seeds; every latitude runs with every seed.
    regions : sequence of {"quiet", "sunspot"}
        The curves to fit.
    config : `~gongsynth.config.SimulationConfig`, optional
        Base configuration (its latitude and seed are replaced); default built
        from ``simulate_kwargs``.
    preset : {"default", "paper"}
        Instrument changes applied to the configuration (see `PRESETS`):
        ``"paper"`` uses the authors' seeing kernel (4.24″ FWHM).
    n_boot : int
        Bootstrap resamples per fit.
    client : `dask.distributed.Client`, optional
        Run the simulations on this Dask cluster (a ``LocalCluster``, or an
        HPC scheduler's through ``dask_jobqueue``); the table is the same.
    workers : int, optional
        Without a client: a local Dask cluster of this many processes
        (``None`` or 1: serial, no Dask needed).
    cache : path-like, optional
        Folder of finished runs (one FITS file each, named by a hash of the
        run's full configuration and the gongsynth version; see
        `gongsynth.run_cache`); on a cluster, one every worker can write.
    progress : bool
        A progress bar over the runs (tqdm).
    input_sun : str, optional
        Description of the input Sun for the metadata; default the built-in photosphere.
    **simulate_kwargs
        `gongsynth.simulate` arguments for the base configuration.

    Returns
    -------
    `~astropy.table.QTable`
        See `gongsynth.analysis.calibration_table.calibration_table`; the
        metadata records the gongsynth version and git commit, input Sun,
        grid (columns and their size), seeds, estimators, instrument, run
        configuration and date.  The ``systematic`` column is added by
        `gongsynth.analysis.calibration_table.add_systematic`.

    Examples
    --------
    >>> import astropy.units as u
    >>> table = build_calibration_table([0] * u.deg, seeds=[1], regions=["quiet"], n_boot=5,
    ...                                 detector_shape=96, duration=1 * u.min, sun="milne-eddington",
    ...                                 progress=False)
    >>> len(table), table.meta["seeds"]
    (1, [1])
    """
    latitudes = u.Quantity(latitudes, u.deg).ravel()
    seeds = [int(s) for s in seeds]
    for region in regions:
        if region not in ("quiet", "sunspot"):
            raise ValueError(f"regions must be 'quiet' or 'sunspot', got {region!r}")
    configs = sweep_configs(latitudes, seeds, config=config, preset=preset, **simulate_kwargs)
    config = configs[0]
    # Each latitude is fitted as soon as all its seeds are in, and its runs dropped: the
    # fits do not depend on the order the runs finish in.
    pending = [dict() for _ in latitudes]
    fits = [None] * latitudes.size
    per_seed = [None] * latitudes.size
    for index, run in cached_runs(configs, cache=cache, client=client, workers=workers, progress=progress,
                                  desc="calibration table"):
        group = pending[index // len(seeds)]
        group[index % len(seeds)] = run
        if len(group) == len(seeds):
            runs = [group.pop(k) for k in range(len(seeds))]
            fits[index // len(seeds)], per_seed[index // len(seeds)] = _fit_latitude(runs, regions, n_boot)
    mu = [Pointing(latitude, config.obstime).mu for latitude in latitudes for _ in regions]
    return calibration_table([fit for group in fits for fit in group], mu=mu,
                             per_seed=[factors for group in per_seed for factors in group], metadata={
        "gongsynth_version": __version__,
        "git_commit": git_commit(),
        "input_sun": input_sun or (f"built-in Sun {config.sun!r} ({config.photosphere_shape[0]}^2 columns of "
                                   f"{config.photosphere_pixel_size})"),
        "grid": {"columns": list(config.photosphere_shape),
                 "column_size": str(config.photosphere_pixel_size)},
        "seeds": seeds,
        "n_boot": int(n_boot),
        "instrument_name": config.instrument.name,
        "preset": preset,
        "estimator": "papers II/III: flux-conserving piecewise-linear truth = g(measured), "
                     "sign-symmetrised, weak-flux factor = dg/dmeasured at 0, fitted to the seeds' pixels "
                     "pooled",
        "instrument": {k: str(v) for k, v in config.instrument.to_dict().items()},
        "config": run_config(config).to_toml(),
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
    })
