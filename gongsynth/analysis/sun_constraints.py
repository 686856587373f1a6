r"""
Observational constraints on a model Sun: measured from its synthesised spectra, next to the observations.

A variant of the built-in Sun (`gongsynth.sun.model_atmosphere.ensemble`) is
built on two small seeded boxes and synthesised with
`gongsynth.sun.rt.synthesize`:

- a **quiet box** (default 160² columns of 96 km, 15 Mm, no spot): the
  granulation's continuum contrast at 676.8 and 617.3 nm, the mean disk-centre
  profiles of Ni I 676.8 and Fe I 617.3 (central depth 1 − I_core/I_c, FWHM),
  their centre-to-limb change at a second μ (on rays inclined through the box),
  the continuum's limb darkening, the continuum contrast of the kG elements
  (pixels whose field at the elements' base plane exceeds half the element
  field) against the field-free quiet Sun (the disk-centre continuum at the
  diffraction limit of Hinode's 50 cm aperture, as the deconvolved
  observations it is compared with), and the flux densities at the
  paper's truth height (175 km above τ = 1), averaged over 2 × 2 columns
  (192 km, about Hinode SP's 0.32″ pixels: the observations' resolution);
- a **spot box** (default 128² columns of 384 km, 49 Mm) with the sunspot: the
  676.8 nm continuum of the umbral core (3 × 3 mean at the darkest point),
  the mean penumbra, the umbra's share of the spot's area (spot: I_c below 0.9
  of the quiet Sun, as the outer penumbral boundary of Löptien et al. 2018,
  A&A 619, A42; umbra: below 0.5, our choice between the umbral ~0.2 and the
  penumbral ~0.8), and the spot's area.

The Wilson depressions are the builder's own (``meta``: pressure balance at the
element's / umbra's τ = 1).  `CONSTRAINTS` holds each observation with its
source and the accepted range; a constraint without a range (NaN) is
reported, not used to exclude.  The accepted ranges are explained in
``docs/guide/sun_ensemble.rst``.
"""
from __future__ import annotations

from collections import namedtuple

import astropy.units as u
import numpy as np
import scipy.ndimage
from astropy.table import QTable

from gongsynth.sun.model_atmosphere.ensemble import variant as get_variant
from gongsynth.sun.photosphere.line import NECKEL_LABS_617, NECKEL_LABS_676
from gongsynth.sun.rt import synthesize
from gongsynth.sun.rt.atomic_data import get_line

__all__ = ["Constraint", "CONSTRAINTS", "LINES", "measure_quiet", "measure_spot", "constraint_table",
           "sun_constraints"]

#: One observational constraint: what it is, its unit, the observed value, the accepted range, the source.
Constraint = namedtuple("Constraint", "label unit observed low high source")

_NAN = float("nan")
#: 1 MSH (millionth of the solar hemisphere) in km²: 2π R☉² / 1e6 with R☉ = 695 700 km (IAU 2015 B3).
_MSH_KM2 = 2 * np.pi * 695700.0 ** 2 / 1e6

#: The two lines measured, by their short name in the constraint names.
LINES = {"ni": "Ni I 676.8", "fe": "Fe I 617.3"}

_ATLAS = ("Kitt Peak FTS atlas as quoted by Norton et al. 2006, Sol. Phys. 239, 69 (the numbers gongsynth's "
          "line tuning uses); range: the synthesis's own systematic on 1-D models, tests/test_rt_lines.py")

