r"""
The Sun's large-scale motions along the line of sight: differential rotation and the observer's motion.

A point of the photosphere at Stonyhurst longitude λ and latitude φ moves with
the Sun's sidereal rotation, ω(φ) about the solar axis; the observer (the
Earth's centre, plus a ground site's daily rotation) moves with its own
velocity.  The Doppler velocity GONG measures there is the relative velocity
projected on the line of sight, positive away from the observer (redshift):

.. math::

   v_\mathrm{LOS} = (\mathbf{v}_\mathrm{point} - \mathbf{v}_\mathrm{obs}) \cdot \hat{\mathbf{d}},
   \qquad \hat{\mathbf{d}} = \frac{\mathbf{r}_\mathrm{point} - \mathbf{r}_\mathrm{obs}}
                                  {|\mathbf{r}_\mathrm{point} - \mathbf{r}_\mathrm{obs}|},

evaluated in sunpy's heliocentric inertial frame, whose z axis is the solar
rotation axis, with the observer's velocity from the ephemeris (a centred
difference over ±60 s).  No synodic correction is needed: the Earth's orbital
motion enters through v_obs and the direction of each line of sight.

The rotation profile is Snodgrass & Ulrich (1990, ApJ 351, 309), the
photospheric Doppler rate ω = A + B sin²φ + C sin⁴φ with A = 14.713,
B = −2.396, C = −1.787 deg/day (sidereal).

The convective blueshift (`convective_blueshift`) is the measured shift of a
photospheric line's mean bisector from disk centre toward the limb: granular
upflows are brighter and cover more area than the downflows, so the spatially
averaged line is blueshifted by a few hundred m/s at disk centre, less toward
the limb where the flows are seen sideways.  No such curve has been published
for Ni I 676.8 nm at the accuracy of the laser-comb measurements; the default
is that of Fe I 630.25 nm (Löhner-Böttcher et al. 2018, A&A 611, A4, Table 2,
mean bisector), a photospheric Fe I line of similar depth and formation height.

`disk_velocity` adds the three for many points at once (plain vector algebra
in Stonyhurst axes, the observer's velocity from `observer_velocity`).  Not
included: supergranulation (a full-disk scene adds its network's flow,
`gongsynth.sun.surface_field.supergranulation`), oscillations (the built-in
Sun's own flows stand for the small scales), the gravitational redshift (a
constant 636 m/s that GONG's zero point removes).
"""
import astropy.units as u
import numpy as np
from astropy.coordinates import SkyCoord
from astropy.time import Time
from sunpy.coordinates import frames, get_earth
from sunpy.sun import constants

__all__ = ["SNODGRASS_ULRICH_1990", "CONVECTIVE_BLUESHIFT_FE6302", "rotation_rate", "observer_velocity",
           "line_of_sight_velocity", "convective_blueshift", "disk_velocity"]

#: Sidereal photospheric Doppler rotation rate coefficients (A, B, C) of
#: ω = A + B sin²φ + C sin⁴φ, Snodgrass & Ulrich (1990).
SNODGRASS_ULRICH_1990 = (14.713, -2.396, -1.787) * u.deg / u.day

#: Convective blueshift of Fe I 630.25 nm against μ: Löhner-Böttcher et al. (2018, A&A 611, A4),
#: Table 2, mean bisector (absolute laser-comb wavelengths, quiet Sun), in m/s.
CONVECTIVE_BLUESHIFT_FE6302 = ((1.0, 0.95, 0.9, 0.85, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3),
                               (-295, -249, -262, -281, -260, -286, -274, -221, -170, -94) * u.m / u.s)

_STEP = 60 * u.s  # half-step of the centred difference for the observer's velocity


def rotation_rate(latitude, profile=SNODGRASS_ULRICH_1990):
    """
    Sidereal angular velocity of the photosphere at a heliographic latitude.

    Parameters
    ----------
    latitude : `~astropy.units.Quantity`
        Heliographic latitude(s).
    profile : `~astropy.units.Quantity`
        (A, B, C) of ω = A + B sin²φ + C sin⁴φ, angle per time.

    Returns
    -------
    `~astropy.units.Quantity`
        In deg / day.

    Examples
    --------
    >>> import astropy.units as u
    >>> rotation_rate([0, 60] * u.deg).round(3)
    <Quantity [14.713, 11.911] deg / d>
    """
    s2 = np.sin(u.Quantity(latitude, u.deg)) ** 2
    a, b, c = u.Quantity(profile).to(u.deg / u.day)
    return a + b * s2 + c * s2**2


