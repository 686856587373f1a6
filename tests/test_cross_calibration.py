"""Cross-calibration of two magnetograms, the conversion table and calibrate(to=...): known answers."""
import astropy.units as u
import numpy as np
import pytest
import sunpy.map
from astropy.coordinates import SkyCoord
from sunpy.coordinates import frames
from sunpy.map.header_helper import make_heliographic_header

import gongsynth
from gongsynth.analysis.apply_calibration import calibrate, map_instrument
from gongsynth.analysis.cross_calibration import bisector_slope, common_grid, cross_calibrate
from gongsynth.analysis.cross_calibration_table import (
    conversion_factors,
    read_cross_calibration_table,
    tabulate_cross_calibration,
)

ALL = dict(angle_bins=[0, 90] * u.deg, strength_bins=[0, np.inf] * u.G)


def _disk_map(values, scale, telescope=None, observer="earth"):
    ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective, observer=observer,
                   obstime="2020-01-01")
    header = sunpy.map.make_fitswcs_header(values.shape, ref, scale=[scale, scale] * u.arcsec / u.pix,
                                           unit=u.G, **({"telescope": telescope} if telescope else {}))
    return sunpy.map.Map(values, header)


def _synoptic_map(values, telescope=None):
    ny, nx = values.shape
    header = make_heliographic_header("2020-01-01", "earth", (ny, nx), frame="carrington",
                                      projection_code="CEA")
    header["bunit"] = "G"
    if telescope:
        header["telescop"] = telescope
    return sunpy.map.Map(values, header)


def _field(shape, seed=0, sigma=50.0, smooth=3):
    """A smooth random field (G): neighbouring pixels correlated, like a magnetogram."""
    rng = np.random.default_rng(seed)
    white = rng.normal(0, 1, shape)
    kernel = np.ones(smooth) / smooth
    smoothed = np.apply_along_axis(np.convolve, 0, white, kernel, "same")
    smoothed = np.apply_along_axis(np.convolve, 1, smoothed, kernel, "same")
    return sigma * smoothed / smoothed.std()


def test_a_map_against_itself_times_1_3_gives_1_3():
    field = _field((120, 120))
    for a, b in ((_disk_map(field, 2.5), _disk_map(1.3 * field, 2.5)),
                 (_synoptic_map(field[:60]), _synoptic_map(1.3 * field[:60]))):
        table = cross_calibrate(a, b)
        every = table[(table["angle_max"] == 90 * u.deg) & np.isinf(table["strength_max"])
                      & (table["angle_min"] == 0 * u.deg) & (table["strength_min"] == 0 * u.G)]
        assert len(every) == 1
        for column in ("flux_ratio", "signed_ratio", "slope"):
            assert every[column][0] == pytest.approx(1.3, rel=1e-12), column
        assert every["correlation"][0] == pytest.approx(1.0, abs=1e-12)
        assert every["slope_uncertainty"][0] == pytest.approx(0.0, abs=1e-9)
        # Every group with enough cells says 1.3 too.
        filled = table[table["n_pixels"] >= 20]
        assert len(filled) > 1 and np.allclose(filled["flux_ratio"], 1.3, rtol=1e-12)


def test_two_resolutions_of_one_flux_preserving_map_give_1_for_the_signed_flux():
    # Disk: 0.5" pixels and their 5 x 5 means on 2.5" pixels sharing the reference point.
    fine = _field((200, 200), seed=1, smooth=9) + 3.0  # a net flux, so that the signed ratio is defined
    coarse = fine.reshape(40, 5, 40, 5).mean(axis=(1, 3))
    table = cross_calibrate(_disk_map(fine, 0.5), _disk_map(coarse, 2.5), **ALL)
    assert table["n_pixels"][0] == 40 * 40
    assert table["signed_ratio"][0] == pytest.approx(1.0, abs=1e-12)
    assert table["slope"][0] == pytest.approx(1.0, abs=1e-10)
    # Synoptic: a chart and its 2 x 2 means (like HMI's 0.5° and GONG's 1° grids), in either order.
    fine = _field((180, 360), seed=2) + 1.0
    coarse = fine.reshape(90, 2, 180, 2).mean(axis=(1, 3))
    for a, b in ((_synoptic_map(coarse), _synoptic_map(fine)), (_synoptic_map(fine), _synoptic_map(coarse))):
        table = cross_calibrate(a, b, **ALL)
        assert table["n_pixels"][0] == 90 * 180
        assert table["signed_ratio"][0] == pytest.approx(1.0, abs=1e-9)  # round-off of sums that cancel
        assert table["slope"][0] == pytest.approx(1.0, abs=1e-10)


