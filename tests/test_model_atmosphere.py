"""
The built-in 3-D model Sun (`gongsynth.sun.model_atmosphere`): construction, physics and statistics.

Statistics are compared with a genuine MURaM snapshot and a Stein & Nordlund
granulation slice (``../shared/data``; those tests skip without it), through
the same optical-depth computation and, for spectra, gongsynth's own RT.
Boxes are small (32²-64²) and seeded.
"""
from pathlib import Path

import astropy.units as u
import numpy as np
import pytest

import gongsynth
from gongsynth.sun.model_atmosphere import model_atmosphere
from gongsynth.sun.model_atmosphere import stratification as st
from gongsynth.sun.model_atmosphere.builder import reference_stratifications
from gongsynth.sun.model_atmosphere.granulation import PeriodicGrid
from gongsynth.sun.rt.eos import AMU, MEAN_MASS_PER_H, solve_state
from gongsynth.sun.rt.hydrostatic import SOLAR_GRAVITY, hydrostatic_tau_scale
from gongsynth.sun.rt.opacity import continuum_opacity

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
MURAM = DATA / "mhd" / "muram-test3d-it000000"
NS = DATA / "real" / "models" / "ns_y27_63x64.atmos"
needs_muram = pytest.mark.skipif(not (MURAM / "Header.000000").is_file(), reason="needs ../shared/data")
needs_ns = pytest.mark.skipif(not NS.is_file(), reason="needs ../shared/data")

QUIET = dict(spot=False, element_flux_density=0 * u.G)


def log_tau(temp, z_km, *, pressure=None, density=None, ne=None):
    """log10 τ₅₀₀ (nz, ...) integrated from the top, z increasing along axis 0."""
    s = solve_state(temp, gas_pressure=pressure, density=density, electron_density_=ne)
    k = continuum_opacity(500.0, temp, s["electron_density"], s["hydrogen_density"])
    dz = np.diff(z_km * 1e5).reshape((-1,) + (1,) * (temp.ndim - 1))
    seg = 0.5 * (k[1:] + k[:-1]) * dz
    tau = np.concatenate([np.cumsum(seg[::-1], axis=0)[::-1], np.zeros((1,) + temp.shape[1:])])
    return np.log10(np.maximum(tau, 1e-30)), s


def at_log_tau(field, lt, level):
    """``field`` interpolated per column to log τ = level (lt decreasing along axis 0)."""
    i1 = np.clip((lt > level).sum(0), 1, lt.shape[0] - 1)[None]
    i0 = i1 - 1
    l0, l1 = np.take_along_axis(lt, i0, 0)[0], np.take_along_axis(lt, i1, 0)[0]
    w = (level - l0) / (l1 - l0)
    return (1 - w) * np.take_along_axis(field, i0, 0)[0] + w * np.take_along_axis(field, i1, 0)[0]


def model_stats(atm):
    temp = atm.raw("temperature").astype(float)
    lt, _ = log_tau(temp, atm.z.to_value(u.km), pressure=atm.raw("gas_pressure").astype(float))
    return lt, temp, atm.raw("velocity")[2].astype(float)


def muram_stats():
    atm = gongsynth.Atmosphere.from_muram(MURAM)
    temp = atm.raw("temperature").astype(float)
    lt, _ = log_tau(temp, atm.z.to_value(u.km), density=atm.raw("density").astype(float),
                    ne=atm.raw("electron_density").astype(float))
    return lt, temp, atm.raw("velocity")[2].astype(float)


def ns_stats():
    raw = NS.read_bytes()
    a = np.frombuffer(raw[24:], ">f8")
    z = a[63:127][::-1].copy()
    temp, ne, _, _, vz, nh = (f[::-1] for f in a[127:].reshape(6, 64, 63))
    lt, _ = log_tau(temp, z, density=nh * 1e-6 * AMU * MEAN_MASS_PER_H, ne=ne * 1e-6)
    return lt, temp, vz


@pytest.fixture(scope="module")
def quiet_box():
    return model_atmosphere((48, 48), seed=11, nz=66, **QUIET)


