"""
Will a run fit?  Its memory estimated from the configuration, before anything is computed.
"""
import math
import os
import shutil
from pathlib import Path

import astropy.units as u

__all__ = ["CannotRunHereError", "available_memory", "check_resources", "estimate_memory",
           "estimate_output_size", "check_disk_space"]


class CannotRunHereError(RuntimeError):
    """A run this machine cannot do (it would need more memory than is available)."""


#: Bytes of one frame's row in the camera's frame schedule, with temporaries.
_SCHEDULE_BYTES_PER_FRAME = 80
#: Wavelengths of the built-in synthesis (the paper's 51-point grid).
_N_WAVELENGTHS = 51


#: Safety factor over the sum of the terms.
_MARGIN = 1.1


def estimate_memory(config):
    """
    An upper estimate of the peak memory a run needs, from its configuration alone.

    The run holds its largest arrays in two phases that do not overlap: the
    built-in photosphere model's temporaries (450 bytes per column), then the
    photosphere and its channel images (110 bytes per column) with the
    supersampled scene (six float32 planes plus the truth; the Stokes cube is
    synthesised block by block and never held) and the optics' float32 work
    arrays on the padded grid.  To the larger of the two it adds the
    detector-sized camera and product arrays, the camera's frame schedule and
    the loaded libraries (300 MB); the sum times 1.1.

    Calibrated against the peak resident memory (``/usr/bin/time -v``, seed 1,
    Python 3.12, Linux) of these runs:

    ========================================  ==========  ==========
    run                                       measured    estimate
    ========================================  ==========  ==========
    default (860 px, 10 min)                  1.48 GB     1.87 GB
    ``--shape 430 --duration 1``              0.80 GB     0.91 GB
    ``--shape 256 --duration 1``              0.78 GB     0.87 GB
    ``--mode full-disk --duration 1``         1.48 GB     2.14 GB
    ========================================  ==========  ==========

    (before issue 17's streaming and float32 optics: 3.58 GB for the default
    run, 2.79 GB for the full disk; the full disk from the patch library of
    issue 16: 1.48 GB when it builds the library, 1.25 GB when it loads it).

    Parameters
    ----------
    config : `~gongsynth.config.SimulationConfig`

    Returns
    -------
    `~astropy.units.Quantity`
        In bytes.

    Examples
    --------
    >>> from gongsynth.config import SimulationConfig
    >>> print(f"{estimate_memory(SimulationConfig(seed=0)).to(u.GB):.2f}")      # the 3-D Sun
    1.75 Gbyte
    >>> print(f"{estimate_memory(SimulationConfig(seed=0, sun='milne-eddington')).to(u.GB):.2f}")
    1.87 Gbyte
    """
    inst = config.instrument
    columns = config.photosphere_shape[0] * config.photosphere_shape[1]
    library = 0
    if config.mode == "full-disk":
        # The patch library (`gongsynth.stages.scene.library`): 256² columns per patch, held whole.
        columns, library = 256 * 256, 350e6
    model = 450 * columns  # the photosphere model's temporaries
    if config.sun == "model-atmosphere" and config.atmosphere_file is None:
        # The 3-D atmosphere (9 float32 fields on 80 heights) and its synthesised Stokes cube
        # (4 x 51 float32), both held until the channels are made.
        model = (9 * 80 + 4 * 51) * 4 * columns + model
    side = config.detector_pixels * inst.supersampling
    grid = side ** 2
    reach = 2 * math.ceil((inst.psf_radius / inst.plate_scale).to_value(u.one) * inst.supersampling)
    padded = (side + reach) ** 2
    # Photosphere and channels, the instrument's K planes + truth in float32, and the optics'
    # float32 work arrays (padded plane, half spectrum, transfer function, common part, a difference).
    scene = 110 * columns + 4 * grid * (len(inst.analysers) + 1) + 4 * padded * 6
    detector = 8 * config.detector_pixels ** 2 * 40
    frames = inst.schedule(config.duration).n_frames
    schedule = _SCHEDULE_BYTES_PER_FRAME * frames
    return _MARGIN * (max(model, scene) + library + detector + schedule + 300e6) * u.byte  # + the modules


def available_memory():
    """
    Memory available to a new run (Linux ``MemAvailable``; else physical memory free).

    Returns
    -------
    `~astropy.units.Quantity` or None
        In bytes; None where it cannot be found.
    """
    try:
        with open("/proc/meminfo") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024 * u.byte
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE") * u.byte
    except (ValueError, OSError, AttributeError):
        return None


def check_resources(config):
    """
    Refuse, before computing, a run that cannot fit in this machine's memory.

    Parameters
    ----------
    config : `~gongsynth.config.SimulationConfig`

    Raises
    ------
    CannotRunHereError
        With the estimate and the available memory.
    """
    need, have = estimate_memory(config), available_memory()
    if have is not None and need > have:
        raise CannotRunHereError(
            f"this run needs about {need.to(u.GB):.1f} of memory but {have.to(u.GB):.1f} is available: "
            f"use a smaller detector_shape or photosphere_shape, or a shorter duration")


#: Bytes per detector pixel of an output set: raw.fits holds six float64 planes, the flat (one
#: plane, or six when they differ) and the dark, each float64; five float32 maps.
_SET_BYTES_PER_PIXEL = 8 * (6 + 6 + 1) + 4 * 5
#: The quick-look PNG, the configuration and FITS headers, at most.
_SET_BYTES_FIXED = 4e6


def estimate_output_size(config):
    """
    An upper estimate of the disk space of a run's output set.

    Parameters
    ----------
    config : `~gongsynth.config.SimulationConfig`

    Returns
    -------
    `~astropy.units.Quantity`
        In bytes.  The default run writes 64 MB (measured); the estimate for it is 96 MB.

    Examples
    --------
    >>> from gongsynth.config import SimulationConfig
    >>> round(estimate_output_size(SimulationConfig(seed=0)).to_value(u.MB))
    96
    """
    return (_SET_BYTES_PER_PIXEL * config.detector_pixels ** 2 + _SET_BYTES_FIXED) * u.byte


def check_disk_space(configs, directory):
    """
    Refuse, before computing, runs whose output sets cannot fit on the disk of ``directory``.

    The sets are written into a staging folder beside the old ones, so the
    whole new output must fit next to what is already there.

    Parameters
    ----------
    configs : list of `~gongsynth.config.SimulationConfig`
        One per output set.
    directory : path-like
        The output folder (it need not exist yet).

    Raises
    ------
    CannotRunHereError
        With the space needed and the space free.
    """
    existing = Path(directory).absolute()
    while not existing.exists():
        existing = existing.parent
    try:
        free = shutil.disk_usage(existing).free * u.byte
    except OSError:
        return
    need = sum((estimate_output_size(c) for c in configs), 0 * u.byte)
    if need > free:
        raise CannotRunHereError(
            f"the output needs about {need.to(u.MB):.0f} of disk space but {existing} has "
            f"{free.to(u.MB):.0f} free")
