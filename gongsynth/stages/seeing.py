r"""
Seeing that changes from frame to frame: image motion and its crosstalk into the accumulated planes.

The PSF (`gongsynth.stages.psf`) holds the seeing of a long exposure, a
Gaussian of FWHM ``seeing_fwhm``.  A ground-based magnetograph does not see
that average in every frame: the image moves from frame to frame, and the
planes of the two polarisation states (GONG: I+V and I-V, alternating every
``lcvr_period`` = 1 s) and of the wave-plate channels (one per frame at 60 Hz)
are accumulated over *different* frames, so each plane sees its own sample of
the motion.  Their difference is seeing-induced crosstalk: intensity and
velocity gradients leak into the phases and so into the magnetogram, most
where the image is steepest (the limb, sunspots).  This module draws that
motion and returns the planes each accumulation really sees.

**The motion.**  GONG's 2.8 cm aperture is smaller than the Fried parameter
(r0 = 0.98 λ/FWHM = 3.8 cm for 3.6″ at 676.8 nm), so its short-exposure image
is close to the diffraction limit and the seeing is image motion (Fried 1966,
JOSA 56, 1372): each axis moves by a Gaussian of variance σ² = the PSF's
seeing variance, (FWHM / 2.355)².  The motion's temporal spectrum is that of
the tilt over an aperture D carried by a turbulent layer at speed v (Conan,
Rousset & Madec 1995, JOSA A 12, 1559; Tyler 1994, JOSA A 11, 358):

.. math::

    P(f) \propto (f^2 + f_0^2)^{-1/3}\,\big[1 + (f/f_c)^3\big]^{-1},
    \qquad f_c = 0.3\,v/D, \quad f_0 = v/L_0,

:math:`f^{-2/3}` below the aperture's cut-off :math:`f_c` (54 Hz for
v = 5 m/s), the centroid tilt's :math:`f^{-11/3}` above it, flattened below
:math:`v/L_0` by the outer scale :math:`L_0` (von Kármán).  A frame averages
the motion over its exposure (a sinc² filter at the frame rate, with the
aliases folded in); what moves within a frame stays in the PSF.  Image
motion is coherent over an angle D/h for turbulence at height h, so the
detector is covered by nodes ``D / seeing_layer_height`` apart (58″ for
h = 100 m), each with its own independent motion.

**The planes.**  To second order in the small differences between one
plane's frames and the ensemble the PSF already holds, a plane p that
accumulates frames k with displacements :math:`\delta_k` sees

.. math::

    E_p' = E_p - \bar\delta_p\cdot\nabla E_p
        + \tfrac12\big(\overline{\delta\delta^T}_p - \sigma_f^2\,\mathbb 1\big) : \nabla\nabla E_p,

with :math:`\bar\delta_p` and :math:`\overline{\delta\delta^T}_p` the mean and
second moment of its frames' displacements and :math:`\sigma_f^2` their
ensemble variance: a shift and a blur of its own.  The coefficients are
computed at the nodes and interpolated bilinearly to the pixels, divided by
the root of the sum of the squared weights so that their variance is the
same everywhere; the derivatives are central differences on the detector
pixels.  The camera then draws its noise from these planes, so the photon
statistics are unchanged (a sum of Poisson variates is Poisson).

**Parameters** (the instrument's): ``seeing_fwhm`` (σ, paper Sec. 3.2),
``aperture`` (D), ``seeing_wind_speed`` (v, 5 m/s: a typical near-ground
daytime wind — unpublished for GONG, a choice; the Big Bear header of
2009-09-05 reads ``WIND_SPD = 3.3`` m/s), ``seeing_outer_scale`` (L0 = 20 m,
the median of the GSM campaigns, Ziad et al. 2004, Appl. Opt. 43, 2316) and
``seeing_layer_height`` (h = 100 m: daytime seeing is dominated by the
lowest few hundred metres, Kellerer et al. 2012, A&A 542, A2 at Big Bear —
an effective height chosen, not measured for GONG).

The motion is drawn from the run's seed (stream ``"frame-seeing"``) node by
node in a fixed order, before and independently of the camera's chunking:
the same seed gives the same bits whatever ``chunk_rows`` and ``workers``.
"""
import math

import astropy.units as u
import numpy as np

from gongsynth.seeding import as_seed_sequence

__all__ = ["motion_spectrum", "FrameMotion", "frame_motion", "SeeingPlanes"]

