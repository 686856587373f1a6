"""
`DeferredTransfer`: a model Sun's LTE Stokes spectra, assembled and synthesised a block of rows at a time.

`gongsynth.rt.synthesize` of the whole box holds the whole (nz, ny, nx)
atmosphere and the whole (ny, nx, nλ) cube: 3.0 and 0.8 GB at the papers'
1024² × 96 km × 80 heights.  Here each block of rows is assembled
(`~gongsynth.sun.model_atmosphere.assembly.ModelSun.rows`) with the halo of
rows its inclined rays cross, synthesised by `gongsynth.rt.synthesize` and
handed on (`blocks`; `gongsynth.stages.channels.channel_images` contracts it
with the filter weights at once), so neither is ever held.  The rays' anchor,
the mean τ_c = 1 height (`gongsynth.sun.rt.synthesis.reference_height`), is
the whole box's, found once from the same columns; every ray then samples
the same points as in the whole box and the spectra and the truth are the
same bits.
"""
from __future__ import annotations

import math

import astropy.units as u
import numpy as np

from gongsynth.geometry import check_geometry
from gongsynth.sun.model_atmosphere.assembly import ModelSun
from gongsynth.sun.rt import synthesis as rt_synthesis
from gongsynth.sun.rt.atomic_data import get_line
from gongsynth.sun.rt.rays import ray_offsets, rays_are_vertical
from gongsynth.sun.stokes import DeferredCube, StokesCube
from gongsynth.validation import check_wavelength_grid

__all__ = ["DeferredTransfer"]

# `reference_height`'s default sample of the box (`gongsynth.sun.rt.synthesis`).
_REFERENCE_COLUMNS = 4096

