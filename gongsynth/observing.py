"""
Where and when GONG observes: the six sites, the ephemeris, and the geometry in a real GONG header.

* `GONG_SITES`: the network's sites by their header code (``SITE``), with
  geodetic coordinates; `site_location` gives an `~astropy.coordinates.EarthLocation`.
* `ephemeris`: P angle, B0, L0, distance and apparent radius of the Sun from
  sunpy's ephemeris (`sunpy.coordinates.sun`), the distance and apparent
  radius seen from a site if one is given.  GONG's own headers carry the same
  quantities (PA, B0, L0, DISTANCE, RADIUS/SEMIDIAM): the tests compare them.
* `gong_view`: what a real GONG full-disk file says about its observation —
  date, site, the disk's centre and radius on the detector and the plate
  scale they imply (apparent radius / fitted limb radius in pixels).  This is
  what ``like = "FILE"`` (``--like FILE``) copies into a run: "what GONG saw
  at Big Bear on 2009-09-05 18:54".

Plate scale and disk size of real GONG data: the Big Bear file of 2009-09-05
(``bbbqa090905t1854``) has a limb of 371.5–371.9 px for an apparent radius of
952.1″, 2.561″/px; sunpy's Learmonth header of 2025-01-09, 385.2–385.3 px for
975.9″, 2.533″/px.  `gongsynth.GONGInstrument` assumes the paper's 2.5″/px
(disk radius 381 px on 2009-09-05, 2.5 % larger than Big Bear's).

Site coordinates: Big Bear and Learmonth from the LAT/LON of their real
headers; the others from the published station coordinates to about 0.01°
(heights to about 100 m, which change the site's rotation speed by < 0.01 %).
A header's own LAT/LON always wins over the table.
"""
import math
from collections import namedtuple
from pathlib import Path

import astropy.units as u
from astropy.coordinates import EarthLocation, SkyCoord
from astropy.io import fits
from astropy.time import Time

__all__ = ["GONG_SITES", "Site", "Ephemeris", "GONGView", "check_site", "site_location", "ephemeris",
           "gong_view", "like_gong", "AS_OBSERVED_EFFECTS", "as_observed"]

#: The opt-in effects of the real instrument that a run "like" a real GONG full-disk file switches on
#: unless told otherwise (with the file's count level, ``like_counts``): together they bring the
#: simulated noise within 0-15 % of the real map's; the effects alone, at the paper's five times
#: brighter count level, take the noise further from it (the noise guide's Big Bear table).
AS_OBSERVED_EFFECTS = ("frame_seeing", "minute_average", "image_rotation")

#: A GONG station: name, geodetic latitude and east longitude (deg), height (m).
Site = namedtuple("Site", ["name", "latitude", "longitude", "height"])

#: The GONG network by header code (``SITE``).
GONG_SITES = {
    "BB": Site("Big Bear, California", 34.2604, -116.9214, 2060.0),
    "ML": Site("Mauna Loa, Hawaii", 19.5362, -155.5763, 3440.0),
    "LE": Site("Learmonth, Western Australia", -22.2184, 114.1029, 10.0),
    "UD": Site("Udaipur, India", 24.6049, 73.6724, 660.0),
    "TD": Site("El Teide, Tenerife", 28.3010, -16.5114, 2390.0),
    "CT": Site("Cerro Tololo, Chile", -30.1675, -70.8065, 2200.0),
}

#: The Sun seen at a time (angles in deg, distance in AU, apparent radius in arcsec).
Ephemeris = namedtuple("Ephemeris", ["p_angle", "b0", "l0", "distance", "angular_radius"])

#: The geometry of a real GONG full-disk observation (see `gong_view`).
GONGView = namedtuple("GONGView", ["obstime", "site", "location", "plate_scale", "disk_centre",
                                   "disk_radius", "p_angle", "b0", "distance", "angular_radius", "path",
                                   "pointing"])


def check_site(site):
    """
    A GONG site code, checked and upper-cased (None stays None: the Earth's centre).

    Parameters
    ----------
    site : str or None

    Returns
    -------
    str or None

    Examples
    --------
    >>> check_site("bb"), check_site(None)
    ('BB', None)
    """
    if site is None:
        return None
    if not isinstance(site, str) or site.strip().upper() not in GONG_SITES:
        raise ValueError(f"site must be one of the GONG sites {sorted(GONG_SITES)} or None, got {site!r}")
    return site.strip().upper()


def site_location(site):
    """
    The `~astropy.coordinates.EarthLocation` of a GONG site.

    Parameters
    ----------
    site : str or `~astropy.coordinates.EarthLocation` or None
        A code of `GONG_SITES` (case-insensitive), a location (returned as
        it is), or None (None: the Earth's centre).

    Returns
    -------
    `~astropy.coordinates.EarthLocation` or None

    Examples
    --------
    >>> round(float(site_location("bb").lat.deg), 2)
    34.26
    """
    if site is None or isinstance(site, EarthLocation):
        return site
    s = GONG_SITES[check_site(site)]
    return EarthLocation.from_geodetic(s.longitude * u.deg, s.latitude * u.deg, s.height * u.m)


