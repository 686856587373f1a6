"""
Scenes: the light at the telescope, on a supersampled helioprojective grid.

A `Scene` holds six channel planes (or any stack) of radiance at Earth per
arcsec² on a grid finer than GONG's pixels, the grid's pixel scale, the edge
handling the PSF must use, and a helioprojective WCS (observer at Earth).

Radiometry: specific intensity is conserved along a ray, so the radiance at
Earth per arcsec² is the radiance at the Sun times the solid angle of one
arcsec² (`radiance_at_earth`).
"""
import math

import astropy.units as u
import numpy as np

from gongsynth import instruments
from gongsynth.geometry import wcs_header
from gongsynth.validation import check_quantity

__all__ = ["BOUNDARIES", "EARTH_RADIANCE_UNIT", "DeferredPlane", "DeferredStack", "Scene",
           "radiance_at_earth", "sky_grid"]

#: Edge handling a scene may ask of the PSF (`gongsynth.stages.optics.convolve`).
BOUNDARIES = ("periodic", "zero", "reflect")

#: Unit of a Scene: radiance at Earth per arcsec², integrated over wavelength.
EARTH_RADIANCE_UNIT = u.Unit("erg / (s cm2 arcsec2)")

_SPECTRAL_EARTH_UNIT = u.Unit("erg / (s cm3 arcsec2)")


class DeferredStack:
    """
    A stack of planes made on request, a block of rows at a time, never held whole.

    The supersampled scene of a tiled run is 7 × 4300² samples; its planes are
    each a cheap linear map of a small tile, so they are made where they are
    used: the optics (`gongsynth.stages.imagers.BandLimitedImager`) read one
    plane's rows block by block.  `materialize` (and a `Scene`'s ``data``)
    makes the whole stack.

    Parameters
    ----------
    shape : tuple of int
        (k, ny, nx), or (ny, nx) for a single map.
    dtype : dtype
        Of the rows made.
    unit : `~astropy.units.Unit` or None
        Of the values.
    rows : callable
        ``rows(i, start, stop)`` → (stop - start, nx) array: rows of plane ``i``.
    release : callable, optional
        Frees whatever ``rows`` keeps between calls (called by `release`).
    bands : callable, optional
        ``bands(start, stop)`` → (k, stop - start, nx) array: rows of every
        plane at once, for a maker whose planes share most of their work (a
        full-disk render); see `band`.

    Examples
    --------
    >>> import numpy as np
    >>> stack = DeferredStack((2, 3, 4), np.float32, None,
    ...                       lambda i, a, b: np.full((b - a, 4), i, dtype=np.float32))
    >>> stack.plane(1)[0:2].shape, stack.materialize().shape
    ((2, 4), (2, 3, 4))
    """

    def __init__(self, shape, dtype, unit, rows, release=None, bands=None):
        self.shape = tuple(int(n) for n in shape)
        self.dtype = np.dtype(dtype)
        self.unit = unit
        self._rows = rows
        self._release = release
        self._bands = bands

    @property
    def has_bands(self):
        """Whether `band` makes rows of every plane in one go."""
        return self._bands is not None

    def band(self, start, stop):
        """
        Rows ``start`` to ``stop - 1`` of every plane, made at once.

        Parameters
        ----------
        start, stop : int

        Returns
        -------
        `numpy.ndarray`
            (k, stop - start, nx), or (stop - start, nx) for a map.
        """
        if self._bands is not None:
            return self._bands(start, stop)
        if self.ndim == 2:
            return self._rows(0, start, stop)
        return np.stack([self._rows(i, start, stop) for i in range(self.shape[0])])

    @property
    def ndim(self):
        """Number of dimensions (3 for a stack, 2 for a map)."""
        return len(self.shape)

    def plane(self, i=0):
        """
        Plane ``i`` as an object whose row slices (``plane[a:b]``) are made on request.

        Parameters
        ----------
        i : int

        Returns
        -------
        `DeferredPlane`
        """
        return DeferredPlane(self, i)

    def __getitem__(self, i):
        """Plane ``i`` of a stack (`plane`)."""
        if self.ndim != 3 or not isinstance(i, (int, np.integer)):
            raise TypeError("a deferred stack gives its planes by integer index (stack[i]); "
                            "use materialize() for the whole stack")
        return self.plane(int(i))

    def materialize(self):
        """
        The whole stack.

        Returns
        -------
        `numpy.ndarray` or `~astropy.units.Quantity`
        """
        k = self.shape[0] if self.ndim == 3 else 1
        ny, nx = self.shape[-2:]
        out = np.empty((k, ny, nx), dtype=self.dtype)
        for i in range(k):
            out[i] = self._rows(i, 0, ny)
        self.release()
        out = out.reshape(self.shape)
        return out if self.unit is None else u.Quantity(out, self.unit, copy=False)

    def release(self):
        """Free what the row maker keeps between calls (caches)."""
        if self._release is not None:
            self._release()


