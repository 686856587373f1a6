r"""
The point-spread function of an instrument: Airy pattern of its aperture ⊗ seeing.

The PSF is the Airy pattern of the circular aperture D at the line wavelength
λ0 convolved with the seeing (paper Sec. 3.2, design §3.9).  Both factors
are known in Fourier space, so the radial profile is the Hankel transform of
the product of their optical transfer functions,

.. math::

    \mathrm{PSF}(r) = 2\pi\int_0^{\nu_c} \mathrm{OTF}_\mathrm{Airy}(\nu)\,
        \mathrm{OTF}_\mathrm{seeing}(\nu)\,J_0(2\pi\nu r)\,\nu\,d\nu, \qquad
    \mathrm{OTF}_\mathrm{Airy}(\nu) = \tfrac{2}{\pi}\big[\arccos s - s\sqrt{1-s^2}\big],
    \; s = \nu/\nu_c,

with cut-off :math:`\nu_c = D/\lambda_0` (0.2006 cycles per arcsec for
D = 2.8 cm).  The seeing is the paper's Gaussian of FWHM ``seeing_fwhm``,
:math:`\mathrm{OTF}_\mathrm{seeing} = e^{-2\pi^2\sigma^2\nu^2}`, or, with
the instrument's ``seeing_profile = "kolmogorov"``, the long-exposure
transfer function of Kolmogorov turbulence (Fried 1966, JOSA 56, 1372),
:math:`e^{-3.44(\lambda_0\nu/r_0)^{5/3}}` (ν per radian), with the Fried
parameter of the same FWHM, :math:`r_0 = 0.976\,\lambda_0/\mathrm{FWHM}`
(`KOLMOGOROV_FWHM`; 3.8 cm for 3.6″): the same core, heavier wings.  The
profile has unit integral over the plane and its first
Airy zero lies at :math:`1.22\lambda_0/D \approx 6.08''`.  Because the PSF is
band limited, point samples on any grid finer than :math:`\lambda_0/(2D)
\approx 2.49''` represent it exactly; kernels are point samples normalised to
unit sum (the Airy wings, ∝ r⁻³, put about 1 % of the energy beyond 100″:
the default kernel is truncated there, the instrument's ``psf_radius``).

An instrument may bring its own measured profile instead (``psf_model``,
``"module:function"`` of ``f(radius_arcsec, instrument)`` with unit integral
over the plane: HMI's Gaussian core and scattered-light wings,
`gongsynth.instruments.hmi.psf`); it is sampled, truncated at ``psf_radius``
and normalised the same way.

``seeing=False`` gives the diffraction-limited PSF (the Airy pattern alone,
FWHM 1.029 λ0/D ≈ 5.13″), as an instrument with ``seeing_fwhm = 0``.
The imaging operators that use these kernels are in `gongsynth.stages.optics`.
"""
import functools
import importlib
import math
import os

import astropy.units as u
import numpy as np
import scipy.interpolate
import scipy.special

from gongsynth import instruments
from gongsynth.validation import check_finite

__all__ = ["psf_profile", "psf_kernel", "normalize_kernel", "psf_instrument", "wrapped_kernel", "fft_workers",
           "seeing_profile", "KOLMOGOROV_FWHM"]

# Gauss-Legendre nodes of the Hankel transform over [0, ν_c]: the integrand
# oscillates ν_c r ≈ 30 times at r = 150″; 768 nodes give < 1e-9 relative error.
_N_HANKEL = 768
# Radial sampling (arcsec) of the profile that `psf_kernel` interpolates.
_SPLINE_STEP = 0.05
#: FWHM of Kolmogorov long-exposure seeing in units of λ/r0 (Dierickx 1992, J. Mod. Opt. 39, 569;
#: Tokovinin 2002, PASP 114, 1156, for an infinite outer scale).
KOLMOGOROV_FWHM = 0.976


def _cutoff_per_arcsec(inst):
    """Airy OTF cut-off D/λ0 in cycles per arcsec."""
    return float((inst.aperture / inst.line_wavelength).to_value(u.one) * u.arcsec.to(u.rad))


