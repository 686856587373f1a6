"""
The GONG magnetogram-mode frame schedule, frame by frame, as data.

The camera takes ``frame_rate`` frames per second (60).  The half-wave plate
turns ``waveplate_step`` (30°) per frame, so frame *k* integrates sector
``k mod 12`` of the turn and channel ``k mod 3`` (the response repeats every
90°, design §4).  The LCVR selects I+V or I-V and flips every ``lcvr_period``
(1 s): polarisation = ⌊t / lcvr_period⌋ mod 2 with t = k / frame_rate.  Frame
*k* is accumulated onto plane ``polarisation * 3 + channel``
(`gongsynth.planes`).

Dither (paper Sec. 3.2, design §3.11): the offset starts at ``dither_start``
(32 ADU).  *Before* frame *k* is recorded, if k is a multiple of
``dither_interval`` (12) the offset changes by +``dither_step`` (2 ADU) when
``k mod dither_cycle < dither_cycle / 2`` (first half of each minute) and by
-``dither_step`` otherwise.  Frame 0 therefore already carries 34 ADU; the
triangle runs 34 … 332 … 32 and repeats exactly every minute with a mean of
182 ADU per frame (starting the steps at frame 12 instead would give 180).
"""
from dataclasses import dataclass

import astropy.units as u
import numpy as np

from gongsynth.instruments.base import FrameSchedule, whole_frames
from gongsynth.instruments.gong.parameters import GONGInstrument, resolve_instrument
from gongsynth.instruments.gong.planes import N_CHANNELS, N_PLANES, N_POLARISATIONS

__all__ = ["FrameSchedule", "GONGFrameSchedule", "frame_schedule", "dither_sequence", "n_frames_in"]


def _whole(value, what):
    """``value`` (a float) as an int, or ValueError if it is not (nearly) whole."""
    n = int(round(value))
    if abs(value - n) > 1e-6 * max(1.0, abs(value)) or n < 1:
        raise ValueError(f"{what} must be a positive whole number, got {value:g}")
    return n


def n_frames_in(duration, instrument=None):
    """
    Number of camera frames in ``duration``.

    Parameters
    ----------
    duration : `~astropy.units.Quantity`
        Observing time (time units).  Must hold a whole number of frames.
    instrument : `~gongsynth.GONGInstrument`, optional

    Returns
    -------
    int

    Examples
    --------
    >>> import astropy.units as u
    >>> n_frames_in(10 * u.min)
    36000
    """
    inst = resolve_instrument(instrument)
    return whole_frames(duration, (1 / inst.frame_rate).to(u.s))