def test_a_different_observer_is_reprojected_not_indexed():
    field = _field((100, 100), seed=3, smooth=15)
    earth = _disk_map(field, 2.5)
    elsewhere = _disk_map(field, 2.5, observer=SkyCoord(0 * u.deg, 0 * u.deg, 0.99 * u.AU,
                                                        frame=frames.HeliographicStonyhurst,
                                                        obstime="2020-01-01"))
    a, b, how = common_grid(earth, elsewhere, resolution=10 * u.arcsec)
    assert "reproject" in how and a.data.shape == b.data.shape
    _, _, how = common_grid(earth, _disk_map(field, 2.5), resolution=10 * u.arcsec)
    assert "by index" in how


def test_noise_alone_does_not_bias_the_bisector_slope():
    """Same signal, independent noise of equal variance in both maps: E[slope] = 1 (OLS would give 0.8)."""
    rng = np.random.default_rng(42)
    n, trials, signal, noise = 400, 300, 20.0, 10.0
    slopes, sigmas, ols = [], [], []
    for _ in range(trials):
        s = rng.normal(0, signal, n)
        x, y = s + rng.normal(0, noise, n), s + rng.normal(0, noise, n)
        slope, sigma, _ = bisector_slope(x, y)
        slopes.append(slope)
        sigmas.append(sigma)
        ols.append(np.polyfit(x, y, 1)[0])
    spread = np.std(slopes, ddof=1)
    # Unbiased within 4 standard errors of the mean of the trials ...
    assert abs(np.mean(slopes) - 1) < 4 * spread / np.sqrt(trials)
    # ... while the ordinary fit is diluted to signal² / (signal² + noise²) = 0.8, far outside that band.
    assert abs(np.mean(ols) - 0.8) < 4 * np.std(ols) / np.sqrt(trials)
    assert abs(np.mean(ols) - 1) > 20 * spread / np.sqrt(trials)
    # Isobe et al.'s asymptotic uncertainty describes the scatter (to the ~4 % precision of 300 trials).
    assert np.mean(sigmas) == pytest.approx(spread, rel=0.15)


def test_noise_does_not_bias_the_slope_between_two_maps():
    rng = np.random.default_rng(7)
    signal = rng.normal(0, 30, (100, 100))
    a = _disk_map(signal + rng.normal(0, 12, signal.shape), 2.5)
    b = _disk_map(1.3 * (signal + rng.normal(0, 12, signal.shape)), 2.5)  # noise on b's scale too
    row = cross_calibrate(a, b, **ALL)[0]
    assert abs(row["slope"] - 1.3) < 4 * row["slope_uncertainty"]
    assert 0 < row["slope_uncertainty"] < 0.02


def test_groups_and_masks_are_recorded():
    field = _field((80, 80), seed=4)
    table = cross_calibrate(_disk_map(field, 2.5), _disk_map(field, 2.5), resolution=5 * u.arcsec,
                            strength_bins=[0, 20, np.inf] * u.G, angle_bins=[0, 90] * u.deg)
    assert list(table["strength_max"].to_value(u.G)) == [np.inf, 20, np.inf]
    assert table["n_pixels"][0] == table["n_pixels"][1] + table["n_pixels"][2]
    for key in ("mask_valid", "mask_angle", "mask_strength", "grid", "resolution", "slope_estimator"):
        assert key in table.meta
    assert "Isobe" in table.meta["slope_estimator"]
    mask = np.zeros((40, 40), bool)
    mask[:10] = True
    assert cross_calibrate(_disk_map(field, 2.5), _disk_map(field, 2.5), resolution=5 * u.arcsec, mask=mask,
                           **ALL)["n_pixels"][0] == 400


