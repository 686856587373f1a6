"""The scene-dependent calibration: distance from strong fields, the scene table, calibrate(scene=...)."""
import astropy.units as u
import numpy as np
import pytest
import sunpy.map
from astropy.coordinates import SkyCoord
from sunpy.coordinates import frames

from gongsynth.analysis.apply_calibration import calibrate, scene_factor_map, viewing_angle
from gongsynth.analysis.calibration_table import read_calibration_table
from gongsynth.analysis.scene_calibration import (
    local_flux_density,
    read_scene_table,
    scene_ratio,
    scene_table,
    strong_field_distance,
    strong_field_mask,
)
from gongsynth.cli import main

#: Ratio 1.3 up to 10 Mm from strong fields, falling linearly to 0.9 at 50 Mm and beyond, at 0° and 60°.
_NODES = ((5, 1.3), (10, 1.3), (50, 0.9))


def _table(threshold="400.0 G"):
    rows = [dict(latitude=lat, distance_min=d - 1, distance_max=d + 1, distance=d, ratio=r, uncertainty=0.01)
            for lat in (0, 60) for d, r in _NODES]
    return scene_table(rows, metadata={"threshold": threshold})


def _disk_map(values, scale):
    ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective, observer="earth",
                   obstime="2020-01-01")
    header = sunpy.map.make_fitswcs_header(values.shape, ref, scale=[scale, scale] * u.arcsec / u.pix,
                                           unit=u.G, telescope="NSO-GONG")
    return sunpy.map.Map(values, header)


def _patch_map():
    """61² pixels of 2.5″ at disk centre, quiet 10 G, a 3 × 3 strong patch of 1000 G in the middle."""
    values = np.full((61, 61), 10.0)
    values[29:32, 29:32] = 1000.0
    return _disk_map(values, 2.5)


def _sky_distance_mm(smap, rows, columns, patch_rows, patch_columns):
    """Distance to the nearest patch pixel on the sky at disk centre, in Mm (flat-Sun approximation)."""
    dy = rows[..., None] - patch_rows.ravel()
    dx = columns[..., None] - patch_columns.ravel()
    pixels = np.sqrt(dx ** 2 + dy ** 2).min(axis=-1)
    # At disk centre the surface lies R closer than the Sun's centre.
    mm_per_arcsec = (smap.dsun - smap.rsun_meters).to_value(u.Mm) * np.deg2rad(1 / 3600)
    return pixels * 2.5 * mm_per_arcsec


def test_distance_from_a_known_strong_patch_and_the_factor_map():
    smap = _patch_map()
    theta = viewing_angle(smap).to_value(u.deg)
    strong = strong_field_mask(smap.data, theta)
    assert strong.sum() == 9 and strong[30, 30]
    distance = strong_field_distance(smap, strong).to_value(u.Mm)
    rows, columns = np.mgrid[:61, :61]
    expected = _sky_distance_mm(smap, rows, columns, *np.mgrid[29:32, 29:32])
    assert np.all(distance[strong] == 0)
    # The surface curves away from the sky plane: an arc β is longer than its projection by β²/6, 0.2 %
    # at 73 Mm (the corners).
    assert np.allclose(distance, expected, rtol=2.5e-3, atol=1e-6)
    ratio = scene_factor_map(smap, table=_table()).data
    d, r = np.array(_NODES).T
    assert np.allclose(ratio, np.interp(expected, d, r), rtol=2.5e-3)
    # Near the patch 1.3, beyond 50 Mm 0.9 (the corner is 53 Mm away), decreasing in between.
    assert ratio[30, 33] == pytest.approx(1.3) and ratio[0, 0] == pytest.approx(0.9)
    assert np.all(np.diff(ratio[30, 32:]) <= 1e-12)


def test_calibrate_with_the_scene_multiplies_only_quiet_pixels():
    smap = _patch_map()
    plain = calibrate(smap)
    assert "calscene" not in plain.meta
    scene = calibrate(smap, scene="distance", scene_table=_table())
    ratio = scene_factor_map(smap, table=_table()).data
    strong = smap.data >= 400
    assert np.array_equal(scene.data[strong], plain.data[strong])
    assert np.allclose(scene.data[~strong], plain.data[~strong] * ratio[~strong], rtol=1e-12)
    assert scene.meta["calscene"] == "in-memory table" and "distance from" in scene.meta["history"]
    # The threshold comes from the table: at 2000 G nothing is strong, every distance is infinite.
    none = calibrate(smap, scene="distance", scene_table=_table("2000 G"))
    quiet = ~strong
    assert np.allclose(none.data[quiet], plain.data[quiet] * 0.9, rtol=1e-12)


def test_synoptic_distance_is_the_great_circle_on_the_sun():
    header = sunpy.map.make_fitswcs_header(
        (90, 180), SkyCoord(180 * u.deg, 0 * u.deg, frame=frames.HeliographicCarrington, observer="earth",
                            obstime="2020-03-06"),
        scale=[2, 2] * u.deg / u.pix, projection_code="CAR", unit=u.G)
    smap = sunpy.map.Map(np.zeros((90, 180)), header)
    ny, nx = smap.data.shape
    lon, lat = (c.to_value(u.rad) for c in (lambda w: (w.lon, w.lat))(
        smap.pixel_to_world(*np.meshgrid(np.arange(nx), np.arange(ny)) * u.pix)))
    strong = np.zeros((ny, nx), bool)
    strong[50, 0] = True  # next to the 0/360° seam
    distance = strong_field_distance(smap, strong).to_value(u.Mm)
    # The spherical law of cosines, independently of the k-d tree's chords.
    cosine = (np.sin(lat) * np.sin(lat[50, 0])
              + np.cos(lat) * np.cos(lat[50, 0]) * np.cos(lon - lon[50, 0]))
    expected = smap.rsun_meters.to_value(u.Mm) * np.arccos(np.clip(cosine, -1, 1))
    assert np.allclose(distance, expected, rtol=1e-6, atol=1e-6)
    assert distance[50, nx - 1] == pytest.approx(expected[50, 1], rel=1e-6)  # across the seam
    assert np.isinf(strong_field_distance(smap, np.zeros_like(strong)).value).all()


