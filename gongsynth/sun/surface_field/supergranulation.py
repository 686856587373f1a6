r"""
The supergranular flow on the network's cells: outflow from each cell's centre to its walls.

Supergranulation is first a flow: a cellular pattern 30-35 Mm across, a
horizontal component of 300-400 m/s rms and a much weaker vertical one of
20-30 m/s rms, evolving over 24-48 h (Rincon & Rieutord 2018, Living Rev.
Sol. Phys. 15, 6, abstract and §2.1.3).  Its outflow sweeps the magnetic flux
to the cell walls, where the flow converges: the network of
`gongsynth.sun.surface_field.network` lies there.  `supergranular_flow` gives
the velocity of the same cells, so that the Dopplergram's supergranules and
the magnetogram's network are one pattern, as on the Sun.

The shape of a cell's flow (chosen, the simplest that has the observed
parts; not fitted): with d the distance of a point to its cell's centre and
w its distance to the nearest wall (the bisector of its centre and the next
one), s = d / (d + w) runs from 0 at the centre to 1 on the wall, and

.. math::

    \mathbf v_h = V_h\,\sin(\pi s)\,\hat{\mathbf e}_\mathrm{out}, \qquad
    v_z = V_z\,\big(\cos(\pi s) - \langle\cos(\pi s)\rangle\big),

:math:`\hat{\mathbf e}_\mathrm{out}` the horizontal direction away from the
centre: zero at the centre, fastest halfway, zero on the wall, where the
outflows of two cells meet (converge); up in the cell's middle, down near
its walls, no net vertical flow.  :math:`V_h` and :math:`V_z` scale the two
parts to the requested rms over the sphere: `HORIZONTAL_RMS` (350 m/s) and
`VERTICAL_RMS` (25 m/s), the middles of the ranges above.  A snapshot: a run lasts hours, a cell a day or two.
"""
import astropy.units as u
import numpy as np
from scipy.spatial import cKDTree

from gongsynth.validation import check_quantity

__all__ = ["supergranular_flow", "cell_flow_profile", "HORIZONTAL_RMS", "VERTICAL_RMS", "GRANULAR_FLOW_SCALE"]

#: RMS horizontal and vertical supergranular velocities (Rincon & Rieutord 2018: 300-400 and 20-30 m/s).
HORIZONTAL_RMS = 350 * u.m / u.s
VERTICAL_RMS = 25 * u.m / u.s
#: The largest scale a granulation keeps of its own flow where the supergranules flow too: granules
#: and mesogranules are 1-10 Mm (Rincon & Rieutord 2018, §2.1.4); beyond, the cells' flow is the flow.
GRANULAR_FLOW_SCALE = 10 * u.Mm


def cell_flow_profile(s, reference, horizontal_rms=HORIZONTAL_RMS, vertical_rms=VERTICAL_RMS):
    """
    A cell's outward speed and vertical velocity at s (0 at its centre, 1 on its walls), in m/s.

    The shape is sin(π s) outward and cos(π s) up, less its mean; each part is
    scaled so that its rms over the equal-area sample ``reference`` of s
    (the cells' whole area) is the requested one.

    Parameters
    ----------
    s, reference : array_like
        Where the flow is wanted; an equal-area sample of the cells.
    horizontal_rms, vertical_rms : `~astropy.units.Quantity`
        RMS outward speed and vertical velocity over ``reference`` (0 switches a part off).

    Returns
    -------
    along, rise : `numpy.ndarray`
        m/s, outward and up.

    Examples
    --------
    >>> s = np.linspace(0, 1, 5)
    >>> along, rise = cell_flow_profile(s, reference=np.sqrt(np.linspace(0, 1, 10001)))
    >>> [round(float(v)) for v in along], [round(float(v)) for v in rise]
    ([0, 350, 495, 350, 0], [61, 48, 17, -13, -26])
    """
    speeds = []
    for name, value in (("horizontal_rms", horizontal_rms), ("vertical_rms", vertical_rms)):
        speed = check_quantity(value, u.m / u.s, name).to_value(u.m / u.s)
        if np.ndim(speed) or not speed >= 0:
            raise ValueError(f"{name} must be a scalar speed >= 0, got {value}")
        speeds.append(float(speed))
    s, reference = np.asarray(s, dtype=float), np.asarray(reference, dtype=float)
    along_ref, rise_ref = np.sin(np.pi * reference), np.cos(np.pi * reference)
    scale_h = speeds[0] / max(np.sqrt(np.mean(along_ref ** 2)), 1e-300)
    scale_z = speeds[1] / max(rise_ref.std(), 1e-300)
    return scale_h * np.sin(np.pi * s), scale_z * (np.cos(np.pi * s) - rise_ref.mean())


