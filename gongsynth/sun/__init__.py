"""
The Sun that enters the telescope: Stokes spectra and the models that make them.

- `gongsynth.sun.stokes`: `StokesCube`, the spectra at the Sun (and their files).
- `gongsynth.sun.photosphere`: the built-in column photosphere and its
  Milne–Eddington synthesis (the fast toy input).
- `gongsynth.sun.surface_field`: the large-scale radial field of the whole
  Sun (from a real map or a seeded synthetic Sun) that a full-disk scene fills.
"""
__all__ = []
