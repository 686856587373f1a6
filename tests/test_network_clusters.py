"""Network clusters of a magnetogram: fluxes of known elements, connectivity, the quiet mask, the index."""
import astropy.units as u
import numpy as np
import pytest
import sunpy.map
from astropy.coordinates import SkyCoord
from sunpy.coordinates import frames
from sunpy.sun.constants import radius as solar_radius

from gongsynth.analysis.network_clusters import network_clusters

SCALE = 2.5  # arcsec per pixel


def centre_map(data):
    """A helioprojective map of ``data`` (G) centred on disk centre, 2.5″ pixels, seen from Earth."""
    ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective, observer="earth",
                   obstime="2020-06-01T12:00")
    header = sunpy.map.make_fitswcs_header(data, ref, scale=[SCALE, SCALE] * u.arcsec / u.pix, unit=u.G)
    return sunpy.map.Map(data, header)


def pixel_flux(smap, field):
    """Flux (Mx) of one pixel of ``field`` G at disk centre: its side in cm from the map's solar radius."""
    side_cm = SCALE * solar_radius.to_value(u.cm) / smap.rsun_obs.to_value(u.arcsec)
    return field * side_cm**2


def test_fluxes_signs_and_connectivity():
    data = np.zeros((121, 121))
    data[60:63, 60:63] = 100.0          # 3 × 3 positive element
    data[40, 40] = data[41, 41] = 50.0  # touching diagonally: one cluster
    data[80, 80] = -70.0                # a negative one
    data[80, 81] = 70.0                 # a positive neighbour of opposite sign: its own cluster
    data[20, 100] = 15.0                # below the threshold
    smap = centre_map(data)
    found = network_clusters(smap, max_radius=0.15)
    t = found.table
    assert len(t) == 4
    # Radial-field flux: B/μ over the area A/μ, with μ² = 1 − ρ² from each pixel's distance to the centre.
    def rho2(y, x):
        return ((np.hypot(y - 60, x - 60) * SCALE) / smap.rsun_obs.to_value(u.arcsec)) ** 2

    expected = [sum(100.0 / (1 - rho2(y, x)) for y in range(60, 63) for x in range(60, 63)),
                50.0 / (1 - rho2(40, 40)) + 50.0 / (1 - rho2(41, 41)), 70.0 / (1 - rho2(80, 80)),
                70.0 / (1 - rho2(80, 81))]
    measured = t["flux"].to_value(u.Mx)
    np.testing.assert_allclose(measured[:2], pixel_flux(smap, np.array(expected[:2])), rtol=1e-6)
    np.testing.assert_allclose(sorted(measured[2:]), pixel_flux(smap, np.sort(expected[2:])), rtol=1e-6)
    assert list(t["pixels"]) == [9, 2, 1, 1]
    assert sorted(t["sign"][2:]) == [-1, 1]
    np.testing.assert_allclose(t["peak"].to_value(u.G), [100, 50, 70, 70])
    summary = found.summary()
    assert summary["number"] == 4
    np.testing.assert_allclose(summary["flux_density"].to_value(u.G),
                               t["flux"].sum().to_value(u.Mx) / (found.region_area.to_value(u.Mm**2) * 1e16))


def test_elongation_of_lines_squares_and_single_pixels():
    # Pixels count as uniform squares: a row of n equal pixels has second moments n²/12 along it and
    # 1/12 across, so its elongation is exactly n; a square cluster's and one pixel's are 1.
    data = np.zeros((121, 121))
    data[50, 40:47] = 60.0              # a row of 7 pixels
    data[70:75, 60] = -60.0             # a column of 5
    data[60:63, 75:78] = 60.0           # a 3 × 3 square
    data[45, 70] = 60.0                 # one pixel
    data[80, 50] = data[80, 52] = 40.0  # two single pixels (not 8-connected): two clusters
    found = network_clusters(centre_map(data), max_radius=0.15)
    by_pixels = {int(n): float(e) for n, e in zip(found.table["pixels"], found.table["elongation"])}
    assert by_pixels[7] == pytest.approx(7.0, rel=1e-9)
    assert by_pixels[5] == pytest.approx(5.0, rel=1e-9)
    assert by_pixels[9] == pytest.approx(1.0, rel=1e-9)
    assert by_pixels[1] == pytest.approx(1.0, rel=1e-9)
    # The summary's median is over the clusters of at least SHAPE_PIXELS (6) pixels: the row and the square.
    summary = found.summary()
    assert summary["shaped"] == 2
    assert summary["elongation"] == pytest.approx(4.0, rel=1e-9)


