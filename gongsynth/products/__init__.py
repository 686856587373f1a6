"""
Products of a run: sunpy Maps with helioprojective WCS, and the files a run writes.
"""
__all__ = []
