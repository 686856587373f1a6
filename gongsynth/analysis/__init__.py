"""
Analysis: real observations, map statistics, degrading to GONG, comparison and calibration.
"""
__all__ = []
