"""
SOHO/MDI as an instrument of gongsynth's family.

`MDIInstrument` holds every parameter (with its source) and
`filtergram_responses` the transmission of the five filtergrams F0..F4
(`gongsynth.instruments.mdi.filters`); both sit early in the data flow, beside
the other instruments' parameters.  The reduction, which needs
`gongsynth.stages.reduction`, is imported from its own modules:
`gongsynth.instruments.mdi.observables.reduce_mdi` (the onboard ratio
algorithm and its look-up table) and `gongsynth.instruments.mdi.noise`
(photon budget and magnetogram noise).  See the guide page ``instrument_mdi``.
"""
from gongsynth.instruments.mdi.filters import filtergram_responses
from gongsynth.instruments.mdi.parameters import (
    LEVELS,
    N_MDI_PLANES,
    N_TUNINGS,
    MDIInstrument,
    resolve_mdi,
)

__all__ = ["MDIInstrument", "N_MDI_PLANES", "N_TUNINGS", "LEVELS", "resolve_mdi", "filtergram_responses"]
