"""
The full-disk patch library from the 3-D Sun (`gongsynth.stages.scene.library_rt`), on tiny grids.

Checked against independent computations: the radiative transfer of the same
column projected on the Doppler basis directly, the exact B·n of a uniform
vertical field, the Milne-Eddington library's cache (the keys must differ),
and the chain's own repeatability.
"""
import astropy.units as u
import numpy as np
import pytest

import gongsynth
import gongsynth.chain as chain_module
from gongsynth import GONGInstrument
from gongsynth.config import SimulationConfig
from gongsynth.seeding import as_seed_sequence, child_sequence
from gongsynth.stages.scene import library as library_module
from gongsynth.stages.scene.disk_render import library_scene
from gongsynth.stages.scene.fulldisk import DEFAULT_CELL
from gongsynth.stages.scene.library import cached_library
from gongsynth.stages.scene.library_rt import (
    PATCH_FLOW_CUTOFF,
    STRONG_COLUMNS,
    TILED_COLUMN,
    atmosphere_grid,
    build_atmosphere_library,
)
from gongsynth.sun.model_atmosphere import model_atmosphere
from gongsynth.sun.rt import synthesize as rt_synthesize

TINY = dict(shape=(8, 8), pixel_size=3 * u.Mm, theta=(0.0, 60.0), knobs={"nz": 40})
WHOLE = GONGInstrument(plate_scale=20 * u.arcsec)


@pytest.fixture(scope="module")
def tiny_library():
    return build_atmosphere_library(seed=2, **TINY)


def test_levels_and_strong_columns(tiny_library):
    lib = tiny_library
    assert lib.n_levels == 4 + len(STRONG_COLUMNS) and lib.meta["sun"] == "model-atmosphere"
    # The levels' net flux increases from the balanced quiet Sun through plage to the sunspot columns.
    assert lib.level_net[0] == 0 and np.all(np.diff(lib.level_net) > 0)
    assert lib.level_net[3] > lib.level_net[1] > 0
    layout = lib.layout()
    # A patch level's net flux is the mean of its stored truth at disk centre.
    first = lib.patches[lib.level_patches[2][0], :, :, 0, layout["bz"]]
    assert first.mean() == pytest.approx(lib.level_net[2], rel=1e-5)
    # A uniform vertical field: B·n = B cos θ at every angle, stored as B_z = B (B_x = 0).
    for number, (_, knob) in enumerate(STRONG_COLUMNS):
        field = model_atmosphere.__kwdefaults__[knob].to_value(u.G)
        assert np.allclose(lib.uniform[number, :, layout["bz"]], field, rtol=1e-6)
        assert np.all(lib.uniform[number, :, layout["bx"]] == 0)
    # Umbrae are darker than penumbrae, both darker than the quiet Sun's mean continuum.
    quiet = lib.patches[lib.level_patches[0][0], :, :, 0, 0].mean()
    assert lib.uniform[1, 0, 0] < lib.uniform[0, 0, 0] < quiet


def test_rows_are_the_transfer_projected_on_the_basis(tiny_library):
    """A patch's stored rows against rt.synthesize of the same atmosphere, projected by the basis."""
    lib = tiny_library
    seed = child_sequence(as_seed_sequence(2), "library", 1, 0)      # the enhanced-network patch
    atm = model_atmosphere((8, 8), pixel_size=3 * u.Mm, seed=seed, nz=40, element_flux_density=30 * u.G,
                           positive_fraction=0.8, spot=False, flow_cutoff=PATCH_FLOW_CUTOFF)
    layout = lib.layout()
    j1 = lib.rank + 1
    eps = np.finfo(np.float32).eps
    for t, angle in enumerate(lib.theta):
        mu = np.cos(np.radians(angle))
        cube = rt_synthesize(atm, mu=mu, progress=False)
        ld = lib.line.limb_darkening_factor(mu)
        stored = lib.patches[lib.level_patches[1][0], :, :, t]
        for name, start in (("I", layout["e"][0]), ("V", layout["v"])):
            spectra = getattr(cube, name).value.reshape(-1, cube.shape[-1])
            cont, coords = lib.basis.coordinates(spectra)
            want = np.concatenate([cont[:, None], coords], axis=1) / ld
            got = stored[:, :, start:start + j1].reshape(want.shape)
            # float32 spectra through the basis vectors: the coordinates' rounding (|E| summed).
            bound = 4 * eps * np.abs(cube.I.value).max() / ld * (1 + np.abs(lib.basis.vectors).sum())
            assert np.abs(got - want).max() <= bound
        assert np.allclose(stored[:, :, layout["bz"]] * mu, cube.blos.value, rtol=1e-6, atol=1e-4)


