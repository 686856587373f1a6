"""
Files of Stokes spectra: gongsynth's FITS cube and RH 1.5D ``output_ray.hdf5``.

FITS layout written by `write_fits` (and required by `read_fits`):

========== ======================= =================================================
HDU        EXTNAME                 content
========== ======================= =================================================
0          (primary, no data)      ``CONTENT = 'GONGSYNTH STOKES CUBE'``, ``PIXSIZE``
                                   [km], ``MU`` (scalar μ, or ``'ARRAY'``),
                                   ``GSMETA`` (JSON of the provenance dict)
1-4        ``I``, ``Q``, ``U``,    float32 (ny, nx, nλ) in numpy order (NAXIS1 = λ),
           ``V``                   ``BUNIT = 'erg / (s cm2 sr cm)'``
5          ``WAVELENGTH``          float64 (nλ,) in nm (any grid, exact)
optional   ``MU``                  float64 (ny, nx), per-column μ
optional   ``BLOS``                float32 (ny, nx) true B_LOS in G
========== ======================= =================================================

Values round-trip exactly (float32 Stokes, float64 wavelengths).  Files are
written under a temporary name and renamed, and an existing file is only
replaced with ``overwrite=True``.
"""
from __future__ import annotations

import json
from pathlib import Path

import astropy.units as u
import numpy as np
from astropy.io import fits

from gongsynth.files import atomic_path, check_writable
from gongsynth.optional import import_optional
from gongsynth.validation import check_quantity
from gongsynth.version import version

__all__ = ["write_fits", "read_fits", "read_rh15d", "FITS_CONTENT", "RADIANCE_UNIT", "STOKES"]

#: Storage unit of every Stokes array: spectral radiance per unit wavelength.
RADIANCE_UNIT = u.Unit("erg / (s cm2 sr cm)")

#: Names of the four Stokes parameters, in storage order.
STOKES = ("I", "Q", "U", "V")

#: Value of the CONTENT keyword that marks a gongsynth Stokes cube.
FITS_CONTENT = "GONGSYNTH STOKES CUBE"

# RH 1.5D marks columns that did not converge with this fill value.
_RH_FILL_THRESHOLD = 1e30
_RH_UNIT = u.Unit("J / (s m2 Hz sr)")


def write_fits(cube, path, *, overwrite=False):
    """
    Write a `~gongsynth.sun.stokes.StokesCube` to FITS (layout in the module docstring).

    Parameters
    ----------
    cube : `~gongsynth.sun.stokes.StokesCube`
    path : str or `pathlib.Path`
    overwrite : bool, optional
        Replace an existing file; default False raises `FileExistsError`.

    Examples
    --------
    >>> import numpy as np, astropy.units as u, tempfile, os
    >>> from gongsynth.sun.stokes import StokesCube
    >>> data = np.ones((4, 2, 2, 3), dtype=np.float32)
    >>> cube = StokesCube.from_array(data, [676.7, 676.78, 676.9] * u.nm, 96 * u.km)
    >>> path = os.path.join(tempfile.mkdtemp(), "cube.fits")
    >>> write_fits(cube, path)
    >>> bool(np.all(read_fits(path)["V"] == cube.V))
    True
    """
    if not all(hasattr(cube, name) for name in (*STOKES, "wavelength", "pixel_size", "mu")):
        raise TypeError(f"cube must be a StokesCube, got {type(cube).__name__}")
    path = Path(path)
    check_writable([path], overwrite)
    primary = fits.PrimaryHDU()
    hdr = primary.header
    hdr["CONTENT"] = (FITS_CONTENT, "file layout: gongsynth.sun.stokes_files")
    hdr["ORIGIN"] = ("gongsynth", "synthetic data, not an observation")
    hdr["GSVERS"] = (version, "gongsynth version")
    hdr["PIXSIZE"] = (float(cube.pixel_size.to_value(u.km)), "[km] horizontal size of one column")
    if np.ndim(cube.mu) == 0:
        hdr["MU"] = (float(cube.mu), "cos of the viewing angle")
    else:
        hdr["MU"] = ("ARRAY", "per-column mu in extension MU")
    hdr["BUNIT"] = (RADIANCE_UNIT.to_string(), "unit of the Stokes extensions")
    hdr["GSMETA"] = json.dumps(cube.meta, default=str, sort_keys=True)
    hdus = [primary]
    for name in STOKES:
        hdu = fits.ImageHDU(getattr(cube, name).value, name=name)
        hdu.header["BUNIT"] = RADIANCE_UNIT.to_string()
        hdus.append(hdu)
    wave = fits.ImageHDU(cube.wavelength.to_value(u.nm).astype(np.float64), name="WAVELENGTH")
    wave.header["BUNIT"] = "nm"
    hdus.append(wave)
    if np.ndim(cube.mu) != 0:
        hdus.append(fits.ImageHDU(np.asarray(cube.mu, dtype=np.float64), name="MU"))
    if cube.blos is not None:
        blos = fits.ImageHDU(cube.blos.to_value(u.G).astype(np.float32), name="BLOS")
        blos.header["BUNIT"] = "G"
        hdus.append(blos)
    with atomic_path(path, overwrite=overwrite) as tmp:
        fits.HDUList(hdus).writeto(tmp, overwrite=True)


