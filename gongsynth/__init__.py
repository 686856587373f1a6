"""
gongsynth: what would GONG have measured?

An end-to-end simulator of the GONG magnetograph, from Stokes spectra of the
Ni I 676.8 nm line to GONG Doppler and line-of-sight magnetograms as sunpy Maps.

The package's folders follow the data flow: `gongsynth.sun` (the input
spectra), `gongsynth.stages` (the instrument), `gongsynth.products` (Maps and
files) and `gongsynth.analysis` (real data, comparison, calibration).
"""
import sys

from gongsynth.analysis import calibration, compare
from gongsynth.analysis.apply_calibration import calibrate
from gongsynth.analysis.observations import load_observation
from gongsynth.analysis.weak_flux import weak_flux_factor
from gongsynth.instrument import GONGInstrument
from gongsynth.pipeline import SimulationResult, simulate, simulate_many
from gongsynth.products.maps import GONGSynthMap  # registers the map source with sunpy.map.Map
from gongsynth.stages import filters, reduction
from gongsynth.sun import photosphere, rt
from gongsynth.sun.atmosphere import Atmosphere
from gongsynth.sun.model_atmosphere import model_atmosphere
from gongsynth.sun.stokes import StokesCube
from gongsynth.sun.surface_field import surface_field_from_map, synthetic_surface_field
from gongsynth.version import version as __version__

__citation__ = (
    "Plowman, J. & Berger, T., Calibrating GONG Magnetograms with End-to-end Instrument "
    "Simulation I, and the gongsynth software (version " + __version__ + "); see CITATION.cff"
)

# The dotted paths promised to users (DESIGN §2) name the modules in their new
# folders: ``import gongsynth.filters`` gives `gongsynth.stages.filters` itself.
for _name, _module in {"filters": filters, "reduction": reduction, "compare": compare,
                       "calibration": calibration, "photosphere": photosphere, "rt": rt}.items():
    sys.modules[f"{__name__}.{_name}"] = _module
del _name, _module

__all__ = ["Atmosphere", "GONGInstrument", "GONGSynthMap", "SimulationResult", "StokesCube", "calibrate",
           "calibration", "compare", "filters", "load_observation", "model_atmosphere",
           "photosphere", "reduction", "rt", "simulate", "simulate_many", "surface_field_from_map",
           "synthetic_surface_field", "weak_flux_factor", "__citation__", "__version__"]
