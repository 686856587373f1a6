"""Full-disk HMI: the patch library in the instrument's line, its cache key, the plane groups, HMI's PSF."""
import astropy.units as u
import numpy as np
import pytest

from gongsynth import instruments
from gongsynth.instruments.hmi.psf import WACHTER_2012, encircled_energy, radius_unit
from gongsynth.stages.psf import psf_kernel, psf_profile
from gongsynth.stages.scene import disk_render
from gongsynth.stages.scene.disk_render import library_scene
from gongsynth.stages.scene.library import _key, build_library
from gongsynth.sun.photosphere import NiLine, me_line, model_photosphere, synthesize
from gongsynth.sun.photosphere.line import NECKEL_LABS_617

HMI = instruments.get("hmi")
GONG = instruments.get("gong")
TINY = dict(shape=(12, 12), pixel_size=3 * u.Mm, seeds_per_level=(1, 1, 1, 1), theta=(0, 60))


@pytest.fixture(scope="module")
def hmi_library():
    return build_library(instrument=HMI, **TINY)


def test_library_key_follows_the_instrument_and_its_line():
    """GONG's library is never taken for HMI's; parameters that do not shape the rows share a key."""
    args = dict(seed=0, knobs={})
    gong, hmi = _key({**args, "instrument": GONG}, "milne-eddington"), _key({**args, "instrument": HMI},
                                                                             "milne-eddington")
    assert gong != hmi
    assert _key({**args, "instrument": HMI}, "model-atmosphere") not in (gong, hmi)
    # optics and camera: the same library; a filter or the Landé factor: another one
    assert _key({**args, "instrument": HMI.replace(plate_scale=8 * u.arcsec, detector_shape=256)},
                "milne-eddington") == hmi
    for change in ({"nb_fsr": 171 * u.mAA}, {"lande_g": 2.4 * u.one}):
        assert _key({**args, "instrument": HMI.replace(**change)}, "milne-eddington") != hmi


def test_the_hmi_library_is_synthesised_in_fe_i(hmi_library):
    """The Milne-Eddington description of Fe I 617.3, its limb darkening, HMI's 12 planes."""
    assert hmi_library.line == me_line("Fe I 617.3") and hmi_library.line.limb_darkening == NECKEL_LABS_617
    assert hmi_library.basis.amplitudes.shape[1] == 6        # six tunings per polarisation
    assert me_line(GONG.line) == NiLine()      # GONG's library keeps Ni I (its default line)
    light, truth = library_scene(hmi_library, instrument=HMI.replace(plate_scale=40 * u.arcsec),
                                 detector_shape=64, supersampling=1)
    data = light.data.value
    centre = data[:, 32, 32]
    assert data.shape == (12, 64, 64) and np.all(centre > 0)
    # I±V at each tuning: the line's wings (I0, I5) brighter than its core (I2, I3) in both states
    for pol in (0, 1):
        p = centre[6 * pol:6 * pol + 6]
        assert min(p[0], p[5]) > max(p[2], p[3])


def test_fe_i_milne_eddington_profile_matches_the_atlas():
    """Disk-centre mean profile of the built-in photosphere: depth 0.62, FWHM 10.2 pm (Norton et al. 2006)
    to within the patch-to-patch scatter of a smaller patch than the fit's."""
    ph = model_photosphere(shape=(64, 64), pixel_size=96 * u.km, seed=0, spot=False)
    lam = np.linspace(-0.25, 0.25, 251) * u.nm + HMI.line_wavelength
    i = synthesize(ph, 1.0, lam, instrument=HMI).I.value.mean(axis=(0, 1)).astype(float)
    x = lam.to_value(u.pm)
    depth = 1 - i.min() / i[0]
    half = i[0] * (1 - depth / 2)
    core = int(np.argmin(i))
    left = np.interp(half, i[:core + 1][::-1], x[:core + 1][::-1])    # I decreasing to the core
    right = np.interp(half, i[core:], x[core:])
    assert abs(depth - 0.62) < 0.01 and abs(right - left - 10.2) < 0.3


