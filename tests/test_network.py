"""The supergranular network at disk scale: cells, flux budget, imbalance, reproducibility."""
import astropy.units as u
import numpy as np
import pytest
from sunpy.sun.constants import radius

from gongsynth.sun.surface_field.network import SupergranularNetwork

STEP = 0.5                          # the scene's grid is 0.25°; 0.5° keeps the tests fast
LON, LAT = np.linspace(-180, 180, 721), np.linspace(-90, 90, 361)
R_CM = radius.to_value(u.cm)


def _area():
    step = np.radians(STEP)
    return (R_CM * step) ** 2 * np.cos(np.radians(LAT))[:, None] * np.ones(LON.size)


def _band(field, lat_lo, lat_hi):
    rows = (LAT >= lat_lo) & (LAT <= lat_hi)
    area = _area()[rows][:, :-1]
    return field[rows][:, :-1], area


def test_quiet_network_budget_balance_and_reproducibility():
    net = SupergranularNetwork(seed=3, ephemeral_flux_density=0 * u.G)
    quiet = net.on_grid(LON, LAT, np.zeros((LAT.size, LON.size)))
    field, area = _band(quiet, -90, 90)
    unsigned = np.sum(np.abs(field) * area) / np.sum(area)
    # 5 G of unsigned flux laid (~5e4 concentrations: to ~1 %), less what concentrations of both
    # signs cancel in a shared grid cell (~10 % on this 0.5° grid).
    assert 4.0 < unsigned <= 5.05
    # Balanced: the net flux of ~5e4 concentrations of mean 5.8e18 Mx with coherent cell signs.
    assert abs(np.sum(field * area)) / np.sum(np.abs(field) * area) < 0.05
    again = net.on_grid(LON, LAT, np.zeros(quiet.shape))
    assert np.array_equal(quiet, again)
    # Ephemeral regions alone (a negligible network): 1.5 G of unsigned flux in exactly balanced
    # bipoles, less the footpoints 7 Mm apart that share or touch a grid cell (~20 % on this 6 Mm grid).
    er = SupergranularNetwork(seed=3, flux_density=1e-9 * u.G).on_grid(LON, LAT, np.zeros(quiet.shape))
    field, area = _band(er, -90, 90)
    assert 1.0 < np.sum(np.abs(field) * area) / np.sum(area) <= 1.55
    assert abs(np.sum(field * area)) / np.sum(np.abs(field) * area) < 0.01


def test_network_has_power_at_the_supergranular_scale_and_follows_the_large_scale_imbalance():
    unipolar = np.where(LAT[:, None] > 0, 3.0, -3.0) * np.ones(LON.size)
    field = SupergranularNetwork(seed=5).on_grid(LON, LAT, unipolar)
    for lo, hi, expected in ((5, 60, 3.0), (-60, -5, -3.0)):
        f, area = _band(field, lo, hi)
        # The mean flux density is the large-scale field's, to the Poisson scatter of ~2e4 concentrations.
        assert np.sum(f * area) / np.sum(area) == pytest.approx(expected, abs=0.3)
    # Each cell's own sign makes the network's signed pattern coherent over a cell: power at
    # 18-70 Mm that concentrations of independent signs (coherence 0) do not have.
    zero = np.zeros((LAT.size, LON.size))
    strip = (LAT > -20) & (LAT < 20)
    k = np.fft.rfftfreq(LON.size - 1, d=STEP)                       # cycles per degree
    cells = (k > 1 / 6) & (k < 1 / 1.5)                                # 18-70 Mm at the equator
    # Concentrations up to 3e19 Mx (not the default 1e20): many of similar flux, so that ~1e4 modes
    # average the power to ~2 %; the default's few large ones would set one seed's power alone.
    nets = [SupergranularNetwork(seed=5, coherence=c, flux_range=(1e18, 3e19) * u.Mx) for c in (1.0, 0.0)]
    power = [np.mean(np.abs(np.fft.rfft(net.on_grid(LON, LAT, zero)[strip][:, :-1], axis=1)[:, cells]) ** 2)
             for net in nets]
    # The same places and fluxes, only the signs differ, so a 10 % excess is five times that scatter
    # (seed 5 measures 14 %).
    assert power[0] > 1.10 * power[1]


def test_large_concentrations_spread_no_denser_than_plage():
    """A concentration that would make its grid cell denser than 300 G spreads, keeping its flux."""
    lon = lat = np.linspace(-10, 10, 201)                  # 0.1° cells of ~1.2 Mm: 5e19 Mx would be 3 kG
    kwargs = dict(seed=2, flux_density=1 * u.G, flux_range=(5e19, 1e20) * u.Mx,
                  ephemeral_flux_density=0 * u.G, chain_length=0 * u.Mm)   # the spread alone
    zero = np.zeros((lat.size, lon.size))
    point = SupergranularNetwork(cluster_flux_density=None, **kwargs).on_grid(lon, lat, zero)
    spread = SupergranularNetwork(**kwargs).on_grid(lon, lat, zero)
    area = (R_CM * np.radians(0.1)) ** 2 * np.cos(np.radians(lat))[:, None] * np.ones(lon.size)
    assert np.abs(point).max() > 2000
    # A Gaussian of 300 G peak averaged over a 1.2 Mm cell (σ ≥ 1.6 Mm): 250-300 G at its centre (the
    # discrete weights' normalisation may add a few tenths of a per cent).
    assert 200 < np.abs(spread).max() <= 305
    # Same places, same signs: the region's signed and unsigned flux are kept (no two clusters meet here).
    assert np.sum(spread * area) == pytest.approx(np.sum(point * area), rel=1e-9)
    assert np.sum(np.abs(spread) * area) == pytest.approx(np.sum(np.abs(point) * area), rel=1e-6)