@pytest.mark.parametrize(("call", "error", "words"), [
    (lambda a, s: cross_calibrate(np.zeros((4, 4)), a), TypeError, "map_a"),
    (lambda a, s: cross_calibrate(a, sunpy.map.Map(a.data, {**a.meta, "bunit": "m/s"})), u.UnitsError,
     "map_b"),
    (lambda a, s: cross_calibrate(a, s), ValueError, "both be disk images or both synoptic"),
    (lambda a, s: cross_calibrate(a, a, resolution=1 * u.arcsec), ValueError, "resolution"),
    (lambda a, s: cross_calibrate(a, a, resolution=5 * u.km), u.UnitsError, "resolution"),
    (lambda a, s: cross_calibrate(s, s, resolution=1.5 * u.deg), ValueError, "resolution"),
    (lambda a, s: cross_calibrate(a, a, angle_bins=[30, 10] * u.deg), ValueError, "angle_bins"),
    (lambda a, s: cross_calibrate(a, a, strength_bins=[5] * u.G), ValueError, "strength_bins"),
    (lambda a, s: cross_calibrate(a, a, mask=np.ones((3, 3), bool)), ValueError, "mask"),
    (lambda a, s: cross_calibrate(a, a, min_pixels=1), ValueError, "min_pixels"),
    (lambda a, s: cross_calibrate(a, sunpy.map.Map(np.full((8, 8), np.nan), a.meta)), ValueError, "map_b"),
    (lambda a, s: bisector_slope([1, 2, 3], [3, 2, 1]), ValueError, "positively correlated"),
])
def test_bad_inputs_name_the_argument(call, error, words, small_maps):
    with pytest.raises(error, match=words):
        call(*small_maps)


@pytest.fixture(scope="module")
def small_maps():
    """A small disk image and a small synoptic map (built once: sunpy's headers take a while)."""
    return _disk_map(_field((8, 8)), 2.5), _synoptic_map(_field((90, 180)))


def test_exported_from_the_package():
    assert gongsynth.cross_calibrate is cross_calibrate
    assert gongsynth.analysis.cross_calibrate is cross_calibrate


# --- the conversion table and calibrate(to=...) -------------------------------------------------


def test_shipped_conversion_table_loads_with_units_and_provenance():
    table = read_cross_calibration_table()
    assert table["latitude"].unit == u.deg and table["strength_min"].unit == u.G
    assert sorted(set(table["latitude"].to_value(u.deg))) == [0, 25, 45, 60, 70, 75]
    for key in ("seeds", "instruments", "resolution", "field", "input_sun", "gongsynth_version", "method"):
        assert key in table.meta, key
    assert set(table.meta["instruments"]) == {"gong", "hmi", "mdi"}
    assert table.meta["instruments"]["hmi"]["duration"] == "0.75 min"
    assert table.meta["instruments"]["mdi"]["duration"] == "1.0 min"
    assert table.meta["instruments"]["mdi"]["detector_shape"] == 82
    names = ("gong", "hmi", "mdi")
    for source in names:
        for target in [*names, "truth"]:
            if target == source:
                continue
            latitude, factor, uncertainty = conversion_factors(table, source, target)
            assert latitude.size == 6 and np.all(np.isfinite(factor)) and np.all(uncertainty >= 0)
            if target != "truth":
                # There and back is the identity: the bisector slopes of one seed are exactly reciprocal,
                # their means over the seeds to the square of the seeds' relative scatter (~1e-4 here).
                _, back, _ = conversion_factors(table, target, source)
                assert np.allclose(factor * back, 1, rtol=1e-3), (source, target)