def ephemeris(obstime, site=None):
    """
    P angle, B0, L0, distance and apparent radius of the Sun at ``obstime``.

    Parameters
    ----------
    obstime : `~astropy.time.Time` or str
    site : str or `~astropy.coordinates.EarthLocation`, optional
        Distance and apparent radius from this site (default: the Earth's
        centre); the angles are geocentric (a site moves B0 by < 0.001°).

    Returns
    -------
    `Ephemeris`
        Angles in deg, distance in AU, apparent radius in arcsec (sunpy's
        photospheric radius, 695 700 km), as Quantities.

    Examples
    --------
    >>> e = ephemeris("2009-09-05T18:54:16")
    >>> round(float(e.p_angle.value), 3), round(float(e.b0.value), 3)
    (22.232, 7.245)
    """
    from sunpy.coordinates import frames, sun
    from sunpy.sun import constants

    time = Time(obstime)
    location = site_location(site)
    if location is None:
        distance = sun.earth_distance(time)
    else:
        observer = SkyCoord(location.get_gcrs(time)).transform_to(
            frames.HeliographicStonyhurst(obstime=time))
        distance = observer.radius
    radius = (math.asin((constants.radius / distance).to_value(u.one)) * u.rad).to(u.arcsec)
    return Ephemeris(sun.P(time).to(u.deg), sun.B0(time).to(u.deg), sun.L0(time).to(u.deg),
                     distance.to(u.AU), radius)


def _header(source):
    if isinstance(source, fits.Header):
        return source, None
    path = Path(source)
    if path.suffix == ".header":  # a FITS header saved as text (sunpy's test headers)
        return fits.Header.fromtextfile(path), str(path)
    with fits.open(path) as hdul:
        for hdu in hdul:
            if hdu.header.get("NAXIS", 0) >= 2:
                return hdu.header.copy(), str(path)
    raise ValueError(f"{path} holds no image header")


def gong_view(source):
    """
    Date, site and disk geometry of a real GONG full-disk observation.

    Parameters
    ----------
    source : path-like or `astropy.io.fits.Header`
        A GONG full-disk FITS file (any generation: old site files with
        RADIUS, current ones with SEMIDIAM) or its header.

    Returns
    -------
    `GONGView`
        ``obstime`` (`~astropy.time.Time`), ``site`` (code), ``location``
        (`~astropy.coordinates.EarthLocation`, from the header's LAT/LON and
        the site table's height), ``plate_scale`` (arcsec, the apparent
        radius over the mean fitted limb radius), ``disk_centre`` ((x, y)
        0-based pixels), ``disk_radius`` (pix), ``p_angle``, ``b0`` (deg, or
        None where the header has no B0), ``distance`` (AU),
        ``angular_radius`` (arcsec), ``path``, ``pointing`` (helioprojective
        (Tx, Ty) of the image's centre: the disk centre's offset from it
        times the plate scale).

    Raises
    ------
    ValueError
        If the header is not a GONG full-disk header (keywords named).

    Examples
    --------
    >>> from gongsynth.observing import gong_view
    >>> import sunpy.data.test
    >>> from astropy.io import fits
    >>> h = fits.Header.fromtextfile(sunpy.data.test.get_test_filepath("gong_magnetogram.header"))
    >>> v = gong_view(h)
    >>> v.site, v.obstime.isot[:16], round(float(v.plate_scale.value), 3)
    ('LE', '2025-01-09T01:35', 2.533)
    """
    header, path = _header(source)
    where = path or "the header"
    radius_key = "SEMIDIAM" if "SEMIDIAM" in header else "RADIUS"
    needed = [k for k in ("DATE-OBS", radius_key, "FNDLMBMI", "FNDLMBMA", "CRPIX1", "CRPIX2")
              if k not in header]
    if needed or not str(header.get("TELESCOP", "")).strip().endswith("GONG"):
        raise ValueError(f"{where} is not a GONG full-disk header (TELESCOP {header.get('TELESCOP')!r}; "
                         f"missing {needed})")
    date = str(header["DATE-OBS"]).strip().replace("/", "-")
    if "T" not in date and "TIME-OBS" in header:
        date = f"{date}T{str(header['TIME-OBS']).strip()}"
    obstime = Time(date, scale="utc")
    code = str(header.get("SITE", "")).strip().upper() or None
    height = GONG_SITES[code].height if code in GONG_SITES else 0.0
    if "LAT" in header and "LON" in header:
        location = EarthLocation.from_geodetic(float(header["LON"]) * u.rad, float(header["LAT"]) * u.rad,
                                               height * u.m)
    else:
        location = site_location(code) if code in GONG_SITES else None
    angular = (float(header[radius_key]) * u.rad).to(u.arcsec)
    limb = 0.5 * (float(header["FNDLMBMI"]) + float(header["FNDLMBMA"])) * u.pix
    b0 = float(header["B0"]) * u.deg if "B0" in header else None
    p_angle = (float(header["PA"]) * u.rad).to(u.deg) if "PA" in header else None
    distance = float(header["DISTANCE"]) * u.AU if "DISTANCE" in header else None
    centre = tuple(float(header.get(f"FNDLMB{a}C", header[f"CRPIX{i}"])) - 1 for i, a in ((1, "X"), (2, "Y")))
    scale = angular / (limb / u.pix)
    # The image's centre, (n - 1) / 2 in 0-based pixels, west and north of the disk centre.
    size = [int(header.get(f"NAXIS{i}", 860)) for i in (1, 2)]
    pointing = u.Quantity([((n - 1) / 2 - c) for n, c in zip(size, centre)]) * scale.to(u.arcsec)
    return GONGView(obstime, code, location, scale, centre, limb, p_angle, b0, distance, angular, path,
                    pointing)


