r"""
Open flux of a synoptic map: potential-field source-surface (PFSS) extrapolation.

Solar-wind models driven by synoptic magnetograms (PFSS, WSA) give less open
flux than spacecraft measure at 1 AU, and modellers multiply the maps by 2 to 4
(the "open flux problem": Linker et al. 2017, ApJ 848, 70; Wallace et al. 2019,
Sol. Phys. 294, 19).  This module puts a calibrated (or raw) synoptic map
through the PFSS extrapolation of **sunkit-magex** (``sunkit_magex.pfss``, the
successor of pfsspy; Stansby et al. 2020, JOSS 5, 2732), an optional dependency
(``pip install 'gongsynth[pfss]'``), and returns the open flux.

**Convention.**  The open flux is the **total unsigned** flux through the source surface,

.. math:: \Phi_\mathrm{open} = \oint_{r = R_\mathrm{ss}} |B_r|\, dA
          = R_\mathrm{ss}^2 R_\odot^2 \sum_{ij} |B_r(R_\mathrm{ss})_{ij}|\, \Delta s\, \Delta\phi ,

both polarities together (not the flux of one polarity, which is half of it
for a balanced map), in Mx, with :math:`R_\odot` = 695 700 km (IAU 2015
nominal, ``astropy.constants.R_sun``).  The in-situ counterpart is
`in_situ_open_flux`, :math:`4\pi r^2 |B_r|` with :math:`|B_r| r^2` measured
near 1 AU (the Ulysses result that :math:`|B_r| r^2` does not depend on
latitude: Smith & Balogh 1995, GRL 22, 3317; Lockwood et al. 2004, Ann.
Geophys. 22, 1395).

**Preparing the map** (`prepare_synoptic_map`).  sunkit-magex needs a
full-Sun Carrington map on a grid regular in longitude
and sine latitude (cylindrical equal area, CEA), with finite values.  In order:

1. **Check**: a 2-D map in a heliographic (Carrington or Stonyhurst) frame
   whose pixels span 360° of longitude and pole to pole, in a CEA or plate
   carrée (CAR) projection; anything else is a ValueError naming the argument.
2. **Polar fill**: GONG and HMI synoptic maps see the poles at grazing
   incidence (HMI's charts leave the polemost rows NaN).  ``polar_cap``
   (optional latitude) also declares every pixel poleward of ±polar_cap
   unobserved.  ``polar_fill`` then says what the unobserved pixels become:
   ``"none"`` (refuse NaNs: ValueError), ``"zero"`` (no field there) or
   ``"nearest"`` (the nearest observed value toward the equator in the same
   longitude column: the polemost observed field is carried to the pole).
3. **Resampling** to ``shape`` = (n_sinlat, n_lon) by exact area weighting
   (the map is taken piecewise constant on its pixels; the flux of every output
   pixel is the flux of the input areas it covers), so the net flux is kept
   to round-off (the unsigned flux drops where opposite polarities share an
   output pixel).  A CAR map is put on the sine-latitude grid the same way.
4. **Zero point** (``zero_point``): a map's net flux (monopole) is an
   instrument or zero-point error, and a potential field cannot carry it
   (sunkit-magex drops the l = 0 term, so a monopole would be silently
   removed anyway).  ``"subtract"`` removes the mean field (the same offset
   from every pixel: a zero-point correction); ``"balance"`` scales each
   polarity so that both carry half of the unsigned flux (a gain correction of
   the weaker polarity; zero pixels stay zero).

**Resolution error.**  sunkit-magex solves on a grid uniform in ln r with
``nr`` cells between 1 and R_ss.  On the dipole, whose open flux is known
exactly (see ``tests/test_open_flux.py``), the computed open flux is high by
0.42/nr (first order in the radial step: 2.6 % at nr = 16, 1.05 % at nr = 40,
0.53 % at nr = 80, for 45 to 180 sine-latitude rows), and the Richardson
extrapolation 2 Φ(2n) − Φ(n) is within 8e-4 of the exact value at 45 rows and
nr = 16/32, 3e-5 at 90 rows and nr = 40/80.  A real map converges the same
way: GONG CR 2254's open flux drops by 0.65 % from nr = 40 to 80, and by 0.02 %
from the default 90 × 180 grid to 180 × 360 (the small scales open little
flux; ``scripts/open_flux_table.py``).
"""
import contextlib
import math
import warnings

