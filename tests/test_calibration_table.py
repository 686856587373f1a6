"""Calibration tables: building, saving, reading and applying them."""
import astropy.units as u
import numpy as np
import pytest
import sunpy.map
from astropy.coordinates import SkyCoord
from sunpy.coordinates import frames

from gongsynth import GONGInstrument
from gongsynth.analysis.apply_calibration import calibrate, viewing_angle, weak_flux_factor_map
from gongsynth.analysis.calibration_table import (
    INSTRUMENT_TABLES,
    calibration_table,
    read_calibration_table,
    table_curve,
    write_calibration_table,
)
from gongsynth.analysis.weak_flux import WeakFluxFactor, flux_conserving_fit


def _known_table(factors):
    """A table whose quiet-Sun curves are exactly truth = factor × measured."""
    t = np.random.default_rng(0).normal(0, 100, 20_000)
    fits = [WeakFluxFactor(f, 0.0, flux_conserving_fit(t / f, t, 9), "quiet", t.size, lat * u.deg)
            for lat, f in factors.items()]
    return calibration_table(fits, mu=[np.cos(np.deg2rad(lat)) for lat in factors], metadata={"x": 1})


def _disk_map(values, scale=20):
    ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
                   observer="earth", obstime="2020-01-01")
    header = sunpy.map.make_fitswcs_header(values.shape, ref, scale=[scale, scale] * u.arcsec / u.pix,
                                           unit=u.G)
    return sunpy.map.Map(values, header)


def test_round_trip_through_ecsv(tmp_path):
    table = _known_table({0: 2.0, 60: 1.0})
    path = tmp_path / "table.ecsv"
    write_calibration_table(table, path)
    with pytest.raises(FileExistsError):
        write_calibration_table(table, path)
    back = read_calibration_table(path)
    assert back["latitude"].unit == u.deg and back["nodes"].unit == u.G
    assert back.meta["x"] == 1 and back.meta["source"] == str(path)
    curve = table_curve(back, 60 * u.deg)
    assert np.allclose(curve(np.array([-50.0, 10.0])).to_value(u.G), [-50.0, 10.0], atol=1e-6)
    with pytest.raises(KeyError, match="sunspot"):
        table_curve(back, 60 * u.deg, "sunspot")


def test_calibrate_interpolates_in_viewing_angle():
    table = _known_table({0: 2.0, 60: 1.0})
    values = np.full((101, 101), 10.0)
    smap = _disk_map(values)
    theta = viewing_angle(smap).to_value(u.deg)
    out = calibrate(smap, table=table)
    on = np.isfinite(theta)
    # Linear in θ between 0° (×2) and 60° (×1), the 60° curve beyond.
    expected = 10.0 * np.where(theta[on] < 60, 2.0 - theta[on] / 60, 1.0)
    assert np.allclose(out.data[on], expected, rtol=1e-6)
    assert np.all(np.isnan(out.data[~on]))
    assert out.meta["caltable"] == "in-memory table"
    factors = weak_flux_factor_map(smap, table=table)
    assert np.allclose(factors.data[on], expected / 10.0, rtol=1e-9)


def test_a_simulated_tiled_map_has_its_runs_angle_at_every_pixel():
    """A tiled run is one box seen at one angle: its WCS places only the frame's centre on the disk."""
    from gongsynth.geometry import Pointing

    table = _known_table({0: 2.0, 60: 1.0})
    smap = _disk_map(np.full((101, 101), 10.0))   # 2000″ wide: the WCS corners are off the disk
    smap.meta.update({"simmode": "tiled", "simlat": 45.0, "date-beg": "2020-01-01T00:00:00"})
    theta = np.rad2deg(np.arccos(Pointing(45 * u.deg, "2020-01-01T00:00:00").mu))
    assert abs(theta - 45) > 1   # B0 = -3°: the angle is the run's, not its latitude
    assert np.allclose(viewing_angle(smap).to_value(u.deg), theta, rtol=0, atol=1e-9)
    assert np.allclose(calibrate(smap, table=table).data, 10.0 * (2.0 - theta / 60), rtol=1e-6)
    smap.meta["simmode"] = "full-disk"   # a full-disk simulation is a disk image like any other
    assert np.isnan(viewing_angle(smap)[0, 0])