def _seeing_sigma(inst):
    return inst.seeing_fwhm.to_value(u.arcsec) / (2 * math.sqrt(2 * math.log(2)))


def seeing_profile(instrument):
    """
    The shape of an instrument's seeing: its ``seeing_profile``, or ``"gaussian"`` (the paper's) if none.

    Examples
    --------
    >>> from gongsynth import GONGInstrument
    >>> seeing_profile(GONGInstrument()), seeing_profile(GONGInstrument(seeing_profile="kolmogorov"))
    ('gaussian', 'kolmogorov')
    """
    return getattr(instrument, "seeing_profile", "gaussian")


def _seeing_otf(nu, inst):
    """The seeing's transfer function at ``nu`` (cycles per arcsec): Gaussian or Kolmogorov."""
    if seeing_profile(inst) == "gaussian":
        return np.exp(-2 * math.pi**2 * _seeing_sigma(inst) ** 2 * nu**2)
    fwhm = inst.seeing_fwhm.to_value(u.rad)
    if fwhm == 0:
        return np.ones_like(nu)
    wavelength = inst.line_wavelength.to_value(u.m)
    fried = KOLMOGOROV_FWHM * wavelength / fwhm          # r0 of that FWHM
    baseline = wavelength * nu / u.arcsec.to(u.rad)      # λν, ν in cycles per radian
    return np.exp(-3.44 * (baseline / fried) ** (5 / 3))


@functools.lru_cache(maxsize=1)
def _hankel_nodes():
    """
    Gauss-Legendre nodes and weights on [0, 1].

    Newton's iteration on P_n from Tricomi's estimates of the roots (a few
    milliseconds; `numpy.polynomial.legendre.leggauss` solves an eigenproblem
    that takes seconds on a loaded machine); the same nodes and weights to
    ~1e-15.
    """
    n = _N_HANKEL
    k = np.arange(1, n + 1)
    x = (1 - (n - 1) / (8.0 * n**3)) * np.cos(np.pi * (4 * k - 1) / (4 * n + 2))
    for _ in range(100):
        p0, p1 = np.ones_like(x), x
        for m in range(2, n + 1):
            p0, p1 = p1, ((2 * m - 1) * x * p1 - (m - 1) * p0) / m
        dp = n * (x * p1 - p0) / (x * x - 1)
        step = p1 / dp
        x = x - step
        if np.max(np.abs(step)) < 1e-16:
            break
    p0, p1 = np.ones_like(x), x
    for m in range(2, n + 1):
        p0, p1 = p1, ((2 * m - 1) * x * p1 - (m - 1) * p0) / m
    dp = n * (x * p1 - p0) / (x * x - 1)
    w = 2 / ((1 - x * x) * dp * dp)
    order = np.argsort(x)
    return 0.5 * (x[order] + 1), 0.5 * w[order]


def _instrument_model(inst):
    """The instrument's own PSF profile (``psf_model = "module:function"``), or None: Airy ⊗ seeing."""
    target = getattr(inst, "psf_model", None)
    if target is None:
        return None
    module, _, name = target.partition(":")
    return getattr(importlib.import_module(module), name)


def _profile(radius, inst):
    """PSF(r) per arcsec² for radii in arcsec (ndarray, any shape)."""
    model = _instrument_model(inst)
    if model is not None:
        return model(np.asarray(radius, dtype=float), inst)
    nu_c = _cutoff_per_arcsec(inst)
    s, w = _hankel_nodes()
    otf = (2 / math.pi) * (np.arccos(s) - s * np.sqrt(1 - s * s))
    otf *= _seeing_otf(s * nu_c, inst)
    weight = 2 * math.pi * nu_c**2 * w * s * otf  # dν = ν_c ds, ν = ν_c s
    r = np.asarray(radius, dtype=float)
    flat, inverse = np.unique(r.ravel(), return_inverse=True)
    values = np.empty(flat.size)
    for start in range(0, flat.size, 4096):  # bounded (4096 x nodes) temporaries
        block = flat[start:start + 4096]
        values[start:start + 4096] = scipy.special.j0(
            2 * math.pi * nu_c * np.outer(block, s)) @ weight
    return values[inverse].reshape(r.shape)


