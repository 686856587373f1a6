"""
SDO/HMI as an instrument of gongsynth's family.

`HMIInstrument` holds every parameter (with its source); `filters` the
transmission of the six tuning positions; `observables` the MDI-like
reduction (`reduce_hmi`); `noise` the photon budget and magnetogram noise.
See the Instruments guide page ``instrument_hmi``.
"""
from gongsynth.instruments.hmi.filters import filtergram_responses
from gongsynth.instruments.hmi.noise import magnetogram_noise
from gongsynth.instruments.hmi.observables import lookup_table, reduce_hmi
from gongsynth.instruments.hmi.parameters import (
    N_HMI_PLANES,
    N_TUNINGS,
    HMIInstrument,
    resolve_hmi,
)

__all__ = ["HMIInstrument", "N_HMI_PLANES", "N_TUNINGS", "resolve_hmi", "filtergram_responses",
           "reduce_hmi", "lookup_table", "magnetogram_noise"]