class DeferredTransfer(DeferredCube):
    """
    The spectra `gongsynth.rt.synthesize` makes of a model Sun, synthesised a block of rows at a time.

    It stands for the `~gongsynth.sun.stokes.StokesCube` of
    ``rt.synthesize(sun.atmosphere(), mu=mu, azimuth=azimuth, line=line)``:
    `blocks` yields that cube a block of rows at a time (bit for bit), and
    ``shape``, ``wavelength``, ``pixel_size`` and ``mu`` are known without
    synthesis.  ``blos`` (the truth) and ``meta`` come with a pass of
    `blocks` (one is run if they are asked for first); anything else
    (``I``, ``V``, slicing, ...) synthesises the whole cube once (`cube`).

    Parameters
    ----------
    sun : `~gongsynth.sun.model_atmosphere.assembly.ModelSun`
    mu : float
        cos θ of the viewing angle, in (0, 1].
    azimuth : `~astropy.units.Quantity`
        Line-of-sight azimuth, as in `gongsynth.rt.synthesize`.
    line : str or `~gongsynth.sun.rt.atomic_data.LineData`, optional
    progress : bool
        A progress bar over the blocks.
    wavelength : `~astropy.units.Quantity`, optional
        Air wavelengths, as in `gongsynth.rt.synthesize` (default its
        `~gongsynth.sun.rt.synthesis.default_wavelength`, 51 points).

    Examples
    --------
    >>> import astropy.units as u, numpy as np, gongsynth
    >>> from gongsynth.sun.model_atmosphere import model_sun
    >>> sun = model_sun((16, 16), 384 * u.km, seed=1, nz=40)
    >>> deferred = DeferredTransfer(sun, mu=0.8, azimuth=-90 * u.deg)
    >>> whole = gongsynth.rt.synthesize(sun.atmosphere(), mu=0.8, azimuth=-90 * u.deg, progress=False)
    >>> parts = [cube.V.value for _, cube in deferred.blocks(columns=64, halo_share=None)]
    >>> len(parts), bool(np.array_equal(np.concatenate(parts), whole.V.value))
    (4, True)
    >>> bool(np.array_equal(deferred.blos, whole.blos))
    True
    """

    _method = "LTE radiative transfer by blocks"

    def __init__(self, sun, *, mu, azimuth, line=None, progress=False, wavelength=None):
        if not isinstance(sun, ModelSun):
            raise TypeError(f"sun must be a ModelSun (gongsynth.sun.model_atmosphere.model_sun), "
                            f"got {type(sun).__name__}")
        mu_value, az = check_geometry(mu, azimuth, sun.shape[1:])
        if np.ndim(mu_value) or np.ndim(az):
            raise ValueError("DeferredTransfer takes one viewing geometry (scalar mu and azimuth)")
        self._sun = sun
        self._mu, self._az, self._azimuth = float(mu_value), float(az), azimuth
        # As rt.synthesize decides: rays nearly vertical across the box are read as columns.
        self._vertical = rays_are_vertical(sun.z.to_value(u.km), self._mu, sun.pixel_size.to_value(u.km))
        self._line = get_line(line)
        self._progress = progress
        if wavelength is None:
            wavelength = rt_synthesis.default_wavelength(self._line)
        self._wavelength = check_wavelength_grid(wavelength, self._line.wavelength_nm * u.nm).to(u.nm)
        self._blos = None
        self._meta = None
        self._cube = None

    @property
    def shape(self):
        """(ny, nx, nλ)."""
        return self._sun.shape[1:] + (self._wavelength.size,)

    @property
    def wavelength(self):
        """The wavelength grid (nm)."""
        return self._wavelength

    @property
    def pixel_size(self):
        """Horizontal size of one column (km)."""
        return self._sun.pixel_size

    @property
    def mu(self):
        """Cosine of the viewing angle."""
        return self._mu

    @property
    def blos(self):
        """The truth (ny, nx) float32 in G, as the cube's ``blos``: made by a pass of `blocks`."""
        if self._blos is None:
            for _ in self.blocks():
                pass
        return self._blos

    @property
    def meta(self):
        """Provenance, as the cube's, but ``truth_anchor_mean_km`` None (a block's includes its halo)."""
        if self._meta is None:
            for _ in self.blocks():
                pass
        return self._meta

    def _reference_height(self):
        """The whole box's `reference_height`, from the same columns, assembled alone (nan: vertical rays)."""
        _, ny, nx = self._sun.shape
        if self._vertical:
            return float("nan")
        step = max(1, int(np.ceil(np.sqrt(ny * nx / _REFERENCE_COLUMNS))))
        sample = self._sun.rows(np.arange(0, ny, step), thermodynamics_only=True)[:, ::step]
        columns = sample.shape[1] * sample.shape[2]
        return rt_synthesis.reference_height(sample, self._line, max_columns=columns)

    def _halo(self, z_ref):
        """Rows below and above a block that its rays reach (`gongsynth.sun.rt.rays.sample_rays`)."""
        if self._vertical:
            return 0, 0
        _, dy = ray_offsets(self._sun.z.to_value(u.km), z_ref, self._mu, self._az,
                            self._sun.pixel_size.to_value(u.km))
        lo, hi = math.floor(float(dy.min())), math.floor(float(dy.max()))
        return max(0, -lo), max(0, hi + 1)

    def blocks(self, columns=65536, halo_share=0.25):
        """
        Yield the cube a block of whole rows at a time.

        Parameters
        ----------
        columns : int
            Columns per block (rounded to whole rows, at least one).
        halo_share : float or None
            Blocks are made a whole multiple of that larger where the halo
            rows the inclined rays cross (synthesised and dropped) would
            exceed this share of a block; None: never.

        Yields
        ------
        rows : slice
            The block's rows.
        cube : `~gongsynth.sun.stokes.StokesCube`
            Their spectra (``cube[rows]`` of the whole cube, bit for bit).
        """
        _, ny, nx = self._sun.shape
        step = max(1, int(columns) // nx)
        z_ref = self._reference_height()
        below, above = self._halo(z_ref)
        if halo_share is not None and below + above > halo_share * step:
            step *= math.ceil((below + above) / (halo_share * step))
        blos = np.empty((ny, nx), dtype=np.float32)
        starts = range(0, ny, step)
        if self._progress:
            from tqdm.auto import tqdm
            starts = tqdm(starts, desc="rt.synthesize by blocks", unit="block")
        for start in starts:
            rows = slice(start, min(ny, start + step))
            n = rows.stop - rows.start
            if n == ny:  # the whole box: periodic in itself
                box, keep = self._sun.atmosphere(), slice(None)
            else:
                box = self._sun.rows(np.arange(start - below, rows.stop + above))
                keep = slice(below, below + n)
            cube = rt_synthesis.synthesize(box, mu=self._mu, azimuth=self._azimuth, line=self._line,
                                           wavelength=self._wavelength, progress=False,
                                           anchor_height=z_ref * u.km)
            del box
            part = cube[keep]
            blos[rows] = part.blos.to_value(u.G)
            meta = cube.meta
            yield rows, part
        self._sun.release()  # the canopy's layers: made again only if asked for
        self._blos = u.Quantity(blos, u.G, copy=False)
        self._meta = dict(meta, truth_anchor_mean_km=None)

    def cube(self):
        """
        The whole `~gongsynth.sun.stokes.StokesCube` (synthesised on the first call, then kept).

        Returns
        -------
        `~gongsynth.sun.stokes.StokesCube`
        """
        if self._cube is None:
            parts = [cube for _, cube in self.blocks()]
            stack = [np.concatenate([getattr(c, s).value for c in parts]) for s in ("I", "Q", "U", "V")]
            unit = parts[0].I.unit
            self._cube = StokesCube(*(u.Quantity(a, unit, copy=False) for a in stack), self._wavelength,
                                    self.pixel_size, mu=self._mu, blos=self._blos, meta=self._meta)
        return self._cube