def test_cached_and_reloaded_bit_identical_with_its_own_key(tmp_path, monkeypatch):
    monkeypatch.setenv("GONGSYNTH_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(library_module, "_MEMO", {})
    args = dict(TINY, seed=3)
    built = cached_library(sun="model-atmosphere", **args)
    assert cached_library(sun="model-atmosphere", **args) is built
    monkeypatch.setattr(library_module, "_MEMO", {})
    loaded = cached_library(sun="model-atmosphere", progress=True, **args)     # progress is not in the key
    assert loaded is not built and "cache" in loaded.meta and loaded.meta["spectra_carry_blueshift"]
    assert np.array_equal(loaded.patches, built.patches) and np.array_equal(loaded.uniform, built.uniform)
    assert np.array_equal(loaded.level_net, built.level_net)
    # The Milne-Eddington library of the same arguments is another cache entry.
    cached_library(sun="milne-eddington", shape=(8, 8), pixel_size=3 * u.Mm, theta=(0.0, 60.0), seed=3,
                   seeds_per_level=(1, 1, 1, 1))
    assert len(list(tmp_path.iterdir())) == 2
    with pytest.raises(ValueError, match="sun must be"):
        cached_library(sun="muram", **args)


def test_the_default_grid_is_one_sun_for_every_instrument():
    """One grid (the tiled run's 384 km columns, one surface cell) whatever the instrument; a coarser
    grid of the same seed is another Sun, which is why (the builder draws its elements on its grid)."""
    shape, column = atmosphere_grid()
    assert column == TILED_COLUMN and shape[0] == shape[1] >= 8
    assert shape[0] * column >= DEFAULT_CELL > (shape[0] - 1) * column
    from gongsynth.seeding import as_seed_sequence, child_sequence
    from gongsynth.sun.model_atmosphere import model_atmosphere

    def bz(n, km):
        seed = child_sequence(as_seed_sequence(0), "library", 0, 0)
        box = model_atmosphere((n, n), pixel_size=km * u.km, seed=seed, spot=False, network=False, nz=40)
        return box.magnetic_field[2, np.argmin(np.abs(box.z.to_value(u.km)))].value
    fine, coarse = bz(32, 384), bz(16, 768)
    r = np.corrcoef(fine.reshape(16, 2, 16, 2).mean(axis=(1, 3)).ravel(), coarse.ravel())[0, 1]
    assert r < 0.5       # the same box and seed, another field (0.03 here; one Sun would be > 0.9)


def test_the_default_grid_is_in_the_cache_key(tmp_path, monkeypatch, tiny_library):
    """The default grid is in the key, the same for every plate scale: one entry; a grid given, another."""
    import gongsynth.stages.scene.library_rt as library_rt

    monkeypatch.setenv("GONGSYNTH_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(library_module, "_MEMO", {})
    grids = []

    def record(**arguments):            # the builder is tested above: here only what it is given
        grids.append((arguments["shape"], arguments["pixel_size"]))
        return tiny_library

    monkeypatch.setattr(library_rt, "build_atmosphere_library", record)
    args = dict(theta=(0.0, 60.0), knobs={"nz": 40}, seed=3)
    coarse = GONGInstrument(plate_scale=25 * u.arcsec)
    first = cached_library(sun="model-atmosphere", instrument=coarse, **args)
    assert grids == [atmosphere_grid()]
    gong = GONGInstrument(plate_scale=2.5 * u.arcsec)
    same = cached_library(sun="model-atmosphere", instrument=gong, **args)
    assert same is first and len(list(tmp_path.iterdir())) == 1 and len(grids) == 1
    # A grid given explicitly is the builder's, whatever the instrument's pixel.
    cached_library(sun="model-atmosphere", instrument=coarse, shape=(8, 8), pixel_size=3 * u.Mm, **args)
    assert len(list(tmp_path.iterdir())) == 2
    # HMI and MDI (other lines and filters: other entries) are given the same grid as GONG.
    for name in ("hmi", "mdi"):
        cached_library(sun="model-atmosphere", instrument=name, **args)
    assert grids[2:] == [atmosphere_grid()] * 2 and len(list(tmp_path.iterdir())) == 4
    assert grids[1] == ((8, 8), 3 * u.Mm)


def test_the_scene_leaves_out_the_tabulated_blueshift(tiny_library):
    light, _ = library_scene(tiny_library, instrument=WHOLE, detector_shape=100, supersampling=1)
    # No network given: no supergranular cells to flow either.
    assert light.meta["velocities"] == {"rotation": True, "observer": True, "blueshift": False,
                                        "supergranulation": False}


def test_a_full_disk_run_of_the_3d_sun_repeats_by_seed(tmp_path, monkeypatch):
    """The full disk's default Sun is the 3-D one (a tiny library here); same seed, same map."""
    monkeypatch.setenv("GONGSYNTH_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(library_module, "_MEMO", {})
    calls = []

    def tiny(**arguments):
        calls.append(arguments["sun"])
        return cached_library(**{**arguments, **TINY})

    monkeypatch.setattr(chain_module, "cached_library", tiny)
    coarse = GONGInstrument(plate_scale=20 * u.arcsec, detector_shape=100, supersampling=2)
    config = SimulationConfig(mode="full-disk", instrument=coarse, seed=5, duration=1 * u.min,
                              photosphere={"nz": 40})
    first = gongsynth.simulate(config=config, progress=False)
    again = gongsynth.simulate(config=first.config, progress=False)
    other = gongsynth.simulate(config=config.replace(seed=6), progress=False)
    assert calls == ["model-atmosphere"] * 3 and first.config.sun == "model-atmosphere"
    assert np.array_equal(again.magnetogram.data, first.magnetogram.data, equal_nan=True)
    on = np.isfinite(first.magnetogram.data)
    assert on.mean() > 0.5 and not np.array_equal(other.magnetogram.data[on], first.magnetogram.data[on])
