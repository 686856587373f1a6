"""
The supergranular flow: its shape on the cells, its rms, its line-of-sight signal over the disk, the network
in its downflows, and the 3-D patches' flows that it replaces above 10 Mm.
"""
import astropy.units as u
import numpy as np
import pytest
from scipy.ndimage import gaussian_filter
from scipy.spatial import cKDTree

from gongsynth.stages.scene.surface import large_scale_grid
from gongsynth.sun.model_atmosphere import model_atmosphere
from gongsynth.sun.surface_field.network import SupergranularNetwork
from gongsynth.sun.surface_field.supergranulation import HORIZONTAL_RMS, VERTICAL_RMS, supergranular_flow

DATE = "2009-09-05T18:54:16"


def unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def split(velocity, points):
    """Vertical part and horizontal vector of velocities at points."""
    up = (velocity * points).sum(axis=1)
    return up, velocity - up[:, None] * points


@pytest.fixture(scope="module")
def sphere():
    rng = np.random.default_rng(7)
    centres = unit(rng.standard_normal((600, 3)))
    points = unit(rng.standard_normal((60000, 3)))
    return centres, points


def test_outflow_from_the_centre_converging_on_the_walls(sphere):
    centres, points = sphere
    v = supergranular_flow(centres, points).to_value(u.m / u.s)
    horizontal = split(v, points)[1]
    # Each point's own cell (its nearest centre): the flow points away from that centre, never toward it.
    own = centres[cKDTree(centres).query(points)[1]]        # not a dense 6e4 × 600 product (0.3 GB)
    toward_centre = own - (own * points).sum(axis=1)[:, None] * points
    assert np.all((horizontal * toward_centre).sum(axis=1) <= 1e-9)
    # At a centre the horizontal flow is still and the vertical one rises.
    up_c, h_c = split(supergranular_flow(centres, centres[:5]).to_value(u.m / u.s), centres[:5])
    assert np.abs(h_c).max() < 1e-6 and np.all(up_c > 0)
    # On a wall (the midpoint of two neighbouring centres) it is still too, and sinks.
    nearest = np.argsort(centres @ centres[0])[-2]
    wall = unit(centres[0] + centres[nearest])[None, :]
    up_w, h_w = split(supergranular_flow(centres, wall).to_value(u.m / u.s), wall)
    assert np.linalg.norm(h_w) < 1e-6 * HORIZONTAL_RMS.to_value(u.m / u.s) and up_w[0] < 0
    # Just either side of that wall, each cell's outflow heads for it: the flow converges there.
    across = unit(centres[nearest] - centres[0])
    for side in (-1, 1):
        p = unit(wall + side * 1e-3 * across)
        h = split(supergranular_flow(centres, p).to_value(u.m / u.s), p)[1]
        assert (h @ across)[0] * side < 0


def test_rms_over_the_sphere_whichever_points_are_asked(sphere):
    """
    The set rms values hold over the sphere: 60 000 random points measure them within 1.5 % (about five
    times the scatter of a mean over 600 cells of ~100 points each), the vertical mean within 0.5 m/s.
    """
    centres, points = sphere
    v = supergranular_flow(centres, points, horizontal_rms=300 * u.m / u.s,
                           vertical_rms=20 * u.m / u.s).to_value(u.m / u.s)
    up, horizontal = split(v, points)
    assert np.sqrt(np.mean((horizontal ** 2).sum(axis=1))) == pytest.approx(300, rel=0.015)
    assert np.sqrt(np.mean(up ** 2)) == pytest.approx(20, rel=0.015)
    assert abs(np.mean(up)) < 0.5
    # A point's flow is its own: asked alone it is the same, bit for bit.
    alone = supergranular_flow(centres, points[:1], horizontal_rms=300 * u.m / u.s,
                               vertical_rms=20 * u.m / u.s).to_value(u.m / u.s)
    assert np.array_equal(alone, v[:1])
    off = supergranular_flow(centres, points, horizontal_rms=0 * u.m / u.s, vertical_rms=0 * u.m / u.s)
    assert not np.any(off.value)


@pytest.mark.parametrize(("kwargs", "match"), [
    (dict(centres=np.ones((1, 3))), "at least two cells"),
    (dict(points=np.ones((4, 2))), "points must be an"),
    (dict(horizontal_rms=-1 * u.m / u.s), "horizontal_rms"),
    (dict(vertical_rms=3 * u.G), "vertical_rms"),
])
def test_bad_arguments_are_named(kwargs, match):
    args = dict(centres=unit(np.eye(3)), points=unit(np.ones((4, 3))))
    args.update(kwargs)
    with pytest.raises((ValueError, u.UnitsError, TypeError), match=match):
        supergranular_flow(args.pop("centres"), args.pop("points"), **args)


