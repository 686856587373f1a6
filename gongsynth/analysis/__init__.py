"""
Analysis: real observations, map statistics, degrading to GONG, comparison and calibration.

`cross_calibrate` (two magnetograms of one Sun at a common resolution) is
importable from here; the other tools live in their modules.
"""
import importlib

__all__ = ["cross_calibrate"]

# Public name -> module (imported when first used, so that importing the package stays light).
_LAZY = {"cross_calibrate": "gongsynth.analysis.cross_calibration"}


def __getattr__(name):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
