r"""
Scenes: the light at the telescope, on a supersampled helioprojective grid.

A `Scene` holds six channel planes (or any stack) of radiance at Earth per
arcsec² on a grid finer than GONG's pixels, the grid's pixel scale, the edge
handling the PSF must use, and a helioprojective WCS (observer at Earth).

**Tiled mode** (the paper's, Sec. 3.2 and Fig. 8): periodic copies of the
input tile (a small simulation box) cover the detector field.  With
``resolutions=(1, 2, 4, 8)`` quadrant k (0 bottom-left, 1 bottom-right,
2 top-left, 3 top-right; rows run south to north) shows the tile magnified by
2^k about the field centre, which is the same as an instrument with 2^k times
better resolution; ``resolutions=(1,)`` gives a uniform GONG-resolution
field.  The tile is foreshortened by μ = cos(latitude − B0) along the
north-south axis and placed with its centre at heliographic (Stonyhurst)
latitude ``latitude`` on the central meridian, seen from Earth at
``obstime``.  The WCS is true for resolution 1.  Angles follow from the
physical size of the tile and the distance from the observer to the tile
centre (≈ 722 km per arcsec at disk centre).

Resampling the tile onto the sky grid averages the tile's bilinear
interpolant over each sky pixel's footprint.  This low-pass filter avoids
aliasing when the tile's 96 km columns are finer than the 0.5″ sky pixels,
reduces to bilinear interpolation when they are coarser, and conserves flux.
Every placement function works on any stack ``(k, ny, nx)``, so the true
B_LOS is placed exactly like the light.

Radiometry: specific intensity is conserved along a ray, so the radiance at
Earth per arcsec² is the radiance at the Sun times the solid angle of one
arcsec² (`radiance_at_earth`).
"""
import math

import astropy.units as u
import numpy as np
import scipy.sparse
from astropy.coordinates import SkyCoord
from astropy.time import Time

from .instrument import resolve_instrument
from .planes import N_PLANES
from .validation import check_finite, check_quantity

__all__ = [
    "DEFAULT_OBSTIME",
    "EARTH_RADIANCE_UNIT",
    "Scene",
    "radiance_at_earth",
    "viewing_geometry",
    "field_centre",
    "sky_grid",
    "tile",
    "tiled_scenes",
    "tiled_scene",
    "wcs_header",
]

#: Default observation time: B0 = -0.3″ (the Sun's equator faces Earth), 1.0148 au.
DEFAULT_OBSTIME = Time("2019-06-07T00:20:00", scale="utc")

#: Unit of a Scene: radiance at Earth per arcsec², integrated over wavelength.
EARTH_RADIANCE_UNIT = u.Unit("erg / (s cm2 arcsec2)")

_SPECTRAL_EARTH_UNIT = u.Unit("erg / (s cm3 arcsec2)")


