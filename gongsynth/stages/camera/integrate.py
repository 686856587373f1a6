r"""
The camera: frames accumulated into the instrument's K raw planes.

The paper's time integration (Sec. 3.2, second list), for every frame *k* of
the instrument's schedule (`~gongsynth.instruments.base.FrameSchedule`: GONG's
in `gongsynth.instruments.gong.schedule`) and every pixel:

.. math::

    n_k &\sim \mathrm{Poisson}(f_p\,E_{p(k)} + D), \qquad
    a_k = \mathrm{round}\!\big(n_k / g + \sigma_r z_k\big) + d_k, \\
    S_p &= \sum_{k \in p} a_k \ \text{(int64)}, \qquad
    \mathrm{raw}_p = \big\lfloor S_p / 2^b \big\rfloor + \frac{2^b - 1}{2^{b+1}}
        - \frac{1}{2^b}\sum_{k\in p} d_k,

with E the expected electrons per frame (after QE, from the optics), f the
median-normalised flat, D the dark current per frame (the photon and dark
Poisson draws are merged: a sum of independent Poisson variates is Poisson),
g the gain (GONG: 33 e⁻/adu), σ_r the read noise (GONG: 4.8 adu), z standard
normal, d_k the dither (zero for an instrument without) and b =
``truncate_bits`` (GONG: 3; 0 for an instrument that keeps every bit).  The
last two terms are the bookkeeping of design §3.11: the exact dither of the
plane is removed, and the mean −(2^b−1)/2^(b+1) bias of dropping b low bits (uniformly distributed
because σ_r ≫ 1 adu) is put back, so that ``raw`` is an unbiased estimate of
Σ(f E + D)/g / 2^b in DN (1 DN = 2^b adu) and the reduction's dark subtraction
(N_p D / g / 2^b) is exact.

Two engines, one interface:

``"frames"``
    The algorithm above, frame by frame (numba, parallel over pixels; each
    pixel has its own random stream, so the result is bit-identical for a
    seed whatever ``chunk_rows`` and ``workers``).
``"blocks"``
    Statistically equivalent and ~1000× faster.  The dither is deterministic
    and integer, so it passes through the sum untouched; within a plane
    Σ n_k ~ Poisson(Σλ_k), and Σ round(n_k/g + σ_r z_k) equals
    Σ n_k / g plus a lattice-Gaussian of variance N(σ_r² + 1/12) (Sheppard:
    each rounding adds 1/12 adu², independent of the signal when σ_r ≳ 1).
    The engine draws S_p = round(P/g + √(Nσ_r² + (N−1)/12) z) + Σd_k,
    whose final rounding supplies the last 1/12.  Both engines agree in mean
    and variance of every plane (tested).

Both accept time-varying input: ``expected`` of shape (n_snap, K, ny, nx)
holds n_snap snapshots spread evenly over the duration; frame *k* sees
snapshot ⌊k·n_snap/N⌋.
"""
import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import astropy.units as u
import numpy as np
from astropy.io import fits

from gongsynth import instruments
from gongsynth.files import atomic_path
from gongsynth.seeding import as_seed_sequence, child_sequence, stage_generator
from gongsynth.stages.camera.detector import normalise_flat, prepare_dark, synthetic_dark, synthetic_flat
from gongsynth.validation import check_quantity

__all__ = ["RawPlanes", "integrate", "ENGINES", "snapshot_index"]

#: The accepted values of ``engine`` (the one definition: the configuration imports it).
ENGINES = ("frames", "blocks")

# Pixels per progress-bar step of the frames engine (bounded memory per chunk).
_FRAMES_CHUNK_PIXELS = 1 << 15
_BLOCKS_CHUNK_PIXELS = 1 << 17