def test_elongation_weighs_by_field():
    # A row of 3 whose ends are weak is rounder than one of equal pixels: the weights are |B|.
    data = np.zeros((121, 121))
    data[50, 40:43] = [30.0, 90.0, 30.0]
    found = network_clusters(centre_map(data), max_radius=0.15)
    # Variance along the row: 2 × 30 / 150 = 0.4 pixel², plus 1/12 for the pixels' own extent.
    expected = np.sqrt((0.4 + 1 / 12) / (1 / 12))
    assert float(found.table["elongation"][0]) == pytest.approx(expected, rel=1e-9)
    assert np.isnan(found.summary()["elongation"])      # no cluster of 6 pixels


def test_median_is_removed_and_region_is_a_disk():
    data = np.full((121, 121), -3.0)    # a zero point: not a cluster at any threshold above it
    data[60, 60] = 30.0                 # 33 G above the median
    data[0, 0] = 500.0                  # outside max_radius
    found = network_clusters(centre_map(data), threshold=20 * u.G, max_radius=0.15)
    assert len(found.table) == 1
    assert float(found.table["peak"][0].to_value(u.G)) == pytest.approx(33.0)
    # The region's area is the disk of 0.15 R☉ on the sphere (pixelised: within 2 %).
    expected = np.pi * (0.15 * solar_radius.to_value(u.Mm))**2 * 2 * (1 - np.sqrt(1 - 0.15**2)) / 0.15**2
    assert found.region_area.to_value(u.Mm**2) == pytest.approx(expected, rel=0.02)


def test_active_region_left_out():
    data = np.zeros((161, 161))
    data[20:60, 20:60] = 80.0           # plage: even its corners' 60″ boxes average 20 G
    data[120, 120] = 60.0               # a network element in the quiet Sun
    smap = centre_map(data)
    quiet = network_clusters(smap, max_radius=0.2)
    everything = network_clusters(smap, max_radius=0.2, quiet_below=None)
    assert len(quiet.table) == 1 and len(everything.table) == 2
    assert quiet.region_area < everything.region_area


def test_power_law_index_recovered():
    """Isolated one-pixel elements with Pareto fluxes (index 2.5): the fit within 3 of its standard errors.

    Within 0.1 R☉ the 1/μ² of the radial-field flux is below 1.006, which biases the index by < 0.01
    (a quarter of its standard error)."""
    rng = np.random.default_rng(7)
    n_side = 40
    data = np.zeros((2 * n_side + 1, 2 * n_side + 1))
    smap = centre_map(data)
    one = pixel_flux(smap, 1.0)
    lo = 30.0 * one                       # 30 G in one pixel
    flux = lo * (1 - rng.uniform(size=n_side**2)) ** (-1 / 1.5)
    data[1::2, 1::2][:n_side, :n_side] = (flux / one).reshape(n_side, n_side)
    found = network_clusters(centre_map(data), max_radius=0.1, quiet_below=None)
    summary = found.summary(index_flux=lo * u.Mx)
    assert summary["above_index_flux"] > 1000
    assert abs(summary["index"] - 2.5) < 3 * summary["index_error"]


@pytest.mark.parametrize("kwargs, match", [
    ({"threshold": 0 * u.G}, "threshold"),
    ({"threshold": 20}, "threshold"),
    ({"max_radius": 1.5}, "max_radius"),
    ({"quiet_below": -1 * u.G}, "quiet_below"),
    ({"quiet_window": 0 * u.arcsec}, "quiet_window"),
])
def test_bad_arguments_named(kwargs, match):
    with pytest.raises((ValueError, TypeError), match=match):
        network_clusters(centre_map(np.zeros((21, 21))), **kwargs)


def test_not_a_map():
    with pytest.raises(TypeError, match="smap"):
        network_clusters(np.zeros((10, 10)))


def test_quiet_mask_leaves_out_a_plage_strip_and_its_box_around_it():
    from gongsynth.analysis.network_clusters import quiet_mask

    field = np.zeros((80, 80))
    field[:, 50:] = 40.0                        # plage: mean |B| 40 G, above the 15 G rule
    quiet = quiet_mask(field, 2.5 * u.arcsec)   # a 60″ box is 24 pixels
    assert quiet[:, :30].all() and not quiet[:, 52:].any()
    # A box half on the strip averages 20 G: still not quiet; one pixel off the box's reach is.
    assert not quiet[:, 49].any() and quiet[:, 37].all()
    with pytest.raises(u.UnitsError, match="pixel_scale"):
        quiet_mask(field, 2.5 * u.G)
