"""The line registry of gongsynth.rt (issue 22): Fe I 617.3 nm beside Ni I 676.8 nm, Zeeman, broadening."""
import math
from pathlib import Path

import astropy.units as u
import numpy as np
import pytest

import gongsynth
from gongsynth.stages.scene import library
from gongsynth.sun.rt import LINES, LineData, NiLineData, default_wavelength, get_line, synthesize
from gongsynth.sun.rt.atomic_data import (
    ABUNDANCE,
    FE_I_6173,
    LANDE_LS,
    LANDE_MEASURED,
    effective_lande,
    zeeman_pattern,
)
from gongsynth.sun.rt.kernels import ZEEMAN_CM_PER_G
from gongsynth.sun.rt.opacity import line_constants
from gongsynth.sun.rt.synthesis import reference_height

MODELS = Path(__file__).resolve().parents[2] / "shared" / "data" / "real" / "models"
needs_data = pytest.mark.skipif(not (MODELS / "FALC_82.atmos").is_file(), reason="needs ../shared/data")

#: The observed disk-centre Fe I 617.33 nm line (Kitt Peak FTS atlas as quoted in the HMI line selection,
#: Norton et al. 2006, Sol. Phys. 239, 69): central depth 1 - I_core/I_c and FWHM.
ATLAS_FE_DEPTH, ATLAS_FE_FWHM_PM = 0.62, 10.2


@pytest.fixture(scope="module")
def models():
    return {name: gongsynth.Atmosphere.from_1d(MODELS / f) for name, f in
            (("FAL-C", "FALC_82.atmos"), ("HSRA", "hsra11.1d"))}


def uniform_field(atm, bz):
    return atm.replace(magnetic_field=np.array([0.0, 0.0, bz])[:, None] * np.ones((3, atm.shape[0])) * u.G)


def depth_fwhm(cube):
    """Central depth and FWHM (pm) of a (1, 1, nλ) intensity profile, the continuum at the window's edge."""
    i = cube.I.value[0, 0].astype(float)
    lam = cube.wavelength.to_value(u.pm)
    ic = max(i[0], i[-1])
    depth = 1 - i.min() / ic
    half = ic * (1 - depth / 2)
    below = np.flatnonzero(i < half)
    a, b = below[0], below[-1]
    left = np.interp(half, [i[a], i[a - 1]], [lam[a], lam[a - 1]])
    right = np.interp(half, [i[b], i[b + 1]], [lam[b], lam[b + 1]])
    return depth, right - left


def test_registry_names_and_lookup():
    assert tuple(LINES) == ("Ni I 676.8", "Fe I 617.3")
    assert get_line() is LINES["Ni I 676.8"] and get_line("Fe I 617.3") is FE_I_6173
    assert get_line(FE_I_6173) is FE_I_6173
    with pytest.raises(ValueError, match="Fe I 617.3"):
        get_line("Fe I 630.2")
    with pytest.raises(TypeError, match="line"):
        get_line(617.3)


def test_nickel_keeps_its_old_name_and_carries_the_measured_lande_factor():
    ni = NiLineData()
    assert isinstance(ni, LineData) and ni == LINES["Ni I 676.8"]
    assert ni.lande == LANDE_MEASURED == 1.426 and ni.is_normal_triplet
    assert NiLineData(lande_g=LANDE_LS).lande == 1.5           # the paper's value stays available
    assert ni.g_lower == 1 and ni.wavelength_nm == 676.78


def test_fe_line_data():
    fe = get_line("Fe I 617.3")
    assert fe.wavelength_nm == pytest.approx(617.33433)
    assert fe.lower_energy_ev == pytest.approx(2.223, abs=1e-3)
    assert fe.g_lower == 3 and fe.lande == 2.5 and fe.is_normal_triplet
    # The levels: a5P1 (J = 1, g = 2.5 in LS coupling: S = 2, L = 1) -> J = 0, so the pattern is
    # the lower level's: sigma at +-2.5, pi at 0.
    assert fe.zeeman == {-1: [(-2.5, 1.0)], 0: [(0.0, 1.0)], 1: [(2.5, 1.0)]}
    ls = 1 + (1 * 2 + 2 * 3 - 1 * 2) / (2 * 1 * 2)
    assert fe.lande_lower == ls


@pytest.mark.parametrize("jl,ju,gl,gu", [(2, 2, 1.5, 1.5), (2, 3, 1.5, 1.25), (1.5, 0.5, 4 / 3, 2.0),
                                         (2, 2, 1.83, 2.0), (1, 1, 2.5, 1.5)])
def test_anomalous_zeeman_pattern(jl, ju, gl, gu):
    """Strengths sum to 1 per q, the pi pattern is symmetric, and the sigma centroid is the effective
    Landé factor of the closed formula (Landi Degl'Innocenti & Landolfi 2004, eq. 3.44)."""
    p = zeeman_pattern(jl, ju, gl, gu)
    for q in (-1, 0, 1):
        assert sum(s for _, s in p[q]) == pytest.approx(1.0, abs=1e-9)
    assert sorted(p[1]) == sorted((-c, s) for c, s in p[-1])
    assert sum(c * s for c, s in p[0]) == pytest.approx(0.0, abs=1e-9)
    assert sum(c * s for c, s in p[1]) == pytest.approx(effective_lande(jl, ju, gl, gu), abs=1e-9)
    line = FE_I_6173.replace(j_lower=jl, j_upper=ju, lande_lower=gl, lande_upper=gu)
    assert line.is_normal_triplet == (gl == gu)
    assert line.lande == pytest.approx(effective_lande(jl, ju, gl, gu))


