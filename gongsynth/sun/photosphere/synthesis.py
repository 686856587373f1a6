r"""
Milne–Eddington synthesis of Ni I 676.78 nm: Photosphere → StokesCube.

For each column the field is projected on the viewing geometry: γ is the angle
between B and the line of sight n, χ the azimuth of its sky projection from e1
(see `gongsynth.geometry`).  The normal Zeeman triplet with the
effective Landé factor g splits by

.. math:: \Delta\lambda_B = \frac{e\,\lambda_0^2\,g\,B}{4\pi m_e c^2}
          \approx 4.67\times10^{-13}\,g\,\lambda_0^2\,B \quad (\text{Å, G}),

the line shifts by λ0 v_LOS / c (v_LOS > 0 away from the observer) and the
Unno–Rachkovsky solution (Landi Degl'Innocenti & Landolfi 2004, Eq. 9.45) gives
I, Q, U, V with magneto-optical effects.  In the weak-field limit
V ≈ −Δλ_B cosγ dI/dλ, i.e. V ≈ −4.67e−13 g λ0² B_LOS dI/dλ.  The continuum is
``line.continuum_intensity`` × ``photosphere.continuum`` × limb darkening(μ).
"""
from __future__ import annotations

import dataclasses

import astropy.constants as const
import astropy.units as u
import numpy as np
from scipy.special import wofz

from gongsynth import instruments
from gongsynth.geometry import check_geometry, los_basis
from gongsynth.sun.photosphere._kernel import me_kernel, me_project_kernel, voigt_table
from gongsynth.sun.photosphere.columns import Photosphere
from gongsynth.sun.photosphere.line import NiLine, me_line
from gongsynth.sun.stokes import RADIANCE_UNIT, DeferredCube, StokesCube
from gongsynth.validation import check_wavelength_grid

__all__ = ["synthesize", "DeferredStokes", "default_wavelength", "zeeman_splitting"]

_METHODS = ("numba", "numpy")


def default_wavelength(instrument=None):
    """
    The paper's spectral grid: 51 points from 676.73 to 676.83 nm (for GONG).

    Parameters
    ----------
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
        Another instrument's line gets the same window moved to its
        ``line_wavelength`` (±0.05 nm about it), sampled as finely as its
        channel integrals need (`gongsynth.sun.sampling.spectral_requirement`).

    Returns
    -------
    `~astropy.units.Quantity`
        (51,) in nm.

    Examples
    --------
    >>> lam = default_wavelength()
    >>> lam.size, lam[0], lam[-1]
    (51, <Quantity 676.73 nm>, <Quantity 676.83 nm>)
    """
    from gongsynth.sun.sampling import spectral_requirement
    inst = instruments.get(instrument)
    # Halve the step until it is as fine as the instrument's channel integrals need
    # (`gongsynth.sun.sampling`): GONG's 2 pm passes, HMI's narrower line needs 1 pm.
    step = spectral_requirement(inst)[1].to_value(u.nm)
    points = 51
    while 0.1 / (points - 1) > step * (1 + 1e-6):
        points = 2 * points - 1
    # For GONG's 676.78 nm the shift is exactly 0: the paper's grid, bit for bit.
    shift = inst.line_wavelength.to_value(u.nm) - 676.78
    return (np.linspace(676.73, 676.83, points) + shift) * u.nm


def zeeman_splitting(field, wavelength, lande_g):
    """
    Zeeman splitting Δλ_B = e λ² g B / (4π m_e c²) of a normal triplet.

    Parameters
    ----------
    field : `~astropy.units.Quantity`
        Field strength (G).
    wavelength : `~astropy.units.Quantity`
        Line wavelength.
    lande_g : float
        Effective Landé factor.

    Returns
    -------
    `~astropy.units.Quantity`
        In pm.

    Examples
    --------
    >>> import astropy.units as u
    >>> zeeman_splitting(1000 * u.G, 676.78 * u.nm, 1.5).to(u.AA)   # paper: 0.03205 Å/kG
    <Quantity 0.03207577 Angstrom>
    """
    coeff = const.e.gauss.value / (4 * np.pi * const.m_e.cgs.value * const.c.cgs.value ** 2)
    dl = coeff * wavelength.to_value(u.cm) ** 2 * lande_g * field.to_value(u.G)
    return (dl * u.cm).to(u.pm)