def test_calibrate_to_hmi_multiplies_by_the_factor_at_each_viewing_angle():
    table = tabulate_cross_calibration([
        dict(latitude=lat * u.deg, mu=np.cos(np.deg2rad(lat)), instrument="gong", target="hmi", seed=1,
             table=_row(factor)) for lat, factor in ((0, 1.5), (60, 1.1))])
    values = np.full((41, 41), 10.0)
    gong = _disk_map(values, 50, telescope="NSO-GONG")
    on_hmi = calibrate(gong, to="hmi", table=table)
    assert on_hmi.data[20, 20] == pytest.approx(15.0)  # disk centre: θ = 0
    theta = gongsynth.analysis.apply_calibration.viewing_angle(gong).to_value(u.deg)
    expected = 10 * np.interp(np.clip(theta, 0, 60), [0, 60], [1.5, 1.1])
    assert np.allclose(on_hmi.data, expected, equal_nan=True)
    assert on_hmi.meta["calto"] == "hmi" and on_hmi.unit == u.G
    # Synoptic maps: θ from the latitude (a plain CEA header: sunpy's GONG source would rescale its CDELT2).
    chart = _synoptic_map(np.full((90, 180), 10.0))
    synoptic = calibrate(chart, to="hmi", table=table, instrument="gong")
    theta = gongsynth.analysis.apply_calibration.viewing_angle(chart).to_value(u.deg)
    assert np.allclose(synoptic.data, 10 * np.interp(np.clip(theta, 0, 60), [0, 60], [1.5, 1.1]))
    assert np.nanmin(synoptic.data) == 11.0  # beyond the table's last angle: its factor
    with pytest.raises(ValueError, match="calibrated already"):
        calibrate(on_hmi, to="hmi", table=table)
    with pytest.raises(ValueError, match="HMI map already"):
        calibrate(_disk_map(values, 50, telescope="SDO/HMI"), to="hmi", table=table)
    with pytest.raises(ValueError, match="no target 'mdi'"):
        calibrate(gong, to="mdi", table=table)
    with pytest.raises(ValueError, match="cannot tell which instrument"):
        calibrate(_disk_map(values, 50), to="hmi", table=table)
    assert calibrate(_disk_map(values, 50), to="hmi", table=table, instrument="gong").data[20, 20] == 15.0


def _row(factor):
    from astropy.table import QTable

    return QTable({"strength_min": [0] * u.G, "strength_max": [np.inf] * u.G, "n_pixels": [100],
                   "slope": [factor], "slope_uncertainty": [0.01], "flux_ratio": [factor],
                   "correlation": [0.9]})


def test_map_instrument_reads_the_header():
    def named(**keys):
        return keys

    assert map_instrument(named(telescop="gongsynth (simulated HMI)")) == "hmi"
    assert map_instrument(named(telescop="NSO-GONG")) == "gong"
    assert map_instrument(named(telescop="SDO/HMI", instrume="HMI_SIDE1")) == "hmi"
    assert map_instrument(named(telescop="SOHO", instrume="MDI")) == "mdi"
    assert map_instrument(_disk_map(np.zeros((4, 4)), 2.5, telescope="NSO-GONG")) == "gong"
    with pytest.raises(ValueError, match="cannot tell"):
        map_instrument(named(telescop="SOLIS"))


