r"""
The per-sample work of a full-disk scene (numba): which patch column lies under each sample, and its channels.

Every sample of the supersampled grid is traced to the solar sphere exactly
as `gongsynth.geometry.disk_geometry` does (observer at distance D, latitude
B0, solar north up), giving its Stonyhurst longitude, latitude and μ.  The
solar surface is cut into cells of ``cell_km`` in the sinusoidal plane
(x = R ℓ cos b, y = R b).  Each cell lays each library level's patch with its
own random offset, mirror and seed variant (a hash of the run's seed, the
level and the cell), turned about the cell centre so that the observer, seen
from the cell centre, lies toward the patch's +x: the direction the library
was synthesised for.  A sample's local offset from its cell centre (west,
north, in km) then picks the patch column (nearest column: point sampling).

The large-scale radial field and velocity are read bilinearly from a
regular Stonyhurst grid (`gongsynth.stages.scene.surface.LargeScale`).  Per
sample the library rows of the two viewing angles around its own and
the two levels around the local |B_r| are mixed linearly (a sub-sample
filling factor: light and true field mix alike), the stored V and B·n take
the sign of B_r (the quiet level a random sign per cell), the true B·n is
B_z μ + B_x sin θ of the mixed columns (exact at the sample's angle), the
continuum limb
darkening is put back at the sample's own μ, and the Doppler basis gives the
six channel values at the sample's large-scale line-of-sight velocity.
"""
import math

import numba as nb
import numpy as np

from gongsynth.threads import run_chunks

__all__ = ["cell_table", "render_disk", "disk_counts"]

@nb.njit(cache=True, inline="always")
def _splitmix(state):
    """One step of splitmix64: (new state, 64 random bits)."""
    state = state + np.uint64(0x9E3779B97F4A7C15)
    z = state
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return state, z ^ (z >> np.uint64(31))


@nb.njit(cache=True, inline="always")
def _bracket(nodes, x):
    """Index k and weight w with x ≈ (1 - w) nodes[k] + w nodes[k + 1]; clamped at both ends."""
    n = nodes.size
    if x <= nodes[0]:
        return 0, 0.0
    if x >= nodes[n - 1]:
        return n - 2, 1.0
    k = np.searchsorted(nodes, x) - 1
    return k, (x - nodes[k]) / (nodes[k + 1] - nodes[k])


@nb.njit(cache=True, inline="always")
def _bilinear2(first, second, lon0, lat0, step, lon, lat):
    """Bilinear values of two (nlat, nlon) grids on one lattice at (lon, lat) in deg; clamped at the edges."""
    nlat, nlon = first.shape
    x = min(max((lon - lon0) / step, 0.0), nlon - 1.000001)
    y = min(max((lat - lat0) / step, 0.0), nlat - 1.000001)
    i, j = np.int64(y), np.int64(x)
    fy, fx = y - i, x - j
    a = ((1 - fy) * ((1 - fx) * first[i, j] + fx * first[i, j + 1])
         + fy * ((1 - fx) * first[i + 1, j] + fx * first[i + 1, j + 1]))
    b = ((1 - fy) * ((1 - fx) * second[i, j] + fx * second[i, j + 1])
         + fy * ((1 - fx) * second[i + 1, j] + fx * second[i + 1, j + 1]))
    return a, b


@nb.njit(cache=True, inline="always")
def _ray(x, y, distance, radius, cb, sb):
    """
    The sight line of helioprojective (x, y) (rad) to the sphere (`gongsynth.geometry.disk_geometry`):
    (μ, sx, sy, sz), the point it meets in Stonyhurst cartesian km; μ = -1 where it misses.
    """
    q = x * x + y * y
    norm = math.sqrt(1 + q)
    disc = radius * radius - distance * distance * q / (1 + q)
    if disc <= 0:
        return -1.0, 0.0, 0.0, 0.0
    t = distance / norm - math.sqrt(disc)
    px, py, pz = t * x / norm, t * y / norm, distance - t / norm
    sx, sy, sz = pz * cb - py * sb, px, pz * sb + py * cb
    nxo, nyo, nzo = -x / norm, -y / norm, 1 / norm
    mu = ((nzo * cb - nyo * sb) * sx + nxo * sy + (nzo * sb + nyo * cb) * sz) / radius
    return mu, sx, sy, sz


