"""
The ``gongsynth`` command line.

::

    gongsynth simulate [--config run.toml] [--latitude 60] [--duration 10] [--engine frames]
                       [--seed 1] [--workers N] [--mode tiled|full-disk] [--shape 256]
                       [--date ISO] [--site BB] [--like GONG.fits] [--pointing TX TY]
                       [--no-psf] [--no-photon-noise] ...
                       [--overwrite] [--quiet]
                       --out DIR
    gongsynth compare SIM.fits OBS.fits [--out FIGURE.png]
    gongsynth calibrate IN.fits --out OUT.fits [--to truth|hmi|mdi|gong] [--instrument NAME]
                        [--table TABLE.ecsv] [--scene angle|distance] [--overwrite] [--open-flux]
    gongsynth config --print-defaults

Exit codes (`EXIT_CODES`; ``gongsynth --help`` lists them with what to do):
0 success, 1 runtime failure (for a sweep: some run failed, the others are
saved), 2 bad usage or bad input (the message names the argument), 3 refusing
to overwrite existing output, 4 the run cannot be done on this machine (more
memory than is available), 130 interrupted, 143 terminated (SIGTERM).
"""
import argparse
import dataclasses
import gc
import math
import signal
import sys
import threading
from pathlib import Path

import astropy.units as u
from sunpy import log

from gongsynth import instruments
from gongsynth.config import ENGINES, MODES, Effects
from gongsynth.resources import CannotRunHereError
from gongsynth.suns import SUNS
from gongsynth.version import version as __version__

__all__ = ["main", "run_command", "build_parser", "EXIT_CODES"]

EXIT_OK, EXIT_FAILURE, EXIT_USAGE, EXIT_EXISTS, EXIT_CANNOT_RUN, EXIT_INTERRUPTED = 0, 1, 2, 3, 4, 130
EXIT_TERMINATED = 143
#: Each exit code: what it means, and what to do.
EXIT_CODES = {
    EXIT_OK: ("success", ""),
    EXIT_FAILURE: ("failure while running (an I/O error such as a full disk; a failed run of a sweep, "
                   "the others saved; or a bug)", "fix the disk and run the same command again (a sweep "
                                                  "computes only the missing runs); report a bug"),
    EXIT_USAGE: ("bad input: the message names the argument or key", "change it as the message says"),
    EXIT_EXISTS: ("the output exists", "another --out, or --overwrite"),
    EXIT_CANNOT_RUN: ("cannot run here: more memory than this machine has",
                      "a smaller --shape, a shorter --duration, fewer --workers"),
    EXIT_INTERRUPTED: ("interrupted (Ctrl-C)", "run it again: output sets are complete or absent"),
    EXIT_TERMINATED: ("terminated (SIGTERM)", "as for 130"),
}


def _number(kind, *, minimum=None, positive=False):
    """An argparse type: a finite number of ``kind`` (and >= minimum / > 0), so the message names the flag."""
    def convert(text):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"{text!r} is not a{'n integer' if kind is int else ' number'}") from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"{text!r} is not finite")
        if positive and value <= 0:
            raise argparse.ArgumentTypeError(f"must be positive, got {text}")
        if minimum is not None and value < minimum:
            raise argparse.ArgumentTypeError(f"must be at least {minimum}, got {text}")
        return value
    convert.__name__ = kind.__name__
    return convert