def read_fits(path):
    """
    Read a FITS file written by `write_fits`.

    Parameters
    ----------
    path : str or `pathlib.Path`

    Returns
    -------
    dict
        The `~gongsynth.sun.stokes.StokesCube` constructor's arguments
        (``StokesCube.from_fits`` builds the cube from them).

    Raises
    ------
    FileNotFoundError
        If the file does not exist.
    ValueError
        If the file is not FITS, or not a gongsynth Stokes cube (missing
        extensions or keywords, wrong shapes); the message says which.

    Examples
    --------
    >>> import tempfile, os
    >>> from astropy.io import fits
    >>> path = os.path.join(tempfile.mkdtemp(), "image.fits")
    >>> fits.PrimaryHDU(np.zeros((2, 2))).writeto(path)
    >>> read_fits(path)
    Traceback (most recent call last):
    ...
    ValueError: ... is not a gongsynth Stokes cube: primary header CONTENT is None, ...
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"no such file: {path}")
    try:
        hdul = fits.open(path, memmap=True, lazy_load_hdus=False)
    except (OSError, ValueError, TypeError) as exc:
        raise ValueError(f"{path} is not a readable FITS file ({exc})") from exc
    with hdul:
        hdr = hdul[0].header
        if hdr.get("CONTENT") != FITS_CONTENT:
            raise ValueError(
                f"{path} is not a gongsynth Stokes cube: primary header CONTENT is "
                f"{hdr.get('CONTENT')!r}, expected {FITS_CONTENT!r}"
            )
        names = [h.name for h in hdul[1:]]
        missing = [n for n in (*STOKES, "WAVELENGTH") if n not in names]
        if missing:
            raise ValueError(f"{path} is not a complete Stokes cube: missing extension(s) {missing}")
        for keyword, what in (("PIXSIZE", "the column size in km"),
                              ("MU", "the cosine of the viewing angle, or 'ARRAY'")):
            if keyword not in hdr:
                raise ValueError(f"{path} has no {keyword} keyword ({what})")
        try:
            meta = json.loads(hdr.get("GSMETA", "{}"))
        except json.JSONDecodeError as exc:
            raise ValueError(f"{path}: GSMETA is not valid JSON ({exc})") from exc
        wavelength = u.Quantity(np.array(hdul["WAVELENGTH"].data, dtype=np.float64),
                                hdul["WAVELENGTH"].header.get("BUNIT", "nm"))
        stokes = []
        for name in STOKES:
            hdu = hdul[name]
            if hdu.data is None or hdu.data.ndim != 3:
                raise ValueError(f"{path}: extension {name} must hold a 3-D array (ny, nx, nλ)")
            unit = u.Unit(hdu.header.get("BUNIT", RADIANCE_UNIT.to_string()))
            # Big-endian on disk: one native float32 copy per Stokes parameter.
            try:
                values = np.array(hdu.data, dtype=np.float32)
            except (ValueError, OSError) as exc:  # a truncated file cannot fill the array
                raise ValueError(f"{path}: extension {name} cannot be read; is the file truncated? "
                                 f"({exc})") from exc
            stokes.append(u.Quantity(values, unit, copy=False))
        if hdr["MU"] == "ARRAY":
            if "MU" not in names:
                raise ValueError(f"{path}: MU = 'ARRAY' but there is no MU extension")
            mu = np.array(hdul["MU"].data, dtype=np.float64)
        else:
            mu = float(hdr["MU"])
        blos = None
        if "BLOS" in names:
            blos = u.Quantity(np.array(hdul["BLOS"].data, dtype=np.float32),
                              hdul["BLOS"].header.get("BUNIT", "G"))
        return dict(zip(STOKES, stokes), wavelength=wavelength,
                    pixel_size=float(hdr["PIXSIZE"]) * u.km, mu=mu, blos=blos, meta=meta)


def _rh_pixel_size(path):
    """Column spacing from the ``atmos/x`` array of a sibling output_indata.hdf5, or None."""
    h5py = import_optional("h5py", "h5py")

    indata = Path(path).with_name("output_indata.hdf5")
    if not indata.exists():
        return None
    try:
        with h5py.File(indata, "r") as f:
            x = np.asarray(f["atmos/x"][:2], dtype=np.float64)
    except (OSError, KeyError):
        return None
    if x.size < 2 or not x[1] > x[0]:
        return None
    return ((x[1] - x[0]) * u.m).to(u.km)


def read_rh15d(path, *, pixel_size=None, mu=1.0, wavelength_range=None, region=None):
    """
    Read Stokes spectra from an RH 1.5D ``output_ray.hdf5`` file.

    The rh15d code (Pereira & Uitenbroek 2015) writes ``wavelength`` (nλ) in
    nm and ``intensity``, ``stokes_Q``, ``stokes_U``, ``stokes_V`` with
    dimensions (x, y, wavelength) in W m⁻² Hz⁻¹ sr⁻¹, float32.  Only the
    requested wavelength window and region are read, a block of x at a time,
    converted to erg s⁻¹ cm⁻² sr⁻¹ cm⁻¹ and transposed to (y, x, λ).

    Parameters
    ----------
    path : str or `pathlib.Path`
        The ``output_ray.hdf5`` file.
    pixel_size : `~astropy.units.Quantity`, optional
        Horizontal column size (length).  Default: the spacing of ``atmos/x``
        in an ``output_indata.hdf5`` next to ``path``; an error if there is none.
    mu : float, optional
        Cosine of the ray's viewing angle (RH's ray.input; not stored in the
        ray file).  Default 1.
    wavelength_range : `~astropy.units.Quantity`, shape (2,), optional
        Keep only wavelengths within [min, max] (e.g. ``[676.73, 676.83] * u.nm``).
        RH wavelengths are in air when ``VACUUM_TO_AIR`` was set.
    region : tuple of two slices, optional
        (y, x) sub-region of columns to read.

    Returns
    -------
    dict
        The `~gongsynth.sun.stokes.StokesCube` constructor's arguments, with
        ``meta`` holding the file name and the file's global attributes
        (``StokesCube.from_rh15d`` builds the cube from them).

    Raises
    ------
    FileNotFoundError
        If the file does not exist.
    ValueError
        If the file is not HDF5, lacks a Stokes variable or the wavelength,
        has inconsistent shapes, or holds RH's fill value (columns that did
        not converge).

    Examples
    --------
    >>> import h5py, tempfile, os, astropy.units as u
    >>> path = os.path.join(tempfile.mkdtemp(), "output_ray.hdf5")
    >>> with h5py.File(path, "w") as f:                   # a 2 × 3-column RH-like file
    ...     f["wavelength"] = np.linspace(676.70, 676.86, 17)
    ...     for name in ("intensity", "stokes_Q", "stokes_U", "stokes_V"):
    ...         f[name] = np.full((3, 2, 17), 4.6e-8 if name == "intensity" else 0, "f4")
    >>> fields = read_rh15d(path, pixel_size=48 * u.km, wavelength_range=[676.73, 676.83] * u.nm)
    >>> fields["I"].shape                                   # (y, x, wavelength)
    (2, 3, 11)
    """
    h5py = import_optional("h5py", "h5py")

    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"no such file: {path}")
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise ValueError(f"{path} is not a readable HDF5 file ({exc})") from exc
    with f:
        names = {"I": "intensity", "Q": "stokes_Q", "U": "stokes_U", "V": "stokes_V"}
        missing = [v for v in ("wavelength", *names.values()) if v not in f]
        if missing:
            hint = ""
            if "intensity" in f and "stokes_V" in missing:
                hint = " (was RH run with STOKES_MODE = NO_STOKES? a magnetogram needs V)"
            raise ValueError(
                f"{path} is not an RH 1.5D Stokes ray file: missing variable(s) {missing}{hint}; "
                f"found {sorted(f.keys())}"
            )
        lam = np.asarray(f["wavelength"][()], dtype=np.float64)
        if lam.ndim != 1:
            raise ValueError(f"{path}: wavelength must be 1-D, got shape {lam.shape}")
        shape = f["intensity"].shape
        if len(shape) != 3 or shape[2] != lam.size:
            raise ValueError(
                f"{path}: intensity must have dimensions (x, y, wavelength) with "
                f"{lam.size} wavelengths, got shape {shape}"
            )
        for key in names.values():
            if f[key].shape != shape:
                raise ValueError(f"{path}: {key} has shape {f[key].shape}, intensity has {shape}")
        if wavelength_range is not None:
            check_quantity(wavelength_range, u.nm, "wavelength_range")
            lo, hi = np.sort(wavelength_range.to_value(u.nm).ravel())[[0, -1]]
            keep = np.flatnonzero((lam >= lo) & (lam <= hi))
            if keep.size < 2:
                raise ValueError(
                    f"wavelength_range {lo}-{hi} nm holds {keep.size} of the file's wavelengths "
                    f"({lam.min():.4f}-{lam.max():.4f} nm); need at least 2"
                )
            wsl = slice(int(keep[0]), int(keep[-1]) + 1)
        else:
            wsl = slice(None)
        lam = lam[wsl]
        if np.any(np.diff(lam) <= 0):
            order = "" if wavelength_range is not None else " (pass wavelength_range to select one line)"
            raise ValueError(f"{path}: wavelengths in the selected range are not strictly increasing{order}")
        ysl, xsl = (slice(None), slice(None)) if region is None else region
        if not (isinstance(ysl, slice) and isinstance(xsl, slice)):
            raise TypeError("region must be a tuple of two slices (y, x)")
        xs = range(shape[0])[xsl]
        ys = range(shape[1])[ysl]
        if len(xs) == 0 or len(ys) == 0:
            raise ValueError(f"region {region} selects no columns of the {shape[1]}×{shape[0]} file")
        if pixel_size is None:
            pixel_size = _rh_pixel_size(path)
            if pixel_size is None:
                raise ValueError(
                    f"pixel_size not given and no output_indata.hdf5 with atmos/x next to {path}; "
                    "pass pixel_size (e.g. 48 * u.km)"
                )
        wavelength = u.Quantity(lam, u.nm)
        factor = u.Quantity(np.ones(lam.size), _RH_UNIT).to_value(
            RADIANCE_UNIT, equivalencies=u.spectral_density(wavelength)).astype(np.float32)
        nl = lam.size
        step = max(1, 4_000_000 // max(1, len(ys) * nl))
        out = {}
        for name, key in names.items():
            ds = f[key]
            arr = np.empty((len(ys), len(xs), nl), dtype=np.float32)
            for j in range(0, len(xs), step):
                xchunk = slice(xs.start + j * xs.step, xs.start + min(len(xs), j + step) * xs.step, xs.step)
                block = np.asarray(ds[xchunk, ysl, wsl], dtype=np.float32)   # (x, y, λ)
                if np.any(np.abs(block) > _RH_FILL_THRESHOLD):
                    bad = int(np.any(np.abs(block) > _RH_FILL_THRESHOLD, axis=-1).sum())
                    raise ValueError(
                        f"{path}: {key} holds RH's fill value in {bad} column(s) of x {xchunk.start}-"
                        f"{xchunk.stop} (columns that did not converge); re-run RH or pass a region "
                        "that excludes them"
                    )
                np.multiply(block.transpose(1, 0, 2), factor, out=arr[:, j:j + block.shape[0]])
            out[name] = u.Quantity(arr, RADIANCE_UNIT, copy=False)
        meta = {"source": str(path), "format": "rh15d output_ray.hdf5"}
        for k, v in f.attrs.items():
            v = v.decode() if isinstance(v, bytes) else v
            meta[f"rh_{k}"] = v.item() if isinstance(v, np.generic) else (
                v.tolist() if isinstance(v, np.ndarray) else v)
    return dict(out, wavelength=wavelength, pixel_size=pixel_size, mu=mu, meta=meta)
