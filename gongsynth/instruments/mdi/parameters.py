"""
The SOHO/MDI instrument model: every parameter of a simulated MDI in one place.

`MDIInstrument` is a frozen dataclass on the family's shared parameter
machinery (`gongsynth.instruments.base.InstrumentParameters`), like
`gongsynth.GONGInstrument`: each physical parameter is an
`astropy.units.Quantity` with a default and its source.  References (full
list in the guide page ``instrument_mdi``):

* Scherrer et al. 1995, Sol. Phys. 162, 129 (the instrument: line, filters,
  Michelsons, CCD, observables);
* SOI technical note SOI-TN-132 (Hoeksema 1996): the onboard continuum
  estimate, the 15-s F0-F4 pass and the counts and shot noise of a filtergram;
* the SOI ``ipvcalc`` manual page: the nominal tuning positions of F1-F4 and
  the onboard velocity from Sa = F1 - F3 and Sc = F2 - F4;
* Liu & Hoeksema (SHINE 2008, "MDI Level 1.8 magnetograms"): the ratio α and
  its branch rule;
* the MDI team's level-1.8 page (soi.stanford.edu/magnetic/Lev1.8, 2007): the
  recalibration of the archive's magnetograms (Tran et al. 2005, ApJS 156, 295).

Values marked *chosen* are not published in the documents read for this
model; the guide says why each was chosen.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import astropy.constants as const
import astropy.units as u

from gongsynth.instruments.base import InstrumentParameters
from gongsynth.instruments.base import plain_field as _plain
from gongsynth.instruments.base import quantity_field as _param

__all__ = ["MDIInstrument", "N_TUNINGS", "N_MDI_PLANES", "TUNING_INDICES", "LEVELS", "resolve_mdi"]

#: Filtergrams of one polarisation: F0 (near the continuum) and F1-F4 across the line.
N_TUNINGS = 5
#: Raw planes: (LCP, RCP) x F0..F4, plane = polarisation * 5 + filtergram.
N_MDI_PLANES = 2 * N_TUNINGS
#: Position of F0..F4 in units of the tuning step: F1 the bluest, F4 the reddest
#: (nominal -120, -40, +40, +120 mÅ, SOI ``ipvcalc``); F0 half a period of the
#: wide Michelson away, where its two transmission peaks sit at ±189 mÅ in the wings.
TUNING_INDICES = (2.5, -1.5, -0.5, 0.5, 1.5)
#: Archive levels: "1.5" the onboard magnetogram as downlinked, "1.8" with the
#: level-1.8.2 recalibration factor (soi.stanford.edu/magnetic/Lev1.8).
LEVELS = ("1.5", "1.8")

_mA = u.Unit("mAA")  # milli-ångström, the customary unit of MDI's tuning and widths


@dataclass(frozen=True, eq=False)
class MDIInstrument(InstrumentParameters):
    """
    Every parameter of the simulated SOHO/MDI (full-disk line-of-sight magnetograms).

    All physical parameters are `~astropy.units.Quantity` objects; any unit
    convertible to the canonical one is accepted.  The instance is immutable:
    use `replace` to derive a modified instrument.  Each field's source is in
    ``MDIInstrument.source(name)`` and in the guide page ``instrument_mdi``.

    Notes
    -----
    One magnetogram minute is 20 filtergrams, one every 3 s: four 15-s passes
    F0..F4, alternately in LCP and RCP.  Raw plane = polarisation × 5 +
    filtergram, polarisation 0 = LCP = I+V; filtergram 0..4 = F0..F4 at +189,
    −113.4, −37.8, +37.8, +113.4 mÅ (F0's twin peak at −189 mÅ transmits as
    much).  With gongsynth's V ≈ −Δλ_B dI/dλ for B_LOS > 0 the I+V profile is
    red-shifted, so B = (v_LCP − v_RCP) K_m > 0 for a field toward the
    observer (design §3.21).  A run of n minutes is the average of n
    one-minute magnetograms; the archive's 96-minute product is n = 5.

    Examples
    --------
    >>> import astropy.units as u
    >>> mdi = MDIInstrument()
    >>> mdi.name, mdi.line, mdi.plate_scale, mdi.default_duration
    ('mdi', 'Ni I 676.8', <Quantity 1.986 arcsec>, <Quantity 1. min>)
    >>> [round(float(d), 1) for d in mdi.tuning_offsets.value]
    [189.0, -113.4, -37.8, 37.8, 113.4]
    >>> MDIInstrument.from_toml(mdi.to_toml()) == mdi
    True
    """

    # ---- line and tuning
    line_wavelength: u.Quantity = _param(676.78, u.nm, "Ni I rest wavelength in air, 6767.8 A "
                                         "(Scherrer et al. 1995)")
    lande_g: u.Quantity = _param(1.5, u.one, "Lande factor of the onboard K_m: GONG's Ni I 676.8 value "
                                 "(GONG paper Eq. 9); MDI's constant not found, chosen the same")
    tuning_step: u.Quantity = _param(75.6, _mA, "spacing of F1-F4, FSR_narrow / 2.5: F1-F4 at -113.4, "
                                     "-37.8, +37.8, +113.4 mA (Scherrer et al. 1995; ipvcalc +-40, +-120)")
    nb_fsr: u.Quantity = _param(189.0, _mA, "narrow Michelson free spectral range (Scherrer et al. 1995)")
    wb_fsr: u.Quantity = _param(377.0, _mA, "wide Michelson free spectral range (Scherrer et al. 1995)")
    nb_contrast: u.Quantity = _param(1.0, u.one, "narrow Michelson contrast (chosen: ideal)")
    wb_contrast: u.Quantity = _param(1.0, u.one, "wide Michelson contrast (chosen: ideal)")
    lyot_fwhm: u.Quantity = _param(465.0, _mA, "Lyot filter FWHM (Scherrer et al. 1995)")
    lyot_elements: int = _plain(5, int, "Lyot elements, FSR doubling from the narrowest (chosen: the "
                                "blocker holds the next order below 0.5 %)")
    blocker_fwhm: u.Quantity = _param(0.8, u.nm, "blocking filter FWHM, 8 A (Scherrer et al. 1995)")
    front_window_fwhm: u.Quantity = _param(5.0, u.nm, "front window FWHM, 50 A (chosen: as HMI's, "
                                           "Schou et al. 2012)")
    integration_half_width: u.Quantity = _param(2.5, u.nm, "filter integration half range (chosen: "
                                                "beyond the Lyot's next order at +-1.7 nm)")
    quadrature_step: u.Quantity = _param(0.2, u.pm, "quadrature step (chosen: 94 per narrow "
                                         "Michelson period)")
    # ---- telescope and detector
    aperture: u.Quantity = _param(12.5, u.cm, "aperture diameter (Scherrer et al. 1995)")
    plate_scale: u.Quantity = _param(1.986, u.arcsec, "full-disk pixel, nominally 2 arcsec (Scherrer "
                                     "et al. 1995); 1.986 in real lev1.8 files (CDELT, shared/data/real)")
    detector_shape: int = _plain(1024, int, "CCD side in pixels (Scherrer et al. 1995)")
    supersampling: int = _plain(4, int, "resampling factor before binning (chosen: 0.5-arcsec "
                                "sub-pixels Nyquist-sample the 12.5-cm PSF)")
    seeing_fwhm: u.Quantity = _param(0.0, u.arcsec, "no seeing: SOHO is in space")
    psf_radius: u.Quantity = _param(20.0, u.arcsec, "PSF kernel truncation radius (chosen: 18 lambda/D)")
    effective_area: u.Quantity = _param(0.0607, u.cm**2, "effective area incl. filters and CCD QE, "
                                        "derived from the counts of SOI-TN-132 "
                                        "(gongsynth.instruments.mdi.noise)")
    quantum_efficiency: u.Quantity = _param(1.0, u.one, "CCD QE, folded into effective_area (chosen)")
    gain: u.Quantity = _param(100.0, u.electron / u.adu, "camera gain: 3000-DN filtergrams with 5.48 DN "
                              "shot noise (SOI-TN-132)")
    read_noise: u.Quantity = _param(1.0, u.adu, "read noise, 100 e- (chosen: negligible vs "
                                "photon noise; the blocks camera engine needs >= 1 adu)")
    exposure_time: u.Quantity = _param(0.4, u.s, "exposure per filtergram (chosen; the counts fix "
                                       "the photon budget, not this)")
    # ---- frame schedule
    frame_interval: u.Quantity = _param(3.0, u.s, "time between filtergrams: F0-F4 every 15 s "
                                        "(SOI-TN-132), 20 per minute (Scherrer et al. 1995)")
    magnetogram_cadence: u.Quantity = _param(1.0, u.min, "one magnetogram per minute: two LCP and two "
                                             "RCP passes (Scherrer et al. 1995; pass order chosen)")
    # ---- reduction
    reference_line_depth: u.Quantity = _param(0.6, u.one, "depth of the Gaussian look-up-table line: "
                                              "Ni I at disk centre (design 3.4, as GONG's)")
    reference_line_fwhm: u.Quantity = _param(100.0, _mA, "FWHM of that line (design 3.4, as GONG's)")
    lut_velocity_max: u.Quantity = _param(9.0, u.km / u.s, "look-up-table span searched for its "
                                          "monotonic branch (chosen)")
    lut_velocity_step: u.Quantity = _param(10.0, u.m / u.s, "look-up-table velocity step (chosen)")
    level: str = _plain("1.8", str, "archive level: '1.8' applies the recalibration factor, '1.5' is "
                        "the onboard magnetogram (soi.stanford.edu/magnetic/Lev1.8)")
    recalibration_factor: u.Quantity = _param(1.7, u.one, "level-1.8.2 factor: values 'increased by "
                                              "approximately 1.7' (MDI Lev1.8 page, 2007; Tran et al. 2005)")

    #: The registry key (`gongsynth.instruments.get`), the name in metadata and the line.
    name: ClassVar[str] = "mdi"
    label: ClassVar[str] = "MDI"
    line: ClassVar[str] = "Ni I 676.8"
    #: MDI's onboard ratio algorithm (`gongsynth.instruments.mdi.observables.reduce_mdi`).
    algorithm: ClassVar[str] = "gongsynth.instruments.mdi.observables:reduce_mdi"
    #: The camera keeps every bit: no truncation, no dither.
    truncate_bits: ClassVar[int] = 0

    def __post_init__(self):
        super().__post_init__()
        if self.level not in LEVELS:
            raise ValueError(f"MDIInstrument.level must be one of {LEVELS}, got {self.level!r}")
        if self.quadrature_step >= self.integration_half_width:
            raise ValueError(f"MDIInstrument.quadrature_step ({self.quadrature_step}) must be smaller "
                             f"than integration_half_width ({self.integration_half_width})")
        if self.lut_velocity_step >= self.lut_velocity_max:
            raise ValueError(f"MDIInstrument.lut_velocity_step ({self.lut_velocity_step}) must be "
                             f"smaller than lut_velocity_max ({self.lut_velocity_max})")
        per_minute = (self.magnetogram_cadence / self.frame_interval).to_value(u.one)
        if abs(per_minute - round(per_minute)) > 1e-9 or round(per_minute) % (2 * N_TUNINGS):
            raise ValueError(f"MDIInstrument.magnetogram_cadence ({self.magnetogram_cadence}) must hold a "
                             f"whole number of LCP+RCP passes of {2 * N_TUNINGS} filtergrams every "
                             f"frame_interval ({self.frame_interval})")

    # ------------------------------------------------------------------ derived
    @property
    def tuning_offsets(self):
        """
        Nominal centres of F0..F4 relative to the line, `~astropy.units.Quantity` in mÅ.

        +189, −113.4, −37.8, +37.8, +113.4 mÅ for the defaults.
        """
        return (self.tuning_step * TUNING_INDICES).to(_mA)

    @property
    def default_duration(self):
        """A run's length when it names none: one magnetogram (1 min; the 96-minute product is 5)."""
        return self.magnetogram_cadence

    @property
    def frames_per_magnetogram(self):
        """Filtergrams per magnetogram, 20 = 1 min / 3 s."""
        return int(round((self.magnetogram_cadence / self.frame_interval).to_value(u.one)))

    @property
    def analysers(self):
        """
        (filtergram index, sign of Stokes V) for each of the 10 raw planes.

        Planes 0-4 are LCP = I+V at F0..F4, planes 5-9 RCP = I−V.

        Examples
        --------
        >>> MDIInstrument().analysers[:2], MDIInstrument().analysers[5]
        (((0, 1), (1, 1)), (0, -1))
        """
        return tuple((k, sign) for sign in (1, -1) for k in range(N_TUNINGS))

    @property
    def plane_names(self):
        """Short name of each raw plane: ``"LCP F0"`` ... ``"RCP F4"``, tuple of str."""
        return tuple(f"{'LCP' if sign > 0 else 'RCP'} F{k}" for k, sign in self.analysers)

    @property
    def gauss_per_velocity(self):
        """
        K_m of the onboard magnetogram: B = (v_LCP − v_RCP) K_m (level 1.5, before recalibration).

        K_m = 4π m_e c / (2 e g λ0): the σ components move by ±c Δλ_B / λ0.

        Returns
        -------
        `~astropy.units.Quantity`
            In G / (m / s); 0.3519 for g = 1.5 at 676.78 nm (half GONG's 0.7038,
            which multiplies the half difference).
        """
        m_e = const.m_e.cgs.value
        c = const.c.cgs.value
        e = const.e.gauss.value
        per_cm_s = 4 * math.pi * m_e * c / (2 * e * self.lande_g.to_value(u.one)
                                           * self.line_wavelength.to_value(u.cm))
        return (per_cm_s * 100) * u.G / (u.m / u.s)

    @property
    def archive_factor(self):
        """The archive's factor on the onboard magnetogram: ``recalibration_factor`` at level 1.8, else 1."""
        return float(self.recalibration_factor.to_value(u.one)) if self.level == "1.8" else 1.0

    @property
    def velocity_per_wavelength(self):
        """The Doppler velocity per unit wavelength shift, c / λ0, in m/s per mÅ."""
        return (const.c / self.line_wavelength * _mA).to(u.m / u.s) / _mA

    def responses(self, wavelength):
        """
        Transmission of F0..F4, `~astropy.units.Quantity` (5, nλ).

        See `gongsynth.instruments.mdi.filters.filtergram_responses`.
        """
        from gongsynth.instruments.mdi.filters import filtergram_responses
        return filtergram_responses(wavelength, self)

    def schedule(self, duration):
        """
        The camera's frames: one filtergram every 3 s, F0..F4 in LCP, then in RCP, twice a minute.

        Parameters
        ----------
        duration : `~astropy.units.Quantity`
            A whole number of magnetograms (minutes): every plane then gets
            the same number of frames.

        Returns
        -------
        `~gongsynth.instruments.frames.FrameSchedule`

        Raises
        ------
        ValueError
            Naming ``duration`` when it is not a whole number of magnetograms.

        Examples
        --------
        >>> import astropy.units as u
        >>> s = MDIInstrument().schedule(1 * u.min)
        >>> s.n_frames, s.frames_per_plane.tolist(), s.plane[:11].tolist()
        (20, [2, 2, 2, 2, 2, 2, 2, 2, 2, 2], [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 0])
        """
        from gongsynth.instruments.frames import FrameSchedule, whole_frames
        n = whole_frames(duration, self.frame_interval)
        per = self.frames_per_magnetogram
        if n % per:
            raise ValueError(f"duration must be a whole number of {self.magnetogram_cadence} MDI "
                             f"magnetograms ({per} filtergrams each), got {duration} ({n / per:g} "
                             f"magnetograms): an incomplete one would give some planes more frames")
        # A 15-s pass takes F0..F4 in one polarisation, LCP and RCP passes alternate: frame k
        # goes to plane k mod 10, the planes in turn.
        return FrameSchedule.regular(duration, self.frame_interval, N_MDI_PLANES)

    @property
    def detector_maps(self):
        """
        The synthetic flat and dark's parameters: GONG's illustrative ones (chosen).

        No MDI flat or dark is modelled; the camera stage applies these
        illustrative maps (or none, with the effects ``flat`` and ``dark`` off).
        """
        from gongsynth.instruments.gong.parameters import GONGInstrument
        return GONGInstrument()

    def header_cards(self):
        """
        The inversion constants every product records: Landé factor, K_m, archive level and factor.

        Returns
        -------
        dict
        """
        return {"landeg": (self.lande_g.to_value(u.one), "Lande factor of K_m"),
                "kmag": (self.gauss_per_velocity.to_value(u.G / (u.m / u.s)),
                         "[G/(m/s)] B = (v_LCP - v_RCP) K_m onboard"),
                "mdilevel": (self.level, "MDI archive level modelled (1.5 or 1.8)"),
                "recalfac": (self.archive_factor, "factor applied to the onboard B")}


def resolve_mdi(instrument):
    """The MDI a function should use (`MDIInstrument.resolve`: the default for None, else the one given)."""
    return MDIInstrument.resolve(instrument)


#: Allowed range of each numeric field in its canonical unit.
MDIInstrument.RANGES = {
    **dict.fromkeys(("line_wavelength", "tuning_step", "nb_fsr", "wb_fsr", "lyot_fwhm", "blocker_fwhm",
                     "front_window_fwhm", "integration_half_width", "quadrature_step", "aperture",
                     "plate_scale", "psf_radius", "effective_area", "gain", "exposure_time",
                     "frame_interval", "magnetogram_cadence", "reference_line_fwhm", "lut_velocity_max",
                     "lut_velocity_step", "recalibration_factor"), "(0, inf)"),
    **dict.fromkeys(("seeing_fwhm", "read_noise"), "[0, inf)"),
    **dict.fromkeys(("nb_contrast", "wb_contrast", "quantum_efficiency", "reference_line_depth"), "(0, 1]"),
    **dict.fromkeys(("detector_shape", "supersampling"), "[1, inf)"),
    "lyot_elements": "[1, 12]",
    "lande_g": "(0, 4]",
}
