"""
Stokes spectra of the solar surface: the input of every simulation.

A `StokesCube` holds Stokes I, Q, U and V as spectral radiance at the Sun on a
(ny, nx, nλ) grid of photospheric columns, the wavelength axis, the horizontal
size of one column, the viewing angle and, when the cube was synthesised by
gongsynth, the true line-of-sight field (the ground truth of a calibration).

Storage is float32 in erg s⁻¹ cm⁻² sr⁻¹ cm⁻¹ (radiance per unit wavelength).
A cube of the paper's size (1024 × 1024 × 51) takes 850 MB; the class never
copies the data behind the user's back: arrays that are already float32 in
that unit are kept as they are (a view), spatial slicing returns views, and the
unit conversion of other inputs is done block by block into one float32 array.

File formats live in `gongsynth.sun.stokes_files`; `StokesCube.to_fits`,
`StokesCube.from_fits` and `StokesCube.from_rh15d` call them.
"""
from __future__ import annotations

import copy as _copy
import numbers

import astropy.units as u
import numpy as np

from gongsynth.sun.sampling import MAX_FIELD, MAX_VELOCITY, check_spectral_sampling
from gongsynth.sun.stokes_files import RADIANCE_UNIT, STOKES, read_fits, read_rh15d, write_fits
from gongsynth.validation import check_quantity

__all__ = ["StokesCube", "DeferredCube", "RADIANCE_UNIT", "STOKES"]

# Rows converted / checked at once: bounds temporaries to ~a few tens of MB.
_BLOCK_ELEMENTS = 4_000_000


