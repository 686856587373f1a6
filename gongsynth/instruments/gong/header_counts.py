"""
The count level a real GONG header states, and the factor that brings a simulation's counts to it.

A GONG site file's header carries ``DIODE1``-``DIODE3``, "sum of diode values
from phase plane 1..3": the sum over the camera's pixels of the mean
per-frame value (adu) of each phase plane, a phase plane being the mean of
its I+V and I−V planes (the reading, and the evidence for it, are in
`gongsynth.analysis.count_levels`: the intensity image equals
(ACCUM / 2³) Σ DIODE to 0.2 % in the Big Bear files of 2009-09-05).  A sum
over the whole image of the disk is the disk's total light per frame, which
does not depend on the pixel size, so the simulation's counterpart is the
sum over its detector of the expected counts per frame (mean of the six
planes, in adu), and their ratio is the factor by which the simulation's
effective area must be multiplied to collect what that observation
collected: ``[simulation] like_counts`` (``--like-counts``) applies it to
a ``like`` run's expected counts before the camera (counts scale linearly
with ``effective_area``, `gongsynth.stages.optics.photometric_factor`) and
records the effective area it implies in the raw header (``EFFAREA``).
For Big Bear 2009-09-05 `gongsynth.analysis.count_levels` measured
0.102-0.119 cm² from the three DIODEs (0.109 cm² from the disk centre of
the intensity image), the paper's 0.6 cm² being about 5.5 times too much
for that observation (Earth's atmosphere at 30° zenith distance included).
"""
import astropy.units as u
import numpy as np

__all__ = ["DIODE_KEYWORDS", "header_diodes", "count_scale"]

#: The header keywords of the three phase planes' diode sums.
DIODE_KEYWORDS = ("DIODE1", "DIODE2", "DIODE3")


def header_diodes(header):
    """
    ``DIODE1``-``DIODE3`` of a GONG header (or a FITS path), in adu per frame summed over the pixels.

    Parameters
    ----------
    header : `~astropy.io.fits.Header`, mapping or path-like

    Returns
    -------
    `~astropy.units.Quantity`
        (3,) adu.

    Raises
    ------
    ValueError
        If a DIODE keyword is missing or not positive.

    Examples
    --------
    >>> header_diodes({"DIODE1": 228773684, "DIODE2": 252631643, "DIODE3": 228385037})
    <Quantity [2.28773684e+08, 2.52631643e+08, 2.28385037e+08] adu>
    """
    if not hasattr(header, "get"):
        from astropy.io import fits

        header = fits.getheader(header)
    values = [header.get(k, header.get(k.lower())) for k in DIODE_KEYWORDS]
    if any(v is None for v in values) or not all(float(v) > 0 for v in values):
        raise ValueError(f"the GONG header needs positive {', '.join(DIODE_KEYWORDS)} (the phase planes' "
                         f"diode sums) to give a count level, got {values}")
    return np.array(values, dtype=float) * u.adu


def count_scale(expected, header, instrument):
    """
    Real total counts per frame over simulated ones: the factor on the effective area.

    Parameters
    ----------
    expected : `~astropy.units.Quantity`
        ``(6, ny, nx)`` expected electrons per frame of a full-disk run (the
        whole disk on the detector, a dark sky around it).
    header : `~astropy.io.fits.Header`, mapping or path-like
        The real GONG file's header (``DIODE1``-``DIODE3``).
    instrument : `~gongsynth.GONGInstrument`
        Supplies ``gain``.

    Returns
    -------
    float
        mean(DIODE) / Σ_pixels mean_planes(expected) / gain.

    Raises
    ------
    ValueError
        If the detector's edge is not dark sky (the disk is not wholly on it)
        or a DIODE keyword is missing.

    Examples
    --------
    >>> import numpy as np, astropy.units as u
    >>> from gongsynth import GONGInstrument
    >>> inst = GONGInstrument()
    >>> expected = np.zeros((6, 12, 12)) * u.electron
    >>> expected[:, 1:-1, 1:-1] = 33.0 * 4 * u.electron     # 4 adu per pixel and frame on 100 pixels
    >>> round(count_scale(expected, {"DIODE1": 100, "DIODE2": 100, "DIODE3": 100}, inst), 3)
    0.25
    """
    counts = np.mean(u.Quantity(expected).to_value(u.electron), axis=0)
    edge = np.concatenate([counts[0], counts[-1], counts[:, 0], counts[:, -1]])
    if not np.max(counts) > 0 or np.mean(edge) > 0.01 * np.max(counts):
        raise ValueError("the header's DIODE sums hold the whole disk: the simulated disk must lie wholly "
                         "on the detector with dark sky at its edges (a full-disk run)")
    real = float(np.mean(header_diodes(header).to_value(u.adu)))
    gain = instrument.gain.to_value(u.electron / u.adu)
    return float(real / (np.sum(counts) / gain))