def test_line_of_sight_signal_grows_toward_the_limb():
    """
    The flow's Doppler signal in rings of μ: √(V_h² sin²θ / 2 + V_z² μ²) for horizontal directions at random.

    A ring holds N ≥ 250 supergranules; the squared signal of one cell is nearly independent of the
    next, so the ring's rms strays by about 1/√(2N) ≤ 4.5 %; the tolerance is three times that.
    """
    net = SupergranularNetwork(seed=3)
    with_flow, without = (large_scale_grid(DATE, network=net, rotation=False, observer=False, blueshift=None,
                                           supergranulation=flow) for flow in (True, False))
    assert with_flow.meta["supergranulation"] and not without.meta["supergranulation"]
    assert not np.any(without.velocity)
    lat, lon = np.meshgrid(np.radians(with_flow.latitude), np.radians(with_flow.longitude), indexing="ij")
    from sunpy.coordinates import sun
    b0 = sun.B0(DATE).to_value(u.rad)
    mu = np.cos(lat) * np.cos(lon) * np.cos(b0) + np.sin(lat) * np.sin(b0)
    vh, vz = HORIZONTAL_RMS.to_value(u.m / u.s), VERTICAL_RMS.to_value(u.m / u.s)
    cell_area = (30e3) ** 2
    for lo, hi in ((0.9, 1.0), (0.7, 0.8), (0.45, 0.55), (0.2, 0.3)):
        ring = (mu > lo) & (mu <= hi)
        weight = np.cos(lat[ring])
        rms = np.sqrt(np.sum(weight * with_flow.velocity[ring] ** 2) / weight.sum())
        m = 0.5 * (lo + hi)
        expected = np.sqrt(vh ** 2 * (1 - m ** 2) / 2 + vz ** 2 * m ** 2)
        cells = 2 * np.pi * 696e3 ** 2 * (hi - lo) / cell_area
        assert cells > 250
        assert rms == pytest.approx(expected, rel=3 / np.sqrt(2 * cells)), (lo, hi)
    assert not np.any(with_flow.velocity[mu < -0.03])


def test_a_cells_limbward_half_recedes():
    """West of disk centre a cell's outflow toward the limb moves away from the observer: a redshift."""
    from sunpy.coordinates import sun
    net = SupergranularNetwork(seed=3)
    grid = large_scale_grid(DATE, network=net, rotation=False, observer=False, blueshift=None)
    centres = net.cells()[0]
    b0 = sun.B0(DATE).to_value(u.rad)
    # The cell centre nearest to 40° west on the disk's central row (latitude B0 seen face on: lat 0 here).
    target = unit([np.cos(np.radians(40)), np.sin(np.radians(40)), 0.0])
    c = centres[np.argmax(centres @ target)]
    lon, lat = np.degrees(np.arctan2(c[1], c[0])), np.degrees(np.arcsin(c[2]))
    row = np.argmin(np.abs(grid.latitude - lat))
    step = 6.0 / 696.0 * 180 / np.pi / np.cos(np.radians(lat))      # 6 Mm along the row, in degrees
    limbward = grid.velocity[row, np.argmin(np.abs(grid.longitude - (lon + step)))]
    centreward = grid.velocity[row, np.argmin(np.abs(grid.longitude - (lon - step)))]
    assert abs(b0) < 0.2 and limbward > 50 and centreward < -50


def test_the_network_sits_in_the_flows_downdrafts():
    """The network's flux, weighted, lies where the flow sinks and converges: near the cells' walls."""
    net = SupergranularNetwork(seed=4, ephemeral_flux_density=0 * u.G)
    lon, lat = np.linspace(-60, 60, 481), np.linspace(-60, 60, 481)
    field = net.on_grid(lon, lat, np.zeros((lat.size, lon.size)))
    glat, glon = np.meshgrid(np.radians(lat), np.radians(lon), indexing="ij")
    points = np.stack([np.cos(glat) * np.cos(glon), np.cos(glat) * np.sin(glon), np.sin(glat)], axis=-1)
    points = points.reshape(-1, 3)
    area = np.cos(glat).ravel()
    up = (supergranular_flow(net.cells()[0], points).to_value(u.m / u.s) * points).sum(axis=1)
    flux = np.abs(field).ravel() * area
    # Area mean of the vertical flow is zero; the flux-weighted mean is a clear downflow.
    assert abs(np.sum(up * area) / area.sum()) < 1.0
    assert np.sum(up * flux) / flux.sum() < -0.5 * VERTICAL_RMS.to_value(u.m / u.s)   # -21 m/s here