# --- construction --------------------------------------------------------------------------------
def test_reproducible_and_seeded():
    a = model_atmosphere((32, 32), seed=5, nz=40)
    b = model_atmosphere((32, 32), seed=5, nz=40)
    c = model_atmosphere((32, 32), seed=6, nz=40)
    for name in ("temperature", "gas_pressure", "velocity", "magnetic_field"):
        assert np.array_equal(a.raw(name), b.raw(name)), name
        assert not np.array_equal(a.raw(name), c.raw(name)), name
        assert a.raw(name).dtype == np.float32
    assert a.shape == (40, 32, 32) and a.meta["seed_entropy"] == "5"


def test_periodic(quiet_box):
    """No seam: differences across the wrap are like differences between interior neighbours."""
    k = int(np.argmin(np.abs(quiet_box.z.value)))
    for name, f in (("T", quiet_box.raw("temperature")[k]), ("vz", quiet_box.raw("velocity")[2, k]),
                    ("Bx", quiet_box.raw("magnetic_field")[0, k])):
        inner = np.sqrt(np.mean(np.diff(f, axis=1) ** 2))
        seam = np.sqrt(np.mean((f[:, 0] - f[:, -1]) ** 2))
        assert seam < 2.0 * inner, name


@pytest.mark.parametrize("kwargs, match", [
    (dict(shape=(4, 32)), "shape"),
    (dict(pixel_size=96), "pixel_size"),
    (dict(pixel_size=-1 * u.km), "pixel_size"),
    (dict(nz=5), "nz"),
    (dict(height_range=(0, 700) * u.km), "height_range"),
    (dict(spot="yes"), "spot"),
    (dict(spot=True), "spot=True"),
    (dict(granulation_models="xyz"), "granulation_models"),
    (dict(granulation_amplitude=-1), "granulation_amplitude"),
    (dict(element_field=1500 * u.km), "element_field"),
    (dict(element_field=9000 * u.G), "element_field"),
    (dict(umbra_radius=20 * u.Mm), "umbra_radius"),
    (dict(positive_fraction=1.5), "positive_fraction"),
    (dict(umbra_model="z"), "umbra_model"),
    (dict(microturbulence=-1 * u.km / u.s), "microturbulence"),
    (dict(shape=(512, 512), height_range=(-250, 700) * u.km), "height_range.*umbra_field"),
])
def test_bad_input_names_the_argument(kwargs, match):
    args = dict(shape=(16, 16), seed=0)
    args.update(kwargs)
    with pytest.raises((ValueError, TypeError, u.UnitsError), match=match):
        model_atmosphere(**args)


def test_shallow_grid_without_spot():
    atm = model_atmosphere((16, 16), seed=0, nz=40, height_range=(-250, 600) * u.km)
    assert not atm.meta["spot"] and atm.z.value[0] == -250


def test_seed_is_required():
    with pytest.raises(TypeError, match="seed"):
        model_atmosphere((16, 16))


# --- 1-D stratifications -------------------------------------------------------------------------
def test_tau_scale_solver_matches_gongsynth_hydrostatics():
    t = st.model_temperature("hsra")
    z, p, _ = st.tau_scale_family(t[None])
    z2, p2, _ = hydrostatic_tau_scale(st.LOG_TAU, t)
    assert np.max(np.abs(p[0] / p2 - 1)) < 1e-3
    assert np.max(np.abs(z[0] - z2)) < 1.0


@needs_muram
def test_subsurface_extension_against_muram():
    """Below its table the extended HSRA follows MURaM's mean T (15 %) and P rise (10 %) at 300-500 km."""
    zg = np.linspace(-600, 700, 66)
    ref = reference_stratifications(tuple(zg))
    lt, temp, _ = muram_stats()
    atm = gongsynth.Atmosphere.from_muram(MURAM)
    z1 = at_log_tau(np.broadcast_to(atm.z.value[:, None, None], temp.shape), lt, 0.0).mean()
    pm = np.log(atm.raw("gas_pressure").astype(float).mean(axis=(1, 2)))
    p0_muram = np.interp(z1, atm.z.value, pm)
    p0_ref = np.interp(0.0, zg, ref["mean_lnp"])
    for depth in (-300.0, -500.0):
        k = int(np.argmin(np.abs(atm.z.value - z1 - depth)))
        t_ref = np.interp(depth, zg, ref["mean_t"])
        rise_ref = np.interp(atm.z.value[k] - z1, zg, ref["mean_lnp"]) - p0_ref
        assert abs(t_ref / temp[k].mean() - 1) < 0.15, depth
        assert rise_ref == pytest.approx(pm[k] - p0_muram, rel=0.10), depth