def test_the_table_builder_compares_every_pair_and_caches_the_runs(tmp_path, monkeypatch):
    """The sweep's bookkeeping on stand-in runs: GONG sees the truth / 1.5, HMI / 1.2 (no simulation)."""
    from types import SimpleNamespace

    import gongsynth.cross_calibration_sweep as sweep
    import gongsynth.run_cache as run_cache

    truth = _field((64, 64), seed=5, smooth=5)
    seen = {"gong": 1.5, "hmi": 1.2}
    calls = []

    def fake_run(*, config, progress):
        calls.append(config.instrument.name)
        maps = {"magnetogram": truth / seen[config.instrument.name], "truth": truth}
        return SimpleNamespace(**{name: _disk_map(maps.get(name, truth), 2.5) for name in run_cache.RUN_MAPS},
                               resolution_map=np.ones(truth.shape))

    monkeypatch.setattr(run_cache, "simulate", fake_run)
    # A name and an instrument object (the ablation script passes changed instruments).
    kwargs = dict(instruments=("gong", gongsynth.instruments.get("hmi")), latitudes=[0] * u.deg, seeds=[1],
                  resolution=10 * u.arcsec, strength_bins=[0, np.inf] * u.G, sun="milne-eddington",
                  cache=tmp_path, progress=False)
    table = sweep.cross_calibration_table(**kwargs)
    assert calls == ["gong", "hmi"]
    factor = {(r["instrument"], r["target"]): r["factor"] for r in table}
    assert factor[("gong", "hmi")] == pytest.approx(1.5 / 1.2, rel=1e-9)
    assert factor[("hmi", "gong")] == pytest.approx(1.2 / 1.5, rel=1e-9)
    assert factor[("gong", "truth")] == pytest.approx(1.5, rel=1e-9)
    assert factor[("hmi", "truth")] == pytest.approx(1.2, rel=1e-9)
    assert table.meta["seeds"] == [1] and set(table.meta["instruments"]) == {"gong", "hmi"}
    # A rerun reads the cached maps: nothing is simulated again, and the maps are the same bits.
    configs = [sweep.instrument_config(name, 0 * u.deg, 1, sun="milne-eddington") for name in ("gong", "hmi")]
    cached = sweep.simulate_instruments(configs, cache=tmp_path, progress=False)
    assert calls == ["gong", "hmi"]
    assert np.array_equal(cached[0][0].data, truth / 1.5) and np.array_equal(cached[1][1].data, truth)


def _three_instrument_table():
    """GONG sees the truth / 1.8, HMI / 1.3, MDI / 1.5 at 0°; all / 1.2, 1.1, 1.15 at 60° (stand-ins)."""
    seen = {0: {"gong": 1.8, "hmi": 1.3, "mdi": 1.5}, 60: {"gong": 1.2, "hmi": 1.1, "mdi": 1.15}}
    return tabulate_cross_calibration([
        dict(latitude=lat * u.deg, mu=np.cos(np.deg2rad(lat)), instrument=a, target=b, seed=1,
             table=_row(seen[lat][a] / seen[lat].get(b, 1.0)))
        for lat in seen for a in seen[lat] for b in [*seen[lat], "truth"] if a != b])


def test_calibrate_to_mdi_and_between_any_two_instruments_of_the_table():
    table = _three_instrument_table()
    values = np.full((41, 41), 10.0)
    gong = _disk_map(values, 50, telescope="NSO-GONG")
    on_mdi = calibrate(gong, to="MDI", table=table)
    assert on_mdi.meta["calto"] == "mdi" and "GONG put on MDI" in on_mdi.meta["history"]
    assert on_mdi.data[20, 20] == pytest.approx(10 * 1.8 / 1.5)
    # A real MDI map (TELESCOP SOHO, INSTRUME MDI) to HMI's scale and back to GONG's.
    mdi = _disk_map(values, 50, telescope="SOHO")
    mdi.meta["instrume"] = "MDI"
    assert calibrate(mdi, to="hmi", table=table).data[20, 20] == pytest.approx(10 * 1.5 / 1.3)
    assert calibrate(mdi, to="gong", table=table).data[20, 20] == pytest.approx(10 * 1.5 / 1.8)
    theta = gongsynth.analysis.apply_calibration.viewing_angle(mdi).to_value(u.deg)
    expected = 10 * np.interp(np.clip(theta, 0, 60), [0, 60], [1.5 / 1.3, 1.15 / 1.1])
    assert np.allclose(calibrate(mdi, to="hmi", table=table).data, expected, equal_nan=True)
    # to="truth" with the conversion table: MDI's own factor.
    assert calibrate(mdi, to="truth", table=table).data[20, 20] == pytest.approx(15.0)
    with pytest.raises(ValueError, match="MDI map already"):
        calibrate(mdi, to="mdi", table=table)
    with pytest.raises(ValueError, match=r"to must be one of \('truth', 'gong', 'hmi', 'mdi'\), got 'solis'"):
        calibrate(gong, to="solis", table=table)
    with pytest.raises(ValueError, match="to must be one of"):
        calibrate(gong, to=None, table=table)
    with pytest.raises(ValueError, match="instrument must be one of"):
        calibrate(gong, to="mdi", table=table, instrument="spm")
    with pytest.raises(ValueError, match=r"cannot tell which instrument.*--instrument"):
        calibrate(_disk_map(values, 50), to="mdi", table=table)


