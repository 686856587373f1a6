"""
The six GONG accumulation planes and their order.

GONG's magnetogram mode records three wave-plate sectors (channels 0, 1, 2)
for each of two circular polarisation states selected by the LCVR.  Every
array of planes in gongsynth has a leading axis of length 6 in this order::

    index = polarisation * 3 + channel,   polarisation 0 = I+V, 1 = I-V
"""
__all__ = ["N_CHANNELS", "N_POLARISATIONS", "N_PLANES", "POLARISATIONS", "PLANE_NAMES", "ANALYSERS",
           "plane_index"]

N_CHANNELS = 3
N_POLARISATIONS = 2
N_PLANES = N_CHANNELS * N_POLARISATIONS
#: Names of the polarisation states, in order (sign of V).
POLARISATIONS = ("I+V", "I-V")
#: Human-readable plane names, in plane order.
PLANE_NAMES = tuple(f"{p} ch{c}" for p in POLARISATIONS for c in range(N_CHANNELS))
#: (sector, sign of V) of each plane, in plane order (`gongsynth.instruments.base.Instrument.analysers`).
ANALYSERS = tuple((c, sign) for sign in (1, -1) for c in range(N_CHANNELS))


def plane_index(polarisation, channel):
    """
    Index of a plane in the leading axis of a (6, ...) array.

    Parameters
    ----------
    polarisation : int
        0 for I+V, 1 for I-V.
    channel : int
        Wave-plate sector 0, 1 or 2.

    Returns
    -------
    int

    Examples
    --------
    >>> plane_index(1, 2)
    5
    """
    if polarisation not in (0, 1) or channel not in (0, 1, 2):
        raise ValueError(f"polarisation must be 0 or 1 and channel 0-2, got {polarisation}, {channel}")
    return polarisation * N_CHANNELS + channel