def psf_instrument(instrument=None, *, seeing=True):
    """
    The instrument whose PSF is wanted: as given, or without seeing.

    Parameters
    ----------
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
    seeing : bool
        False: the same instrument with ``seeing_fwhm = 0`` (diffraction only).

    Returns
    -------
    `~gongsynth.GONGInstrument`

    Examples
    --------
    >>> import astropy.units as u
    >>> psf_instrument(seeing=False).seeing_fwhm
    <Quantity 0. arcsec>
    """
    inst = instruments.get(instrument)
    if not isinstance(seeing, (bool, np.bool_)):
        raise TypeError(f"seeing must be True or False, got {seeing!r}")
    return inst if seeing else inst.replace(seeing_fwhm=0 * u.arcsec)


@u.quantity_input
def psf_profile(radius: u.arcsec, instrument=None, *, seeing=True):
    """
    Radial profile of the PSF (Airy ⊗ seeing), unit integral over the plane.

    Parameters
    ----------
    radius : `~astropy.units.Quantity`
        Angular distance from the centre, any shape, in angle units.
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
        Supplies ``aperture``, ``line_wavelength`` and ``seeing_fwhm``
        (0 arcsec gives the pure Airy pattern).
    seeing : bool
        False: the diffraction-limited PSF (no seeing), whatever ``seeing_fwhm``.

    Returns
    -------
    `~astropy.units.Quantity`
        PSF surface density in arcsec⁻², same shape as ``radius``.

    Examples
    --------
    >>> import astropy.units as u
    >>> import numpy as np
    >>> from gongsynth import GONGInstrument
    >>> airy = GONGInstrument(seeing_fwhm=0 * u.arcsec)
    >>> p = psf_profile([0, 6.08] * u.arcsec, airy)
    >>> bool(p[1] < 1e-4 * p[0])   # first Airy zero at 1.22 λ/D
    True
    >>> bool(np.isclose(psf_profile(6.08 * u.arcsec, seeing=False), p[1]))
    True
    """
    inst = psf_instrument(instrument, seeing=seeing)
    r = np.abs(radius.to_value(u.arcsec))
    check_finite(r, "radius")
    return u.Quantity(_profile(r, inst), u.arcsec**-2)


def _default_half_width(pixel_scale_arcsec, inst):
    radius = inst.psf_radius.to_value(u.arcsec)
    if not radius > 0:
        raise ValueError(f"instrument psf_radius must be positive, got {inst.psf_radius}")
    return max(1, int(math.ceil(radius / pixel_scale_arcsec)))


