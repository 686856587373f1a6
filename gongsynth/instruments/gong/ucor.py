r"""
GONG's per-minute image rotation: the camera's rotated view, and the reduction's interpolation back.

GONG's reduction resamples **every one-minute image once** before the
minutes are averaged.  The processing history of the Big Bear magnetogram of
2009-09-05 18:54 (``GHIST000``-``GHIST012``) records the task that made each
one-minute image: ``Task UCOR ... cal_image=./wlmnbcavg.fits, ...,
rot=1.785431, interp=4; sw_vmbi=yes`` — the calibration, the velocity,
modulation, field and intensity images (``vmbi``), and a rotation by
1.785431°, which is the file's rotator position ``ROTATOR`` =
−0.031161648 rad = −1.785431° with the sign changed: UCOR turns the image
by the angle the image rotator stands at.  The nine one-minute images are
averaged afterwards (``N_USED``, `gongsynth.stages.averaging`).  What this
does to the noise is what the noise statistics see: interpolation correlates
neighbouring pixels, so the pixel-to-pixel (pixel-difference) noise falls
more than the noise of a box, and by a different amount in every pixel,
since a rotation about the rotator's axis shifts each pixel by its own
fraction of a pixel (at 1.785° the fraction cycles every 1/0.0312 = 32
pixels).

**The interpolant.**  ``interp=4`` is not documented by GONG.  GONG's
reduction runs in IRAF (the header's ``IRAFNAME``, the ``.imh`` images of
``HISTORY``), and IRAF's 2-D image interpolants (``math/iminterp``) are
numbered 1 nearest, 2 linear, 3 bicubic polynomial ("poly3"), 4 biquintic
polynomial ("poly5"), 5 bicubic spline: the default here reads 4 as the
biquintic polynomial, i.e. the tensor product of the 6-point Lagrange
polynomial through the neighbouring pixels in each axis.  That is a reading,
not GONG's documentation; ``image_interpolant`` also offers ``"poly3"``
(4 × 4 points) and ``"linear"`` (bilinear) to bracket it.  The rotation's
centre, the rotator's axis (GONG calibrates it with a pinhole), is not in the
header; the detector's centre stands for it.

**The model.**  gongsynth renders the Sun on the product's grid, so with
``effects.image_rotation`` the camera stage first turns the noiseless
expected counts by −θ onto the camera's grid (`to_camera`: an approximation
of rendering the optics on rotated pixels, done with the same interpolant on
counts band-limited by the PSF, see the guide), the camera adds its noise
there, and the reduction turns the observables by +θ back (`from_camera`,
the UCOR step).  GONG turns each minute before averaging; the turn is the
same linear interpolation every minute, so turning the minutes' average, as
the chain does, gives the same maps at a ninth of the cost.  The two rotations
cancel geometrically (the maps keep their WCS, the truth maps stay aligned)
and the noise goes through exactly one interpolation, as GONG's does.
Pixels whose interpolation reaches beyond the detector take the nearest edge
pixel (full-disk runs: sky; tiled runs: the corners' outermost ~20 pixels).
"""
import dataclasses

import astropy.units as u
import numpy as np

__all__ = ["INTERPOLANTS", "lagrange_weights", "rotate_image", "to_camera", "from_camera"]

#: Accepted ``image_interpolant`` values and their points per axis (IRAF's 2-D interpolants 2-4).
INTERPOLANTS = {"linear": 2, "poly3": 4, "poly5": 6}