class Scene:
    """
    Light arriving at the telescope on a supersampled helioprojective grid.

    Parameters
    ----------
    data : `~astropy.units.Quantity`
        The light: shape (6, NY, NX), radiance at Earth per arcsec² in
        erg s⁻¹ cm⁻² arcsec⁻².  A scene may also carry any other stack
        (k, NY, NX) or map (NY, NX) placed with the same geometry, in any unit
        (e.g. the true B_LOS in G).
    pixel_scale : `~astropy.units.Quantity`
        Grid spacing in arcsec (the same along both axes).
    header : `astropy.io.fits.Header` or dict
        Helioprojective WCS of the grid (`wcs_header`).
    boundary : {"periodic", "zero", "reflect"}
        Edge handling for the PSF (`gongsynth.optics.convolve`).
    instrument : `~gongsynth.GONGInstrument`, optional
    detector_shape : (int, int), optional
        The detector grid that covers the same field; default: the field
        divided by ``instrument.plate_scale``.
    blos : `~astropy.units.Quantity`, optional
        True line-of-sight field (NY, NX) in G, placed exactly like the light.
    centre : `~astropy.coordinates.SkyCoord`, optional
        Helioprojective coordinate of the field centre.
    meta : dict, optional
        How the scene was built (mode, latitude, resolutions, ...).
    placer : callable, optional
        ``placer(stack, pixel_size)`` places another stack with the scene's
        geometry (see `place`).
    regions : list, optional
        ``(row slice, column slice, magnification)`` of each region of the
        supersampled grid (tiled scenes); default: one region at magnification 1.

    Examples
    --------
    >>> import astropy.units as u, numpy as np
    >>> data = np.ones((6, 10, 10)) * EARTH_RADIANCE_UNIT
    >>> scene = Scene(data, 0.5 * u.arcsec, {}, boundary="periodic")
    >>> scene.detector_shape
    (2, 2)
    """

    def __init__(self, data, pixel_scale, header, *, boundary, instrument=None, detector_shape=None,
                 blos=None, centre=None, meta=None, placer=None, regions=None):
        from .optics import BOUNDARIES
        if not isinstance(data, u.Quantity):
            raise TypeError(f"data must be an astropy Quantity, got {type(data).__name__}")
        if data.ndim not in (2, 3):
            raise ValueError(f"data must have shape (k, ny, nx) or (ny, nx), got {data.shape}")
        check_quantity(pixel_scale, u.arcsec, "pixel_scale")
        if boundary not in BOUNDARIES:
            raise ValueError(f"boundary must be one of {BOUNDARIES}, got {boundary!r}")
        self.data = data
        self.pixel_scale = pixel_scale.to(u.arcsec)
        self.header = header
        self.boundary = boundary
        self.instrument = resolve_instrument(instrument)
        if detector_shape is None:
            ratio = (self.pixel_scale / self.instrument.plate_scale).to_value(u.one)
            detector_shape = tuple(int(round(n * ratio)) for n in data.shape[-2:])
        self.detector_shape = tuple(int(n) for n in detector_shape)
        if blos is not None:
            check_quantity(blos, u.G, "blos")
            if blos.shape != data.shape[-2:]:
                raise ValueError(f"blos must have shape {data.shape[-2:]}, got {blos.shape}")
        self.blos = blos
        self.centre = centre
        self.meta = dict(meta or {})
        self._placer = placer
        self.regions = (list(regions) if regions is not None
                        else [(slice(0, data.shape[-2]), slice(0, data.shape[-1]), 1.0)])

    @property
    def shape(self):
        """(nplanes, NY, NX) or (NY, NX)."""
        return self.data.shape

    def resolution_map(self, instrument=None):
        """
        Magnification of the input at each detector pixel (1 = GONG resolution).

        Parameters
        ----------
        instrument : `~gongsynth.GONGInstrument`, optional
            Unused (the scene knows its detector grid); accepted for symmetry.

        Returns
        -------
        `numpy.ndarray`
            float64 (ny_det, nx_det): the magnification of the region holding
            each detector pixel's centre (2**k in quadrant k of a Fig. 8 scene).
        """
        ny, nx = self.data.shape[-2:]
        ndy, ndx = self.detector_shape
        rows = ((np.arange(ndy) + 0.5) * ny / ndy).astype(int)
        cols = ((np.arange(ndx) + 0.5) * nx / ndx).astype(int)
        out = np.ones((ndy, ndx))
        for rs, cs, mag in self.regions:
            sel_r = (rows >= rs.start) & (rows < rs.stop)
            sel_c = (cols >= cs.start) & (cols < cs.stop)
            out[np.ix_(sel_r, sel_c)] = mag
        return out

    @property
    def detector_header(self):
        """WCS header of the detector grid (``instrument.plate_scale``) over the same field."""
        if self.centre is None:
            raise ValueError("this scene has no centre coordinate, so no detector WCS")
        return wcs_header(self.detector_shape, self.instrument.plate_scale, self.centre,
                          self.instrument)

    def place(self, stack, pixel_size):
        """
        Place another stack (e.g. a continuum or truth map) with this scene's geometry.

        Parameters
        ----------
        stack : array_like or `~astropy.units.Quantity`
            (k, ny, nx) or (ny, nx) on the input grid of the scene (the tile for
            tiled scenes, the periodic photosphere for full-disk scenes).
        pixel_size : `~astropy.units.Quantity`
            Size of one input column (km).

        Returns
        -------
        `numpy.ndarray` or `~astropy.units.Quantity`
            Same leading shape, on the scene grid; unit kept.
        """
        if self._placer is None:
            raise ValueError("this scene was built from data and cannot place other stacks")
        return self._placer(stack, pixel_size)

    def __repr__(self):
        return (f"<Scene {self.meta.get('mode', '')} {'×'.join(map(str, self.shape))} "
                f"at {self.pixel_scale:g}, detector {self.detector_shape}, boundary={self.boundary}>")


