"""
A built-in, seeded 3-D model Sun: granulation, hot kG flux elements, internetwork field and a sunspot.

One job per module, in data-flow order: `tables` (the 1-D semi-empirical
T(log τ) models, with sources), `stratification` (their hydrostatic
equilibrium and placement on a geometric grid), `granulation` (the periodic
grid, the granular pattern and its anelastic flow), `flux_elements` (kG
elements, potential spreading, internetwork field), `sunspot` (umbra,
penumbra, Evershed and moat flows), `builder` (`model_atmosphere`, and
`model_sun`: its whole-plane parts), `assembly` (`ModelSun`: the 3-D
atmosphere of any rows) and `transfer` (`DeferredTransfer`: its spectra by
`gongsynth.rt.synthesize` a block of rows at a time).
"""
from gongsynth.sun.model_atmosphere.assembly import ModelSun
from gongsynth.sun.model_atmosphere.builder import model_atmosphere, model_sun
from gongsynth.sun.model_atmosphere.transfer import DeferredTransfer

__all__ = ["model_atmosphere", "model_sun", "ModelSun", "DeferredTransfer"]