def test_pressure_balance_places_the_magnetic_models():
    """P_int(τ=1) + B²/8π = P_ext at the depressed height, for the element and the umbra."""
    zg = np.linspace(-600, 700, 131)
    ref = reference_stratifications(tuple(zg), element_field=1500.0, umbra_field=3000.0)
    for key, field in (("tube", 1500.0), ("umbra", 3000.0)):
        depth = ref[f"z_{key}"]
        p_int = np.exp(np.interp(depth, zg, ref[f"{key}_lnp"]))
        p_ext = np.exp(np.interp(depth, zg, ref["mean_lnp"]))
        assert p_int + field ** 2 / (8 * np.pi) == pytest.approx(p_ext, rel=0.02), key
    assert 0 < -ref["z_tube"] < -ref["z_umbra"]


# --- 3-D consistency -----------------------------------------------------------------------------
def test_hydrostatic_consistency(quiet_box):
    """dP/dz = −ρg in the quiet box to a few per cent (each component is hydrostatic; blends nearly)."""
    z = quiet_box.z.to_value(u.cm)
    p = quiet_box.raw("gas_pressure").astype(float)
    rho = solve_state(quiet_box.raw("temperature").astype(float), gas_pressure=p)["density"]
    dpdz = np.diff(p, axis=0) / np.diff(z)[:, None, None]
    rho_mid = 0.5 * (rho[1:] + rho[:-1])
    zmid = 0.5 * (z[1:] + z[:-1]) * 1e-5
    sel = (zmid > -400) & (zmid < 600)
    ratio = -dpdz[sel] / (rho_mid[sel] * SOLAR_GRAVITY)
    assert np.median(np.abs(ratio - 1)) < 0.02
    assert np.percentile(np.abs(ratio - 1), 95) < 0.08


def test_anelastic_flow_divergence(quiet_box):
    """∇·(ρ̄ v) = 0: the horizontal divergence cancels ∂z(ρ̄ v_z) to < 2 % of its size."""
    ref = reference_stratifications(tuple(quiet_box.z.value))
    rho = ref["density"]
    v = quiet_box.raw("velocity").astype(float)
    grid = PeriodicGrid(48, 48, 96.0)
    z = quiet_box.z.value
    vert = np.gradient(rho[:, None, None] * v[2], z, axis=0)
    horiz = np.stack([rho[k] * (grid.gradient(v[0, k])[0] + grid.gradient(v[1, k])[1])
                      for k in range(z.size)])
    sel = (z > -400) & (z < 600)
    assert np.sqrt(np.mean((vert + horiz)[sel] ** 2)) < 0.02 * np.sqrt(np.mean(vert[sel] ** 2))
    # Outflows from the granules: horizontal divergence positive where v_z > 0 at tau = 1.
    k = int(np.argmin(np.abs(z)))
    assert np.corrcoef(horiz[k].ravel(), v[2, k].ravel())[0, 1] > 0.9


def test_magnetic_field_is_divergence_free():
    atm = model_atmosphere((48, 48), seed=4, nz=66, spot=False, element_flux_density=60 * u.G)
    b = atm.raw("magnetic_field").astype(float)
    z = atm.z.value
    grid = PeriodicGrid(48, 48, 96.0)
    base = -atm.meta["wilson_depression_km"]["element"]
    sel = np.flatnonzero(z > base + 40)[1:-1]
    div = np.stack([grid.gradient(b[0, k])[0] + grid.gradient(b[1, k])[1]
                    + (b[2, k + 1] - b[2, k - 1]) / (z[k + 1] - z[k - 1]) for k in sel])
    scale = np.stack([np.abs(b[2, k + 1] - b[2, k - 1]) / (z[k + 1] - z[k - 1]) for k in sel])
    assert np.sqrt(np.mean(div ** 2)) < 0.05 * np.sqrt(np.mean(scale ** 2))


def test_internetwork_weak_mixed_mostly_horizontal(quiet_box):
    k = int(np.argmin(np.abs(quiet_box.z.value)))
    b = quiet_box.raw("magnetic_field")[:, k].astype(float)
    bh = np.sqrt(np.mean(b[0] ** 2 + b[1] ** 2))
    bz = np.sqrt(np.mean(b[2] ** 2))
    assert 10 < bh < 100 and 3 < bz < 40
    assert bh > 3 * bz
    assert abs(b[2].mean()) < 0.2 * bz