def observer_velocity(obstime, site=None):
    """
    Position and velocity of the observer in the heliocentric inertial frame.

    Parameters
    ----------
    obstime : `~astropy.time.Time` or str
    site : `~astropy.coordinates.EarthLocation`, optional
        A ground site; default the Earth's centre.

    Returns
    -------
    position : `~astropy.units.Quantity`
        (3,) in km, heliocentric inertial (z along the solar rotation axis).
    velocity : `~astropy.units.Quantity`
        (3,) in m / s, the same axes, relative to the Sun's centre.
    """
    t = Time(obstime)

    def where(time):
        body = get_earth(time) if site is None else SkyCoord(site.get_gcrs(time))
        # Relative to the Sun's centre at the same instant (the Sun moves too, ~12 m/s about
        # the barycentre); the frame's axes are inertial, so both ends share them.
        return body.transform_to(frames.HeliocentricInertial(obstime=time)).cartesian.xyz.to(u.km)

    velocity = ((where(t + _STEP) - where(t - _STEP)) / (2 * _STEP)).to(u.m / u.s)
    return where(t), velocity


def line_of_sight_velocity(longitude, latitude, obstime, *, site=None, profile=SNODGRASS_ULRICH_1990,
                           rotation=True, observer=True):
    """
    Doppler velocity of points of the photosphere from rotation and the observer's motion.

    Parameters
    ----------
    longitude, latitude : `~astropy.units.Quantity`
        Heliographic Stonyhurst coordinates of the points (any matching shape;
        NaN gives NaN).
    obstime : `~astropy.time.Time` or str
    site : `~astropy.coordinates.EarthLocation`, optional
        A ground site (GONG's: Big Bear, Learmonth, ...); default the Earth's centre.
    profile : `~astropy.units.Quantity`
        Rotation profile, see `rotation_rate`.
    rotation, observer : bool
        Include the solar rotation and the observer's motion (both by default).

    Returns
    -------
    `~astropy.units.Quantity`
        In m / s, positive away from the observer.

    Examples
    --------
    >>> import astropy.units as u
    >>> v = line_of_sight_velocity([-90, 90] * u.deg, [0, 0] * u.deg, "2009-09-05", observer=False)
    >>> [round(float(x)) for x in v.to_value(u.m / u.s)]   # east limb approaches, west recedes
    [-2051, 2051]
    """
    t = Time(obstime)
    lon = u.Quantity(longitude, u.deg)
    lat = u.Quantity(latitude, u.deg)
    lon, lat = np.broadcast_arrays(lon, lat, subok=True)
    valid = np.isfinite(lon) & np.isfinite(lat)
    out = np.full(lon.shape, np.nan) * u.m / u.s
    if not valid.any():
        return out
    points = SkyCoord(lon[valid], lat[valid], constants.radius, frame=frames.HeliographicStonyhurst,
                      obstime=t).transform_to(frames.HeliocentricInertial(obstime=t))
    r = points.cartesian.xyz.to(u.km)  # (3, n)
    obs_position, obs_velocity = observer_velocity(t, site)
    d = r - obs_position[:, None]
    d_hat = (d / np.sqrt((d**2).sum(axis=0))).value
    v_point = np.zeros(r.shape) * u.m / u.s
    if rotation:
        omega = rotation_rate(lat[valid], profile).to(u.rad / u.s).value / u.s
        # ω ẑ × r = ω (−y, x, 0)
        v_point = (omega * u.Quantity([-r[1], r[0], np.zeros_like(r[0])])).to(u.m / u.s)
    relative = v_point - (obs_velocity[:, None] if observer else 0 * obs_velocity[:, None])
    out[valid] = (relative * d_hat).sum(axis=0)
    return out


