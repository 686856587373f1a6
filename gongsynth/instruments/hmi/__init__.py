"""
SDO/HMI as an instrument of gongsynth's family.

`HMIInstrument` holds every parameter (with its source) and
`filtergram_responses` the transmission of the six tuning positions
(`gongsynth.instruments.hmi.filters`); both sit early in the data flow, beside
the other instruments' parameters.  The reduction, which needs
`gongsynth.stages.reduction`, is imported from its own modules:
`gongsynth.instruments.hmi.observables.reduce_hmi` (the MDI-like algorithm)
and `gongsynth.instruments.hmi.noise` (photon budget and magnetogram noise).
See the guide page ``instrument_hmi``.
"""
from gongsynth.instruments.hmi.filters import filtergram_responses
from gongsynth.instruments.hmi.parameters import (
    N_HMI_PLANES,
    N_TUNINGS,
    HMIInstrument,
    resolve_hmi,
)

__all__ = ["HMIInstrument", "N_HMI_PLANES", "N_TUNINGS", "resolve_hmi", "filtergram_responses"]
