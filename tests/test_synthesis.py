"""Tests of the Milne–Eddington synthesis (gongsynth.sun.photosphere.synthesize) against physics."""
import astropy.constants as const
import astropy.units as u
import numpy as np
import pytest

from gongsynth import GONGInstrument
from gongsynth.sun.photosphere import (
    NiLine,
    Photosphere,
    model_photosphere,
    synthesize,
    zeeman_splitting,
)
from gongsynth.sun.photosphere.line import NECKEL_LABS_676
from gongsynth.sun.stokes import RADIANCE_UNIT

LAM0 = 676.78  # nm
FINE = np.linspace(676.70, 676.86, 1601) * u.nm          # 0.1 pm steps
KMS = u.km / u.s


def columns(B, inclination=0.0, azimuth=0.0, vz=0.0, vx=0.0, vy=0.0, continuum=1.0):
    """A Photosphere of one row holding the given columns (scalars broadcast)."""
    arrays = np.broadcast_arrays(*(np.atleast_1d(np.asarray(a, dtype=float))
                                   for a in (B, inclination, azimuth, vx, vy, vz, continuum)))
    B, inc, az, vx, vy, vz, cont = (a[None, :] for a in arrays)
    return Photosphere(B * u.G, inc * u.deg, az * u.deg, vx * KMS, vy * KMS, vz * KMS, cont, 96 * u.km)


def weak_field_v(i_profile, lam_nm, blos, g=1.5):
    """V = -4.67e-13 g λ0² B_LOS dI/dλ (λ in Å, B in G), derivative per Å."""
    lam_aa = lam_nm * 10
    didl = np.gradient(i_profile, lam_aa)
    return -4.6686e-13 * g * (LAM0 * 10) ** 2 * blos * didl


# ---------------------------------------------------------------- weak-field limit
@pytest.mark.parametrize("B", [5.0, 30.0, 100.0])
def test_weak_field_limit_for_longitudinal_field(B):
    cube = synthesize(columns([0.0, B]), wavelength=FINE)
    i0, v = cube.I.value[0, 0].astype(float), cube.V.value[0, 1].astype(float)
    expected = weak_field_v(i0, FINE.value, B)
    # Next order is (Δλ_B/Δλ_D)² ~ (0.32 pm B/100 G / 3.1 pm)² ≈ 1 % at 100 G.
    rel = np.abs(v - expected).max() / np.abs(expected).max()
    assert rel < 0.02
    # V > 0 on the blue wing for a field toward the observer (CONTRACTS sign).
    blue = FINE.value < LAM0
    assert v[blue][np.argmax(np.abs(v[blue]))] > 0


def test_weak_field_scales_with_line_of_sight_component_and_lande_factor():
    inc = np.array([0.0, 60.0, 120.0])
    cube = synthesize(columns(50.0, inclination=inc, azimuth=30.0), wavelength=FINE)
    i0 = synthesize(columns(0.0), wavelength=FINE).I.value[0, 0].astype(float)
    for k, gamma in enumerate(inc):
        blos = 50.0 * np.cos(np.radians(gamma))
        expected = weak_field_v(i0, FINE.value, blos)
        np.testing.assert_allclose(cube.V.value[0, k], expected, atol=0.02 * np.abs(expected).max() + 1e8)
    np.testing.assert_allclose(cube.blos.value[0], 50 * np.cos(np.radians(inc)), atol=1e-4)
    # g from the instrument, or from NiLine.lande_g when set
    g1 = synthesize(columns(50.0), wavelength=FINE, instrument=GONGInstrument().replace(lande_g=1.0))
    g143 = synthesize(columns(50.0), wavelength=FINE, line=NiLine(lande_g=1.43))
    v15 = cube.V.value[0, 0]
    assert np.abs(g1.V.value).max() / np.abs(v15).max() == pytest.approx(1 / 1.5, rel=0.01)
    assert np.abs(g143.V.value).max() / np.abs(v15).max() == pytest.approx(1.43 / 1.5, rel=0.01)
    assert g143.meta["lande_g"] == 1.43


