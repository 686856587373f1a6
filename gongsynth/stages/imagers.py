r"""
PSF, binning and sampling at the detector pixels as one operator in Fourier space.

A scene sampled at exactly ``factor`` × ``factor`` samples per detector pixel
(gongsynth's grid: 0.5″ for GONG's 2.5″ pixels) goes through the paper's
chain — convolution with the PSF kernel, bilinear resampling (then the
identity) and ``factor`` × ``factor`` binning — which is linear and shift
invariant up to the final sampling at the detector pixels.  Two operators
evaluate it plane by plane:

`BandLimitedImager` (the pipeline's)
    The aperture's diffraction cut-off D/λ0 (0.2006 cycles per arcsec) is the
    Nyquist frequency of the 2.5″ pixels (0.2 cycles per arcsec), so the
    blurred, binned field is band limited to what the detector samples.  Each
    plane is transformed along its rows (one real FFT per row), only the
    ``ny / factor`` lowest frequencies are kept, the columns of those are
    transformed, multiplied by the kernel's and the pixel's transfer
    functions, and one small inverse transform gives the detector pixels.
    What it leaves out is the part of the transfer function beyond the
    detector's Nyquist frequency (the Airy OTF's last 0.3 % below its cut-off,
    and the truncated kernel's leakage): at most 5e-5 of its peak, 2e-5 of its
    integral (see the tests and ``benchmarks/bench_optics.py`` for what that
    does to B and v: far below the noise).
`ExactImager` (the reference)
    The same operator with every alias folded in: equal to `convolve`
    followed by `pixelize` (`gongsynth.stages.optics`) to rounding, at a
    fifth of the inverse transforms and without the supersampled result.

Both work in the planes' precision (float32 planes in float32) and transform
a plane less its mean (a constant passes unchanged through a unit-sum kernel
with periodic or mirrored edges), so float32 round-off is relative to the
contrast, not to the level.
"""
from collections import deque
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import scipy.fft

from gongsynth.stages.psf import fft_workers, wrapped_kernel

__all__ = ["BandLimitedImager", "ExactImager", "BandImager", "image_planes", "pixel_means", "made_ahead"]

# Rows of a plane transformed at once by `BandLimitedImager` (bounded temporaries).
_BLOCK_ROWS = 128
# Grid rows per band of `BandImager`: a full-disk HMI slab of 12 planes is then ~0.6 GB, and the
# transforms ~1.4 times the whole plane's (the kernel's 479 rows of overlap per band).
_BAND_ROWS = 1024