class DeferredPlane:
    """
    One plane of a `DeferredStack`: ``plane[a:b]`` makes rows a..b-1.

    Parameters
    ----------
    stack : `DeferredStack`
    index : int
    """

    def __init__(self, stack, index):
        self.stack, self.index = stack, index
        self.shape = stack.shape[-2:]
        self.dtype = stack.dtype

    def __array__(self, dtype=None, copy=None):
        rows = self.stack._rows(self.index, 0, self.shape[0])
        return rows if dtype is None else rows.astype(dtype, copy=False)

    def __getitem__(self, key):
        if not isinstance(key, slice) or key.step not in (None, 1):
            raise TypeError("a deferred plane gives contiguous row slices only, e.g. plane[0:128]")
        start, stop, _ = key.indices(self.shape[0])
        return self.stack._rows(self.index, start, max(start, stop))


class Scene:
    """
    Light arriving at the telescope on a supersampled helioprojective grid.

    Parameters
    ----------
    data : `~astropy.units.Quantity` or `DeferredStack`
        The light: shape (6, NY, NX), radiance at Earth per arcsec² in
        erg s⁻¹ cm⁻² arcsec⁻².  A scene may also carry any other stack
        (k, NY, NX) or map (NY, NX) placed with the same geometry, in any unit
        (e.g. the true B_LOS in G).  A `DeferredStack` is made plane by plane
        where it is used (`planes`); ``data`` then makes it whole on first
        access and keeps it.
    pixel_scale : `~astropy.units.Quantity`
        Grid spacing in arcsec (the same along both axes).
    header : `astropy.io.fits.Header` or dict
        Helioprojective WCS of the grid (`wcs_header`).
    boundary : {"periodic", "zero", "reflect"}
        Edge handling for the PSF (`gongsynth.stages.optics.convolve`).
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
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
        if isinstance(data, DeferredStack):
            if data.unit is None:
                raise TypeError("a deferred scene stack must have a unit")
        elif not isinstance(data, u.Quantity):
            raise TypeError(f"data must be an astropy Quantity, got {type(data).__name__}")
        if data.ndim not in (2, 3):
            raise ValueError(f"data must have shape (k, ny, nx) or (ny, nx), got {data.shape}")
        check_quantity(pixel_scale, u.arcsec, "pixel_scale")
        if boundary not in BOUNDARIES:
            raise ValueError(f"boundary must be one of {BOUNDARIES}, got {boundary!r}")
        self._data = data
        self.pixel_scale = pixel_scale.to(u.arcsec)
        self.header = header
        self.boundary = boundary
        self.instrument = instruments.get(instrument)
        if detector_shape is None:
            ratio = (self.pixel_scale / self.instrument.plate_scale).to_value(u.one)
            detector_shape = tuple(int(round(n * ratio)) for n in data.shape[-2:])
        self.detector_shape = tuple(int(n) for n in detector_shape)
        if blos is not None:
            if isinstance(blos, DeferredStack):
                if not u.Unit(blos.unit).is_equivalent(u.G):
                    raise u.UnitsError(f"blos must be in G, got {blos.unit}")
            else:
                check_quantity(blos, u.G, "blos")
            if blos.shape != data.shape[-2:]:
                raise ValueError(f"blos must have shape {data.shape[-2:]}, got {blos.shape}")
        self._blos = blos
        self.centre = centre
        self.meta = dict(meta or {})
        self._placer = placer
        self.regions = (list(regions) if regions is not None
                        else [(slice(0, data.shape[-2]), slice(0, data.shape[-1]), 1.0)])

    @property
    def data(self):
        """The stack as a `~astropy.units.Quantity` (a deferred one is made whole here, once)."""
        if isinstance(self._data, DeferredStack):
            self._data = self._data.materialize()
        return self._data

    @property
    def planes(self):
        """
        The stack as it is held: a `~astropy.units.Quantity`, or a `DeferredStack` not yet made.

        Indexing either gives plane ``i`` whose row slices are what the optics read.
        """
        return self._data

    @property
    def blos(self):
        """True line-of-sight field (NY, NX) in G placed like the light, or None."""
        if isinstance(self._blos, DeferredStack):
            self._blos = self._blos.materialize()
        return self._blos

    @property
    def shape(self):
        """(nplanes, NY, NX) or (NY, NX)."""
        return self._data.shape

    def resolution_map(self, instrument=None):
        """
        Magnification of the input at each detector pixel (1 = the true size: the instrument's resolution).

        Parameters
        ----------
        instrument : `~gongsynth.instruments.base.Instrument` or str, optional
            Unused (the scene knows its detector grid); accepted for symmetry.

        Returns
        -------
        `numpy.ndarray`
            float64 (ny_det, nx_det): the magnification of the region holding
            each detector pixel's centre (2**k in quadrant k of a Fig. 8 scene).
        """
        ny, nx = self.shape[-2:]
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
                          wavelength=self.instrument.line_wavelength)

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
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
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
    inst = instruments.get(instrument)
    det = _pair(inst.detector_shape if detector_shape is None else detector_shape, "detector_shape")
    grid = (tuple(n * inst.supersampling for n in det) if shape is None
            else _pair(shape, "shape"))
    plate = inst.plate_scale.to_value(u.arcsec)
    scales = [d * plate / n for d, n in zip(det, grid)]
    if not math.isclose(scales[0], scales[1], rel_tol=1e-9):
        raise ValueError(f"shape {grid} and detector_shape {det} give different pixel scales along y and x")
    return grid, scales[0] * u.arcsec, det