@nb.njit(cache=True, inline="always")
def _latitude_longitude(sx, sy, sz, radius):
    """Stonyhurst latitude and longitude (rad) of a point on the sphere."""
    return math.asin(min(max(sz / radius, -1.0), 1.0)), math.atan2(sy, sx)


@nb.njit(cache=True, inline="always")
def _velocity_index(vel, v_first, v_step, n_v):
    """Fractional index of a velocity in the basis' table, clamped, and whether it was outside."""
    xv = (vel - v_first) / v_step
    if xv < 0.0 or xv > n_v - 1:
        return min(max(xv, 0.0), n_v - 1.0), True
    return xv, False


def cell_table(radius, cell_km, distance, b0):
    """
    Centre and turn of every surface cell: (table, (j0, i0)).

    Parameters
    ----------
    radius, cell_km, distance : float
        Solar radius, cell side and observer distance (km).
    b0 : float
        B0 (rad).

    Returns
    -------
    table : `numpy.ndarray`
        float64 (nj, ni, 4): centre longitude and latitude (rad), cos and sin
        of the observer's azimuth seen from the centre (in its west-north frame),
        for cell (j, i) at ``[j + j0, i + i0]``.
    origin : (int, int)
        (j0, i0).
    """
    i0 = int(math.ceil(math.pi * radius / cell_km)) + 1
    j0 = int(math.ceil(0.5 * math.pi * radius / cell_km)) + 1
    cj = np.arange(-j0, j0)[:, None]
    ci = np.arange(-i0, i0)[None, :]
    bc = np.clip((cj + 0.5) * cell_km / radius, -1.5, 1.5)
    lc = (ci + 0.5) * cell_km / (radius * np.cos(bc))
    dx = distance * math.cos(b0) - radius * np.cos(bc) * np.cos(lc)
    dy = -radius * np.cos(bc) * np.sin(lc)
    dz = distance * math.sin(b0) - radius * np.sin(bc)
    west = -np.sin(lc) * dx + np.cos(lc) * dy
    north = -np.sin(bc) * (np.cos(lc) * dx + np.sin(lc) * dy) + np.cos(bc) * dz
    alpha = np.arctan2(north, west)
    table = np.stack(np.broadcast_arrays(lc, bc, np.cos(alpha), np.sin(alpha)), axis=-1)
    return np.ascontiguousarray(table), (j0, i0)


