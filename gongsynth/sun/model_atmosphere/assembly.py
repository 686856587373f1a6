"""
`ModelSun`: the 3-D model Sun assembled a block of rows at a time, the same bits as the whole box.
"""
from __future__ import annotations

import astropy.units as u
import numpy as np

from gongsynth.sun.atmosphere import Atmosphere
from gongsynth.sun.model_atmosphere import flux_elements as fe
from gongsynth.sun.model_atmosphere.builder import assemble_rows
from gongsynth.threads import run_chunks

__all__ = ["ModelSun"]


class ModelSun:
    """
    The 3-D model Sun held as its whole-plane ingredients and assembled by rows.

    The horizontally periodic construction needs whole planes (the granular
    pattern, the element map, the flows' and the internetwork's potentials,
    the spectra of the canopy's base planes: a few dozen 2-D arrays), but
    every height-dependent value of a column is then a function of its own
    row's planes and the 1-D profiles.  `rows` assembles any set of rows,
    the same bits as those rows of the whole box (`atmosphere`), so a
    synthesis can run a block of rows at a time without the whole
    (nz, ny, nx) atmosphere (3 GB in float32 at 1024² × 80 heights).  The
    potential-field canopy is the exception: one inverse FFT per height and
    component of the whole plane, so it is made once for all rows (3 float32
    components, a third of the atmosphere) and kept until `release`.

    Made by `~gongsynth.sun.model_atmosphere.builder.model_sun`;
    `~gongsynth.sun.model_atmosphere.builder.model_atmosphere` returns its `atmosphere`.  Any
    other attribute (``raw``, ``bz``, slicing, ...) is the whole atmosphere's
    (assembled once and kept).
    """

    def __init__(self, plan):
        self._plan = plan
        self._canopy = None
        self._whole = None

    @property
    def shape(self):
        """(nz, ny, nx), as the Atmosphere's."""
        grid = self._plan["grid"]
        return (self._plan["z"].size, grid.ny, grid.nx)

    @property
    def z(self):
        """Heights (km)."""
        return self._plan["z"] * u.km

    @property
    def pixel_size(self):
        """Horizontal spacing (km)."""
        return self._plan["pixel_size"] * u.km

    @property
    def meta(self):
        """The atmosphere's ``meta``."""
        return self._plan["meta"]

    def _canopy_layers(self):
        """The potential field of the base planes, (3, nz, ny, nx) float32, or None (no canopy, no spot)."""
        plan = self._plan
        if self._canopy is None and plan["spectra"]:
            canopy = np.empty((3,) + self.shape, dtype=np.float32)

            def layers(start, stop):
                for k in range(start, stop):
                    canopy[0, k], canopy[1, k], canopy[2, k] = fe.potential_layer(
                        plan["grid"], plan["spectra"], plan["bases"], plan["z"][k])

            # Heights on threads (numpy's and scipy.fft's loops release the GIL): each its own bits.
            run_chunks(layers, plan["z"].size)
            self._canopy = canopy
        return self._canopy

    def release(self):
        """Drop the canopy's layers (made again when next needed) and the kept whole atmosphere."""
        self._canopy = None
        self._whole = None

    def rows(self, rows, *, thermodynamics_only=False):
        """
        The atmosphere of some rows, bit for bit the same as those rows of `atmosphere`.

        Parameters
        ----------
        rows : array_like of int
            Row indices, taken modulo ny (the box is periodic: a block with a
            halo may wrap around), in any order, repeats allowed.
        thermodynamics_only : bool
            Temperature and pressure only (no flow, no field: what the
            reference height of the rays needs).

        Returns
        -------
        `~gongsynth.Atmosphere`
            (nz, len(rows), nx).
        """
        plan = self._plan
        nz, ny, nx = self.shape
        rows = np.mod(np.asarray(rows, dtype=np.int64).reshape(-1), ny)
        whole = rows.size == ny and bool(np.array_equal(rows, np.arange(ny)))
        canopy = None if thermodynamics_only else self._canopy_layers()
        if thermodynamics_only:
            mag = None
        elif canopy is None:
            mag = np.zeros((3, nz, rows.size, nx), dtype=np.float32)
        elif whole:
            mag, self._canopy = canopy, None          # handed over, not copied
        else:
            mag = canopy[:, :, rows]
        temp, pres, vel = assemble_rows(plan, rows, mag)
        kms = u.km / u.s
        if thermodynamics_only:
            return Atmosphere(temp << u.K, self.z, self.pixel_size, gas_pressure=pres << u.Unit("dyn cm-2"),
                              microturbulence=plan["microturbulence"] * kms, meta=self.meta)
        return Atmosphere(temp << u.K, self.z, self.pixel_size, gas_pressure=pres << u.Unit("dyn cm-2"),
                          velocity=vel << kms, magnetic_field=mag << u.G,
                          microturbulence=plan["microturbulence"] * kms, meta=self.meta)

    def atmosphere(self):
        """
        The whole `~gongsynth.Atmosphere` (all rows; what `model_atmosphere` returns).

        Returns
        -------
        `~gongsynth.Atmosphere`
        """
        return self.rows(np.arange(self.shape[1]))

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        if self._whole is None:
            self._whole = self.atmosphere()
        return getattr(self._whole, name)

    def __getitem__(self, key):
        return self.atmosphere()[key]

    def __repr__(self):
        nz, ny, nx = self.shape
        return f"<ModelSun {nz} heights x {ny} x {nx}, {self._plan['pixel_size']:g} km pixels, by rows>"