def test_plane_groups_render_the_same_light(hmi_library, monkeypatch):
    """A grid rendered a group of planes at a time (bounded memory) has the same bits as all at once."""
    inst = HMI.replace(plate_scale=40 * u.arcsec)
    whole, truth = library_scene(hmi_library, instrument=inst, detector_shape=48, supersampling=1, seed=3)
    monkeypatch.setattr(disk_render, "LIGHT_BYTES", 5 * 48 * 48 * 4)      # groups of 5 planes: 5, 5, 2
    grouped, truth2 = library_scene(hmi_library, instrument=inst, detector_shape=48, supersampling=1, seed=3)
    planes = grouped.planes
    assert type(planes).__name__ == "DeferredStack"
    for i in (0, 7, 11, 2, 5):   # out of order: a group is rendered again when asked for
        assert np.array_equal(np.asarray(planes[i]), whole.data.value[i])
    assert np.array_equal(planes[6][10:20], whole.data.value[6, 10:20])
    assert np.array_equal(truth.data, truth2.data)


def test_hmi_psf_is_wachters_through_the_shared_stage():
    """The optics stage's PSF of HMI is its instrument's (Wachter et al. 2012), GONG's the Airy ⊗ seeing."""
    r = np.array([0.0, 0.5, 3.0, 30.0])
    unit = radius_unit(HMI)
    x = r / unit
    p = WACHTER_2012
    shape = (1 - p["epsilon"]) * np.exp(-(x / p["omega"]) ** 2) + p["epsilon"] / (1 + (x / p["width"]) ** 3)
    values = psf_profile(r * u.arcsec, HMI).to_value(u.arcsec**-2)
    assert np.allclose(values / values[0], shape / shape[0], rtol=1e-12)
    # unit integral: the analytic encircled energy at 60″ against the sampled kernel's truncation
    scale = HMI.plate_scale.to_value(u.arcsec) / HMI.supersampling
    radii = np.arange(0, 60, 0.01) + 0.005
    inside = np.sum(2 * np.pi * radii * psf_profile(radii * u.arcsec, HMI).value) * 0.01
    assert inside == pytest.approx(encircled_energy(60.0, HMI), rel=1e-4)
    assert 1 - encircled_energy(10.0, HMI) == pytest.approx(0.0307, abs=5e-4)
    kernel = psf_kernel(scale * u.arcsec, HMI)
    assert kernel.shape[0] == 2 * int(np.ceil(60 / scale)) + 1 and kernel.sum() == pytest.approx(1)
    # GONG: unchanged, the Airy pattern's first zero at 1.22 λ/D
    airy = psf_profile([0, 6.08] * u.arcsec, GONG, seeing=False).value
    assert airy[1] < 1e-4 * airy[0]


def test_light_made_by_bands_images_as_the_whole_light(hmi_library, monkeypatch):
    """A grid too large to hold goes through the optics in bands of rows, rendered once: the same
    expected counts and truth as the whole light through the whole-plane operator, to float32 rounding."""
    from gongsynth.stages import imagers
    from gongsynth.stages.optics import image_scene
    inst = HMI.replace(plate_scale=40 * u.arcsec)
    whole = image_scene(*library_scene(hmi_library, instrument=inst, detector_shape=48, seed=3), inst)
    monkeypatch.setattr(disk_render, "LIGHT_BYTES", 5 * 96 * 96 * 4)
    monkeypatch.setattr(imagers, "_BAND_ROWS", 16)      # several bands, each slab moved on
    light, truth = library_scene(hmi_library, instrument=inst, detector_shape=48, seed=3)
    assert light.planes.has_bands
    banded = image_scene(light, truth, inst)
    scale = whole[0].value.max()
    assert np.abs(banded[0].value - whole[0].value).max() < 2e-6 * scale
    assert np.array_equal(banded[1], whole[1])                  # pixel means: the same bits
    assert np.allclose(banded[2].value, whole[2].value, rtol=0, atol=2e-6 * np.abs(whole[2].value).max())