# ----------------------------------------------------------------- strong fields
def _minima(profile, lam):
    """Wavelengths (pm from λ0) of the local minima deeper than 2 % of the continuum."""
    p = profile / profile[0]
    idx = [j for j in range(1, p.size - 1) if p[j] < p[j - 1] and p[j] <= p[j + 1] and p[j] < 0.98]
    return (lam[idx] - LAM0) * 1000


def test_zeeman_splitting_at_3kG_is_resolved():
    split = zeeman_splitting(3000 * u.G, LAM0 * u.nm, 1.5).to_value(u.pm)
    assert split == pytest.approx(0.0320758 * 3 * 100, rel=1e-4)      # paper: 0.03205 Å per kG
    cube = synthesize(columns(3000.0, inclination=[0.0, 90.0]), wavelength=FINE)
    lam = FINE.value
    longitudinal = _minima(cube.I.value[0, 0], lam)     # σ components only
    transverse = _minima(cube.I.value[0, 1], lam)       # π at centre and both σ
    np.testing.assert_allclose(longitudinal, [-split, split], atol=0.3)
    np.testing.assert_allclose(transverse, [-split, 0.0, split], atol=0.3)
    # Fully split V: the σ components carry opposite circular polarisation.
    v = cube.V.value[0, 0]
    blue_sigma = np.argmin(np.abs(lam - (LAM0 - split / 1000)))
    red_sigma = np.argmin(np.abs(lam - (LAM0 + split / 1000)))
    assert v[blue_sigma] > 0 > v[red_sigma]


def test_linear_polarisation_vanishes_for_longitudinal_and_appears_for_inclined_fields():
    az = np.array([0.0, 45.0, 90.0, 0.0])
    inc = np.array([90.0, 90.0, 90.0, 0.0])
    cube = synthesize(columns(800.0, inclination=inc, azimuth=az), wavelength=FINE)
    ic = cube.I.value[0, 0, 0]
    q, uu, v = cube.Q.value[0] / ic, cube.U.value[0] / ic, cube.V.value[0] / ic
    centre = np.argmin(np.abs(FINE.value - LAM0))
    # longitudinal: no Q/U at all
    assert np.abs(q[3]).max() < 1e-6 and np.abs(uu[3]).max() < 1e-6
    # transverse along e1 (= +x at disk centre): Q only, negative at line centre (π absorbs
    # the polarisation parallel to B), no V
    assert q[0, centre] < -0.02 and np.abs(uu[0]).max() < 1e-5 and np.abs(v[0]).max() < 1e-5
    # azimuth 45°: the signal moves to U; azimuth 90°: Q changes sign
    assert np.abs(uu[1]).max() > 0.02 and np.abs(q[1]).max() < 0.01 * np.abs(uu[1]).max()
    np.testing.assert_allclose(q[2], -q[0], atol=1e-6)
    # linear polarisation grows like B² in the weak-field regime
    weak = synthesize(columns([50.0, 100.0], inclination=90.0), wavelength=FINE)
    ratio = np.abs(weak.Q.value[0, 1]).max() / np.abs(weak.Q.value[0, 0]).max()
    assert ratio == pytest.approx(4.0, rel=0.02)


# ----------------------------------------------------------------- viewing angle
def test_vertical_field_at_60_degrees_projects_and_shows_transverse_signal():
    B = 100.0
    mu = 0.5
    cube = synthesize(columns([0.0, B]), mu=mu, wavelength=FINE)
    assert cube.blos.value[0, 1] == pytest.approx(B * mu, rel=1e-6)
    i0 = cube.I.value[0, 0].astype(float)
    expected = weak_field_v(i0, FINE.value, B * mu)
    v = cube.V.value[0, 1]
    assert np.abs(v - expected).max() < 0.02 * np.abs(expected).max()
    # the field's sky projection lies along e2 (north, toward the limb) → Q > 0 at line centre
    centre = np.argmin(np.abs(FINE.value - LAM0))
    assert cube.Q.value[0, 1, centre] > 0
    # U only from Faraday rotation (magneto-optical ρ_V), a few per cent of Q at 100 G
    assert np.abs(cube.U.value[0, 1]).max() < 0.1 * np.abs(cube.Q.value[0, 1]).max()


