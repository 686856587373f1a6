"""
Count levels: a simulation's counts next to a real GONG file's, and the effective area that matches.

The real files are the Big Bear magnetogram and intensity image of 2009-09-05
(old GONG header, shared/data/real/gong); tests that need them skip when they
are absent.  The simulations are small (1 minute, a few dozen pixels).
"""
import types

import astropy.units as u
import numpy as np
import pytest
import sunpy.map
from astropy.coordinates import SkyCoord
from astropy.io import fits
from sunpy.coordinates import frames

import gongsynth
from gongsynth.analysis.count_levels import DIODE_KEYWORDS, count_levels, real_count_levels
from gongsynth.analysis.disk import disk_coordinates
from gongsynth.analysis.noise import noise_estimate
from gongsynth.chain import build_chain
from gongsynth.config import Effects

from .realdata import load_real, real_file

MAGNETOGRAM = "gong/bbbqa090905t1854.fits.gz"
INTENSITY = "gong/bbiqa090905t1854.fits.gz"
SMALL = dict(sun="milne-eddington", detector_shape=32, duration=1 * u.min, photosphere_shape=(128, 128),
             photosphere_pixel_size=768 * u.km, resolutions=(1,), progress=False)
CENTRE, CONTINUUM = 0, 1  # rows of the table


@pytest.fixture(scope="module")
def intensity():
    return load_real(INTENSITY, "continuum")


@pytest.fixture(scope="module")
def magnetogram():
    return load_real(MAGNETOGRAM, "magnetogram")


@pytest.fixture(scope="module")
def stokes_and_config():
    base = gongsynth.simulate(seed=3, **SMALL)
    return build_chain(base.config).run(until="synthesis", progress=False)["stokes"], base.config


def _simulate(stokes_and_config, area, seed=3):
    stokes, config = stokes_and_config
    inst = config.instrument.replace(effective_area=area)
    return gongsynth.simulate(stokes, config=config.replace(instrument=inst, seed=seed), progress=False)


def _map(shape, scale, value=0.0):
    ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
                   observer="earth", obstime="2020-01-01")
    return sunpy.map.Map(np.full(shape, value, dtype=float), sunpy.map.make_fitswcs_header(
        shape, ref, scale=[scale, scale] * u.arcsec / u.pix))


# -- the real file -------------------------------------------------------------------------

def test_diode_sums_add_up_to_the_intensity_image(intensity):
    """Σ image = (ACCUM / 2**3) Σ DIODE: the DIODEs are per-frame pixel sums (module notes).

    The image is the mean of 9 one-minute images and the DIODEs belong to one
    of them, so the two agree only as far as the sky stayed the same: 1 %."""
    levels = real_count_levels(intensity)
    assert levels.accum == 600
    assert levels.diode_check == pytest.approx(1, abs=0.01)


def test_diode_per_pixel_follows_the_images_limb_darkening(intensity, magnetogram):
    # Read from the magnetogram's header, the DIODEs per on-disk pixel are a
    # disk mean; over the disk-centre level they give the image's own
    # disk-mean / centre ratio (limb darkening, ~0.83 at 677 nm).
    levels = real_count_levels(magnetogram, intensity=intensity)
    rho, _ = disk_coordinates(intensity)
    image_ratio = np.nanmean(intensity.data[rho < 1]) / np.nanmedian(intensity.data[rho < 0.1])
    diode_ratio = np.mean(levels.diode_per_pixel) / levels.centre
    assert float(diode_ratio) == pytest.approx(image_ratio, rel=0.01)
    # The header alone (limb-fit semi-axes for the disk area) gives the same per-pixel sums.
    header_levels = real_count_levels(fits.getheader(real_file(MAGNETOGRAM)))
    assert header_levels.diode_per_pixel.value == pytest.approx(levels.diode_per_pixel.value, rel=1e-3)
    assert header_levels.pixel_area.value == pytest.approx(levels.pixel_area.value, rel=1e-3)


def test_one_minute_planes_fit_in_sixteen_bits(intensity):
    """The 3-bit truncation exists so that a one-minute plane fits 16 bits (paper Sec. 3.2).

    Under the default reading the brightest disk-centre plane (with the mean
    dither of 182 adu per frame) fits; if the image were the mean of the
    planes rather than their sum over 3 phases, it would not."""
    level = real_count_levels(intensity, max_radius=0.02).centre.to_value(u.adu)
    assert (level + 182) * 600 / 8 < 2**16
    assert (3 * level + 182) * 600 / 8 > 2**16


def test_six_plane_reading_halves_the_levels(intensity):
    three = real_count_levels(intensity)
    six = real_count_levels(intensity, phase_planes=6)
    assert six.centre.value == pytest.approx(three.centre.value / 2)
    assert six.diode_per_pixel.value == pytest.approx(three.diode_per_pixel.value / 2)
    assert six.diode_check == three.diode_check
    with pytest.raises(ValueError, match="phase_planes"):
        real_count_levels(intensity, phase_planes=4)