def test_strong_pixels_use_the_sunspot_curve():
    quiet = _known_table({0: 2.0})
    t = np.random.default_rng(1).normal(0, 1000, 20_000)
    spot = WeakFluxFactor(1.5, 0.0, flux_conserving_fit(t / 1.5, t, 9), "sunspot", t.size, 0 * u.deg)
    table = calibration_table([*[WeakFluxFactor(f, 0, table_curve(quiet, 0 * u.deg), "quiet", 1, 0 * u.deg)
                                 for f in (2.0,)], spot], mu=[1, 1])
    smap = _disk_map(np.array([[100.0, 1000.0]]), scale=1)
    out = calibrate(smap, table=table)
    assert out.data[0, 0] == pytest.approx(200.0, rel=1e-6)   # quiet: |B| < 400 G
    assert out.data[0, 1] == pytest.approx(1500.0, rel=1e-6)  # strong: the sunspot curve


def test_synoptic_maps_use_latitude_and_b0():
    header = sunpy.map.make_fitswcs_header(
        (90, 360), SkyCoord(0 * u.deg, 0 * u.deg, frame=frames.HeliographicCarrington,
                            observer="earth", obstime="2020-03-06"),
        scale=[1, 2] * u.deg / u.pix, projection_code="CAR", unit=u.G)
    smap = sunpy.map.Map(np.ones((90, 360)), header)
    theta = viewing_angle(smap)
    from sunpy.coordinates import sun
    b0 = sun.B0("2020-03-06").to_value(u.deg)
    latitude = smap.pixel_to_world(0 * u.pix, 45 * u.pix).lat.to_value(u.deg)
    assert theta[45, 0].to_value(u.deg) == pytest.approx(abs(latitude - b0), abs=1e-6)


def test_a_small_sweep_builds_a_table():
    from gongsynth.calibration_sweep import build_calibration_table

    # Tiny runs (the toy Sun on a coarse box, 48² pixels): the table's make-up, not its values.
    table = build_calibration_table([0, 60] * u.deg, seeds=[1, 2], regions=["quiet"], n_boot=10,
                                    sun="milne-eddington", detector_shape=48, duration=1 * u.min,
                                    photosphere_shape=(64, 64), photosphere_pixel_size=1536 * u.km,
                                    resolutions=(1,), progress=False)
    assert list(table["latitude"].to_value(u.deg)) == [0.0, 60.0]
    assert table["mu"][1] == pytest.approx(0.5, abs=0.1)
    assert np.all(table["factor"] > 0) and np.all(table["uncertainty"] > 0)
    assert table.meta["seeds"] == [1, 2] and "[simulation]" in table.meta["config"]
    assert table.meta["grid"] == {"columns": [64, 64], "column_size": "1536.0 km"}
    assert table.meta["instrument_name"] == "gong" and "git_commit" in table.meta
    # Each seed fitted alone too; the statistical uncertainty is at least the pooled bootstrap.
    assert table["seed_factors"].shape == (2, 2) and np.all(table["uncertainty"] >= table["bootstrap"])
    with pytest.raises(ValueError, match="regions"):
        build_calibration_table([0] * u.deg, regions=["plage"], progress=False)
    with pytest.raises(ValueError, match="preset"):
        build_calibration_table([0] * u.deg, preset="authors", progress=False)


def test_the_paper_preset_is_the_authors_seeing_kernel():
    from gongsynth.calibration_sweep import PRESETS
    from gongsynth.stages.psf import psf_profile

    # exp(-r²/2σ²) with σ = 1.8″ falls to half at the FWHM: 4.24″ across.
    fwhm = PRESETS["paper"]["seeing_fwhm"]
    assert fwhm.to_value(u.arcsec) == pytest.approx(4.239, abs=1e-3)
    assert np.exp(-0.5 * ((fwhm / 2).to_value(u.arcsec) / 1.8) ** 2) == pytest.approx(0.5, rel=1e-12)
    # The seeing kernel of that instrument is wider than the default's.
    paper = GONGInstrument().replace(**PRESETS["paper"])
    r = [0, 3] * u.arcsec
    ratio_paper = psf_profile(r, paper)[1] / psf_profile(r, paper)[0]
    ratio_default = psf_profile(r, GONGInstrument())[1] / psf_profile(r, GONGInstrument())[0]
    assert ratio_paper > ratio_default



