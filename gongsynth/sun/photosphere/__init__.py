"""
The built-in photosphere and its Milne–Eddington Ni I 676.8 nm spectra.

- `Photosphere`: field vector, velocity and continuum per column.
- `model_photosphere`: a seeded, periodic model of a sunspot in its
  surroundings, like the paper's MURaM snapshot.
- `synthesize`: Milne–Eddington Stokes spectra → `~gongsynth.sun.stokes.StokesCube`;
  `DeferredStokes`: the same, synthesised block by block when needed.
- `NiLine`: a line's Milne–Eddington parameters and the continuum limb darkening;
  `me_line`: those of each line by name (Ni I 676.8, Fe I 617.3).
"""
from gongsynth.sun.photosphere.columns import Photosphere
from gongsynth.sun.photosphere.line import ME_LINES, NiLine, me_line
from gongsynth.sun.photosphere.model import model_photosphere
from gongsynth.sun.photosphere.synthesis import (
    DeferredStokes,
    default_wavelength,
    synthesize,
    zeeman_splitting,
)

__all__ = ["Photosphere", "NiLine", "ME_LINES", "me_line",
           "model_photosphere", "synthesize", "DeferredStokes", "default_wavelength",
           "zeeman_splitting"]
