"""
Reading real (and simulated) full-disk observations as sunpy Maps, with header checks.

`load_observation` reads GONG full-disk magnetograms as NSO distributes them
(860 × 860 ``*zqa*`` / ``*bqa*`` FITS, which sunpy reads as
`~sunpy.map.sources.GONGMagnetogramMap`), SDO/HMI (``hmi.M_45s``,
``hmi.M_720s``), SOHO/MDI (96-minute magnetograms, continuum) and gongsynth's
own product files, and returns a Map whose data are in gauss (magnetograms).

Real headers are not always right.  Problems found here are *said*, never
silently passed on:

* a JSOC cut-out (``im_patch``) whose WCS keywords claim a helioprojective
  ``HPLN-TAN`` grid in arcsec while its HISTORY records a heliographic map
  projection (e.g. Postel): the coordinates from such a header are wrong by a
  factor of ~17 in scale.  The WCS is rebuilt from the HISTORY (Postel →
  ``CRLN-ARC``/``CRLT-ARC``, the zenithal equidistant projection) and a
  `BadHeaderWarning` says so;
* old MDI headers with ``CTYPE = 'solar-x'/'solar-y'`` are translated to
  ``HPLN-TAN``/``HPLT-TAN`` (noted in the map's history);
* a full-disk image whose finite pixels do not match the disk that its WCS
  predicts (wrong centre or plate scale) gets a `BadHeaderWarning`;
* missing WCS keywords, files that are not FITS images, maps that are not of
  the requested kind (a continuum image passed as a magnetogram) and maps
  without a single finite pixel raise clear errors naming the file.

Warnings that astropy raises while it fixes non-standard cards
(`~astropy.io.fits.verify.VerifyWarning`) are caught here and recorded in the
map's ``history`` instead of being re-emitted: they do not affect the data.
"""
import re
import warnings
from pathlib import Path

import astropy.units as u
import numpy as np
import sunpy.map
from astropy.io import fits
from astropy.io.fits.verify import VerifyWarning
from sunpy.coordinates import frames, get_earth, sun
from sunpy.util.exceptions import SunpyMetadataWarning

from gongsynth.analysis.disk import disk_coordinates

__all__ = [
    "BadHeaderWarning",
    "BadHeaderError",
    "ObservationKindError",
    "KINDS",
    "JSOC_PROJECTIONS",
    "load_observation",
    "check_disk_footprint",
]

#: Accepted values of ``kind`` in `load_observation`.
KINDS = ("magnetogram", "continuum", None)

#: JSOC map projections (``MapProj`` in HISTORY) and their FITS zenithal codes,
#: valid for projections centred on (LonHG, LatHG).
JSOC_PROJECTIONS = {
    "postel": "ARC",
    "gnomonic": "TAN",
    "orthographic": "SIN",
    "stereographic": "STG",
    "lambert": "ZEA",
}

# Keywords that carry the observation time (any one is enough).
_DATE_KEYS = ("date-obs", "date_obs", "t_obs", "date-avg", "date-beg")
# Required for a GONG-format (CTYPE GONGX/GONGY) header.
_GONG_KEYS = ("crpix1", "crpix2", "fndlmbmi", "fndlmbma")
#: The apparent solar radius in radians: SEMIDIAM (current headers) or RADIUS (old headers).
_GONG_RADIUS_KEYS = ("semidiam", "radius")
# Old-style helioprojective axis names.
_OLD_CTYPES = {"solar-x": "HPLN-TAN", "solar_x": "HPLN-TAN", "solar-y": "HPLT-TAN", "solar_y": "HPLT-TAN"}


class BadHeaderWarning(UserWarning):
    """A FITS header of an observation is wrong or inconsistent (coordinates may be affected)."""


class BadHeaderError(ValueError):
    """A FITS header cannot be used to place the map on the Sun (missing or unrepairable WCS)."""


class ObservationKindError(ValueError):
    """The file does not hold the kind of map asked for (e.g. a continuum image, not a magnetogram)."""


def _history_text(header):
    parts = []
    for key in ("HISTORY", "COMMENT"):
        if key in header:
            parts.extend(str(card) for card in header[key])
    return "".join(parts)