def radiance_at_earth(radiance):
    """
    Convert radiance at the Sun (per steradian) to radiance at Earth per arcsec².

    Specific intensity is conserved along a ray in vacuum, so only the solid
    angle unit changes: 1 arcsec² = 2.35e-11 sr.

    Parameters
    ----------
    radiance : `~astropy.units.Quantity`
        Radiance in erg s⁻¹ cm⁻² sr⁻¹ (channel images, integrated over
        wavelength) or spectral radiance in erg s⁻¹ cm⁻² sr⁻¹ cm⁻¹ (or any
        convertible unit).

    Returns
    -------
    `~astropy.units.Quantity`
        In erg s⁻¹ cm⁻² arcsec⁻² or erg s⁻¹ cm⁻³ arcsec⁻² (the paper's unit).

    Examples
    --------
    >>> import astropy.units as u
    >>> r = radiance_at_earth(3e14 * u.Unit("erg / (s cm2 sr cm)"))
    >>> round(float(r.value), 2), r.unit == u.Unit("erg / (s cm3 arcsec2)")
    (7051.33, True)
    """
    if not isinstance(radiance, u.Quantity):
        check_quantity(radiance, u.Unit("erg / (s cm2 sr)"), "radiance")  # raises TypeError
    for unit in (EARTH_RADIANCE_UNIT, _SPECTRAL_EARTH_UNIT):
        if radiance.unit.is_equivalent(unit):
            return radiance.to(unit)
    raise u.UnitsError(
        f"radiance must be a radiance per solid angle, erg / (s cm2 sr), optionally per unit "
        f"wavelength, erg / (s cm2 sr cm); got {radiance.unit}"
    )


def _latitude_deg(latitude):
    check_quantity(latitude, u.deg, "latitude")
    value = float(latitude.to_value(u.deg))
    if not -90 < value < 90:
        raise ValueError(f"latitude must lie strictly between -90 and 90 deg, got {latitude}")
    return value


def _obstime(obstime):
    if obstime is None:
        return DEFAULT_OBSTIME
    try:
        return Time(obstime)
    except ValueError as err:
        raise ValueError(f"obstime must be an astropy Time or a time string, got {obstime!r}") from err


@u.quantity_input
def viewing_geometry(latitude: u.deg, obstime=None):
    """
    Viewing angle of a region on the central meridian, for `~gongsynth.photosphere.synthesize`.

    Parameters
    ----------
    latitude : `~astropy.units.Quantity`
        Heliographic latitude, strictly between -90° and 90°.
    obstime : `~astropy.time.Time` or str, optional
        Default `DEFAULT_OBSTIME` (B0 ≈ 0).

    Returns
    -------
    mu : float
        cos(latitude − B0) (observer at infinity; the 0.23° parallax of a
        point at 60° seen from 1 au is ignored, as in the paper).
    los_azimuth : `~astropy.units.Quantity`
        -90° when the observer lies toward the south of the region (latitude
        above B0), +90° otherwise (CONTRACTS sign convention).

    Examples
    --------
    >>> import astropy.units as u
    >>> mu, az = viewing_geometry(60 * u.deg)
    >>> round(mu, 4), az
    (0.5, <Quantity -90. deg>)
    """
    from sunpy.coordinates import sun
    lat = _latitude_deg(latitude)
    b0 = float(sun.B0(_obstime(obstime)).to_value(u.deg))
    mu = math.cos(math.radians(lat - b0))
    return mu, (-90.0 if lat >= b0 else 90.0) * u.deg


