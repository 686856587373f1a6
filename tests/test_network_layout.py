"""The 3-D Sun's supergranular network (`gongsynth.sun.model_atmosphere.network_layout`)."""
import math

import astropy.units as u
import numpy as np
import pytest

from gongsynth.config import SimulationConfig
from gongsynth.sun.model_atmosphere import model_sun
from gongsynth.sun.model_atmosphere.granulation import PeriodicGrid
from gongsynth.sun.model_atmosphere.network_layout import LANE_WIDTH_KM, MIN_SEPARATION, cell_centres
from gongsynth.sun.photosphere.voronoi import cell_walls

#: A cheap 98 Mm box, the default run box's size.
SHAPE, PIXEL = (128, 128), 768 * u.km


def _sun(seed=1, **kwargs):
    return model_sun(SHAPE, PIXEL, seed=seed, nz=16, spot=False, **kwargs)._plan


@pytest.mark.parametrize("size_mm", [20.0, 35.0])
def test_cells_periodic_and_of_requested_size(size_mm):
    grid = PeriodicGrid(*SHAPE, PIXEL.to_value(u.km))
    s = size_mm * 1e3
    centres = cell_centres(grid, np.random.default_rng(3), s)
    area = grid.Lx * grid.Ly
    # n = round(area / s²): the mean spacing is s up to that rounding.
    n = len(centres)
    assert abs(area / n - s ** 2) <= 0.5 * s ** 2 / n * (1 + 1e-9)
    box = np.array([grid.Lx, grid.Ly])
    off = (centres[:, None] - centres[None] + box / 2) % box - box / 2
    dist = np.hypot(off[..., 0], off[..., 1]) + np.eye(n) * 1e30
    assert dist.min() >= MIN_SEPARATION * s
    # Periodic: centres moved by whole pixels (across the box's edge) move the walls by as many pixels.
    wall, _, cell = cell_walls(grid, centres)
    shift = np.array([37, 101]) * grid.dx                      # (x, y)
    moved, _, _ = cell_walls(grid, (centres + shift) % box)
    np.testing.assert_allclose(moved, np.roll(wall, (101, 37), axis=(0, 1)), atol=1e-6)
    assert np.unique(cell).size == n


def _effective_count(total, lo=1e17, hi=1e19, index=1.85):
    """(ΣΦ)²/ΣΦ² of the builder's element fluxes (N(Φ) ∝ Φ^−index, Parnell 2009) summing to ``total``."""
    a = 1.0 - index
    m1 = (hi ** (a + 1) - lo ** (a + 1)) / (a + 1)            # ∫Φ N dΦ, up to the normalisation
    m2 = (hi ** (a + 2) - lo ** (a + 2)) / (a + 2)            # ∫Φ² N dΦ
    return total * m1 / m2


def test_elements_concentrate_on_cell_boundaries():
    on, off = _sun(network=True), _sun(network=False)
    grid = on["grid"]
    near = on["network_wall"] < 2 * LANE_WIDTH_KM
    area = near.mean()
    f_on, f_off = (float(b[near].sum() / b.sum()) for b in
                   (np.abs(grid.ifft(p["spectra"][0])) for p in (on, off)))
    # Noise of a flux fraction: each element lands in the zone or not, σ² ≤ ¼ ΣΦ²/(ΣΦ)².  Without the
    # network the elements move together in clusters of ~5 Mm (2 × the 2.5 Mm noise correlation): count those.
    sigma_on = math.sqrt(0.25 / _effective_count(20.0 * grid.Lx * grid.Ly * 1e10))
    sigma_off = math.sqrt(0.25 / (grid.Lx * grid.Ly / 5e3 ** 2))
    assert abs(f_off - area) < 5 * sigma_off                  # blind to the cells: the zone's area share
    assert f_on - area > 5 * math.hypot(sigma_on, sigma_off)  # concentrated on the boundaries
    assert on["meta"]["network"]["cells"] == round(grid.Lx * grid.Ly / 30e3 ** 2)


def test_same_seed_same_bits_and_other_streams_unchanged():
    a, b, c = _sun(network=True), _sun(network=True), _sun(network=False)
    assert np.array_equal(a["spectra"][0], b["spectra"][0])
    assert np.array_equal(a["network_wall"], b["network_wall"])
    assert not np.array_equal(a["spectra"][0], c["spectra"][0])
    # The granulation and the internetwork draw from their own streams: untouched by the switch.
    for key in ("blend", "internetwork"):
        assert np.array_equal(a[key][0], c[key][0])
    assert "network" not in c["meta"]["params"] and c["network_wall"] is None


@pytest.mark.parametrize(("kwargs", "match"), [
    (dict(network="yes"), "network must be True, False or 'auto'"),
    (dict(network=True, supergranule_size=200 * u.Mm), "supergranule_size .* must fit in the box"),
    (dict(network=True, supergranule_size=-3 * u.Mm), "supergranule_size"),
])
def test_bad_inputs(kwargs, match):
    with pytest.raises(ValueError, match=match):
        _sun(**kwargs)


def test_config_knob():
    cfg = SimulationConfig(seed=1, photosphere={"network": True})
    assert cfg.sun_arguments()["network"] is True
    assert "network" not in SimulationConfig(seed=1).sun_arguments()        # the default: builder's "auto"
    with pytest.raises(TypeError, match='network must be true, false or "auto"'):
        SimulationConfig(seed=1, photosphere={"network": "yes"})


def test_auto_lays_the_network_where_the_box_holds_two_cells_a_side():
    # 98 Mm box, 30 Mm cells: on; the same box with 50 Mm cells (< 2 a side) and a 49 Mm box: off.
    assert _sun(network="auto")["meta"]["network"]["cells"] == _sun(network=True)["meta"]["network"]["cells"]
    assert np.array_equal(_sun(network="auto")["spectra"][0], _sun(network=True)["spectra"][0])
    assert "network" not in _sun(network="auto", supergranule_size=50 * u.Mm)["meta"]
    small = model_sun((64, 64), PIXEL, seed=1, nz=16, spot=False)._plan       # the default: "auto"
    assert "network" not in small["meta"]
    off = model_sun((64, 64), PIXEL, seed=1, nz=16, spot=False, network=False)._plan
    assert np.array_equal(small["spectra"][0], off["spectra"][0])