@dataclass(eq=False)
class RawPlanes:
    """
    The K accumulated planes of an instrument, as the camera writes them.

    Attributes
    ----------
    data : `numpy.ndarray`
        float64, shape (K, ny, nx), in DN (1 DN = 2**truncate_bits adu) after
        truncation and mean-dither subtraction; the instrument's plane order
        (GONG: `gongsynth.planes`).  float32 for a camera whose planes are
        whole numbers of DN (no truncation, no dither: HMI's) far below 2^24,
        which float32 holds exactly.
    frames_per_plane : `numpy.ndarray`
        int64, shape (K,): frames accumulated in each plane.
    header : `astropy.io.fits.Header`
        Raw-like header (ITIME, EXPTIME, ENGINE, SEED, GSVERS, PLANEn, ...; GONG's
        ACCUM and COUNT).  Never claims DTYPE = 'OBSERVE'.
    flat : `numpy.ndarray`
        float64, shape (K, ny, nx): the median-normalised flat that was applied.
    dark : `~astropy.units.Quantity`
        Shape (ny, nx): the dark current that was applied, electron per frame.
    """

    data: np.ndarray
    frames_per_plane: np.ndarray
    header: fits.Header
    flat: np.ndarray
    dark: u.Quantity

    @property
    def shape(self):
        """(ny, nx) of the detector."""
        return self.data.shape[1:]

    @property
    def engine(self):
        """The engine that made the planes (str)."""
        return self.header.get("ENGINE")

    @property
    def seed(self):
        """Root entropy of the seed (int), as recorded in the header."""
        return int(self.header["SEED"])

    def to_fits(self, path, overwrite=False):
        """
        Write the planes, the flat and the dark to a FITS file, atomically.

        The primary HDU holds ``data`` (K, ny, nx) with ``header``; extension
        ``FLAT`` the flat (ny, nx) or (K, ny, nx); ``DARK`` the dark (electron).

        Parameters
        ----------
        path : str or path-like
        overwrite : bool
            Replace an existing file (default: refuse).

        Raises
        ------
        FileExistsError
            If ``path`` exists and ``overwrite`` is False.
        """
        flat = self.flat[0] if _same_planes(self.flat) else self.flat
        dark_hdu = fits.ImageHDU(np.ascontiguousarray(self.dark.to_value(u.electron)), name="DARK")
        dark_hdu.header["BUNIT"] = ("electron", "dark current per frame")
        hdul = fits.HDUList([
            fits.PrimaryHDU(np.ascontiguousarray(self.data), header=self.header),
            fits.ImageHDU(np.ascontiguousarray(flat), name="FLAT"),
            dark_hdu,
        ])
        with atomic_path(path, overwrite=overwrite) as tmp:
            hdul.writeto(tmp, overwrite=True)

    @classmethod
    def from_fits(cls, path):
        """
        Read planes written by `to_fits`.

        Parameters
        ----------
        path : str or path-like

        Returns
        -------
        `RawPlanes`
        """
        with fits.open(os.fspath(path)) as hdul:
            header = hdul[0].header.copy()
            data = np.array(hdul[0].data, dtype=np.float64)
            flat = np.array(hdul["FLAT"].data, dtype=np.float64)
            dark = np.array(hdul["DARK"].data, dtype=np.float64) * u.electron
        if data.ndim != 3 or any(f"NFRAME{p}" not in header for p in range(data.shape[0])):
            raise ValueError(f"{os.fspath(path)!r}: primary HDU must hold (K, ny, nx) planes with "
                             f"NFRAME0 ... NFRAME(K-1) in its header, got shape {data.shape}")
        frames = np.array([header[f"NFRAME{p}"] for p in range(data.shape[0])], dtype=np.int64)
        return cls(data=data, frames_per_plane=frames, header=header,
                   flat=normalise_flat(flat, data.shape[1:], data.shape[0]), dark=dark)


def _same_planes(flat):
    return flat.strides[0] == 0 or all(np.array_equal(flat[0], f) for f in flat[1:])


def snapshot_index(n_frames, n_snapshots):
    """
    Which snapshot of a time-varying input each frame sees.

    Snapshots are spread evenly over the observation: frame *k* of
    ``n_frames`` sees snapshot ⌊k·n_snapshots/n_frames⌋.

    Parameters
    ----------
    n_frames, n_snapshots : int

    Returns
    -------
    `numpy.ndarray`
        int64, shape (n_frames,).

    Examples
    --------
    >>> snapshot_index(6, 3).tolist()
    [0, 0, 1, 1, 2, 2]
    """
    if n_snapshots < 1 or n_snapshots > n_frames:
        raise ValueError(f"the number of snapshots must be between 1 and the number of frames "
                         f"({n_frames}), got {n_snapshots}")
    return np.arange(n_frames, dtype=np.int64) * n_snapshots // n_frames