def convective_blueshift(mu, table=CONVECTIVE_BLUESHIFT_FE6302):
    """
    The convective blueshift of the spatially averaged line at μ.

    Parameters
    ----------
    mu : float or array_like
        Cosine of the heliocentric angle.
    table : (sequence of float, `~astropy.units.Quantity`)
        μ values (decreasing or increasing) and the shift at each (default
        `CONVECTIVE_BLUESHIFT_FE6302`); interpolated linearly in μ and held
        at its end values beyond them (no measurement below μ = 0.3).

    Returns
    -------
    `~astropy.units.Quantity`
        In m/s (negative: toward the observer).

    Examples
    --------
    >>> convective_blueshift([1.0, 0.3, 0.1]).round()
    <Quantity [-295.,  -94.,  -94.] m / s>
    """
    nodes = np.asarray(table[0], dtype=float)
    values = u.Quantity(table[1]).to_value(u.m / u.s)
    order = np.argsort(nodes)
    return np.interp(np.asarray(mu, dtype=float), nodes[order], values[order]) * u.m / u.s


def disk_velocity(longitude, latitude, mu, obstime, *, site=None, profile=SNODGRASS_ULRICH_1990,
                  rotation=True, observer=True, blueshift=CONVECTIVE_BLUESHIFT_FE6302):
    """
    Large-scale Doppler velocity of many points: rotation, observer's motion, convective blueshift.

    The same rotation and observer terms as `line_of_sight_velocity`, written
    as vector algebra in Stonyhurst axes (which share the solar rotation axis
    with the inertial frame) so that millions of points cost a few array
    operations; lines of sight from the Earth's centre, the observer's
    velocity from the site when one is given.

    Parameters
    ----------
    longitude, latitude : `~astropy.units.Quantity`
        Stonyhurst coordinates of the points (NaN gives NaN).
    mu : array_like
        μ of each point (for the blueshift).
    obstime : `~astropy.time.Time` or str
    site : `~astropy.coordinates.EarthLocation`, optional
        A ground site; default the Earth's centre.
    profile : `~astropy.units.Quantity`
        Rotation profile, see `rotation_rate`.
    rotation, observer : bool
        Include the solar rotation and the observer's motion.
    blueshift : tuple or None
        Convective-blueshift table (`convective_blueshift`), or None for none.

    Returns
    -------
    `~astropy.units.Quantity`
        In m/s, positive away from the observer.

    Examples
    --------
    >>> import astropy.units as u
    >>> v = disk_velocity([-90, 90] * u.deg, [0, 0] * u.deg, [0, 0], "2009-09-05", observer=False,
    ...                   blueshift=None)
    >>> [round(float(x)) for x in v.to_value(u.m / u.s)]
    [-2051, 2051]
    """
    from sunpy.coordinates import sun
    t = Time(obstime)
    lon = np.radians(u.Quantity(longitude, u.deg).value)
    lat = np.radians(u.Quantity(latitude, u.deg).value)
    radius = constants.radius.to_value(u.km)
    cos_lat = np.cos(lat)
    r = (radius * cos_lat * np.cos(lon), radius * cos_lat * np.sin(lon), radius * np.sin(lat))
    # Stonyhurst axes: x toward the Earth's projection on the solar equator.
    earth = get_earth(t)
    distance = earth.radius.to_value(u.km)
    b0 = sun.B0(t).to_value(u.rad)
    obs = np.array([distance * np.cos(b0), 0.0, distance * np.sin(b0)])
    d = [r[k] - obs[k] for k in range(3)]
    norm = np.sqrt(d[0] ** 2 + d[1] ** 2 + d[2] ** 2)
    out = np.zeros(np.broadcast(lon, lat).shape)
    if rotation:
        omega = rotation_rate(u.Quantity(latitude, u.deg), profile).to_value(u.rad / u.s)
        # ω ẑ × r = ω (−y, x, 0), in m/s; projected on the line of sight away from the observer.
        out = out + omega * 1e3 * (-r[1] * d[0] + r[0] * d[1]) / norm
    if observer:
        earth_hci = earth.transform_to(frames.HeliocentricInertial(obstime=t)).cartesian.xyz.to_value(u.km)
        turn = -np.arctan2(earth_hci[1], earth_hci[0])
        _, velocity = observer_velocity(t, site)
        vx, vy, vz = velocity.to_value(u.m / u.s)
        v_obs = (vx * np.cos(turn) - vy * np.sin(turn), vx * np.sin(turn) + vy * np.cos(turn), vz)
        out = out - (v_obs[0] * d[0] + v_obs[1] * d[1] + v_obs[2] * d[2]) / norm
    if blueshift is not None:
        out = out + convective_blueshift(mu, blueshift).to_value(u.m / u.s)
    return out * u.m / u.s
