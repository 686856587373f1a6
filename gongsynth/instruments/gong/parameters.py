"""
The GONG instrument model: every parameter of GONG in one place.

`GONGInstrument` is a frozen dataclass.  Each physical parameter is an
`astropy.units.Quantity` whose default is the value given in Plowman & Berger,
"Calibrating GONG Magnetograms with End-to-end Instrument Simulation I"
(the *paper*), or, where the paper is ambiguous or wrong, the value decided in
the project's design notes (the *design*, section "Physics decisions").  No
other module of gongsynth holds an instrument parameter of its own.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import astropy.constants as const
import astropy.units as u

from gongsynth.instruments.gong.ucor import INTERPOLANTS
from gongsynth.instruments.parameters import InstrumentParameters, gauss_per_zeeman_velocity
from gongsynth.instruments.parameters import plain_field as _plain
from gongsynth.instruments.parameters import quantity_field as _param

__all__ = ["GONGInstrument", "PREFILTER_FORMS", "SEEING_PROFILES", "resolve_instrument"]

#: Accepted values of `GONGInstrument.prefilter_form`.
PREFILTER_FORMS = ("memo", "ideal")
#: Accepted values of `GONGInstrument.seeing_profile` (`gongsynth.stages.psf`).
SEEING_PROFILES = ("gaussian", "kolmogorov")


@dataclass(frozen=True, eq=False)
class GONGInstrument(InstrumentParameters):
    """
    Every parameter of the simulated GONG magnetograph.

    All physical parameters are `~astropy.units.Quantity` objects; any unit
    convertible to the canonical one is accepted and stored as given.  The
    instance is immutable: use `replace` to derive a modified instrument.

    Parameters
    ----------
    line_wavelength : `~astropy.units.Quantity`, length
        Rest wavelength of Ni I 676.78 nm (paper, Sec. 2).
    lande_g : `~astropy.units.Quantity`, dimensionless
        Effective Landé factor used in the inversion, 1.5 (paper, Eq. 9;
        the literature value is 1.426, Bruls 1993).
    prefilter_center : `~astropy.units.Quantity`, length
        Centre of the interference prefilter, 676.78 nm (paper, Sec. 2).
    prefilter_fwhm : `~astropy.units.Quantity`, length
        Width parameter w_p of the prefilter, 0.5 nm (paper, Eqs. 1-2).
    prefilter_form : str
        ``"memo"`` (default): the GONG-memo form
        [1 + 1.6569((λ-λ0)/w_p)²]⁻² (paper, Eq. 2);
        ``"ideal"``: [1 + ((λ-λ0)/(w_p/2))⁴]⁻¹, the intended FWHM = w_p form of
        the paper's Eq. 1 (design §3.7; as printed, (2w_p)⁴ has a 2 nm FWHM).
    lyot_delta_h : `~astropy.units.Quantity`, length
        Lyot thickness parameter Δh = 608 µm (paper, Eq. 3).
    lyot_angle_1, lyot_angle_2, lyot_angle_3 : `~astropy.units.Quantity`, angle
        Element angles θ_k in cos²(2^(k-1) πΔh/λ - θ_k): 67.7°, -45.3°, 93°.
        The paper prints θ_2 = +45.3°, which puts a transmission null on the
        line; -45.3° is the working tuning (design §3.3).
    michelson_fsr : `~astropy.units.Quantity`, length
        Free spectral range Δλ_m of the Michelson, 0.305 Å (paper, Eq. 4).
    michelson_angle : `~astropy.units.Quantity`, angle
        Michelson phase offset θ_m = 8.2° (paper, Eq. 4).
    waveplate_rate : `~astropy.units.Quantity`, frequency
        Rotation rate of the half-wave plate, 5 Hz (paper, Sec. 2).
    frame_rate : `~astropy.units.Quantity`, frequency
        Camera frame rate, 60 frames per second (paper, Sec. 2).
    exposure_time : `~astropy.units.Quantity`, time
        Exposure of one frame, 1/60 s (paper, Sec. 3.2).
    lcvr_period : `~astropy.units.Quantity`, time
        Time between LCVR switches I+V ↔ I-V, 1 s (paper, Sec. 2).
    aperture : `~astropy.units.Quantity`, length
        Effective aperture diameter D = 2.8 cm (paper, Sec. 2).
    plate_scale : `~astropy.units.Quantity`, angle
        Detector pixel size on the sky, 2.5 arcsec (paper, Sec. 2).  Real GONG
        files differ by site: 2.561″ (Big Bear, 2009: disk radius 371.7 px)
        and 2.533″ (Learmonth, 2025); a run ``like`` a real file takes that
        file's (`gongsynth.observing.like_gong`).
    detector_shape : int
        Detector side in pixels, 860 (GONG full-disk images are 860 × 860).
    supersampling : int
        Resampling factor before binning to GONG pixels, 5 (paper, Sec. 3.2).
    seeing_fwhm : `~astropy.units.Quantity`, angle
        FWHM of the seeing kernel, 3.6 arcsec (paper, Sec. 3.2).
    seeing_profile : str
        Its shape (`gongsynth.stages.psf`): ``"gaussian"`` (the paper's), or
        ``"kolmogorov"``, the long-exposure seeing of Kolmogorov turbulence
        (Fried 1966), whose wings are heavier for the same FWHM.
    seeing_wind_speed : `~astropy.units.Quantity`, speed
        Frame-to-frame seeing (`gongsynth.stages.seeing`): speed of the
        turbulence that moves the image, 5 m/s (a choice: a typical near-ground
        daytime wind; Big Bear's header of 2009-09-05 reads 3.3 m/s).
    seeing_outer_scale : `~astropy.units.Quantity`, length
        Frame-to-frame seeing: the turbulence's outer scale L0, 20 m (median of
        the GSM campaigns, Ziad et al. 2004, Appl. Opt. 43, 2316).
    seeing_layer_height : `~astropy.units.Quantity`, length
        Frame-to-frame seeing: effective height of the turbulence, 100 m (a
        choice: daytime seeing comes mostly from the lowest few hundred
        metres, Kellerer et al. 2012, A&A 542, A2); the image moves coherently
        over aperture / height (58″).  0: the whole image moves together.
    magnetogram_cadence : `~astropy.units.Quantity`, time
        GONG reduces one magnetogram per minute (``ITIME = 60``) and its
        standard product averages them (``N_USED = 9`` one-minute images in
        the Big Bear file of 2009-09-05; Hill 2018, Space Weather 16, 1488):
        with ``effects.minute_average`` a run longer than this is reduced
        minute by minute and the magnetograms and Dopplergrams averaged.
    image_rotation_angle : `~astropy.units.Quantity`, angle
        GONG's reduction turns every one-minute image by the image rotator's
        angle (`gongsynth.instruments.gong.ucor`, ``effects.image_rotation``):
        1.785431° (``GHIST``: UCOR ``rot=1.785431`` = −``ROTATOR`` of the Big
        Bear file of 2009-09-05; ``like`` takes the file's ``ROTATOR``).
    image_interpolant : str
        Its interpolant: ``"poly5"`` (the header's ``interp=4`` read as IRAF's
        biquintic polynomial, a reading), ``"poly3"`` or ``"linear"``.
    effective_area : `~astropy.units.Quantity`, area
        Effective collecting area, 0.6 cm² (paper, Sec. 3.2).
    quantum_efficiency : `~astropy.units.Quantity`, dimensionless
        CCD quantum efficiency, 0.16 (paper, Sec. 3.2).
    gain : `~astropy.units.Quantity`, electron / adu
        ADU conversion factor, 33 e⁻/ADU (paper, Sec. 3.2).
    read_noise : `~astropy.units.Quantity`, adu
        Gaussian read noise per frame, 4.8 ADU (paper, Sec. 3.2).
    dither_start : `~astropy.units.Quantity`, adu
        Initial dither offset, 32 ADU (paper, Sec. 3.2).
    dither_step : `~astropy.units.Quantity`, adu
        Dither increment, 2 ADU (paper, Sec. 3.2).
    dither_interval : int
        The dither changes on every frame whose number is a multiple of this,
        12 (paper, Sec. 3.2).
    dither_cycle : int
        Frames in one dither triangle (one minute at 60 fps), 3600; the dither
        rises in the first half and falls in the second (design §3.11).
    truncate_bits : int
        Lowest bits dropped after accumulation, 3 (paper, Sec. 3.2).
    v0 : `~astropy.units.Quantity`, velocity / angle
        Doppler velocity per radian of GONG phase, 2151.86 m/s/rad (paper,
        Eq. 5; c Δλ_m / (2π λ0) with c = 3e8 m/s, design §3.6).
    integration_half_width : `~astropy.units.Quantity`, length
        Half width of the wavelength range over which the filter chain is
        integrated, 3 nm (design §3.8: Lyot side orders at ±0.75 and ±1.5 nm).
    quadrature_step : `~astropy.units.Quantity`, length
        Wavelength step of the filter-chain quadrature, 0.1 pm (300 points per
        Michelson period).
    reference_line_fwhm : `~astropy.units.Quantity`, length
        FWHM of the Gaussian rest line used to fix the Michelson zero point,
        10 pm (the solar Ni I line at disk centre, design §3.4).
    reference_line_depth : `~astropy.units.Quantity`, dimensionless
        Central depth of that line relative to the continuum, 0.6.
    psf_radius : `~astropy.units.Quantity`, angle
        Truncation radius of the PSF kernel, 100 arcsec: the Airy pattern
        encloses 1 - 2/(π² ν_c r) ≈ 99 % of its energy within it
        (`gongsynth.stages.psf.psf_kernel`).
    detector_map_seed : int
        Seed of the synthetic flat and dark, 20190601 (fixed, so that the
        camera and the reduction see the same maps).
    flat_tilt : `~astropy.units.Quantity`, dimensionless
        Synthetic flat: peak-to-centre amplitude of the linear gradient, 0.03.
    flat_vignetting : `~astropy.units.Quantity`, dimensionless
        Synthetic flat: fractional darkening in the corners, 0.04.
    flat_dust_density : `~astropy.units.Quantity`, 1 / Mpix
        Synthetic flat: mean number of dust shadows per million pixels, 40
        (≈ 30 on 860 × 860).
    flat_dust_depth_min, flat_dust_depth_max : `~astropy.units.Quantity`, dimensionless
        Synthetic flat: range of the dust shadows' central depths, 0.01 to 0.05
        (drawn uniformly).
    flat_dust_radius_min, flat_dust_radius_max : `~astropy.units.Quantity`, pix
        Synthetic flat: range of the dust shadows' radii, 3 to 12 pixels
        (drawn uniformly).
    flat_prnu : `~astropy.units.Quantity`, dimensionless
        Synthetic flat: RMS pixel response non-uniformity, 0.01.
    dark_level : `~astropy.units.Quantity`, electron
        Synthetic dark: typical dark current per frame, 30 e⁻ (≈ 0.9 ADU per
        1/60 s frame; illustrative, not a measured GONG value).
    dark_glow : `~astropy.units.Quantity`, dimensionless
        Synthetic dark: amplifier-glow amplitude relative to ``dark_level`` in
        the glowing corner, 0.2.
    dark_glow_length : `~astropy.units.Quantity`, dimensionless
        Synthetic dark: e-folding length of the glow in units of the detector
        side, 0.25.
    dark_hot_fraction : `~astropy.units.Quantity`, dimensionless
        Synthetic dark: fraction of hot pixels, 0.001.
    dark_hot_factor : `~astropy.units.Quantity`, dimensionless
        Synthetic dark: dark current of a hot pixel in units of ``dark_level``, 10.
    wrap_margin : `~astropy.units.Quantity`, angle
        Reduction: a pixel is flagged as possibly wrapped when either
        polarisation's phase lies within this of ±π, 0.3 rad (≈ 650 m/s,
        ≈ 450 G; design §3.5).

    Raises
    ------
    TypeError, astropy.units.UnitsError, ValueError
        Naming the field: a value of the wrong type or unit, or outside its
        physical range (e.g. ``seeing_fwhm`` in [0, inf) arcsec, ``quantum_efficiency``
        in (0, 1]).

    Notes
    -----
    The synthetic flat and dark are illustrative GONG-like maps (no real GONG
    flat or dark is public): see `gongsynth.stages.camera.detector`.

    Examples
    --------
    >>> import astropy.units as u
    >>> from gongsynth import GONGInstrument
    >>> gong = GONGInstrument()
    >>> gong.plate_scale
    <Quantity 2.5 arcsec>
    >>> GONGInstrument.from_toml(gong.to_toml()) == gong
    True
    >>> gong.replace(seeing_fwhm=2 * u.arcsec).seeing_fwhm
    <Quantity 2. arcsec>
    """

    line_wavelength: u.Quantity = _param(676.78, u.nm, "Ni I rest wavelength (paper Sec. 2)")
    lande_g: u.Quantity = _param(1.5, u.dimensionless_unscaled, "effective Lande factor (paper Eq. 9)")
    prefilter_center: u.Quantity = _param(676.78, u.nm, "prefilter centre (paper Sec. 2)")
    prefilter_fwhm: u.Quantity = _param(0.5, u.nm, "prefilter width w_p (paper Eqs. 1-2)")
    prefilter_form: str = _plain("memo", str, "'memo' (paper Eq. 2) or 'ideal' (design 3.7)")
    lyot_delta_h: u.Quantity = _param(608.0, u.um, "Lyot thickness parameter (paper Eq. 3)")
    lyot_angle_1: u.Quantity = _param(67.7, u.deg, "Lyot element 1 angle (paper Eq. 3)")
    lyot_angle_2: u.Quantity = _param(-45.3, u.deg, "Lyot element 2 angle, sign per design 3.3")
    lyot_angle_3: u.Quantity = _param(93.0, u.deg, "Lyot element 3 angle (paper Eq. 3)")
    michelson_fsr: u.Quantity = _param(0.305, u.AA, "Michelson free spectral range (paper Eq. 4)")
    michelson_angle: u.Quantity = _param(8.2, u.deg, "Michelson phase offset theta_m (paper Eq. 4)")
    waveplate_rate: u.Quantity = _param(5.0, u.Hz, "half-wave plate rotation rate (paper Sec. 2)")
    frame_rate: u.Quantity = _param(60.0, u.Hz, "camera frame rate (paper Sec. 2)")
    exposure_time: u.Quantity = _param(1 / 60, u.s, "exposure per frame (paper Sec. 3.2)")
    lcvr_period: u.Quantity = _param(1.0, u.s, "time between LCVR switches (paper Sec. 2)")
    aperture: u.Quantity = _param(2.8, u.cm, "effective aperture diameter (paper Sec. 2)")
    plate_scale: u.Quantity = _param(2.5, u.arcsec, "detector pixel on the sky (paper Sec. 2)")
    detector_shape: int = _plain(860, int, "detector side in pixels (GONG full disk)")
    supersampling: int = _plain(5, int, "resampling factor before binning (paper Sec. 3.2)")
    seeing_fwhm: u.Quantity = _param(3.6, u.arcsec, "seeing FWHM (paper Sec. 3.2)")
    seeing_profile: str = _plain("gaussian", str, "seeing's shape: 'gaussian' (the paper) or 'kolmogorov'")
    seeing_wind_speed: u.Quantity = _param(5.0, u.m / u.s, "frame seeing: speed of the turbulence (a choice)")
    seeing_outer_scale: u.Quantity = _param(20.0, u.m, "frame seeing: outer scale L0 (Ziad et al. 2004)")
    seeing_layer_height: u.Quantity = _param(100.0, u.m, "frame seeing: height of the turbulence (a choice)")
    magnetogram_cadence: u.Quantity = _param(1.0, u.min, "one magnetogram per minute (GONG headers, N_USED)")
    image_rotation_angle: u.Quantity = _param(1.785431, u.deg, "UCOR rot of Big Bear 2009-09-05 (GHIST)")
    image_interpolant: str = _plain("poly5", str, "UCOR interp=4 read as IRAF's biquintic polynomial")
    effective_area: u.Quantity = _param(0.6, u.cm**2, "effective collecting area (paper Sec. 3.2)")
    quantum_efficiency: u.Quantity = _param(0.16, u.dimensionless_unscaled, "CCD QE (paper Sec. 3.2)")
    gain: u.Quantity = _param(33.0, u.electron / u.adu, "ADU conversion factor (paper Sec. 3.2)")
    read_noise: u.Quantity = _param(4.8, u.adu, "read noise per frame (paper Sec. 3.2)")
    dither_start: u.Quantity = _param(32, u.adu, "initial dither offset (paper Sec. 3.2)")
    dither_step: u.Quantity = _param(2, u.adu, "dither increment (paper Sec. 3.2)")
    dither_interval: int = _plain(12, int, "frames between dither steps (paper Sec. 3.2)")
    dither_cycle: int = _plain(3600, int, "frames per dither triangle (design 3.11)")
    truncate_bits: int = _plain(3, int, "low bits dropped after accumulation (paper Sec. 3.2)")
    v0: u.Quantity = _param(2151.86, u.m / u.s / u.rad, "velocity per radian of phase (paper Eq. 5)")
    integration_half_width: u.Quantity = _param(3.0, u.nm, "filter integration half range (design 3.8)")
    quadrature_step: u.Quantity = _param(0.1, u.pm, "filter quadrature step")
    reference_line_fwhm: u.Quantity = _param(10.0, u.pm, "rest line FWHM for the zero point (design 3.4)")
    reference_line_depth: u.Quantity = _param(0.6, u.dimensionless_unscaled, "rest line depth (design 3.4)")
    psf_radius: u.Quantity = _param(100.0, u.arcsec, "PSF kernel truncation radius (99 % of the energy)")
    detector_map_seed: int = _plain(20190601, int, "seed of the synthetic flat and dark")
    flat_tilt: u.Quantity = _param(0.03, u.dimensionless_unscaled, "synthetic flat: gradient amplitude")
    flat_vignetting: u.Quantity = _param(0.04, u.dimensionless_unscaled,
                                         "synthetic flat: darkening in the corners")
    flat_dust_density: u.Quantity = _param(40.0, 1 / u.Mpix, "synthetic flat: dust shadows per Mpix")
    flat_dust_depth_min: u.Quantity = _param(0.01, u.dimensionless_unscaled,
                                             "synthetic flat: shallowest dust shadow")
    flat_dust_depth_max: u.Quantity = _param(0.05, u.dimensionless_unscaled,
                                             "synthetic flat: deepest dust shadow")
    flat_dust_radius_min: u.Quantity = _param(3.0, u.pix, "synthetic flat: smallest dust shadow radius")
    flat_dust_radius_max: u.Quantity = _param(12.0, u.pix, "synthetic flat: largest dust shadow radius")
    flat_prnu: u.Quantity = _param(0.01, u.dimensionless_unscaled, "synthetic flat: RMS pixel response")
    dark_level: u.Quantity = _param(30.0, u.electron, "synthetic dark: dark current per frame")
    dark_glow: u.Quantity = _param(0.2, u.dimensionless_unscaled, "synthetic dark: amplifier glow amplitude")
    dark_glow_length: u.Quantity = _param(0.25, u.dimensionless_unscaled,
                                          "synthetic dark: glow e-folding length / detector side")
    dark_hot_fraction: u.Quantity = _param(1e-3, u.dimensionless_unscaled, "synthetic dark: hot pixels")
    dark_hot_factor: u.Quantity = _param(10.0, u.dimensionless_unscaled,
                                         "synthetic dark: hot pixel current / dark_level")
    wrap_margin: u.Quantity = _param(0.3, u.rad, "reduction: wrap flag margin from +-pi (design 3.5)")

    #: The registry key (`gongsynth.instruments.get`), the name in metadata, and the line
    #: (the radiative-transfer line registry's key).
    name: ClassVar[str] = "gong"
    label: ClassVar[str] = "GONG"
    line: ClassVar[str] = "Ni I 676.8"
    #: GONG's reduction algorithm (`gongsynth.instruments.gong.reduction.three_phase`).
    algorithm: ClassVar[str] = "gongsynth.instruments.gong.reduction:three_phase"
    #: A run's length when none is given: the paper's 10-minute accumulation (paper, Sec. 3).
    default_duration: ClassVar[u.Quantity] = 10 * u.min

    def __post_init__(self):
        super().__post_init__()
        if self.seeing_profile not in SEEING_PROFILES:
            raise ValueError(f"GONGInstrument.seeing_profile must be one of {SEEING_PROFILES}, "
                             f"got {self.seeing_profile!r}")
        if self.image_interpolant not in INTERPOLANTS:
            raise ValueError(f"GONGInstrument.image_interpolant must be one of {sorted(INTERPOLANTS)}, "
                             f"got {self.image_interpolant!r}")
        if self.prefilter_form not in PREFILTER_FORMS:
            raise ValueError(
                f"GONGInstrument.prefilter_form must be one of {PREFILTER_FORMS}, got {self.prefilter_form!r}"
            )
        for smaller, larger in (("flat_dust_depth_min", "flat_dust_depth_max"),
                                ("flat_dust_radius_min", "flat_dust_radius_max")):
            if getattr(self, smaller) > getattr(self, larger):
                raise ValueError(f"GONGInstrument.{smaller} ({getattr(self, smaller)}) must not exceed "
                                 f"{larger} ({getattr(self, larger)})")
        if self.quadrature_step >= self.integration_half_width:
            raise ValueError(f"GONGInstrument.quadrature_step ({self.quadrature_step}) must be smaller "
                             f"than integration_half_width ({self.integration_half_width})")

    # ------------------------------------------------------------------ derived
    @property
    def frames_per_sector_cycle(self):
        """Number of frames in one 90° period of the wave plate (3)."""
        return int(round((self.frame_rate / (4 * self.waveplate_rate)).to_value(u.one)))

    @property
    def waveplate_step(self):
        """Wave-plate rotation during one frame (30° by default), `~astropy.units.Quantity`."""
        return (360 * u.deg * self.waveplate_rate / self.frame_rate).to(u.deg)

    @property
    def v0_from_fsr(self):
        """
        v0 = c Δλ_m / (2π λ0) computed with the exact speed of light.

        Returns
        -------
        `~astropy.units.Quantity`
            In m / s / rad (2150.27 for the defaults; the paper's 2151.86 used
            c = 3e8 m/s).
        """
        v = const.c * self.michelson_fsr / (2 * math.pi * self.line_wavelength)
        return (v / u.rad).to(u.m / u.s / u.rad)

    @property
    def gauss_per_velocity(self):
        """
        Conversion from the half difference of the I±V velocities to B_LOS.

        B = 4π m_e c / (e g λ0) × (v⁺ - v⁻)/2 in Gaussian units (paper, Eq. 9).

        Returns
        -------
        `~astropy.units.Quantity`
            In G / (m / s); 0.7038 for g = 1.5 at 676.78 nm.
        """
        return gauss_per_zeeman_velocity(self.line_wavelength, self.lande_g)

    # ------------------------------------------------------------ the protocol
    @property
    def analysers(self):
        """
        The (sector, sign of Stokes V) pair of each raw plane, a tuple of int pairs.

        Plane = polarisation × 3 + sector (`gongsynth.planes`), I+V first:
        ``((0, 1), (1, 1), (2, 1), (0, -1), (1, -1), (2, -1))``.
        """
        from gongsynth.instruments.gong.planes import ANALYSERS
        return ANALYSERS

    @property
    def plane_names(self):
        """Short name of each raw plane (``"I+V ch0"`` ...), tuple of str."""
        from gongsynth.instruments.gong.planes import PLANE_NAMES
        return PLANE_NAMES

    def responses(self, wavelength):
        """
        The three sector responses R̄_i(λ) (`gongsynth.filters.channel_responses`).

        Parameters
        ----------
        wavelength : `~astropy.units.Quantity`
            Shape (nλ,).

        Returns
        -------
        `~astropy.units.Quantity`
            Dimensionless, shape (3, nλ).
        """
        from gongsynth.instruments.gong.filters import channel_responses
        return channel_responses(wavelength, self)

    def schedule(self, duration):
        """
        GONG's magnetogram-mode frame schedule (`gongsynth.instruments.gong.schedule.frame_schedule`).

        Parameters
        ----------
        duration : `~astropy.units.Quantity`

        Returns
        -------
        `~gongsynth.instruments.gong.schedule.GONGFrameSchedule`
        """
        from gongsynth.instruments.gong.schedule import frame_schedule
        return frame_schedule(duration, self)

    @property
    def detector_maps(self):
        """The parameters of the synthetic flat and dark (GONG's own fields: the instrument itself)."""
        return self

    def header_cards(self):
        """
        The inversion constants every product records (Landé factor, v0).

        Returns
        -------
        dict
        """
        return {"landeg": (self.lande_g.to_value(u.one), "Lande factor used in the inversion"),
                "v0": (self.v0.to_value(u.m / u.s / u.rad), "[m/s/rad] Michelson velocity scale")}


def resolve_instrument(instrument):
    """
    The instrument a stage should use: the default GONG for None, else the one given.

    Kept for the stages' old callers; the family's entry point is
    `gongsynth.instruments.get`, which also takes a name.

    Parameters
    ----------
    instrument : `~gongsynth.instruments.base.Instrument`, str or None

    Returns
    -------
    An instrument of the family.

    Raises
    ------
    TypeError
        If ``instrument`` is neither None, a name nor an instrument.

    Examples
    --------
    >>> resolve_instrument(None) == GONGInstrument()
    True
    """
    from gongsynth.instruments import get
    return get(instrument)


#: Allowed range of each numeric field in its canonical unit, as an interval ("[" and "]" inclusive).
_RANGES = {
    **dict.fromkeys(("line_wavelength", "prefilter_center", "prefilter_fwhm", "lyot_delta_h",
                     "michelson_fsr", "waveplate_rate", "frame_rate", "exposure_time", "lcvr_period",
                     "aperture", "plate_scale", "effective_area", "gain", "v0", "integration_half_width",
                     "quadrature_step", "reference_line_fwhm", "psf_radius", "flat_dust_radius_min",
                     "flat_dust_radius_max", "dark_glow_length"), "(0, inf)"),
    **dict.fromkeys(("seeing_wind_speed", "seeing_outer_scale", "magnetogram_cadence"),
                    "(0, inf)"),
    **dict.fromkeys(("seeing_fwhm", "seeing_layer_height", "read_noise", "dither_start", "dither_step",
                     "flat_dust_density",
                     "dark_level", "dark_glow", "dark_hot_factor"), "[0, inf)"),
    **dict.fromkeys(("detector_shape", "supersampling", "dither_interval", "dither_cycle"), "[1, inf)"),
    **dict.fromkeys(("flat_dust_depth_min", "flat_dust_depth_max", "dark_hot_fraction"), "[0, 1]"),
    **dict.fromkeys(("flat_tilt", "flat_vignetting", "flat_prnu"), "[0, 1)"),
    **dict.fromkeys(("quantum_efficiency", "reference_line_depth"), "(0, 1]"),
    "lande_g": "(0, 4]", "truncate_bits": "[0, 31]", "wrap_margin": "[0, pi)",
}

GONGInstrument.RANGES = _RANGES