import astropy.constants as const
import astropy.units as u
import numpy as np
import sunpy.map
from astropy.coordinates import SkyCoord
from sunpy.util.exceptions import SunpyMetadataWarning

from gongsynth.analysis.calibration import gauss_values
from gongsynth.analysis.disk import check_map
from gongsynth.optional import import_optional

__all__ = ["POLAR_FILLS", "ZERO_POINTS", "synoptic_pixel_edges", "prepare_synoptic_map", "pfss_extrapolation",
           "source_surface_flux", "open_flux", "in_situ_open_flux"]

#: Accepted values of ``polar_fill``.
POLAR_FILLS = ("none", "zero", "nearest")
#: Accepted values of ``zero_point``.
ZERO_POINTS = ("subtract", "balance")

_DEFAULT_SHAPE = (90, 180)
_ANGLE_TOLERANCE = 0.1  # deg: the tolerance of sunkit-magex's own full-Sun check


def synoptic_pixel_edges(smap):
    """
    Sine latitude and longitude (deg) of a full-Sun synoptic map's pixel edges, from its WCS.

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        A CEA or CAR Carrington map spanning 360° × 180°.

    Returns
    -------
    sin_lat : `numpy.ndarray`
        ``ny + 1`` edges in sine latitude.
    lon : `numpy.ndarray`
        ``nx + 1`` edges in longitude (deg).

    Raises
    ------
    ValueError
        If the map is not a full-Sun CEA or CAR map with unrotated axes.
    """
    with warnings.catch_warnings():  # the pixel grid needs no observer (HMI's charts have none)
        warnings.simplefilter("ignore", SunpyMetadataWarning)
        wcs = smap.wcs.wcs
    ctype = [str(c) for c in wcs.ctype]
    projection = ctype[0][-3:]
    if projection != ctype[1][-3:] or projection not in ("CEA", "CAR"):
        raise ValueError(f"synoptic_map must be in a cylindrical equal-area (CEA) or plate carrée (CAR) "
                         f"projection, got CTYPE {ctype[0]!r}, {ctype[1]!r}")
    ny, nx = smap.data.shape
    units = [u.Unit(str(c)) if str(c) else u.deg for c in wcs.cunit]
    cdelt = [(wcs.cdelt[i] * units[i]).to_value(u.deg) for i in range(2)]
    crval = [(wcs.crval[i] * units[i]).to_value(u.deg) for i in range(2)]
    if wcs.has_pc():
        pc = np.asarray(wcs.get_pc())
        if not np.allclose(pc, np.eye(2)):
            raise ValueError(f"synoptic_map must have unrotated axes (PC = identity), got PC {pc.tolist()}")
    if crval[1] != 0:
        raise ValueError(f"synoptic_map must have its reference latitude on the equator (CRVAL2 = 0; "
                         f"otherwise the projection is oblique), got {crval[1]} deg")
    lon = crval[0] + (np.arange(nx + 1) + 0.5 - wcs.crpix[0]) * cdelt[0]
    y = (np.arange(ny + 1) + 0.5 - wcs.crpix[1]) * cdelt[1]
    if projection == "CEA":
        pv = {(i, m): v for i, m, v in wcs.get_pv()}
        if not math.isclose(pv.get((2, 1), 1.0), 1.0):
            raise ValueError(f"synoptic_map: CEA with PV2_1 = {pv[(2, 1)]} is not a sine-latitude grid")
        sin_lat = np.deg2rad(y)  # CEA (lambda = 1): y = sin(latitude) × 180/π
        span = abs(cdelt[1]) * ny * math.pi / 2
    else:
        sin_lat = np.sin(np.deg2rad(np.clip(y, -90, 90)))
        span = abs(cdelt[1]) * ny
    if abs(abs(cdelt[0]) * nx - 360) > _ANGLE_TOLERANCE or abs(span - 180) > _ANGLE_TOLERANCE:
        raise ValueError(f"synoptic_map must span 360° of longitude and 180° of latitude (a full-Sun "
                         f"synoptic map), got {abs(cdelt[0]) * nx:.3f}° × {span:.3f}° from its "
                         f"{ny} × {nx} pixels")
    return np.clip(sin_lat, -1, 1), lon


