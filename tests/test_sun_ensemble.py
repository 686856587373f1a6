"""The Sun-model ensemble (its variants) and the observational constraints measured on a tiny box."""
import inspect

import astropy.units as u
import numpy as np
import pytest

from gongsynth.analysis.sun_constraints import (
    CONSTRAINTS,
    constraint_table,
    measure_quiet,
    measure_spot,
    sun_constraints,
)
from gongsynth.config import SimulationConfig
from gongsynth.sun.model_atmosphere import model_atmosphere
from gongsynth.sun.model_atmosphere.ensemble import VARIANTS, SunVariant, variant, variant_names


def test_every_variant_is_a_valid_sun_and_a_valid_run():
    defaults = inspect.signature(model_atmosphere).parameters
    assert variant_names()[0] == "default" and not variant("default").changes
    for name, member in VARIANTS.items():
        assert member.name == name and member.source
        assert set(member.probes) <= set(CONSTRAINTS), name
        # each changes something, to a value other than the builder's default
        for key, value in member.changes.items():
            assert not np.all(value == defaults[key].default), (name, key)
        # the run's [photosphere] knobs accept every variant as it is
        config = SimulationConfig(photosphere=member.photosphere())
        assert set(config.photosphere) == set(member.changes)
        atm = member.atmosphere((16, 16), 384 * u.km, seed=1, nz=16, spot=False)
        if member.spot_only:  # its spotless box is the default Sun's, bit for bit (the script relies on it)
            base = variant("default").atmosphere((16, 16), 384 * u.km, seed=1, nz=16, spot=False)
            assert all(np.array_equal(atm.raw(f), base.raw(f)) for f in ("temperature", "magnetic_field"))
        for key, value in member.changes.items():
            stored = atm.meta["params"][next(k for k in atm.meta["params"] if k.startswith(key))]
            expected = value.to_value(u.G if value.unit.physical_type == "magnetic flux density" else u.km) \
                if isinstance(value, u.Quantity) else value
            assert stored == expected, (name, key)


def test_bad_names_and_arguments_fail_early():
    with pytest.raises(ValueError, match="variant must be one of .*default"):
        variant("hot-sun")
    with pytest.raises(ValueError, match="not Sun arguments"):
        SunVariant("x", {"elemnt_field": 1 * u.kG})
    with pytest.raises(ValueError, match="not Sun arguments"):
        SunVariant("x", {"seed": 3})
    with pytest.raises(ValueError, match="sets \\['element_field'\\] itself"):
        variant("strong-elements").atmosphere((16, 16), seed=1, element_field=1 * u.kG)
    with pytest.raises(TypeError):
        VARIANTS["default"].changes["umbra_model"] = "maltby-e"   # frozen
    with pytest.raises(ValueError, match="unknown constraint"):
        constraint_table({"contrast": 0.1})


def test_verdicts_follow_the_ranges():
    low, high = CONSTRAINTS["umbral_area_fraction"].low, CONSTRAINTS["umbral_area_fraction"].high
    cases = ((low - 0.01, "outside"), (low, "within"), (high, "within"), (high + 0.01, "outside"),
             (np.nan, "outside"))
    for value, verdict in cases:
        assert constraint_table({"umbral_area_fraction": value})["verdict"][0] == verdict
    # one-sided (a lower bound only) and reported-only constraints
    table = constraint_table({"network_flux_density": 1e3, "spot_area": 1.0, "limb_darkening_ni": 0.0})
    assert list(table["constraint"]) == ["limb_darkening_ni", "network_flux_density", "spot_area"]
    assert list(table["verdict"]) == ["outside", "within", "reported"]


@pytest.fixture(scope="module")
def tiny_quiet():
    return model_atmosphere((32, 32), 96 * u.km, seed=3, nz=40, spot=False, element_flux_density=200 * u.G)


def test_quiet_constraints_on_a_tiny_box(tiny_quiet):
    values = measure_quiet(tiny_quiet, mu=0.5)
    assert 0.02 < values["continuum_contrast_ni"] < 0.4
    # the contrast is larger at the shorter wavelength (Planck function's temperature sensitivity)
    assert values["continuum_contrast_fe"] > values["continuum_contrast_ni"]
    for key in ("ni", "fe"):
        assert 0.3 < values[f"line_depth_{key}"] < 0.95 and 5 < values[f"line_fwhm_{key}"] < 20
        assert 0.6 < values[f"limb_darkening_{key}"] < 0.9        # limb darkening at mu = 0.5
    assert values["element_wilson_depression"] == tiny_quiet.meta["wilson_depression_km"]["element"]
    # Above the elements' base plane their field is a potential field: B_z there is B_z at the base
    # convolved with the (positive, unit-area) Poisson kernel, so the mean |B_z| cannot grow with height;
    # the internetwork (10 G RMS) adds at most ~10 G.
    z = tiny_quiet.z.to_value(u.km)
    base = np.argmin(np.abs(z + values["element_wilson_depression"]))
    at_base = np.abs(tiny_quiet.raw("magnetic_field")[2, base]).mean()
    assert 0.3 * at_base < values["network_flux_density"] < at_base + 15
    table = constraint_table(values)
    assert set(table["verdict"]) <= {"within", "outside", "reported"} and len(table) == len(values)
    with pytest.raises(ValueError, match="without its spot"):
        measure_quiet(model_atmosphere((48, 48), 384 * u.km, seed=1, nz=40, spot=True, umbra_radius=2 * u.Mm,
                                       penumbra_radius=4.5 * u.Mm))


def test_spot_constraints_on_a_tiny_box(tiny_quiet):
    atm = model_atmosphere((48, 48), 384 * u.km, seed=1, nz=40, spot=True, umbra_radius=2.5 * u.Mm,
                           penumbra_radius=5 * u.Mm)
    values = measure_spot(atm)
    assert 0 < values["umbral_core_intensity"] < values["penumbral_intensity"] < 1
    # spot area within a factor 2 of the penumbra's disc (pi 5 Mm^2 = 26 MSH)
    disc = np.pi * 5000.0 ** 2 / (2 * np.pi * 695700.0 ** 2 / 1e6)
    assert 0.5 * disc < values["spot_area"] < 2 * disc
    assert 0 < values["umbral_area_fraction"] < 1
    with pytest.raises(ValueError, match="with its spot"):
        measure_spot(tiny_quiet)
    with pytest.raises(ValueError, match="mu must be"):
        measure_quiet(tiny_quiet, mu=1.0)
    table = sun_constraints("maltby-e-umbra", quiet_shape=(16, 16), spot_shape=None, nz=24)
    assert "umbral_core_intensity" not in set(table["constraint"])
