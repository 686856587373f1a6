"""
Building the cross-calibration table by simulation: one Sun through several instruments.

Run-layer work (it runs the whole chain, like `gongsynth.calibration_sweep`);
the comparison of two maps is `gongsynth.analysis.cross_calibration.cross_calibrate`
and the table's format and use live in
`gongsynth.analysis.cross_calibration_table`.

How the instruments are compared (they have different plate scales: GONG
2.5″, HMI 0.504″, MDI 1.986″).  Every instrument observes the same built-in Sun (same
root seed: the same 3-D atmosphere, each instrument's line synthesised from
it) at the same latitude, date and pointing, on a detector covering the same
``field`` of sky (one 1× tile: ``resolutions=(1,)``), each for its default
duration (GONG 10 min, HMI 45 s, MDI 1 min).  Both magnetograms and their ground truths
(the true B_LOS averaged over each detector pixel, design §3.13, without any
PSF: the same quantity for every instrument, decision 19) are then binned,
flux-preserving, onto one grid of square cells of side ``resolution`` on the
sky, anchored at the common field centre, so a cell holds the same patch of
Sun in every map.  On that grid `cross_calibrate` compares each instrument's
magnetogram with the other's (the factor to HMI's scale) and with its truth
(the factor to the truth).
"""
import datetime
import math

import astropy.units as u

from gongsynth import instruments as family
from gongsynth.analysis.calibration_table import TABLE_LATITUDES
from gongsynth.analysis.cross_calibration import DEFAULT_STRENGTH_BINS, cross_calibrate
from gongsynth.analysis.cross_calibration_table import tabulate_cross_calibration
from gongsynth.config import SimulationConfig
from gongsynth.geometry import Pointing
from gongsynth.run_cache import cached_runs, run_config
from gongsynth.version import version as __version__

__all__ = ["CROSS_FIELD", "CROSS_RESOLUTION", "instrument_config", "simulate_instruments",
           "cross_calibration_table"]

#: Side of the sky every instrument's detector covers (about one period of the
#: built-in Sun's 98 Mm box at disk centre, 135″, plus a margin).
CROSS_FIELD = 160 * u.arcsec

#: Side of the common cells: 4 GONG pixels, twice GONG's PSF (FWHM about 5″:
#: seeing 3.6″ with the 6.1″-radius Airy core), so that neighbouring cells are
#: nearly independent and the PSFs move little flux between cells.
CROSS_RESOLUTION = 10 * u.arcsec


def instrument_config(instrument, latitude, seed, *, field=CROSS_FIELD, **simulate_kwargs):
    """
    The run of one instrument in a cross-calibration sweep.

    Parameters
    ----------
    instrument : str or `~gongsynth.instruments.base.Instrument`
    latitude : `~astropy.units.Quantity`
    seed : int
    field : `~astropy.units.Quantity`
        Side of the detector on the sky; the detector gets the even number of
        pixels that covers it.
    **simulate_kwargs
        Further `gongsynth.simulate` arguments (default: the instrument's own
        duration, the default built-in Sun).

    Returns
    -------
    `~gongsynth.config.SimulationConfig`

    Examples
    --------
    >>> import astropy.units as u
    >>> instrument_config("hmi", 0 * u.deg, 1).detector_shape
    318
    >>> instrument_config("gong", 0 * u.deg, 1).detector_shape
    64
    """
    inst = family.get(instrument)
    field = u.Quantity(field, u.arcsec)
    if not (field.isscalar and field.to_value(u.arcsec) > 0):
        raise ValueError(f"field must be a positive angle, got {field}")
    side = 2 * math.ceil(float((field / inst.plate_scale).to_value(u.one)) / 2 - 1e-9)
    return SimulationConfig.from_arguments(instrument=inst, latitude=u.Quantity(latitude, u.deg),
                                           seed=int(seed), detector_shape=side, resolutions=(1,),
                                           **simulate_kwargs)


def simulate_instruments(configs, *, cache=None, client=None, workers=None, progress=True):
    """
    Run configurations and keep only their magnetogram and pixel-averaged truth, cached on disk if asked.

    Parameters
    ----------
    configs : sequence of `~gongsynth.config.SimulationConfig`
    cache : path-like, optional
        Folder of finished runs (`gongsynth.run_cache`: one FITS file each,
        named by a hash of the full configuration and the gongsynth version): a
        rerun after an interruption only simulates what is missing, and gives
        the same bits.
    client : `dask.distributed.Client`, optional
        Run the missing simulations on this client.
    workers : int, optional
        Without a client: a local Dask cluster of this many processes (``None`` or 1: serially).
    progress : bool

    Returns
    -------
    list of (magnetogram, truth)
        sunpy Maps in G (float64), in the order of ``configs``.
    """
    configs = list(configs)
    out = [None] * len(configs)
    for index, run in cached_runs(configs, cache=cache, client=client, workers=workers, progress=progress,
                                  desc="cross-calibration runs"):
        out[index] = (run.magnetogram, run.truth)
    return out