def _jsoc_projection(header):
    """(name, lon, lat) of a JSOC map projection recorded in HISTORY/COMMENT, or None."""
    text = _history_text(header)
    match = re.search(r"MapProj\s*=\s*([A-Za-z]+?)(?=\s*,?\s*LonHG|[^A-Za-z]|$)", text)
    if match is None:
        return None
    lon = re.search(r"LonHG\s*=\s*([-+]?[\d.]+(?:[eE][-+]?\d+)?)", text)
    lat = re.search(r"LatHG\s*=\s*([-+]?[\d.]+(?:[eE][-+]?\d+)?)", text)
    return (match.group(1), float(lon.group(1)) if lon else None, float(lat.group(1)) if lat else None)


def _fix_jsoc_projection(header, path, repair, notes):
    """Detect (and rebuild) the WCS of a JSOC map-projected cut-out labelled as helioprojective."""
    found = _jsoc_projection(header)
    ctype1 = str(header.get("CTYPE1", "")).strip()
    ctype2 = str(header.get("CTYPE2", "")).strip()
    if found is None or not ctype1.upper().startswith(("HPLN", "SOLAR")):
        return
    name, lon, lat = found
    cunit = str(header.get("CUNIT1", "arcsec")).strip()
    cdelt = header.get("CDELT1")
    claim = (f"{path}: the WCS keywords say {ctype1}/{ctype2} (helioprojective) with CDELT1 = {cdelt} "
             f"{cunit}, but HISTORY records a JSOC {name} map projection centred at Carrington "
             f"longitude {lon} deg, latitude {lat} deg; coordinates from this header are wrong")
    code = JSOC_PROJECTIONS.get(name.lower())
    if not repair:
        warnings.warn(claim + " (repair=False: header left as it is)", BadHeaderWarning, stacklevel=3)
        return
    if code is None or lon is None or lat is None or cdelt is None:
        raise BadHeaderError(
            claim + f"; gongsynth can rebuild only zenithal projections centred on (LonHG, LatHG) "
            f"({', '.join(sorted(JSOC_PROJECTIONS))}), not this one"
        )
    header["CTYPE1"] = f"CRLN-{code}"
    header["CTYPE2"] = f"CRLT-{code}"
    header["CUNIT1"] = "deg"
    header["CUNIT2"] = "deg"
    header["CRVAL1"] = lon
    header["CRVAL2"] = lat
    for key in ("CDELT1", "CDELT2"):
        # JSOC writes the map scale in heliographic degrees per pixel.
        header[key] = float(header[key])
    fixed = (f"the WCS was rebuilt as CRLN-{code}/CRLT-{code} (Carrington, {name} = FITS {code}) "
             f"centred at ({lon}, {lat}) deg with {header['CDELT1']} deg per pixel")
    warnings.warn(f"{claim}; {fixed}", BadHeaderWarning, stacklevel=3)
    notes.append(f"header repaired: {name} projection labelled {ctype1}; {fixed}")


