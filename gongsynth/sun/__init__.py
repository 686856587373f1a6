"""
The Sun that enters the telescope: Stokes spectra and the models that make them.

- `gongsynth.sun.stokes`: `StokesCube`, the spectra at the Sun (and their files).
- `gongsynth.sun.photosphere`: the built-in column photosphere and its
  Milne–Eddington synthesis (the fast toy input).
"""
__all__ = []
