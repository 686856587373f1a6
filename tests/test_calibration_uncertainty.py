"""Calibration tables' uncertainties: the seeds' scatter, the Sun-model systematic, metadata, old tables."""
import astropy.units as u
import numpy as np
import pytest
import sunpy.map
from astropy.coordinates import SkyCoord
from astropy.table import QTable, Table
from sunpy.coordinates import frames

from gongsynth.analysis.apply_calibration import calibrate, weak_flux_factor_map
from gongsynth.analysis.calibration_table import (
    UNCERTAINTY_ESTIMATOR,
    add_systematic,
    calibration_table,
    ensemble_systematic,
    read_calibration_table,
    seed_uncertainty,
    write_calibration_table,
)
from gongsynth.analysis.weak_flux import WeakFluxFactor, flux_conserving_fit

CHANGES = Table({"variant": ["small", "large", "excluded", "small", "large", "excluded"],
                 "latitude": [0, 0, 0, 60, 60, 60] * u.deg,
                 "change": [-0.07, 0.10, 0.9, -0.045, -0.007, 0.9]})


def _table(factors, per_seed=None, sunspot=False):
    """Quiet-Sun (and sunspot) rows whose curves are truth = factor × measured, bootstrap 0.004."""
    t = np.random.default_rng(0).normal(0, 100, 20_000)
    regions = ("quiet", "sunspot") if sunspot else ("quiet",)
    fits = [WeakFluxFactor(f, 0.004, flux_conserving_fit(t / f, t, 9), region, t.size, lat * u.deg)
            for lat, f in factors.items() for region in regions]
    mu = [np.cos(np.deg2rad(lat)) for lat in factors for _ in regions]
    return calibration_table(fits, mu=mu, per_seed=per_seed, metadata={
        "grid": {"columns": [1024, 1024], "column_size": "96.0 km"}, "seeds": [1, 2, 3, 4],
        "instrument_name": "gong", "git_commit": "abc1234"})


def _disk_map(n=41, scale=50):
    ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective, observer="earth",
                   obstime="2020-01-01")
    header = sunpy.map.make_fitswcs_header((n, n), ref, scale=[scale, scale] * u.arcsec / u.pix, unit=u.G)
    return sunpy.map.Map(np.full((n, n), 10.0), header)


def test_the_seed_scatter_is_recovered_within_its_own_expected_error():
    rng = np.random.default_rng(24)
    sigma, bootstrap, n = 0.05, 0.004, 4
    # One sweep with many seeds: the spread is sigma within its standard error sigma / sqrt(2 (n - 1)).
    many = rng.normal(1.25, sigma, 400)
    uncertainty, spread = seed_uncertainty(many, bootstrap)
    assert abs(spread - sigma) < 4 * sigma / np.sqrt(2 * 399)
    assert uncertainty == pytest.approx(np.hypot(spread / 20, bootstrap))
    # Many sweeps of 4 seeds: the squared uncertainty estimates the variance of a 4-seed mean (+ the
    # bootstrap floor) without bias; var(s^2) = 2 sigma^4 / (n - 1) bounds the mean over the sweeps.
    squared = np.array([seed_uncertainty(rng.normal(1.25, sigma, n), bootstrap)[0] ** 2 for _ in range(2000)])
    expected = sigma ** 2 / n + bootstrap ** 2
    assert abs(squared.mean() - expected) < 4 * (sigma ** 2 / n) * np.sqrt(2 / (n - 1)) / np.sqrt(2000)
    # ... and it is what the scatter of the 4-seed means is.
    means = rng.normal(1.25, sigma, (2000, n)).mean(axis=1)
    assert abs(means.var(ddof=1) - sigma ** 2 / n) < 4 * (sigma ** 2 / n) * np.sqrt(2 / 1999)


def test_one_seed_or_nan_seeds_fall_back_to_the_bootstrap():
    assert seed_uncertainty([1.2], 0.004) == (0.004, pytest.approx(np.nan, nan_ok=True))
    uncertainty, spread = seed_uncertainty([1.2, np.nan, 1.3], 0.0)
    assert spread == pytest.approx(np.std([1.2, 1.3], ddof=1))
    assert uncertainty == pytest.approx(spread / np.sqrt(2))


