"""
The 3-D model Sun's row kernels (`~gongsynth.sun.model_atmosphere.builder.assemble_rows`).

A module of their own that imports numba and numpy only: a first run's background compiler
(`gongsynth.precompile`) imports it without the builder's imports (sunpy.map among them, ~1.5 s
of CPU).
"""
import numba as nb
import numpy as np

__all__ = ["blend_rows", "flow_rows", "internetwork_rows"]


@nb.njit(cache=True, nogil=True)
def blend_rows(start, stop, a, f, su, sp, a0, da, q_t, q_p, tube_t, tube_p, u_t, u_p, p_t, p_p, temp, pres):
    """T and P per (height, column) of rows ``start`` to ``stop``: area-weighted means of the components."""
    na, nz = q_t.shape
    nx = a.shape[1]
    for j in range(start, stop):
        m = np.empty(nx, dtype=np.int64)
        w = np.empty(nx)
        q = np.empty(nx)
        for i in range(nx):
            x = min(max((a[j, i] - a0) / da, 0.0), na - 1.000001)
            m[i] = int(x)
            w[i] = x - m[i]
            q[i] = max(1.0 - f[j, i] - su[j, i] - sp[j, i], 0.0)
        for k in range(nz):
            for i in range(nx):
                mi, wi = m[i], w[i]
                tq = (1 - wi) * q_t[mi, k] + wi * q_t[mi + 1, k]
                pq = (1 - wi) * q_p[mi, k] + wi * q_p[mi + 1, k]
                temp[k, j, i] = q[i] * tq + f[j, i] * tube_t[k] + su[j, i] * u_t[k] + sp[j, i] * p_t[k]
                pres[k, j, i] = q[i] * pq + f[j, i] * tube_p[k] + su[j, i] * u_p[k] + sp[j, i] * p_p[k]


@nb.njit(cache=True, nogil=True)
def flow_rows(start, stop, h, s, fl, vz0, gx, gy, svx, svy, vel):
    """v_z = h V, v_h = s ∇φ + (Evershed, moat) × their height profile, rows ``start`` to ``stop``."""
    nz = h.size
    nx = vz0.shape[1]
    for j in range(start, stop):
        for k in range(nz):
            for i in range(nx):
                vel[0, k, j, i] = s[k] * gx[j, i] + fl[k] * svx[j, i]
                vel[1, k, j, i] = s[k] * gy[j, i] + fl[k] * svy[j, i]
                vel[2, k, j, i] = h[k] * vz0[j, i]


@nb.njit(cache=True, nogil=True)
def internetwork_rows(start, stop, c, dc, ax, ay, dazdx, dazdy, curl, mag):
    """B += curl of A c(z) in rows ``start`` to ``stop`` (`~gongsynth.sun.model_atmosphere.flux_elements`)."""
    nz = c.size
    nx = ax.shape[1]
    for j in range(start, stop):
        for k in range(nz):
            for i in range(nx):
                mag[0, k, j, i] += c[k] * dazdy[j, i] - dc[k] * ay[j, i]
                mag[1, k, j, i] += dc[k] * ax[j, i] - c[k] * dazdx[j, i]
                mag[2, k, j, i] += c[k] * curl[j, i]