def render_disk(light, truth, h, x0, y0, distance, b0, radius,
                field, velocity, grid_lon0, grid_lat0, grid_step,
                cell_km, cells, cell_j0, cell_i0, seed, theta, ld_coeff,
                level_net, level_first, level_count, level_uniform,
                patches, uniform, pixel_km, mirror_ok, n_e, e_index, v_sign,
                amplitudes, totals, v_first, v_step, to_earth, plane0=0, row0=0):
    """
    Fill the light (2C, NY, NX), or some planes or rows of it, and the truth (NY, NX) of a full disk.

    C is the instrument's filtergrams per analyser state (GONG's 3 channels, HMI's 6 tunings): plane
    ``pol * C + c``, the layout of every instrument's ``analysers``.

    Parameters
    ----------
    light, truth : `numpy.ndarray`
        float32 (n, m, NX) and (NY, NX) outputs (zero beyond the limb), written in place: light
        holds planes ``plane0 .. plane0 + n - 1`` (all 2C by default) of the grid's rows
        ``row0 .. row0 + m - 1`` (m = NY by default), truth the same rows.  With n = 0 only the
        truth is made (the light's sums are skipped: a cheap pass).
    h : float
        Grid spacing (rad).
    x0, y0 : float
        Helioprojective offsets of the grid's centre from the Sun's (rad).
    distance, b0, radius : float
        Observer distance (km), B0 (rad), solar radius (km).
    field, velocity : `numpy.ndarray`
        float64 (nlat, nlon): large-scale radial field (G) and line-of-sight velocity (m/s).
    grid_lon0, grid_lat0, grid_step : float
        Their first longitude and latitude and spacing (deg).
    cell_km : float
        Cell side.
    cells : `numpy.ndarray`
        float64 (nj, ni, 4), `cell_table`: each cell's centre and turn.
    cell_j0, cell_i0 : int
        Its origin.
    seed : `numpy.uint64`
        The run's scene seed.
    theta : `numpy.ndarray`
        The library's viewing angles (rad), float64.
    ld_coeff : `numpy.ndarray`
        Limb-darkening polynomial coefficients, float64.
    level_net : `numpy.ndarray`
        Net flux density of each level (G), increasing, float64.
    level_first, level_count, level_uniform : `numpy.ndarray`
        int64, per level: first patch and number of patches; its uniform index (-1: a patch level).
    patches, uniform : `numpy.ndarray`
        The library rows: float32 (patch, y, x, angle, row) and (uniform level, angle, row).
    pixel_km : float
        Patch column size.
    mirror_ok : bool
    n_e : int
    e_index, v_sign : `numpy.ndarray`
        Analyser layout (`gongsynth.stages.scene.library.PatchLibrary`), int64 and float64 (2,).
    amplitudes, totals : `numpy.ndarray`
        The Doppler basis tables, float64 (velocity, C, J) and (velocity, C), at velocities
        ``v_first + k v_step``.
    v_first, v_step : float
    to_earth : float
        Radiance at the Sun to radiance at Earth per arcsec².
    plane0 : int
        The first plane ``light`` holds (a group of planes at a time bounds the memory of a large grid).
    row0 : int
        The first grid row ``light`` holds (a band of rows at a time: the same bound, one pass).

    Returns
    -------
    on_disk : int
        Samples on the disk.
    outside : int
        Samples whose velocity fell outside the basis' table (clamped).
    """
    # Rows are independent (each writes its own row from its own sample): the same bits for any
    # thread count.  A serial nogil kernel on `run_chunks`' threads compiles in a fraction of the
    # time of a ``parallel=True`` loop (a first full-disk run's compile).
    n_v, n_c, j = amplitudes.shape
    # The amplitudes with the filtergram index last (values copied, not computed).
    basis_t = np.ascontiguousarray(np.transpose(amplitudes, (0, 2, 1))).reshape(n_v, j * n_c)
    counts = np.zeros((light.shape[1], 2), dtype=np.int64)
    run_chunks(_render_rows, light.shape[1], light, truth, h, x0, y0, distance, b0, radius,
               field, velocity, grid_lon0, grid_lat0, grid_step,
               cell_km, cells, cell_j0, cell_i0, seed, theta, ld_coeff,
               level_net, level_first, level_count, level_uniform,
               patches, uniform, pixel_km, mirror_ok, n_e, e_index, v_sign,
               basis_t, totals, v_first, v_step, to_earth, plane0, row0, counts, min_chunk=8)
    return int(counts[:, 0].sum()), int(counts[:, 1].sum())