def as_observed(settings, effects, *, mode, instrument_name):
    """
    A ``like`` run's defaults: the file's count level and the real instrument's effects, unless given.

    A full-disk GONG run "like" a real file reproduces that observation, so
    ``like_counts`` and the `AS_OBSERVED_EFFECTS` default to on; values given
    explicitly win.  Any other run is returned unchanged.

    Parameters
    ----------
    settings : dict
        ``[simulation]`` values given explicitly (``like``, ``like_counts``).
    effects : dict
        ``[effects]`` values given explicitly.
    mode : {"full-disk", "tiled"}
        The run's mode.
    instrument_name : str
        The run's instrument (only GONG has a ``like`` file's count level).

    Returns
    -------
    settings, effects : dict
        Copies, with the defaults added where they were missing.

    Examples
    --------
    >>> s, e = as_observed({"like": "bb.fits"}, {"image_rotation": False}, mode="full-disk",
    ...                    instrument_name="gong")
    >>> s["like_counts"], e
    (True, {'frame_seeing': True, 'minute_average': True, 'image_rotation': False})
    >>> as_observed({"like": "bb.fits"}, {}, mode="tiled", instrument_name="gong")   # date and site only
    ({'like': 'bb.fits'}, {})
    """
    settings, effects = dict(settings), dict(effects)
    if settings.get("like") is not None and mode == "full-disk" and instrument_name == "gong":
        settings.setdefault("like_counts", True)
        effects = {**dict.fromkeys(AS_OBSERVED_EFFECTS, True), **effects}
    return settings, effects


def like_gong(path, *, settings=None, instrument=None, fixed_plate_scale=False, mode="full-disk"):
    """
    The run settings of "what GONG saw" in a real full-disk file: its date, site, plate scale and pointing.

    Parameters
    ----------
    path : path-like
        A real GONG full-disk FITS file (e.g. ``bbbqa090905t1854.fits.gz``).
    settings : dict, optional
        ``[simulation]`` values given explicitly: they win over the file's.
    instrument : `~gongsynth.GONGInstrument`, optional
        The instrument to give the file's plate scale (default the standard one).
    fixed_plate_scale : bool
        Keep ``instrument``'s plate scale (it was given explicitly).
    mode : {"full-disk", "tiled"}
        The run's mode: only a full-disk run takes the file's pointing.

    Returns
    -------
    settings : dict
        ``settings`` with ``like`` (the path), ``obstime``, ``site`` and
        ``pointing`` (where the image's centre looks, so that the simulated
        disk sits on the same pixels as the real one) added where they were
        missing.  The file is not read when nothing is missing, so a saved
        run configuration repeats without it.
    instrument : `~gongsynth.GONGInstrument`
        With the file's plate scale (apparent radius / fitted limb radius)
        and, unless it was changed from the default, the image rotation of
        its reduction (``image_rotation_angle`` = −``ROTATOR``).

    Examples
    --------
    >>> import sunpy.data.test
    >>> settings, inst = like_gong(sunpy.data.test.get_test_filepath("gong_magnetogram.header"))
    >>> settings["obstime"][:16], settings["site"], round(float(inst.plate_scale.value), 3)
    ('2025-01-09T01:35', 'LE', 2.533)
    """
    from gongsynth.instruments.gong.parameters import GONGInstrument

    settings = dict(settings or {})
    instrument = GONGInstrument() if instrument is None else instrument
    settings.setdefault("like", str(path))
    wanted = {"obstime", "site"} | ({"pointing"} if mode == "full-disk" else set())
    if wanted <= set(settings) and fixed_plate_scale:
        return settings, instrument
    view = gong_view(path)
    settings.setdefault("obstime", view.obstime.isot)
    settings.setdefault("site", view.site if view.site in GONG_SITES else None)
    if mode == "full-disk":
        settings.setdefault("pointing", view.pointing)
    if not fixed_plate_scale:
        instrument = instrument.replace(plate_scale=view.plate_scale.to(u.arcsec))
    default_angle = getattr(type(instrument)(), "image_rotation_angle", None)
    if default_angle is not None and u.allclose(instrument.image_rotation_angle, default_angle):
        # GONG's reduction turns each image by the rotator's angle (GHIST: UCOR rot = -ROTATOR).
        rotator = _header(path)[0].get("ROTATOR")
        if rotator is not None:
            instrument = instrument.replace(image_rotation_angle=(-float(rotator) * u.rad).to(u.deg))
    return settings, instrument
