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
import math
import numbers
import tomllib
from dataclasses import dataclass, field, fields
from pathlib import Path

import astropy.constants as const
import astropy.units as u
import tomlkit

from gongsynth.tomlfmt import toml_table

__all__ = ["HMIInstrument", "N_TUNINGS", "N_HMI_PLANES", "TUNING_INDICES", "resolve_hmi"]

#: Tuning positions of the HMI sequence (filtergrams I0..I5).
N_TUNINGS = 6
#: Raw planes of one LOS sequence: (LCP, RCP) x 6 tunings, plane = pol * 6 + tuning.
N_HMI_PLANES = 2 * N_TUNINGS
#: Position of each filtergram in units of the tuning step: I0 is the reddest
#: (+172 mÅ), I5 the bluest (HMI's numbering, Couvidat et al. 2016, Sec. 2).
TUNING_INDICES = (2.5, 1.5, 0.5, -0.5, -1.5, -2.5)

_UNIT = "unit"
_DOC = "doc"
_mA = u.Unit("mAA")  # milli-ångström, HMI's customary unit for tuning and widths


# Local equivalents of gongsynth.instrument's private field helpers (kept local
# so that this subpackage does not reach into another module's private names).
def _param(default, unit, doc):
    """A Quantity-valued dataclass field with its canonical unit and source."""
    return field(default=u.Quantity(default, unit), metadata={_UNIT: u.Unit(unit), _DOC: doc})


def _plain(default, kind, doc):
    """A plain (int or str) dataclass field."""
    return field(default=default, metadata={_UNIT: kind, _DOC: doc})


@dataclass(frozen=True)
class HMIInstrument:
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

    name = "hmi"
    line = "Fe I 617.3"
    #: The name in metadata; the reduction algorithm (`gongsynth.instruments.hmi.observables.reduce_hmi`,
    #: imported by the reduction stage); the camera keeps every bit (no truncation, no dither).
    label = "HMI"
    algorithm = "gongsynth.instruments.hmi.observables:reduce_hmi"
    truncate_bits = 0
    #: The PSF: Wachter et al. (2012)'s measured core and scattered-light wings
    #: (`gongsynth.instruments.hmi.psf`).
    psf_model = "gongsynth.instruments.hmi.psf:psf_profile"

    def __post_init__(self):
        for f in fields(self):
            kind = f.metadata[_UNIT]
            value = getattr(self, f.name)
            if kind is int:
                if isinstance(value, numbers.Integral) and not isinstance(value, bool):
                    object.__setattr__(self, f.name, int(value))
                    value = int(value)
                if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                    raise TypeError(f"HMIInstrument.{f.name} must be a positive int, got {value!r}")
            else:
                object.__setattr__(self, f.name, _as_quantity(f.name, value, kind))
        for name in _NONNEGATIVE:
            if getattr(self, name).value < 0:
                raise ValueError(f"HMIInstrument.{name} must be >= 0, got {getattr(self, name)}")
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, u.Quantity) and f.name not in _NONNEGATIVE + ("nontunable_phase",) \
                    and not value.value > 0:
                raise ValueError(f"HMIInstrument.{f.name} must be > 0, got {value}")
        for name in _FRACTIONS:
            if getattr(self, name).to_value(u.one) > 1:
                raise ValueError(f"HMIInstrument.{name} must lie in (0, 1], got {getattr(self, name)}")
        if self.quadrature_step >= self.integration_half_width:
            raise ValueError(f"HMIInstrument.quadrature_step ({self.quadrature_step}) must be smaller "
                             f"than integration_half_width ({self.integration_half_width})")
        if self.lut_velocity_step >= self.lut_velocity_max:
            raise ValueError(f"HMIInstrument.lut_velocity_step ({self.lut_velocity_step}) must be "
                             f"smaller than lut_velocity_max ({self.lut_velocity_max})")
        if self.adc_bits > 31:
            raise ValueError(f"HMIInstrument.adc_bits must be at most 31, got {self.adc_bits}")

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
        m_e = const.m_e.cgs.value
        c = const.c.cgs.value
        e = const.e.gauss.value
        lam = self.line_wavelength.to_value(u.cm)
        per_cm_s = 4 * math.pi * m_e * c / (2 * e * self.lande_g.to_value(u.one) * lam)
        return (per_cm_s * 100) * u.G / (u.m / u.s)

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

    # --------------------------------------------------------------- utilities
    @classmethod
    def source(cls, name):
        """
        The documented source of a parameter.

        Examples
        --------
        >>> HMIInstrument.source("plate_scale")
        'pixel on the sky (Schou et al. 2012)'
        """
        for f in fields(cls):
            if f.name == name:
                return f.metadata[_DOC]
        raise KeyError(f"HMIInstrument has no parameter {name!r}")

    def replace(self, **changes):
        """
        Return a copy with some parameters changed.

        Parameters
        ----------
        **changes
            Field names and their new values.

        Returns
        -------
        `HMIInstrument`
        """
        unknown = set(changes) - {f.name for f in fields(self)}
        if unknown:
            raise TypeError(f"HMIInstrument has no parameter(s) {sorted(unknown)}")
        return dataclasses.replace(self, **changes)

    def __eq__(self, other):
        if not isinstance(other, HMIInstrument):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self):
        return hash(self._key())

    def _key(self):
        """A hashable tuple of (name, value, unit string) for every field."""
        key = []
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, u.Quantity):
                key.append((f.name, float(value.value), value.unit.to_string()))
            else:
                key.append((f.name, value))
        return tuple(key)

    def to_dict(self):
        """
        Every parameter as a TOML-ready value (Quantities as strings such as ``"0.504 arcsec"``).

        Returns
        -------
        dict
        """
        out = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, u.Quantity) and value.unit == u.one:
                out[f.name] = float(value.value)
            elif isinstance(value, u.Quantity):
                out[f.name] = f"{float(value.value)!r} {value.unit.to_string()}"
            else:
                out[f.name] = value
        return out

    @classmethod
    def from_dict(cls, mapping, *, where="instrument"):
        """
        Build an instrument from a mapping such as a parsed TOML table.

        Parameters
        ----------
        mapping : dict
            Parameter names to values (Quantities, strings like ``"0.504 arcsec"``,
            numbers for dimensionless parameters, ints).  A ``name`` key, if
            present, must be ``"hmi"``.
        where : str
            Name of the table, used in error messages.

        Returns
        -------
        `HMIInstrument`

        Raises
        ------
        KeyError
            If a key is not a parameter of the instrument.
        ValueError
            If ``name`` is not ``"hmi"`` or a value is not a quantity.
        """
        mapping = dict(mapping)
        name = mapping.pop("name", cls.name)
        if name != cls.name:
            raise ValueError(f"[{where}] name = {name!r} is not {cls.name!r}")
        known = {f.name: f for f in fields(cls)}
        unknown = [k for k in mapping if k not in known]
        if unknown:
            raise KeyError(f"unknown key(s) {unknown} in [{where}]; valid keys are {sorted(known)}")
        kwargs = {}
        for key, value in mapping.items():
            kind = known[key].metadata[_UNIT]
            if isinstance(kind, u.UnitBase) and isinstance(value, str):
                try:
                    value = u.Quantity(value)
                except (TypeError, ValueError) as exc:
                    raise ValueError(
                        f"[{where}] {key} = {value!r} is not a quantity such as '1.0 {kind}'"
                    ) from exc
            kwargs[key] = value
        return cls(**kwargs)

    def toml_table(self, *, comments=True):
        """
        The instrument as a tomlkit ``[instrument]`` table (``name = "hmi"`` first).

        Parameters
        ----------
        comments : bool
            Write each parameter's source as a comment.

        Returns
        -------
        `tomlkit.items.Table`
        """
        values = self.to_dict()
        rows = [("name", self.name, "instrument of the family")]
        rows += [(f.name, values[f.name], f.metadata[_DOC]) for f in fields(self)]
        return toml_table(rows, comments=comments)

    def to_toml(self):
        """
        The instrument as a TOML ``[instrument]`` table.

        Returns
        -------
        str
        """
        doc = tomlkit.document()
        doc.add("instrument", self.toml_table())
        return tomlkit.dumps(doc)

    @classmethod
    def from_toml(cls, source):
        """
        Read an instrument from TOML text or a path to a TOML file.

        Parameters
        ----------
        source : str or `pathlib.Path`
            TOML text (parameters at top level or in ``[instrument]``) or a path.

        Returns
        -------
        `HMIInstrument`
        """
        if isinstance(source, Path) or (isinstance(source, str) and source.endswith(".toml")
                                        and "\n" not in source):
            text = Path(source).read_text()
        else:
            text = source
        table = tomllib.loads(text)
        if "instrument" in table:
            extra = [k for k in table if k != "instrument"]
            if extra:
                raise KeyError(f"unknown top-level key(s) {extra} next to [instrument]")
            table = table["instrument"]
        return cls.from_dict(table)