def test_cli_calibrate_to_mdi_with_the_shipped_table(tmp_path, capsys):
    from gongsynth.cli import main

    gong = _disk_map(np.full((41, 41), 10.0), 50, telescope="NSO-GONG")
    source = tmp_path / "gong.fits"
    gong.save(source)
    out = tmp_path / "on_mdi.fits"
    assert main(["calibrate", str(source), "--out", str(out), "--to", "mdi"]) == 0
    on_mdi = sunpy.map.Map(out)
    latitude, factor, _ = conversion_factors(read_cross_calibration_table(), "gong", "mdi")
    assert on_mdi.meta["calto"] == "mdi" and latitude[0] == 0 * u.deg
    assert on_mdi.data[20, 20] == pytest.approx(10 * factor[0])
    # A header that names no instrument: exit 2 saying so, unless --instrument names it.
    plain = tmp_path / "plain.fits"
    _disk_map(np.full((41, 41), 10.0), 50).save(plain)
    assert main(["calibrate", str(plain), "--out", str(tmp_path / "x.fits"), "--to", "mdi"]) == 2
    assert "--instrument" in capsys.readouterr().err
    assert main(["calibrate", str(plain), "--out", str(tmp_path / "y.fits"), "--to", "mdi",
                 "--instrument", "gong"]) == 0
    assert sunpy.map.Map(tmp_path / "y.fits").data[20, 20] == pytest.approx(10 * factor[0])
    assert main(["calibrate", str(source), "--out", str(tmp_path / "z.fits"), "--to", "solis"]) == 2


def test_the_ablation_moves_hmi_to_ni_i_without_changing_its_filters():
    """scripts/instrument_ablation.py's 'line' switch: the same filtergrams, in mÅ from the line, on Ni I."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "scripts" / "instrument_ablation.py"
    if not path.exists():
        pytest.skip("needs a source checkout")
    spec = importlib.util.spec_from_file_location("instrument_ablation", path)
    ablation = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(ablation)
    hmi = gongsynth.instruments.get("hmi")
    gong, nickel, effects = ablation.variant(("line",))
    assert nickel.line == gongsynth.instruments.get("gong").line and nickel.name == "hmi"
    assert nickel.line_wavelength == gongsynth.instruments.get("mdi").line_wavelength
    offsets = np.linspace(-600, 600, 241) * u.Unit("mAA")
    assert np.allclose(nickel.responses(nickel.line_wavelength + offsets),
                       hmi.responses(hmi.line_wavelength + offsets), rtol=1e-6, atol=1e-9)
    assert gong == gongsynth.instruments.get("gong") and effects.off == ()
    # Everything at once: both on Ni I with the Sun's Lande factor, GONG on HMI's pixels, no PSF, no noise.
    gong, nickel, effects = ablation.variant(ablation.CAUSES)
    assert gong.plate_scale == hmi.plate_scale and gong.seeing_fwhm == 0 * u.arcsec
    assert float(gong.lande_g) == float(nickel.lande_g) == 1.426
    assert set(effects.off) == {"psf", "photon_noise", "read_noise"}
