"""
The camera's frame schedule: which raw plane each frame is added to, when, with what dither.

Every instrument's ``schedule(duration)`` returns a `FrameSchedule`; the camera
stage (`gongsynth.stages.camera`) takes its frames in that order.
"""
from __future__ import annotations

from dataclasses import dataclass

import astropy.units as u
import numpy as np

from gongsynth.validation import check_finite, check_quantity

__all__ = ["FrameSchedule", "whole_frames"]


def whole_frames(duration, cadence):
    """
    The number of frames in ``duration`` at one frame per ``cadence``, checked.

    Parameters
    ----------
    duration, cadence : `~astropy.units.Quantity`
        Times.

    Returns
    -------
    int

    Raises
    ------
    TypeError, astropy.units.UnitsError, ValueError
        Naming ``duration`` if it is not a finite positive time holding a whole number of frames.

    Examples
    --------
    >>> import astropy.units as u
    >>> whole_frames(45 * u.s, 3.75 * u.s)
    12
    """
    check_quantity(duration, u.s, "duration")
    if np.ndim(duration) != 0:
        raise ValueError(f"duration must be a scalar, got shape {np.shape(duration)}")
    check_finite(duration, "duration")
    if duration <= 0 * u.s:
        raise ValueError(f"duration must be positive, got {duration}")
    frames = (duration / cadence).to_value(u.one)
    n = int(round(frames))
    if abs(frames - n) > 1e-6 * max(1.0, abs(frames)) or n < 1:
        raise ValueError(f"duration must hold a whole number of frames of {cadence}, got {duration} "
                         f"({frames:g} frames)")
    return n


@dataclass(frozen=True, eq=False)
class FrameSchedule:
    """
    What the camera does in every frame of an observation (one entry per frame).

    The camera stage (`gongsynth.stages.camera.integrate`) needs nothing else
    from the instrument's timing: frame *k* is read out, its dither added, and
    it is accumulated onto plane ``plane[k]``.

    Attributes
    ----------
    time : `~astropy.units.Quantity`
        Start of each frame's exposure since the start of the observation, s.
    plane : `numpy.ndarray`
        int64: the raw plane each frame is accumulated onto, 0 … n_planes - 1.
    dither : `~astropy.units.Quantity`
        Whole-adu offset added to each frame after its rounding (zero for an
        instrument without dither), adu.
    n_planes : int
        Number of raw planes K.
    duration : `~astropy.units.Quantity`
        The observation's length, s.
    """

    time: u.Quantity
    plane: np.ndarray
    dither: u.Quantity
    n_planes: int
    duration: u.Quantity

    def __len__(self):
        return self.plane.size

    @property
    def n_frames(self):
        """Number of frames (int)."""
        return self.plane.size

    @property
    def frames_per_plane(self):
        """Number of frames accumulated on each plane, int64 array (n_planes,)."""
        return np.bincount(self.plane, minlength=self.n_planes).astype(np.int64)

    @property
    def dither_sum(self):
        """Sum of the dither over the frames of each plane, int64 array (n_planes,) in adu."""
        d = self.dither.to_value(u.adu).astype(np.int64)
        return np.bincount(self.plane, weights=d, minlength=self.n_planes).round().astype(np.int64)

    @property
    def mean_dither(self):
        """Mean dither per frame of each plane, `~astropy.units.Quantity` (n_planes,) in adu."""
        return (self.dither_sum / np.maximum(self.frames_per_plane, 1)) * u.adu

    @classmethod
    def regular(cls, duration, cadence, n_planes):
        """
        Frames every ``cadence`` cycling through the planes in order, without dither.

        The schedule of an instrument that takes one filtergram of each plane
        in turn (HMI: 12 filtergrams, one every 3.75 s, per 45-s sequence).

        Parameters
        ----------
        duration : `~astropy.units.Quantity`
            Observation length: a whole number of frames (time).
        cadence : `~astropy.units.Quantity`
            Time from one frame to the next (time).
        n_planes : int

        Returns
        -------
        `FrameSchedule`

        Raises
        ------
        ValueError
            Naming ``duration`` when it is not a positive whole number of
            sequences (``n_planes`` frames): an incomplete sequence would give
            some planes one frame more than the others, and the reduction,
            which compares the planes' accumulated counts, would read that
            exposure difference as a line shift.

        Examples
        --------
        >>> import astropy.units as u
        >>> s = FrameSchedule.regular(45 * u.s, 3.75 * u.s, 12)
        >>> s.n_frames, s.frames_per_plane.tolist()[:3], float(s.time[-1].value)
        (12, [1, 1, 1], 41.25)
        """
        n = whole_frames(duration, cadence)
        if n % n_planes:
            sequence = (n_planes * cadence).to(u.s)
            raise ValueError(f"duration must be a whole number of sequences of {n_planes} frames "
                             f"({sequence:g} each), got {duration} ({n / n_planes:.4g} sequences)")
        k = np.arange(n, dtype=np.int64)
        return cls(time=(k * cadence).to(u.s), plane=k % n_planes, dither=np.zeros(n, dtype=np.int64) * u.adu,
                   n_planes=int(n_planes), duration=(n * cadence).to(u.s))

    def header_cards(self):
        """
        Raw-header cards of the instrument's own counters (none here).

        Returns
        -------
        dict
            Key to ``(value, comment)``.
        """
        return {}