def _row_blocks(ny, row_size):
    """Row ranges such that a block holds about `_BLOCK_ELEMENTS` values."""
    step = max(1, _BLOCK_ELEMENTS // max(1, row_size))
    for start in range(0, ny, step):
        yield slice(start, min(ny, start + step))


def _as_radiance(value, wavelength, name, copy):
    """
    ``value`` as a float32 Quantity in `RADIANCE_UNIT`, without copying if possible.

    Per-frequency radiance (as RH writes it) is converted with I_λ = I_ν c / λ².
    """
    check_quantity(value, RADIANCE_UNIT, name, equivalencies=u.spectral_density(wavelength))
    if value.ndim != 3:
        raise ValueError(f"{name} must be a 3-D array (ny, nx, nwavelength), got shape {value.shape}")
    if value.shape[-1] != wavelength.size:
        raise ValueError(
            f"{name} has {value.shape[-1]} wavelength points but wavelength has {wavelength.size}"
        )
    if value.unit == RADIANCE_UNIT and value.dtype == np.float32:
        if copy:
            return value.copy()
        return value if type(value) is u.Quantity else u.Quantity(value, copy=False)
    # One conversion factor per wavelength (exact for per-frequency units too).
    factor = u.Quantity(np.ones(wavelength.size), value.unit).to_value(
        RADIANCE_UNIT, equivalencies=u.spectral_density(wavelength))
    out = np.empty(value.shape, dtype=np.float32)
    data = value.value
    row = value.shape[1] * value.shape[2]
    for rows in _row_blocks(value.shape[0], row):
        np.multiply(data[rows], factor, out=out[rows], casting="unsafe")
    return u.Quantity(out, RADIANCE_UNIT, copy=False)


def _check_values(array, name, *, non_negative):
    """Finite (and optionally non-negative) check, block by block to bound memory."""
    data = array.value
    row = data.shape[1] * data.shape[2]
    for rows in _row_blocks(data.shape[0], row):
        block = data[rows]
        if not np.isfinite(block).all():
            bad = sum(int((~np.isfinite(data[r])).sum()) for r in _row_blocks(data.shape[0], row))
            raise ValueError(f"{name} contains {bad} non-finite value(s) (NaN or inf)")
        if non_negative and block.min(initial=0.0) < 0:
            raise ValueError(
                f"{name} (Stokes I) must be non-negative; minimum is {float(data.min())} {array.unit}"
            )


def _check_wavelength(wavelength):
    check_quantity(wavelength, u.nm, "wavelength")
    lam = np.asarray(wavelength.to_value(u.nm), dtype=np.float64)
    if lam.ndim != 1 or lam.size < 2:
        raise ValueError(f"wavelength must be one-dimensional with at least 2 points, got shape {lam.shape}")
    if not np.isfinite(lam).all():
        raise ValueError("wavelength contains non-finite value(s) (NaN or inf)")
    if np.any(np.diff(lam) <= 0):
        i = int(np.argmax(np.diff(lam) <= 0))
        raise ValueError(
            f"wavelength must be strictly increasing; wavelength[{i + 1}] = {lam[i + 1]} nm "
            f"follows wavelength[{i}] = {lam[i]} nm"
        )
    return u.Quantity(lam, u.nm)


def _check_mu(mu, shape2d):
    if isinstance(mu, u.Quantity):
        mu = mu.to_value(u.one)
    if isinstance(mu, numbers.Real) and not isinstance(mu, bool):
        value = float(mu)
        if not 0 < value <= 1:
            raise ValueError(f"mu must be in (0, 1] (cos of the viewing angle), got {value}")
        return value
    arr = np.asarray(mu, dtype=np.float64)
    if arr.ndim == 0:
        return _check_mu(float(arr), shape2d)
    if arr.shape != tuple(shape2d):
        raise ValueError(f"mu must be a scalar or have shape (ny, nx) = {tuple(shape2d)}, got {arr.shape}")
    if not np.isfinite(arr).all() or arr.min() <= 0 or arr.max() > 1:
        raise ValueError("mu must be finite and in (0, 1] everywhere")
    return arr


class StokesCube:
    """
    Stokes I, Q, U, V spectra of a patch of the Sun.

    Parameters
    ----------
    I, Q, U, V : `~astropy.units.Quantity`, shape (ny, nx, nλ)
        Spectral radiance at the Sun, in any unit convertible to
        erg s⁻¹ cm⁻² sr⁻¹ cm⁻¹, including per-frequency units such as
        J s⁻¹ m⁻² Hz⁻¹ sr⁻¹ (RH's unit; converted with I_λ = I_ν c/λ²).
        Stored as float32 in erg s⁻¹ cm⁻² sr⁻¹ cm⁻¹: an input already in
        that form is kept without a copy (unless ``copy=True``).  Axis 0 is
        y (north at disk centre), axis 1 is x (west).  I must be finite and
        non-negative, Q, U, V finite.
    wavelength : `~astropy.units.Quantity`, shape (nλ,)
        Wavelength of each spectral point (length unit; stored in nm), strictly
        increasing.
    pixel_size : `~astropy.units.Quantity`
        Horizontal size of one column (length unit; stored in km), before any
        foreshortening.
    mu : float or array of shape (ny, nx), optional
        Cosine of the viewing angle, in (0, 1]; an array gives one per column
        (full-disk scenes).  Default 1 (disk centre).
    blos : `~astropy.units.Quantity`, shape (ny, nx), optional
        True line-of-sight field B·n (G, positive toward the observer), set by
        `gongsynth.sun.photosphere.synthesize`: the ground truth downstream.
    meta : dict, optional
        Provenance (source file, code, seed, ...).  Copied (shallow).
    copy : bool, optional
        Copy the Stokes arrays even when they could be kept as views.

    Raises
    ------
    TypeError, astropy.units.UnitsError, ValueError
        With the argument's name, for non-Quantity input, wrong units, shapes
        that disagree, NaN/inf, negative intensity or non-increasing wavelengths.

    Examples
    --------
    >>> import numpy as np, astropy.units as u
    >>> from gongsynth.sun.stokes import StokesCube
    >>> lam = np.linspace(676.73, 676.83, 51) * u.nm
    >>> I = np.full((4, 6, 51), 3e14, dtype=np.float32) * u.Unit("erg / (s cm2 sr cm)")
    >>> zero = np.zeros((4, 6, 51), dtype=np.float32) * I.unit
    >>> cube = StokesCube(I, zero, zero, zero, lam, 96 * u.km)
    >>> cube.shape
    (4, 6, 51)
    >>> np.shares_memory(cube.I, I)      # no copy
    True
    >>> cube[:2, 2:4].shape              # spatial slice: a view
    (2, 2, 51)
    >>> cube.rebin(2).pixel_size
    <Quantity 192. km>
    """

    def __init__(self, I, Q, U, V, wavelength, pixel_size, *, mu=1.0, blos=None, meta=None,
                 copy=False):
        self._wavelength = _check_wavelength(wavelength)
        arrays = {}
        for name, value in zip(STOKES, (I, Q, U, V)):
            arrays[name] = _as_radiance(value, self._wavelength, name, copy)
        shape = arrays["I"].shape
        for name in STOKES[1:]:
            if arrays[name].shape != shape:
                raise ValueError(f"{name} has shape {arrays[name].shape} but I has shape {shape}")
        for name in STOKES:
            _check_values(arrays[name], name, non_negative=(name == "I"))
        check_quantity(pixel_size, u.km, "pixel_size")
        if np.ndim(pixel_size) != 0 or not np.isfinite(pixel_size.value) or pixel_size.value <= 0:
            raise ValueError(f"pixel_size must be a positive finite scalar length, got {pixel_size}")
        self._pixel_size = pixel_size.to(u.km)
        self._mu = _check_mu(mu, shape[:2])
        if blos is not None:
            check_quantity(blos, u.G, "blos")
            if blos.shape != shape[:2]:
                raise ValueError(f"blos must have shape (ny, nx) = {shape[:2]}, got {blos.shape}")
            if not np.isfinite(blos.value).all():
                raise ValueError("blos contains non-finite value(s) (NaN or inf)")
            blos = blos.to(u.G)
            if blos.dtype != np.float32:
                blos = blos.astype(np.float32)
        self._blos = blos
        if meta is not None and not isinstance(meta, dict):
            raise TypeError(f"meta must be a dict, got {type(meta).__name__}")
        self.meta = dict(meta or {})
        self._stokes = arrays

    @classmethod
    def _trusted(cls, arrays, wavelength, pixel_size, mu, blos, meta):
        """Build without re-validating (slices and rebins of a valid cube)."""
        self = cls.__new__(cls)
        self._stokes = arrays
        self._wavelength = wavelength
        self._pixel_size = pixel_size
        self._mu = mu
        self._blos = blos
        self.meta = dict(meta)
        return self

    @classmethod
    def from_array(cls, data, wavelength, pixel_size, *, unit=RADIANCE_UNIT, mu=1.0, blos=None,
                   meta=None):
        """
        Build a cube from one plain array holding all four Stokes parameters.

        Parameters
        ----------
        data : array_like or `~astropy.units.Quantity`, shape (4, ny, nx, nλ)
            Stokes I, Q, U, V stacked on axis 0, axes (y, x, λ) after it.  A
            float32 array in erg s⁻¹ cm⁻² sr⁻¹ cm⁻¹ is used without a copy.
        wavelength : `~astropy.units.Quantity`, shape (nλ,)
            Wavelengths (length unit), strictly increasing.
        pixel_size : `~astropy.units.Quantity`
            Horizontal size of one column (length unit).
        unit : `~astropy.units.UnitBase` or str, optional
            Unit of a plain ``data`` array (ignored for a Quantity).  Default
            erg s⁻¹ cm⁻² sr⁻¹ cm⁻¹.
        mu, blos, meta
            As for `StokesCube`.

        Returns
        -------
        `StokesCube`

        Examples
        --------
        >>> import numpy as np, astropy.units as u
        >>> data = np.zeros((4, 2, 3, 5), dtype=np.float32)
        >>> data[0] = 1e-8                   # RH-like per-frequency radiance
        >>> cube = StokesCube.from_array(data, np.linspace(676.7, 676.9, 5) * u.nm, 48 * u.km,
        ...                              unit="J / (s m2 Hz sr)")
        >>> print(f'{cube.I[0, 0, 2]:.4e}')   # I_lambda = I_nu c / lambda^2
        6.5449e+13 erg / (s sr cm3)
        """
        if not isinstance(data, u.Quantity):
            data = u.Quantity(np.asarray(data), unit, copy=False)
        if data.ndim != 4 or data.shape[0] != 4:
            raise ValueError(f"data must have shape (4, ny, nx, nwavelength), got {data.shape}")
        return cls(data[0], data[1], data[2], data[3], wavelength, pixel_size, mu=mu, blos=blos,
                   meta=meta)

    # ---------------------------------------------------------------- access
    @property
    def I(self):  # noqa: E743 - Stokes I is the natural name
        """Stokes I, `~astropy.units.Quantity` (ny, nx, nλ) float32 in erg s⁻¹ cm⁻² sr⁻¹ cm⁻¹."""
        return self._stokes["I"]

    @property
    def Q(self):
        """Stokes Q (same shape and unit as `I`); positive along the sky-projected local +x (west)."""
        return self._stokes["Q"]

    @property
    def U(self):
        """Stokes U (same shape and unit as `I`)."""
        return self._stokes["U"]

    @property
    def V(self):
        """Stokes V (same shape and unit as `I`); V ≈ -Δλ_B cosγ dI/dλ, positive B_LOS toward the observer."""
        return self._stokes["V"]

    @property
    def wavelength(self):
        """Wavelength axis, `~astropy.units.Quantity` (nλ,) in nm, strictly increasing."""
        return self._wavelength

    @property
    def pixel_size(self):
        """Horizontal size of one column, `~astropy.units.Quantity` in km."""
        return self._pixel_size

    @property
    def mu(self):
        """Cosine of the viewing angle: float, or (ny, nx) array for per-column geometry."""
        return self._mu

    @property
    def viewing_angle(self):
        """Viewing angle arccos(μ), `~astropy.units.Quantity` in deg (scalar or (ny, nx))."""
        return np.degrees(np.arccos(self._mu)) * u.deg

    @property
    def blos(self):
        """True line-of-sight field, `~astropy.units.Quantity` (ny, nx) in G, or None."""
        return self._blos

    def check_spectral_sampling(self, instrument=None, *, max_field=MAX_FIELD, max_velocity=MAX_VELOCITY):
        """
        Refuse a cube whose wavelengths cannot give the GONG channel integrals.

        `gongsynth.sun.sampling.check_spectral_sampling` on the cube's wavelengths: they must cover
        the line ± two widths, the Zeeman shift of ``max_field`` and the
        Doppler shift of ``max_velocity`` (676.7404-676.8196 nm by default), at
        steps of 2 pm or finer (`gongsynth.sun.sampling.spectral_requirement`).
        Call it on a cube of your own before simulating it: a narrower or
        coarser grid gives wrong magnetograms without any other sign.

        Parameters
        ----------
        instrument : `~gongsynth.GONGInstrument`, optional
        max_field, max_velocity : `~astropy.units.Quantity`
            Default 4 kG and 3 km/s.

        Raises
        ------
        ValueError
            Saying what the cube covers and what is needed.
        """
        check_spectral_sampling(self._wavelength, instrument, max_field=max_field,
                                max_velocity=max_velocity, name="the cube's wavelength grid")

    @property
    def shape(self):
        """(ny, nx, nλ)."""
        return self._stokes["I"].shape

    @property
    def nbytes(self):
        """Bytes held by the four Stokes arrays."""
        return sum(a.nbytes for a in self._stokes.values())

    def __repr__(self):
        ny, nx, nl = self.shape
        lam = self._wavelength.value
        mu = f"{self._mu:g}" if np.ndim(self._mu) == 0 else "per-column"
        return (f"<StokesCube {ny}×{nx} columns of {self._pixel_size:g}, {nl} wavelengths "
                f"{lam[0]:.4f}-{lam[-1]:.4f} nm, mu={mu}, "
                f"blos={'yes' if self._blos is not None else 'no'}>")

    def __getitem__(self, key):
        """
        Slice the cube: ``cube[y, x]`` or ``cube[y, x, wavelength]`` with slices.

        Integer indices keep their axis (``cube[3, 5]`` is a 1 × 1 cube).  The
        result shares memory with this cube (no copy).
        """
        if not isinstance(key, tuple):
            key = (key,)
        if len(key) > 3:
            raise IndexError(f"StokesCube takes at most 3 indices (y, x, wavelength), got {len(key)}")
        key = tuple(slice(k, k + 1 if k != -1 else None) if isinstance(k, numbers.Integral) else k
                    for k in key)
        for axis, k in zip(("y", "x", "wavelength"), key):
            if not isinstance(k, slice):
                raise TypeError(f"StokesCube index along {axis} must be an int or a slice, got {k!r}")
        key = key + (slice(None),) * (3 - len(key))
        if key[2].step is not None and key[2].step < 1:
            raise ValueError("the wavelength slice must have a positive step (wavelengths stay increasing)")
        arrays = {name: a[key] for name, a in self._stokes.items()}
        if 0 in arrays["I"].shape:
            raise IndexError(f"slice {key} leaves an empty cube")
        wavelength = self._wavelength[key[2]]
        if wavelength.size < 2:
            raise IndexError("a StokesCube needs at least 2 wavelengths")
        mu = self._mu if np.ndim(self._mu) == 0 else self._mu[key[:2]]
        blos = None if self._blos is None else self._blos[key[:2]]
        return StokesCube._trusted(arrays, wavelength, self._pixel_size, mu, blos, self.meta)

    def copy(self):
        """
        A deep copy.

        Returns
        -------
        `StokesCube`
            With new arrays (the only method that copies the spectra).
        """
        arrays = {name: a.copy() for name, a in self._stokes.items()}
        mu = self._mu if np.ndim(self._mu) == 0 else self._mu.copy()
        blos = None if self._blos is None else self._blos.copy()
        return StokesCube._trusted(arrays, self._wavelength.copy(), self._pixel_size, mu, blos,
                                   _copy.deepcopy(self.meta))

    # --------------------------------------------------------------- rebin
    def rebin(self, factor):
        """
        Average ``factor × factor`` blocks of columns (e.g. 48 km → 96 km with 2).

        Spectra, ``blos`` and a per-column ``mu`` are averaged (area averages:
        flux density, as a pixel measures it).  Accumulation is in float64 one
        output row at a time, so memory is the output cube plus one row.

        Parameters
        ----------
        factor : int
            Block size; must divide both ny and nx.

        Returns
        -------
        `StokesCube`
            With ``pixel_size * factor``.
        """
        if isinstance(factor, bool) or not isinstance(factor, numbers.Integral) or factor < 1:
            raise ValueError(f"factor must be a positive int, got {factor!r}")
        factor = int(factor)
        ny, nx, nl = self.shape
        if ny % factor or nx % factor:
            raise ValueError(f"factor {factor} must divide the cube's (ny, nx) = {(ny, nx)}")
        if factor == 1:
            return self[:, :]
        my, mx = ny // factor, nx // factor
        arrays = {}
        for name, a in self._stokes.items():
            data = a.value
            out = np.empty((my, mx, nl), dtype=np.float32)
            for j in range(my):
                block = data[j * factor:(j + 1) * factor].reshape(factor, mx, factor, nl)
                out[j] = block.mean(axis=(0, 2), dtype=np.float64)
            arrays[name] = u.Quantity(out, RADIANCE_UNIT, copy=False)

        def _block_mean(m):
            return m.reshape(my, factor, mx, factor).mean(axis=(1, 3), dtype=np.float64)

        mu = self._mu if np.ndim(self._mu) == 0 else _block_mean(self._mu)
        blos = None
        if self._blos is not None:
            blos = u.Quantity(_block_mean(self._blos.value).astype(np.float32), u.G, copy=False)
        meta = dict(self.meta)
        meta["rebin_factor"] = meta.get("rebin_factor", 1) * factor
        return StokesCube._trusted(arrays, self._wavelength, self._pixel_size * factor, mu, blos, meta)

    # ----------------------------------------------------------------- I/O
    def to_fits(self, path, *, overwrite=False):
        """
        Write the cube to a FITS file (exact round trip with `from_fits`).

        See `gongsynth.sun.stokes_files.write_fits` for the layout.

        Parameters
        ----------
        path : str or `pathlib.Path`
        overwrite : bool, optional
            Replace an existing file (default: refuse).
        """
        write_fits(self, path, overwrite=overwrite)

    @classmethod
    def from_fits(cls, path):
        """
        Read a cube written by `to_fits`; see `gongsynth.sun.stokes_files.read_fits`.

        Parameters
        ----------
        path : str or `pathlib.Path`

        Returns
        -------
        `StokesCube`
        """
        return cls(**read_fits(path))

    @classmethod
    def from_rh15d(cls, path, *, pixel_size=None, mu=1.0, wavelength_range=None, region=None):
        """
        Read the Stokes spectra of an RH 1.5D ``output_ray.hdf5`` file.

        Parameters
        ----------
        path : str or `pathlib.Path`
            The ``output_ray.hdf5`` file.
        pixel_size : `~astropy.units.Quantity`, optional
            Column size; default from a sibling ``output_indata.hdf5``.
        mu : float, optional
            Cosine of the ray's viewing angle (default 1).
        wavelength_range : `~astropy.units.Quantity`, shape (2,), optional
            Wavelength window to keep.
        region : tuple of two slices, optional
            (y, x) columns to read.

        See `gongsynth.sun.stokes_files.read_rh15d` for details.

        Returns
        -------
        `StokesCube`
        """
        return cls(**read_rh15d(path, pixel_size=pixel_size, mu=mu,
                                wavelength_range=wavelength_range, region=region))


class DeferredCube:
    """
    Base of the cubes synthesised only where and when needed (block by block).

    A subclass knows ``shape`` and its own cheap attributes, sets ``_cube``
    (None until the whole cube is made) and ``_method`` (words for the
    repr), and defines ``cube()``; any other attribute (``I``, ``V``, ...)
    and slicing are the whole cube's, synthesised once by ``cube()``.
    """

    _cube = None
    _method = ""

    def cube(self):
        """The whole `StokesCube` (a subclass makes it on the first call and keeps it)."""
        raise NotImplementedError

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        return getattr(self.cube(), name)

    def __getitem__(self, key):
        return self.cube()[key]

    def __repr__(self):
        ny, nx, nl = self.shape
        held = "held" if self._cube is not None else "not synthesised"
        return f"<{type(self).__name__} {ny}×{nx}×{nl}, {self._method}, {held}>"