@u.quantity_input
def field_centre(latitude: u.deg, obstime=None):
    """
    Helioprojective coordinate of a point at ``latitude`` on the central meridian.

    Parameters
    ----------
    latitude : `~astropy.units.Quantity`
        Heliographic Stonyhurst latitude, strictly between -90° and 90°.
    obstime : `~astropy.time.Time` or str, optional
        Default `DEFAULT_OBSTIME`.

    Returns
    -------
    centre : `~astropy.coordinates.SkyCoord`
        In `~sunpy.coordinates.Helioprojective`, observer at Earth.
    km_per_arcsec : `~astropy.units.Quantity`
        Length on the Sun's surface per arcsec of sky at that point, for a
        surface perpendicular to the line of sight (distance × 1″).

    Examples
    --------
    >>> import astropy.units as u
    >>> centre, scale = field_centre(0 * u.deg)
    >>> round(float(scale.to_value(u.km / u.arcsec)), 1)
    732.7
    """
    from sunpy.coordinates import HeliographicStonyhurst, Helioprojective, get_earth
    from sunpy.sun.constants import radius
    lat = _latitude_deg(latitude)
    time = _obstime(obstime)
    point = SkyCoord(0 * u.deg, lat * u.deg, radius, frame=HeliographicStonyhurst(obstime=time))
    hpc = point.transform_to(Helioprojective(observer=get_earth(time), obstime=time))
    km_per_arcsec = hpc.distance.to(u.km) * u.arcsec.to(u.rad) / u.arcsec
    # Keep the 2-D direction only: sunpy then intersects pixels with the solar sphere.
    centre = SkyCoord(hpc.Tx, hpc.Ty, frame=hpc.frame.replicate_without_data())
    return centre, km_per_arcsec


def _pair(value, name):
    if np.ndim(value) == 0:
        value = (value, value)
    try:
        pair = tuple(int(v) for v in value)
    except (TypeError, ValueError) as err:
        raise TypeError(f"{name} must be an int or a pair of ints, got {value!r}") from err
    if len(pair) != 2 or min(pair) < 1 or any(int(v) != v for v in value):
        raise ValueError(f"{name} must be a positive int or a pair of positive ints, got {value!r}")
    return pair


def sky_grid(instrument=None, *, detector_shape=None, shape=None):
    """
    Supersampled grid over the detector field.

    Parameters
    ----------
    instrument : `~gongsynth.GONGInstrument`, optional
    detector_shape : int or (int, int), optional
        Detector pixels; default ``instrument.detector_shape`` (860).
    shape : int or (int, int), optional
        Samples of the supersampled grid over the same field; default
        ``instrument.supersampling`` × ``detector_shape`` (exactly 5 samples per
        pixel, so pixelization needs no interpolation).  The paper used 4096².

    Returns
    -------
    shape : (int, int)
    pixel_scale : `~astropy.units.Quantity`
        Arcsec per sample (the same along both axes).
    detector_shape : (int, int)

    Examples
    --------
    >>> sky_grid(detector_shape=64)[:2]
    ((320, 320), <Quantity 0.5 arcsec>)
    """
    inst = resolve_instrument(instrument)
    det = _pair(inst.detector_shape if detector_shape is None else detector_shape, "detector_shape")
    grid = (tuple(n * inst.supersampling for n in det) if shape is None
            else _pair(shape, "shape"))
    plate = inst.plate_scale.to_value(u.arcsec)
    scales = [d * plate / n for d, n in zip(det, grid)]
    if not math.isclose(scales[0], scales[1], rel_tol=1e-9):
        raise ValueError(f"shape {grid} and detector_shape {det} give different pixel scales along y and x")
    return grid, scales[0] * u.arcsec, det