# Aliases folded into the frame-averaged spectrum on each side.
_ALIASES = 6
_FWHM_PER_SIGMA = 2 * math.sqrt(2 * math.log(2))
_ARCSEC_PER_RAD = 206264.80624709636


def _hz(value, unit, name):
    try:
        return float(u.Quantity(value).to_value(unit))
    except (TypeError, u.UnitsError) as exc:
        raise TypeError(f"{name} must be a Quantity in {unit}, got {value!r}") from exc


def motion_spectrum(frequency, instrument):
    r"""
    One-axis power spectrum of the image motion, unit-free shape (see the module notes).

    Parameters
    ----------
    frequency : `~astropy.units.Quantity`
        Frequencies (Hz), any shape.
    instrument : `~gongsynth.GONGInstrument`
        Supplies ``aperture``, ``seeing_wind_speed`` and ``seeing_outer_scale``.

    Returns
    -------
    `numpy.ndarray`
        :math:`(f^2 + f_0^2)^{-1/3} [1 + (f/f_c)^3]^{-1}`, same shape.

    Examples
    --------
    >>> import astropy.units as u
    >>> from gongsynth import GONGInstrument
    >>> p = motion_spectrum([1, 10, 100, 1000] * u.Hz, GONGInstrument())
    >>> bool(p[0] > p[1] > p[2] > p[3])
    True
    """
    f = np.abs(_hz(frequency, u.Hz, "frequency") if np.ndim(frequency) == 0
               else u.Quantity(frequency).to_value(u.Hz))
    v = _hz(instrument.seeing_wind_speed, u.m / u.s, "seeing_wind_speed")
    f_c = 0.3 * v / instrument.aperture.to_value(u.m)
    f_0 = v / instrument.seeing_outer_scale.to_value(u.m)
    return (f**2 + f_0**2) ** (-1 / 3) / (1 + (f / f_c) ** 3)


def _frame_autocovariance(n, instrument):
    """
    Autocovariance (arcsec²) of one axis of the frame-averaged motion at lags 0 .. n-1 frames.

    The instantaneous two-sided spectrum, normalised to the seeing variance σ²,
    times the exposure's sinc² and folded at the frame rate (the aliases
    added), transformed back on a grid of 4n frames.
    """
    rate = instrument.frame_rate.to_value(u.Hz)
    sigma2 = (instrument.seeing_fwhm.to_value(u.arcsec) / _FWHM_PER_SIGMA) ** 2
    f = np.geomspace(1e-6, 1e6, 40001)
    norm = sigma2 / (2 * np.trapezoid(motion_spectrum(f * u.Hz, instrument), f))
    length = 4 * n
    freq = np.fft.rfftfreq(length, 1 / rate)
    alias = [freq + k * rate for k in range(-_ALIASES, _ALIASES + 1)]
    folded = sum(motion_spectrum(g * u.Hz, instrument) * np.sinc(g / rate) ** 2 for g in alias)
    return np.fft.irfft(norm * folded, n=length)[:n] * rate


def _plane_covariances(weights, lag_covariance):
    """Σ_kl w_p[k] w_q[l] c(|k - l|) for every pair of weight rows (FFT convolution, no wrap)."""
    n = weights.shape[1]
    length = 2 * n
    kernel = np.zeros(length)
    kernel[:n] = lag_covariance
    kernel[length - n + 1:] = lag_covariance[1:][::-1]
    conv = np.fft.irfft(np.fft.rfft(weights, length, axis=1) * np.fft.rfft(kernel), length, axis=1)[:, :n]
    cov = weights @ conv.T
    return 0.5 * (cov + cov.T)


def _factor(cov):
    """A factor F with F Fᵀ = cov, for a covariance that may be singular (planes without frames)."""
    vals, vecs = np.linalg.eigh(cov)
    return vecs * np.sqrt(np.clip(vals, 0, None))


class FrameMotion:
    """
    Each plane's mean and second moment of the frames' image displacements, at the motion's nodes.

    Attributes
    ----------
    mean : `numpy.ndarray`
        Shape (n_groups, K, 2, ny_nodes, nx_nodes): mean displacement (arcsec,
        y then x) of the frames of each group (a minute, or the whole run) and plane.
    second : `numpy.ndarray`
        Shape (n_groups, K, 3, ny_nodes, nx_nodes): mean of δy², δx², δy δx (arcsec²).
    sigma_f2 : float
        Ensemble variance of one frame's displacement per axis (arcsec²).
    node_spacing : float
        Arcsec between nodes (inf: one node, the whole image moves together).
    """

    def __init__(self, mean, second, sigma_f2, node_spacing):
        self.mean, self.second, self.sigma_f2, self.node_spacing = mean, second, sigma_f2, node_spacing


