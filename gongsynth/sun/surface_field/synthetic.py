r"""
A seeded synthetic Sun: active regions of the cycle of the date, their decay, polar fields and network.

`synthetic_surface_field` builds B_r on the surface-field grid from four parts
(numbers and their sources; "assumed" marks a choice made here):

1. **Active regions** that emerged during the ``history`` (365 days) before
   the date, as a Poisson process whose rate follows the sunspot number of
   each overlapping cycle (`gongsynth.sun.surface_field.cycle`):

   * count: the number of sunspot groups on the visible hemisphere is
     R_v2 / 20.1 (the group number's 12.08 normalisation, Hoyt & Schatten
     1998, Sol. Phys. 179, 189, with v1 = 0.6 v2), so the whole Sun holds
     twice that many spotted regions; the emergence rate is that count
     divided by the mean spot lifetime below;
   * total unsigned flux Φ: a power law dN/dΦ ∝ Φ^-1.85 (Parnell et al.
     2009, ApJ 698, 75) between 1e21 and 2e23 Mx;
   * spots: a region's peak spot area is A = Φ / (9.1e19 Mx/MSH) (spots of
     mean field 1.5 kG holding half the flux: assumed, after Solanki 2003,
     A&ARv 11, 153 and Yeo et al. 2021, A&A 654, A28), shrinking linearly at
     10 MSH/day (the Gnevyshev–Waldmeier rule; Petrovay & van
     Driel-Gesztelyi 1997, Sol. Phys. 176, 249), one Gaussian spot per
     polarity of the spot's area (peak 1.5 kG);
   * plage: the rest of each polarity's flux, a Gaussian of peak 200 G at
     emergence (plage flux densities 100–300 G; assumed), spreading as
     σ² = σ0² + 2ηt with η = 250 km²/s (Baumann et al. 2004, A&A 426, 1075),
     so that the two polarities overlap and cancel into network over months;
     the spots' flux joins the plage as they decay;
   * place: latitude from Spörer's law of the region's cycle, longitude
     uniform, bipole separation d = 4.5° (Φ / 1e22 Mx)^0.3 (30–150 Mm;
     assumed, after Wang & Sheeley 1989), Hale's polarity, Joy's tilt with
     scatter; then carried by the magnetic differential rotation
     (`gongsynth.sun.surface_field.maps.rotation_drift`) and the meridional
     flow u = 11 m/s sin 2φ (Hathaway & Rightmire 2010, Science 327, 1350),
     integrated exactly: tan φ(t) = tan φ0 exp(2 u0 t / R☉).
2. **Polar fields**: `gongsynth.sun.surface_field.cycle.polar_field`
   (10 G at the pole at full strength, sin⁸ latitude).
3. **Quiet large-scale field**: a stationary Gaussian field of standard
   deviation 3 G — the robust width of the ADAPT-GONG map of 2017-07-20
   within 30° of the equator (2.9 G, ``shared/data/real/PROVENANCE.md``) —
   with that band's measured correlation, close to exp(−r / 6.5°): unipolar
   patches of ~80 Mm (`gongsynth.sun.surface_field.quiet`; the band's width
   stays 2.8 G averaged over 5°, so it is not white from cell to cell).  The
   network's imbalance follows it (`gongsynth.sun.surface_field.network`).
   The internetwork's mixed polarities cancel at these scales and add
   nothing here.

The cycle phase follows the date unless ``cycle_phase`` is given (a phase in
the date's own cycle: signs stay the date's).  Everything random comes from
``seed`` through named streams (`gongsynth.seeding.stage_generator`): the
same seed gives the same bits, and switching the active regions off leaves the
network unchanged.  Not modelled: active longitudes and nests, the
asymmetry between leading and trailing spots, ephemeral regions, the flux
older than ``history`` except through the polar fields.
"""
import math

import astropy.units as u
import numpy as np
from sunpy.sun import constants

from gongsynth.geometry import as_obstime
from gongsynth.seeding import root_seed, stage_generator
from gongsynth.sun.surface_field.cycle import (
    JOY_AMPLITUDE,
    JOY_SCATTER,
    ZONE_WIDTH,
    SolarCycle,
    active_latitude,
    cycle_of,
    leading_polarity,
    polar_field,
)
from gongsynth.sun.surface_field.maps import (
    DEFAULT_RESOLUTION,
    ROTATION_MODEL,
    cell_area,
    field_grid,
    grid_shape,
    make_surface_field,
    rotation_drift,
)
from gongsynth.sun.surface_field.quiet import quiet_field
from gongsynth.validation import check_quantity

