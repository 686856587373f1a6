"""
Scenes: the six planes placed on a supersampled helioprojective grid.

``scene`` holds the `Scene` container, ``tiled`` the paper's tiling of a small
box and ``fulldisk`` the photosphere mapped over the visible disk.
"""
__all__ = []