def _check_synoptic(smap):
    check_map(smap, "synoptic_map")
    # From CTYPE, not smap.coordinate_frame: a synoptic map needs no observer (HMI's charts have none).
    axes = tuple(str(axis)[:4] for axis in smap.coordinate_system)
    if axes not in (("CRLN", "CRLT"), ("HGLN", "HGLT")):
        raise ValueError(f"synoptic_map must be a heliographic (Carrington) synoptic map, got axes "
                         f"{tuple(smap.coordinate_system)}; disk images have no far side")
    return synoptic_pixel_edges(smap)


def _fill_poles(data, sin_lat_edges, polar_fill, polar_cap):
    """NaN and poleward-of-cap pixels filled by ``polar_fill`` (see the module notes)."""
    data = data.copy()
    if polar_cap is not None:
        cap = math.sin(math.radians(polar_cap))
        centres = 0.5 * (sin_lat_edges[1:] + sin_lat_edges[:-1])
        data[np.abs(centres) > cap, :] = np.nan
    missing = ~np.isfinite(data)
    if not missing.any():
        return data
    if polar_fill == "none":
        rows = np.nonzero(missing.any(axis=1))[0]
        raise ValueError(f"synoptic_map has {int(missing.sum())} NaN or unobserved pixel(s) (in rows "
                         f"{rows.min()}-{rows.max()}); choose polar_fill='zero' or 'nearest'")
    if polar_fill == "zero":
        data[missing] = 0.0
        return data
    centre = data.shape[0] // 2
    for half in (slice(centre, None), slice(centre - 1, None, -1)):  # north, then south, walking poleward
        rows = data[half]
        for k in range(1, rows.shape[0]):
            hole = ~np.isfinite(rows[k])
            rows[k, hole] = rows[k - 1, hole]
    if not np.isfinite(data).all():
        raise ValueError("synoptic_map: polar_fill='nearest' needs an observed pixel between the equator "
                         "and each unobserved one in its longitude column")
    return data


def _remap(values, old_edges, new_edges, axis):
    """Exact area-weighted resampling along ``axis`` between cell edges (both increasing, same ends)."""
    moved = np.moveaxis(values, axis, 0)
    cumulative = np.concatenate([np.zeros((1,) + moved.shape[1:]),
                                 np.cumsum(moved * np.diff(old_edges)[:, None], axis=0)])
    at_new = np.stack([np.interp(new_edges, old_edges, column) for column in cumulative.T], axis=1)
    return np.moveaxis(np.diff(at_new, axis=0) / np.diff(new_edges)[:, None], 0, axis)


def _cea_header(smap, shape, left_longitude):
    ns, nphi = shape
    centre = SkyCoord((left_longitude + 180) * u.deg, 0 * u.deg, const.R_sun, obstime=smap.date,
                      frame="heliographic_carrington", observer="self")
    header = sunpy.map.make_fitswcs_header(
        (ns, nphi), centre, scale=[360 / nphi, 180 / ns] * u.deg / u.pix,
        reference_pixel=[nphi / 2 - 0.5, ns / 2 - 0.5] * u.pix, projection_code="CEA", unit=u.G)
    header["cdelt2"] = 180 / np.pi * 2 / ns  # CEA: the axis steps in sine latitude, in rad × 180/π
    return header


def _check_options(shape, polar_fill, zero_point, polar_cap):
    if (not isinstance(shape, (tuple, list)) or len(shape) != 2
            or not all(isinstance(n, (int, np.integer)) and not isinstance(n, bool) for n in shape)):
        raise TypeError(f"shape must be a pair of integers (n_sinlat, n_lon), got {shape!r}")
    if shape[0] < 8 or shape[1] < 16:
        raise ValueError(f"shape must be at least (8, 16) pixels (n_sinlat, n_lon), got {tuple(shape)}")
    if polar_fill not in POLAR_FILLS:
        raise ValueError(f"polar_fill must be one of {POLAR_FILLS}, got {polar_fill!r}")
    if zero_point not in ZERO_POINTS:
        raise ValueError(f"zero_point must be one of {ZERO_POINTS}, got {zero_point!r}")
    if polar_cap is None:
        return None
    if not isinstance(polar_cap, u.Quantity) or not polar_cap.unit.is_equivalent(u.deg):
        raise TypeError(f"polar_cap must be an angle Quantity (e.g. 60 * u.deg) or None, got {polar_cap!r}")
    cap = float(polar_cap.to_value(u.deg))
    if not 0 < cap < 90:
        raise ValueError(f"polar_cap must be between 0 and 90 deg, got {polar_cap}")
    return cap