def test_the_table_keeps_the_pooled_factor_and_the_seeds():
    table = _table({0: 1.25, 60: 1.05}, per_seed=[[1.3, 1.2, 1.35, 1.25], [1.0, 1.1, 1.05, 1.05]])
    assert list(table["factor"]) == [1.25, 1.05]  # the pooled fit, not the seeds' mean
    assert list(table["bootstrap"]) == [0.004, 0.004] and list(table["n_seeds"]) == [4, 4]
    expected = np.hypot(np.std([1.3, 1.2, 1.35, 1.25], ddof=1) / 2, 0.004)
    assert table["uncertainty"][0] == pytest.approx(expected)
    assert table["seed_factors"].shape == (2, 4)
    assert table.meta["uncertainty_estimator"] == UNCERTAINTY_ESTIMATOR
    with pytest.raises(ValueError, match="per_seed must have one entry per fit"):
        _table({0: 1.25}, per_seed=[[1.0], [1.1]])


def test_the_systematic_band_is_the_largest_accepted_change():
    sys = ensemble_systematic([0, 25, 60, 75] * u.deg, CHANGES, members=["small", "large"])
    # Measured angles: max |change| of the members (the excluded 0.9 ignored); others: the envelope.
    assert sys.tolist() == pytest.approx([0.10, 0.10, 0.045, 0.10])
    assert ensemble_systematic([60] * u.deg, CHANGES, members=["large"]).tolist() == pytest.approx([0.007])
    with pytest.raises(ValueError, match="members .'nope'. are not in the ensemble"):
        ensemble_systematic([0] * u.deg, CHANGES, members=["nope"])


def test_metadata_and_uncertainty_columns_round_trip(tmp_path):
    table = _table({0: 1.25, 60: 1.05}, per_seed=[[1.3, 1.2, 1.35, 1.25]] * 4, sunspot=True)
    add_systematic(table, CHANGES, ["small", "large"], source="ensemble.ecsv")
    assert np.isnan(table["systematic"][1]) and table["systematic"][2] == pytest.approx(0.045)
    path = tmp_path / "table.ecsv"
    write_calibration_table(table, path)
    back = read_calibration_table(path)
    for column in ("factor", "uncertainty", "bootstrap", "seed_spread", "n_seeds", "seed_factors",
                   "systematic"):
        np.testing.assert_array_equal(np.asarray(back[column]), np.asarray(table[column]))
    assert back.meta["grid"] == {"columns": [1024, 1024], "column_size": "96.0 km"}
    assert back.meta["seeds"] == [1, 2, 3, 4] and back.meta["instrument_name"] == "gong"
    assert back.meta["git_commit"] == "abc1234" and back.meta["ensemble_members"] == ["large", "small"]
    assert back.meta["ensemble_source"] == "ensemble.ecsv" and "systematic_rule" in back.meta


def test_calibrate_reports_statistical_and_systematic_apart_and_old_tables_still_work(tmp_path):
    old = _table({0: 2.0, 60: 1.0})  # no per-seed columns, no systematic: a table as shipped before
    path = tmp_path / "old.ecsv"
    write_calibration_table(old, path)
    smap = _disk_map()
    out = calibrate(smap, table=path)
    assert "calsyst" not in out.meta and out.meta["calstat"] == pytest.approx(0.004, abs=1e-4)  # 0.004 / 1
    with pytest.raises(ValueError, match="no 'systematic' column"):
        weak_flux_factor_map(smap, table=path, column="systematic")
    new = add_systematic(_table({0: 2.0, 60: 1.0}, per_seed=[[2.1, 1.9], [1.0, 1.0]]), CHANGES,
                         ["small", "large"], source="test")
    out_new = calibrate(smap, table=new)
    np.testing.assert_array_equal(out_new.data, out.data)  # the curves are the same
    # Relative: the disk centre's 0.1 / 2 against the limb's 0.045 / 1.
    assert out_new.meta["calsyst"] == pytest.approx(0.05, abs=2e-3)
    stat_centre = np.hypot(np.std([2.1, 1.9], ddof=1) / np.sqrt(2), 0.004) / 2
    assert out_new.meta["calstat"] == pytest.approx(stat_centre, abs=2e-3)
    systematic = weak_flux_factor_map(smap, table=new, column="systematic").data
    on = np.isfinite(systematic)
    assert np.nanmax(systematic) <= 0.1 + 1e-12 and np.nanmin(systematic[on]) >= 0.045 - 1e-12
    with pytest.raises(ValueError, match="column must be"):
        weak_flux_factor_map(smap, table=new, column="values")


def test_the_shipped_table_loads_and_calibrates():
    table = read_calibration_table()
    assert isinstance(table, QTable) and {"factor", "uncertainty"} <= set(table.colnames)
    out = calibrate(_disk_map(11, 200), table=table)
    assert np.isfinite(out.data).any() and "calstat" in out.meta and "calsyst" in out.meta
    assert table.meta["grid"]["columns"] == [1024, 1024] and table.meta["seeds"] == [1, 2, 3, 4]
    assert np.all(table["uncertainty"] >= table["bootstrap"]) and "systematic" in table.colnames