__all__ = ["REGION_FLUX_RANGE", "FLUX_INDEX", "synthetic_surface_field", "active_regions"]

#: Range of active-region total unsigned flux (Mx).
REGION_FLUX_RANGE = (1e21, 2e23)
#: Index of the flux distribution dN/dΦ ∝ Φ^-FLUX_INDEX (Parnell et al. 2009).
FLUX_INDEX = 1.85

_MX_PER_MSH = 9.1e19          # total region flux per MSH of peak spot area (assumed, see above)
_DECAY_MSH_PER_DAY = 10.0     # Gnevyshev-Waldmeier
_SPOT_FIELD = 1500.0          # G, mean spot field
_PLAGE_FIELD = 200.0          # G, peak plage flux density at emergence (assumed)
_DIFFUSIVITY = 250.0          # km^2/s (Baumann et al. 2004)
_MERIDIONAL = 11.0            # m/s (Hathaway & Rightmire 2010)
_DECAY_INDEX = 0.70           # decay rate ∝ peak flux^0.70 (Plotnikov et al. 2023)
_DECAY_TIME = 33.0            # days: e-folding of a 1e22 Mx region (3e20 Mx/day; assumed)
_GROUPS_PER_SSN = 1 / 20.1    # visible groups per unit v2 sunspot number
_MSH_CM2 = 1e-6 * 2 * math.pi * constants.radius.to_value(u.cm) ** 2
_CM_PER_DEG = constants.radius.to_value(u.cm) * math.pi / 180
_MAX_LATITUDE = 45.0          # emergences are clipped here (deg)


def _spot_lifetime(flux):
    """Days until the spots of a region of total flux ``flux`` (Mx) are gone (at least 1 day)."""
    return np.maximum(flux / _MX_PER_MSH / _DECAY_MSH_PER_DAY, 1.0)


def _mean_spot_lifetime():
    """Mean spot lifetime over the flux distribution (days), by quadrature of the power law."""
    lo, hi = REGION_FLUX_RANGE
    phi = np.geomspace(lo, hi, 4001)
    density = phi ** (1 - FLUX_INDEX)  # dN/dlnΦ
    log_phi = np.log(phi)
    return float(np.trapezoid(_spot_lifetime(phi) * density, log_phi) / np.trapezoid(density, log_phi))


def _draw_flux(rng, n):
    lo, hi = REGION_FLUX_RANGE
    k = 1 - FLUX_INDEX
    q = rng.random(n)
    return (lo**k + q * (hi**k - lo**k)) ** (1 / k)


def active_regions(obstime, *, seed, cycle_phase=None, history=365 * u.day):
    """
    The active regions of the synthetic Sun: when, where and how they emerged.

    Parameters
    ----------
    obstime : `~astropy.time.Time` or str
    seed : int, `numpy.random.SeedSequence` or `numpy.random.Generator`
    cycle_phase : float, optional
        Phase in the cycle of ``obstime`` to use instead of the date's.
    history : `~astropy.units.Quantity`
        How far back emergences are drawn.

    Returns
    -------
    dict of `numpy.ndarray`
        ``age`` (days), ``cycle``, ``hemisphere`` (±1), ``latitude`` and
        ``longitude`` (Carrington, deg, at emergence), ``flux`` (Mx, total
        unsigned), ``tilt`` (deg, toward the equator), ``leading`` (sign of
        the leading polarity).

    Examples
    --------
    >>> import astropy.units as u
    >>> r = active_regions("2014-04-01", seed=1)
    >>> len(r["age"]) > 300, set(r["leading"][r["hemisphere"] > 0].tolist())
    (True, {-1})
    """
    check_quantity(history, u.day, "history")
    time = as_obstime(obstime)
    n, phase = cycle_of(time)
    here = SolarCycle(n)
    year = here.start + (phase if cycle_phase is None else float(cycle_phase)) * here.length
    rng = stage_generator(seed, "surface-field", 0)
    days = int(math.ceil(history.to_value(u.day)))
    ages = np.arange(days) + 0.5
    cycles = [SolarCycle(m) for m in (n - 1, n, n + 1)]
    # v2 sunspot number per cycle on each day -> expected emergences per day on the whole Sun.
    ssn = np.stack([c.sunspot_number(year - ages / 365.25) for c in cycles], axis=1)
    rate = 2 * _GROUPS_PER_SSN * ssn / _mean_spot_lifetime()
    counts = rng.poisson(rate)
    day_index, cycle_index = np.nonzero(counts)
    repeat = counts[day_index, cycle_index]
    day_index = np.repeat(day_index, repeat)
    cycle_index = np.repeat(cycle_index, repeat)
    total = day_index.size
    age = day_index + rng.random(total)
    cycle = np.array([c.number for c in cycles])[cycle_index]
    start = np.array([c.start for c in cycles])[cycle_index]
    hemisphere = np.where(rng.random(total) < 0.5, 1, -1)
    centre = active_latitude(year - age / 365.25 - start).to_value(u.deg)
    latitude = np.clip(np.abs(centre + ZONE_WIDTH * rng.standard_normal(total)), 0.0, _MAX_LATITUDE)
    tilt = JOY_AMPLITUDE * np.sin(np.radians(latitude)) + JOY_SCATTER * rng.standard_normal(total)
    return {"age": age, "cycle": cycle, "hemisphere": hemisphere, "latitude": hemisphere * latitude,
            "longitude": 360.0 * rng.random(total), "flux": _draw_flux(rng, total), "tilt": tilt,
            "leading": leading_polarity(cycle, hemisphere)}