# --- statistics against MURaM and Stein & Nordlund ------------------------------------------------
def _granulation_facts(lt, temp, vz):
    """T and v_z statistics at log τ = 0, −1, −2 (rms and the T–v_z correlation)."""
    out = {}
    for level in (0.0, -1.0, -2.0):
        t, v = at_log_tau(temp, lt, level), at_log_tau(vz, lt, level)
        out[level] = (t.std(), v.std(), np.corrcoef(t.ravel(), v.ravel())[0, 1])
    return out


@needs_muram
@needs_ns
def test_granulation_statistics_against_simulations(quiet_box):
    """
    Hot upflows at τ = 1, contrast and velocities fading with height, as in MURaM and Stein & Nordlund.

    The model's rms values are smaller than the simulations' (its ΔT(log τ) is
    that of spatially averaged two-component models); the facts tested are the
    ones all three share: the ranges and the signs.
    """
    stats = {"model": _granulation_facts(*model_stats(quiet_box)),
             "muram": _granulation_facts(*muram_stats()), "ns": _granulation_facts(*ns_stats())}
    for name, s in stats.items():
        t0, v0, c0 = s[0.0]
        assert 150 < t0 < 1200, (name, t0)            # several hundred K at tau = 1
        assert 1.0 < v0 < 4.0, (name, v0)             # ~2 km/s at tau = 1
        assert c0 > 0.5, (name, c0)                   # hot upflows, cool downflows
        assert s[-2.0][1] < 0.7 * v0, name            # velocities decay with height
        assert s[-2.0][2] < c0 - 0.2, name            # the T-v correlation fades / reverses above


@pytest.fixture(scope="module")
def quiet_spectra(quiet_box):
    return gongsynth.rt.synthesize(quiet_box, progress=False)


def _line_facts(cube):
    i = cube.I.value.astype(float)
    ic = i[..., 0]
    wl = cube.wavelength.to_value(u.pm)
    prof = i.mean(axis=(0, 1)) / i[..., 0].mean()
    depth = 1 - prof.min()
    fine = np.linspace(wl[0], wl[-1], 2001)
    below = fine[np.interp(fine, wl, prof) < 1 - depth / 2]
    return ic.std() / ic.mean(), depth, below.max() - below.min()


def test_continuum_contrast_and_mean_line(quiet_spectra):
    """676.8 nm contrast of order 10 % (Sun 13-15 %, MURaM 20 %); Ni I depth ~0.6-0.7, FWHM ~10 pm."""
    contrast, depth, fwhm = _line_facts(quiet_spectra)
    assert 0.05 < contrast < 0.25
    assert 0.55 < depth < 0.8
    assert 6.0 < fwhm < 13.0


# --- kG elements --------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def element_box():
    atm = model_atmosphere((48, 48), seed=3, nz=66, spot=False, element_flux_density=150 * u.G)
    base = int(np.argmin(np.abs(atm.z.value + atm.meta["wilson_depression_km"]["element"])))
    bz = np.abs(atm.raw("magnetic_field")[2, base])
    core, quiet = bz > 1300, bz < 50
    assert core.sum() >= 5 and quiet.sum() > 500
    return atm, core, quiet


def test_kg_elements_field_depression_and_heating(element_box):
    atm, core, quiet = element_box
    lt, temp, _ = model_stats(atm)
    b = np.sqrt((atm.raw("magnetic_field").astype(float) ** 2).sum(axis=0))
    z = np.broadcast_to(atm.z.value[:, None, None], temp.shape)
    b1 = at_log_tau(b, lt, 0.0)[core]
    assert 1200 < np.median(b1) < 1900                     # ~1.3-1.7 kG at tau = 1
    z1 = at_log_tau(z, lt, 0.0)
    assert z1[core].mean() < z1[quiet].mean() - 20         # the tau = 1 surface sinks (Wilson depression)
    for level, excess in ((0.0, 200), (-1.0, 400), (-2.0, 150)):  # hot: network model above log tau -1
        t = at_log_tau(temp, lt, level)
        assert t[core].mean() > t[quiet].mean() + excess, level