def test_reduced_basis_keeps_every_filtergram_within_its_bound(hmi_library):
    """The render's lower-rank Doppler basis (issue 26, hmi26): each stored row's 12 filtergrams at every
    tabulated velocity within the returned bound (≤ the tolerance) of the full basis' (float32 rows:
    + 1e-6); the truth is untouched, and the scene says which rank it used."""
    tolerance, lib = 1e-3, hmi_library
    patches, uniform, amplitudes, bound = disk_render.render_rows(lib, tolerance)
    rank, j1, basis = amplitudes.shape[-1], lib.rank + 1, lib.basis
    assert rank < lib.rank and 0 < bound <= tolerance and patches.shape[-1] == 2 * (rank + 1) + 2
    old, new = lib.patches.reshape(-1, lib.row_size).astype(float), patches.reshape(-1, 2 * rank + 4)

    totals = basis.totals[::40]

    def channels(rows, width, amp):
        e, v = rows[:, :width], rows[:, width:2 * width]
        return np.stack([(s[:, :1, None] * totals[None] + np.einsum("vck,nk->nvc", amp, s[:, 1:]))
                         for s in (e + v, e - v)])

    full = channels(old, j1, basis.amplitudes[::40])
    reduced = channels(new.astype(float), rank + 1, amplitudes[::40])
    continuum = np.stack([c[:, None, None] * totals[None]
                          for c in (old[:, 0] + old[:, j1], old[:, 0] - old[:, j1])])
    assert np.abs(reduced - full).max() > 0         # a real change ...
    assert np.all(np.abs(reduced - full) <= (bound + 1e-6) * continuum)   # ... within its bound
    np.testing.assert_array_equal(new[:, -2:], old[:, -2:])          # B_z, B_x kept
    args = dict(instrument=HMI.replace(plate_scale=40 * u.arcsec), detector_shape=48, supersampling=1, seed=3)
    light, truth = library_scene(lib, basis_tolerance=tolerance, **args)
    light_full, truth_full = library_scene(lib, basis_tolerance=None, **args)
    assert light.meta["render_rank"] == rank and light_full.meta["render_rank"] == lib.rank
    np.testing.assert_array_equal(truth.data, truth_full.data)
    on = light_full.data.value > 0
    rel = np.abs(light.data.value - light_full.data.value)[on] / light_full.data.value[on]
    assert 0 < rel.max() < 2 * (bound + 1e-6)      # a line filtergram is ≥ half its continuum's here
    with pytest.raises(ValueError, match="basis_tolerance"):
        library_scene(lib, basis_tolerance="fast", **args)


def test_truth_comes_with_the_light_bands(hmi_library, monkeypatch):
    """A light made by bands writes its truth in the same passes (issue 26, hmi27): the truth read after
    the light, or before it (a pass of its own), has the bits of the whole render's, and the counts
    from the sight lines alone are the whole render's: samples on the disk, velocities off the table."""
    import dataclasses
    import warnings

    from gongsynth.stages.scene.scene import DeferredStack
    inst = HMI.replace(plate_scale=40 * u.arcsec)
    args = dict(instrument=inst, detector_shape=48, supersampling=2, seed=3)
    real = disk_render.large_scale_grid

    def fast(*a, **k):      # velocities beyond the basis' table in part of the disk
        large = real(*a, **k)
        return dataclasses.replace(large, velocity=large.velocity * 20 + 3000 * np.sign(large.velocity))

    for grid in (real, fast):
        monkeypatch.setattr(disk_render, "large_scale_grid", grid)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            light, truth = library_scene(hmi_library, **args)
        with monkeypatch.context() as m:
            m.setattr(disk_render, "LIGHT_BYTES", 5 * 96 * 96 * 4)
            with warnings.catch_warnings(record=True) as caught_bands:
                warnings.simplefilter("always")
                banded, banded_truth = library_scene(hmi_library, **args)
                early, early_truth = library_scene(hmi_library, **args)
        assert isinstance(banded_truth.planes, DeferredStack) and banded.planes.has_bands
        assert [str(w.message) for w in caught_bands] == 2 * [str(w.message) for w in caught]
        assert banded.meta["on_disk_samples"] == light.meta["on_disk_samples"] > 0
        # after the light's bands (as the optics read them), then before any light
        band = banded.planes.band(0, 50), banded.planes.band(50, 96)
        np.testing.assert_array_equal(np.concatenate(band, axis=1), light.data.value)
        np.testing.assert_array_equal(np.asarray(banded_truth.planes.plane()[0:96]), truth.data.value)
        np.testing.assert_array_equal(early_truth.planes.plane()[30:60], truth.data.value[30:60])
        np.testing.assert_array_equal(early_truth.data.value, truth.data.value)
        np.testing.assert_array_equal(early.blos.value, truth.data.value)
    assert "clamped" in str(caught[0].message)