def _gong_format_to_hpc(header, notes):
    """
    Give a GONG-format header (CTYPE GONGX/GONGY) that sunpy's GONG source does not claim a HPC WCS.

    Both header generations: current ones give the apparent radius as
    SEMIDIAM, old site files (e.g. Big Bear 2009, DTYPE RW, CDELT = 0) as
    RADIUS, both in radians; FNDLMBMI/FNDLMBMA are the fitted limb's semi-axes
    in pixels and CRPIX1/2 the disk centre.  The image is taken as solar north
    up, as GONG's reduced images are (their PA keyword is the ephemeris P angle,
    removed by the reduction).
    """
    radius_key = "SEMIDIAM" if "SEMIDIAM" in header else "RADIUS"
    semidiam = (float(header[radius_key]) * u.rad).to_value(u.arcsec)
    header["CTYPE1"], header["CTYPE2"] = "HPLN-TAN", "HPLT-TAN"
    header["CUNIT1"], header["CUNIT2"] = "arcsec", "arcsec"
    header["CDELT1"] = semidiam / float(header["FNDLMBMI"])
    header["CDELT2"] = semidiam / float(header["FNDLMBMA"])
    header["CRVAL1"], header["CRVAL2"] = 0.0, 0.0
    header["RSUN_OBS"] = semidiam
    if "TIME-OBS" in header and "T" not in str(header.get("DATE-OBS", "T")):
        date = str(header["DATE-OBS"]).strip().replace("/", "-")
        header["DATE-OBS"] = f"{date}T{str(header['TIME-OBS']).strip()}"
    if "DISTANCE" in header and "DSUN_OBS" not in header:
        # The observer is the site on Earth: the Sun's distance from the header, B0 from the
        # header or, in old headers without it, from the ephemeris at DATE-OBS.
        header["DSUN_OBS"] = (float(header["DISTANCE"]) * u.AU).to_value(u.m)
        header["HGLN_OBS"] = 0.0
        header["HGLT_OBS"] = (float(header["B0"]) if "B0" in header
                              else sun.B0(str(header["DATE-OBS"]).strip()).to_value(u.deg))
    if ("SKYVALUE" not in header and str(header.get("IMTYPE", "")).strip() == "MAGNETIC"
            and "IMGMIN01" in header):
        header["SKYVALUE"] = float(header["IMGMIN01"])  # old magnetograms: the sky is the image minimum
        notes.append(f"sky value {header['SKYVALUE']} taken from IMGMIN01 (old GONG magnetogram)")
    notes.append(f"GONG-format header (GONGX/GONGY) given a helioprojective WCS from {radius_key} and "
                 "FNDLMBMI/FNDLMBMA")


def _is_gong_observation(header):
    return (str(header.get("TELESCOP", "")).strip().endswith("GONG")
            and str(header.get("IMTYPE", "")).strip() == "MAGNETIC"
            and str(header.get("DTYPE", "")).strip() == "OBSERVE")


def _prepare_header(header, path, repair, notes):
    """Check and fix a header in place before sunpy sees it."""
    keys = {k.lower() for k in header.keys()}
    ctype1 = str(header.get("CTYPE1", "")).strip()
    if ctype1.upper().startswith("GONG"):
        missing = [k.upper() for k in _GONG_KEYS if k not in keys]
        if not any(k in keys for k in _GONG_RADIUS_KEYS):
            missing.append("SEMIDIAM (or RADIUS)")
        if not any(k in keys for k in _DATE_KEYS):
            missing.append("DATE-OBS")
        if missing:
            raise BadHeaderError(
                f"{path}: GONG-format header lacks the keyword(s) {missing} needed to place the map "
                f"on the Sun"
            )
        if not _is_gong_observation(header):
            _gong_format_to_hpc(header, notes)
        return
    for axis in ("CTYPE1", "CTYPE2"):
        value = str(header.get(axis, "")).strip()
        if value.lower() in _OLD_CTYPES:
            header[axis] = _OLD_CTYPES[value.lower()]
            notes.append(f"old-style {axis} = {value!r} read as {header[axis]!r}")
            if "RSUN_OBS" not in header and "OBS_R0" in header:
                # Old MDI headers give the apparent radius (arcsec) as OBS_R0.
                header["RSUN_OBS"] = float(header["OBS_R0"])
                notes.append("RSUN_OBS taken from OBS_R0 (old MDI header)")
    missing = [k for k in ("CTYPE1", "CTYPE2", "CRPIX1", "CRPIX2") if k.lower() not in keys]
    has_scale = {"cdelt1", "cdelt2"} <= keys or {"cd1_1", "cd2_2"} <= keys
    if not has_scale:
        missing.append("CDELT1/CDELT2 (or CD1_1/CD2_2)")
    if not any(k in keys for k in _DATE_KEYS):
        missing.append("DATE-OBS")
    if missing:
        raise BadHeaderError(
            f"{path}: missing WCS keyword(s) {missing}; cannot place the map on the Sun"
        )
    _fix_jsoc_projection(header, path, repair, notes)