def disk_counts(shape, h, x0, y0, distance, b0, radius, field, velocity, grid_lon0, grid_lat0, grid_step,
                v_first, v_step, n_v):
    """
    The counts `render_disk` returns, without rendering: samples on the disk, and those whose velocity
    falls outside the Doppler basis' table.

    A grid whose light is made where the optics read it (`gongsynth.stages.scene.disk_render`) has its
    counts here, before the light: the rays alone, and the velocities only where the large-scale grid
    reaches beyond the table (a bilinear value lies within its four nodes' range).

    Parameters
    ----------
    shape : (int, int)
        (NY, NX) of the grid.
    h, x0, y0, distance, b0, radius, field, velocity, grid_lon0, grid_lat0, grid_step
        As in `render_disk`.
    v_first, v_step : float
        The basis' velocity table, ``v_first + k v_step``, ...
    n_v : int
        ... for k < n_v.

    Returns
    -------
    on_disk, outside : int
    """
    # Rounding of a bilinear value and of its index: far below this margin (in table steps).
    margin = 1e-6
    low, high = (float(np.min(velocity)) - v_first) / v_step, (float(np.max(velocity)) - v_first) / v_step
    check_velocity = not (low >= margin and high <= n_v - 1 - margin)
    counts = np.zeros((int(shape[0]), 2), dtype=np.int64)
    run_chunks(_count_rows, counts.shape[0], int(shape[1]), h, x0, y0, distance, b0, radius,
               field, velocity, grid_lon0, grid_lat0, grid_step, v_first, v_step, int(n_v), check_velocity,
               counts, min_chunk=8)
    return int(counts[:, 0].sum()), int(counts[:, 1].sum())


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _count_rows(start, stop, big_x, h, x0, y0, distance, b0, radius, field, velocity, grid_lon0, grid_lat0,
                grid_step, v_first, v_step, n_v, check_velocity, counts):
    """`disk_counts` for the rows ``start .. stop - 1`` (the same sight lines as `_render_rows`)."""
    big_y = counts.shape[0]
    cb, sb = math.cos(b0), math.sin(b0)
    for row in range(start, stop):
        y = y0 + (row - (big_y - 1) / 2) * h
        for col in range(big_x):
            x = x0 + (col - (big_x - 1) / 2) * h
            mu, sx, sy, sz = _ray(x, y, distance, radius, cb, sb)
            if mu <= 0:
                continue
            counts[row, 0] += 1
            if check_velocity:
                b, lon = _latitude_longitude(sx, sy, sz, radius)
                _, vel = _bilinear2(field, velocity, grid_lon0, grid_lat0, grid_step, math.degrees(lon),
                                    math.degrees(b))
                if _velocity_index(vel, v_first, v_step, n_v)[1]:
                    counts[row, 1] += 1


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _render_rows(start, stop, light, truth, h, x0, y0, distance, b0, radius,
                 field, velocity, grid_lon0, grid_lat0, grid_step,
                 cell_km, cells, cell_j0, cell_i0, seed, theta, ld_coeff,
                 level_net, level_first, level_count, level_uniform,
                 patches, uniform, pixel_km, mirror_ok, n_e, e_index, v_sign,
                 basis_t, totals, v_first, v_step, to_earth, plane0, row0, counts):
    """`render_disk` for the rows ``start .. stop - 1`` of ``light`` (their counts in ``counts``)."""
    big_y, big_x = truth.shape
    ny, nx, k_row = patches.shape[1], patches.shape[2], patches.shape[4]
    n_v, n_c = totals.shape
    j = basis_t.shape[1] // n_c
    j1 = j + 1
    v_off = n_e * j1
    b_off = (n_e + 1) * j1
    n_levels = level_net.size
    n_out = light.shape[0]
    first = b_off if n_out == 0 else 0   # truth only: B·n's two sums alone
    size_y, size_x = ny * pixel_km, nx * pixel_km
    cb, sb = math.cos(b0), math.sin(b0)
    for band_row in range(start, stop):
        row = row0 + band_row
        acc = np.empty(k_row)
        spec = np.empty(2 * j1)
        val = np.empty(2 * n_c)
        y = y0 + (row - (big_y - 1) / 2) * h
        for col in range(big_x):
            x = x0 + (col - (big_x - 1) / 2) * h
            mu, sx, sy, sz = _ray(x, y, distance, radius, cb, sb)
            if mu <= 0:
                continue
            mu = min(mu, 1.0)
            b, lon = _latitude_longitude(sx, sy, sz, radius)
            counts[band_row, 0] += 1
            for k in range(k_row):
                acc[k] = 0.0
            m, vel = _bilinear2(field, velocity, grid_lon0, grid_lat0, grid_step, math.degrees(lon),
                                math.degrees(b))
            sign = 1.0 if m >= 0 else -1.0
            level0, wl = _bracket(level_net, abs(m))
            if abs(m) >= level_net[n_levels - 1]:
                level0, wl = n_levels - 1, 0.0
            view = math.acos(mu)
            t0, wt = _bracket(theta, view)
            # -- the cell and the sample's offset from its centre (west, north; km)
            cos_b = math.cos(b)
            ci = math.floor(radius * lon * cos_b / cell_km)
            cj = math.floor(radius * b / cell_km)
            cell = cells[min(max(cj + cell_j0, 0), cells.shape[0] - 1),
                         min(max(ci + cell_i0, 0), cells.shape[1] - 1)]
            lc, bc, ca, sa = cell[0], cell[1], cell[2], cell[3]
            xl = radius * cos_b * (lon - lc)
            yl = radius * (b - bc)
            u0 = ca * xl + sa * yl
            w0 = -sa * xl + ca * yl
            for side in range(2):
                level = level0 + side
                weight = 1.0 - wl if side == 0 else wl
                if weight == 0.0 or level >= n_levels:
                    continue
                s = sign
                uni = level_uniform[level]
                p = 0
                ix = 0
                iy = 0
                if uni < 0:
                    state = seed ^ (np.uint64(level + 1) * np.uint64(0x9E3779B97F4A7C15))
                    state = state ^ (np.uint64(ci & 0xFFFFFFFF) << np.uint64(32)) ^ np.uint64(cj & 0xFFFFFFFF)
                    state, r1 = _splitmix(state)
                    state, r2 = _splitmix(state)
                    state, r3 = _splitmix(state)
                    ox = (r1 >> np.uint64(11)) * (1.0 / 9007199254740992.0) * size_x
                    oy = (r2 >> np.uint64(11)) * (1.0 / 9007199254740992.0) * size_y
                    p = level_first[level] + np.int64(r3 % np.uint64(level_count[level]))
                    mirror = mirror_ok and ((r3 >> np.uint64(40)) & np.uint64(1)) == np.uint64(1)
                    if level == 0:  # the quiet Sun is balanced: a random polarity per cell
                        s = 1.0 if ((r3 >> np.uint64(41)) & np.uint64(1)) == np.uint64(1) else -1.0
                    w = -w0 if mirror else w0
                    ix = min(np.int64(((u0 + ox) % size_x) / pixel_km), nx - 1)
                    iy = min(np.int64(((w + oy) % size_y) / pixel_km), ny - 1)
                # Both angles' rows side by side (adjacent in memory): one pass over the row.
                if uni < 0:
                    src = patches[p, iy, ix]
                else:
                    src = uniform[uni]
                wa, wb = weight * (1.0 - wt), weight * wt
                row_a, row_b = src[t0], src[t0 + 1]
                for k in range(first, v_off):
                    acc[k] += wa * row_a[k] + wb * row_b[k]
                wa, wb = wa * s, wb * s
                for k in range(max(v_off, first), k_row):
                    acc[k] += wa * row_a[k] + wb * row_b[k]
            # -- limb darkening at the sample's own μ, then the Doppler basis at its velocity
            ld = 0.0
            for k in range(ld_coeff.size - 1, -1, -1):
                ld = ld * mu + ld_coeff[k]
            xv, off_table = _velocity_index(vel, v_first, v_step, n_v)
            if off_table:
                counts[band_row, 1] += 1
            # The true B·n: the patch frame's observer lies toward +x at the sample's own angle.
            truth[row, col] = acc[b_off] * mu + acc[b_off + 1] * math.sin(view)
            if n_out == 0:
                continue
            kv = min(np.int64(xv), n_v - 2)
            fv = xv - kv
            gv = 1.0 - fv
            for pol in range(2):
                e0 = e_index[pol] * j1
                vs = v_sign[pol]
                for qq in range(j1):
                    spec[pol * j1 + qq] = acc[e0 + qq] + vs * acc[v_off + qq]
            for c in range(n_c):
                tc = gv * totals[kv, c] + fv * totals[kv + 1, c]
                val[c] = spec[0] * tc
                val[n_c + c] = spec[j1] * tc
            for qq in range(j):
                s0 = spec[qq + 1]
                s1 = spec[j1 + qq + 1]
                for c in range(n_c):
                    a = gv * basis_t[kv, qq * n_c + c] + fv * basis_t[kv + 1, qq * n_c + c]
                    val[c] += a * s0
                    val[n_c + c] += a * s1
            scale = ld * to_earth
            for o in range(n_out):
                light[o, band_row, col] = scale * val[plane0 + o]