def lagrange_weights(fraction, points):
    """
    Weights of the Lagrange polynomial through ``points`` equally spaced samples, at a fractional offset.

    Parameters
    ----------
    fraction : array_like
        Offsets t in [0, 1) from sample 0 towards sample 1.
    points : int
        Samples in the stencil, even (2: linear, 4: cubic, 6: quintic); they
        sit at offsets ``-(points/2 - 1) .. points/2`` from sample 0.

    Returns
    -------
    `numpy.ndarray`
        Shape ``(points,) + fraction.shape``; they sum to 1 and reproduce
        polynomials of degree ``points - 1`` exactly.

    Examples
    --------
    >>> lagrange_weights(0.5, 6) * 256
    array([  3., -25., 150., 150., -25.,   3.])
    """
    if points not in INTERPOLANTS.values():
        raise ValueError(f"points must be one of {sorted(INTERPOLANTS.values())}, got {points!r}")
    t = np.asarray(fraction, dtype=float)
    nodes = np.arange(points) - (points // 2 - 1)
    weights = np.ones((points,) + t.shape)
    for j, xj in enumerate(nodes):
        for m, xm in enumerate(nodes):
            if m != j:
                weights[j] *= (t - xm) / (xj - xm)
    return weights


def _angle(angle, name="angle"):
    try:
        return float(u.Quantity(angle).to_value(u.rad))
    except (TypeError, u.UnitsError) as exc:
        raise TypeError(f"{name} must be an angle Quantity, got {angle!r}") from exc


def _sources(shape, theta, centre=None):
    """(y, x) in the input of every output pixel of a turn by ``theta`` (rad) about ``centre``."""
    ny, nx = shape
    cy, cx = ((ny - 1) / 2, (nx - 1) / 2) if centre is None else (float(centre[0]), float(centre[1]))
    qy, qx = np.mgrid[:ny, :nx].astype(np.float64)
    cos, sin = np.cos(theta), np.sin(theta)
    return cy - sin * (qx - cx) + cos * (qy - cy), cx + cos * (qx - cx) + sin * (qy - cy)


def rotate_image(images, angle, *, interpolant="poly5", centre=None):
    """
    Images turned by ``angle`` about ``centre`` on their own grid, by separable Lagrange interpolation.

    The output pixel q takes the value at c + R(−angle)(q − c) of the input
    (the image content turns counter-clockwise by ``angle`` with x the last
    axis and y the first); taps beyond the image take the nearest edge pixel.

    Parameters
    ----------
    images : array_like or `~astropy.units.Quantity`
        ``(..., ny, nx)``; every leading slice is turned alike.
    angle : `~astropy.units.Quantity`
        Rotation angle.
    interpolant : {"linear", "poly3", "poly5"}
        Points per axis 2, 4 or 6 (see the module notes).
    centre : (float, float), optional
        (y, x) of the rotation axis in pixels (default the array's centre).

    Returns
    -------
    `numpy.ndarray` or `~astropy.units.Quantity`
        Same shape and unit, float64.

    Examples
    --------
    A plane (degree 1) is reproduced exactly, and a turn by +θ then −θ
    returns a smooth image to within the interpolation error:

    >>> import numpy as np, astropy.units as u
    >>> y, x = np.mgrid[:64, :64]
    >>> plane = 2.0 * x - 0.5 * y
    >>> turned = rotate_image(plane, 10 * u.deg)
    >>> c = 31.5
    >>> xs = c + np.cos(np.radians(10)) * (x - c) + np.sin(np.radians(10)) * (y - c)
    >>> ys = c - np.sin(np.radians(10)) * (x - c) + np.cos(np.radians(10)) * (y - c)
    >>> inside = (xs > 3) & (xs < 60) & (ys > 3) & (ys < 60)
    >>> bool(np.allclose(turned[inside], (2.0 * xs - 0.5 * ys)[inside]))
    True
    """
    if interpolant not in INTERPOLANTS:
        raise ValueError(f"interpolant must be one of {sorted(INTERPOLANTS)}, got {interpolant!r}")
    theta = _angle(angle)
    unit = getattr(images, "unit", None)
    data = np.asarray(getattr(images, "value", images), dtype=np.float64)
    if data.ndim < 2:
        raise ValueError(f"images must have at least 2 dimensions (..., ny, nx), got shape {data.shape}")
    ny, nx = data.shape[-2:]
    sy, sx = _sources((ny, nx), theta, centre)
    points = INTERPOLANTS[interpolant]
    x0, y0 = np.floor(sx), np.floor(sy)
    wx, wy = lagrange_weights(sx - x0, points), lagrange_weights(sy - y0, points)
    offsets = np.arange(points) - (points // 2 - 1)
    ix = [np.clip(x0.astype(np.intp) + o, 0, nx - 1) for o in offsets]
    iy = [np.clip(y0.astype(np.intp) + o, 0, ny - 1) * nx for o in offsets]
    flat = data.reshape(-1, ny * nx)
    out = np.zeros_like(flat)
    for a in range(points):
        for b in range(points):
            out += flat[:, iy[a] + ix[b]].reshape(flat.shape[0], -1) * (wy[a] * wx[b]).ravel()
    out = out.reshape(data.shape)
    return out if unit is None else out * unit


def to_camera(expected, instrument):
    """
    The expected counts as the rotated camera sees them: turned by −``image_rotation_angle``.

    Parameters
    ----------
    expected : `~astropy.units.Quantity`
        ``(planes, ny, nx)`` expected counts on the product's grid.
    instrument : `~gongsynth.GONGInstrument`
        Supplies ``image_rotation_angle`` and ``image_interpolant``.

    Returns
    -------
    `~astropy.units.Quantity`
        The same on the camera's grid.
    """
    return rotate_image(expected, -instrument.image_rotation_angle, interpolant=instrument.image_interpolant)


def from_camera(observables, instrument):
    """
    One reduction's maps turned back by +``image_rotation_angle`` onto the product's grid (GONG's UCOR).

    Parameters
    ----------
    observables : `~gongsynth.instruments.base.Observables`
        Reduced on the camera's grid.
    instrument : `~gongsynth.GONGInstrument`

    Returns
    -------
    `~gongsynth.instruments.base.Observables`
        ``magnetogram``, ``doppler``, ``continuum``, ``velocity`` and
        ``phase`` interpolated; ``wrapped`` taken from the nearest camera pixel.
    """
    angle, kind = instrument.image_rotation_angle, instrument.image_interpolant
    names = ("magnetogram", "doppler", "continuum", "velocity", "phase")
    turned = {name: rotate_image(getattr(observables, name), angle, interpolant=kind) for name in names
              if getattr(observables, name) is not None}
    wrapped = observables.wrapped
    if wrapped is not None:
        # Nearest neighbour: a flag is not interpolated.
        ny, nx = np.shape(wrapped)[-2:]
        sy, sx = _sources((ny, nx), _angle(angle))
        nearest = (np.clip(np.rint(sy), 0, ny - 1).astype(np.intp) * nx
                   + np.clip(np.rint(sx), 0, nx - 1).astype(np.intp))
        wrapped = np.asarray(wrapped).reshape(-1, ny * nx)[:, nearest].reshape(np.shape(wrapped))
    return dataclasses.replace(observables, wrapped=wrapped, **turned)