def _out_path(text):
    """An argparse type: a non-empty path (an empty one would write into the current folder)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("is empty; name the output folder (e.g. --out run1)")
    return Path(text)


def build_parser():
    """
    The argument parser of the ``gongsynth`` command.

    Returns
    -------
    `argparse.ArgumentParser`

    Examples
    --------
    >>> build_parser().parse_args(["simulate", "--latitude", "60", "--out", "run"]).latitude
    [60.0]
    """
    parser = argparse.ArgumentParser(
        prog="gongsynth",
        description="Simulate what GONG would have measured, end to end.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="exit codes (the documentation's troubleshooting page says more):\n" + "\n".join(
            f"  {code:<4d}{meaning}" + (f"\n        -> {todo}" if todo else "")
            for code, (meaning, todo) in EXIT_CODES.items()))
    parser.add_argument("--version", action="version", version=f"gongsynth {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    sim = sub.add_parser("simulate", help="run the simulator and save maps and raw planes")
    sim.add_argument("--config", type=Path, help="TOML run configuration (see 'gongsynth config')")
    sim.add_argument("--latitude", type=_number(float), nargs="+", metavar="DEG",
                     help="heliographic latitude(s) in degrees; several run a sweep "
                          "(e.g. --latitude 0 25 45 60 70 75)")
    sim.add_argument("--duration", type=_number(float, positive=True), metavar="MIN",
                     help="observation length in minutes, a whole number of the instrument's frames "
                          "(default: its standard product, GONG 10, HMI 0.75, MDI 1)")
    sim.add_argument("--instrument", metavar="NAME",
                     help=f"the instrument: {', '.join(instruments.names())} (TOML: [instrument] name)")
    sim.add_argument("--engine", choices=ENGINES, help="camera engine")
    sim.add_argument("--mode", choices=MODES, help="scene mode")
    sim.add_argument("--date", "--obstime", dest="obstime", metavar="ISO",
                     help="observation time, e.g. 2009-09-05T18:54 (sets B0, the observer and the map dates)")
    sim.add_argument("--site", metavar="CODE", help="the observer's GONG site (BB, ML, LE, UD, TD, CT); "
                                                    "default the Earth's centre")
    sim.add_argument("--like", type=Path, metavar="GONG.fits",
                     help="take date, site and plate scale from a real GONG full-disk file ('what GONG "
                          "saw at Big Bear on 2009-09-05 18:54'); --date and --site still win")
    sim.add_argument("--like-counts", dest="like_counts", action=argparse.BooleanOptionalAction, default=None,
                     help="with --like (full disk): observe at the file's count level (its DIODE sums: "
                          "that observation's effective area; the default) or, with --no-like-counts, "
                          "with the instrument's effective_area")
    sim.add_argument("--pointing", type=_number(float), nargs=2, metavar=("TX", "TY"),
                     help="full-disk mode: helioprojective x and y of the detector's centre in arcsec "
                          "(default 0 0: the Sun's centre; --like takes the real file's)")
    sim.add_argument("--surface-field", dest="surface_field", metavar="synthetic|quiet|MAP.fits",
                     help="full-disk mode: the Sun's large-scale field, 'synthetic' (the seeded synthetic "
                          "Sun of the date; default), 'quiet' (the quiet Sun everywhere) or a magnetogram / "
                          "synoptic map")
    sim.add_argument("--seed", type=_number(int, minimum=0),
                     help="root random seed (default: fresh, recorded)")
    sim.add_argument("--shape", type=_number(int, minimum=8), metavar="N",
                     help="detector side in pixels (default: the instrument's; GONG 860, "
                          "HMI 1024 tiled and 4096 full-disk)")
    sim.add_argument("--workers", type=_number(int, minimum=1), metavar="N",
                     help="parallel workers: threads for one run, Dask workers for a sweep")
    sim.add_argument("--sun", choices=tuple(SUNS),
                     help="the built-in Sun: the 3-D model atmosphere through LTE radiative transfer "
                          "(the default; over the full disk its patch library, built once and cached) or "
                          "Milne-Eddington columns (fast, a toy for calibration)")
    sim.add_argument("--atmosphere", type=Path, metavar="PATH",
                     help="a model atmosphere as the input Sun, synthesised by LTE radiative transfer: "
                          "a MURaM snapshot folder, a gongsynth or ART HDF5 file (.h5), or a 1-D model "
                          "(SIR .mod, Hazel .1d, RH .atmos)")
    sim.add_argument("--out", type=_out_path, required=True, help="output directory")
    sim.add_argument("--overwrite", action="store_true", help="replace existing output files")
    sim.add_argument("--quiet", action="store_true", help="no progress bars or messages")
    effects = sim.add_argument_group(
        "instrument effects", "switch an effect off (or an opt-in one on) to see what it does "
                              "(TOML: [effects])")
    for effect in dataclasses.fields(Effects):
        flag, words = effect.name.replace("_", "-"), effect.name.replace("_", " ")
        if effect.default:
            effects.add_argument(f"--no-{flag}", dest=f"effect_{effect.name}", action="store_false",
                                 default=None, help=f"switch off the {words}")
        else:
            effects.add_argument(f"--{flag}", dest=f"effect_{effect.name}",
                                 action=argparse.BooleanOptionalAction, default=None,
                                 help=f"switch the {words} on (off by default; on by default in a "
                                      f"full-disk --like run) or off")

    cmp_ = sub.add_parser("compare", help="compare a simulated map with an observed one")
    cmp_.add_argument("simulated", type=Path, help="gongsynth magnetogram FITS")
    cmp_.add_argument("observed", type=Path, help="real GONG / HMI / MDI magnetogram FITS")
    cmp_.add_argument("--out", type=Path, help="where to save the side-by-side figure (PNG)")
    cmp_.add_argument("--overwrite", action="store_true", help="replace an existing figure")

    cal = sub.add_parser("calibrate", help="calibrate a magnetogram: the true field its values imply")
    cal.add_argument("magnetogram", type=Path,
                     help="magnetogram FITS: gongsynth, GONG (disk or synoptic), HMI or MDI")
    cal.add_argument("--out", type=Path, required=True, help="the calibrated map (FITS)")
    cal.add_argument("--table", type=Path,
                     help="calibration table (ECSV; default: the shipped one; with --to an instrument: the "
                          "conversion table)")
    cal.add_argument("--to", default="truth",
                     help="'truth' (default: the true field) or an instrument's name ('hmi', 'mdi', "
                          "'gong'): the map put on that instrument's scale with the predicted conversion "
                          "factors")
    cal.add_argument("--instrument", dest="source", metavar="NAME",
                     help="the map's own instrument ('gong', 'hmi', 'mdi') when its header does not say: "
                          "with --to truth it picks that instrument's shipped table")
    cal.add_argument("--scene", choices=("angle", "distance"), default="angle",
                     help="'angle' (default): the curves at each pixel's viewing angle; 'distance': each "
                          "quiet pixel also times the shipped scene table's ratio at its distance from the "
                          "map's own strong fields (abs(B) >= 400 G cos theta)")
    cal.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    cal.add_argument("--open-flux", dest="open_flux", action="store_true",
                     help="synoptic maps: also the PFSS open flux (source surface 2.5 R_sun) before and "
                          "after calibration, printed and written as OPENFLX0 / OPENFLX1 (Mx) in the "
                          "output's header (needs gongsynth[pfss])")
    cal.add_argument("--force", action="store_true",
                     help="calibrate even a map calibrated already (the correction compounds) or a truth map")

    cfg = sub.add_parser("config", help="print the default configuration as TOML")
    cfg.add_argument("--print-defaults", action="store_true", required=True,
                     help="print a complete, commented default configuration")
    return parser


def _simulation_config(args):
    from gongsynth.config import SimulationConfig
    from gongsynth.observing import as_observed, like_gong

    config = SimulationConfig.from_toml(args.config) if args.config else SimulationConfig()
    changes = {}
    if args.instrument is not None and instruments.get(args.instrument).name != config.instrument.name:
        changes["instrument"] = instruments.get(args.instrument)  # its defaults; [instrument] was another's
        if config.duration == config.instrument.default_duration:
            changes["duration"] = None      # the new instrument's standard product, unless --duration says
    if args.duration is not None:
        changes["duration"] = args.duration * u.min
    for name in ("engine", "mode", "seed", "workers", "obstime", "sun", "site", "surface_field"):
        if getattr(args, name) is not None:
            changes[name] = getattr(args, name)
    if args.surface_field is not None:
        changes["surface_field_sha256"] = None     # a new file: recorded when read
    if args.pointing is not None:
        changes["pointing"] = args.pointing * u.arcsec
    if args.like is not None:
        try:
            taken, changes["instrument"] = like_gong(args.like, settings=changes,
                                                     instrument=changes.get("instrument", config.instrument),
                                                     mode=changes.get("mode", config.mode))
        except (OSError, ValueError, TypeError, KeyError, IndexError) as exc:
            raise ValueError(f"--like {args.like}: {_cause(exc)} (expected a GONG full-disk FITS "
                             f"file)") from exc
        changes.update(taken)
    if args.like_counts is not None:
        changes["like_counts"] = args.like_counts
    switched = {e.name: getattr(args, f"effect_{e.name}") for e in dataclasses.fields(Effects)
                if getattr(args, f"effect_{e.name}") is not None}
    if args.like is not None:
        changes, switched = as_observed(changes, switched, mode=changes.get("mode", config.mode),
                                        instrument_name=changes.get("instrument", config.instrument).name)
    if switched:
        changes["effects"] = dataclasses.replace(config.effects, **switched)
    if args.shape is not None:
        changes["detector_shape"] = args.shape
    if args.atmosphere is not None:
        changes["atmosphere_file"], changes["atmosphere_sha256"] = str(args.atmosphere), None
    if args.latitude and len(args.latitude) == 1:
        changes["latitude"] = args.latitude[0] * u.deg
    return config.replace(**changes)


def _run_simulate(args):
    from gongsynth.pipeline import check_scene, simulate, simulate_each
    from gongsynth.products.output import check_output_folder
    from gongsynth.resources import check_disk_space, check_resources

    config = _simulation_config(args)
    if args.latitude and config.mode == "full-disk":
        raise ValueError(f"--latitude {' '.join(map(str, args.latitude))}: a full-disk run sees the whole "
                         f"disk; --latitude places a tiled field (use --pointing TX TY to move the full-disk "
                         f"detector)")
    progress = not args.quiet
    config, atmosphere = _input_files(args, config)
    state = {"written": [], "saving": None}
    try:
        if args.latitude and len(args.latitude) > 1:
            latitudes = u.Quantity(args.latitude, u.deg)
            folders = [_sweep_folder(args.out, lat) for lat in latitudes]
            if len(set(folders)) != len(folders):
                raise ValueError(f"--latitude {' '.join(map(str, args.latitude))}: two runs of the sweep "
                                 f"would share an output folder; give distinct latitudes")
            # Refuse before hours of computing, not after.
            configs = [config.replace(latitude=lat) for lat in latitudes]
            check_output_folder(args.out, overwrite=True, name="--out")
            configs = _adopt_seed(args, configs, folders)
            todo = []
            for cfg, folder in zip(configs, folders):
                if not args.overwrite and _holds_run(folder, cfg):   # a rerun completes an interrupted sweep
                    _say(args, f"latitude {cfg.latitude:.1f}: {folder} is complete already (kept)")
                    continue
                check_resources(cfg)
                check_scene(cfg, atmosphere)
                check_output_folder(folder, overwrite=args.overwrite, name="--out")
                todo.append((cfg, folder))
            check_disk_space([cfg for cfg, _ in todo], args.out)
            failed = []
            runs = simulate_each([cfg for cfg, _ in todo], stokes=atmosphere, workers=args.workers,
                                 progress=progress)
            for index, result in runs:   # each set saved as soon as its run is done
                cfg, folder = todo[index]
                if isinstance(result, BaseException):
                    failed.append((cfg, result))
                    continue
                state["saving"] = folder
                result.save(folder, overwrite=args.overwrite)
                state["written"].append(folder)
                _say(args, f"latitude {result.config.latitude:.1f}: wrote {folder}")
            if failed:
                return _sweep_failures(failed, state)
        else:
            check_resources(config)
            check_scene(config, atmosphere)
            check_output_folder(args.out, overwrite=args.overwrite, name="--out")
            check_disk_space([config], args.out)
            result = simulate(atmosphere, config=config, progress=progress)
            state["saving"] = args.out
            paths = result.save(args.out, overwrite=args.overwrite)
            state["written"].append(args.out)
            _say(args, "wrote " + ", ".join(str(p) for p in paths))
            if not args.quiet:
                print(result.summary())
    except (KeyboardInterrupt, OSError) as exc:
        exc.add_note(_what_was_written(state))
        raise
    return EXIT_OK


def _input_files(args, config):
    """
    The input atmosphere (read once for all latitudes of a sweep) and a check of the surface-field map,
    before any computing; the config records both by absolute path and SHA-256.  A bad one is named
    by its argument (exit 2).
    """
    from gongsynth.analysis.observations import load_observation
    from gongsynth.config import SURFACE_FIELD_NAMES
    from gongsynth.pipeline import record_input_file
    from gongsynth.sun.atmosphere import Atmosphere

    atmosphere = None
    if config.atmosphere_file:
        name = "--atmosphere" if args.atmosphere else "atmosphere_file"
        try:
            config = record_input_file(config, "atmosphere_file", "atmosphere_sha256")
            atmosphere = Atmosphere.read(config.atmosphere_file)
        except (OSError, ValueError, TypeError, KeyError) as exc:
            raise ValueError(f"{name} {config.atmosphere_file}: {_cause(exc)}") from exc
    if config.surface_field is not None and config.surface_field not in SURFACE_FIELD_NAMES:
        given = args.surface_field is not None
        try:
            config = record_input_file(config, "surface_field", "surface_field_sha256", folder=False)
            load_observation(config.surface_field, kind="magnetogram")
        except (OSError, ValueError, TypeError, KeyError) as exc:
            raise ValueError(f"{'--surface-field' if given else 'surface_field'} "
                             f"{args.surface_field if given else config.surface_field!r}: {_cause(exc)} "
                             f"(expected 'synthetic', 'quiet' or a magnetogram or synoptic map FITS "
                             f"file)") from exc
    return config, atmosphere


def _cause(exc):
    """What went wrong, for a message that names the argument first."""
    message = _describe(exc)[0]
    return message[len("error: "):] if message.startswith("error: ") else message


def _adopt_seed(args, configs, folders):
    """
    Without a seed given, a rerun of a sweep takes the seed of its finished runs (every run of a
    sweep shares one), so that it completes the same sweep.
    """
    import tomllib

    if args.seed is not None or (args.config is not None and "seed" in tomllib.loads(
            Path(args.config).read_text()).get("simulation", {})):
        return configs
    for cfg, folder in zip(configs, folders):
        saved = _saved_config(folder)
        if saved is not None and saved == cfg.replace(seed=saved.seed):
            return [c.replace(seed=saved.seed) for c in configs]
    return configs


def _saved_config(folder):
    """The configuration of the complete set in ``folder`` (None if there is none)."""
    from gongsynth.config import SimulationConfig
    from gongsynth.products.output import CONFIG_FILE, clean_leftovers

    if not (folder / CONFIG_FILE).is_file():
        return None
    clean_leftovers(folder)       # an interrupted save is finished first (the sets are atomic)
    try:
        return SimulationConfig.from_toml(folder / CONFIG_FILE)
    except (OSError, ValueError, TypeError, KeyError, u.UnitsError):
        return None


def _holds_run(folder, config):
    """Whether ``folder`` holds the complete set of this very run."""
    from gongsynth.products.output import planned_files

    saved = _saved_config(folder)
    return saved == config and all(p.is_file() for p in planned_files(folder, quicklook=False, truth=False))


def _sweep_failures(failed, state):
    """Report the runs of a sweep that failed (the others are saved) and return the exit code."""
    lines = [f"latitude {cfg.latitude:.1f}: {_describe(exc)[0]}" for cfg, exc in failed]
    done = ", ".join(str(f) for f in state["written"]) or "none"
    _fail(f"{len(failed)} run(s) of the sweep failed ({'; '.join(lines)}); complete sets written: {done}; "
          f"run the same command again to compute only the missing ones", 0)
    return max(_describe(exc)[1] for _, exc in failed)


def _what_was_written(state):
    """What a failed or interrupted simulate left on disk, in words (the sets are atomic)."""
    done = ", ".join(str(f) for f in state["written"])
    if state["saving"] is None:
        return "nothing was written (it stopped before saving)"
    pending = state["saving"] if state["saving"] not in state["written"] else None
    text = f"complete output in {done}; " if done else ""
    if pending is not None:
        text += f"{pending} was left as it was before this run (no partial set)"
    return text.rstrip("; ")


def _sweep_folder(out, latitude):
    """A run's folder in a sweep: the latitude to 0.001 deg, so distinct runs get distinct folders."""
    return out / f"lat{latitude.to_value(u.deg):+08.3f}"


