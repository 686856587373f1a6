"""
The SDO/HMI instrument model: every parameter of a simulated HMI in one place.

`HMIInstrument` is a frozen dataclass in the style of `gongsynth.GONGInstrument`:
each physical parameter is an `astropy.units.Quantity` with a default and its
source.  References (full list in the Instruments guide, ``instrument_hmi``):

* Schou et al. 2012, Sol. Phys. 275, 229 (design and ground calibration);
* Couvidat et al. 2012a, Sol. Phys. 275, 285 (wavelength dependence of the
  transmission: front window, blocker, Lyot E1-E5, Michelsons);
* Couvidat et al. 2016, Sol. Phys. 291, 1887 (observables pipeline, MDI-like
  algorithm, look-up tables, K_m);
* Wachter et al. 2012, Sol. Phys. 275, 261 (image quality, cameras);
* Liu et al. 2012, Sol. Phys. 279, 295 (noise of the 45-s and 720-s magnetograms).

Values marked *chosen* are not published (or not found in this work); the
guide says why each was chosen.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import ClassVar

import astropy.constants as const
import astropy.units as u

from gongsynth.instruments.parameters import InstrumentParameters, field_unit, gauss_per_zeeman_velocity
from gongsynth.instruments.parameters import plain_field as _plain
from gongsynth.instruments.parameters import quantity_field as _param

__all__ = ["HMIInstrument", "N_TUNINGS", "N_HMI_PLANES", "TUNING_INDICES", "resolve_hmi"]

#: Tuning positions of the HMI sequence (filtergrams I0..I5).
N_TUNINGS = 6
#: Raw planes of one LOS sequence: (LCP, RCP) x 6 tunings, plane = pol * 6 + tuning.
N_HMI_PLANES = 2 * N_TUNINGS
#: Position of each filtergram in units of the tuning step: I0 is the reddest
#: (+172 mÅ), I5 the bluest (HMI's numbering, Couvidat et al. 2016, Sec. 2).
TUNING_INDICES = (2.5, 1.5, 0.5, -0.5, -1.5, -2.5)

_mA = u.Unit("mAA")  # milli-ångström, HMI's customary unit for tuning and widths


@dataclass(frozen=True, eq=False)
class HMIInstrument(InstrumentParameters):
    """
    Every parameter of the simulated SDO/HMI (line-of-sight observables).

    All physical parameters are `~astropy.units.Quantity` objects; any unit
    convertible to the canonical one is accepted.  The instance is immutable:
    use `replace` to derive a modified instrument.  Each field's source is in
    ``HMIInstrument.source(name)`` and in the Instruments guide.

    Notes
    -----
    One LOS sequence is 12 filtergrams: plane = polarisation × 6 + tuning, with
    polarisation 0 = LCP = I+V and 1 = RCP = I−V (the HMI code's labels) and
    tuning 0..5 = HMI's I0..I5 at +172, +103.2, +34.4, −34.4, −103.2, −172 mÅ.
    `analysers` gives (tuning index, sign of V) per plane.  With gongsynth's
    convention V ≈ −Δλ_B dI/dλ for B_LOS > 0 (toward the observer), the I+V
    profile is red-shifted, so B = (v_LCP − v_RCP) K_m > 0: a positive
    line-of-sight field gives a positive magnetogram (design §3.21).

    Examples
    --------
    >>> import astropy.units as u
    >>> hmi = HMIInstrument()
    >>> hmi.name, hmi.line, hmi.plate_scale
    ('hmi', 'Fe I 617.3', <Quantity 0.504 arcsec>)
    >>> HMIInstrument.from_toml(hmi.to_toml()) == hmi
    True
    >>> hmi.replace(exposure_time=0.1 * u.s).exposure_time
    <Quantity 0.1 s>
    """

    # ---- line and tuning
    line_wavelength: u.Quantity = _param(617.33433, u.nm, "Fe I rest wavelength in air, 6173.3433 A "
                                         "(Schou et al. 2012; Couvidat et al. 2016)")
    lande_g: u.Quantity = _param(2.5, u.one, "Lande factor of the reduction's K_m "
                                 "(Couvidat et al. 2016; HMI pipeline constant)")
    tuning_step: u.Quantity = _param(68.8, _mA, "spacing of the six tuning positions, FSR_NB/2.5 "
                                     "(Schou et al. 2012; Couvidat et al. 2016)")
    # ---- filter elements (FSR at 6173 A; contrast of the cosine modulation)
    nb_fsr: u.Quantity = _param(172.0, _mA, "narrow-band Michelson FSR (Schou et al. 2012)")
    wb_fsr: u.Quantity = _param(344.0, _mA, "wide-band Michelson FSR (Schou et al. 2012)")
    e1_fsr: u.Quantity = _param(695.0, _mA, "tunable Lyot element E1 FSR (Couvidat et al. 2012a)")
    e2_fsr: u.Quantity = _param(1417.0, _mA, "Lyot element E2 FSR (Couvidat et al. 2012a)")
    e3_fsr: u.Quantity = _param(2779.0, _mA, "Lyot element E3 FSR (Couvidat et al. 2012a)")
    e4_fsr: u.Quantity = _param(5682.0, _mA, "Lyot element E4 FSR (Couvidat et al. 2012a)")
    e5_fsr: u.Quantity = _param(11354.0, _mA, "Lyot element E5 FSR (Couvidat et al. 2012a)")
    nb_contrast: u.Quantity = _param(0.977, u.one, "NB Michelson contrast (Couvidat et al. 2012a)")
    wb_contrast: u.Quantity = _param(0.997, u.one, "WB Michelson contrast (Couvidat et al. 2012a)")
    e1_contrast: u.Quantity = _param(0.976, u.one, "E1 contrast at disk centre (Couvidat et al. 2012a)")
    e2_contrast: u.Quantity = _param(0.985, u.one, "E2 contrast at disk centre (Couvidat et al. 2012a)")
    e3_contrast: u.Quantity = _param(0.965, u.one, "E3 contrast at disk centre (Couvidat et al. 2012a)")
    e4_contrast: u.Quantity = _param(0.988, u.one, "E4 contrast at disk centre (Couvidat et al. 2012a)")
    e5_contrast: u.Quantity = _param(0.999, u.one, "E5 contrast at disk centre (Couvidat et al. 2012a)")
    nontunable_phase: u.Quantity = _param(0.0, u.deg, "phase of E2-E5 (chosen: centred on the line)")
    front_window_center: u.Quantity = _param(617.26, u.nm, "front window centre (Couvidat et al. 2012a, "
                                             "measured profile)")
    front_window_fwhm: u.Quantity = _param(4.85, u.nm, "front window FWHM, ~50 A (Schou et al. 2012)")
    front_window_peak: u.Quantity = _param(0.837, u.one, "front window peak transmission "
                                           "(Couvidat et al. 2012a)")
    blocker_center: u.Quantity = _param(617.243, u.nm, "blocker centre (Couvidat et al. 2012a, "
                                        "measured profile with its calibrated shift)")
    blocker_fwhm: u.Quantity = _param(0.843, u.nm, "blocker FWHM, ~8 A (Schou et al. 2012; "
                                      "Couvidat et al. 2012a)")
    blocker_peak: u.Quantity = _param(0.656, u.one, "blocker peak transmission (Couvidat et al. 2012a)")
    integration_half_width: u.Quantity = _param(2.0, u.nm, "filter integration half range "
                                                "(chosen: blocker < 0.3 % beyond)")
    quadrature_step: u.Quantity = _param(0.2, u.pm, "quadrature step (chosen: 86 per NB period)")
    # ---- telescope and detector
    aperture: u.Quantity = _param(14.0, u.cm, "aperture diameter (Schou et al. 2012)")
    plate_scale: u.Quantity = _param(0.504, u.arcsec, "pixel on the sky (Schou et al. 2012)")
    detector_shape: int = _plain(4096, int, "CCD side in pixels (Schou et al. 2012)")
    supersampling: int = _plain(2, int, "resampling factor before binning (chosen: PSF Nyquist-sampled)")
    seeing_fwhm: u.Quantity = _param(0.0, u.arcsec, "no seeing: SDO is in space")
    psf_radius: u.Quantity = _param(60.0, u.arcsec, "PSF kernel truncation radius (chosen: 0.5 % of the "
                                    "Wachter et al. 2012 PSF's light lies beyond)")
    effective_area: u.Quantity = _param(3.29, u.cm**2, "effective area incl. analyser and CCD QE, "
                                        "derived from the counts (gongsynth.instruments.hmi.noise)")
    quantum_efficiency: u.Quantity = _param(1.0, u.one, "CCD QE, folded into effective_area (chosen)")
    gain: u.Quantity = _param(16.0, u.electron / u.adu, "camera gain (chosen, order of Wachter et al. 2012)")
    read_noise: u.Quantity = _param(2.5, u.adu, "read noise, ~40 e- (chosen, negligible vs photon noise)")
    full_well: u.Quantity = _param(2.0e5, u.electron, "full well (chosen)")
    adc_bits: int = _plain(14, int, "ADC bits (chosen)")
    exposure_time: u.Quantity = _param(0.135, u.s, "exposure per filtergram (Schou et al. 2012, nominal)")
    # ---- frame schedule
    frame_interval: u.Quantity = _param(3.75, u.s, "time between filtergrams of the LOS camera "
                                        "(Schou et al. 2012)")
    sequence_cadence: u.Quantity = _param(45.0, u.s, "LOS observables cadence, 12 filtergrams "
                                          "(Schou et al. 2012; Couvidat et al. 2016)")
    vector_cycle: u.Quantity = _param(135.0, u.s, "framelist of the vector camera; 12 of its "
                                      "filtergrams are LCP/RCP (JSOC hmi.M_720s notes)")
    vector_window: u.Quantity = _param(1215.0, u.s, "span of the filtergrams averaged for a 720-s "
                                       "product (JSOC hmi.M_720s notes)")
    vector_cadence: u.Quantity = _param(720.0, u.s, "cadence and FWHM of the 720-s temporal "
                                        "weighting (Couvidat et al. 2016; taper shape chosen)")
    # ---- reduction
    reference_line_depth: u.Quantity = _param(0.661, u.one, "depth of the Gaussian look-up-table "
                                              "line at disk centre (Couvidat et al. 2016)")
    reference_line_fwhm: u.Quantity = _param(92.8, _mA, "FWHM of that line (Couvidat et al. 2016)")
    lut_velocity_max: u.Quantity = _param(9.6, u.km / u.s, "look-up-table range +-9.6 km/s: the "
                                          "+-4444 G cap of real hmi.M_45s data")
    lut_velocity_step: u.Quantity = _param(24.0, u.m / u.s, "look-up-table velocity step "
                                           "(HMI pipeline value)")

    #: The registry key (`gongsynth.instruments.get`) and the line (the radiative-transfer
    #: line registry's key).
    name: ClassVar[str] = "hmi"
    line: ClassVar[str] = "Fe I 617.3"
    #: The name in metadata; the reduction algorithm (`gongsynth.instruments.hmi.observables.reduce_hmi`,
    #: imported by the reduction stage); the camera keeps every bit (no truncation, no dither).
    label: ClassVar[str] = "HMI"
    algorithm: ClassVar[str] = "gongsynth.instruments.hmi.observables:reduce_hmi"
    #: A run's length when none is given: one LOS sequence, the hmi.M_45s magnetogram
    #: (Schou et al. 2012, Sec. 4; the 720-s product is 16 sequences: 12 min).
    default_duration: ClassVar[u.Quantity] = 45 * u.s
    truncate_bits: ClassVar[int] = 0
    #: A tiled run's detector when none is given (chosen): 1024² of the 4096² CCD's pixels.
    #: 1024 × 0.504″ = 516″ (374 Mm at disk centre): each quadrant of the tiled layout holds
    #: about two copies of the default 98-Mm box at 1× and a quarter of it at 8×; the full
    #: CCD would only repeat the box 16 times more at 16 times the optics, camera and
    #: reduction cost (139 s and 9.5 GB for a 10-min run).
    tiled_detector_shape: ClassVar[int] = 1024
    #: The full-disk render's Doppler basis may be reduced while every filtergram stays within this
    #: fraction of its continuum's (`gongsynth.stages.scene.disk_render.render_rows`).  From the photon
    #: noise: a continuum filtergram holds N_e ≈ 1.31e5 electrons
    #: (`gongsynth.instruments.hmi.noise.continuum_electrons`), σ = N_e^-1/2 = 2.77e-3 of it; B and v
    #: are linear in the 12 filtergrams near
    #: the signal, so an error ≤ ε in each moves them by at most √12 ε/σ of their photon noise
    #: (Cauchy-Schwarz): 8e-5 bounds that at 10 % (the actual errors are far smaller).
    render_tolerance: ClassVar[float] = 8e-5
    #: The PSF: Wachter et al. (2012)'s measured core and scattered-light wings
    #: (`gongsynth.instruments.hmi.psf`).
    psf_model: ClassVar[str] = "gongsynth.instruments.hmi.psf:psf_profile"

    def __post_init__(self):
        super().__post_init__()
        for smaller, larger in (("quadrature_step", "integration_half_width"),
                                ("lut_velocity_step", "lut_velocity_max")):
            if getattr(self, smaller) >= getattr(self, larger):
                raise ValueError(f"HMIInstrument.{smaller} ({getattr(self, smaller)}) must be smaller "
                                 f"than {larger} ({getattr(self, larger)})")

    # ------------------------------------------------------------------ derived
    @property
    def tuning_offsets(self):
        """
        Nominal centres of filtergrams I0..I5 relative to the line, `~astropy.units.Quantity`.

        +172, +103.2, +34.4, −34.4, −103.2, −172 mÅ for the defaults (Schou et al. 2012).
        """
        return (self.tuning_step * TUNING_INDICES).to(_mA)

    @property
    def tuning_period(self):
        """Period T = 6 × tuning_step of the Fourier sums, 412.8 mÅ (Couvidat et al. 2016)."""
        return (N_TUNINGS * self.tuning_step).to(_mA)

    @property
    def analysers(self):
        """
        (tuning index, sign of Stokes V) for each of the 12 raw planes.

        Planes 0-5 are LCP = I+V at I0..I5, planes 6-11 RCP = I−V.

        Examples
        --------
        >>> HMIInstrument().analysers[:2], HMIInstrument().analysers[6]
        (((0, 1), (1, 1)), (0, -1))
        """
        return tuple((k, sign) for sign in (1, -1) for k in range(N_TUNINGS))

    @property
    def frames_per_sequence(self):
        """Filtergrams per LOS sequence, 12 = 45 s / 3.75 s."""
        return int(round((self.sequence_cadence / self.frame_interval).to_value(u.one)))

    @property
    def gauss_per_velocity(self):
        """
        K_m: B_LOS = (v_LCP − v_RCP) K_m.

        A field B splits the σ components by Δλ_B = e λ0² g B / (4π m_e c²), i.e.
        by Δv = c Δλ_B / λ0 each, so v_LCP − v_RCP = 2Δv and
        K_m = 4π m_e c / (2 e g λ0) (Couvidat et al. 2016: 1/(2 × 4.67e-5 λ0 g c)).

        Returns
        -------
        `~astropy.units.Quantity`
            In G / (m / s); 0.2314 for g = 2.5 at 617.33 nm.
        """
        return gauss_per_zeeman_velocity(self.line_wavelength, self.lande_g) / 2

    @property
    def velocity_per_wavelength(self):
        """The Doppler velocity per unit wavelength shift, c / λ0, in m/s per mÅ."""
        return (const.c / self.line_wavelength * _mA).to(u.m / u.s) / _mA

    def responses(self, wavelength):
        """
        Transmission of the six tuning positions, `~astropy.units.Quantity` (6, nλ).

        See `gongsynth.instruments.hmi.filters.filtergram_responses`.
        """
        from gongsynth.instruments.hmi.filters import filtergram_responses
        return filtergram_responses(wavelength, self)

    # ------------------------------------------- the family's protocol (gongsynth.instruments.base)
    @property
    def plane_names(self):
        """Short name of each raw plane: ``"LCP I0"`` ... ``"RCP I5"``, tuple of str."""
        return tuple(f"{'LCP' if sign > 0 else 'RCP'} I{k}" for k, sign in self.analysers)

    def schedule(self, duration):
        """
        The LOS camera's frames: one filtergram every ``frame_interval`` (3.75 s), the 12 planes in turn.

        No dither and no truncation.  The real sequence's order of tunings and
        polarisations within the 45 s is not modelled (each plane gets the same
        number of frames, which is all the accumulation needs).

        Parameters
        ----------
        duration : `~astropy.units.Quantity`
            A whole number of filtergrams (45 s: one LOS sequence).

        Returns
        -------
        `~gongsynth.instruments.base.FrameSchedule`
        """
        from gongsynth.instruments.base import FrameSchedule
        return FrameSchedule.regular(duration, self.frame_interval, N_HMI_PLANES)

    @property
    def detector_maps(self):
        """
        The synthetic flat and dark's parameters: GONG's illustrative ones (chosen).

        No HMI flat or dark is modelled; the camera stage applies these
        illustrative maps (or none, with the effects ``flat`` and ``dark`` off).
        """
        from gongsynth.instruments.gong.parameters import GONGInstrument
        return GONGInstrument()

    def header_cards(self):
        """
        The inversion constants every product records: the Landé factor and K_m.

        Returns
        -------
        dict
        """
        return {"landeg": (self.lande_g.to_value(u.one), "Lande factor of K_m"),
                "kmag": (self.gauss_per_velocity.to_value(u.G / (u.m / u.s)),
                         "[G/(m/s)] B = (v_LCP - v_RCP) K_m")}


def resolve_hmi(instrument):
    """The HMI a function should use (`HMIInstrument.resolve`: the default for None, else the one given)."""
    return HMIInstrument.resolve(instrument)


#: Allowed range of each numeric field in its canonical unit ("[" and "]" inclusive);
#: ``nontunable_phase`` may take any value.
_RANGES = {
    **{f.name: "(0, inf)" for f in dataclasses.fields(HMIInstrument)
       if isinstance(field_unit(HMIInstrument, f.name), u.UnitBase)},
    **dict.fromkeys(("seeing_fwhm", "read_noise"), "[0, inf)"),
    **dict.fromkeys(("nb_contrast", "wb_contrast", "e1_contrast", "e2_contrast", "e3_contrast",
                     "e4_contrast", "e5_contrast", "front_window_peak", "blocker_peak",
                     "quantum_efficiency", "reference_line_depth"), "(0, 1]"),
    **dict.fromkeys(("detector_shape", "supersampling"), "[1, inf)"),
    "adc_bits": "[1, 31]",
}
del _RANGES["nontunable_phase"]

HMIInstrument.RANGES = _RANGES
