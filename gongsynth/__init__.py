"""
gongsynth: what would GONG have measured?

An end-to-end simulator of the GONG magnetograph, from Stokes spectra of the
Ni I 676.8 nm line to GONG Doppler and line-of-sight magnetograms as sunpy Maps.
"""
from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("gongsynth")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0.0.0+unknown"

from .instrument import GONGInstrument  # noqa: E402
from .maps import GONGSynthMap  # noqa: E402  (registers the map source with sunpy.map.Map)
from .pipeline import SimulationResult, simulate, simulate_many  # noqa: E402
from .stokes import StokesCube  # noqa: E402

__all__ = ["GONGInstrument", "GONGSynthMap", "SimulationResult", "StokesCube", "simulate",
           "simulate_many", "__version__"]
