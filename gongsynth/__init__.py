"""
gongsynth: what would GONG have measured?

An end-to-end simulator of the GONG magnetograph, from Stokes spectra of the
Ni I 676.8 nm line to GONG Doppler and line-of-sight magnetograms as sunpy Maps.
"""
from importlib.metadata import PackageNotFoundError, version

from .instrument import GONGInstrument

try:
    __version__ = version("gongsynth")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0.0.0+unknown"

__all__ = ["GONGInstrument", "__version__"]