#: The constraints, by name.  Ranges: see the module notes and docs/guide/sun_ensemble.rst.
CONSTRAINTS = {
    "continuum_contrast_ni": Constraint(
        "RMS continuum contrast, quiet Sun, 676.8 nm, mu = 1", "", 0.166, 0.11, 0.173,
        "Hinode/BFI 668 nm deconvolved: 16.6 +- 0.7 % (Wedemeyer-Bohm & Rouppe van der Voort 2009, "
        "A&A 503, 225), 11 % (Mathew et al. 2009, A&A 501, L19)"),
    "continuum_contrast_fe": Constraint(
        "RMS continuum contrast, quiet Sun, 617.3 nm, mu = 1", "", _NAN, 0.11, 0.208,
        "between the deconvolved 668 nm (>= 11 %, Mathew et al. 2009) and 555 nm (19.4 +- 1.4 %, "
        "Wedemeyer-Bohm & Rouppe van der Voort 2009) contrasts"),
    "line_depth_ni": Constraint("Ni I 676.8 central depth, mean profile, mu = 1", "", 0.60, 0.57, 0.73,
                                _ATLAS),
    "line_fwhm_ni": Constraint("Ni I 676.8 FWHM, mean profile, mu = 1", "pm", 10.0, 8.0, 12.0, _ATLAS),
    "line_depth_fe": Constraint("Fe I 617.3 central depth, mean profile, mu = 1", "", 0.62, 0.59, 0.75,
                                _ATLAS),
    "line_fwhm_fe": Constraint("Fe I 617.3 FWHM, mean profile, mu = 1", "pm", 10.2, 8.2, 12.2, _ATLAS),
    "limb_darkening_ni": Constraint(
        "continuum I(mu)/I(1), 676.8 nm", "", _NAN, _NAN, _NAN,
        "Neckel & Labs 1994, Sol. Phys. 153, 91 (gongsynth.sun.photosphere.line.NECKEL_LABS_676); +- 0.02"),
    "limb_darkening_fe": Constraint(
        "continuum I(mu)/I(1), 617.3 nm", "", _NAN, _NAN, _NAN,
        "Neckel & Labs 1994 (gongsynth.sun.photosphere.line.NECKEL_LABS_617); +- 0.02"),
    "line_depth_clv_ni": Constraint("Ni I 676.8 depth(mu) / depth(1)", "", _NAN, _NAN, _NAN,
                                    "no published value found: reported only"),
    "line_fwhm_clv_ni": Constraint("Ni I 676.8 FWHM(mu) / FWHM(1)", "", _NAN, _NAN, _NAN,
                                   "no published value found: reported only"),
    "line_depth_clv_fe": Constraint("Fe I 617.3 depth(mu) / depth(1)", "", _NAN, _NAN, _NAN,
                                    "no published value found: reported only"),
    "line_fwhm_clv_fe": Constraint("Fe I 617.3 FWHM(mu) / FWHM(1)", "", _NAN, _NAN, _NAN,
                                   "no published value found: reported only"),
    "bright_point_contrast": Constraint(
        "continuum contrast of kG pixels against field-free quiet Sun, 676.8 nm, mu = 1", "",
        0.085, 0.03, 0.15,
        "network kG patches +10 % at 630 nm, plage -3 % (Buehler et al. 2019, A&A 630, A86); bright points "
        "+7 % at 668 nm deconvolved (Mathew et al. 2009); range: the network values +- 0.04"),
    "element_wilson_depression": Constraint("Wilson depression of the kG elements", "km", _NAN, _NAN, _NAN,
                                            "not measured directly: reported only"),
    "network_flux_density": Constraint(
        "mean |B_LOS| of the box at 0.2 arcsec (175 km above tau = 1)", "G", 11.0, 11.0, _NAN,
        "very quiet Sun, Hinode SP: 11 Mx cm-2 (Lites et al. 2008, ApJ 672, 1237): a lower bound for a box "
        "with network around a spot; no upper bound"),
    "internetwork_flux_density": Constraint(
        "mean |B_LOS| away from kG elements at 0.2 arcsec", "G", 11.0, 8.0, 20.0,
        "11 Mx cm-2 (Lites et al. 2008), 16.3 Mx cm-2 (Orozco Suarez & Bellot Rubio 2012, ApJ 751, 2); "
        "range: the two +- 25 %"),
    "internetwork_horizontal_ratio": Constraint(
        "mean |B_horizontal| / mean |B_LOS| away from kG elements", "", 5.0, 2.5, 6.0,
        "5 (55 / 11 Mx cm-2, Lites et al. 2008), 3.1 (Orozco Suarez & Bellot Rubio 2012); photon noise "
        "inflates the horizontal field (Borrero & Kobel 2011, A&A 527, A29): range widened to 2.5-6"),
    "umbral_core_intensity": Constraint(
        "umbral core continuum / quiet Sun, 676.8 nm", "", _NAN, 0.1, 0.4,
        "MDI continuum at 676.8 nm, stray-light corrected: darker in larger spots (Mathew et al. 2007, "
        "A&A 465, 291); range read from their figures, approximate"),
    "penumbral_intensity": Constraint(
        "mean penumbral continuum / quiet Sun, 676.8 nm", "", _NAN, 0.7, 0.9,
        "Mathew et al. 2007 (MDI 676.8 nm); range read from their figures, approximate"),
    "umbral_area_fraction": Constraint(
        "umbral area / spot area", "", _NAN, 0.2, 0.4,
        "20-40 % in 30 084 MDI spot detections (Watson, Fletcher & Marshall 2011, A&A 533, A14)"),
    "spot_area": Constraint("spot area (continuum below 0.9)", "MSH", _NAN, _NAN, _NAN,
                            "spots of every size occur: reported only"),
    "umbral_wilson_depression": Constraint(
        "Wilson depression of the umbra", "km", _NAN, 400.0, 1000.0,
        "400-1000 km from force balance (Solanki et al. 1993; Martinez Pillet & Vazquez 1993; Mathew et al. "
        "2004; as summarised by Loptien et al. 2018, A&A 619, A42)"),
}

