r"""
The paper's tiled scene: periodic copies of a small simulation box over the field.

**Tiled mode** (the paper's, Sec. 3.2 and Fig. 8): periodic copies of the
input tile (a small simulation box) cover the detector field.  With
``resolutions=(1, 2, 4, 8)`` quadrant k (0 bottom-left, 1 bottom-right,
2 top-left, 3 top-right; rows run south to north) shows the tile magnified by
2^k about the field centre, which is the same as an instrument with 2^k times
better resolution; ``resolutions=(1,)`` gives a uniform GONG-resolution
field.  The tile is foreshortened by μ = cos(latitude − B0) along the
north-south axis and placed with its centre at heliographic (Stonyhurst)
latitude ``pointing.latitude`` on the central meridian, seen from Earth at
``pointing.obstime`` (`~gongsynth.geometry.Pointing`).  The WCS is true for
resolution 1.  Angles follow from the physical size of the tile and the
distance from the observer to the tile centre (≈ 722 km per arcsec at disk
centre).

Resampling the tile onto the sky grid averages the tile's bilinear
interpolant over each sky pixel's footprint.  This low-pass filter avoids
aliasing when the tile's 96 km columns are finer than the 0.5″ sky pixels,
reduces to bilinear interpolation when they are coarser, and conserves flux.
Every placement function works on any stack ``(k, ny, nx)``, so the true
B_LOS is placed exactly like the light.
"""
import math

import astropy.units as u
import numpy as np
import scipy.sparse

from gongsynth import instruments
from gongsynth.geometry import Pointing, wcs_header
from gongsynth.stages.channels import CHANNEL_UNIT
from gongsynth.stages.scene._rows import sparse_rows
from gongsynth.stages.scene.scene import DeferredStack, Scene, radiance_at_earth, sky_grid
from gongsynth.threads import run_chunks
from gongsynth.validation import check_finite, check_quantity

__all__ = ["tile", "tiled_scenes", "check_tile_extent"]

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


# Fewest rows per thread: below, the threads' start and join (and, on a loaded machine, their
# waiting for each other) cost more than the work (the optics' blocks of rows stay on one thread).
_THREAD_ROWS = 512


class _Tiler:
    """
    Rows of the tiled planes on request: per region, ``opy @ (values[i] @ opx.T)``.

    The narrow product ``values[i] @ opx.T`` (tile rows × the region's sky
    columns, in the output's precision) of the first plane and of the latest one are kept, so a
    plane read block by block, alternating with the first plane (the optics'
    differences), is made once.
    """

    def __init__(self, values, pixel_km, shape, scale, km_per_arcsec, mu, regions, dtype):
        k, ny, nx = values.shape
        self.values, self.shape, self.dtype = values, tuple(shape), np.dtype(dtype)
        # Sky offsets of pixel centres from the field centre, arcsec.
        y_sky = (np.arange(shape[0]) + 0.5 - shape[0] / 2) * scale
        x_sky = (np.arange(shape[1]) + 0.5 - shape[1] / 2) * scale
        self.regions = []
        for rows, cols, mag in regions:
            per_px_x = km_per_arcsec / (mag * pixel_km)       # tile pixels per arcsec along x
            per_px_y = km_per_arcsec / (mag * mu * pixel_km)  # ... along y (foreshortened)
            opy = _footprint_operator(ny / 2 + y_sky[rows] * per_px_y, scale * per_px_y, ny)
            opx = _footprint_operator(nx / 2 + x_sky[cols] * per_px_x, scale * per_px_x, nx)
            self.regions.append((rows, cols, opy, opx))
        self._narrow = {}

    def _narrow_of(self, i):
        if i not in self._narrow:
            for j in [j for j in self._narrow if j != 0]:
                del self._narrow[j]
            # Small side first: (ny, NXq) for each region.
            self._narrow[i] = [np.ascontiguousarray((opx @ self.values[i].T).T, dtype=self.dtype)
                               for _, _, _, opx in self.regions]
        return self._narrow[i]

    def rows(self, i, start, stop):
        """Rows ``start`` .. ``stop - 1`` of plane ``i``, (stop - start, NX) of the tiler's dtype."""
        out = np.empty((stop - start, self.shape[1]), dtype=self.dtype)
        for (rows, cols, opy, _), narrow in zip(self.regions, self._narrow_of(i)):
            lo, hi = max(start, rows.start), min(stop, rows.stop)
            if lo < hi:
                run_chunks(sparse_rows, hi - lo, opy.indptr, opy.indices, opy.data, lo - rows.start, narrow,
                           out[lo - start:hi - start, cols], min_chunk=_THREAD_ROWS)
        return out

    def release(self):
        """Forget the kept narrow products."""
        self._narrow.clear()