def _read_image(path, notes):
    """(data, header, quantisation step) of the first 2-D image HDU of a FITS file."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.filterwarnings("always", category=VerifyWarning)
        # A short file is reported below, by name, when its data cannot be read.
        warnings.filterwarnings("ignore", message="File may have been truncated")
        try:
            hdul = fits.open(path, memmap=False)
        except (OSError, ValueError) as err:
            raise ValueError(f"{path} is not a readable FITS file ({err})") from err
        with hdul:
            image = None
            for hdu in hdul:
                if getattr(hdu, "is_image", False) and hdu.header.get("NAXIS", 0) >= 2:
                    image = hdu
                    break
            if image is None:
                raise ValueError(f"{path} holds no image HDU with at least two axes")
            # Quantisation step of integer data: astropy drops BSCALE once it scales the data.
            step = abs(float(image.header.get("BSCALE", 1.0))) if image.header.get("BITPIX", -32) > 0 else 0.0
            try:
                data = np.asarray(image.data)
            except (ValueError, OSError) as err:  # astropy's words for a file cut short: "cannot reshape"
                raise ValueError(f"{path}: the image data cannot be read, the file is probably truncated "
                                 f"(an incomplete download or copy): {err}") from None
            header = image.header.copy()
    for w in caught:
        if issubclass(w.category, VerifyWarning):
            notes.append(f"astropy fixed the header: {str(w.message).strip()[:200]}")
        else:  # not ours to swallow
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    while data.ndim > 2 and data.shape[0] == 1:
        data = data[0]
    if data.ndim != 2:
        axes = [str(header.get(f"CTYPE{i}", "")).strip() for i in range(data.ndim, 0, -1)]
        named = f" with axes {axes}" if any(axes) else ""
        what = f" (OBS_TYPE {header['OBS_TYPE']!r})" if "OBS_TYPE" in header else ""
        if "NREAL" in header:
            model = str(header.get("MODEL", "")).strip()
            what = f" (the {model} model's {header['NREAL']} realisations, NREAL)"
        raise ValueError(
            f"{path}: the image is a {data.ndim}-D array of shape {data.shape}{named}{what}, not a 2-D "
            f"map; save the one map to compare (e.g. one realisation or one Stokes parameter) as a FITS "
            f"image with its WCS"
        )
    if data.dtype.kind not in "fiu":
        raise ValueError(f"{path}: the image has non-numeric data of type {data.dtype}")
    return data.astype(np.float64 if data.dtype.itemsize > 4 else np.float32, copy=False), header, step


def _describe(header):
    text = (f"BUNIT = {header.get('BUNIT', '(none)')!r}, CONTENT = {header.get('CONTENT', '(none)')!r}, "
            f"IMTYPE = {header.get('IMTYPE', '(none)')!r}")
    if "OBS_TYPE" in header:
        text += f", OBS_TYPE = {header['OBS_TYPE']!r}"
    return text


def _says(header, *words):
    text = " ".join(str(header.get(k, "")) for k in ("CONTENT", "IMTYPE", "OBS_TYPE")).upper()
    return any(w in text for w in words)


def _check_kind(smap, header, kind, path, notes):
    """Return the factor to gauss (magnetograms) or None, after checking the kind of map."""
    unit = smap.unit
    if kind == "magnetogram":
        if unit is not None and unit.is_equivalent(u.G):
            return unit.to(u.G)
        if unit is None and _says(header, "MAGNETOGRAM", "MAGNETIC"):
            notes.append("no BUNIT; CONTENT/IMTYPE says magnetogram: values taken as gauss")
            return 1.0
        raise ObservationKindError(f"{path} is not a magnetogram: {_describe(header)} (a magnetogram "
                                   f"holds a field in gauss: BUNIT G, or CONTENT/IMTYPE saying magnetogram)")
    if kind == "continuum":
        magnetic = unit is not None and unit.is_equivalent(u.G)
        velocity = unit is not None and unit.is_equivalent(u.m / u.s)
        if magnetic or velocity or _says(header, "MAGNETOGRAM", "MAGNETIC", "DOPPLER"):
            raise ObservationKindError(f"{path} is not a continuum/intensity image: {_describe(header)}")
    return None


def check_disk_footprint(smap, *, name="map", rho=None):
    """
    Check that the finite pixels of a full-disk image match the disk of its WCS.

    Full-disk products set the sky to NaN (or a sky value).  If the WCS puts
    the disk elsewhere or gives it another size (wrong CRPIX, CDELT or
    RSUN_OBS), finite pixels appear far off the predicted disk or blanks
    inside it.  Maps with fewer than 5 % non-finite pixels (cut-outs, maps
    with data off the limb) are not tested.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
    name : str
        Name used in the warning (e.g. the file name).
    rho : `numpy.ndarray`, optional
        Distance of every pixel from disk centre in solar radii, if already
        computed (`gongsynth.analysis.disk.disk_coordinates`).

    Returns
    -------
    bool
        False if the footprint disagrees with the WCS (a `BadHeaderWarning`
        is then issued), True otherwise.

    Examples
    --------
    >>> import astropy.units as u
    >>> import numpy as np
    >>> import sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> from gongsynth.analysis.disk import disk_coordinates
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> m = sunpy.map.Map(np.ones((100, 100)), sunpy.map.make_fitswcs_header(
    ...     (100, 100), ref, scale=[25, 25] * u.arcsec / u.pix))
    >>> rho, _ = disk_coordinates(m)
    >>> check_disk_footprint(sunpy.map.Map(np.where(rho < 1, 1.0, np.nan), m.meta))
    True
    """
    finite = np.isfinite(np.asarray(smap.data, dtype=float))
    if finite.mean() > 0.95:
        return True
    if rho is None:
        rho, _ = disk_coordinates(smap)
    with np.errstate(invalid="ignore"):
        inner = rho < 0.9
        outer = rho > 1.1
    problems = []
    if inner.sum() >= 100 and finite[inner].mean() < 0.9:
        problems.append(f"only {finite[inner].mean():.0%} of the pixels within 0.9 solar radii are finite")
    if outer.sum() >= 100 and finite[outer].mean() > 0.1:
        problems.append(f"{finite[outer].mean():.0%} of the pixels beyond 1.1 solar radii are finite")
    if np.count_nonzero(inner) == 0:
        problems.append("the WCS puts no pixel within 0.9 solar radii of disk centre")
    if problems:
        warnings.warn(
            f"{name}: the finite pixels do not match the solar disk of the WCS ("
            + "; ".join(problems) + "): CRPIX, CDELT or RSUN_OBS is probably wrong",
            BadHeaderWarning, stacklevel=2,
        )
        return False
    return True


def _with_data(smap, data, meta):
    """A map of the same sunpy source with new data and metadata, keeping ``smap``'s plot settings."""
    new = sunpy.map.Map(data, meta)
    new.plot_settings.update(smap.plot_settings)
    return new