def test_the_shipped_table_loads_with_units_and_provenance():
    table = read_calibration_table()
    assert table["latitude"].unit == u.deg and table["nodes"].unit == u.G
    assert sorted(table["latitude"].to_value(u.deg)) == sorted([0, 25, 45, 60, 70, 75] * 2)
    assert {str(r) for r in table["region"]} == {"quiet", "sunspot"}
    for key in ("gongsynth_version", "input_sun", "seeds", "estimator", "instrument", "config", "created"):
        assert key in table.meta, key
    assert np.all(np.isfinite(table["factor"])) and np.all(table["uncertainty"] > 0)
    # Each row's curve evaluates and is odd.
    for row in table:
        curve = table_curve(table, row["latitude"], str(row["region"]))
        pair = curve(np.array([-30.0, 30.0])).to_value(u.G)
        assert pair[0] == pytest.approx(-pair[1], rel=1e-9, abs=1e-9)


def test_weak_flux_of_a_calibrated_map_grows_by_the_tables_factor():
    # Fields far weaker than the central bins' width: each curve is linear
    # there with slope = the weak-flux factor, so the unsigned flux grows by
    # the |B|-weighted mean of the factor map over the disk.
    table = read_calibration_table()
    smap = _disk_map(np.random.default_rng(5).uniform(-2, 2, (121, 121)), scale=18)
    out = calibrate(smap, table=table)
    factor = weak_flux_factor_map(smap, table=table).data
    on = np.isfinite(out.data)
    expected = np.sum(np.abs(smap.data[on]) * factor[on]) / np.sum(np.abs(smap.data[on]))
    assert np.abs(out.data[on]).sum() / np.abs(smap.data[on]).sum() == pytest.approx(expected, rel=1e-9)
    assert out.meta["caltable"].endswith("calibration_default.ecsv")


def test_same_seeds_same_table():
    from gongsynth.calibration_sweep import build_calibration_table

    def build():
        return build_calibration_table([30] * u.deg, seeds=[3], regions=["quiet"], n_boot=5,
                                       sun="milne-eddington", detector_shape=96, duration=1 * u.min,
                                       photosphere_shape=(128, 128),
                                       photosphere_pixel_size=768 * u.km, progress=False)

    first, second = build(), build()
    for column in ("factor", "uncertainty", "n_pixels", "nodes", "values"):
        assert np.array_equal(np.asarray(first[column]), np.asarray(second[column]), equal_nan=True), column


def test_calibrate_applies_the_maps_own_instruments_table():
    measured = np.full((3, 3), 10.0)
    centre = {}
    for telescope, name in (("NSO-GONG", "gong"), ("SDO/HMI", "hmi"), ("", "gong")):
        smap = _disk_map(measured.copy())
        smap.meta["telescop"] = telescope
        calibrated = calibrate(smap)
        assert calibrated.meta["caltable"] == f"gongsynth/data/{INSTRUMENT_TABLES[name]}"
        centre[telescope or "none"] = calibrated.data[1, 1]
    # Each table's own curve: GONG's factor at 0° is above 1, HMI's below.
    assert centre["NSO-GONG"] == centre["none"] > 10 > centre["SDO/HMI"]
    on_mdi = calibrate(_disk_map(measured.copy()), instrument="mdi")
    assert on_mdi.meta["caltable"] == "gongsynth/data/calibration_mdi.ecsv"
    with pytest.raises(ValueError, match="table or instrument"):
        calibrate(_disk_map(measured.copy()), instrument="hmi", table=read_calibration_table())
    with pytest.raises(ValueError, match="instrument must be one of"):
        calibrate(_disk_map(measured.copy()), instrument="spectroheliograph")