def _gaussian_into(out, lon_grid, lat_grid, lon0, lat0, sigma, flux_per_cell):
    """Add a Gaussian of width ``sigma`` (deg on the sphere) holding ``flux_per_cell`` × cells."""
    ny, nx = out.shape
    reach = 3.5 * sigma
    rows = np.nonzero(np.abs(lat_grid - lat0) <= reach)[0]
    if rows.size == 0:
        return
    coslat = max(math.cos(math.radians(lat0)), 0.05)
    half = min(int(math.ceil(reach / coslat / (360.0 / nx))) + 1, nx // 2)
    centre = int(math.floor(lon0 % 360.0 / (360.0 / nx)))
    cols = np.arange(centre - half, centre + half + 1) % nx
    dlon = (lon_grid[cols] - lon0 + 180.0) % 360.0 - 180.0
    wx = np.exp(-0.5 * (dlon * coslat / sigma) ** 2)
    wy = np.exp(-0.5 * ((lat_grid[rows] - lat0) / sigma) ** 2)
    weight = np.outer(wy, wx)
    total = weight.sum()
    if total > 0:
        block = out[rows[0]:rows[-1] + 1]
        block[:, cols] += weight * (flux_per_cell / total)


def _region_fields(regions, shape, lon_grid, lat_grid, model):
    ny, nx = shape
    out = np.zeros(shape)
    area = cell_area(shape).to_value(u.cm**2)
    age = regions["age"]
    lifetime = _DECAY_TIME * (regions["flux"] / 1e22) ** (1 - _DECAY_INDEX)
    flux = regions["flux"] / 2 * np.exp(-age / lifetime)  # per polarity, now
    # Bipole geometry at emergence: leading polarity west (+longitude) and equatorward.
    separation = np.clip(4.5 * (regions["flux"] / 1e22) ** 0.3, 2.0, 15.0)
    tilt = np.radians(regions["tilt"])
    half_ew = 0.5 * separation * np.cos(tilt)
    half_ns = 0.5 * separation * np.sin(tilt) * regions["hemisphere"]
    spot_area = np.maximum(regions["flux"] / _MX_PER_MSH - _DECAY_MSH_PER_DAY * age, 0.0) / 2
    spot_flux = np.minimum(_SPOT_FIELD * spot_area * _MSH_CM2, flux)
    sigma_spot = np.sqrt(spot_area * _MSH_CM2 / (2 * math.pi)) / _CM_PER_DEG
    plage0 = flux - np.minimum(_SPOT_FIELD * (regions["flux"] / _MX_PER_MSH / 2) * _MSH_CM2, flux)
    sigma0 = np.sqrt(np.maximum(plage0, 1e18) / (2 * math.pi * _PLAGE_FIELD)) / _CM_PER_DEG
    spread = 2 * _DIFFUSIVITY * 1e10 * age * 86400.0 / _CM_PER_DEG**2
    sigma_plage = np.sqrt(sigma0**2 + spread)
    growth = np.exp(2 * _MERIDIONAL * 1e2 * age * 86400.0 / constants.radius.to_value(u.cm))
    min_sigma = 0.5 * 360.0 / nx
    for end, sign in ((1.0, 1.0), (-1.0, -1.0)):  # leading, trailing
        lat0 = regions["latitude"] - end * half_ns
        lon0 = regions["longitude"] + end * half_ew / np.maximum(np.cos(np.radians(lat0)), 0.05)
        lat = np.degrees(np.arctan(np.tan(np.radians(lat0)) * growth))
        lon = lon0 + rotation_drift(lat * u.deg, age * u.day, model).to_value(u.deg)
        polarity = sign * regions["leading"]
        for k in range(age.size):
            if spot_flux[k] > 0:
                _gaussian_into(out, lon_grid, lat_grid, lon[k], lat[k], max(sigma_spot[k], min_sigma),
                               polarity[k] * spot_flux[k] / area)
            _gaussian_into(out, lon_grid, lat_grid, lon[k], lat[k], max(sigma_plage[k], min_sigma),
                           polarity[k] * (flux[k] - spot_flux[k]) / area)
    return out


def synthetic_surface_field(obstime=None, *, seed, cycle_phase=None, resolution=DEFAULT_RESOLUTION,
                            active_regions_on=True, polar_strength=10 * u.G, network_rms=3 * u.G,
                            history=365 * u.day):
    """
    A seeded synthetic radial field of the whole Sun at the cycle phase of ``obstime``.

    Parameters
    ----------
    obstime : `~astropy.time.Time` or str, optional
        The date (default `gongsynth.geometry.DEFAULT_OBSTIME`); sets the
        cycle, its phase, the signs and the map's date.
    seed : int, `numpy.random.SeedSequence` or `numpy.random.Generator`
        Root seed (required: the same seed gives the same bits).
    cycle_phase : float, optional
        Phase (0 = minimum, ~0.4 = maximum) in the date's cycle instead of the date's own.
    resolution : `~astropy.units.Quantity`
        Longitude step of the grid.
    active_regions_on : bool
        False: the quiet Sun only (network and polar fields), e.g. to fill a
        real map's unobserved cells.
    polar_strength : `~astropy.units.Quantity`
        Polar field at the pole at full strength.
    network_rms : `~astropy.units.Quantity`
        Standard deviation of the quiet large-scale field
        (`gongsynth.sun.surface_field.quiet`).
    history : `~astropy.units.Quantity`
        How far back active regions are drawn.

    Returns
    -------
    `sunpy.map.GenericMap`
        The surface field (`gongsynth.sun.surface_field.maps`), with the cycle,
        phase, sunspot number and region count in its header.

    Examples
    --------
    >>> field = synthetic_surface_field("2014-04-01", seed=3)
    >>> field.meta["cycle"], field.data.shape, field.meta["nregions"] > 300
    (24, (360, 720), True)
    """
    for value, unit, name in ((polar_strength, u.G, "polar_strength"), (network_rms, u.G, "network_rms")):
        check_quantity(value, unit, name)
    if cycle_phase is not None and not 0 <= float(cycle_phase) < 1:
        raise ValueError(f"cycle_phase must lie in [0, 1), got {cycle_phase!r}")
    time = as_obstime(obstime)
    shape = grid_shape(resolution)
    lon_grid, lat_grid = field_grid(shape)
    n, phase = cycle_of(time)
    if cycle_phase is not None:
        phase = float(cycle_phase)
    cycle = SolarCycle(n)
    year = cycle.start + phase * cycle.length
    ssn = sum(SolarCycle(m).sunspot_number(year) for m in (n - 1, n, n + 1))
    data = np.zeros(shape)
    n_regions = 0
    if active_regions_on:
        regions = active_regions(time, seed=seed, cycle_phase=phase, history=history)
        n_regions = regions["age"].size
        data += _region_fields(regions, shape, lon_grid, lat_grid, ROTATION_MODEL)
    data += polar_field(time, lat_grid * u.deg, polar_strength, cycle_phase=phase).to_value(u.G)[:, None]
    data += quiet_field(stage_generator(seed, "surface-field", 1), lat_grid, shape, network_rms.to_value(u.G))
    seed_int = root_seed(seed)
    history_lines = [
        f"synthetic Sun (seed {seed_int}): cycle {n} at phase {phase:.3f}, sunspot number {ssn:.1f} (v2)",
        f"{n_regions} active regions emerged in the last {history:g}; polar field {polar_strength:g} at "
        f"full strength; quiet field {network_rms:g} rms, ADAPT's correlation",
    ]
    extra = {"cycle": int(n), "cycphase": round(float(phase), 6), "ssn": round(float(ssn), 3),
             "nregions": int(n_regions), "seed": str(seed_int), "polarb": float(polar_strength.to_value(u.G)),
             "netrms": float(network_rms.to_value(u.G))}
    return make_surface_field(data, time, source="gongsynth synthetic Sun", history=history_lines,
                              extra=extra)