def test_horizontal_field_and_flow_toward_the_limb_seen_at_an_angle():
    # observer toward -y (region north of disk centre, los_azimuth = -90°)
    theta = np.radians(60.0)
    ph = columns([200.0, 200.0], inclination=90.0, azimuth=[90.0, -90.0], vy=[-1.0, 1.0])
    cube = synthesize(ph, mu=0.5, los_azimuth=-90 * u.deg, wavelength=FINE)
    np.testing.assert_allclose(cube.blos.value[0], [-200 * np.sin(theta), 200 * np.sin(theta)], rtol=1e-6)
    np.testing.assert_allclose(ph.los_velocity(0.5).value[0], [-np.sin(theta), np.sin(theta)], rtol=1e-6)
    # opposite line-of-sight components give opposite V (and opposite line shifts)
    v0, v1 = cube.V.value[0]
    blue = FINE.value < LAM0
    assert v0[blue][np.argmax(np.abs(v0[blue]))] < 0 < v1[blue][np.argmax(np.abs(v1[blue]))]
    shift = [FINE.value[np.argmin(cube.I.value[0, k])] - LAM0 for k in range(2)]
    assert shift[0] < 0 < shift[1]


def test_limb_darkening_and_continuum_level():
    mus = np.array([1.0, 0.8, 0.5, 0.3])
    ph = columns(np.zeros(4), continuum=1.0)
    ph_dark = columns(np.zeros(4), continuum=0.25)
    for mu in mus:
        c = synthesize(ph, mu=float(mu)).I.value[0, 0, 0]
        ld = np.polynomial.polynomial.polyval(mu, NECKEL_LABS_676)
        assert c == pytest.approx(3.0e14 * ld, rel=2e-3)    # 676.73 nm is 0.05 nm from the line core
    assert np.polynomial.polynomial.polyval(0.5, NECKEL_LABS_676) == pytest.approx(0.760, abs=1e-3)
    # the continuum proxy scales continuum and line alike (dark umbra = dark line)
    bright = synthesize(ph).I.value[0, 0]
    dark = synthesize(ph_dark).I.value[0, 0]
    np.testing.assert_allclose(dark, 0.25 * bright, rtol=1e-6)
    # Milne–Eddington: the line weakens toward the limb
    depth = [1 - synthesize(ph, mu=float(m)).I.value[0, 0].min() / (3e14 * np.polynomial.polynomial.polyval(
        m, NECKEL_LABS_676)) for m in mus]
    assert np.all(np.diff(depth) < 0)


def test_line_shift_follows_los_velocity():
    # a downflow at disk centre is a redshift: line minimum moves by λ0 v / c
    vz = np.array([0.0, -1.0, 2.0])
    cube = synthesize(columns(0.0, vz=vz), wavelength=FINE)
    lam = FINE.value
    for k, v in enumerate(vz):
        i = cube.I.value[0, k].astype(float)
        j = np.argmin(i)
        # parabolic refinement of the minimum
        a, b, c = i[j - 1], i[j], i[j + 1]
        lam_min = lam[j] + 0.5 * (a - c) / (a - 2 * b + c) * (lam[1] - lam[0])
        expected = LAM0 * (1 - v / const.c.to_value(KMS))
        assert lam_min == pytest.approx(expected, abs=2e-5)