def _mask_gong_sky(smap, header, step, rho):
    """NaN the GONG sky value (SKYVALUE) off the disk."""
    if "SKYVALUE" not in header:
        return smap
    sky = float(header["SKYVALUE"])
    tol = max(step, 1e-3)
    data = np.array(smap.data, dtype=float)
    with np.errstate(invalid="ignore"):
        sky_pixels = (np.abs(data - sky) <= tol) & ~(rho < 0.98)
    if not sky_pixels.any():
        return smap
    data[sky_pixels] = np.nan
    return _with_data(smap, data, smap.meta)


def _with_earth_observer(smap, notes):
    """
    A Carrington synoptic map without observer keywords, observed from Earth on its date.

    HMI's synoptic charts (``hmi.Synoptic_Mr``) carry no observer: sunpy then
    warns on every use of their WCS.  A synoptic map is made from Earth (or
    near-Earth) views, so the observer is Earth at the map's date, as sunpy's
    own GONG synoptic source assumes.  Maps with an observer, or with a
    source that supplies one, are returned unchanged.
    """
    if not str(smap.meta.get("ctype1", "")).upper().startswith("CRLN"):
        return smap
    with warnings.catch_warnings():
        warnings.simplefilter("error", SunpyMetadataWarning)
        try:
            if smap.observer_coordinate is not None:
                return smap
        except SunpyMetadataWarning:
            pass
    earth = get_earth(smap.date)
    meta = smap.meta.copy()
    meta.update({"hgln_obs": earth.lon.to_value(u.deg), "hglt_obs": earth.lat.to_value(u.deg),
                 "dsun_obs": earth.radius.to_value(u.m)})
    notes.append("synoptic map without observer keywords: observer placed at Earth on the map's date")
    return _with_data(smap, smap.data, meta)


