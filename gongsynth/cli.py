"""
The ``gongsynth`` command line.

::

    gongsynth simulate [--config run.toml] [--latitude 60] [--duration 10] [--engine frames]
                       [--seed 1] [--workers N] [--mode tiled|full-disk] [--shape 256]
                       [--obstime ISO] [--no-psf] [--no-photon-noise] ... [--overwrite] [--quiet]
                       --out DIR
    gongsynth compare SIM.fits OBS.fits [--out FIGURE.png]
    gongsynth config --print-defaults

Exit codes: 0 success, 1 runtime failure, 2 bad usage or bad input (the
message names the argument), 3 refusing to overwrite existing output.
"""
import argparse
import dataclasses
import sys
from pathlib import Path

import astropy.units as u

from sunpy import log

from gongsynth.config import ENGINES, MODES, Effects
from gongsynth.version import version as __version__

__all__ = ["main", "build_parser"]

EXIT_OK, EXIT_FAILURE, EXIT_USAGE, EXIT_EXISTS = 0, 1, 2, 3


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
        description="Simulate what GONG would have measured, end to end.")
    parser.add_argument("--version", action="version", version=f"gongsynth {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    sim = sub.add_parser("simulate", help="run the simulator and save maps and raw planes")
    sim.add_argument("--config", type=Path, help="TOML run configuration (see 'gongsynth config')")
    sim.add_argument("--latitude", type=float, nargs="+", metavar="DEG",
                     help="heliographic latitude(s) in degrees; several run a sweep "
                          "(e.g. --latitude 0 25 45 60 70 75)")
    sim.add_argument("--duration", type=float, metavar="MIN", help="observation length in minutes")
    sim.add_argument("--engine", choices=ENGINES, help="camera engine")
    sim.add_argument("--mode", choices=MODES, help="scene mode")
    sim.add_argument("--obstime", metavar="ISO", help="observation time, e.g. 2009-09-05T18:54 "
                                                      "(sets B0, the observer and the map dates)")
    sim.add_argument("--seed", type=int, help="root random seed (default: fresh, recorded)")
    sim.add_argument("--shape", type=int, metavar="N", help="detector side in pixels (default 860)")
    sim.add_argument("--workers", type=int, metavar="N",
                     help="parallel workers: threads for one run, Dask workers for a sweep")
    sim.add_argument("--out", type=Path, required=True, help="output directory")
    sim.add_argument("--overwrite", action="store_true", help="replace existing output files")
    sim.add_argument("--quiet", action="store_true", help="no progress bars or messages")
    effects = sim.add_argument_group(
        "instrument effects", "switch an effect off to see what it does (TOML: [effects])")
    for effect in dataclasses.fields(Effects):
        flag = effect.name.replace("_", "-")
        effects.add_argument(f"--no-{flag}", dest=f"no_{effect.name}", action="store_true",
                             help=f"switch off the {effect.name.replace('_', ' ')}")

    cmp_ = sub.add_parser("compare", help="compare a simulated map with an observed one")
    cmp_.add_argument("simulated", type=Path, help="gongsynth magnetogram FITS")
    cmp_.add_argument("observed", type=Path, help="real GONG / HMI / MDI magnetogram FITS")
    cmp_.add_argument("--out", type=Path, help="where to save the side-by-side figure (PNG)")
    cmp_.add_argument("--overwrite", action="store_true", help="replace an existing figure")

    cfg = sub.add_parser("config", help="print the default configuration as TOML")
    cfg.add_argument("--print-defaults", action="store_true", required=True,
                     help="print a complete, commented default configuration")
    return parser


def _simulation_config(args):
    from gongsynth.config import SimulationConfig

    config = SimulationConfig.from_toml(args.config) if args.config else SimulationConfig()
    changes = {}
    if args.duration is not None:
        changes["duration"] = args.duration * u.min
    for name in ("engine", "mode", "seed", "workers", "obstime"):
        if getattr(args, name) is not None:
            changes[name] = getattr(args, name)
    off = {e.name: False for e in dataclasses.fields(Effects) if getattr(args, f"no_{e.name}")}
    if off:
        changes["effects"] = dataclasses.replace(config.effects, **off)
    if args.shape is not None:
        changes["detector_shape"] = args.shape
    if args.latitude and len(args.latitude) == 1:
        changes["latitude"] = args.latitude[0] * u.deg
    if args.seed is None and not args.config:
        changes["seed"] = SimulationConfig.from_arguments().seed
    return config.replace(**changes)


def _run_simulate(args):
    from gongsynth.files import check_writable
    from gongsynth.products.output import planned_files
    from gongsynth.pipeline import simulate, simulate_many

    config = _simulation_config(args)
    progress = not args.quiet
    if args.latitude and len(args.latitude) > 1:
        latitudes = u.Quantity(args.latitude, u.deg)
        folders = [_sweep_folder(args.out, lat) for lat in latitudes]
        # Refuse before hours of computing, not after.
        check_writable([p for f in folders for p in planned_files(f)], args.overwrite)
        results = simulate_many(latitudes=latitudes, config=config, workers=args.workers,
                                progress=progress)
        for result, folder in zip(results, folders):
            result.save(folder, overwrite=args.overwrite)
            _say(args, f"latitude {result.config.latitude:.1f}: wrote {folder}")
    else:
        check_writable(planned_files(args.out), args.overwrite)
        result = simulate(config=config, progress=progress)
        paths = result.save(args.out, overwrite=args.overwrite)
        _say(args, "wrote " + ", ".join(str(p) for p in paths))
        if not args.quiet:
            print(result.summary())
    return EXIT_OK


def _sweep_folder(out, latitude):
    return out / f"lat{latitude.to_value(u.deg):+05.1f}"


def _run_compare(args):
    from gongsynth.analysis.compare import compare_files

    report = compare_files(args.simulated, args.observed, out=args.out,
                           overwrite=args.overwrite)
    print(report.summary())
    return EXIT_OK


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
    try:
        if args.command == "config":
            from gongsynth.config import SimulationConfig

            print(SimulationConfig().to_toml(), end="")
            return EXIT_OK
        if args.command == "simulate":
            return _run_simulate(args)
        return _run_compare(args)
    except FileExistsError as exc:
        print(f"gongsynth: {exc}", file=sys.stderr)
        return EXIT_EXISTS
    except FileNotFoundError as exc:
        print(f"gongsynth: file not found: {exc.filename or exc}", file=sys.stderr)
        return EXIT_USAGE
    except (ValueError, TypeError, KeyError, u.UnitsError) as exc:
        print(f"gongsynth: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("gongsynth: interrupted; no partial files were left behind", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