def _column_parameters(photosphere, mu, azimuth, lam0_pm, g, line):
    """Per-column kernel inputs (float64 (ny, nx) arrays) and the true B·n."""
    shape = photosphere.shape
    n, e1, e2 = los_basis(mu, azimuth)
    bx, by, bz = photosphere.field_vector()
    b_par = bx * n[0] + by * n[1] + bz * n[2]
    b1 = bx * e1[0] + by * e1[1] + bz * e1[2]
    b2 = bx * e2[0] + by * e2[1] + bz * e2[2]
    b2sum = b_par * b_par + b1 * b1 + b2 * b2
    has_field = b2sum > 0
    inv = np.where(has_field, 1.0 / np.where(has_field, b2sum, 1.0), 0.0)
    cosg = np.where(has_field, b_par * np.sqrt(inv), 1.0)
    qfac = (b1 * b1 - b2 * b2) * inv
    ufac = 2.0 * b1 * b2 * inv
    del b1, b2, bx, by, bz
    dop = line.doppler_width.to_value(u.pm)
    vzeeman = zeeman_splitting(np.sqrt(b2sum) * u.G, lam0_pm * u.pm, g).to_value(u.pm) / dop
    vx, vy, vz = (getattr(photosphere, f"velocity_{c}").value.astype(np.float64) for c in "xyz")
    v_los = -(vx * n[0] + vy * n[1] + vz * n[2])          # km/s, > 0 away from the observer
    vshift = v_los * (lam0_pm / const.c.to_value(u.km / u.s)) / dop
    bmu = np.broadcast_to(line.source_gradient * np.asarray(mu), shape)
    ic = line.continuum_intensity.to_value(RADIANCE_UNIT)
    scale = (ic * photosphere.continuum.value.astype(np.float64)
             * line.limb_darkening_factor(mu) / (1.0 + bmu))
    cols = dict(vshift=vshift, vzeeman=vzeeman, cosg=cosg, qfac=qfac, ufac=ufac,
                bmu=bmu, scale=scale)
    cols = {k: np.ascontiguousarray(np.broadcast_to(v, shape), dtype=np.float64) for k, v in cols.items()}
    return cols, b_par


def _numpy_rows(vgrid, cols, eta0, damping, rows):
    """Vectorised-numpy Unno–Rachkovsky (exact Faddeeva function) for a block of rows."""
    c = {k: v[rows, :, None] for k, v in cols.items()}
    v = vgrid[None, None, :] - c["vshift"]
    wp = wofz(v + 1j * damping)
    wb = wofz(v + c["vzeeman"] + 1j * damping)
    wr = wofz(v - c["vzeeman"] + 1j * damping)
    ws = 0.5 * (wb + wr)
    cg = c["cosg"]
    half = 0.5 * eta0
    ei = half * (wp.real * (1 - cg * cg) + ws.real * (1 + cg * cg))
    eq = half * (wp.real - ws.real) * c["qfac"]
    eu = half * (wp.real - ws.real) * c["ufac"]
    ev = half * (wr.real - wb.real) * cg
    rq = half * (wp.imag - ws.imag) * c["qfac"]
    ru = half * (wp.imag - ws.imag) * c["ufac"]
    rv = half * (wr.imag - wb.imag) * cg
    k = 1.0 + ei
    k2 = k * k
    r2 = rq * rq + ru * ru + rv * rv
    pi_ = eq * rq + eu * ru + ev * rv
    f = c["bmu"] / (k2 * (k2 - eq * eq - eu * eu - ev * ev + r2) - pi_ * pi_)
    s = c["scale"]
    return (s * (1.0 + f * k * (k2 + r2)),
            -s * f * (k2 * eq + k * (ev * ru - eu * rv) + rq * pi_),
            -s * f * (k2 * eu + k * (eq * rv - ev * rq) + ru * pi_),
            -s * f * (k2 * ev + k * (eu * rq - eq * ru) + rv * pi_))


