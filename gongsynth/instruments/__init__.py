"""
The instruments of gongsynth's family (placeholder: the integrator replaces this file).

Each instrument lives in a subpackage, e.g. `gongsynth.instruments.hmi`.
"""

__all__ = []