def test_a_tiled_maps_distance_is_measured_in_its_box():
    """A simulated tiled map: its box seen at the run's μ, not the disk its WCS would put it on."""
    from gongsynth.geometry import Pointing

    values = np.full((41, 41), 10.0)
    values[20, 20] = 1000.0
    smap = _disk_map(values, 500.0)   # 20000″ wide: most pixels' WCS coordinates miss the Sun
    smap.meta.update({"simmode": "tiled", "simlat": 60.0, "date-beg": "2020-01-01T00:00:00"})
    pointing = Pointing(60 * u.deg, "2020-01-01T00:00:00")
    strong = values > 400
    distance = strong_field_distance(smap, strong).to_value(u.Mm)
    step = 500 * pointing.km_per_arcsec.to_value(u.Mm / u.arcsec)   # Mm per pixel east-west
    rows, columns = np.mgrid[:41, :41]
    expected = step * np.hypot(columns - 20, (rows - 20) / pointing.mu)
    assert np.allclose(distance, expected, rtol=1e-12)
    assert distance[21, 20] / distance[20, 21] == pytest.approx(1 / pointing.mu)   # foreshortened north-south


def test_scene_ratio_interpolates_and_clamps():
    table = _table()
    d = [0, 30, 1e9] * u.Mm
    assert scene_ratio(table, [0, 0, 0], d).tolist() == pytest.approx([1.3, 1.1, 0.9])
    ratio = scene_ratio(table, [80, 30, 30], [30, 30, np.inf] * u.Mm)
    assert ratio.tolist() == pytest.approx([1.1, 1.1, 0.9])
    assert np.isnan(scene_ratio(table, [np.nan, 0], [1, np.nan] * u.Mm)).all()


def test_local_flux_density():
    values = np.zeros((9, 9))
    values[4, 4] = -90.0
    density = local_flux_density(values, 3).to_value(u.G)
    assert density[4, 4] == pytest.approx(10.0) and density[3, 5] == pytest.approx(10.0)
    assert density[0, 0] == 0.0


def test_the_shipped_scene_table():
    table = read_scene_table()
    for key in ("grid", "seeds", "instrument", "threshold", "method", "gongsynth_version"):
        assert key in table.meta, key
    assert len(table.meta["seeds"]) >= 2 and table.meta["instrument"] == "gong"
    assert np.all(table["uncertainty"] > 0) and np.all(np.isfinite(table["ratio"]))
    # At disk centre the dependence is resolved: 10-20 Mm from strong fields against beyond 35 Mm.
    centre = table[table["latitude"] == 0 * u.deg]
    near, far = centre[centre["distance_min"] == 10 * u.Mm][0], centre[np.isinf(centre["distance_max"])][0]
    assert near["ratio"] - far["ratio"] > 3 * np.hypot(near["uncertainty"], far["uncertainty"])


def test_bad_input_is_refused_early(tmp_path):
    smap = _patch_map()
    with pytest.raises(ValueError, match="scene must be one of"):
        calibrate(smap, scene="spot")
    with pytest.raises(ValueError, match="conversion table"):
        calibrate(smap, scene="distance", to="hmi")
    with pytest.raises(ValueError, match="scene_table is used only"):
        calibrate(smap, scene_table=_table())
    bare = _table()
    del bare.meta["threshold"]
    with pytest.raises(ValueError, match="threshold"):
        calibrate(smap, scene="distance", scene_table=bare)
    path = tmp_path / "not_scene.ecsv"
    read_calibration_table().write(path, format="ascii.ecsv")
    with pytest.raises(ValueError, match="not a gongsynth scene table"):
        read_scene_table(path)
    with pytest.raises(ValueError, match="threshold must be one positive"):
        strong_field_mask(smap.data, np.zeros((61, 61)), threshold=-1 * u.G)
    with pytest.raises(ValueError, match="theta must have"):
        strong_field_mask(smap.data, np.zeros(3))
    with pytest.raises(ValueError, match="strong must be a boolean"):
        strong_field_distance(smap, np.zeros((61, 61)))
    with pytest.raises(ValueError, match="side must be"):
        local_flux_density(smap.data, 4)
    with pytest.raises(ValueError, match="distance must be a length"):
        scene_ratio(_table(), [0], [1] * u.G)


def test_the_cli_switch(tmp_path, capsys):
    source = tmp_path / "in.fits"
    _patch_map().save(source)
    out = tmp_path / "out.fits"
    assert main(["calibrate", str(source), "--out", str(out), "--scene", "distance"]) == 0
    assert sunpy.map.Map(out).meta["calscene"].endswith("scene_factors.ecsv")
    assert main(["calibrate", str(source), "--out", str(tmp_path / "b.fits"), "--scene", "distance",
                 "--to", "hmi"]) == 2
    assert "conversion table" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exit_:
        main(["calibrate", str(source), "--out", str(tmp_path / "c.fits"), "--scene", "spot"])
    assert exit_.value.code == 2