def dither_sequence(n_frames, instrument=None):
    """
    The dither offset added to each frame, in ADU.

    Parameters
    ----------
    n_frames : int
        Number of frames, counted from the start of a minute (frame 0).
    instrument : `~gongsynth.GONGInstrument`, optional
        Supplies ``dither_start``, ``dither_step``, ``dither_interval`` and
        ``dither_cycle``.

    Returns
    -------
    `numpy.ndarray`
        int64, shape (n_frames,): the offset (ADU) carried by each frame.

    Examples
    --------
    >>> d = dither_sequence(3600)
    >>> int(d[0]), int(d[12]), int(d.max()), int(d[-1]), float(d.mean())
    (34, 36, 332, 32, 182.0)
    """
    inst = resolve_instrument(instrument)
    if isinstance(n_frames, bool) or not isinstance(n_frames, (int, np.integer)) or n_frames < 0:
        raise ValueError(f"n_frames must be a non-negative int, got {n_frames!r}")
    if inst.dither_interval < 1 or inst.dither_cycle < 1:
        raise ValueError("instrument.dither_interval and dither_cycle must be >= 1, got "
                         f"{inst.dither_interval} and {inst.dither_cycle}")
    start = _whole_adu(inst.dither_start, "dither_start")
    step = _whole_adu(inst.dither_step, "dither_step")
    frames = np.arange(n_frames, dtype=np.int64)
    step_frames = np.arange(0, n_frames, inst.dither_interval, dtype=np.int64)
    # Rising in the first half of each cycle, falling in the second (design §3.11).
    direction = np.where(2 * (step_frames % inst.dither_cycle) < inst.dither_cycle, 1, -1)
    level = start + step * np.cumsum(direction)
    return level[frames // inst.dither_interval].astype(np.int64)


def _whole_adu(value, name):
    adu = value.to_value(u.adu)
    if adu != round(adu):
        raise ValueError(f"instrument.{name} must be a whole number of ADU, got {value}")
    return int(round(adu))


@dataclass(frozen=True, eq=False)
class GONGFrameSchedule(FrameSchedule):
    """
    GONG's frames: the shared `~gongsynth.instruments.base.FrameSchedule` plus the wave plate and LCVR.

    Attributes
    ----------
    time, plane, dither, n_planes, duration
        As in `~gongsynth.instruments.base.FrameSchedule` (plane =
        ``polarisation * 3 + channel``; dither in adu).
    waveplate_angle : `~astropy.units.Quantity`
        Wave-plate angle at the start of each frame, deg in [0, 360).
    sector : `numpy.ndarray`
        30° sector of the turn, 0-11.
    channel : `numpy.ndarray`
        Channel (sector mod 3), 0-2.
    polarisation : `numpy.ndarray`
        0 = I+V, 1 = I-V (LCVR state).
    instrument : `~gongsynth.GONGInstrument`
        The instrument the schedule was made for.
    """

    waveplate_angle: u.Quantity
    sector: np.ndarray
    channel: np.ndarray
    polarisation: np.ndarray
    instrument: GONGInstrument

    @property
    def accum(self):
        """Frames per polarisation state (GONG's ACCUM keyword: 1800 per minute)."""
        return int(np.count_nonzero(self.polarisation == 0))

    @property
    def waveplate_turns(self):
        """Completed wave-plate turns (GONG's COUNT keyword: 300 per minute)."""
        return int((self.n_frames * self.instrument.waveplate_step / (360 * u.deg)).to_value(u.one))

    def header_cards(self):
        """
        GONG's raw-header counters ACCUM and COUNT.

        Returns
        -------
        dict
        """
        return {"ACCUM": (self.accum, "integrations per image plane (per polarisation)"),
                "COUNT": (self.waveplate_turns, "waveplate index pulses per integration")}


def frame_schedule(duration=1 * u.min, instrument=None):
    """
    The frame-by-frame schedule of a GONG magnetogram-mode observation.

    Parameters
    ----------
    duration : `~astropy.units.Quantity`
        Observing time (time units), a whole number of frames; GONG's product
        is 1 min, the paper's 10 min.
    instrument : `~gongsynth.GONGInstrument`, optional
        Supplies ``frame_rate``, ``waveplate_rate``, ``lcvr_period`` and the
        dither parameters.

    Returns
    -------
    `GONGFrameSchedule`

    Raises
    ------
    ValueError
        If the duration is not positive and whole in frames, or the instrument's
        rates do not give a whole number of frames per 90° of wave plate
        (3 channels) and per LCVR state.

    Examples
    --------
    >>> import astropy.units as u
    >>> s = frame_schedule(1 * u.min)
    >>> s.n_frames, s.frames_per_plane.tolist(), s.accum, s.waveplate_turns
    (3600, [600, 600, 600, 600, 600, 600], 1800, 300)
    >>> s.plane[:6].tolist(), s.plane[60:63].tolist()
    ([0, 1, 2, 0, 1, 2], [3, 4, 5])
    >>> float(s.dither.mean().value)
    182.0
    """
    inst = resolve_instrument(instrument)
    n = n_frames_in(duration, inst)
    if inst.frames_per_sector_cycle != N_CHANNELS:
        raise ValueError(
            f"frame_rate / (4 × waveplate_rate) must be {N_CHANNELS} frames per 90° of wave plate "
            f"(one per channel), got {(inst.frame_rate / (4 * inst.waveplate_rate)).to_value(u.one):g}"
        )
    sectors = _whole((360 * u.deg / inst.waveplate_step).to_value(u.one), "sectors per wave-plate turn")
    per_state = _whole((inst.lcvr_period * inst.frame_rate).to_value(u.one), "frames per LCVR state")
    k = np.arange(n, dtype=np.int64)
    sector = k % sectors
    channel = sector % N_CHANNELS
    polarisation = (k // per_state) % N_POLARISATIONS
    return GONGFrameSchedule(
        time=(k / inst.frame_rate).to(u.s),
        plane=polarisation * N_CHANNELS + channel,
        dither=dither_sequence(n, inst) * u.adu,
        n_planes=N_PLANES,
        duration=(n / inst.frame_rate).to(u.s),
        waveplate_angle=(sector * inst.waveplate_step).to(u.deg),
        sector=sector,
        channel=channel,
        polarisation=polarisation,
        instrument=inst,
    )