def wcs_header(shape, pixel_scale, centre, instrument=None):
    """
    Helioprojective FITS-WCS header of a grid centred on ``centre``.

    Parameters
    ----------
    shape : (int, int)
        (ny, nx) of the grid.
    pixel_scale : `~astropy.units.Quantity`
        Arcsec per pixel.
    centre : `~astropy.coordinates.SkyCoord`
        Helioprojective coordinate (with observer and obstime) of the field
        centre, which lies at pixel ((nx - 1) / 2, (ny - 1) / 2); solar north up.
    instrument : `~gongsynth.GONGInstrument`, optional
        Supplies the wavelength.

    Returns
    -------
    `sunpy.util.MetaDict`
        From `sunpy.map.make_fitswcs_header`.

    Examples
    --------
    >>> import astropy.units as u
    >>> centre, _ = field_centre(60 * u.deg)
    >>> header = wcs_header((100, 200), 0.5 * u.arcsec, centre)
    >>> float(header["crpix1"]), float(header["cdelt2"]), header["ctype2"]
    (100.5, 0.5, 'HPLT-TAN')
    """
    import sunpy.map
    inst = resolve_instrument(instrument)
    ny, nx = shape
    scale = pixel_scale.to_value(u.arcsec)
    return sunpy.map.make_fitswcs_header(
        (ny, nx), centre,
        reference_pixel=[(nx - 1) / 2, (ny - 1) / 2] * u.pix,
        scale=[scale, scale] * u.arcsec / u.pix,
        telescope="GONG (simulated)", instrument="gongsynth",
        wavelength=inst.line_wavelength.to(u.AA),
    )


# ------------------------------------------------------------------ tiling
def _hat_antiderivative(t):
    """∫ of the unit hat (support |t| < 1) from -inf to t."""
    t = np.clip(t, -1.0, 1.0)
    return np.where(t <= 0, 0.5 * (t + 1) ** 2, 1 - 0.5 * (1 - t) ** 2)


def _footprint_operator(centres, width, n_tile):
    """
    Sparse (n_out, n_tile) operator: mean of the periodic bilinear interpolant over footprints.

    ``centres`` are footprint centres and ``width`` their width, in tile
    pixels; tile sample n sits at coordinate n + 0.5.  Rows sum to 1.
    """
    a = centres - width / 2
    b = centres + width / 2
    first = np.floor(a - 0.5).astype(np.int64) - 1
    span = int(np.max(np.floor(b - 0.5).astype(np.int64) - first)) + 3
    n = first[:, None] + np.arange(span)[None, :]
    weight = (_hat_antiderivative(b[:, None] - n - 0.5)
              - _hat_antiderivative(a[:, None] - n - 0.5)) / width
    rows = np.repeat(np.arange(centres.size), span)
    op = scipy.sparse.csr_matrix((weight.ravel(), (rows, (n % n_tile).ravel())),
                                 shape=(centres.size, n_tile))
    op.sum_duplicates()
    op.eliminate_zeros()
    return op


def _check_resolutions(resolutions):
    try:
        res = tuple(float(r) for r in resolutions)
    except TypeError as err:
        raise TypeError(f"resolutions must be a sequence of numbers, got {resolutions!r}") from err
    if len(res) not in (1, 4) or not all(math.isfinite(r) and r > 0 for r in res):
        raise ValueError(
            f"resolutions must hold 1 (uniform field) or 4 (quadrants) positive factors, got {resolutions!r}"
        )
    return res


