"""
The built-in Suns a run can take: their builders, each mode's default, a run's default grid, their knobs.
"""
import inspect

import astropy.units as u

from gongsynth.sun.model_atmosphere import model_atmosphere
from gongsynth.sun.photosphere import model_photosphere

__all__ = ["SUNS", "RUN_GRIDS", "DEFAULT_SUNS", "PHOTOSPHERE_RUN_KEYS", "default_sun", "photosphere_defaults",
           "run_grid_default"]

#: The built-in Suns (`SimulationConfig.sun`) and the function that builds each: the
#: Milne-Eddington column photosphere (fast; a toy for calibration: one line strength
#: everywhere) and the 3-D model atmosphere synthesised by LTE radiative transfer.
SUNS = {"milne-eddington": model_photosphere, "model-atmosphere": model_atmosphere}

#: A run's default grid of a built-in Sun where it differs from the builder's.  The 3-D Sun's radiative
#: transfer takes minutes at its builder's 1024² columns of 96 km; a run covers the same 98 Mm box
#: (the papers' area, with room for the sunspot) with 256² columns of 384 km, which keeps the default
#: run under a minute.  The weak-flux factor does not depend on the column size (seeds 1 and 2, on the
#: Sun of issue 14:
#: 1.23 / 1.00 at 0° / 60° with 384 km columns, 1.25 / 1.00 with 192 km, 1.22 / 0.99 with 96 km) but
#: on the sunspot, which needs a box of 35 Mm or more: without it 0.94 / 0.69 (98 Mm box; today's Sun:
#: 0.93 / 0.73 against 1.25 / 1.05 with its network, ``data/weak_flux_factors.ecsv``), and a 25 Mm
#: box of 96 km columns, too small for a spot, gives 1.06 / 0.69.
RUN_GRIDS = {"model-atmosphere": {"shape": (256, 256), "pixel_size": 384 * u.km}}

#: The built-in Sun of each scene mode when none is named: the 3-D model atmosphere in both, so that
#: the tiled and full-disk modes show the same Sun.  Over the full disk its patch library
#: (`gongsynth.stages.scene.library_rt`, on one grid for every instrument:
#: `~gongsynth.stages.scene.library_rt.atmosphere_grid`) builds once per machine in ~8-30 s and is
#: cached; ``sun = "milne-eddington"`` keeps the fast toy columns (~6 s).
DEFAULT_SUNS = {"tiled": "model-atmosphere", "full-disk": "model-atmosphere"}

#: Arguments of the built-in Suns set by [simulation] instead of [photosphere].
PHOTOSPHERE_RUN_KEYS = ("shape", "pixel_size", "seed")


def default_sun(mode="tiled"):
    """
    The built-in Sun a run uses when none is named: the 3-D model atmosphere in
    every mode (`DEFAULT_SUNS`; over the full disk, its cached patch library).

    Parameters
    ----------
    mode : str
        A scene mode (`gongsynth.config.MODES`).

    Returns
    -------
    str
        A key of `SUNS`.

    Examples
    --------
    >>> default_sun(), default_sun("full-disk")
    ('model-atmosphere', 'model-atmosphere')
    """
    if mode not in DEFAULT_SUNS:
        raise ValueError(f"mode must be one of {tuple(DEFAULT_SUNS)}, got {mode!r}")
    return DEFAULT_SUNS[mode]


def photosphere_defaults(sun="model-atmosphere"):
    """
    The knobs of a built-in Sun that ``[photosphere]`` sets, with their defaults.

    Shape, pixel size and seed are run arguments (``photosphere_shape``,
    ``photosphere_pixel_size``, ``seed``) and are not among them.

    Parameters
    ----------
    sun : str
        A key of `SUNS`.

    Returns
    -------
    dict

    Examples
    --------
    >>> photosphere_defaults("milne-eddington")["umbra_field"]
    <Quantity 3000. G>
    >>> photosphere_defaults()["element_field"]
    <Quantity 1500. G>
    """
    if sun not in SUNS:
        raise ValueError(f"sun must be one of {tuple(SUNS)}, got {sun!r}")
    return {name: p.default for name, p in inspect.signature(SUNS[sun]).parameters.items()
            if name not in PHOTOSPHERE_RUN_KEYS}


def run_grid_default(sun, name):
    """
    A run's default ``shape`` or ``pixel_size`` of a built-in Sun: `RUN_GRIDS`, else the builder's.

    Parameters
    ----------
    sun : str
        A key of `SUNS`.
    name : {"shape", "pixel_size"}

    Returns
    -------
    tuple or `~astropy.units.Quantity`

    Examples
    --------
    >>> run_grid_default("model-atmosphere", "pixel_size"), run_grid_default("milne-eddington", "shape")
    (<Quantity 384. km>, (1024, 1024))
    """
    return RUN_GRIDS.get(sun, {}).get(name, inspect.signature(SUNS[sun]).parameters[name].default)