def test_ni_line_weaker_in_kg_elements(element_box):
    """The physics behind GONG's under-measurement: Ni I 676.8 weakens in the hot elements."""
    atm, core, quiet = element_box
    cube = gongsynth.rt.synthesize(atm, progress=False)
    i = cube.I.value.astype(float)
    ic = i[..., 0]
    dl = np.diff(cube.wavelength.to_value(u.pm))[0]
    ew = (1 - i / ic[..., None]).sum(axis=-1) * dl
    depth = 1 - i.min(axis=-1) / ic
    assert ew[core].mean() < 0.75 * ew[quiet].mean()
    assert depth[core].mean() < depth[quiet].mean() - 0.1
    assert ic[core].mean() > ic[quiet].mean()               # bright points


def test_kg_elements_carry_most_unsigned_flux():
    """Default budget: the elements (their own random stream) carry most of the unsigned vertical flux."""
    def unsigned(**kw):
        atm = model_atmosphere((64, 64), seed=8, nz=40, spot=False, **kw)
        base = int(np.argmin(np.abs(atm.z.value + atm.meta["wilson_depression_km"]["element"])))
        return np.abs(atm.raw("magnetic_field")[2, base].astype(float)).mean()

    assert unsigned(internetwork_field=0 * u.G, internetwork_horizontal_field=0 * u.G) > 0.5 * unsigned()


# --- sunspot --------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def spot_box():
    return model_atmosphere((96, 96), 96 * u.km, seed=2, nz=66, spot=True, umbra_radius=1.5 * u.Mm,
                            penumbra_radius=3.5 * u.Mm, element_flux_density=0 * u.G)


def test_sunspot(spot_box):
    atm = spot_box
    lt, temp, _ = model_stats(atm)
    b = atm.raw("magnetic_field").astype(float)
    z = np.broadcast_to(atm.z.value[:, None, None], temp.shape)
    c = 48
    z1 = at_log_tau(z, lt, 0.0)
    bz1 = at_log_tau(b[2], lt, 0.0)
    bh1 = at_log_tau(np.hypot(b[0], b[1]), lt, 0.0)
    assert 2500 < bz1[c, c] < 3500                          # umbral field at tau = 1
    assert 300 < np.median(z1[:8, :8]) - z1[c, c] < 700      # umbral Wilson depression
    assert at_log_tau(temp, lt, 0.0)[c, c] < 5000            # cool umbra
    yy, xx = np.mgrid[:96, :96]
    r = np.hypot(yy + 0.5 - 48, xx + 0.5 - 48) * 96.0
    pen = (r > 2000) & (r < 3300)
    incl = np.degrees(np.arctan2(bh1[pen], np.abs(bz1[pen])))
    assert np.median(incl) > 30                              # inclined penumbral field
    v = atm.raw("velocity")
    k = int(np.argmin(np.abs(atm.z.value)))
    vr = (v[0, k] * (xx + 0.5 - 48) + v[1, k] * (yy + 0.5 - 48)) / np.maximum(r / 96.0, 1e-9)
    assert vr[pen].mean() > 0.3                              # Evershed outflow
    assert b[2, k].mean() > 0                                # net positive polarity


def test_ablation_switches():
    """element_model='quiet', element_depression=False and canopy=False each remove one ingredient."""
    base = dict(shape=(32, 32), seed=9, nz=40, spot=False, element_flux_density=150 * u.G)
    ref = model_atmosphere(**base)
    k = int(np.argmin(np.abs(ref.z.value - 300)))
    cold = model_atmosphere(**base, element_model="quiet")
    assert cold.raw("temperature")[k].max() < ref.raw("temperature")[k].max()
    flat = model_atmosphere(**base, element_depression=False)
    assert flat.meta["wilson_depression_km"]["element"] == 0.0 < ref.meta["wilson_depression_km"]["element"]
    tubes = model_atmosphere(**base, canopy=False, internetwork_horizontal_field=0 * u.G,
                             internetwork_field=0 * u.G)
    b = tubes.raw("magnetic_field")
    assert np.abs(b[:2]).max() == 0 and np.array_equal(b[2, 0], b[2, -1])
    with pytest.raises(ValueError, match="canopy"):
        model_atmosphere(**base, canopy="no")
