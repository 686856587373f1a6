r"""
The Sun-model ensemble: named variants of the built-in 3-D Sun, each a frozen set of builder arguments.

The built-in Sun (`~gongsynth.sun.model_atmosphere.model_atmosphere`) fixes
each of its uncertain parts at one choice: the kG elements' temperature model,
field strength and flux density, the internetwork field, the granulation's
temperature amplitude, the sunspot's size and umbral model.  Each variant here
moves one of them to another value that the literature allows, so that the
spread of a derived number (the weak-flux factor) over the variants is a
systematic band from the model Sun.  A variant is data: its name, the
arguments it changes (the builder's defaults stand for the rest), why that
value (the source) and the observational constraints of
`gongsynth.analysis.sun_constraints` that can tell it apart from the default
(``probes``).  A variant is not tuned to pass them: the constraints measurement
reports which variants violate a constraint, and such a variant is reported as
excluded.

``default`` is the builder's own Sun.  ``weak-granulation`` is the builder's
ablation of the granulation amplitude (the two-component models as published)
and ``cool-elements`` its ablation of the hot flux tubes: members that the
constraints are expected to exclude, kept to show that they do.
"""
from __future__ import annotations

import inspect
import types
from dataclasses import dataclass, field

import astropy.units as u

from gongsynth.sun.model_atmosphere.builder import model_atmosphere

__all__ = ["SunVariant", "VARIANTS", "SPOT_ARGUMENTS", "variant", "variant_names"]

#: Arguments of `model_atmosphere` that set the grid or the randomness, not the Sun: never part of a variant.
_GRID_ARGUMENTS = ("shape", "pixel_size", "seed", "nz", "height_range")

#: Arguments that shape only the sunspot: a box without its spot (``spot=False``) is the same bits
#: whatever their values (the spot has its own random stream and stratifications).
SPOT_ARGUMENTS = ("umbra_radius", "penumbra_radius", "umbra_field", "penumbra_field", "umbra_model",
                  "evershed_speed", "moat_speed")


@dataclass(frozen=True)
class SunVariant:
    """
    One member of the ensemble: changed `model_atmosphere` arguments, their source, what probes them.

    Attributes
    ----------
    name : str
        The variant's name (a key of `VARIANTS`).
    changes : mapping
        `model_atmosphere` keyword arguments that differ from the builder's
        defaults (read-only).
    source : str
        Why these values: the publication each comes from.
    probes : tuple of str
        Names of the constraints (`gongsynth.analysis.sun_constraints.CONSTRAINTS`)
        that respond to the change.
    """

    name: str
    changes: types.MappingProxyType = field(default_factory=lambda: types.MappingProxyType({}))
    source: str = ""
    probes: tuple = ()

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise TypeError(f"name must be a non-empty string, got {self.name!r}")
        changes = dict(self.changes)
        allowed = set(inspect.signature(model_atmosphere).parameters) - set(_GRID_ARGUMENTS)
        bad = sorted(set(changes) - allowed)
        if bad:
            raise ValueError(f"variant {self.name!r}: {bad} are not Sun arguments of model_atmosphere; "
                             f"valid: {sorted(allowed)}")
        object.__setattr__(self, "changes", types.MappingProxyType(changes))
        object.__setattr__(self, "probes", tuple(self.probes))

    def atmosphere(self, shape=(1024, 1024), pixel_size=96 * u.km, *, seed, **grid):
        """
        The variant's model atmosphere (`model_atmosphere` with `changes`).

        Parameters
        ----------
        shape, pixel_size, seed
            As `model_atmosphere`.
        **grid
            Other arguments of `model_atmosphere` (``nz``, ``height_range``,
            ``spot``); a Sun argument that the variant changes cannot be
            overridden here.

        Returns
        -------
        `~gongsynth.Atmosphere`

        Examples
        --------
        >>> atm = variant("strong-elements").atmosphere((32, 32), seed=1, nz=40)
        >>> atm.meta["params"]["element_field_G"]
        2000.0
        """
        clash = sorted(set(grid) & set(self.changes))
        if clash:
            raise ValueError(f"variant {self.name!r} sets {clash} itself; choose another variant instead")
        return model_atmosphere(shape, pixel_size, seed=seed, **grid, **self.changes)

    @property
    def spot_only(self):
        """True when the variant changes only `SPOT_ARGUMENTS`: its spotless boxes are the default Sun's."""
        return bool(self.changes) and set(self.changes) <= set(SPOT_ARGUMENTS)

    def photosphere(self):
        """
        The variant as a run's ``[photosphere]`` knobs (`gongsynth.config.SimulationConfig.photosphere`).

        Returns
        -------
        dict

        Examples
        --------
        >>> variant("small-spot").photosphere()["umbra_radius"]
        <Quantity 4.5 Mm>
        """
        return dict(self.changes)