def test_reduced_rows_are_kept_with_the_cached_library(tmp_path, monkeypatch):
    """The render's reduced rows (issue 26, hmi27) are computed once per cached library and read back
    with the same bits; another tolerance or reducing code is another copy, a damaged copy is made again,
    and a library outside the cache is reduced every time."""
    import warnings
    from pathlib import Path
    from types import SimpleNamespace

    from gongsynth.stages.scene import library as library_module
    from gongsynth.stages.scene.library import cached_library
    from gongsynth.stages.scene.library_store import CacheWarning, derived_arrays
    monkeypatch.setenv("GONGSYNTH_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(library_module, "_MEMO", {})
    calls = []
    reduce = disk_render._reduced_rows

    def counted(*args):
        calls.append(args[1])
        return reduce(*args)

    monkeypatch.setattr(disk_render, "_reduced_rows", counted)
    built = cached_library(instrument=HMI, seed=5, **TINY)
    assert "cache" in built.meta                       # a fresh build is in the cache at once
    first = disk_render.render_rows(built, 1e-3)
    monkeypatch.setattr(library_module, "_MEMO", {})
    loaded = cached_library(instrument=HMI, seed=5, **TINY)
    assert loaded is not built
    again = disk_render.render_rows(loaded, 1e-3)
    assert calls == [1e-3]                             # read back, not computed
    for a, b in zip(first, again):
        np.testing.assert_array_equal(a, b)
    assert first[3] > 0 and first[2].shape[-1] < built.rank
    disk_render.render_rows(loaded, 2e-3)
    assert calls == [1e-3, 2e-3]
    # the reducing code is in the key: an edit of the basis' module is another copy
    edited = tmp_path / "shifts.py"
    edited.write_bytes(Path(disk_render.shifts.__file__).read_bytes() + b"# edited\n")
    with monkeypatch.context() as m:
        m.setattr(disk_render, "shifts", SimpleNamespace(__file__=str(edited)))
        disk_render.render_rows(loaded, 1e-3)
    assert calls == [1e-3, 2e-3, 1e-3]
    assert derived_arrays(loaded, "other", lambda: {"x": np.zeros(1)}, ["key"])["x"].shape == (1,)
    # a damaged copy: a warning, computed again and replaced
    for copy in Path(loaded.meta["cache"]).glob("render-rows-*"):
        if (copy / "patches.npy").exists():
            data = bytearray((copy / "patches.npy").read_bytes())
            data[-1] ^= 1
            (copy / "patches.npy").write_bytes(bytes(data))
    with pytest.warns(CacheWarning, match="damaged"):
        fixed = disk_render.render_rows(loaded, 1e-3)
    np.testing.assert_array_equal(fixed[0], first[0])
    assert calls == [1e-3, 2e-3, 1e-3, 1e-3]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        disk_render.render_rows(loaded, 1e-3)
    assert len(calls) == 4
    # no lower rank within a tolerance: the stored rows, and nothing of them copied into the cache
    with monkeypatch.context() as m:
        m.setattr(disk_render, "reduced_basis", lambda basis, *_: (None, basis.amplitudes, 0.0))
        stored = disk_render.render_rows(loaded, 5e-3)
        assert stored[3] == 0
        np.testing.assert_array_equal(stored[2], loaded.basis.amplitudes)
        np.testing.assert_array_equal(stored[0], loaded.patches)
        assert len(calls) == 5 and disk_render.render_rows(loaded, 5e-3)[3] == 0 and len(calls) == 5
    assert min(np.load(p / "patches.npy").size for p in Path(loaded.meta["cache"]).glob("render-rows-*")
               if (p / "patches.npy").exists()) == 0
    # outside the cache (built here): reduced every time
    disk_render.render_rows(build_library(instrument=HMI, **TINY), 1e-3)
    assert len(calls) == 6
