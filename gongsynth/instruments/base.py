r"""
What every instrument of the family provides, and what they share.

An instrument is *data*: a frozen dataclass of its parameters (Quantities with
their sources) plus a few methods that say what is its own — its line, its
filtergrams, how its camera takes frames, and its reduction algorithm.  The
shared stages (`gongsynth.stages`) never test which instrument they serve;
they ask it, through the `Instrument` protocol below.

The K planes
------------
An instrument records K raw planes.  Plane k is the light of filtergram
``f_k`` (a tuning position or a wave-plate sector, transmission
:math:`R_{f_k}(\lambda)`, `Instrument.responses`) seen through an analyser
that passes :math:`I + s_k V` (`Instrument.analysers` holds the pairs
:math:`(f_k, s_k)`).  With the instrument's Mueller matrix M, the channels
stage (filter first, DESIGN §1) computes

.. math::

    P_k(x, y) = \int R_{f_k}(\lambda)\,\big[(M S)_0 + s_k (M S)_3\big](x, y, \lambda)\,d\lambda .

GONG: 6 planes, k = polarisation × 3 + sector, polarisation 0 = I+V.
HMI: 12 planes, k = polarisation × 6 + tuning, polarisation 0 = LCP = I+V.

The camera asks for a `FrameSchedule` (which plane each frame is added to,
the dither it carries), the reduction for the instrument's algorithm
(`Instrument.algorithm`) after the shared dark and flat correction.  The
algorithm is named by ``"module:function"`` and imported by the reduction
stage: it may live at the reduction's place in the data flow (it returns the
stage's `Observables`) while the instrument's parameters sit early.

The parameter machinery every instrument dataclass inherits
(`InstrumentParameters`, `quantity_field`, `plain_field`) lives in
`gongsynth.instruments.parameters`; it is re-exported here.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import astropy.units as u
import numpy as np

from gongsynth.instruments.frames import FrameSchedule, whole_frames
from gongsynth.instruments.parameters import (
    InstrumentParameters,
    field_unit,
    gauss_per_zeeman_velocity,
    plain_field,
    quantity_field,
)

__all__ = ["Instrument", "InstrumentParameters", "FrameSchedule", "Observables", "quantity_field",
           "plain_field", "field_unit", "whole_frames", "gauss_per_zeeman_velocity"]


@runtime_checkable
class Instrument(Protocol):
    """
    What a shared stage may ask of an instrument (GONG, HMI, MDI).

    Identity and line
        ``name`` (str, the registry key: ``"gong"``), ``label`` (for
        metadata: ``"GONG"``), ``line`` (the key of the line in the
        radiative-transfer line registry: ``"Ni I 676.8"``),
        ``line_wavelength`` (length).
    Optics
        ``aperture`` (length), ``seeing_fwhm`` (angle), ``psf_radius`` (angle),
        ``plate_scale`` (angle per pixel), ``detector_shape`` (int, side in
        pixels), ``supersampling`` (int).
    Photometry and camera
        ``effective_area`` (area), ``quantum_efficiency``, ``gain``
        (electron/adu), ``read_noise`` (adu), ``exposure_time`` (time of
        one frame), ``truncate_bits`` (int: low bits dropped after
        accumulation; 0 where none are), and ``detector_maps``: an object
        holding the synthetic flat and dark knobs read by
        `gongsynth.stages.camera.detector` (``detector_map_seed``, ``flat_*``,
        ``dark_*``; GONG: itself).
    Filtergrams
        ``responses(wavelength)`` → dimensionless (n_filtergrams, nλ)
        transmissions; ``integration_half_width`` and ``quadrature_step``
        (length): the window λ0 ± half width and step of the fine quadrature
        on which they are integrated against a spectrum
        (`gongsynth.instruments.quadrature`); ``analysers``: one
        ``(filtergram index, sign of Stokes V)`` pair per raw plane;
        ``plane_names``: a short name per plane.
    Schedule
        ``schedule(duration)`` → `FrameSchedule`: the plane of every frame,
        the dither it carries (zero where there is none); it raises
        ValueError naming ``duration`` when the duration is not a whole
        number of the instrument's frames (or, for an instrument that
        cycles through its planes, of its sequences).
        ``default_duration`` (time): the length of a run that names none
        (the instrument's standard product).
    Reduction
        ``algorithm``: ``"package.module:function"`` of
        ``function(planes, instrument, **options)`` → `Observables` from the
        dark- and flat-corrected planes (K, ...) (GONG:
        ``"gongsynth.instruments.gong.reduction:three_phase"``; HMI:
        ``reduce_hmi``); ``gauss_per_velocity`` (G per m/s);
        ``header_cards()`` → dict of FITS cards (≤ 8 characters: ``(value,
        comment)``) that record the instrument's own inversion constants in
        every product.
    Parameter machinery
        ``replace(**changes)``, ``to_dict()``, ``toml_table()`` and the class
        method ``from_dict(mapping)`` (`InstrumentParameters` provides them).
    """

    name: str
    label: str
    line: str
    line_wavelength: u.Quantity
    aperture: u.Quantity
    seeing_fwhm: u.Quantity
    plate_scale: u.Quantity
    detector_shape: int
    supersampling: int
    effective_area: u.Quantity
    quantum_efficiency: u.Quantity
    gain: u.Quantity
    read_noise: u.Quantity
    exposure_time: u.Quantity
    truncate_bits: int
    detector_maps: object
    analysers: tuple
    plane_names: tuple
    algorithm: str
    gauss_per_velocity: u.Quantity
    default_duration: u.Quantity

    def responses(self, wavelength):
        """(n_filtergrams, nλ) dimensionless transmissions at ``wavelength``."""

    def schedule(self, duration):
        """The `FrameSchedule` of an observation of ``duration``."""

    def header_cards(self):
        """FITS cards of the instrument's inversion constants."""


@dataclass(frozen=True)
class Observables:
    """
    What an instrument's reduction measures in each pixel.

    Attributes
    ----------
    magnetogram : `~astropy.units.Quantity`
        Line-of-sight flux density B_LOS, in G.
    doppler : `~astropy.units.Quantity`
        Line-of-sight velocity (positive = redshift, away from the observer), in m/s.
    continuum : `~astropy.units.Quantity`
        (Pseudo-)continuum of the dark- and flat-corrected planes, in DN (adu).
    velocity : `~astropy.units.Quantity`
        Shape (2, ...): velocities of the two polarisation states (I+V, I-V), in m/s.
    phase : `~astropy.units.Quantity`
        Shape (2, ...): measured phases of the two states, in rad.
    wrapped : `numpy.ndarray` of bool
        True where a measurement may have wrapped or saturated (design §3.5).
    """

    magnetogram: u.Quantity
    doppler: u.Quantity
    continuum: u.Quantity
    velocity: u.Quantity
    phase: u.Quantity
    wrapped: np.ndarray