def _variant(name, source, probes, **changes):
    return SunVariant(name, types.MappingProxyType(changes), source, tuple(probes))


_ELEMENT_PROBES = ("bright_point_contrast", "element_wilson_depression")
_IN_PROBES = ("internetwork_flux_density", "internetwork_horizontal_ratio")
_SPOT_PROBES = ("umbral_core_intensity", "penumbral_intensity", "umbral_area_fraction", "spot_area",
                "umbral_wilson_depression")

#: The ensemble, by name.  Sources of the builder's defaults: `gongsynth.sun.model_atmosphere.builder`.
VARIANTS = types.MappingProxyType({v.name: v for v in (
    _variant("default", "the builder's defaults (gongsynth.sun.model_atmosphere.builder)", ()),
    _variant("plage-elements",
             "kG elements with Solanki's plage flux-tube model instead of the network one (tables.py: "
             "6780 K instead of 6960 K at log tau = 0; Buehler et al. 2019, A&A 630, A86 find plage kG "
             "patches 13 % darker than network ones at disk centre)", ("bright_point_contrast",),
             element_model="plage"),
    _variant("cool-elements",
             "kG elements at the quiet HSRA temperature (the builder's 'no hot tubes' ablation): only "
             "evacuated, no heating", ("bright_point_contrast",), element_model="quiet"),
    _variant("strong-elements",
             "2 kG elements at their tau = 1 (the upper end of 1-2 kG: Stenflo 1973; Buehler et al. 2019 "
             "mean 1.5 kG)", _ELEMENT_PROBES, element_field=2000 * u.G),
    _variant("weak-elements",
             "1 kG elements at their tau = 1 (the lower end of 1-2 kG: Stenflo 1973, Solanki 1993)",
             _ELEMENT_PROBES, element_field=1000 * u.G),
    _variant("dense-network",
             "twice the kG-element flux density (40 G): enhanced network around a spot",
             ("network_flux_density",), element_flux_density=40 * u.G),
    _variant("sparse-network",
             "half the kG-element flux density (10 G), near the very quiet Sun's 11 Mx cm-2 "
             "(Lites et al. 2008, ApJ 672, 1237)", ("network_flux_density",),
             element_flux_density=10 * u.G),
    _variant("strong-internetwork",
             "internetwork at Orozco Suarez & Bellot Rubio 2012 (ApJ 751, 2): 16 G vertical; the horizontal "
             "field kept at 50 G, their ratio 3.1", _IN_PROBES, internetwork_field=16 * u.G),
    _variant("weak-internetwork",
             "half the default internetwork (5 G vertical, 25 G horizontal: the ratio 5 of Lites et al. "
             "2008 kept)", _IN_PROBES, internetwork_field=5 * u.G,
             internetwork_horizontal_field=25 * u.G),
    _variant("weak-granulation",
             "granular temperature amplitude 1: the two-component models as published (Ruiz Cobo et al. "
             "1995), inverted from ~1 arcsec data (the builder's note: contrast ~9 %)",
             ("continuum_contrast_ni", "continuum_contrast_fe"), granulation_amplitude=1.0),
    _variant("large-umbra",
             "umbra radius 9 Mm in the same 16 Mm spot: umbral area 32 % of the spot, mid-range of the "
             "20-40 % of Watson et al. 2011 (A&A 533, A14)", _SPOT_PROBES, umbra_radius=9 * u.Mm),
    _variant("small-spot",
             "a smaller spot (umbra 4.5 Mm, penumbra 10 Mm: ~100 MSH instead of ~260), umbral area 20 %",
             _SPOT_PROBES, umbra_radius=4.5 * u.Mm, penumbra_radius=10 * u.Mm),
    _variant("maltby-e-umbra",
             "Maltby et al. 1986 (ApJ 306, 284) model E umbra (early in the cycle) instead of M",
             ("umbral_core_intensity", "umbral_wilson_depression"), umbra_model="maltby-e"),
)})


def variant_names():
    """
    The names of the ensemble's variants, in order.

    Returns
    -------
    tuple of str

    Examples
    --------
    >>> variant_names()[:3]
    ('default', 'plage-elements', 'cool-elements')
    """
    return tuple(VARIANTS)


def variant(name):
    """
    A variant of the ensemble by name.

    Parameters
    ----------
    name : str or `SunVariant`
        A key of `VARIANTS` (a `SunVariant` is returned as it is).

    Returns
    -------
    `SunVariant`

    Raises
    ------
    ValueError
        For an unknown name (the message lists the known ones).

    Examples
    --------
    >>> variant("maltby-e-umbra").changes["umbra_model"]
    'maltby-e'
    """
    if isinstance(name, SunVariant):
        return name
    if name not in VARIANTS:
        raise ValueError(f"variant must be one of {variant_names()}, got {name!r}")
    return VARIANTS[name]