def prepare_synoptic_map(synoptic_map, *, shape=_DEFAULT_SHAPE, polar_fill="nearest", polar_cap=None,
                         zero_point="subtract"):
    r"""
    A synoptic map made ready for PFSS: full Sun, CEA grid of ``shape``, finite, no net flux.

    Parameters
    ----------
    synoptic_map : `~sunpy.map.GenericMap`
        Full-Sun Carrington synoptic map of the radial field in G (GONG
        ``mrbqs``/``mrzqs``, HMI ``Synoptic_Mr``; CEA or CAR projection), raw or
        `gongsynth.calibrate`\ d.
    shape : tuple of int, optional
        (n_sinlat, n_lon) of the grid the field is resampled to (exact area
        weighting); default (90, 180), a 2° grid in longitude.
    polar_fill : {"nearest", "zero", "none"}, optional
        What unobserved (NaN, or poleward of ``polar_cap``) pixels become; see
        the module notes.  ``"none"`` refuses maps with NaNs.
    polar_cap : `~astropy.units.Quantity`, optional
        Latitude (deg) poleward of which every pixel is treated as unobserved
        and filled; default None (only NaN pixels are filled).
    zero_point : {"subtract", "balance"}, optional
        How the net flux (monopole) is removed; see the module notes.

    Returns
    -------
    `~sunpy.map.GenericMap`
        CEA Carrington map in G of ``shape``, with the net flux removed; its
        ``NETFLUX`` keyword records the removed mean field (G) and HISTORY the
        choices.

    Raises
    ------
    TypeError, ValueError
        Not a map, not a full-Sun heliographic CEA/CAR map, NaNs with
        ``polar_fill="none"``, a map with no field, unknown options.

    Examples
    --------
    >>> import numpy as np, astropy.units as u, sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> ref = SkyCoord(180 * u.deg, 0 * u.deg, frame="heliographic_carrington", observer="earth",
    ...                obstime="2022-03-01")
    >>> header = sunpy.map.make_fitswcs_header((180, 360), ref, scale=[1, 180 / np.pi / 90] * u.deg / u.pix,
    ...                                        projection_code="CEA", unit=u.G)
    >>> sin_lat = (np.arange(180) + 0.5) / 90 - 1
    >>> dipole = sunpy.map.Map(np.repeat(sin_lat[:, None], 360, axis=1) + 0.5, header)
    >>> ready = prepare_synoptic_map(dipole)
    >>> ready.data.shape, round(ready.meta["netflux"], 6), round(float(abs(ready.data).mean()), 4)
    ((90, 180), 0.5, 0.5)
    """
    cap = _check_options(shape, polar_fill, zero_point, polar_cap)
    sin_lat, lon = _check_synoptic(synoptic_map)
    data = gauss_values(synoptic_map, "synoptic_map")
    if sin_lat[0] > sin_lat[-1]:  # put south first
        sin_lat, data = sin_lat[::-1], data[::-1]
    if lon[0] > lon[-1]:
        lon, data = lon[::-1], data[:, ::-1]
    data = _fill_poles(data, sin_lat, polar_fill, cap)
    ns, nphi = shape
    sin_lat[0], sin_lat[-1] = -1.0, 1.0  # the full-Sun check allowed 0.1° of slack
    data = _remap(data, sin_lat, np.linspace(-1, 1, ns + 1), axis=0)
    data = _remap(data, lon, np.linspace(lon[0], lon[-1], nphi + 1), axis=1)
    net = float(data.mean())  # equal-area pixels: the mean is the monopole
    positive, negative = data[data > 0].sum(), -data[data < 0].sum()
    if positive + negative == 0:
        raise ValueError("synoptic_map has no field (all zero): there is no open flux to compute")
    if zero_point == "subtract":
        data = data - net
    else:
        if positive == 0 or negative == 0:
            raise ValueError("synoptic_map has one polarity only: zero_point='balance' cannot balance it; "
                             "use zero_point='subtract'")
        half = 0.5 * (positive + negative)
        data = np.where(data > 0, data * (half / positive), data * (half / negative))
    header = _cea_header(synoptic_map, shape, lon[0] % 360)
    header["netflux"] = net  # G: the mean field (monopole) removed
    header["history"] = (f"gongsynth.prepare_synoptic_map: polar_fill={polar_fill}, polar_cap={polar_cap}, "
                         f"area-weighted to {ns}x{nphi} CEA, zero_point={zero_point}")
    return sunpy.map.Map(data, header)