def test_quiet_sun_mean_profile_has_the_solar_depth_and_width():
    ph = model_photosphere(shape=(128, 128), pixel_size=96 * u.km, spot=False, plage=False, seed=3)
    cube = synthesize(ph, wavelength=FINE)
    mean = cube.I.value.mean(axis=(0, 1), dtype=np.float64)
    ic = mean[0]
    depth = 1 - mean.min() / ic
    half = ic - 0.5 * (ic - mean.min())
    below = FINE.value[mean < half]
    fwhm_pm = (below[-1] - below[0]) * 1000
    assert depth == pytest.approx(0.60, abs=0.03)
    assert fwhm_pm == pytest.approx(10.0, abs=0.8)
    assert ic == pytest.approx(3.0e14, rel=0.02)
    # single static column: deeper and narrower
    static = synthesize(columns(0.0), wavelength=FINE).I.value[0, 0]
    assert 1 - static.min() / static[0] == pytest.approx(0.673, abs=0.005)


# ------------------------------------------------------------ numerics and geometry
def test_numba_kernel_matches_the_exact_numpy_reference():
    rng = np.random.default_rng(5)
    shape = (6, 7)
    ph = Photosphere(rng.uniform(0, 3500, shape) * u.G, rng.uniform(0, 180, shape) * u.deg,
                     rng.uniform(-180, 180, shape) * u.deg, rng.normal(0, 2, shape) * KMS,
                     rng.normal(0, 2, shape) * KMS, rng.normal(0, 2, shape) * KMS,
                     rng.uniform(0.2, 1.2, shape), 96 * u.km)
    mu = rng.uniform(0.2, 1.0, shape)
    az = rng.uniform(-180, 180, shape) * u.deg
    wide = np.linspace(676.0, 677.6, 400) * u.nm      # reaches the asymptotic branch (|v| > 40)
    for lam in (None, wide):
        fast = synthesize(ph, mu=mu, los_azimuth=az, wavelength=lam)
        ref = synthesize(ph, mu=mu, los_azimuth=az, wavelength=lam, method="numpy")
        for s in "IQUV":
            diff = np.abs(getattr(fast, s).value - getattr(ref, s).value).max()
            assert diff < 3e-6 * 3e14, s
        np.testing.assert_array_equal(fast.blos.value, ref.blos.value)


def test_per_column_geometry_equals_scalar_geometry_column_by_column():
    ph = columns([0.0, 500.0, 1500.0], inclination=[10.0, 70.0, 120.0], azimuth=[0.0, 40.0, -100.0],
                 vx=0.5, vy=-1.0, vz=0.3)
    mu = np.array([[1.0, 0.6, 0.3]])
    az = np.array([[-90.0, 20.0, 135.0]]) * u.deg
    cube = synthesize(ph, mu=mu, los_azimuth=az)
    assert isinstance(cube.mu, np.ndarray)
    for k in range(3):
        one = synthesize(ph[:, k], mu=float(mu[0, k]), los_azimuth=az[0, k])
        for s in "IQUV":
            np.testing.assert_array_equal(getattr(cube, s).value[:, k:k + 1], getattr(one, s).value)


def test_output_cube_metadata_and_default_grid():
    ph = model_photosphere(shape=(32, 32), pixel_size=3072 * u.km)
    cube = synthesize(ph, mu=0.8)
    assert cube.shape == (32, 32, 51)
    np.testing.assert_allclose(cube.wavelength.value, np.linspace(676.73, 676.83, 51))
    assert cube.pixel_size == 3072 * u.km and cube.mu == 0.8
    assert cube.I.dtype == np.float32 and cube.I.unit == RADIANCE_UNIT
    np.testing.assert_allclose(cube.blos.value, ph.los_field(0.8).value, rtol=1e-5, atol=1e-3)
    assert cube.meta["origin"] == "gongsynth.sun.photosphere.synthesize"
    assert cube.meta["photosphere"]["origin"] == "gongsynth.sun.photosphere.model_photosphere"


