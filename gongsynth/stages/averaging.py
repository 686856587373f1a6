"""
GONG's real averaging: one magnetogram per minute, and the average of them.

GONG's cameras write a set of six raw planes every minute (``ITIME = 60``,
``ACCUM = 600`` frames per plane), each minute is reduced to its own
magnetogram and Dopplergram, and the standard "10-minute" product is the mean
of the one-minute maps that passed the quality checks: the Big Bear file of
2009-09-05 18:54 lists ``N_USED = 9`` one-minute images (18:50-18:59 without
18:54; Hill 2018, Space Weather 16, 1488, for the network's products; the
paper, Sec. 3.2, accumulated ten minutes into one set of planes instead).
With ``effects.minute_average`` a run of several minutes does the same: the
camera accumulates each minute on its own (stream ``"camera"`` chunk *i* of the
run's seed, its own dither, truncation and frame seeing), the reduction
reduces each minute, and the magnetogram and Dopplergram are the means of the
minutes'.  The saved raw planes are the sum of the minutes' planes.

Reducing a minute at a time differs from reducing the sum where the phase is
not linear in the planes (noise near a wrap, a phase's noise bias) and, with
frame seeing, by each minute's own image motion.
"""
import dataclasses

import astropy.units as u
import numpy as np

__all__ = ["minutes_in", "sum_planes", "average_observables"]

# Header cards of a raw set that count frames or time: summed over the minutes.
_SUMMED = ("ITIME", "NFRAMES", "ACCUM", "COUNT")


def minutes_in(duration, instrument):
    """
    How many one-minute magnetograms a run of ``duration`` averages (1: reduce the whole run at once).

    Parameters
    ----------
    duration : `~astropy.units.Quantity`
    instrument : `~gongsynth.instruments.base.Instrument`
        An instrument with ``magnetogram_cadence`` (GONG) reduces each
        cadence of a run that holds several whole ones; any other: 1.

    Returns
    -------
    int

    Examples
    --------
    >>> import astropy.units as u
    >>> from gongsynth import GONGInstrument
    >>> minutes_in(9 * u.min, GONGInstrument()), minutes_in(90 * u.s, GONGInstrument())
    (9, 1)
    """
    cadence = getattr(instrument, "magnetogram_cadence", None)
    if cadence is None:
        return 1
    ratio = float((duration / cadence).to_value(u.one))
    n = int(round(ratio))
    return n if n >= 2 and abs(ratio - n) < 1e-9 else 1


def sum_planes(raws):
    """
    The sum of several raw sets of planes (the minutes of a run), with the counting cards summed.

    Parameters
    ----------
    raws : sequence of `~gongsynth.stages.camera.integrate.RawPlanes`
        Same shape, flat and dark.

    Returns
    -------
    `~gongsynth.stages.camera.integrate.RawPlanes`
        ``data`` and ``frames_per_plane`` summed; the first set's header with
        ITIME, NFRAMES, ACCUM, COUNT, NFRAMEn and DITHSUMn summed and
        ``NMINUTES`` (how many sets were reduced one by one).
    """
    first = raws[0]
    header = first.header.copy()
    for key in list(header.keys()):
        if key in _SUMMED or key.startswith(("NFRAME", "DITHSUM")):
            header[key] = sum(r.header[key] for r in raws)
    header["NMINUTES"] = (len(raws), "minutes reduced one by one, maps averaged")
    return dataclasses.replace(first, data=np.sum([r.data for r in raws], axis=0),
                               frames_per_plane=np.sum([r.frames_per_plane for r in raws], axis=0),
                               header=header)


def average_observables(minutes, whole):
    """
    The mean of the minutes' magnetograms and Dopplergrams, with the whole run's continuum.

    Parameters
    ----------
    minutes : iterable of `~gongsynth.instruments.base.Observables`
        One reduction per minute (a generator is summed as it goes: one
        minute's maps held at a time).
    whole : `~gongsynth.instruments.base.Observables`
        The reduction of the summed planes: its continuum (the sum of the
        planes) is kept.

    Returns
    -------
    `~gongsynth.instruments.base.Observables`
        ``magnetogram``, ``doppler``, ``velocity`` and ``phase``-derived
        velocities averaged over the minutes; ``wrapped`` where any minute is.
    """
    names = ("magnetogram", "doppler", "velocity")
    sums, wrapped, count = None, None, 0
    for minute in minutes:
        if sums is None:
            sums = {name: u.Quantity(getattr(minute, name), copy=True) for name in names}
            wrapped = np.array(minute.wrapped, copy=True)
        else:
            for name in names:
                sums[name] += getattr(minute, name)
            wrapped |= minute.wrapped
        count += 1
    if not count:
        raise ValueError("minutes holds no reduction")
    return dataclasses.replace(whole, wrapped=wrapped, **{name: sums[name] / count for name in names})