def _check_expected(expected, n_planes):
    check_quantity(expected, u.electron, "expected")
    values = np.asarray(expected.to_value(u.electron))
    if values.dtype != np.float32:     # float32 counts (a full-disk HMI stack) are widened a chunk at a time
        values = values.astype(np.float64, copy=False)
    if values.ndim == 3:
        values = values[None]
    if values.ndim != 4 or values.shape[1] != n_planes or min(values.shape) < 1:
        raise ValueError(
            f"expected must have shape ({n_planes}, ny, nx) or (n_snapshots, {n_planes}, ny, nx) "
            f"(electrons per frame in each of the instrument's planes), got {expected.shape}")
    finite = np.isfinite(values)
    if not finite.all():
        raise ValueError(f"expected contains {int((~finite).sum())} non-finite value(s) (NaN or inf)")
    negative = int(np.count_nonzero(values < 0))
    if negative:
        raise ValueError(f"expected counts must be non-negative (electrons per frame); "
                         f"{negative} value(s) are negative (min {values.min():g})")
    return values


def _workers(workers):
    if workers is None:
        return os.cpu_count() or 1
    if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or workers < 1:
        raise ValueError(f"workers must be a positive int or None, got {workers!r}")
    return int(workers)


def _chunks(ny, nx, chunk_rows, default_pixels):
    if chunk_rows is None:
        chunk_rows = max(1, default_pixels // nx)
    if isinstance(chunk_rows, bool) or not isinstance(chunk_rows, (int, np.integer)) or chunk_rows < 1:
        raise ValueError(f"chunk_rows must be a positive int or None, got {chunk_rows!r}")
    return [(r, min(r + int(chunk_rows), ny)) for r in range(0, ny, int(chunk_rows))]


def _progress(total, enabled, engine):
    from tqdm.auto import tqdm
    return tqdm(total=total, disable=not enabled, desc=f"camera ({engine})", unit="row")


def _flat_map(flat, shape, inst, n_planes):
    """(source label, median-normalised (K, ny, nx) flat) for the ``flat`` argument of `integrate`."""
    if flat is None or flat is True:
        return "synthetic", normalise_flat(synthetic_flat(shape, instrument=inst), shape, n_planes)
    if flat is False:
        return "none", normalise_flat(np.ones(shape), shape, n_planes)
    return "user", normalise_flat(flat, shape, n_planes)


def _dark_map(dark, shape, inst):
    """(source label, (ny, nx) dark in electron) for the ``dark`` argument of `integrate`."""
    if dark is None or dark is True:
        return "synthetic", prepare_dark(synthetic_dark(shape, instrument=inst), shape)
    if dark is False:
        return "none", prepare_dark(0 * u.electron, shape)
    return "user", prepare_dark(dark, shape)


def _switch(value, name):
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def integrate(expected, *, duration=None, engine="blocks", seed=None, instrument=None,
              flat=None, dark=None, photon_noise=True, read_noise=True, dither=True, truncation=True,
              chunk_rows=None, workers=None, progress=True):
    """
    Accumulate an observation into the instrument's K raw planes.

    Parameters
    ----------
    expected : `~astropy.units.Quantity`
        Expected electrons per frame per pixel in each plane (after QE), shape
        (K, ny, nx), or (n_snap, K, ny, nx) for an input that changes during
        the observation (snapshots spread evenly over ``duration``; see
        `snapshot_index`).  Finite and non-negative.
    duration : `~astropy.units.Quantity`, optional
        Observing time (whole number of frames): 1 min for GONG's product,
        10 min for the paper's.  Default: the instrument's ``default_duration``.
    engine : {"blocks", "frames"}
        ``"blocks"`` draws each plane's sum directly (fast, statistically
        equivalent); ``"frames"`` simulates every frame.  See `ENGINES`.
    seed : None, int, `numpy.random.SeedSequence` or `numpy.random.Generator`
        Root seed; its entropy is written to the header.
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
        Supplies the schedule (`~gongsynth.instruments.base.Instrument.schedule`:
        planes and dither), gain, read noise, truncation and the synthetic flat
        and dark.  Default GONG.
    flat : None, bool, array_like, str or path-like
        ``None`` or ``True`` (default): the instrument's
        `~gongsynth.stages.camera.detector.synthetic_flat`; ``False``: a unity
        flat (a perfect detector); an array (ny, nx) or (K, ny, nx), or a FITS
        path: a user flat, median-normalised per plane inside.
    dark : None, bool, `~astropy.units.Quantity`, str or path-like
        ``None`` or ``True`` (default): the instrument's
        `~gongsynth.stages.camera.detector.synthetic_dark`; ``False``: no dark
        current (0 e⁻); a Quantity (electron per frame, scalar or (ny, nx)) or
        a FITS path: a user dark.
    photon_noise : bool
        Draw each frame's electrons from Poisson(f E + D) (default).  False
        uses the expected electrons f E + D themselves: no photon or
        dark-current shot noise.
    read_noise : bool
        Add the instrument's Gaussian read noise to each frame (default).
        False: none (in the frames engine exactly as an instrument with
        ``read_noise = 0 adu``).  The blocks engine treats each frame's
        rounding as noise, which needs read noise of at least 1 adu: it
        accepts ``read_noise=False`` only together with
        ``photon_noise=False``, where it computes the (then deterministic)
        per-frame rounding exactly.
    dither : bool
        Add the dither sequence to the frames (and remove its exact sum from
        each plane; default).  False: no dither (DITHSUM = 0 in the header).  An
        instrument without dither (an all-zero schedule) has no DITHSUM cards.
    truncation : bool
        Drop the ``truncate_bits`` lowest bits of each accumulated plane and
        put back the mean bias of doing so (default).  False: keep every bit;
        the plane is the exact sum (S - Σd) / 2^b, still in DN (1 DN = 2^b adu)
        so that the reduction is unchanged, with no truncation offset.
    chunk_rows : int, optional
        Detector rows per chunk (memory bound and progress step); never
        changes the result.
    workers : int, optional
        Threads (default: all cores); never changes the result.
    progress : bool
        Show a tqdm progress bar.

    Returns
    -------
    `RawPlanes`

    Raises
    ------
    TypeError, astropy.units.UnitsError, ValueError
        On bad units, shapes, negative or non-finite input, an unknown engine,
        a switch that is not a bool, or ``engine="blocks"`` with read noise
        below 1 adu (or switched off while photon noise is on).

    Notes
    -----
    With ``photon_noise``, ``read_noise``, ``dither`` and ``truncation`` all
    False the planes are deterministic, Σ_k round((f E_k + D) / g) / 2^b, and
    both engines give exactly the same numbers.

    Examples
    --------
    >>> import numpy as np
    >>> import astropy.units as u
    >>> expected = np.full((6, 4, 5), 1e5) * u.electron
    >>> raw = integrate(expected, duration=1 * u.min, seed=1, flat=False, dark=False,
    ...                 progress=False)
    >>> raw.data.shape, raw.frames_per_plane.tolist()
    ((6, 4, 5), [600, 600, 600, 600, 600, 600])
    >>> expected_dn = 600 * 1e5 / 33 / 8
    >>> bool(np.all(np.abs(raw.data / expected_dn - 1) < 1e-3))
    True
    >>> exact = integrate(np.full((6, 4, 5), 33e3) * u.electron, duration=1 * u.min, flat=False,
    ...                   dark=False, photon_noise=False, read_noise=False, dither=False,
    ...                   truncation=False, progress=False)
    >>> bool(np.all(exact.data == 600 * 1000 / 8))
    True
    """
    inst = instruments.get(instrument)
    if engine not in ENGINES:
        raise ValueError(f"engine must be one of {ENGINES}, got {engine!r}")
    effects = {name: _switch(value, name) for name, value in (
        ("photon_noise", photon_noise), ("read_noise", read_noise), ("dither", dither),
        ("truncation", truncation))}
    schedule = inst.schedule(inst.default_duration if duration is None else duration)
    values = _check_expected(expected, schedule.n_planes)
    n_snap, _, ny, nx = values.shape
    snap = snapshot_index(schedule.n_frames, n_snap)
    root = as_seed_sequence(seed)
    flat_source, flat = _flat_map(flat, (ny, nx), inst, schedule.n_planes)
    dark_source, dark = _dark_map(dark, (ny, nx), inst)
    gain = inst.gain.to_value(u.electron / u.adu)
    sigma = inst.read_noise.to_value(u.adu)
    if not gain > 0 or sigma < 0:
        raise ValueError(f"instrument gain must be positive and read_noise non-negative, "
                         f"got {inst.gain} and {inst.read_noise}")
    if not effects["read_noise"]:
        sigma = 0.0
    nworkers = _workers(workers)
    frame_dither = schedule.dither.to_value(u.adu).astype(np.int64)
    dither_sum = schedule.dither_sum
    if not effects["dither"]:
        frame_dither = np.zeros_like(frame_dither)
        dither_sum = np.zeros_like(dither_sum)

    bits = inst.truncate_bits
    scale = 2.0**bits
    # A plane without frames (runs shorter than 2 LCVR states) holds an exact 0.
    centring = np.where(schedule.frames_per_plane > 0, (scale - 1) / (2 * scale), 0.0)
    offset = (centring - dither_sum / scale)[:, None, None]
    whole = _whole_numbers(values, flat, dark.to_value(u.electron), schedule, gain, sigma, bits, dither_sum)
    data = np.empty(values.shape[1:], dtype=np.float32 if whole else np.float64)

    def store(rows, sums):
        """A band of rows' integer sums → the planes in DN (so no whole integer copy is held)."""
        if whole and np.abs(sums).max(initial=0) >= _EXACT_FLOAT32:
            raise RuntimeError("a plane sum beyond float32's exact integers: _whole_numbers' bound failed")
        if effects["truncation"]:
            part = data[:, rows]
            np.copyto(part, sums >> bits, casting="unsafe")
            part += offset
        else:
            data[:, rows] = (sums - dither_sum[:, None, None]) / scale

    if engine == "frames":
        _run_frames(values, flat, dark.to_value(u.electron), schedule, snap, frame_dither, gain,
                    sigma, effects["photon_noise"], root, chunk_rows, nworkers, progress, store)
    elif not effects["photon_noise"] and not effects["read_noise"]:
        store(slice(None), _exact_sums(values, flat, dark.to_value(u.electron), schedule, snap, dither_sum,
                                       gain))
    else:
        if sigma < 1:
            raise ValueError(
                f"engine='blocks' treats each frame's rounding as uniform noise, which needs "
                f"read_noise >= 1 adu; got {sigma:g} adu (read_noise={effects['read_noise']}, "
                f"instrument read_noise {inst.read_noise}). Use engine='frames'.")
        _run_blocks(values, flat, dark.to_value(u.electron), schedule, snap, dither_sum, gain,
                    sigma, effects["photon_noise"], root, chunk_rows, nworkers, progress, store)

    header = _header(schedule, engine, root, flat_source, dark_source, n_snap, inst, effects,
                     frame_dither, dither_sum)
    return RawPlanes(data=data, frames_per_plane=schedule.frames_per_plane, header=header,
                     flat=flat, dark=dark)


#: float32 holds every integer below this exactly.
_EXACT_FLOAT32 = 2**24


def _whole_numbers(values, flat, dark, schedule, gain, sigma, bits, dither_sum):
    """
    Whether the planes are whole numbers of DN that float32 holds exactly: no truncation and no
    dither (HMI's camera), and sums far below 2^24 DN (a 12-σ bound of the photon and read noise).
    A full-disk HMI stack is then 0.8 GB instead of 1.6, with the same values.
    """
    if bits or np.any(dither_sum):
        return False
    frames = float(schedule.frames_per_plane.max(initial=0))
    lam = float(values.max(initial=0.0)) * float(flat.max(initial=0.0)) + float(dark.max(initial=0.0))
    bound = frames * (lam + 12 * np.sqrt(lam) + 12) / gain + 12 * (sigma + 1) * np.sqrt(frames) + frames
    return bound < _EXACT_FLOAT32 / 2


def _frame_segments(schedule, snap):
    """Frame ranges that share one snapshot: (start (n_seg+1,), snapshot (n_seg,))."""
    change = np.flatnonzero(np.diff(snap)) + 1
    start = np.concatenate([[0], change, [schedule.n_frames]]).astype(np.int64)
    return start, snap[start[:-1]].astype(np.int64)


def _run_frames(values, flat, dark, schedule, snap, dither, gain, sigma, photon, root, chunk_rows, workers,
                progress, store):
    import numba

    from gongsynth.stages.camera.kernels import frames_kernel

    n_snap, _, ny, nx = values.shape
    seg_start, seg_snap = _frame_segments(schedule, snap)
    plane = schedule.plane.astype(np.int64)
    key0, key1 = child_sequence(root, "camera-frames").generate_state(2, dtype=np.uint64)
    n_planes = schedule.n_planes
    previous = numba.get_num_threads()
    numba.set_num_threads(min(workers, numba.config.NUMBA_NUM_THREADS))
    try:
        with _progress(ny, progress, "frames") as bar:
            for r0, r1 in _chunks(ny, nx, chunk_rows, _FRAMES_CHUNK_PIXELS):
                npix = (r1 - r0) * nx
                lam = (values[:, :, r0:r1] * flat[None, :, r0:r1] + dark[r0:r1]).reshape(
                    n_snap, n_planes, npix)
                out = np.empty((n_planes, npix), dtype=np.int64)
                frames_kernel(lam, seg_start, seg_snap, plane, dither, 1.0 / gain, sigma, photon,
                              key0, key1, np.int64(r0 * nx), out)
                store(slice(r0, r1), out.reshape(n_planes, r1 - r0, nx))
                bar.update(r1 - r0)
    finally:
        numba.set_num_threads(previous)


def _snapshot_counts(schedule, snap, n_snap):
    """Frames of each (snapshot, plane), int64 (n_snap, K)."""
    counts = np.zeros((n_snap, schedule.n_planes), dtype=np.int64)
    np.add.at(counts, (snap, schedule.plane), 1)
    return counts


def _exact_sums(values, flat, dark, schedule, snap, dither_sum, gain):
    """
    Plane sums without photon or read noise: Σ_k round(λ_k / g) + Σd_k, exactly.

    Each frame's electrons are their mean λ = f E + D, so its rounding is
    deterministic and a snapshot's frames on a plane all round alike: the
    frames engine's arithmetic (λ × (1/g), then floor(x + 0.5)) times the
    frame count.
    """
    counts = _snapshot_counts(schedule, snap, values.shape[0])
    inv_gain = 1.0 / gain
    sums = np.zeros(values.shape[1:], dtype=np.int64)
    for s, lam in enumerate(values):
        adu = np.floor((lam * flat + dark) * inv_gain + 0.5).astype(np.int64)
        sums += counts[s][:, None, None] * adu
    return sums + dither_sum[:, None, None]


def _run_blocks(values, flat, dark, schedule, snap, dither_sum, gain, sigma, photon, root, chunk_rows,
                workers, progress, store):
    n_snap, _, ny, nx = values.shape
    # Frames of each (snapshot, plane): Σλ over a plane is Σ_snap count × λ_snap.
    counts = _snapshot_counts(schedule, snap, n_snap).astype(np.float64)
    frames = schedule.frames_per_plane.astype(np.float64)
    spread = np.sqrt(frames * sigma**2 + np.maximum(frames - 1, 0) / 12.0)[:, None]
    offset = dither_sum[:, None]
    n_planes = schedule.n_planes

    def work(rows):
        r0, r1 = rows
        signal = np.einsum("sp,spyx->pyx", counts, values[:, :, r0:r1])
        lam = signal * flat[:, r0:r1] + frames[:, None, None] * dark[r0:r1]
        sums = np.empty((n_planes, r1 - r0, nx), dtype=np.int64)
        for row in range(r0, r1):
            # One generator per detector row: independent of chunking and threads.
            rng = stage_generator(root, "camera-blocks", row)
            total = rng.poisson(lam[:, row - r0]) if photon else lam[:, row - r0]
            noise = rng.standard_normal((n_planes, nx))
            sums[:, row - r0] = np.floor(total / gain + spread * noise + 0.5).astype(np.int64) + offset
        store(slice(r0, r1), sums)
        return r1 - r0

    chunks = _chunks(ny, nx, chunk_rows, _BLOCKS_CHUNK_PIXELS)
    with _progress(ny, progress, "blocks") as bar:
        if workers == 1 or len(chunks) == 1:
            for rows in chunks:
                bar.update(work(rows))
        else:
            with ThreadPoolExecutor(max_workers=workers) as pool:
                for done in pool.map(work, chunks):
                    bar.update(done)


def _header(schedule, engine, root, flat_source, dark_source, n_snap, inst, effects, dither, dither_sum):
    from gongsynth.version import version as __version__

    header = fits.Header()
    entropy = int(root.entropy)
    header["ORIGIN"] = ("gongsynth", "simulated data, not an observation")
    header["DTYPE"] = ("SIMULATE", f"synthetic {inst.label} raw planes (never OBSERVE)")
    header["IMTYPE"] = ("RAW", f"{schedule.n_planes} accumulated planes, named by PLANEn")
    header["MAGNETO"] = (True, "magnetogram mode")
    header["BUNIT"] = ("DN", f"1 DN = 2**{inst.truncate_bits} adu, dither removed")
    header["GSVERS"] = (__version__, "gongsynth version")
    header["ENGINE"] = (engine, "camera engine (frames | blocks)")
    header["SEED"] = (entropy if entropy < 2**63 else str(entropy), "root seed entropy")
    if root.spawn_key:
        header["SEEDKEY"] = (" ".join(map(str, root.spawn_key)), "spawn key of the camera's SeedSequence")
    header["ITIME"] = (schedule.duration.to_value(u.s), "[s] observing time")
    header["EXPTIME"] = (inst.exposure_time.to_value(u.s), "[s] exposure of one frame")
    header["FRAMERAT"] = ((schedule.n_frames / schedule.duration).to_value(u.Hz), "[Hz] camera frame rate")
    header["NFRAMES"] = (schedule.n_frames, "frames in the observation")
    for key, card in schedule.header_cards().items():  # the instrument's own counters (GONG: ACCUM, COUNT)
        header[key] = card
    header["NSNAP"] = (n_snap, "input snapshots spread over the observation")
    header["GAIN"] = (inst.gain.to_value(u.electron / u.adu), "[e-/adu]")
    header["RDNOISE"] = (inst.read_noise.to_value(u.adu), "[adu] read noise per frame")
    header["TRUNCBIT"] = (inst.truncate_bits, "1 DN = 2**TRUNCBIT adu (if TRUNCATE)")
    scale = 2**inst.truncate_bits
    offset = (scale - 1) / (2 * scale) if effects["truncation"] else 0.0
    header["TRUNCOFF"] = (offset, "[DN] added back: mean truncation bias")
    header["DITHMEAN"] = (float(dither.mean()) if dither.size else 0.0, "[adu] mean dither per frame")
    header["PHOTNOIS"] = (effects["photon_noise"], "Poisson photon and dark noise drawn")
    header["READNOIS"] = (effects["read_noise"], "read noise added")
    header["DITHER"] = (effects["dither"], "dither added to the frames (and removed)")
    header["TRUNCATE"] = (effects["truncation"], "low bits dropped after accumulation")
    header["FLATSRC"] = (flat_source, "flat field: synthetic default, user or none")
    header["DARKSRC"] = (dark_source, "dark map: synthetic default, user or none")
    for p in range(schedule.n_planes):
        header[f"PLANE{p}"] = (inst.plane_names[p], f"plane {p}")
        header[f"NFRAME{p}"] = (int(schedule.frames_per_plane[p]), f"frames in plane {p}")
        if schedule.dither.value.any():  # an instrument without dither (HMI) records none
            header[f"DITHSUM{p}"] = (int(dither_sum[p]), f"[adu] dither summed in plane {p}")
    return header
