"""Real GONG geometry: sunpy's ephemeris against GONG's headers, and a run "like" a real GONG file."""
import astropy.units as u
import numpy as np
import pytest
from astropy.io import fits

from gongsynth.config import SimulationConfig
from gongsynth.geometry import disk_geometry
from gongsynth.observing import GONG_SITES, check_site, ephemeris, gong_view, like_gong, site_location

from .realdata import gong_header, load_real, real_file

BIG_BEAR = "gong/bbbqa090905t1854.fits.gz"


def test_sunpy_ephemeris_agrees_with_the_big_bear_header():
    header = fits.getheader(real_file(BIG_BEAR))
    view = gong_view(real_file(BIG_BEAR))
    e = ephemeris(view.obstime, view.location)
    # P angle to 0.01 deg (the header's PA, radians); the header's distance and apparent radius
    # (computed with R = 696 000 km, sunpy's is 695 700 km) to 1e-4 AU and 0.1 %.
    assert e.p_angle.to_value(u.deg) == pytest.approx(np.degrees(header["PA"]), abs=0.01)
    assert e.distance.to_value(u.AU) == pytest.approx(header["DISTANCE"], abs=1e-4)
    assert e.angular_radius.to_value(u.rad) == pytest.approx(header["RADIUS"], rel=1e-3)


def test_sunpy_ephemeris_agrees_with_the_learmonth_header():
    header = gong_header()  # sunpy's real GONG header, Learmonth 2025-01-09
    view = gong_view(header)
    e = ephemeris(view.obstime, view.location)
    assert e.p_angle.to_value(u.deg) == pytest.approx(np.degrees(header["PA"]), abs=0.01)
    assert e.b0.to_value(u.deg) == pytest.approx(header["B0"], abs=0.01)
    # L0 turns 0.55 deg per hour: 0.05 deg is 5 minutes of the header's time convention.
    assert e.l0.to_value(u.deg) == pytest.approx(header["L0"], abs=0.05)
    assert e.distance.to_value(u.AU) == pytest.approx(header["DISTANCE"], abs=1e-4)


@pytest.mark.parametrize("source", ["big bear", "learmonth"])
def test_the_site_table_agrees_with_the_headers(source):
    header = fits.getheader(real_file(BIG_BEAR)) if source == "big bear" else gong_header()
    site = GONG_SITES[header["SITE"].strip()]
    assert site.latitude == pytest.approx(np.degrees(header["LAT"]), abs=0.01)
    assert site.longitude == pytest.approx(np.degrees(header["LON"]), abs=0.01)


def test_a_run_like_big_bear_has_its_disk():
    # The plate scale from the header (apparent radius over the fitted limb) puts the simulated
    # disk on the real one: the count of on-disk pixels of the real magnetogram gives its radius.
    view = gong_view(real_file(BIG_BEAR))
    assert view.site == "BB" and view.obstime.isot == "2009-09-05T18:54:16.000"
    assert 2.55 < view.plate_scale.to_value(u.arcsec) < 2.57
    real = load_real(BIG_BEAR, "magnetogram")
    real_radius = np.sqrt(np.isfinite(real.data).sum() / np.pi)
    geometry = disk_geometry((860, 860), view.plate_scale, obstime=view.obstime, pointing=view.pointing)
    simulated_radius = np.sqrt(geometry.on_disk.sum() / np.pi)
    assert simulated_radius == pytest.approx(real_radius, abs=0.5)
    assert simulated_radius == pytest.approx(view.disk_radius.to_value(u.pix), abs=0.5)
    # The pointing (the image centre 11.6 px west and 1.9 px north of the disk centre) puts the
    # simulated disk on the real one's pixels: same centroid to a tenth of a pixel, and the two
    # masks differ only along the limb's one-pixel rim (a circumference of ~2300 pixels).
    rows, cols = np.nonzero(np.isfinite(real.data))
    sim_rows, sim_cols = np.nonzero(geometry.on_disk)
    assert sim_cols.mean() == pytest.approx(cols.mean(), abs=0.1)
    assert sim_rows.mean() == pytest.approx(rows.mean(), abs=0.1)
    assert (geometry.on_disk != np.isfinite(real.data)).sum() < 2 * np.pi * real_radius
    assert view.pointing.to_value(u.arcsec) == pytest.approx(
        [(429.5 - view.disk_centre[0]) * view.plate_scale.to_value(u.arcsec),
         (429.5 - view.disk_centre[1]) * view.plate_scale.to_value(u.arcsec)])