def resolve_hmi(instrument):
    """
    The HMI a function should use: the default for None, else the one given.

    Parameters
    ----------
    instrument : `HMIInstrument` or None

    Returns
    -------
    `HMIInstrument`

    Raises
    ------
    TypeError
        If ``instrument`` is neither None nor an `HMIInstrument`.
    """
    if instrument is None:
        return HMIInstrument()
    if not isinstance(instrument, HMIInstrument):
        raise TypeError(f"instrument must be an HMIInstrument or None, got {type(instrument).__name__}")
    return instrument


_NONNEGATIVE = ("seeing_fwhm", "read_noise")
_FRACTIONS = ("nb_contrast", "wb_contrast", "e1_contrast", "e2_contrast", "e3_contrast", "e4_contrast",
              "e5_contrast", "front_window_peak", "blocker_peak", "quantum_efficiency",
              "reference_line_depth")


def _as_quantity(name, value, unit):
    """Check that ``value`` is a finite scalar Quantity in ``unit`` (a number if dimensionless)."""
    if not isinstance(value, u.Quantity):
        if unit == u.one and isinstance(value, (int, float)) and not isinstance(value, bool):
            return u.Quantity(float(value))
        raise TypeError(f"HMIInstrument.{name} must be an astropy Quantity in units of {unit} "
                        f"(e.g. {name}=1.0 * u.Unit('{unit}')), got {value!r}")
    if not value.unit.is_equivalent(unit):
        raise u.UnitsError(f"HMIInstrument.{name} must have units convertible to '{unit}', "
                           f"got '{value.unit}'")
    if value.ndim != 0 or not math.isfinite(float(value.value)):
        raise ValueError(f"HMIInstrument.{name} must be a finite scalar, got {value!r}")
    return value