@contextlib.contextmanager
def _plain_numpy_kernels(module):
    """
    Run sunkit-magex's solver on its plain-numpy kernels instead of its numba ones.

    sunkit-magex compiles four small kernels with numba on first use in every
    process (no cache), which costs more than it saves on the grids used here
    (measured on a loaded 2-core machine: 90 × 180 × 40 cells in 7.8 s with the
    numpy kernels, 8.4 s with the compiled ones after 37 s of compilation).
    The swap is undone on exit.
    """
    saved = {}
    for name in ("_eigh", "_compute_r_term", "_als_alp", "_A_diag"):
        kernel = getattr(module, name, None)
        if hasattr(kernel, "py_func"):
            saved[name] = kernel
            setattr(module, name, kernel.py_func)
    try:
        yield
    finally:
        for name, kernel in saved.items():
            setattr(module, name, kernel)


def _source_surface_radius(source_surface):
    if isinstance(source_surface, u.Quantity):
        if not source_surface.unit.is_equivalent(u.R_sun):
            raise u.UnitsError(f"source_surface must be in solar radii (a length or a number), got "
                               f"{source_surface.unit}")
        source_surface = float(source_surface.to_value(u.R_sun))
    if isinstance(source_surface, bool) or not isinstance(source_surface, (int, float, np.number)):
        raise TypeError(f"source_surface must be a number of solar radii, got {source_surface!r}")
    if not (math.isfinite(source_surface) and source_surface > 1):
        raise ValueError(f"source_surface must be above the photosphere (> 1 solar radius), "
                         f"got {source_surface}")
    return float(source_surface)


def pfss_extrapolation(synoptic_map, *, source_surface=2.5, nr=40, shape=_DEFAULT_SHAPE, polar_fill="nearest",
                       polar_cap=None, zero_point="subtract"):
    """
    The PFSS field of a synoptic map (sunkit-magex), after `prepare_synoptic_map`.

    Parameters
    ----------
    synoptic_map : `~sunpy.map.GenericMap`
        See `prepare_synoptic_map`.
    source_surface : float or `~astropy.units.Quantity`, optional
        Source-surface radius in solar radii (default 2.5, the usual choice since
        Hoeksema 1984).
    nr : int, optional
        Radial cells (uniform in ln r) between 1 and ``source_surface``; default
        40 (resolution error: module notes).
    shape, polar_fill, polar_cap, zero_point
        Passed to `prepare_synoptic_map`.

    Returns
    -------
    `sunkit_magex.pfss.Output`
        The solution; ``.source_surface_br`` is the source-surface field map,
        ``.input_map`` the prepared map.

    Raises
    ------
    ImportError
        If sunkit-magex is not installed (``pip install 'gongsynth[pfss]'``).
    """
    rss = _source_surface_radius(source_surface)
    if isinstance(nr, bool) or not isinstance(nr, (int, np.integer)) or nr < 4:
        raise ValueError(f"nr must be an integer >= 4 (radial cells), got {nr!r}")
    ready = prepare_synoptic_map(synoptic_map, shape=shape, polar_fill=polar_fill, polar_cap=polar_cap,
                                 zero_point=zero_point)
    pfss = import_optional("sunkit_magex.pfss", "pfss")  # after the checks: bad input is named first
    solver = import_optional("sunkit_magex.pfss.pfss", "pfss")
    with _plain_numpy_kernels(solver):
        return pfss.pfss(pfss.Input(ready, int(nr), rss))