def test_bad_line_data_is_refused():
    with pytest.raises(ValueError, match="dipole"):
        FE_I_6173.replace(j_lower=0, j_upper=0)
    with pytest.raises(ValueError, match="vdw_sigma"):
        FE_I_6173.replace(vdw_alpha=None)
    with pytest.raises(ValueError, match="element"):
        FE_I_6173.replace(element="Xx")
    with pytest.raises(ValueError, match="gamma_rad"):
        NiLineData(gamma_rad=-1.0)


def test_abo_width_matches_barklems_tabulated_width():
    """Barklem, Piskunov & O'Mara (2000) tabulate for Fe I 6173.340 log(FWHM per H atom at 10 000 K) =
    -7.690 (rad s^-1 cm^3) beside sigma = 281, alpha = 0.266: our coefficient, with the temperature law
    T^((1 - alpha)/2) and the helium term taken out, reproduces it to the table's last digit."""
    const, _ = line_constants("Fe I 617.3")
    assert const[12] == pytest.approx((1 - 0.266) / 2)
    gamma_h = const[8] * 1e4 ** const[12] / (1 + 0.42 * ABUNDANCE["He"])
    assert math.log10(gamma_h) == pytest.approx(-7.690, abs=0.002)
    # Nickel keeps Unsöld's T^0.3 (it is not in the ABO list).
    assert line_constants()[0][12] == 0.3


def test_default_wavelength_follows_the_line():
    ni = default_wavelength()
    assert ni.size == 51 and ni[0] == 676.73 * u.nm and ni[-1] == 676.83 * u.nm      # the paper's grid
    fe = default_wavelength("Fe I 617.3")
    assert fe.size == 51 and fe[25].to_value(u.nm) == pytest.approx(617.33433)
    assert np.diff(fe.to_value(u.pm)) == pytest.approx(2.0)


@needs_data
def test_synthesis_in_fe_uses_the_line_and_its_continuum(models):
    falc = models["FAL-C"]
    fe = synthesize(falc, line="Fe I 617.3", progress=False)
    ni = synthesize(falc, progress=False)
    assert fe.meta["line"] == "Fe I 617.3" and fe.meta["lande_g"] == 2.5
    assert ni.meta["line"] == "Ni I 676.8" and ni.meta["lande_g"] == 1.426
    assert fe.wavelength[25].to_value(u.nm) == pytest.approx(617.33433)
    # The continuum is the line's own wavelength's: brighter at 617 nm (Planck and H- opacity), and the
    # tau_c = 1 height differs from Ni's; a LineData object works as well as its name.
    assert fe.I.value[0, 0, 0] > 1.1 * ni.I.value[0, 0, 0]
    assert reference_height(falc, "Fe I 617.3") != reference_height(falc, "Ni I 676.8")
    again = synthesize(falc, line=FE_I_6173, progress=False)
    assert np.array_equal(again.I.value, fe.I.value)
    with pytest.raises(ValueError, match="does not cover"):
        synthesize(falc, line="Fe I 617.3", wavelength=default_wavelength(), progress=False)


@needs_data
@pytest.mark.parametrize("name", ["FAL-C", "HSRA"])
def test_fe_disk_centre_profile_against_the_atlas(models, name):
    """1-D static LTE models have no granular (macroturbulent) broadening, so their lines come out deeper
    than the observed mean profile.  The same code's Ni I 676.8 line on the same models (same depth/FWHM
    measure) is 0.05 (FAL-C) and 0.11 (HSRA) deeper than the observed 0.6 and +9 % / -2 % in FWHM
    against the observed 10 pm; the two models' own widths differ by 10 %.  The Fe I line is asked
    the same: depth within [-0.03, +0.13] of the atlas, FWHM within 20 %.  (Measured: FAL-C 0.675,
    9.60 pm; HSRA 0.728, 8.69 pm.)"""
    lam0 = FE_I_6173.wavelength_nm
    cube = synthesize(models[name], line="Fe I 617.3", progress=False,
                      wavelength=np.linspace(lam0 - 0.06, lam0 + 0.06, 241) * u.nm)
    depth, fwhm = depth_fwhm(cube)
    assert -0.03 < depth - ATLAS_FE_DEPTH < 0.13
    assert 0.80 < fwhm / ATLAS_FE_FWHM_PM < 1.20


@needs_data
def test_fe_weak_field_v_follows_the_intensity_derivative(models):
    """V = -4.67e-13 g lambda^2 B dI/dlambda to first order in B with g = 2.5; DELO-linear on the 82-point
    FAL-C grid is good to a few per cent (3.4 % for Ni, test_rt), so 5 % of the V peak is asked."""
    lam0 = FE_I_6173.wavelength_nm
    lam = np.linspace(lam0 - 0.08, lam0 + 0.08, 321) * u.nm
    b = 30.0
    cube = synthesize(uniform_field(models["FAL-C"], b), line="Fe I 617.3", wavelength=lam, progress=False)
    i, v = cube.I.value[0, 0].astype(float), cube.V.value[0, 0].astype(float)
    pred = -ZEEMAN_CM_PER_G * (lam0 * 1e-7) ** 2 * 2.5 * b * np.gradient(i, lam.to_value(u.cm))
    assert np.abs(v - pred).max() < 0.05 * np.abs(pred).max()
    # and the truth is the same quantity for every line: B_LOS of a uniform vertical field
    assert cube.blos.value[0, 0] == pytest.approx(b)


def test_the_library_cache_key_includes_the_line():
    args = dict(seed=0, shape=(8, 8))
    keys = {library._key(dict(args, **extra), "model-atmosphere")
            for extra in ({}, {"line": "Fe I 617.3"}, {"line": NiLineData(lande_g=LANDE_LS)})}
    assert len(keys) == 3