def _tiler(values, pixel_km, shape, scale, km_per_arcsec, mu, regions, dtype=np.float64):
    """`_Tiler` of plain float arrays (k, ny, nx), computed in float64 (products kept in ``dtype``)."""
    return _Tiler(np.asarray(values, dtype=np.float64), pixel_km, shape, scale, km_per_arcsec, mu, regions,
                  dtype)


def _tile_stack(values, pixel_km, shape, scale, km_per_arcsec, mu, regions, dtype=np.float64):
    """Core of `tile` on plain float arrays (k, ny, nx) -> (k, NY, NX) of ``dtype``."""
    tiler = _tiler(values, pixel_km, shape, scale, km_per_arcsec, mu, regions, dtype)
    out = np.empty((values.shape[0],) + tuple(shape), dtype=dtype)
    for i in range(values.shape[0]):
        out[i] = tiler.rows(i, 0, shape[0])
    tiler.release()
    return out


@u.quantity_input
def check_tile_extent(shape, pixel_size, pointing, resolutions, instrument=None):
    """
    Refuse a tile that, foreshortened at the pointing, is smaller than one detector pixel.

    Cheap: called before the spectra are computed as well as when tiling.

    Parameters
    ----------
    shape : (int, int)
        The tile's columns (ny, nx).
    pixel_size : `~astropy.units.Quantity`
        Their spacing (length).
    pointing : `~gongsynth.geometry.Pointing`
    resolutions : sequence of positive numbers
        The tile's magnifications.
    instrument : `~gongsynth.GONGInstrument`, optional

    Raises
    ------
    ValueError
        Naming the tile, its extent on the sky and what to change.

    Examples
    --------
    >>> import astropy.units as u
    >>> from gongsynth.geometry import Pointing
    >>> check_tile_extent((64, 64), 1536 * u.km, Pointing(89.5 * u.deg), (1,))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: the tile (64×64 columns of pixel_size 1536 km) spans only 1.17″ × 134″ on the sky ...
    """
    inst = instruments.get(instrument)
    plate = inst.plate_scale.to_value(u.arcsec)
    pix = pixel_size.to_value(u.km)
    mu = pointing.mu
    kpa = pointing.km_per_arcsec.to_value(u.km / u.arcsec)
    ny, nx = shape
    extent = (ny * pix * mu * min(resolutions) / kpa, nx * pix * min(resolutions) / kpa)  # arcsec on the sky
    if min(extent) < plate:
        raise ValueError(
            f"the tile ({ny}×{nx} columns of pixel_size {pixel_size:g}) spans only "
            f"{extent[0]:.3g}″ × {extent[1]:.3g}″ on the sky at latitude {pointing.latitude:g} "
            f"(μ = {mu:.3g}): smaller than one {plate:g}″ detector pixel; choose a latitude nearer the "
            f"disk centre or a larger photosphere (photosphere_shape × photosphere_pixel_size)"
        )