@pytest.mark.validation
def test_real_noise_rules_out_the_six_plane_reading(intensity, magnetogram):
    """A simulation at the real level of each reading, against the real map's noise.

    The real 10-minute map averages 9 one-minute magnetograms; its noise can
    only exceed the instrument's photon and read noise, so the pixel-difference
    noise of its quietest box bounds the simulated noise from above (as long as
    GONG's one interpolation of each image lowers the noise by less than the
    factor 1.7 that separates the two readings: module notes)."""
    real_noise = noise_estimate(magnetogram).difference.to_value(u.G)
    # The photon and read noise alone: without the frame seeing, whose crosstalk at the tiled
    # sunspots' edges differs from seed to seed and would count as noise here.
    config = dict(SMALL, detector_shape=96, photosphere_shape=(256, 256), photosphere_pixel_size=384 * u.km,
                  effects=Effects(frame_seeing=False))
    base = gongsynth.simulate(seed=11, **config)
    stokes = build_chain(base.config).run(until="synthesis", progress=False)["stokes"]
    sigma = {}
    for planes in (3, 6):
        table = count_levels(intensity, base, phase_planes=planes)
        area = table["effective_area"][CENTRE]
        runs = [_simulate((stokes, base.config), area, seed) for seed in (21, 22)]
        difference = (runs[0].magnetogram.data - runs[1].magnetogram.data)[8:-8, 8:-8]
        sigma[planes] = np.std(difference) / np.sqrt(2) / 3  # one minute -> mean of 9
    assert sigma[3] < real_noise < sigma[6]


# -- the logic, on simulations ---------------------------------------------------------------

def test_doubling_the_effective_area_doubles_the_simulated_level(intensity, stokes_and_config):
    single = count_levels(intensity, _simulate(stokes_and_config, 0.6 * u.cm**2))
    double = count_levels(intensity, _simulate(stokes_and_config, 1.2 * u.cm**2))
    for row in (CENTRE, CONTINUUM):
        assert double["real"][row] == single["real"][row]
    # Expected counts are noise free: exactly twice.
    assert (double["simulated"][CENTRE] / single["simulated"][CENTRE]).to_value(u.one) == pytest.approx(
        2, rel=1e-6)
    assert double["effective_area"][CENTRE].value == pytest.approx(single["effective_area"][CENTRE].value,
                                                                     rel=1e-6)
    # The pseudo-continuum carries photon and read noise (same seed, different draws):
    # ~1e-4 per pixel for 3600 frames of ~1e5 electrons, far less for a median.
    assert (double["simulated"][CONTINUUM] / single["simulated"][CONTINUUM]).to_value(u.one) == pytest.approx(
        2, rel=1e-3)


def test_the_matching_area_reproduces_the_real_level(intensity, stokes_and_config):
    first = count_levels(intensity, _simulate(stokes_and_config, 0.6 * u.cm**2))
    area = first["effective_area"][CENTRE]
    assert 0 < area.to_value(u.cm**2) < 0.6  # real GONG counts are below gongsynth's at 0.6 cm²
    matched = count_levels(intensity, _simulate(stokes_and_config, area))
    ratio = matched.meta["pixel_area_ratio"]
    # Per unit solid angle the simulation now reaches the real level ...
    assert (matched["simulated"][CENTRE] * ratio).value == pytest.approx(matched["real"][CENTRE].value,
                                                                          rel=1e-6)
    assert (matched["simulated"][CONTINUUM] * ratio).value == pytest.approx(
        matched["real"][CONTINUUM].value, rel=2e-3)
    # ... and the area it asks for is the one it has.
    assert matched["effective_area"][CENTRE].value == pytest.approx(area.value, rel=1e-6)
    # The pseudo-continuum's GONG-image equivalent is the real image's level.
    assert matched.meta["simulated_centre_image"].value * ratio == pytest.approx(
        matched.meta["real_centre_image"].value, rel=2e-3)


def _full_disk(levels, gain=33.0):
    """A synthetic full-disk 'simulation': per-frame adu ``levels`` (3 channels) on the disk, none off it."""
    smap = _map((64, 64), 40.0)
    rho, _ = disk_coordinates(smap)
    disk = (rho < 1).astype(float)
    per_frame = np.concatenate([levels, levels])[:, None, None] * disk  # adu per frame, 6 planes
    frames = np.full(6, 600)
    raw = types.SimpleNamespace(data=per_frame * 600 / 8, frames_per_plane=frames, header=fits.Header())
    continuum = sunpy.map.Map(raw.data.sum(axis=0), smap.meta)
    expected = per_frame * gain * u.electron
    return types.SimpleNamespace(raw=raw, continuum=continuum, expected_counts=expected), int(disk.sum())