def _run_compare(args):
    from gongsynth.analysis.compare import compare_files

    report = compare_files(args.simulated, args.observed, out=args.out,
                           overwrite=args.overwrite)
    print(report.summary())
    return EXIT_OK


def _run_calibrate(args):
    import numpy as np

    from gongsynth.analysis.apply_calibration import calibrate
    from gongsynth.analysis.observations import load_observation
    from gongsynth.files import atomic_path, check_writable

    suffix = "".join(args.out.suffixes[-2:]).lower()
    if not any(suffix.endswith(s) for s in _FITS_SUFFIXES):
        raise ValueError(f"--out {args.out}: the calibrated map is a FITS file; end its name in one of "
                         f"{', '.join(_FITS_SUFFIXES)} (.gz: compressed)")
    check_writable([args.out], args.overwrite)
    smap = load_observation(args.magnetogram)
    calibrated = calibrate(smap, table=args.table, force=args.force, to=args.to, instrument=args.source,
                           scene=args.scene)
    if args.open_flux:
        _record_open_flux(smap, calibrated)
    with atomic_path(args.out, overwrite=args.overwrite) as tmp:
        # FITS whatever the temporary name (astropy compresses a name ending in .gz); it exists already.
        calibrated.save(tmp, filetype="fits", overwrite=True)
    both = np.isfinite(smap.data) & np.isfinite(calibrated.data)
    ratio = np.abs(calibrated.data[both]).sum() / max(np.abs(smap.data[both]).sum(), 1e-300)
    _say(args, f"wrote {args.out} (table {calibrated.meta['caltable']})")
    print(f"unsigned flux, calibrated / measured: {ratio:.4f} over {both.sum()} pixels")
    return EXIT_OK


