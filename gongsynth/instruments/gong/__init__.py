"""
GONG: the instrument of Plowman & Berger (paper I) as a member of the family.

- `~gongsynth.instruments.gong.parameters`: `GONGInstrument`, every parameter with its source;
- `~gongsynth.instruments.gong.filters`: prefilter, Lyot, Michelson, rotating wave plate → the
  three sector responses;
- `~gongsynth.instruments.gong.planes`: the six planes (2 polarisations × 3 sectors);
- `~gongsynth.instruments.gong.schedule`: 60 frames/s, wave plate, LCVR, dither;
- `~gongsynth.instruments.gong.reduction`: the three-phase √3 arctan;
- `~gongsynth.instruments.gong.ucor`: the per-minute image rotation of GONG's reduction;
- `~gongsynth.instruments.gong.header_counts`: the count level of a real header's DIODE sums.
"""
from gongsynth.instruments.gong.parameters import GONGInstrument

__all__ = ["GONGInstrument"]