def load_observation(path, *, kind="magnetogram", repair=True):
    """
    Read a full-disk observation (GONG, HMI, MDI or gongsynth FITS) as a sunpy Map.

    Parameters
    ----------
    path : str or `pathlib.Path`
        FITS file; the first HDU with a 2-D image is read (RICE-compressed
        HDUs included).
    kind : {"magnetogram", "continuum", None}
        What the file must hold.  ``"magnetogram"``: BUNIT convertible to gauss
        (or, without BUNIT, CONTENT/IMTYPE saying magnetogram); the data are
        returned in G.  ``"continuum"``: an intensity image (anything that is
        not a magnetogram or Dopplergram).  ``None``: no check.
    repair : bool
        Rebuild a wrong but recognisable WCS (a JSOC map projection labelled
        as helioprojective, see the module notes).  With ``False`` the header
        is left as it is and only the `BadHeaderWarning` is issued.

    Returns
    -------
    `~sunpy.map.GenericMap`
        The map (GONG: `~sunpy.map.sources.GONGMagnetogramMap`; MDI/HMI: their
        sunpy sources); magnetograms in G.  Off-disk sky values of GONG files
        are set to NaN.  Notes about fixes are appended to ``meta['history']``.

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    ValueError
        If the file is not a FITS image, or the map holds no finite pixel.
    BadHeaderError
        If WCS keywords are missing or a wrong WCS cannot be rebuilt.
    ObservationKindError
        If the file does not hold a map of ``kind``.

    Warns
    -----
    BadHeaderWarning
        When a header is wrong (repaired or not) or the disk footprint of a
        full-disk image disagrees with its WCS.

    Examples
    --------
    >>> import numpy as np, astropy.units as u, sunpy.map, tempfile, os
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> m = sunpy.map.Map(np.full((8, 8), 0.5), sunpy.map.make_fitswcs_header(
    ...     (8, 8), ref, scale=[2.5, 2.5] * u.arcsec / u.pix, unit=u.mT))
    >>> path = os.path.join(tempfile.mkdtemp(), "b.fits")
    >>> m.save(path)
    >>> obs = load_observation(path)
    >>> obs.unit, float(obs.data[0, 0])
    (Unit("G"), 5.0)
    """
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    if not isinstance(path, (str, Path)):
        raise TypeError(f"path must be a str or pathlib.Path, got {type(path).__name__}")
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"load_observation: no such file: {path}")
    notes = []
    data, header, step = _read_image(path, notes)
    if not np.isfinite(data).any():
        raise ValueError(f"{path}: the map holds no finite pixel (all NaN or infinite)")
    _prepare_header(header, path, repair, notes)
    try:
        smap = sunpy.map.Map(data, header)
    except Exception as err:  # sunpy raises several types for unusable metadata
        raise BadHeaderError(f"{path}: sunpy cannot build a map from this header ({err})") from err
    if not isinstance(smap, sunpy.map.GenericMap):
        raise ValueError(f"{path}: expected one map, sunpy returned {type(smap).__name__}")
    smap = _with_earth_observer(smap, notes)
    factor = _check_kind(smap, header, kind, path, notes)
    if factor is not None:
        meta = smap.meta.copy()
        meta["bunit"] = "G"
        values = np.asarray(smap.data) * float(factor) if factor != 1 else smap.data
        smap = _with_data(smap, values, meta)
    if isinstance(smap.coordinate_frame, frames.Helioprojective):
        rho, _ = disk_coordinates(smap)
        smap = _mask_gong_sky(smap, header, step, rho)  # GONG files (old and new) name a SKYVALUE
        check_disk_footprint(smap, name=str(path), rho=rho)
    if notes:
        history = str(smap.meta.get("history", "")).rstrip()
        added = "\n".join(f"gongsynth.load_observation: {n}" for n in notes)
        smap.meta["history"] = f"{history}\n{added}" if history else added
    return smap