#: The names the calibrated map may take.
_FITS_SUFFIXES = (".fits", ".fts", ".fit", ".fits.gz", ".fts.gz", ".fit.gz")


def _record_open_flux(measured, calibrated):
    """Print the open flux of both maps and record it in the calibrated map's header."""
    from gongsynth.analysis.open_flux import open_flux

    for key, name, smap in (("openflx0", "measured", measured), ("openflx1", "calibrated", calibrated)):
        try:
            flux = open_flux(smap).to_value(u.Mx)
        except ImportError as exc:  # sunkit-magex missing: the message names the extra
            raise CannotRunHereError(f"--open-flux: {exc}") from None
        except ValueError as exc:  # e.g. a disk image: the PFSS needs a full-Sun synoptic map
            raise ValueError(f"--open-flux: {exc}") from None
        calibrated.meta[key] = flux
        print(f"open flux (PFSS, source surface 2.5 R_sun), {name}: {flux:.4e} Mx")


def _say(args, message):
    """Informational messages go through sunpy's logger (silenced by --quiet)."""
    if not getattr(args, "quiet", False):
        log.info(message)


def main(argv=None):
    """
    Entry point of the ``gongsynth`` console script.

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default ``sys.argv[1:]``).

    Returns
    -------
    int
        The exit code.

    Examples
    --------
    >>> main(["config", "--print-defaults"])  # doctest: +ELLIPSIS
    # gongsynth run configuration
    ...
    0
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    previous = _terminate_like_ctrl_c()
    try:
        if args.command == "config":
            from gongsynth.config import SimulationConfig

            print(SimulationConfig().to_toml(template=True), end="")
            return EXIT_OK
        if args.command == "simulate":
            return _run_simulate(args)
        if args.command == "calibrate":
            return _run_calibrate(args)
        return _run_compare(args)
    except (OSError, ValueError, TypeError, KeyError, u.UnitsError, CannotRunHereError, MemoryError,
            KeyboardInterrupt) as exc:
        return _fail(*_describe(exc))
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


class Terminated(KeyboardInterrupt):
    """SIGTERM (``kill``, a batch system's time limit): stopped like Ctrl-C, output sets left whole."""


def _terminate_like_ctrl_c():
    """SIGTERM raises `Terminated` (the clean-up of Ctrl-C); the handler it replaced, or None."""
    if threading.current_thread() is not threading.main_thread():
        return None

    def handler(signum, frame):
        raise Terminated

    return signal.signal(signal.SIGTERM, handler)


def _describe(exc):
    """The message and exit code of a failure (the README's table of exit codes)."""
    if isinstance(exc, FileExistsError):
        return f"{exc}", EXIT_EXISTS
    if isinstance(exc, FileNotFoundError):
        return f"file not found: {exc.filename or exc}", EXIT_USAGE
    if isinstance(exc, (IsADirectoryError, NotADirectoryError, PermissionError)):
        return _with_notes(f"error: {exc}", exc), EXIT_USAGE
    if isinstance(exc, (ValueError, TypeError, KeyError, u.UnitsError)):
        # A KeyError's str() is the repr of its message: print the message itself.
        message = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
        return f"error: {message}", EXIT_USAGE
    if isinstance(exc, (CannotRunHereError, MemoryError)):
        what = str(exc) or ("out of memory: use a smaller --shape, a shorter --duration or fewer --workers, "
                            "or a machine with more memory")
        return f"cannot run here: {what}", EXIT_CANNOT_RUN
    if isinstance(exc, Terminated):
        return _with_notes("terminated (SIGTERM)", exc), EXIT_TERMINATED
    if isinstance(exc, KeyboardInterrupt):
        return _with_notes("interrupted", exc), EXIT_INTERRUPTED
    if isinstance(exc, OSError):  # a full disk, an I/O error: the output sets are atomic
        where = f" ({exc.filename})" if exc.filename else ""
        return _with_notes(f"error: {exc.strerror or exc}{where}", exc), EXIT_FAILURE
    return f"error: {type(exc).__name__}: {exc}", EXIT_FAILURE


def _with_notes(message, exc):
    return "; ".join([message, *getattr(exc, "__notes__", [])])


def _fail(message, code):
    """Print an error on a line of its own (after any progress bar) and return the exit code."""
    if sys.stderr.isatty():
        print(file=sys.stderr)
    print(f"gongsynth: {message}", file=sys.stderr)
    return code


def run_command():
    """
    Entry point of the ``gongsynth`` console script: `main` on ``sys.argv``, in a process that ends next.

    Freezes (`gc.freeze`) the imports' ~10⁶ objects out of the run's full collections (~0.5 s of a 6-s
    run), then the run's out of the teardown's (~0.9 s).  Not in `main`, which tests and scripts call.

    Returns
    -------
    int
        `main`'s exit code.
    """
    gc.freeze()
    code = main()
    gc.freeze()
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(run_command())