@pytest.mark.parametrize("sky", [0.0, np.nan])  # gongsynth's full-disk maps blank the sky with NaN
def test_full_disk_simulation_gets_diode_equivalents(sky):
    levels = np.array([500.0, 600.0, 700.0])
    simulated, n_disk = _full_disk(levels)
    rho, _ = disk_coordinates(simulated.continuum)
    simulated.continuum.data[rho > 1] = sky
    real = _map((64, 64), 40.0, value=600.0 * 3 * 600 / 8)
    diodes = [250.0 * n_disk, 300.0 * n_disk, 350.0 * n_disk]
    real.meta.update({"imtype": "INTENSITY", "accum": 600,
                      **{key.lower(): value for key, value in zip(DIODE_KEYWORDS, diodes)}})
    table = count_levels(real, simulated)
    rows = {str(q): i for i, q in enumerate(table["quantity"])}
    for k, key in enumerate(DIODE_KEYWORDS):
        row = rows[f"{key} / on-disk pixels"]
        assert table["simulated"][row].value == pytest.approx(levels[k])
        assert table["real"][row].value == pytest.approx(diodes[k] / n_disk)
        assert table["ratio"][row].value == pytest.approx(0.5)
        assert table["effective_area"][row].value == pytest.approx(0.3)
    # Disk centre: the real image is 600 adu per frame, the simulation the channel mean 600.
    assert table["ratio"][CENTRE].value == pytest.approx(1)
    assert table["ratio"][CONTINUUM].value == pytest.approx(1)
    assert table.meta["diode_check"] == pytest.approx(np.sum(real.data) / (75 * sum(diodes)))


def test_tiled_simulation_has_no_diode_equivalent(intensity, stokes_and_config):
    table = count_levels(intensity, _simulate(stokes_and_config, 0.6 * u.cm**2))
    assert np.isnan(table["simulated"][2:]).all() and np.isfinite(table["real"][2:]).all()
    assert table.meta["simulated_mu"] > 0.99


def test_bad_inputs():
    simulated, _ = _full_disk(np.array([1.0, 1.0, 1.0]))
    real = _map((8, 8), 2.5, 1.0)
    with pytest.raises(ValueError, match="ACCUM"):
        count_levels(real, simulated)
    real.meta.update({"imtype": "INTENSITY", "accum": 600})
    with pytest.raises(TypeError, match="simulated"):
        count_levels(real, types.SimpleNamespace(continuum=simulated.continuum))
    with pytest.raises(TypeError, match="real"):
        count_levels(np.zeros((8, 8)), simulated)
    with pytest.raises(ValueError, match="max_radius"):
        count_levels(real, simulated, max_radius=2)
    # A field far from disk centre has no disk-centre level.
    ref = SkyCoord(600 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
                   observer="earth", obstime="2020-01-01")
    away = sunpy.map.Map(np.ones((8, 8)), sunpy.map.make_fitswcs_header(
        (8, 8), ref, scale=[2.5, 2.5] * u.arcsec / u.pix))
    with pytest.raises(ValueError, match="disk centre"):
        count_levels(real, types.SimpleNamespace(raw=simulated.raw, continuum=away))


def test_sunspots_do_not_pull_the_centre_level_down():
    levels = np.array([600.0, 600.0, 600.0])
    simulated, _ = _full_disk(levels)
    real = _map((64, 64), 40.0, value=600.0 * 3 * 600 / 8)
    real.meta.update({"imtype": "INTENSITY", "accum": 600})
    rho, _ = disk_coordinates(real)
    # Most of the disk-centre region (so that a plain median would fall in it)
    # in a spot at 30 % of the quiet level, in both maps.
    spot = (rho < 0.3) & (np.arange(64)[None, :] < 34)
    assert 0.55 < spot.sum() / (rho < 0.3).sum() < 0.8
    real.data[spot] *= 0.3
    simulated.continuum.data[spot] *= 0.3
    table = count_levels(real, simulated, max_radius=0.3)
    assert table["real"][CENTRE].value == pytest.approx(600)
    assert table["simulated"][CONTINUUM].value == pytest.approx(600)


def test_a_tiled_field_over_the_whole_disk_is_not_a_full_disk():
    simulated, _ = _full_disk(np.array([600.0, 600.0, 600.0]))
    real = _map((64, 64), 40.0, value=600.0 * 3 * 600 / 8)
    real.meta.update({"imtype": "INTENSITY", "accum": 600, "diode1": 1.0, "diode2": 1.0, "diode3": 1.0})
    assert np.isfinite(count_levels(real, simulated)["simulated"][2:]).all()
    simulated.continuum.meta["simmode"] = "tiled"
    assert np.isnan(count_levels(real, simulated)["simulated"][2:]).all()
    # Without a mode, a bright 'sky' (a scene tiled beyond the limb) says the same.
    del simulated.continuum.meta["simmode"]
    simulated.continuum.data[:] = simulated.continuum.data.max()
    assert np.isnan(count_levels(real, simulated)["simulated"][2:]).all()