def synthesize(photosphere, mu=1.0, wavelength=None, *, los_azimuth=-90 * u.deg, instrument=None,
               line=None, method="numba"):
    """
    Milne–Eddington full-Stokes spectra of Ni I 676.78 nm for every column.

    Parameters
    ----------
    photosphere : `~gongsynth.sun.photosphere.Photosphere`
        Field, velocity and continuum per column.
    mu : float or array_like (ny, nx), optional
        Cosine of the viewing angle, in (0, 1] (default 1, disk centre); an
        array gives each column its own geometry (full-disk scenes).
    wavelength : `~astropy.units.Quantity`, optional
        Strictly increasing grid covering the line (length).  Default: the
        paper's 51 points over 676.73–676.83 nm (`default_wavelength`).
    los_azimuth : `~astropy.units.Quantity`, angle, scalar or (ny, nx), optional
        Azimuth of the observer direction from +x toward +y (default −90°: the
        region lies north of disk centre on the central meridian).
    instrument : `~gongsynth.GONGInstrument`, optional
        Source of the rest wavelength (``line_wavelength``) and of the Landé
        factor (``lande_g``, unless ``line.lande_g`` is set).
    line : `~gongsynth.sun.photosphere.NiLine`, optional
        Milne–Eddington line parameters (default: the instrument's line, `me_line`).
    method : {"numba", "numpy"}, optional
        "numba" (default): the parallel kernel with a tabulated Voigt function;
        "numpy": the vectorised reference with the exact Faddeeva function,
        processed in blocks of rows (slower; for checks and benchmarks).

    Returns
    -------
    `~gongsynth.sun.stokes.StokesCube`
        (ny, nx, nλ) float32 spectra in erg s⁻¹ cm⁻² sr⁻¹ cm⁻¹, with ``mu``,
        the photosphere's pixel size, ``blos`` = B·n (G, the ground truth) and
        ``meta`` recording the line parameters and geometry.

    Notes
    -----
    Cost and memory: the default 1024² × 51 cube takes ~5 s on 2 cores
    (``benchmarks/bench_synthesis.py``) and the output (4 × 204 MiB float32)
    plus ~64 bytes per column of temporaries; nothing of size (ny, nx, nλ) is
    allocated besides the output.  The weak-field relation
    V = −4.67e−13 g λ0² B_LOS dI/dλ holds to 0.7 % at 100 G and 6.5 % at 300 G.

    Examples
    --------
    >>> import numpy as np, astropy.units as u
    >>> from gongsynth.sun.photosphere import Photosphere, synthesize
    >>> ones = np.ones((1, 2))
    >>> ph = Photosphere([[0, 1000]] * u.G, 0 * ones * u.deg, 0 * ones * u.deg, 0 * ones * u.km / u.s,
    ...                  0 * ones * u.km / u.s, 0 * ones * u.km / u.s, ones, 96 * u.km)
    >>> cube = synthesize(ph)
    >>> cube.shape, cube.blos
    ((1, 2, 51), <Quantity [[   0., 1000.]] G>)
    >>> i = cube.I[0, 0].value
    >>> round(float(1 - i.min() / i[0]), 2)        # central depth of a static column
    0.67
    """
    inputs = _checked_inputs(photosphere, mu, wavelength, los_azimuth, instrument, line, method)
    return _synthesize_rows(inputs, slice(None))