def _node_count(n_pixels, pixel, spacing):
    if not np.isfinite(spacing):
        return 1
    return max(1, int(math.ceil(n_pixels * pixel / spacing)) + 1)


def frame_motion(schedule, shape, instrument, seed, *, groups=1):
    """
    Draw the image motion of every frame and reduce it to each plane's moments.

    Parameters
    ----------
    schedule : `~gongsynth.instruments.base.FrameSchedule`
        The run's frames (their plane).
    shape : (int, int)
        Detector shape (ny, nx).
    instrument : `~gongsynth.GONGInstrument`
        ``seeing_fwhm``, ``aperture``, ``frame_rate``, ``plate_scale`` and the
        ``seeing_*`` parameters (module notes).
    seed : seed-like
        The motion's seed (`gongsynth.seeding.as_seed_sequence`).
    groups : int
        Consecutive equal groups of frames reduced separately (the minutes of a
        run whose one-minute magnetograms are averaged); must divide the frames.

    Returns
    -------
    `FrameMotion`

    Examples
    --------
    >>> import astropy.units as u
    >>> from gongsynth import GONGInstrument
    >>> gong = GONGInstrument()
    >>> m = frame_motion(gong.schedule(1 * u.min), (40, 40), gong, seed=1)
    >>> m.mean.shape, round(m.sigma_f2, 2)
    ((1, 6, 2, 3, 3), 1.66)
    >>> bool(abs(m.mean).max() < 0.5)     # a plane's 600 frames average the motion down
    True
    """
    n = schedule.n_frames
    if not (isinstance(groups, int) and groups >= 1 and n % groups == 0):
        raise ValueError(f"groups must be a positive int dividing the {n} frames, got {groups!r}")
    pixel = instrument.plate_scale.to_value(u.arcsec)
    height = instrument.seeing_layer_height.to_value(u.m)
    spacing = instrument.aperture.to_value(u.m) / height * _ARCSEC_PER_RAD if height > 0 else math.inf
    ny_nodes, nx_nodes = (_node_count(s, pixel, spacing) for s in shape)
    k_planes = schedule.n_planes
    # One group's frames (every group has the same schedule: GONG's minutes repeat exactly).
    per_group = n // groups
    plane = np.asarray(schedule.plane[:per_group])
    weights = np.zeros((k_planes, per_group))
    weights[plane, np.arange(per_group)] = 1.0
    weights /= np.maximum(weights.sum(axis=1, keepdims=True), 1.0)
    lag = _frame_autocovariance(per_group, instrument)
    sigma_f2 = float(lag[0])
    # Plane means: Gaussian, covariance Σ w w c.  Second moments less σ_f²: sums of many correlated
    # squares, Gaussian to a good approximation, covariance 2 Σ w w c² (Isserlis); the cross
    # moment δy δx: Σ w w c².  Means and second moments are uncorrelated; groups (minutes) are
    # independent (the motion decorrelates in seconds).
    factor_mean = _factor(_plane_covariances(weights, lag))
    factor_square = _factor(_plane_covariances(weights, lag**2))
    rng = np.random.Generator(np.random.PCG64(as_seed_sequence(seed)))
    z = rng.standard_normal((groups, 5, k_planes, ny_nodes, nx_nodes))
    mean = np.einsum("pq,gcqyx->gpcyx", factor_mean, z[:, :2])
    second = np.einsum("pq,gcqyx->gpcyx", factor_square, z[:, 2:])
    second[:, :, :2] *= math.sqrt(2)
    second[:, :, :2] += sigma_f2
    return FrameMotion(mean, second, sigma_f2, spacing)


def _weights(n_pixels, n_nodes, pixel, spacing):
    """
    Bilinear interpolation along one axis: for each pixel the lower node, and the two nodes'
    weights scaled to unit norm (so that an interpolated field keeps the nodes' variance).
    """
    if n_nodes == 1:
        return np.zeros(n_pixels, dtype=int), np.ones(n_pixels), np.zeros(n_pixels)
    pos = np.arange(n_pixels) * pixel / spacing
    i0 = np.clip(np.floor(pos).astype(int), 0, n_nodes - 2)
    t = pos - i0
    norm = np.sqrt((1 - t) ** 2 + t**2)
    return i0, (1 - t) / norm, t / norm