def test_bad_input_is_rejected():
    ph = columns([0.0, 100.0])
    with pytest.raises(TypeError, match="photosphere must be"):
        synthesize(np.zeros((2, 2)))
    with pytest.raises(ValueError, match="does not cover the line"):
        synthesize(ph, wavelength=np.linspace(676.0, 676.5, 10) * u.nm)
    with pytest.raises(ValueError, match="strictly increasing"):
        synthesize(ph, wavelength=np.linspace(676.83, 676.73, 51) * u.nm)
    with pytest.raises(u.UnitsError, match="wavelength"):
        synthesize(ph, wavelength=np.linspace(676.73, 676.83, 51) * u.s)
    with pytest.raises(ValueError, match=r"mu must be in \(0, 1\]"):
        synthesize(ph, mu=0.0)
    with pytest.raises(ValueError, match=r"mu must be a scalar or have shape \(ny, nx\) = \(1, 2\)"):
        synthesize(ph, mu=np.ones((2, 2)))
    with pytest.raises(TypeError, match="los_azimuth must be an astropy Quantity"):
        synthesize(ph, los_azimuth=-90)
    with pytest.raises(ValueError, match="method must be one of"):
        synthesize(ph, method="fortran")
    with pytest.raises(ValueError, match="instrument must be one of"):
        synthesize(ph, instrument="spectroheliograph")
    with pytest.raises(ValueError, match="NiLine.line_strength"):
        NiLine(line_strength=-1.0)
    with pytest.raises(ValueError, match="NiLine.limb_darkening"):
        NiLine(limb_darkening=(0.5, 0.6))


# ------------------------------------------------- optional: true radiative transfer
@pytest.mark.slow
@pytest.mark.validation
def test_me_line_is_realistic_against_lightweaver_falc():
    """LTE polarised transfer in FAL-C (lightweaver) vs the ME line: same depth, V and sign."""
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")        # lightweaver warns on import without a config file
        pytest.importorskip("lightweaver")
    from gongsynth.sun.photosphere.reference import falc_stokes

    lam = np.linspace(676.70, 676.86, 321) * u.nm
    fields = np.array([0.0, 100.0, 1000.0])
    rt = falc_stokes(fields * u.G, wavelength=lam)
    me = synthesize(columns(fields), wavelength=lam)
    assert rt.shape == me.shape == (1, 3, 321)
    I_rt, V_rt = rt.I.value[0].astype(float), rt.V.value[0].astype(float)
    I_me, V_me = me.I.value[0].astype(float), me.V.value[0].astype(float)
    # continuum: FAL-C in LTE gives 2.7e14, the observed disk centre 3.0e14
    assert I_rt[0, 0] == pytest.approx(I_me[0, 0], rel=0.15)

    def depth_fwhm(i):
        ic = i[0]
        below = lam.value[i < ic - 0.5 * (ic - i.min())]
        return 1 - i.min() / ic, (below[-1] - below[0]) * 1000

    d_rt, w_rt = depth_fwhm(I_rt[0])
    d_me, w_me = depth_fwhm(I_me[0])
    assert d_me == pytest.approx(d_rt, abs=0.03)          # 0.673 vs 0.672
    assert 0.7 < w_me / w_rt < 1.1                         # 9.1 pm vs 11.5 pm (single column)
    assert lam.value[np.argmin(I_rt[0])] == pytest.approx(LAM0, abs=1e-3)
    for k in (1, 2):
        amp_rt = np.abs(V_rt[k]).max() / I_rt[k, 0]
        amp_me = np.abs(V_me[k]).max() / I_me[k, 0]
        assert 0.85 < amp_me / amp_rt < 1.2                # 100 G: 5.1 % vs 4.6 %; 1 kG: 31 % vs 29 %
        # same sign convention and lobe positions (within 2 pm)
        assert lam.value[np.argmax(V_rt[k])] < LAM0 < lam.value[np.argmin(V_rt[k])]
        assert abs(lam.value[np.argmax(V_rt[k])] - lam.value[np.argmax(V_me[k])]) < 2e-3