def test_a_patch_keeps_its_granular_flow_and_loses_its_large_scale_tail():
    """
    ``flow_cutoff`` of 10 Mm keeps 1 − exp(−(10 Mm / λ)²) of each wavelength λ: 0.63 at 10 Mm, 0.2 at
    21 Mm, 0.1 at 31 Mm.  Smoothed over σ = 4 Mm (where those scales are what is left) the horizontal
    flow falls by more than four; its full rms, granular, stays within 25 %; the vertical rms at τ = 1 is
    the set granulation velocity.
    """
    def flows(cut):
        atm = model_atmosphere((64, 64), pixel_size=384 * u.km, seed=5, nz=40, spot=False, network=False,
                               flow_cutoff=cut)
        v = atm.velocity.to_value(u.m / u.s)
        z = atm.z.to_value(u.km)
        k = int(np.argmin(np.abs(z - 200)))
        return v[:2, k], v[2, int(np.argmin(np.abs(z)))], atm.meta["params"]

    (h_all, vz_all, p_all), (h_cut, vz_cut, p_cut) = flows(0 * u.Mm), flows(10 * u.Mm)
    assert "flow_cutoff_km" not in p_all and p_cut["flow_cutoff_km"] == 10000.0

    def smoothed(h):
        return np.sqrt(sum(gaussian_filter(c, 4000 / 384, mode="wrap").var() for c in h))

    def rms(h):
        return np.sqrt(sum(c.var() for c in h))

    assert smoothed(h_cut) < smoothed(h_all) / 4
    assert rms(h_cut) == pytest.approx(rms(h_all), rel=0.25)
    assert vz_cut.std() == pytest.approx(vz_all.std(), rel=0.02)
    with pytest.raises(ValueError, match="flow_cutoff"):
        model_atmosphere((16, 16), seed=1, nz=40, flow_cutoff=-1 * u.Mm)


def test_a_tiled_box_with_supergranulation_adds_its_cells_flow_at_every_height():
    """
    ``supergranulation``: the velocity is that of the same box with the granular flow cut at 10 Mm plus
    one flow the same at every height (to float32 rounding, < 0.01 m/s), of 350 m/s rms horizontal and
    25 m/s rms vertical with no mean; temperature, pressure and field keep their bits.
    """
    args = dict(seed=3, nz=40, spot=False, network=True, supergranule_size=10 * u.Mm)
    cut = model_atmosphere((64, 64), pixel_size=384 * u.km, flow_cutoff=10 * u.Mm, **args)
    flowing = model_atmosphere((64, 64), pixel_size=384 * u.km, supergranulation=True, **args)
    assert flowing.meta["params"]["supergranulation"] and flowing.meta["params"]["flow_cutoff_km"] == 10000
    added = flowing.raw("velocity").astype(float) - cut.raw("velocity").astype(float)     # km/s
    added *= 1e3
    assert np.abs(added - added[:, :1]).max() < 0.01
    vx, vy, vz = added[:, 0]
    assert np.sqrt(np.mean(vx ** 2 + vy ** 2)) == pytest.approx(350, rel=1e-4)
    assert vz.std() == pytest.approx(25, rel=1e-3) and abs(vz.mean()) < 0.01
    for name in ("temperature", "gas_pressure", "magnetic_field"):
        assert np.array_equal(flowing.raw(name), cut.raw(name)), name
    with pytest.raises(ValueError, match="supergranulation needs the network"):
        model_atmosphere((16, 16), seed=1, nz=40, network=False, supergranulation=True)


def test_the_periodic_cells_flow_outward_across_the_wrap():
    """`cell_flow` in a periodic box: away from each column's own centre (minimum image), still on walls."""
    from gongsynth.sun.model_atmosphere.granulation import PeriodicGrid
    from gongsynth.sun.model_atmosphere.network_layout import cell_centres, cell_flow
    from gongsynth.sun.photosphere.voronoi import cell_walls

    grid = PeriodicGrid(96, 128, 384.0)
    centres = cell_centres(grid, np.random.default_rng(2), 12000.0)
    vx, vy, vz = cell_flow(grid, centres)
    wall, _, cell = cell_walls(grid, centres)
    y, x = grid.coords()
    dx = (x - centres[cell, 0] + grid.Lx / 2) % grid.Lx - grid.Lx / 2
    dy = (y - centres[cell, 1] + grid.Ly / 2) % grid.Ly - grid.Ly / 2
    assert np.all(vx * dx + vy * dy >= -1e-9)
    near_wall = wall < 0.005 * 12000.0                      # sin(πs) ≈ π (1 - s) there: a few % of the peak
    assert near_wall.sum() > 20 and np.hypot(vx, vy)[near_wall].max() < 0.1 * np.hypot(vx, vy).max()
    assert vz[near_wall].mean() < 0 < vz[wall > 0.3 * 12000.0].mean()