#: Height of the flux densities above the quiet τ = 1 (the paper's truth height, design decision 14), km.
FLUX_HEIGHT_KM = 175.0
#: Target pixel of the flux densities (Hinode SP's 0.32″ ≈ 230 km), km.
HINODE_PIXEL_KM = 230.0
#: Aperture of Hinode SOT (m): the quiet-Sun intensities are compared at its diffraction limit, as the
#: deconvolved observations are (a Gaussian of σ = 0.42 λ/D, the Airy core's best fit).
HINODE_APERTURE_M = 0.5
#: km per arcsec at disk centre (1 AU).
_KM_PER_ARCSEC = 725.3


def _wavelength(line):
    lam0 = get_line(line).wavelength_nm
    return np.linspace(lam0 - 0.05, lam0 + 0.05, 101) * u.nm


def _continuum(cube):
    """Per-pixel continuum: mean of the window's two edges (±50 pm, far outside the ~10 pm line)."""
    i = cube.I.value.astype(float)
    return 0.5 * (i[..., 0] + i[..., -1])


def _depth_fwhm(cube):
    """Central depth and FWHM (pm) of the box's mean profile, the continuum at the window's edges."""
    profile = cube.I.value.astype(float).mean(axis=(0, 1))
    lam = cube.wavelength.to_value(u.pm)
    ic = 0.5 * (profile[0] + profile[-1])
    depth = 1 - profile.min() / ic
    half = ic * (1 - depth / 2)
    below = np.flatnonzero(profile < half)
    a, b = below[0], below[-1]
    left = np.interp(half, [profile[a], profile[a - 1]], [lam[a], lam[a - 1]])
    right = np.interp(half, [profile[b], profile[b + 1]], [lam[b], lam[b + 1]])
    return depth, right - left