def tile(stack, pixel_size: u.km, *, pointing=None, resolutions=(1, 2, 4, 8), instrument=None,
         detector_shape=None, shape=None, dtype=np.float64, deferred=False):
    """
    Cover the detector field with periodic copies of a tile (any stack).

    Parameters
    ----------
    stack : array_like or `~astropy.units.Quantity`
        (k, ny, nx) or (ny, nx): maps on the tile's grid (channel planes,
        B_LOS, continuum, ...); axis -2 is north, axis -1 west.  Unit kept.
    pixel_size : `~astropy.units.Quantity`
        Horizontal size of one tile column (km).
    pointing : `~gongsynth.geometry.Pointing`, optional
        Where the field lies (default: disk centre at the default time).  Sets
        the foreshortening μ and the angular scale (km per arcsec).
    resolutions : sequence of 1 or 4 positive numbers
        Magnification of the tile in the whole field, or in the quadrants
        (bottom-left, bottom-right, top-left, top-right).  Default (1, 2, 4, 8).
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
    detector_shape, shape : int or (int, int), optional
        Detector pixels and supersampled grid (see `sky_grid`).
    dtype : {numpy.float64, numpy.float32}, optional
        Precision of the result and of its intermediate products (sums in
        float64; float32 halves the memory of the large supersampled stack).
    deferred : bool, optional
        Return a `~gongsynth.stages.scene.scene.DeferredStack` whose rows are
        made on request (the same numbers), instead of the whole stack.

    Returns
    -------
    `numpy.ndarray`, `~astropy.units.Quantity` or `~gongsynth.stages.scene.scene.DeferredStack`
        (k, NY, NX) (or (NY, NX)) of ``dtype`` on the supersampled grid.

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
    pointing = Pointing() if pointing is None else pointing
    unit = stack.unit if isinstance(stack, u.Quantity) else None
    values = np.asarray(stack.value if unit is not None else stack, dtype=float)
    squeeze = values.ndim == 2
    if squeeze:
        values = values[None]
    if values.ndim != 3:
        raise ValueError(f"stack must have shape (k, ny, nx) or (ny, nx), got {np.shape(stack)}")
    check_finite(values, "stack")
    inst = instruments.get(instrument)
    res = _check_resolutions(resolutions)
    grid, scale, det = sky_grid(inst, detector_shape=detector_shape, shape=shape)
    mu = pointing.mu
    kpa = pointing.km_per_arcsec.to_value(u.km / u.arcsec)
    pix = pixel_size.to_value(u.km)
    if not (math.isfinite(pix) and pix > 0):
        raise ValueError(f"pixel_size must be positive and finite, got {pixel_size}")
    check_tile_extent(values.shape[1:], pixel_size, pointing, res, inst)
    args = (values, pix, grid, scale.to_value(u.arcsec), kpa, mu, _quadrants(grid, res, det), np.dtype(dtype))
    if deferred:
        tiler = _tiler(*args)
        shape = tuple(grid) if squeeze else (values.shape[0],) + tuple(grid)
        return DeferredStack(shape, dtype, unit, tiler.rows, release=tiler.release)
    out = _tile_stack(*args)
    if squeeze:
        out = out[0]
    return out if unit is None else u.Quantity(out, unit, copy=False)


@u.quantity_input
def tiled_scenes(channels, blos, pixel_size: u.km, *, pointing=None, resolutions=(1, 2, 4, 8),
                 instrument=None, detector_shape=None, shape=None):
    """
    The paper's tiled scene and its ground truth, placed with the same geometry.

    Parameters
    ----------
    channels : `~astropy.units.Quantity`
        Channel images at the Sun (6, ny, nx) in erg s⁻¹ cm⁻² sr⁻¹
        (`gongsynth.stages.channels.channel_images`).
    blos : `~astropy.units.Quantity` or None
        True B_LOS (ny, nx) in G on the same grid (``StokesCube.blos``).
    pixel_size : `~astropy.units.Quantity`
        Tile column size (km).
    pointing, resolutions, instrument, detector_shape, shape
        As in `tile`.

    Returns
    -------
    light : `Scene`
        Radiance at Earth per arcsec² (6, NY, NX), float32 (the optics
        transform float32 planes in float32: B and v change by < 0.01 G and
        0.01 m/s, see the tests), made where it is used, a block of rows at a
        time (a `~gongsynth.stages.scene.scene.DeferredStack`: ``light.data``
        makes it whole).  Boundary ``"periodic"``
        when the field holds a whole number of tiles at a single resolution,
        else ``"reflect"`` (the tiling continues smoothly past the edges).
    truth : `Scene` or None
        B_LOS (NY, NX) in G, float32, same grid, boundary and WCS (deferred too).

    Examples
    --------
    >>> import astropy.units as u, numpy as np
    >>> planes = np.full((6, 64, 64), 1.5e6) * u.Unit("erg / (s cm2 sr)")
    >>> light, truth = tiled_scenes(planes, np.zeros((64, 64)) * u.G, 96 * u.km, detector_shape=32)
    >>> light.shape, truth.shape, light.detector_shape
    ((6, 160, 160), (160, 160), (32, 32))
    """
    inst = instruments.get(instrument)
    pointing = Pointing() if pointing is None else pointing
    check_quantity(channels, CHANNEL_UNIT, "channels")
    n_planes = len(inst.analysers)
    if channels.ndim != 3 or channels.shape[0] != n_planes:
        raise ValueError(f"channels must have shape ({n_planes}, ny, nx) ({inst.label}'s planes), "
                         f"got {channels.shape}")
    if blos is not None:
        check_quantity(blos, u.G, "blos")
        if blos.shape != channels.shape[1:]:
            raise ValueError(f"blos must have shape {channels.shape[1:]} like channels, got {blos.shape}")
    kwargs = dict(pointing=pointing, resolutions=resolutions, instrument=inst,
                  detector_shape=detector_shape, shape=shape)
    # Tiling is linear: convert the small tile to radiance at Earth, not the big scene.
    data = tile(radiance_at_earth(channels), pixel_size, dtype=np.float32, deferred=True, **kwargs)
    mu = pointing.mu
    grid, scale, det = sky_grid(inst, detector_shape=detector_shape, shape=shape)
    centre, km_per_arcsec = pointing.centre, pointing.km_per_arcsec
    res = _check_resolutions(resolutions)
    # Periodic only if the field holds whole tiles (one resolution, both axes).
    kpa = km_per_arcsec.to_value(u.km / u.arcsec)
    periods = [n * pixel_size.to_value(u.km) * f * res[0] / kpa
               for n, f in zip(channels.shape[1:], (mu, 1.0))]
    fields = [n * scale.to_value(u.arcsec) for n in grid]
    whole = all(abs(f / p - round(f / p)) < 1e-6 for f, p in zip(fields, periods))
    boundary = "periodic" if len(res) == 1 and whole else "reflect"

    def placer(stack, size):
        return tile(stack, size, dtype=np.float32, **kwargs)

    meta = dict(mode="tiled", latitude=pointing.latitude, resolutions=res, mu=mu,
                los_azimuth=pointing.los_azimuth, obstime=pointing.obstime, km_per_arcsec=km_per_arcsec,
                tile_pixel_size=pixel_size.to(u.km))
    common = dict(boundary=boundary, instrument=inst, detector_shape=det, centre=centre,
                  placer=placer, regions=_quadrants(grid, res, det))
    header = wcs_header(grid, scale, centre, wavelength=inst.line_wavelength)
    truth = None
    if blos is not None:
        placed = tile(blos.to(u.G), pixel_size, dtype=np.float32, deferred=True, **kwargs)
        truth = Scene(placed, scale, header, meta={**meta, "quantity": "blos"}, **common)
    light = Scene(data, scale, header, blos=None if truth is None else truth.planes,
                  meta={**meta, "quantity": "radiance"}, **common)
    return light, truth
