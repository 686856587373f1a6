"""
LTE polarised radiative transfer of a spectral line through 3-D model atmospheres.

Two lines ship (`LINES`): Ni I 676.78 nm (GONG's, the default) and Fe I
617.33 nm (HMI's); any `LineData` can be synthesised.  One job per module, in
data-flow order: `atomic_data` (line and element data with sources), `eos`
(equation of state), `opacity` (continuum and line opacity), `hydrostatic` (1-D
models on optical-depth or column-mass scales), `kernels` (Faddeeva function,
DELO-linear formal solver), `rays` (inclined rays through the periodic box),
`truth` (the ground-truth B_LOS), `synthesis` (`synthesize`: Atmosphere →
StokesCube).
"""
from gongsynth.sun.rt.atomic_data import DEFAULT_LINE, LINES, LineData, NiLineData, get_line
from gongsynth.sun.rt.synthesis import default_wavelength, synthesize

__all__ = ["synthesize", "LineData", "NiLineData", "LINES", "DEFAULT_LINE", "get_line", "default_wavelength"]