def test_sites():
    assert check_site(" le ") == "LE" and check_site(None) is None
    assert site_location(None) is None
    assert site_location("CT").lat.deg < -30
    with pytest.raises(ValueError, match="GONG sites"):
        check_site("XX")
    with pytest.raises(ValueError, match="not a GONG full-disk header"):
        gong_view(fits.Header({"TELESCOP": "SDO/HMI", "DATE-OBS": "2010-10-15"}))


def test_like_in_toml_and_explicit_keys_win(tmp_path):
    path = str(real_file(BIG_BEAR))
    cfg = SimulationConfig.from_toml(f'[simulation]\nlike = "{path}"\nseed = 1\n')
    assert cfg.obstime.startswith("2009-09-05T18:54:16") and cfg.site == "BB" and cfg.like == path
    assert cfg.instrument.plate_scale.to_value(u.arcsec) == pytest.approx(2.5613, abs=1e-3)
    mine = SimulationConfig.from_toml(f'[simulation]\nlike = "{path}"\nobstime = "2010-01-01T00:00"\n'
                                      f'site = "ML"\n[instrument]\nplate_scale = "2.5 arcsec"\n')
    assert mine.obstime.startswith("2010-01-01") and mine.site == "ML"
    assert mine.instrument.plate_scale == 2.5 * u.arcsec
    # A saved run repeats without the file: everything it took from it is written out.
    assert SimulationConfig.from_toml(cfg.to_toml()) == cfg
    moved = cfg.to_toml().replace(path, str(tmp_path / "gone.fits.gz"))
    assert SimulationConfig.from_toml(moved).replace(like=cfg.like) == cfg
    # ... but a file that is needed and missing is named.
    with pytest.raises(FileNotFoundError, match="gone"):
        SimulationConfig.from_toml(f'[simulation]\nlike = "{tmp_path / "gone.fits.gz"}"\n')
    with pytest.raises(ValueError, match="site"):
        SimulationConfig(site="XX")


def test_like_gong_reads_the_header_only_when_needed(tmp_path):
    settings, inst = like_gong(tmp_path / "absent.fits", settings={"obstime": "2009-01-01", "site": "BB",
                                                                   "pointing": [0, 0] * u.arcsec},
                               fixed_plate_scale=True)
    assert settings["like"].endswith("absent.fits") and inst.plate_scale == 2.5 * u.arcsec


def test_a_full_disk_like_run_observes_as_the_file_did_unless_told_otherwise():
    import sunpy.data.test

    from gongsynth.cli import _simulation_config, build_parser
    from gongsynth.observing import AS_OBSERVED_EFFECTS

    path = sunpy.data.test.get_test_filepath("gong_magnetogram.header")
    disk = SimulationConfig.from_toml(f'[simulation]\nlike = "{path}"\nmode = "full-disk"\nseed = 1\n')
    assert disk.like_counts and all(getattr(disk.effects, name) for name in AS_OBSERVED_EFFECTS)
    assert SimulationConfig.from_toml(disk.to_toml()) == disk          # written out, so it repeats
    mine = SimulationConfig.from_toml(f'[simulation]\nlike = "{path}"\nmode = "full-disk"\n'
                                      f'like_counts = false\n[effects]\nimage_rotation = false\n')
    assert not mine.like_counts and not mine.effects.image_rotation and mine.effects.frame_seeing
    assert SimulationConfig.from_toml(mine.to_toml()) == mine
    # A tiled run takes the date and site only; a run without like keeps every opt-in effect off.
    tiled = SimulationConfig.from_toml(f'[simulation]\nlike = "{path}"\n')
    assert not tiled.like_counts and tiled.effects.opted_in == ()
    assert SimulationConfig(mode="full-disk").effects.opted_in == ()

    def cli(*flags):
        return _simulation_config(build_parser().parse_args(["simulate", "--out", "x", *flags]))

    run = cli("--like", path, "--mode", "full-disk", "--no-minute-average", "--no-like-counts")
    assert not run.like_counts and not run.effects.minute_average
    assert run.effects.frame_seeing and run.effects.image_rotation
    assert cli("--like", path, "--mode", "full-disk", "--seed", "1") == disk
    assert cli("--mode", "full-disk", "--frame-seeing").effects.opted_in == ("frame_seeing",)
