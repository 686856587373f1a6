"""
gongsynth: what would GONG have measured?

An end-to-end simulator of the GONG magnetograph, from Stokes spectra of the
Ni I 676.8 nm line to GONG Doppler and line-of-sight magnetograms as sunpy Maps.

The package's folders follow the data flow: `gongsynth.sun` (the input
spectra), `gongsynth.instruments` (GONG and the family: what is each
instrument's own) and `gongsynth.stages` (what they share), `gongsynth.products`
(Maps and files) and `gongsynth.analysis` (real data, comparison, calibration).

Most names below are imported when first used (``gongsynth.simulate``
imports the pipeline, ``gongsynth.compare`` the comparison tools), so that a
run does not pay for the analysis tools; the map source is registered with
`sunpy.map.Map` at once.
"""
import importlib
import importlib.abc
import importlib.util
import sys

from gongsynth import precompile as _precompile

# A first ``gongsynth simulate``: its kernels compile in the background while sunpy imports.
_precompile.start_for_command(sys.argv)

from gongsynth.products.maps import GONGSynthMap  # noqa: E402 (registers the map source with sunpy.map.Map)
from gongsynth.version import version as __version__  # noqa: E402

__citation__ = (
    "Plowman, J. & Berger, T., Calibrating GONG Magnetograms with End-to-end Instrument "
    "Simulation I, and the gongsynth software (version " + __version__ + "); see CITATION.cff"
)

# Public name -> (module, attribute or None for the module itself).
_LAZY = {
    "Atmosphere": ("gongsynth.sun.atmosphere", "Atmosphere"),
    "GONGInstrument": ("gongsynth.instruments.gong.parameters", "GONGInstrument"),
    "SimulationResult": ("gongsynth.pipeline", "SimulationResult"),
    "StokesCube": ("gongsynth.sun.stokes", "StokesCube"),
    "calibrate": ("gongsynth.analysis.apply_calibration", "calibrate"),
    "cross_calibrate": ("gongsynth.analysis.cross_calibration", "cross_calibrate"),
    "cross_calibration_table": ("gongsynth.cross_calibration_sweep", "cross_calibration_table"),
    "load_observation": ("gongsynth.analysis.observations", "load_observation"),
    "model_atmosphere": ("gongsynth.sun.model_atmosphere", "model_atmosphere"),
    "open_flux": ("gongsynth.analysis.open_flux", "open_flux"),
    "simulate": ("gongsynth.pipeline", "simulate"),
    "simulate_many": ("gongsynth.pipeline", "simulate_many"),
    "surface_field_from_map": ("gongsynth.sun.surface_field", "surface_field_from_map"),
    "synthetic_surface_field": ("gongsynth.sun.surface_field", "synthetic_surface_field"),
    "weak_flux_factor": ("gongsynth.analysis.weak_flux", "weak_flux_factor"),
}

# The dotted paths promised to users (DESIGN §2), and the old homes of modules
# that moved, name the modules in their new folders: ``import gongsynth.filters``
# gives `gongsynth.instruments.gong.filters` itself.
_ALIASES = {
    "filters": "gongsynth.instruments.gong.filters",
    "instrument": "gongsynth.instruments.gong.parameters",
    "planes": "gongsynth.instruments.gong.planes",
    "stages.filters": "gongsynth.instruments.gong.filters",
    "stages.camera.schedule": "gongsynth.instruments.gong.schedule",
    "reduction": "gongsynth.stages.reduction",
    "compare": "gongsynth.analysis.compare",
    "calibration": "gongsynth.analysis.calibration",
    "photosphere": "gongsynth.sun.photosphere",
    "rt": "gongsynth.sun.rt",
}


class _AliasLoader(importlib.abc.Loader):
    """Loads ``gongsynth.<alias>`` as the module it names (the same module object)."""

    def __init__(self, target):
        self.target = target

    def create_module(self, spec):
        return importlib.import_module(self.target)

    def exec_module(self, module):
        pass


class _AliasFinder(importlib.abc.MetaPathFinder):
    """Finds the aliased dotted paths (``import gongsynth.filters``)."""

    def find_spec(self, fullname, path, target=None):
        prefix, _, name = fullname.partition(".")
        if prefix != __name__ or name not in _ALIASES:
            return None
        return importlib.util.spec_from_loader(fullname, _AliasLoader(_ALIASES[name]))


# First in line: an alias wins over a stale file of the same name (an old
# installation's, or an editable install of another checkout).
if not any(isinstance(finder, _AliasFinder) for finder in sys.meta_path):
    sys.meta_path.insert(0, _AliasFinder())


def __getattr__(name):
    if name in _ALIASES:
        return importlib.import_module(f"{__name__}.{name}")
    if name in _LAZY:
        module, attribute = _LAZY[name]
        value = getattr(importlib.import_module(module), attribute)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY) | set(_ALIASES))


__all__ = ["Atmosphere", "GONGInstrument", "GONGSynthMap", "SimulationResult", "StokesCube", "calibrate",
           "calibration", "cross_calibrate", "cross_calibration_table", "compare", "filters",
           "load_observation", "model_atmosphere",
           "open_flux", "photosphere", "reduction", "rt", "simulate", "simulate_many",
           "surface_field_from_map", "synthetic_surface_field", "weak_flux_factor", "__citation__",
           "__version__"]