def _fibonacci_sphere(n):
    """Unit vectors spread nearly evenly, ``n`` of them (a Fibonacci lattice): equal areas, deterministic."""
    k = np.arange(n) + 0.5
    z = 1 - 2 * k / n
    phi = np.pi * (3 - np.sqrt(5)) * k
    r = np.sqrt(1 - z ** 2)
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def _place_in_cell(tree, centres, points):
    """Each point's s (0 at its cell's centre, 1 on a wall) and unit vector away from the centre."""
    d, idx = tree.query(points, k=2)
    own, other = centres[idx[:, 0]], centres[idx[:, 1]]
    # Chord distances: to the own centre, and to the wall (the bisector plane of the two centres).
    wall = (d[:, 1] ** 2 - d[:, 0] ** 2) / (2 * np.linalg.norm(other - own, axis=1))
    s = d[:, 0] / np.maximum(d[:, 0] + wall, 1e-300)
    # Away from the centre along the sphere: the centre's direction with its radial part taken out.
    away = (own * points).sum(axis=1)[:, None] * points - own
    away /= np.maximum(np.linalg.norm(away, axis=1), 1e-300)[:, None]
    return s, away


def supergranular_flow(centres, points, *, horizontal_rms=HORIZONTAL_RMS, vertical_rms=VERTICAL_RMS):
    """
    The supergranular velocity at points on the sphere, cells given by their centres.

    Parameters
    ----------
    centres : array_like
        (n, 3) unit vectors of the cell centres
        (`~gongsynth.sun.surface_field.network.SupergranularNetwork.cells`).
    points : array_like
        (m, 3) unit vectors where the flow is wanted (the same axes).
    horizontal_rms, vertical_rms : `~astropy.units.Quantity`
        RMS horizontal speed and vertical velocity over the whole sphere
        (`HORIZONTAL_RMS`, `VERTICAL_RMS`); 0 switches a part off.

    Returns
    -------
    `~astropy.units.Quantity`
        (m, 3) velocity vectors in the axes of ``centres`` (m/s), tangent to
        the sphere plus the vertical part along ``points``.

    Notes
    -----
    The profile's scales (and the vertical part's mean) are measured on a
    Fibonacci lattice of 20 points per cell over the sphere, whatever
    ``points`` are: a point's flow does not depend on which others are asked.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> centres = rng.standard_normal((400, 3))
    >>> centres /= np.linalg.norm(centres, axis=1)[:, None]
    >>> points = rng.standard_normal((20000, 3))
    >>> points /= np.linalg.norm(points, axis=1)[:, None]
    >>> v = supergranular_flow(centres, points).to_value(u.m / u.s)
    >>> up = (v * points).sum(axis=1)
    >>> horizontal = v - up[:, None] * points
    >>> round(float(np.sqrt((horizontal ** 2).sum(axis=1).mean())), -1), round(float(up.std()))
    (350.0, 25)
    """
    centres = np.asarray(centres, dtype=float)
    points = np.asarray(points, dtype=float)
    for name, value in (("centres", centres), ("points", points)):
        if value.ndim != 2 or value.shape[1] != 3 or not np.all(np.isfinite(value)):
            raise ValueError(f"{name} must be an (n, 3) array of finite unit vectors, "
                             f"got shape {value.shape}")
    if centres.shape[0] < 2:
        raise ValueError(f"centres must hold at least two cells, got {centres.shape[0]}")
    tree = cKDTree(centres)
    reference, _ = _place_in_cell(tree, centres, _fibonacci_sphere(20 * centres.shape[0]))
    s, away = _place_in_cell(tree, centres, points)
    along, rise = cell_flow_profile(s, reference, horizontal_rms, vertical_rms)
    return u.Quantity(along[:, None] * away + rise[:, None] * points, u.m / u.s, copy=False)