def cross_calibration_table(instruments=("gong", "hmi", "mdi"), latitudes=TABLE_LATITUDES, seeds=(1, 2), *,
                            resolution=CROSS_RESOLUTION, field=CROSS_FIELD,
                            strength_bins=DEFAULT_STRENGTH_BINS, client=None, workers=None, cache=None,
                            progress=True, **simulate_kwargs):
    """
    Simulate one Sun through several instruments and tabulate the factors between them and to the truth.

    For every latitude and seed each instrument observes the same built-in
    Sun (see the module notes for how their different plate scales are
    brought together); on the common grid of cells of side ``resolution``
    `cross_calibrate` gives, for every ordered pair of instruments and for
    each instrument against its truth, the bisector slope (the factor),
    the unsigned-flux ratio and the correlation, over all field strengths
    and in the groups of ``strength_bins``.

    Parameters
    ----------
    instruments : sequence of str or `~gongsynth.instruments.base.Instrument`
        Names of the family (`gongsynth.instruments.names`) or instrument
        objects (e.g. one with parameters changed by ``replace``), at least
        one, of distinct names (the table's ``instrument`` and ``target``).
    latitudes : `~astropy.units.Quantity`
        Viewing latitudes (default the papers' 0, 25, 45, 60, 70, 75°).
    seeds : sequence of int
        Root seeds (the same Sun for every instrument); the factors'
        uncertainties come from their scatter.
    resolution : `~astropy.units.Quantity`
        Side of the common cells (arcsec).
    field : `~astropy.units.Quantity`
        Side of every detector on the sky.
    strength_bins : `~astropy.units.Quantity`
        Field-strength groups (G) of `cross_calibrate`.
    client : `dask.distributed.Client`, optional
        Run the simulations on this client; the table is the same.
    workers : int, optional
        Without a client: a local Dask cluster of this many processes.
    cache : path-like, optional
        Keep each run's maps here (see `simulate_instruments`): a rerun
        simulates only what is missing.
    progress : bool
    **simulate_kwargs
        Further `gongsynth.simulate` arguments for every run (e.g. ``sun``).

    Returns
    -------
    `~astropy.table.QTable`
        See `gongsynth.analysis.cross_calibration_table.tabulate_cross_calibration`.
    """
    instruments = [family.get(instrument) for instrument in instruments]
    names = [instrument.name for instrument in instruments]
    if not names or len(set(names)) != len(names):
        raise ValueError(f"instruments must name distinct instruments of the family, got {instruments!r}")
    latitudes = u.Quantity(latitudes, u.deg).ravel()
    seeds = [int(s) for s in seeds]
    if not seeds or latitudes.size == 0:
        raise ValueError("latitudes and seeds must each hold at least one value")
    configs = [instrument_config(instrument, latitude, seed, field=field, **simulate_kwargs)
               for latitude in latitudes for seed in seeds for instrument in instruments]
    maps = iter(simulate_instruments(configs, cache=cache, client=client, workers=workers,
                                     progress=progress))
    kwargs = dict(resolution=resolution, angle_bins=[0, 90] * u.deg, strength_bins=strength_bins)
    comparisons = []
    for latitude in latitudes:
        mu = Pointing(latitude, configs[0].obstime).mu
        for seed in seeds:
            runs = {name: next(maps) for name in names}
            for source in names:
                magnetogram, truth = runs[source]
                pairs = [(t, runs[t][0]) for t in names if t != source] + [("truth", truth)]
                for target, other in pairs:
                    comparisons.append(dict(latitude=latitude, mu=mu, instrument=source, target=target,
                                            seed=seed, table=cross_calibrate(magnetogram, other, **kwargs)))
    return tabulate_cross_calibration(comparisons, metadata={
        "gongsynth_version": __version__,
        "input_sun": f"built-in Sun {configs[0].sun!r} ({configs[0].photosphere_shape[0]}^2 columns of "
                     f"{configs[0].photosphere_pixel_size})",
        "seeds": seeds,
        "instruments": {c.instrument.name: {"duration": str(c.duration), "detector_shape": c.detector_shape,
                                            "plate_scale": str(c.instrument.plate_scale)}
                        for c in configs[:len(names)]},
        "field": str(u.Quantity(field, u.arcsec)),
        "resolution": str(u.Quantity(resolution, u.arcsec)),
        "method": "each instrument's magnetogram and its pixel-averaged truth (no PSF) binned "
                  "flux-preserving onto common square cells anchored at the field centre; factor = "
                  "OLS-bisector slope of the "
                  "target against the source (target = factor x source; Isobe et al. 1990), mean over seeds; "
                  "uncertainty = standard error of the seeds' scatter",
        "configs": {c.instrument.name: run_config(c).to_toml(comments=False)  # the first runs
                    for c in configs[:len(names)]},
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
    })
