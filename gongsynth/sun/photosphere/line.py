"""
The solar Ni I 676.78 nm line as a Milne–Eddington line, and the continuum's limb darkening.

These are properties of the Sun, not of GONG: the line's rest wavelength and
(by default) its Landé factor come from `~gongsynth.GONGInstrument`, everything
else from `NiLine`.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import astropy.units as u
import numpy as np

from gongsynth.validation import check_quantity

__all__ = ["NiLine", "NECKEL_LABS_676", "NECKEL_LABS_617", "FE_I_6173_ME", "ME_LINES",
           "me_line"]

#: Neckel & Labs (1994, Sol. Phys. 153, 91) limb-darkening polynomial
#: I(μ)/I(1) = Σ a_k μ^k at 676.78 nm: their Table coefficients at 669.400 and
#: 700.875 nm interpolated linearly in wavelength and normalised to unit sum.
#: I(0.5)/I(1) = 0.760, I(0)/I(1) = 0.354.
NECKEL_LABS_676 = (0.35435, 1.34727, -1.96564, 2.58568, -1.86144, 0.53977)

#: The same at 617.33 nm (HMI's Fe I line): Neckel & Labs (1994) Table coefficients at 610.975 and
#: 640.970 nm interpolated linearly in wavelength and normalised to unit sum.  I(0.5)/I(1) = 0.739,
#: I(0)/I(1) = 0.314.
NECKEL_LABS_617 = (0.31446, 1.35342, -1.82653, 2.35727, -1.68785, 0.48924)


@dataclass(frozen=True)
class NiLine:
    """
    Milne–Eddington description of the solar Ni I 676.78 nm line.

    The source function is S(τ) = S0 (1 + β τ) in continuum optical depth; the
    emergent spectrum at μ is the Unno–Rachkovsky solution with ``β μ`` in
    place of β, divided by its own continuum (1 + β μ) and multiplied by the
    observed continuum ``continuum_intensity × limb_darkening(μ)``.  The line
    therefore weakens toward the limb as ME predicts while the continuum follows
    the measured limb darkening exactly.

    Defaults are tuned so that the spatial mean of the default model
    photosphere (granular velocities included) at disk centre has a central
    depth of 0.60 of the continuum and a FWHM of 10.0 pm, as the solar Ni I line
    at disk centre (and the reference line of `~gongsynth.GONGInstrument`); a
    single static, field-free column is deeper and narrower (depth 0.67, FWHM
    9.1 pm).  β = 4 was chosen, then Δλ_D and η0 fitted to those two numbers.

    Parameters
    ----------
    doppler_width : `~astropy.units.Quantity`, length
        Doppler width Δλ_D (thermal + microturbulent; 3.1 pm ≈ 1.37 km/s, of
        which 1.2 km/s is thermal Ni at 5000 K).
    damping : float
        Voigt damping parameter a = Γ/(4π Δν_D) (0.05).
    line_strength : float
        η0, ratio of line-centre to continuum opacity (5.6).
    source_gradient : float
        β = S1/S0, slope of the source function in continuum optical depth (4.0).
    continuum_intensity : `~astropy.units.Quantity`
        Quiet-Sun disk-centre continuum near 676.8 nm, 3.0e14 erg s⁻¹ cm⁻² sr⁻¹ cm⁻¹
        (Neckel & Labs 1984; design §3.10).
    limb_darkening : tuple of float
        Polynomial coefficients a_0..a_5 of I(μ)/I(1) (default `NECKEL_LABS_676`).
    lande_g : float or None
        Effective Landé factor used in the synthesis.  None (default) takes
        ``instrument.lande_g`` (1.5, as the paper used in both the radiative
        transfer and the inversion); the literature value is 1.426 (Bruls 1993).
        The 3-D Sun carries the measured factor (DESIGN decision 20,
        `gongsynth.rt.LINES`); this toy keeps the instrument's by default, the
        Sun as the reduction assumes it: the control case without the mismatch.

    Examples
    --------
    >>> import astropy.units as u
    >>> line = NiLine()
    >>> round(float(line.limb_darkening_factor(0.5)), 3)
    0.76
    >>> line.replace(lande_g=1.426).lande_g
    1.426
    """

    doppler_width: u.Quantity = 3.1 * u.pm
    damping: float = 0.05
    line_strength: float = 5.6
    source_gradient: float = 4.0
    continuum_intensity: u.Quantity = 3.0e14 * u.Unit("erg / (s cm2 sr cm)")
    limb_darkening: tuple = NECKEL_LABS_676
    lande_g: float | None = None

    def __post_init__(self):
        check_quantity(self.doppler_width, u.pm, "NiLine.doppler_width")
        check_quantity(self.continuum_intensity, u.Unit("erg / (s cm2 sr cm)"),
                       "NiLine.continuum_intensity")
        if not np.isfinite(self.doppler_width.value) or self.doppler_width.value <= 0:
            raise ValueError(f"NiLine.doppler_width must be positive, got {self.doppler_width}")
        if not np.isfinite(self.continuum_intensity.value) or self.continuum_intensity.value <= 0:
            raise ValueError(f"NiLine.continuum_intensity must be positive, got {self.continuum_intensity}")
        for name, low in (("damping", 0.0), ("line_strength", 0.0), ("source_gradient", 0.0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value) \
                    or value < low:
                raise ValueError(f"NiLine.{name} must be a finite number >= {low}, got {value!r}")
        coeffs = tuple(float(c) for c in self.limb_darkening)
        if len(coeffs) < 1 or not np.isfinite(coeffs).all() or abs(sum(coeffs) - 1) > 1e-3:
            raise ValueError(
                f"NiLine.limb_darkening must be polynomial coefficients with unit sum "
                f"(I(1)/I(1) = 1), got {self.limb_darkening!r}"
            )
        object.__setattr__(self, "limb_darkening", coeffs)
        if self.lande_g is not None and (isinstance(self.lande_g, bool) or not np.isfinite(self.lande_g)):
            raise ValueError(f"NiLine.lande_g must be a finite number or None, got {self.lande_g!r}")

    def limb_darkening_factor(self, mu):
        """
        Continuum intensity at μ relative to disk centre.

        Parameters
        ----------
        mu : float or array_like
            Cosine of the heliocentric angle, in (0, 1].

        Returns
        -------
        float or `numpy.ndarray`
            Σ a_k μ^k (dimensionless, 1 at μ = 1).
        """
        mu = np.asarray(mu, dtype=np.float64)
        return np.polynomial.polynomial.polyval(mu, self.limb_darkening)

    def replace(self, **changes):
        """
        A copy with some parameters changed.

        Parameters
        ----------
        **changes
            Field names and new values.

        Returns
        -------
        `NiLine`
        """
        return dataclasses.replace(self, **changes)


#: Milne–Eddington description of the solar Fe I 617.33 nm line (HMI's), tuned as `NiLine` is: β = 4
#: and the damping kept, Δλ_D and η0 fitted so that the spatial mean of the built-in photosphere at disk
#: centre (`model_photosphere`, 256² columns of 96 km, seed 0, no spot) has the observed disk-centre
#: central depth 0.62 and FWHM 10.2 pm (Kitt Peak FTS atlas as quoted by Norton et al. 2006, Sol. Phys.
#: 239, 69, the numbers ``tests/test_rt_lines.py`` holds the radiative transfer to): Δλ_D = 3.29 pm
#: (≈ 1.60 km/s) and η0 = 5.47 (least squares, ``tests/test_hmi_fulldisk.py`` checks them); the
#: same patch gives Ni I (`NiLine`) 0.61 and 9.8 pm against its 0.60 and 10.0 pm.  Continuum
#: 3.2e14 erg s⁻¹ cm⁻² sr⁻¹ cm⁻¹ near 617.3 nm (Neckel & Labs 1984, the value of
#: `gongsynth.instruments.hmi.noise.CONTINUUM_INTENSITY`), limb darkening `NECKEL_LABS_617`.  The
#: Landé factor is the instrument's (``lande_g = None``): HMI's 2.5 is the line's own (J = 1 → 0,
#: Norton et al. 2006).
FE_I_6173_ME = NiLine(doppler_width=3.29 * u.pm, line_strength=5.47,
                      continuum_intensity=3.2e14 * u.Unit("erg / (s cm2 sr cm)"),
                      limb_darkening=NECKEL_LABS_617)

#: The Milne–Eddington description of each line of `gongsynth.sun.rt.LINES`, by name.
ME_LINES = {"Ni I 676.8": NiLine(), "Fe I 617.3": FE_I_6173_ME}


def me_line(name="Ni I 676.8"):
    """
    The Milne–Eddington description (`ME_LINES`) of a line, by its name (an instrument's ``line``).

    Parameters
    ----------
    name : str
        A key of `ME_LINES`, e.g. ``instrument.line``.

    Returns
    -------
    `NiLine`

    Examples
    --------
    >>> me_line() == NiLine(), me_line("Fe I 617.3").limb_darkening == NECKEL_LABS_617
    (True, True)
    """
    if name not in ME_LINES:
        raise ValueError(f"the Milne-Eddington Sun has no line {name!r}; it knows {tuple(ME_LINES)}")
    return ME_LINES[name]