def _quadrants(shape, resolutions, detector_shape):
    """(row slice, column slice, magnification) for each region of the grid."""
    ny, nx = shape
    if len(resolutions) == 1:
        return [(slice(0, ny), slice(0, nx), resolutions[0])]
    # Split on a detector-pixel boundary so every GONG pixel has one resolution.
    ndy, ndx = detector_shape
    hy, hx = int(round(ndy // 2 * ny / ndy)), int(round(ndx // 2 * nx / ndx))
    spans = [(slice(0, hy), slice(0, hx)), (slice(0, hy), slice(hx, nx)),
             (slice(hy, ny), slice(0, hx)), (slice(hy, ny), slice(hx, nx))]
    return [(r, c, m) for (r, c), m in zip(spans, resolutions)]


def _tile_stack(values, pixel_km, shape, scale, km_per_arcsec, mu, regions):
    """Core of `tile` on plain float arrays (k, ny, nx) -> (k, NY, NX)."""
    k, ny, nx = values.shape
    NY, NX = shape
    out = np.empty((k, NY, NX))
    # Sky offsets of pixel centres from the field centre, arcsec.
    y_sky = (np.arange(NY) + 0.5 - NY / 2) * scale
    x_sky = (np.arange(NX) + 0.5 - NX / 2) * scale
    for rows, cols, mag in regions:
        per_px_x = km_per_arcsec / (mag * pixel_km)       # tile pixels per arcsec along x
        per_px_y = km_per_arcsec / (mag * mu * pixel_km)  # ... along y (foreshortened)
        opy = _footprint_operator(ny / 2 + y_sky[rows] * per_px_y, scale * per_px_y, ny)
        opx = _footprint_operator(nx / 2 + x_sky[cols] * per_px_x, scale * per_px_x, nx)
        for i in range(k):
            # Small side first, and the big product lands in C order (no transposed writes).
            narrow = np.ascontiguousarray((opx @ values[i].T).T)  # (ny, NXq)
            out[i, rows, cols] = opy @ narrow
    return out


@u.quantity_input
def tile(stack, pixel_size: u.km, *, latitude: u.deg = 0 * u.deg, resolutions=(1, 2, 4, 8),
         obstime=None, instrument=None, detector_shape=None, shape=None):
    """
    Cover the detector field with periodic copies of a tile (any stack).

    Parameters
    ----------
    stack : array_like or `~astropy.units.Quantity`
        (k, ny, nx) or (ny, nx): maps on the tile's grid (channel planes,
        B_LOS, continuum, ...); axis -2 is north, axis -1 west.  Unit kept.
    pixel_size : `~astropy.units.Quantity`
        Horizontal size of one tile column (km).
    latitude : `~astropy.units.Quantity`
        Heliographic latitude of the field centre on the central meridian,
        strictly between -90° and 90°.  Sets the foreshortening μ (see
        `viewing_geometry`) and the angular scale (`field_centre`).
    resolutions : sequence of 1 or 4 positive numbers
        Magnification of the tile in the whole field, or in the quadrants
        (bottom-left, bottom-right, top-left, top-right).  Default (1, 2, 4, 8).
    obstime : `~astropy.time.Time` or str, optional
        Default `DEFAULT_OBSTIME`.
    instrument : `~gongsynth.GONGInstrument`, optional
    detector_shape, shape : int or (int, int), optional
        Detector pixels and supersampled grid (see `sky_grid`).

    Returns
    -------
    `numpy.ndarray` or `~astropy.units.Quantity`
        (k, NY, NX) (or (NY, NX)) float64 on the supersampled grid.

    Raises
    ------
    ValueError
        If the latitude is out of range or the tile, at resolution 1 and
        foreshortened, is smaller than one detector pixel.

    Examples
    --------
    >>> import astropy.units as u, numpy as np
    >>> sky = tile(np.ones((32, 32)), 96 * u.km, detector_shape=16)
    >>> sky.shape, bool(np.allclose(sky, 1))
    ((80, 80), True)
    """
    lat = _latitude_deg(latitude)
    unit = stack.unit if isinstance(stack, u.Quantity) else None
    values = np.asarray(stack.value if unit is not None else stack, dtype=float)
    squeeze = values.ndim == 2
    if squeeze:
        values = values[None]
    if values.ndim != 3:
        raise ValueError(f"stack must have shape (k, ny, nx) or (ny, nx), got {np.shape(stack)}")
    check_finite(values, "stack")
    inst = resolve_instrument(instrument)
    res = _check_resolutions(resolutions)
    grid, scale, det = sky_grid(inst, detector_shape=detector_shape, shape=shape)
    mu, _ = viewing_geometry(lat * u.deg, obstime)
    _, km_per_arcsec = field_centre(lat * u.deg, obstime)
    kpa = km_per_arcsec.to_value(u.km / u.arcsec)
    pix = pixel_size.to_value(u.km)
    if not (math.isfinite(pix) and pix > 0):
        raise ValueError(f"pixel_size must be positive and finite, got {pixel_size}")
    plate = inst.plate_scale.to_value(u.arcsec)
    ny, nx = values.shape[1:]
    extent = (ny * pix * mu * min(res) / kpa, nx * pix * min(res) / kpa)  # arcsec on the sky
    if min(extent) < plate:
        raise ValueError(
            f"the tile ({ny}×{nx} columns of pixel_size {pixel_size:g}) spans only "
            f"{extent[0]:.3g}″ × {extent[1]:.3g}″ on the sky at latitude {lat:g} deg (μ = {mu:.3g}): "
            f"smaller than one {plate:g}″ detector pixel"
        )
    out = _tile_stack(values, pix, grid, scale.to_value(u.arcsec), kpa, mu,
                      _quadrants(grid, res, det))
    if squeeze:
        out = out[0]
    return out if unit is None else u.Quantity(out, unit, copy=False)


@u.quantity_input
def tiled_scenes(channels, blos, pixel_size: u.km, *, latitude: u.deg = 0 * u.deg,
                 resolutions=(1, 2, 4, 8), obstime=None, instrument=None, detector_shape=None,
                 shape=None):
    """
    The paper's tiled scene and its ground truth, placed with the same geometry.

    Parameters
    ----------
    channels : `~astropy.units.Quantity`
        Channel images at the Sun (6, ny, nx) in erg s⁻¹ cm⁻² sr⁻¹
        (`gongsynth.polarimetry.channel_images`).
    blos : `~astropy.units.Quantity` or None
        True B_LOS (ny, nx) in G on the same grid (``StokesCube.blos``).
    pixel_size : `~astropy.units.Quantity`
        Tile column size (km).
    latitude, resolutions, obstime, instrument, detector_shape, shape
        As in `tile`.

    Returns
    -------
    light : `Scene`
        Radiance at Earth per arcsec² (6, NY, NX).  Boundary ``"periodic"``
        when the field holds a whole number of tiles at a single resolution,
        else ``"reflect"`` (the tiling continues smoothly past the edges).
    truth : `Scene` or None
        B_LOS (NY, NX) in G, same grid, boundary and WCS.

    Examples
    --------
    >>> import astropy.units as u, numpy as np
    >>> planes = np.full((6, 64, 64), 1.5e6) * u.Unit("erg / (s cm2 sr)")
    >>> light, truth = tiled_scenes(planes, np.zeros((64, 64)) * u.G, 96 * u.km, detector_shape=32)
    >>> light.shape, truth.shape, light.detector_shape
    ((6, 160, 160), (160, 160), (32, 32))
    """
    from .polarimetry import CHANNEL_UNIT
    inst = resolve_instrument(instrument)
    lat = _latitude_deg(latitude)
    check_quantity(channels, CHANNEL_UNIT, "channels")
    if channels.ndim != 3 or channels.shape[0] != N_PLANES:
        raise ValueError(f"channels must have shape (6, ny, nx), got {channels.shape}")
    if blos is not None:
        check_quantity(blos, u.G, "blos")
        if blos.shape != channels.shape[1:]:
            raise ValueError(f"blos must have shape {channels.shape[1:]} like channels, got {blos.shape}")
    kwargs = dict(latitude=lat * u.deg, resolutions=resolutions, obstime=obstime, instrument=inst,
                  detector_shape=detector_shape, shape=shape)
    # Tiling is linear: convert the small tile to radiance at Earth, not the big scene.
    data = tile(radiance_at_earth(channels), pixel_size, **kwargs)
    mu, los_azimuth = viewing_geometry(lat * u.deg, obstime)
    grid, scale, det = sky_grid(inst, detector_shape=detector_shape, shape=shape)
    centre, km_per_arcsec = field_centre(lat * u.deg, obstime)
    res = _check_resolutions(resolutions)
    # Periodic only if the field holds whole tiles (one resolution, both axes).
    kpa = km_per_arcsec.to_value(u.km / u.arcsec)
    periods = [n * pixel_size.to_value(u.km) * f * res[0] / kpa
               for n, f in zip(channels.shape[1:], (mu, 1.0))]
    fields = [n * scale.to_value(u.arcsec) for n in grid]
    whole = all(abs(f / p - round(f / p)) < 1e-6 for f, p in zip(fields, periods))
    boundary = "periodic" if len(res) == 1 and whole else "reflect"

    def placer(stack, size):
        return tile(stack, size, **kwargs)

    meta = dict(mode="tiled", latitude=lat * u.deg, resolutions=res, mu=mu, los_azimuth=los_azimuth,
                obstime=_obstime(obstime), km_per_arcsec=km_per_arcsec,
                tile_pixel_size=pixel_size.to(u.km))
    common = dict(boundary=boundary, instrument=inst, detector_shape=det, centre=centre,
                  placer=placer, regions=_quadrants(grid, res, det))
    header = wcs_header(grid, scale, centre, inst)
    truth = None
    if blos is not None:
        truth = Scene(placer(blos, pixel_size).to(u.G), scale, header, meta={**meta, "quantity": "blos"},
                      **common)
    light = Scene(data, scale, header, blos=None if truth is None else truth.data,
                  meta={**meta, "quantity": "radiance"}, **common)
    return light, truth


@u.quantity_input
def tiled_scene(stokes, *, latitude: u.deg = 0 * u.deg, resolutions=(1, 2, 4, 8), obstime=None,
                instrument=None, detector_shape=None, shape=None, mueller=None):
    """
    The paper's scene from a Stokes cube: filter first, then tile.

    Parameters
    ----------
    stokes : `~gongsynth.stokes.StokesCube`
        Spectra of the tile; its μ must match the latitude (see
        `viewing_geometry`) to within 0.01.  Its ``blos`` (if any) becomes the
        scene's ``blos``.
    latitude, resolutions, obstime, instrument, detector_shape, shape
        As in `tile`.
    mueller : array_like, optional
        Instrument Mueller matrix (`gongsynth.polarimetry.channel_images`).

    Returns
    -------
    `Scene`
        Radiance at Earth per arcsec² (6, NY, NX), with ``blos`` placed alike.

    Examples
    --------
    >>> import astropy.units as u, numpy as np
    >>> from gongsynth.stokes import StokesCube
    >>> lam = np.linspace(676.73, 676.83, 51) * u.nm
    >>> I = np.full((32, 32, 51), 3e14, dtype=np.float32) * u.Unit("erg / (s cm2 sr cm)")
    >>> cube = StokesCube(I, 0 * I, 0 * I, 0 * I, lam, 192 * u.km)
    >>> tiled_scene(cube, resolutions=(1,), detector_shape=16).shape
    (6, 80, 80)
    """
    from .polarimetry import channel_images
    if not hasattr(stokes, "wavelength") or not hasattr(stokes, "pixel_size"):
        raise TypeError(f"stokes must be a StokesCube, got {type(stokes).__name__}")
    lat = _latitude_deg(latitude)
    mu, los_azimuth = viewing_geometry(lat * u.deg, obstime)
    if np.ndim(stokes.mu) != 0:
        raise ValueError("stokes has a per-column mu (a full-disk cube); tiled scenes need one mu")
    if abs(float(stokes.mu) - mu) > 0.01:
        raise ValueError(
            f"stokes was synthesised at mu = {float(stokes.mu):.4g} but latitude {lat:g} deg is "
            f"seen at mu = {mu:.4g}: synthesise it at that mu (los_azimuth {los_azimuth:g})"
        )
    inst = resolve_instrument(instrument)
    planes = channel_images(stokes, mueller=mueller, instrument=inst)
    light, _ = tiled_scenes(planes, stokes.blos, stokes.pixel_size, latitude=lat * u.deg,
                            resolutions=resolutions, obstime=obstime, instrument=inst,
                            detector_shape=detector_shape, shape=shape)
    return light