@functools.lru_cache(maxsize=16)
def _kernel_cached(scale, inst, shape):
    ny, nx = shape
    y = (np.arange(ny) - ny // 2) * scale
    x = (np.arange(nx) - nx // 2) * scale
    r = np.hypot(y[:, None], x[None, :])
    # The profile is band limited (ν ≤ 0.2 /″): a cubic spline through samples
    # every 0.05″ reproduces it to ~1e-8 and costs far less than every radius.
    grid = np.arange(0.0, r.max() + 4 * _SPLINE_STEP, _SPLINE_STEP)
    kernel = scipy.interpolate.CubicSpline(grid, _profile(grid, inst))(r)
    kernel /= kernel.sum()
    kernel.flags.writeable = False
    return kernel


@u.quantity_input
def psf_kernel(pixel_scale: u.arcsec, instrument=None, *, shape=None, seeing=True):
    """
    The PSF sampled on a grid of ``pixel_scale``, normalised to unit sum.

    The centre of the PSF is at index ``(ny // 2, nx // 2)``.  Samples are
    point values of `psf_profile`; this is exact for the band-limited PSF as
    long as ``pixel_scale`` is finer than λ0/(2D) ≈ 2.49″ and slightly aliased
    at GONG's 2.5″.

    Parameters
    ----------
    pixel_scale : `~astropy.units.Quantity`
        Grid spacing, angle (arcsec), positive.
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
    shape : int or (int, int), optional
        Kernel size in pixels.  Default: the odd square that reaches the
        instrument's ``psf_radius`` (100″) from the centre.
    seeing : bool
        False: the diffraction-limited kernel (no seeing).

    Returns
    -------
    `numpy.ndarray`
        2-D float64 kernel with unit sum (a read-only cached array; copy it to modify).

    Examples
    --------
    >>> import astropy.units as u
    >>> k = psf_kernel(0.5 * u.arcsec, shape=65)
    >>> k.shape, round(float(k.sum()), 12)
    ((65, 65), 1.0)
    """
    inst = psf_instrument(instrument, seeing=seeing)
    scale = float(pixel_scale.to_value(u.arcsec))
    if not (math.isfinite(scale) and scale > 0):
        raise ValueError(f"pixel_scale must be positive and finite, got {pixel_scale}")
    if shape is None:
        half = _default_half_width(scale, inst)
        shape = (2 * half + 1, 2 * half + 1)
    elif np.ndim(shape) == 0:
        shape = (int(shape), int(shape))
    shape = tuple(int(n) for n in shape)
    if len(shape) != 2 or min(shape) < 1:
        raise ValueError(f"shape must be a positive int or a pair of positive ints, got {shape}")
    return _kernel_cached(scale, inst, shape)


def normalize_kernel(kernel, name="psf"):
    """
    Check a user PSF array and scale it to unit sum.

    Parameters
    ----------
    kernel : array_like
        2-D array, finite, with a positive sum; centre at ``(ny // 2, nx // 2)``.
    name : str
        Argument name for error messages.

    Returns
    -------
    `numpy.ndarray`
        float64 copy with unit sum.

    Raises
    ------
    ValueError
        If the array is not 2-D, not finite, or its sum is not positive.

    Examples
    --------
    >>> float(normalize_kernel([[0, 1, 0], [1, 4, 1], [0, 1, 0]]).sum())
    1.0
    """
    if isinstance(kernel, u.Quantity):
        if kernel.unit.physical_type != "dimensionless":
            raise u.UnitsError(f"{name} must be dimensionless, got unit {kernel.unit}")
        kernel = kernel.to_value(u.one)
    k = np.array(kernel, dtype=float)
    if k.ndim != 2 or k.size == 0:
        raise ValueError(f"{name} must be a non-empty 2-D array, got shape {k.shape}")
    check_finite(k, name)
    total = k.sum()
    if not total > 0:
        raise ValueError(f"{name} cannot be normalised: its sum must be positive, got {total!r}")
    return k / total


def wrapped_kernel(kernel, shape, dtype):
    """
    A kernel embedded in an array of ``shape`` with its centre at [0, 0] (wrap-added).

    Parameters
    ----------
    kernel : `numpy.ndarray`
        2-D kernel, centre at ``(ky // 2, kx // 2)``.
    shape : (int, int)
        The transform's shape.
    dtype : dtype

    Returns
    -------
    `numpy.ndarray`
    """
    ky, kx = kernel.shape
    rows = (np.arange(ky) - ky // 2) % shape[0]
    cols = (np.arange(kx) - kx // 2) % shape[1]
    out = np.zeros(shape, dtype=dtype)
    if ky <= shape[0] and kx <= shape[1]:
        out[np.ix_(rows, cols)] = kernel
    else:
        np.add.at(out, np.ix_(rows, cols), kernel)
    return out


def fft_workers(workers):
    """
    Threads for `scipy.fft`: ``None`` means every core this process may use.

    Parameters
    ----------
    workers : int or None

    Returns
    -------
    int
    """
    if workers is None:
        try:
            return len(os.sched_getaffinity(0))
        except AttributeError:  # not on Linux
            return os.cpu_count() or 1
    return workers