def _checked_inputs(photosphere, mu, wavelength, los_azimuth, instrument, line, method):
    """`synthesize`'s arguments checked and resolved, as a dict."""
    if not isinstance(photosphere, Photosphere):
        raise TypeError(f"photosphere must be a gongsynth.sun.photosphere.Photosphere, "
                        f"got {type(photosphere).__name__}")
    if method not in _METHODS:
        raise ValueError(f"method must be one of {_METHODS}, got {method!r}")
    instrument = instruments.get(instrument)   # any of the family: its line's wavelength and Lande factor
    line = me_line(instrument.line) if line is None else line
    if not isinstance(line, NiLine):
        raise TypeError(f"line must be a NiLine or None, got {type(line).__name__}")
    wavelength = default_wavelength(instrument) if wavelength is None else wavelength
    check_wavelength_grid(wavelength, instrument.line_wavelength)
    mu, azimuth = check_geometry(mu, los_azimuth, photosphere.shape)
    g = float(instrument.lande_g.to_value(u.one)) if line.lande_g is None else float(line.lande_g)
    meta = {
        "origin": "gongsynth.sun.photosphere.synthesize",
        "method": f"Milne-Eddington ({method})",
        "line_wavelength_nm": float(instrument.line_wavelength.to_value(u.nm)),
        "lande_g": g,
        "line": {f.name: (str(getattr(line, f.name)) if isinstance(getattr(line, f.name), u.Quantity)
                          else getattr(line, f.name)) for f in dataclasses.fields(line)},
        "mu": float(mu) if np.ndim(mu) == 0 else "per-column",
        "los_azimuth_deg": (float(np.degrees(azimuth)) if np.ndim(azimuth) == 0 else "per-column"),
        "photosphere": dict(photosphere.meta),
    }
    return dict(photosphere=photosphere, mu=mu, azimuth=azimuth, wavelength=wavelength, g=g, line=line,
                instrument=instrument, method=method, meta=meta)


def _rows_of(value, rows):
    """A per-column (ny, nx) geometry array's rows; a scalar as it is."""
    return value if np.ndim(value) == 0 else value[rows]


def _kernel_columns(cols):
    """The column parameters as the ME kernels take them: flat, C-ordered, writable float64.

    A read-only (broadcast) column would make numba compile the kernel again for that type.
    """
    return {k: np.require(v.reshape(-1), np.float64, ["C", "W"]) for k, v in cols.items()}