def _fast_multiple(n, factor):
    """The smallest multiple of ``factor`` ≥ ``n`` whose FFT is fast (5-smooth)."""
    m = -(-n // factor)
    while scipy.fft.next_fast_len(factor * m, real=True) != factor * m:
        m += 1
    return factor * m


def _padding(shape, kernel_shape, boundary, factor):
    """Margins ((top, bottom), (left, right)) and transform shape of a plane."""
    (ny, nx), (ky, kx) = shape, kernel_shape
    if boundary == "periodic":
        return ((0, 0), (0, 0)), (ny, nx)
    pads = ((ky - 1 - ky // 2, ky // 2), (kx - 1 - kx // 2, kx // 2))
    return pads, (_fast_multiple(ny + ky - 1, factor), _fast_multiple(nx + kx - 1, factor))


def _source_index(n, pads, length, boundary):
    """
    Field sample held at each position of a circular transform axis, -1 for zero.

    Position q holds padded sample (q + first margin) mod ``length``: the field
    starts at q = 0, its far margin follows it, its near margin wraps to the
    end, and the rest (the transform's round-up) is zero.
    """
    (near, far) = pads
    if boundary == "periodic":
        return np.arange(n)
    if boundary == "reflect":
        padded = np.pad(np.arange(n), (near, far), mode="symmetric")
    else:
        padded = np.pad(np.arange(n), (near, far), mode="constant", constant_values=-1)
    index = np.full(length, -1, dtype=np.int64)
    index[:padded.size] = padded
    return np.roll(index, -near)


def _reflect_into(buffer, plane, pads):
    """Write ``plane`` into ``buffer`` at offset ``pads`` with mirrored ("symmetric") margins."""
    ny, nx = plane.shape
    (top, bottom), (left, right) = pads
    rows = slice(top, top + ny)
    buffer[rows, left:left + nx] = plane
    if left:
        buffer[rows, :left] = plane[:, left - 1::-1]
    if right:
        buffer[rows, left + nx:left + nx + right] = plane[:, :nx - right - 1:-1]
    width = slice(0, left + nx + right)
    if top:
        buffer[:top, width] = buffer[2 * top - 1:top - 1:-1, width]
    if bottom:
        buffer[top + ny:top + ny + bottom, width] = buffer[top + ny - 1:top + ny - bottom - 1:-1, width]


def _level(plane, boundary, dtype, minus=None):
    """
    The level transformed apart: the mean of ``plane`` (less ``minus``; the
    first block of rows of it for `BandLimitedImager`), in float32; 0 where a
    constant would not pass unchanged (zero edges) or in float64.  Any
    constant would do: it only makes the round-off relative to the contrast.
    """
    if boundary == "zero" or dtype != np.float32:
        return 0.0
    mean = np.mean(plane, dtype=np.float64)
    if minus is not None:
        mean -= np.mean(minus, dtype=np.float64)
    return float(np.float32(mean))


class BandLimitedImager:
    """
    PSF, binning and detector sampling evaluated at the frequencies the detector samples.

    See the module notes.  The transfer function is the kernel's discrete
    spectrum (on the padded grid, as in `ExactImager`) times the binning's,
    at the ``ny / factor`` × ``nx / factor`` frequencies below the detector's
    Nyquist frequency; a plane costs one real FFT per row, column FFTs of a
    fifth of the columns and one small inverse transform.

    Parameters
    ----------
    shape : (int, int)
        Shape (ny, nx) of the planes, ``factor`` × the detector's.
    kernel : `numpy.ndarray`
        The PSF sampled on the planes' grid, unit sum, centre at ``(ky // 2, kx // 2)``.
    boundary : {"periodic", "zero", "reflect"}
        Edge handling, as in `gongsynth.stages.optics.convolve`.
    factor : int
        Samples per detector pixel along each axis.
    dtype : dtype
        float32 or float64: the precision of the transforms.
    workers : int or None
        Threads for the transforms (`~gongsynth.stages.psf.fft_workers`).

    Examples
    --------
    >>> import numpy as np
    >>> imager = BandLimitedImager((50, 50), np.ones((3, 3)) / 9, "periodic", 5, np.float64, 1)
    >>> out = imager(np.full((50, 50), 2.0))   # a constant is all at frequency zero
    >>> out.shape, bool(np.allclose(out, 2.0))
    ((10, 10), True)
    """

    def __init__(self, shape, kernel, boundary, factor, dtype, workers):
        ny, nx = shape
        self.shape, self.factor, self.boundary = (ny, nx), factor, boundary
        self.dtype = np.dtype(dtype)
        self.workers = fft_workers(workers)
        self.detector_shape = (ny // factor, nx // factor)
        pads, self.fshape = _padding(shape, kernel.shape, boundary, factor)
        self._pads = pads
        fy, fx = self.fshape
        self._rows = _source_index(ny, pads[0], fy, boundary)
        self._cols = _source_index(nx, pads[1], fx, boundary)
        # Frequencies kept: |f| < M / 2 with M = F / factor (the detector grid), no Nyquist term.
        my, mx = fy // factor, fx // factor
        self.small_shape = (my, mx)
        hy, hx = (my - 1) // 2, (mx - 1) // 2
        self._fy = np.concatenate([np.arange(hy + 1), np.arange(-hy, 0)])  # signed, in small-row order
        self._nx_kept = hx + 1
        self.transfer = self._transfer(kernel, hy, hx)

    def _transfer(self, kernel, hy, hx):
        """Kernel spectrum × binning transfer × the inverse transform's normalisation, (my, mx // 2 + 1)."""
        (fy, fx), factor = self.fshape, self.factor
        ky, kx = kernel.shape
        # Kernel spectrum at the kept frequencies: separable DFT matrices (centre at index 0).
        ey = np.exp(-2j * np.pi * np.outer(self._fy, np.arange(ky) - ky // 2) / fy)
        ex = np.exp(-2j * np.pi * np.outer(np.arange(hx + 1), np.arange(kx) - kx // 2) / fx)
        spectrum = ((ey.real @ kernel) + 1j * (ey.imag @ kernel)) @ ex.T
        # Mean of `factor` samples starting at the detector pixel's first sample.
        box_y = np.exp(2j * np.pi * np.outer(self._fy, np.arange(factor)) / fy).mean(axis=1)
        box_x = np.exp(2j * np.pi * np.outer(np.arange(hx + 1), np.arange(factor)) / fx).mean(axis=1)
        my, mx = self.small_shape
        transfer = np.zeros((my, mx // 2 + 1), dtype=complex)
        transfer[self._fy % my, :hx + 1] = spectrum * box_y[:, None] * box_x[None, :] / factor**2
        return transfer

    def _fill_rows(self, work, block, minus, level):
        """Rows ``block`` (less ``minus`` and ``level``) on the circular transform axis, into ``work``."""
        nx = self.shape[1]
        near, far = self._pads[1]
        if self.boundary != "reflect" or max(near, far) >= nx:
            if minus is not None:
                block = block - minus
            np.take(block, np.where(self._cols < 0, 0, self._cols), axis=1, out=work)
            if level:
                work -= level
            work[:, self._cols < 0] = 0
            return
        field = work[:, :nx]
        if minus is not None:
            np.subtract(block, minus, out=field)
            if level:
                field -= level
        else:
            np.subtract(block, level, out=field)
        # Mirrored margins: the far one after the field, the near one wrapped to the end.
        if far:
            work[:, nx:nx + far] = field[:, nx - 1:nx - far - 1:-1]
        work[:, nx + far:work.shape[1] - near] = 0
        if near:
            work[:, work.shape[1] - near:] = field[:, near - 1::-1]

    def _row_spectra(self, plane, minus):
        """
        The kept row frequencies of every field row, (ny, hx + 1), in the planes' precision,
        and the level taken out (the mean of the first block of rows; any constant would do).
        """
        ny, nx = self.shape
        fx = self.fshape[1]
        kept = self._nx_kept
        out = np.empty((ny, kept), dtype=np.result_type(self.dtype, np.complex64))
        buffer = np.empty((min(_BLOCK_ROWS, ny), fx), dtype=self.dtype)
        level = None
        for r0 in range(0, ny, _BLOCK_ROWS):
            block = np.asarray(plane[r0:r0 + _BLOCK_ROWS], dtype=self.dtype)
            other = None if minus is None else np.asarray(minus[r0:r0 + _BLOCK_ROWS], dtype=self.dtype)
            if level is None:
                level = _level(block, self.boundary, self.dtype, other)
                shift = self.dtype.type(level)
            if self.boundary == "reflect":
                work = buffer[:block.shape[0]]
                self._fill_rows(work, block, other, shift)
            else:  # periodic: the row itself; zero edges: zero-padded to fx by the transform
                work = block if other is None else np.subtract(block, other, out=buffer[:block.shape[0], :nx])
                if level:
                    work = work - shift
            spectrum = scipy.fft.rfft(work, n=fx, axis=1, workers=self.workers)
            out[r0:r0 + block.shape[0]] = spectrum[:, :kept]
        return out, level

    def __call__(self, plane, minus=None):
        """
        One plane through the operator.

        Parameters
        ----------
        plane : `numpy.ndarray` or `~gongsynth.stages.scene.scene.DeferredPlane`
            (ny, nx) samples: an array, or anything whose row slices
            (``plane[a:b]``) give arrays; it is read a block of rows at a time.
        minus : optional
            (ny, nx) samples, as ``plane``, subtracted from it first (block by
            block: the difference is never held whole).

        Returns
        -------
        `numpy.ndarray`
            (ny // factor, nx // factor) float64: the mean over each detector pixel.
        """
        rows, level = self._row_spectra(plane, minus)
        fy = self.fshape[0]
        if self.boundary == "reflect":
            index = self._rows
            columns = rows[np.where(index < 0, 0, index)]
            columns[index < 0] = 0
            del rows
            spectrum = scipy.fft.fft(columns, axis=0, workers=self.workers)
        else:  # periodic (fy = ny), or zero edges padded by the transform
            spectrum = scipy.fft.fft(rows, n=fy, axis=0, workers=self.workers)
        my, mx = self.small_shape
        small = np.zeros((my, mx // 2 + 1), dtype=complex)
        small[self._fy % my, :self._nx_kept] = spectrum[self._fy % fy]
        small *= self.transfer
        out = scipy.fft.irfft2(small, s=(my, mx), workers=self.workers)
        ndy, ndx = self.detector_shape
        return out[:ndy, :ndx] + level


class ExactImager:
    """
    PSF, binning and sampling at the detector pixels with every alias folded in (the reference).

    For a stack sampled at exactly ``factor`` × ``factor`` samples per detector
    pixel, one forward transform per plane is multiplied by the kernel's
    transfer function and by the binning's (a box of ``factor`` samples along
    y, shifted to the first detector row); the spectrum folded onto the
    detector rows is their exact decimation (aliases included), so the inverse
    transform runs on one row in ``factor``; the binning along x is a sum of
    ``factor`` samples after it.  The result equals `convolve` then
    `pixelize` (`gongsynth.stages.optics`) to rounding.

    Parameters
    ----------
    shape, kernel, boundary, factor, dtype, workers
        As in `BandLimitedImager`.

    Examples
    --------
    >>> import numpy as np
    >>> imager = ExactImager((50, 50), np.ones((3, 3)) / 9, "reflect", 5, np.float64, 1)
    >>> bool(np.allclose(imager(np.full((50, 50), 2.0)), 2.0))
    True
    """

    def __init__(self, shape, kernel, boundary, factor, dtype, workers):
        ny, nx = shape
        ky, kx = kernel.shape
        self.shape, self.factor = (ny, nx), factor
        self.dtype = np.dtype(dtype)
        self.workers = fft_workers(workers)
        self.detector_shape = (ny // factor, nx // factor)
        if boundary == "periodic":
            self.pads = ((0, 0), (0, 0))
            fshape = (ny, nx)
        else:
            self.pads = ((ky - 1 - ky // 2, ky // 2), (kx - 1 - kx // 2, kx // 2))
            fshape = (_fast_multiple(ny + ky - 1, factor),
                      scipy.fft.next_fast_len(nx + kx - 1, real=True))
        self.boundary, self.fshape = boundary, fshape
        spectrum = scipy.fft.rfft2(wrapped_kernel(kernel, fshape, np.float64), workers=self.workers)
        # Box of `factor` rows starting at the detector row's first sample (padded row
        # index top + factor * d), as a transfer function; the fold's 1/factor in it.
        n = fshape[0]
        k = scipy.fft.fftfreq(n, 1 / n)
        top = self.pads[0][0]
        box = np.exp(2j * np.pi * np.outer(k, top + np.arange(factor)) / n).sum(axis=1) / factor**3
        spectrum *= box[:, None]
        self.transfer = spectrum.astype(np.result_type(self.dtype, np.complex64))

    def __call__(self, plane):
        """
        One plane through the operator.

        Parameters
        ----------
        plane : `numpy.ndarray`
            (ny, nx) samples.

        Returns
        -------
        `numpy.ndarray`
            (ny // factor, nx // factor) float64: the mean over each detector pixel.
        """
        ny, nx = self.shape
        factor = self.factor
        ndy, ndx = self.detector_shape
        buffer = np.zeros(self.fshape, dtype=self.dtype)
        (top, _), (left, _) = self.pads
        level = _level(plane, self.boundary, self.dtype)
        if level:
            plane = plane - np.float32(level)
        if self.boundary != "reflect":
            buffer[top:top + ny, left:left + nx] = plane
        elif max(self.pads[0] + self.pads[1]) < min(ny, nx):
            _reflect_into(buffer, plane, self.pads)
        else:  # margins wider than the field: repeated reflections
            padded = np.pad(plane, self.pads, mode="symmetric")
            buffer[:padded.shape[0], :padded.shape[1]] = padded
            del padded
        spectrum = scipy.fft.rfft2(buffer, workers=self.workers)
        del buffer
        spectrum *= self.transfer
        n = self.fshape[0] // factor
        folded = spectrum.reshape(factor, n, spectrum.shape[1]).sum(axis=0)
        del spectrum
        rows = scipy.fft.ifft(folded, axis=0, workers=self.workers)[:ndy]
        del folded
        fine = scipy.fft.irfft(rows, n=self.fshape[1], axis=1, workers=self.workers)[:, left:left + nx]
        return fine.reshape(ndy, ndx, factor).sum(axis=2, dtype=np.float64) + level


class BandImager:
    """
    `ExactImager` with zero edges, a band of rows at a time (overlap-save): for a stack made by bands.

    A band of ``band_rows`` grid rows needs the rows a kernel's reach above and
    below it; the slab of those rows, zero-padded in x as `ExactImager` pads
    the whole plane, goes through an `ExactImager` with periodic edges on the
    slab (circular convolution equals the linear one on the band: no output
    row of the band reaches across the slab's wrap), and the band's detector
    rows are kept.  The slab's rows move on by a band, so each grid row is
    made once (`~gongsynth.stages.scene.scene.DeferredStack.band`): a full-disk
    HMI light is rendered in one pass, 12 planes of a band at a time, never
    whole.  The same numbers as `ExactImager` to the float rounding of the
    smaller transforms.

    Parameters
    ----------
    shape, kernel, factor, dtype, workers
        As in `ExactImager`.
    band_rows : int, optional
        Grid rows per band (default 1024; rounded up to the transform's fast length).

    Examples
    --------
    >>> import numpy as np
    >>> plane = np.random.default_rng(1).random((60, 40))
    >>> kernel = np.ones((5, 5)) / 25
    >>> whole = ExactImager((60, 40), kernel, "zero", 2, np.float64, 1)(plane)
    >>> bands = BandImager((60, 40), kernel, 2, np.float64, 1, band_rows=8)
    >>> bool(np.allclose(bands(lambda a, b: plane[None, a:b], 1)[0], whole, atol=1e-12))
    True
    """

    def __init__(self, shape, kernel, factor, dtype, workers, band_rows=None):
        (ny, nx), (ky, kx) = shape, kernel.shape
        self.shape, self.factor, self.dtype = (ny, nx), factor, np.dtype(dtype)
        self.detector_shape = (ny // factor, nx // factor)
        # Margins: a whole number of detector pixels above and left of the field, the kernel's reach below.
        self.top = -(-(ky - 1 - ky // 2) // factor) * factor
        self.left = -(-(kx - 1 - kx // 2) // factor) * factor
        bottom = ky // 2
        band = max(factor, min(int(band_rows or _BAND_ROWS), -(-ny // factor) * factor))
        fy = _fast_multiple(self.top + band + bottom, factor)
        fx = _fast_multiple(self.left + nx + kx // 2, factor)
        self.band_rows = (fy - self.top - bottom) // factor * factor
        self.slab = ExactImager((fy, fx), kernel, "periodic", factor, dtype, workers)

    def __call__(self, bands, n_planes, common=True, dtype=np.float64):
        """
        Every plane through the operator, a band of rows at a time.

        Parameters
        ----------
        bands : callable
            ``bands(start, stop)`` → (n_planes, stop - start, nx) grid rows of every plane.
        n_planes : int
        common : bool
            As `image_planes` does in float32: the first plane, then each
            other one's difference from it (its round-off cancels in ratios).
        dtype : dtype
            Of the result (float32 halves a full-disk HMI stack: 0.8 GB).

        Returns
        -------
        `numpy.ndarray`
            (n_planes, ny // factor, nx // factor).
        """
        (ny, nx), factor, band = self.shape, self.factor, self.band_rows
        fy, fx = self.slab.fshape
        out = np.empty((n_planes,) + self.detector_shape, dtype=dtype)
        slab = np.zeros((n_planes, fy, fx), dtype=self.dtype)
        field = slice(self.left, self.left + nx)
        d_top, d_left = self.top // factor, self.left // factor
        # Each band's new rows, a few hundred at a time (the renderer's output is a copy until placed):
        # made in this order on a thread of their own, a band ahead, while the slabs are transformed.
        new_rows, made = [], 0                     # grid rows [0, made) asked for
        for start in range(0, ny, band):
            first = start - self.top
            new_rows.append([])
            for r0 in range(made, min(first + fy, ny), _BLOCK_ROWS * 2):
                made = min(r0 + _BLOCK_ROWS * 2, first + fy, ny)
                new_rows[-1].append((r0, made))
        blocks = made_ahead(bands, [r for rows in new_rows for r in rows], -(-band // (_BLOCK_ROWS * 2)))
        for start, rows_of_band in zip(range(0, ny, band), new_rows):
            first = start - self.top               # the grid row at slab row 0
            if start:
                for plane in slab:                 # the overlap moves up by a band
                    plane[:fy - band] = plane[band:]
                    plane[fy - band:] = 0
            for r0, r1 in rows_of_band:
                slab[:, r0 - first:r1 - first, field] = next(blocks)
            rows = slice(start // factor, min(start + band, ny) // factor)
            keep = (slice(d_top, d_top + rows.stop - rows.start), slice(d_left, d_left + nx // factor))
            base = self.slab(slab[0])[keep]
            out[0, rows] = base
            for i in range(1, n_planes):
                image = self.slab(slab[i] - slab[0] if common else slab[i])[keep]
                out[i, rows] = image + base if common else image
        return out


def made_ahead(make, ranges, ahead):
    """
    ``make(start, stop)`` for each range in order, the next ones made on a thread while the caller
    uses the current one.

    The calls are made one at a time, in the order given (a renderer's state, a deferred truth's
    rows, see the same calls as without the thread), at most ``ahead`` results waiting.

    Parameters
    ----------
    make : callable
        ``make(start, stop)`` → array.
    ranges : list of (int, int)
    ahead : int
        Results made ahead of the one being used (at least 1).

    Yields
    ------
    The results, in order.

    Examples
    --------
    >>> [int(x) for x in made_ahead(lambda a, b: a + b, [(0, 1), (1, 2), (2, 3)], 2)]
    [1, 3, 5]
    """
    pending = deque()
    with ThreadPoolExecutor(max_workers=1) as pool:
        try:
            for start, stop in ranges:
                pending.append(pool.submit(make, start, stop))
                if len(pending) > ahead:
                    yield pending.popleft().result()
            while pending:
                yield pending.popleft().result()
        finally:                   # abandoned: what was not started is not made
            for future in pending:
                future.cancel()


def image_planes(values, imager):
    """
    A stack (k, ny, nx) through ``imager``, plane by plane.

    In float32 the first plane and each other plane's difference from it are
    transformed separately: the round-off of the first plane's transform is
    the same in every plane, so it cancels in the ratios the reduction
    measures (phases, hence B and v), and that of the differences is relative
    to the differences, which are small.  `BandLimitedImager` forms the
    differences block by block (never a whole difference plane) and reads
    deferred planes (`~gongsynth.stages.scene.scene.DeferredStack`) the same way.

    Parameters
    ----------
    values : `numpy.ndarray` or `~gongsynth.stages.scene.scene.DeferredStack`
        (k, ny, nx); ``values[i]`` is plane i.
    imager : `BandLimitedImager` or `ExactImager`

    Returns
    -------
    `numpy.ndarray`
        (k, ny // factor, nx // factor) float64.

    Examples
    --------
    >>> import numpy as np
    >>> imager = BandLimitedImager((50, 50), np.ones((3, 3)) / 9, "reflect", 5, np.float32, 1)
    >>> image_planes(np.ones((2, 50, 50), dtype=np.float32), imager).shape
    (2, 10, 10)
    """
    out = np.empty((values.shape[0],) + imager.detector_shape)
    streamed = isinstance(imager, BandLimitedImager)
    if imager.dtype != np.float32 or values.shape[0] < 2:
        for i in range(values.shape[0]):
            out[i] = imager(values[i] if streamed else np.asarray(values[i]))
        return out
    common = np.asarray(values[0])  # held: read once per other plane
    out[0] = imager(common)
    for i in range(1, values.shape[0]):
        out[i] = imager(values[i], minus=common) if streamed else imager(np.asarray(values[i]) - common)
        out[i] += out[0]
    return out


def pixel_means(plane, factor):
    """
    Means over factor × factor blocks of a plane, read a block of rows at a time.

    Parameters
    ----------
    plane : `numpy.ndarray` or `~gongsynth.stages.scene.scene.DeferredPlane`
        (ny, nx), both multiples of ``factor``.
    factor : int

    Returns
    -------
    `numpy.ndarray`
        (ny // factor, nx // factor) float64.

    Examples
    --------
    >>> import numpy as np
    >>> pixel_means(np.arange(16.0).reshape(4, 4), 2).tolist()
    [[2.5, 4.5], [10.5, 12.5]]
    """
    ny, nx = plane.shape
    out = np.empty((ny // factor, nx // factor))
    step = factor * max(1, 256 // factor)
    for r0 in range(0, ny, step):
        rows = np.asarray(plane[r0:r0 + step])
        out[r0 // factor:(r0 + rows.shape[0]) // factor] = rows.reshape(
            -1, factor, nx // factor, factor).mean(axis=(1, 3), dtype=np.float64)
    return out
