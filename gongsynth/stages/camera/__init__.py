"""
The camera: frame schedule, detector flat and dark, and the frame-by-frame integration.
"""
__all__ = []