def _blob_elongations(field, lon, lat):
    """Axis ratio of each connected blob's |flux|-weighted second moments on the local tangent plane."""
    from scipy import ndimage

    labels, n = ndimage.label(field != 0, structure=np.ones((3, 3), dtype=bool))
    y, x = np.meshgrid(lat, lon, indexing="ij")
    x = x * np.cos(np.radians(lat))[:, None]            # degrees of great circle
    ratios = []
    for k in range(1, n + 1):
        w = np.abs(field[labels == k])
        if w.size < 2:
            ratios.append(1.0)
            continue
        cov = np.cov(np.vstack([x[labels == k], y[labels == k]]), aweights=w)
        small, large = np.linalg.eigvalsh(cov)
        ratios.append(np.sqrt(large / max(small, 1e-12)))
    return np.array(ratios)


def test_chains_lay_each_concentration_along_its_wall():
    """chain_length spreads every concentration along its cell wall, keeping its flux; 0 is the old point."""
    from gongsynth.sun.surface_field.network import _wall_tangents

    lon = lat = np.linspace(-6, 6, 121)                    # 0.1° cells of ~1.2 Mm
    kwargs = dict(seed=4, flux_density=3 * u.G, flux_range=(5e19, 1e20) * u.Mx,
                  ephemeral_flux_density=0 * u.G, cluster_flux_density=None)
    zero = np.zeros((lat.size, lon.size))
    point = SupergranularNetwork(chain_length=0 * u.Mm, **kwargs).on_grid(lon, lat, zero)
    chain = SupergranularNetwork(chain_length=3 * u.Mm, **kwargs).on_grid(lon, lat, zero)
    area = np.cos(np.radians(lat))[:, None] * np.ones(lon.size)
    inner = (np.abs(lat)[:, None] < 4) & (np.abs(lon)[None, :] < 4)   # away from the region's edge
    assert np.count_nonzero(point[inner]) >= 3                       # a few isolated concentrations
    # The flux of each stays its own: the region's signed and unsigned totals are kept.
    assert np.sum(chain * area) == pytest.approx(np.sum(point * area), rel=1e-9)
    assert np.sum(np.abs(chain) * area) == pytest.approx(np.sum(np.abs(point) * area), rel=1e-6)
    # A point across and a Gaussian of 3 Mm (2.5 cells) along: long, thin blobs.
    assert np.all(_blob_elongations(point, lon, lat) == 1.0)
    assert np.median(_blob_elongations(chain, lon, lat)) > 3
    # The wall between two cells east and west of a point on the equator runs north-south.
    here = np.array([[1.0, 0.0, 0.0]])
    west, east = np.array([[1.0, -0.01, 0.0]]), np.array([[1.0, 0.01, 0.0]])
    np.testing.assert_allclose(np.abs(_wall_tangents(here, west, east)), [[0.0, 1.0]], atol=1e-12)
    with pytest.raises(ValueError, match="chain_length"):
        SupergranularNetwork(chain_length=-1 * u.Mm)


def test_bad_parameters():
    with pytest.raises(ValueError, match="flux_range"):
        SupergranularNetwork(flux_range=(1e19, 1e18) * u.Mx)
    with pytest.raises(ValueError, match="coherence"):
        SupergranularNetwork(coherence=2)
    with pytest.raises(ValueError, match="cluster_flux_density"):
        SupergranularNetwork(cluster_flux_density=0 * u.G)
    with pytest.raises(ValueError, match="large_scale"):
        SupergranularNetwork().on_grid(LON, LAT, np.zeros((3, 3)))


def test_the_network_is_laid_on_the_synthetic_and_quiet_suns_not_over_an_observed_map():
    from gongsynth.config import IN_MEMORY, SimulationConfig

    assert SimulationConfig(mode="full-disk").network_on
    assert SimulationConfig(mode="full-disk", surface_field="quiet").network_on
    for observed in ("mdi.fits", IN_MEMORY):          # an observed map holds the Sun's own network
        assert not SimulationConfig(mode="full-disk", surface_field=observed).network_on
        assert SimulationConfig(mode="full-disk", surface_field=observed, network=True).network_on
    assert not SimulationConfig(mode="full-disk", network=False).network_on
    config = SimulationConfig(mode="full-disk", seed=1)
    assert SimulationConfig.from_toml(config.to_toml()) == config