def _block_mean(a, n):
    """Mean over n × n blocks (the box's sides cut to multiples of n)."""
    ny, nx = (s - s % n for s in a.shape)
    return a[:ny, :nx].reshape(ny // n, n, nx // n, n).mean(axis=(1, 3))


def _at_hinode(image, line, pixel_km):
    """An intensity image at the diffraction limit of Hinode's 50 cm aperture (periodic box)."""
    sigma_arcsec = 0.42 * get_line(line).wavelength_nm * 1e-9 / HINODE_APERTURE_M * 206264.806
    return scipy.ndimage.gaussian_filter(image, sigma_arcsec * _KM_PER_ARCSEC / pixel_km, mode="wrap")


def _limb(coefficients, mu):
    return float(np.polyval(coefficients[::-1], mu))


def measure_quiet(atmosphere, *, mu=0.5):
    """
    The quiet-Sun constraints of a spotless model atmosphere (see the module notes).

    Parameters
    ----------
    atmosphere : `~gongsynth.Atmosphere`
        A box of `~gongsynth.sun.model_atmosphere.model_atmosphere` without
        its spot (``meta["spot"]`` False).
    mu : float
        The second viewing angle's cos θ for the centre-to-limb values.

    Returns
    -------
    dict
        Constraint name → measured value (in the unit of `CONSTRAINTS`).
    """
    meta = atmosphere.meta or {}
    if meta.get("origin") != "gongsynth.model_atmosphere" or meta.get("spot"):
        raise ValueError("atmosphere must be a model_atmosphere box without its spot (spot=False)")
    if not 0 < mu < 1:
        raise ValueError(f"mu must be in (0, 1), got {mu!r}")
    params = meta["params"]
    values = {}
    for key, line in LINES.items():
        centre = synthesize(atmosphere, line=line, wavelength=_wavelength(line), progress=False)
        slant = synthesize(atmosphere, line=line, wavelength=_wavelength(line), mu=mu, progress=False)
        ic = _at_hinode(_continuum(centre), line, atmosphere.pixel_size.to_value(u.km))
        values[f"continuum_contrast_{key}"] = float(ic.std() / ic.mean())
        depth, fwhm = _depth_fwhm(centre)
        depth_mu, fwhm_mu = _depth_fwhm(slant)
        values[f"line_depth_{key}"], values[f"line_fwhm_{key}"] = depth, fwhm
        values[f"line_depth_clv_{key}"], values[f"line_fwhm_clv_{key}"] = depth_mu / depth, fwhm_mu / fwhm
        values[f"limb_darkening_{key}"] = float(_continuum(slant).mean() / ic.mean())
        if key == "ni":
            continuum = ic

    # kG elements: their field at their own (Wilson-depressed) base plane.
    z = atmosphere.z.to_value(u.km)
    bz = atmosphere.raw("magnetic_field")[2]
    base = int(np.argmin(np.abs(z + meta["wilson_depression_km"]["element"])))
    element = np.abs(bz[base]) > 0.5 * params["element_field_G"]
    near = scipy.ndimage.binary_dilation(element, iterations=3, border_value=0)
    field_free = ~near
    values["bright_point_contrast"] = (float(continuum[element].mean() / continuum[field_free].mean() - 1)
                                       if element.any() else _NAN)
    values["element_wilson_depression"] = float(meta["wilson_depression_km"]["element"])

    # Flux densities at the truth height, at about Hinode SP's pixel.
    level = int(np.argmin(np.abs(z - FLUX_HEIGHT_KM)))
    n = max(1, int(round(HINODE_PIXEL_KM / params["pixel_size_km"])))
    b = [_block_mean(atmosphere.raw("magnetic_field")[i, level].astype(float), n) for i in range(3)]
    quiet = _block_mean(field_free.astype(float), n) == 1.0
    vertical, horizontal = np.abs(b[2]), np.hypot(b[0], b[1])
    values["network_flux_density"] = float(vertical.mean())
    values["internetwork_flux_density"] = float(vertical[quiet].mean()) if quiet.any() else _NAN
    values["internetwork_horizontal_ratio"] = (float(horizontal[quiet].mean() / vertical[quiet].mean())
                                               if quiet.any() else _NAN)
    return values


def measure_spot(atmosphere):
    """
    The sunspot constraints of a model atmosphere with its spot (see the module notes).

    Parameters
    ----------
    atmosphere : `~gongsynth.Atmosphere`
        A box of `~gongsynth.sun.model_atmosphere.model_atmosphere` with its
        spot at the box centre (``meta["spot"]`` True).

    Returns
    -------
    dict
        Constraint name → measured value.
    """
    meta = atmosphere.meta or {}
    if meta.get("origin") != "gongsynth.model_atmosphere" or not meta.get("spot"):
        raise ValueError("atmosphere must be a model_atmosphere box with its spot")
    params = meta["params"]
    px = params["pixel_size_km"]
    ic = _continuum(synthesize(atmosphere, progress=False))
    ny, nx = ic.shape
    y = (np.arange(ny) + 0.5 - ny / 2) * px
    x = (np.arange(nx) + 0.5 - nx / 2) * px
    r = np.hypot(y[:, None], x[None, :])
    outside = r > params["penumbra_radius_km"] + 4000.0
    if not outside.any():
        raise ValueError("the box has no quiet Sun 4 Mm beyond the penumbra to normalise by: make it larger")
    rel = ic / ic[outside].mean()
    inside = r < params["penumbra_radius_km"] + 2000.0
    spot = (rel < 0.9) & inside
    umbra = (rel < 0.5) & inside
    penumbra = spot & ~umbra
    return {
        "umbral_core_intensity": float(scipy.ndimage.uniform_filter(rel, 3, mode="wrap").min()),
        "penumbral_intensity": float(rel[penumbra].mean()) if penumbra.any() else _NAN,
        "umbral_area_fraction": float(umbra.sum() / spot.sum()) if spot.any() else _NAN,
        "spot_area": float(spot.sum() * px ** 2 / _MSH_KM2),
        "umbral_wilson_depression": float(meta["wilson_depression_km"]["umbra"]),
    }


def constraint_table(values, *, mu=0.5):
    """
    Measured values beside the observations: a row per constraint of `CONSTRAINTS` present in ``values``.

    Parameters
    ----------
    values : dict
        Constraint name → measured value (`measure_quiet`, `measure_spot`).
    mu : float
        The centre-to-limb values' μ (sets the limb-darkening observation).

    Returns
    -------
    `~astropy.table.QTable`
        Columns ``constraint``, ``description``, ``value``, ``unit``,
        ``observed``, ``low``, ``high`` (NaN: none), ``verdict`` ("within",
        "outside" or "reported": no range) and ``source``.

    Examples
    --------
    >>> t = constraint_table({"umbral_area_fraction": 0.19, "spot_area": 260.0})
    >>> [str(v) for v in t["verdict"]]
    ['outside', 'reported']
    """
    unknown = sorted(set(values) - set(CONSTRAINTS))
    if unknown:
        raise ValueError(f"values has unknown constraint names {unknown}; known: {sorted(CONSTRAINTS)}")
    rows = []
    for name, c in CONSTRAINTS.items():
        if name not in values:
            continue
        observed, low, high = c.observed, c.low, c.high
        if name.startswith("limb_darkening_"):
            observed = _limb(NECKEL_LABS_676 if name.endswith("ni") else NECKEL_LABS_617, mu)
            low, high = observed - 0.02, observed + 0.02
        value = float(values[name])
        if np.isnan(low) and np.isnan(high):
            verdict = "reported"
        elif np.isnan(value):
            verdict = "outside"
        else:
            verdict = "within" if (np.isnan(low) or value >= low) and (np.isnan(high) or value <= high) \
                else "outside"
        rows.append(dict(constraint=name, description=c.label, value=value, unit=c.unit, observed=observed,
                         low=low, high=high, verdict=verdict, source=c.source))
    return QTable(rows=rows, names=("constraint", "description", "value", "unit", "observed", "low", "high",
                                    "verdict", "source"))


def sun_constraints(variant="default", *, seed=1, mu=0.5, quiet_shape=(160, 160), quiet_pixel=96 * u.km,
                    spot_shape=(128, 128), spot_pixel=384 * u.km, nz=80):
    """
    Every constraint of a variant of the built-in Sun, measured on a quiet box and a spot box.

    Parameters
    ----------
    variant : str or `~gongsynth.sun.model_atmosphere.ensemble.SunVariant`
        A variant of the ensemble (``"default"``: the builder's Sun).
    seed : int
        Seed of both boxes.
    mu : float
        cos θ of the centre-to-limb values.
    quiet_shape, quiet_pixel : tuple, `~astropy.units.Quantity`, or None
        The quiet box (no spot); ``quiet_shape=None`` skips the quiet-Sun
        constraints.
    spot_shape, spot_pixel : tuple, `~astropy.units.Quantity`, or None
        The spot box (it must hold the spot and 4 Mm of quiet Sun beyond the
        penumbra); ``spot_shape=None`` skips the spot constraints.
    nz : int
        Heights of both boxes.

    Returns
    -------
    `~astropy.table.QTable`
        `constraint_table` of the measured values.
    """
    member = get_variant(variant)
    values = {}
    if quiet_shape is not None:
        values.update(measure_quiet(member.atmosphere(quiet_shape, quiet_pixel, seed=seed, nz=nz, spot=False),
                                    mu=mu))
    if spot_shape is not None:
        values.update(measure_spot(member.atmosphere(spot_shape, spot_pixel, seed=seed, nz=nz, spot=True)))
    return constraint_table(values, mu=mu)