def _synthesize_rows(inputs, rows):
    """The StokesCube of the photosphere's ``rows`` (a slice) from `_checked_inputs`."""
    photosphere = inputs["photosphere"]
    if rows != slice(None):
        photosphere = photosphere[rows]
    mu, azimuth = _rows_of(inputs["mu"], rows), _rows_of(inputs["azimuth"], rows)
    instrument, line, wavelength, method = (inputs[k] for k in ("instrument", "line", "wavelength", "method"))
    lam0 = instrument.line_wavelength.to_value(u.pm)
    cols, b_par = _column_parameters(photosphere, mu, azimuth, lam0, inputs["g"], line)
    vgrid = (wavelength.to_value(u.pm).astype(np.float64) - lam0) / line.doppler_width.to_value(u.pm)
    ny, nx = photosphere.shape
    out = [np.empty((ny, nx, vgrid.size), dtype=np.float32) for _ in range(4)]
    eta0, damping = float(line.line_strength), float(line.damping)
    if method == "numba":
        tab_re, tab_im = voigt_table(damping)
        flat = _kernel_columns(cols)
        me_kernel(vgrid, flat["vshift"], flat["vzeeman"], flat["cosg"], flat["qfac"], flat["ufac"],
                  flat["bmu"], flat["scale"], eta0, damping, tab_re, tab_im,
                  *(a.reshape(ny * nx, vgrid.size) for a in out))
    else:
        step = max(1, 1_000_000 // max(1, nx * vgrid.size))
        for start in range(0, ny, step):
            block = slice(start, min(ny, start + step))
            for dst, src in zip(out, _numpy_rows(vgrid, cols, eta0, damping, block)):
                dst[block] = src
    del cols
    unit = RADIANCE_UNIT
    return StokesCube(*(u.Quantity(a, unit, copy=False) for a in out), wavelength,
                      photosphere.pixel_size, mu=mu, meta=inputs["meta"],
                      blos=u.Quantity(b_par.astype(np.float32), u.G, copy=False))


class DeferredStokes(DeferredCube):
    """
    The Milne–Eddington spectra of a photosphere, synthesised when and where they are needed.

    It stands for the `~gongsynth.sun.stokes.StokesCube` that `synthesize`
    returns for the same arguments, and holds only the photosphere: `blocks`
    yields that cube a few rows at a time (all that
    `gongsynth.stages.channels.channel_images` needs, so a run never holds the
    whole cube: 816 MiB at the default 1024² × 51), ``shape``, ``wavelength``,
    ``pixel_size``, ``mu``, ``blos`` and ``meta`` are known without
    synthesis, and anything else (``I``, ``Q``, ``U``, ``V``, slicing, ...)
    synthesises the whole cube once (`cube`) and is taken from it.  Every
    column is synthesised independently, so block by block gives the same
    bits as all at once.

    Parameters
    ----------
    photosphere, mu, wavelength, los_azimuth, instrument, line, method
        As in `synthesize`.

    Examples
    --------
    >>> import numpy as np, astropy.units as u
    >>> from gongsynth.sun.photosphere import Photosphere
    >>> ones = np.ones((4, 3))
    >>> ph = Photosphere(500 * ones * u.G, 0 * ones * u.deg, 0 * ones * u.deg, 0 * ones * u.km / u.s,
    ...                  0 * ones * u.km / u.s, 0 * ones * u.km / u.s, ones, 96 * u.km)
    >>> deferred = DeferredStokes(ph)
    >>> deferred.shape, [rows for rows, _ in deferred.blocks(columns=6)]
    ((4, 3, 51), [slice(0, 2, None), slice(2, 4, None)])
    >>> bool(np.array_equal(deferred.I, synthesize(ph).I))
    True
    """

    _method = "Milne-Eddington"

    def __init__(self, photosphere, mu=1.0, wavelength=None, *, los_azimuth=-90 * u.deg, instrument=None,
                 line=None, method="numba"):
        self._inputs = _checked_inputs(photosphere, mu, wavelength, los_azimuth, instrument, line, method)
        self._cube = None
        self._blos = None

    @property
    def shape(self):
        """(ny, nx, nλ)."""
        return self._inputs["photosphere"].shape + (self._inputs["wavelength"].size,)

    @property
    def wavelength(self):
        """The wavelength grid (nm)."""
        return self._inputs["wavelength"].to(u.nm)

    @property
    def pixel_size(self):
        """Horizontal size of one column (km)."""
        return self._inputs["photosphere"].pixel_size.to(u.km)

    @property
    def mu(self):
        """Cosine of the viewing angle: a float, or (ny, nx)."""
        return self._inputs["mu"]

    @property
    def meta(self):
        """Provenance, as the cube's."""
        return self._inputs["meta"]

    @property
    def blos(self):
        """True line-of-sight field B·n (ny, nx), float32, in G: the cube's ``blos``."""
        if self._blos is None:
            inputs = self._inputs
            lam0 = inputs["instrument"].line_wavelength.to_value(u.pm)
            _, b_par = _column_parameters(inputs["photosphere"], inputs["mu"], inputs["azimuth"], lam0,
                                          inputs["g"], inputs["line"])
            self._blos = u.Quantity(b_par.astype(np.float32), u.G, copy=False)
        return self._blos

    def blocks(self, columns=65536):
        """
        Yield the cube a block of whole rows at a time.

        Parameters
        ----------
        columns : int
            Columns per block (rounded to whole rows, at least one): the
            block's cube takes ``16 × nλ`` bytes per column.

        Yields
        ------
        rows : slice
            The block's rows.
        cube : `~gongsynth.sun.stokes.StokesCube`
            Their spectra (``cube[rows]`` of the whole cube, bit for bit).
        """
        ny, nx = self._inputs["photosphere"].shape
        step = max(1, int(columns) // nx)
        for start in range(0, ny, step):
            rows = slice(start, min(ny, start + step))
            yield rows, _synthesize_rows(self._inputs, rows)

    def project(self, weights, columns=65536):
        """
        The spectra contracted with ``weights`` over Stokes parameter and wavelength, column by column.

        ``out[o, y, x] = Σ_j Σ_s weights[o, s, j] S_s(y, x, λ_j)`` with S = (I, Q, U, V):
        e.g. the six channel integrals of the polarimeter and filters
        (`gongsynth.stages.channels.channel_images`).  With the numba method
        the spectra are never stored (computed in float64 and contracted at
        once); the numpy method contracts the float32 cube block by block.
        The true B·n (`blos`) is kept on the way.

        Parameters
        ----------
        weights : array_like
            (n_out, 4, nλ) in the units wanted per unit spectral radiance.
        columns : int
            Columns per block (bounded temporaries).

        Returns
        -------
        `numpy.ndarray`
            (n_out, ny, nx) float64.
        """
        inputs = self._inputs
        weights = np.ascontiguousarray(weights, dtype=np.float64)
        ny, nx, nl = self.shape
        if weights.ndim != 3 or weights.shape[1:] != (4, nl):
            raise ValueError(f"weights must have shape (n_out, 4, {nl}), got {weights.shape}")
        out = np.empty((weights.shape[0], ny, nx))
        blos = np.empty((ny, nx), dtype=np.float32) if self._blos is None else None
        lam0 = inputs["instrument"].line_wavelength.to_value(u.pm)
        line = inputs["line"]
        vgrid = ((inputs["wavelength"].to_value(u.pm).astype(np.float64) - lam0)
                 / line.doppler_width.to_value(u.pm))
        tab_re, tab_im = voigt_table(float(line.damping))
        step = max(1, int(columns) // nx)
        for start in range(0, ny, step):
            rows = slice(start, min(ny, start + step))
            if inputs["method"] != "numba":
                cube = _synthesize_rows(inputs, rows)
                spectra = [getattr(cube, name).value.astype(np.float64) for name in ("I", "Q", "U", "V")]
                out[:, rows] = sum(np.einsum("oj,yxj->oyx", weights[:, s], a) for s, a in enumerate(spectra))
                if blos is not None:
                    blos[rows] = cube.blos.value
                continue
            photosphere = inputs["photosphere"][rows]
            cols, b_par = _column_parameters(photosphere, _rows_of(inputs["mu"], rows),
                                             _rows_of(inputs["azimuth"], rows), lam0, inputs["g"], line)
            flat = _kernel_columns(cols)
            block = np.empty((weights.shape[0], flat["vshift"].size))
            me_project_kernel(vgrid, flat["vshift"], flat["vzeeman"], flat["cosg"], flat["qfac"],
                              flat["ufac"], flat["bmu"], flat["scale"], float(line.line_strength),
                              float(line.damping), tab_re, tab_im, weights, block)
            out[:, rows] = block.reshape(weights.shape[0], -1, nx)
            if blos is not None:
                blos[rows] = b_par
        if blos is not None:
            self._blos = u.Quantity(blos, u.G, copy=False)
        return out

    def cube(self):
        """
        The whole `~gongsynth.sun.stokes.StokesCube` (synthesised on the first call, then kept).

        Returns
        -------
        `~gongsynth.sun.stokes.StokesCube`
        """
        if self._cube is None:
            self._cube = _synthesize_rows(self._inputs, slice(None))
        return self._cube