def source_surface_flux(solution):
    r"""
    Total unsigned flux through the source surface of a PFSS solution, in Mx.

    Parameters
    ----------
    solution : `sunkit_magex.pfss.Output`
        E.g. from `pfss_extrapolation`.

    Returns
    -------
    `~astropy.units.Quantity`
        :math:`R_\mathrm{ss}^2 R_\odot^2 \sum |B_r(R_\mathrm{ss})| \Delta s \Delta\phi` in Mx
        (both polarities; :math:`R_\odot` from ``astropy.constants.R_sun``).
    """
    grid = solution.grid
    br = solution.bc[0][:, :, -1]  # on the faces at r = R_ss
    area = (grid.rss * const.R_sun) ** 2 * grid.ds * grid.dp
    return (np.abs(br).sum() * area).to(u.Mx)


def open_flux(synoptic_map, *, source_surface=2.5, nr=40, shape=_DEFAULT_SHAPE, polar_fill="nearest",
              polar_cap=None, zero_point="subtract"):
    r"""
    Unsigned open flux of a synoptic map by PFSS extrapolation (sunkit-magex), in Mx.

    The **total** unsigned flux through the source surface, both polarities
    (twice the flux of either polarity).  Compare it with `in_situ_open_flux`,
    which follows the same convention.

    Parameters
    ----------
    synoptic_map : `~sunpy.map.GenericMap`
        Full-Sun Carrington synoptic map of the radial field in G (GONG or HMI,
        raw or `gongsynth.calibrate`\ d).
    source_surface : float or `~astropy.units.Quantity`, optional
        Source-surface radius in solar radii; default 2.5.
    nr : int, optional
        Radial cells (uniform in ln r); default 40: the open flux is high by
        about 0.42/nr, 1 % (module notes).
    shape : tuple of int, optional
        (n_sinlat, n_lon) grid the map is resampled to by exact area
        weighting; default (90, 180).
    polar_fill : {"nearest", "zero", "none"}, optional
        Treatment of NaN (and ``polar_cap``) pixels; default "nearest".
    polar_cap : `~astropy.units.Quantity`, optional
        Latitude poleward of which pixels are replaced by ``polar_fill``.
    zero_point : {"subtract", "balance"}, optional
        Removal of the map's net flux; default "subtract" (the mean field).

    Returns
    -------
    `~astropy.units.Quantity`
        Open flux in Mx.

    Raises
    ------
    ImportError
        Without sunkit-magex (``pip install 'gongsynth[pfss]'``).
    TypeError, ValueError
        Bad map or options (see `prepare_synoptic_map`).

    Notes
    -----
    See the module documentation (`gongsynth.analysis.open_flux`) for the
    preparation of the map and the resolution error.
    """
    return source_surface_flux(pfss_extrapolation(
        synoptic_map, source_surface=source_surface, nr=nr, shape=shape, polar_fill=polar_fill,
        polar_cap=polar_cap, zero_point=zero_point))


@u.quantity_input
def in_situ_open_flux(radial_field: u.G, distance: u.AU = 1 * u.AU):
    r"""
    Total unsigned open flux from the radial field measured in situ: :math:`4\pi r^2 |B_r|`.

    The heliospheric |B_r| r² is about independent of latitude (Ulysses:
    Smith & Balogh 1995, GRL 22, 3317), so one spacecraft's |B_r| at distance
    r, averaged over a rotation, stands for the whole sphere (Owens et al.
    2008, JGR 113, A12103; Lockwood et al. 2009, JGR 114, A11104 for the
    "excess flux" this counts when the field folds back).

    Parameters
    ----------
    radial_field : `~astropy.units.Quantity`
        Mean |B_r| at ``distance`` (e.g. nT), or |B_r| r² with ``distance`` = 1 AU.
    distance : `~astropy.units.Quantity`, optional
        Heliocentric distance; default 1 AU.

    Returns
    -------
    `~astropy.units.Quantity`
        Both polarities, in Mx.

    Examples
    --------
    >>> import astropy.units as u
    >>> round(float(in_situ_open_flux(2.5 * u.nT).to_value(u.Mx)) / 1e22, 2)  # Badman et al. 2021
    7.03
    """
    flux = 4 * np.pi * distance**2 * np.abs(radial_field)
    return flux.to(u.Mx)