class SeeingPlanes:
    """
    The planes each group of frames (a minute) accumulates: each shifted and blurred by its own motion.

    Parameters
    ----------
    expected : `~astropy.units.Quantity` or `numpy.ndarray`
        Expected counts per frame, shape (K, ny, nx), with the long-exposure
        seeing already in them (the PSF).
    motion : `FrameMotion`
    instrument : `~gongsynth.GONGInstrument`
        Supplies ``plate_scale``.

    Notes
    -----
    ``planes[g]`` gives group g's planes: same type and shape as
    ``expected``, non-negative.  The derivatives of ``expected`` are computed
    once (float32).

    Examples
    --------
    >>> import numpy as np, astropy.units as u
    >>> from gongsynth import GONGInstrument
    >>> gong = GONGInstrument()
    >>> m = frame_motion(gong.schedule(1 * u.min), (16, 16), gong, seed=2)
    >>> flat = np.full((6, 16, 16), 1e4) * u.electron
    >>> bool(np.all(SeeingPlanes(flat, m, gong)[0] == flat))   # a uniform image has no crosstalk
    True
    """

    def __init__(self, expected, motion, instrument):
        self.unit = getattr(expected, "unit", None)
        values = np.asarray(getattr(expected, "value", expected))
        if values.ndim != 3:
            raise ValueError(f"expected must have shape (K, ny, nx), got {values.shape}")
        self.values, self.motion = values, motion
        self.pixel = instrument.plate_scale.to_value(u.arcsec)
        ny_nodes, nx_nodes = motion.mean.shape[-2:]
        self.wy = _weights(values.shape[1], ny_nodes, self.pixel, motion.node_spacing)
        self.wx = _weights(values.shape[2], nx_nodes, self.pixel, motion.node_spacing)
        # Per plane: d/dy, d/dx, d²/dy², d²/dx², d²/dydx (central differences, pixels).
        self.derivatives = np.empty((values.shape[0], 5) + values.shape[1:], dtype=np.float32)
        for p, plane in enumerate(values):
            gy, gx = np.gradient(np.asarray(plane, dtype=np.float64))
            self.derivatives[p, 0], self.derivatives[p, 1] = gy, gx
            self.derivatives[p, 2] = np.gradient(gy, axis=0)
            self.derivatives[p, 3] = np.gradient(gx, axis=1)
            self.derivatives[p, 4] = np.gradient(gy, axis=1)

    def _field(self, nodes):
        """A node grid interpolated to the pixels (separable; float32)."""
        (iy, ay, by), (ix, ax, bx) = self.wy, self.wx
        if nodes.shape[0] == 1:
            rows = np.broadcast_to(nodes[0], (iy.size, nodes.shape[1]))
        else:
            rows = ay[:, None] * nodes[iy] + by[:, None] * nodes[iy + 1]
        rows = rows.astype(np.float32)
        if nodes.shape[1] == 1:
            return np.repeat(rows, ix.size, axis=1)
        return rows[:, ix] * ax.astype(np.float32) + rows[:, ix + 1] * bx.astype(np.float32)

    def __len__(self):
        return self.motion.mean.shape[0]

    def __getitem__(self, group):
        m = self.motion
        out = np.array(self.values, dtype=np.float32)
        centred = np.array([m.sigma_f2, m.sigma_f2, 0.0])[:, None, None]
        for p in range(out.shape[0]):
            d = self.derivatives[p]
            # Coefficients of the five derivatives: -δy, -δx, ½ Syy, ½ Sxx, Syx (pixels, pixels²).
            shift = -m.mean[group, p] / self.pixel
            blur = (m.second[group, p] - centred) / self.pixel**2 * np.array([0.5, 0.5, 1.0])[:, None, None]
            for k, nodes in enumerate((shift[0], shift[1], blur[0], blur[1], blur[2])):
                term = self._field(nodes)
                term *= d[k]
                out[p] += term
        np.maximum(out, 0.0, out=out)
        out = out.astype(self.values.dtype) if self.values.dtype == np.float64 else out
        return out * self.unit if self.unit is not None else out
