"""
LTE polarised radiative transfer of Ni I 676.78 nm through 3-D model atmospheres.

One job per module, in data-flow order: `atomic_data` (line and element data
with sources), `eos` (equation of state), `opacity` (continuum and line
opacity), `hydrostatic` (1-D models on optical-depth or column-mass scales),
`kernels` (Faddeeva function, DELO-linear formal solver), `rays` (inclined rays
through the periodic box), `truth` (the ground-truth B_LOS), `synthesis`
(`synthesize`: Atmosphere → StokesCube).
"""
from gongsynth.sun.rt.atomic_data import NiLineData
from gongsynth.sun.rt.synthesis import synthesize

__all__ = ["synthesize", "NiLineData"]
