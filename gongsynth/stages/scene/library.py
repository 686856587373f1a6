r"""
The full disk's small scales: photosphere patches, their spectra collapsed at a set of viewing angles.

A full-disk scene needs, at each of ~11 million samples, the six channel values
of the photosphere below it seen at its own μ and azimuth and Doppler shifted
by the Sun's rotation and the observer's motion.  Synthesising each sample's
spectrum costs ~6 µs; this module does the synthesis once per patch column
and viewing angle and keeps only what the channels need:

- **levels** of magnetic activity, by increasing net flux density: the quiet
  Sun (mixed-polarity network and internetwork), enhanced network, weak plage
  and plage (`gongsynth.sun.photosphere.model_photosphere` with denser and
  more unipolar network: its ``network_flux_density`` and
  ``network_polarity`` knobs, no sunspot), then uniform strong-field columns
  standing for pores, penumbrae and umbrae (`STRONG_FIELDS`);
- each level's patches (one or more seeds) are synthesised (Milne-Eddington)
  at the viewing angles ``theta`` (observer toward the patch's +x: azimuth 0)
  and every spectrum is stored as its continuum and its coordinates in the
  Doppler basis of `gongsynth.stages.scene.shifts` (per polarisation state,
  after the instrument's Mueller matrix), divided by the continuum limb
  darkening at that angle, with the true B·n.  Both are linear in the
  spectrum, so the synthesis contracts each column's spectra with them at
  once (`gongsynth.sun.photosphere.DeferredStokes.project`) and no spectrum
  is stored: the same numbers as synthesising the float32 cubes and
  projecting them, to their float32 rounding;
- `gongsynth.stages.scene.fulldisk` places the patches on the sphere and
  interpolates between the angles and levels.

Each patch is periodic; the scene never repeats one over the disk (random
offsets, rotations and mirrors per cell of the surface).

This module builds the library of the Milne-Eddington Sun (`build_library`,
~6 s for the defaults on 2 cores); `gongsynth.stages.scene.library_rt` builds
the same `PatchLibrary` from the 3-D Sun by radiative transfer (~10-30 s for
GONG's full disk, on a grid its pixels need).
`cached_library` builds either once per machine and keeps it on disk.
"""
import dataclasses
import hashlib
import json
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path

import astropy.units as u
import numpy as np

from gongsynth import instruments
from gongsynth.files import fingerprint
from gongsynth.seeding import as_seed_sequence, child_sequence
from gongsynth.stages.scene.library_layout import library_layout

# CacheWarning: re-exported, the name callers have caught since the cache's first version.
from gongsynth.stages.scene.library_store import CacheWarning, warn_cache, write_folder  # noqa: F401
from gongsynth.stages.scene.shifts import ShiftBasis
from gongsynth.sun.photosphere import (
    DeferredStokes,
    NiLine,
    Photosphere,
    me_line,
    model_photosphere,
)
from gongsynth.version import version

__all__ = ["LEVELS", "STRONG_FIELDS", "DEFAULT_THETA", "LIBRARY_SEED", "PatchLibrary", "build_library",
           "cached_library", "cache_directory"]

#: The patch levels: name and the `model_photosphere` knobs that set them (no
#: sunspot, no plage patches: the flux sits in network elements of
#: ``element_field``).  Mean unsigned flux densities: quiet network 8 G (the
#: built-in Sun's; quiet-Sun network ≈ 5-10 G, e.g. Parnell et al. 2009),
#: enhanced network 30 G, weak plage 100 G and plage 300 G (plage averages
#: 100-300 G over ~1″, Schrijver & Zwaan 2000, ch. 4); the unipolar fraction
#: grows from balanced (quiet) to 95 % (plage).
LEVELS = (
    ("quiet", {"network_flux_density": 8 * u.G, "network_polarity": 0.5}),
    ("enhanced network", {"network_flux_density": 30 * u.G, "network_polarity": 0.8}),
    ("weak plage", {"network_flux_density": 100 * u.G, "network_polarity": 0.9}),
    ("plage", {"network_flux_density": 300 * u.G, "network_polarity": 0.95}),
)

#: Uniform vertical-field columns above the plage level: (field, continuum
#: relative to the quiet Sun), no granulation or flows.  The continuum follows
#: the built-in sunspot's: penumbra 0.8 at 1.5 kG, umbra 0.25 at 3 kG
#: (Borrero & Ichimoto 2011), interpolated linearly in field and extended to a
#: pore (1 kG, 0.9) and a dark umbra (4 kG, 0.15).
STRONG_FIELDS = ((1000 * u.G, 0.9), (2000 * u.G, 0.62), (3000 * u.G, 0.25), (4000 * u.G, 0.15))

#: The seed of the built-in library: runs of any seed share its patches (their
#: own seed lays them out), so that it is built once and cached.
LIBRARY_SEED = 0

#: Viewing angles (deg from the vertical) at which the patches are synthesised.
DEFAULT_THETA = (0.0, 15.0, 30.0, 42.0, 52.0, 61.0, 69.0, 76.0, 82.0, 86.5, 89.0)

_FLOAT = np.float32


@dataclass(frozen=True)
class PatchLibrary:
    """
    Channel coordinates of photosphere patches at a set of viewing angles.

    Attributes
    ----------
    patches : `numpy.ndarray`
        float32 (n_patches, ny, nx, n_theta, K): per column and angle the row
        ``[E_0 continuum, E_0 coordinates (J), (E_1 continuum, E_1 coordinates),
        V continuum, V coordinates (J), B_z, B_x]``, where E_p is the
        polarisation-independent part (I, Q, U) of analyser state p and V the
        Stokes V spectrum, each divided by the continuum limb darkening at that
        angle (radiance units: erg s⁻¹ cm⁻² sr⁻¹ cm⁻¹), and the column's field
        in G along the vertical and the patch's +x (toward the observer): the
        true B·n at viewing angle θ is B_z cos θ + B_x sin θ.
    uniform : `numpy.ndarray`
        float32 (n_uniform, n_theta, K): the same for the uniform strong-field columns.
    theta : `numpy.ndarray`
        Viewing angles, deg (increasing).
    level_net : `numpy.ndarray`
        Net flux density of each level, G: the mean B_z of its patches, then
        the uniform fields (increasing).
    level_patches : tuple of tuple of int
        For each level, the indices of its patches in ``patches`` (empty for a
        uniform level).
    level_uniform : tuple of int
        For each level, its index in ``uniform`` (-1 for a patch level).
    pixel_size : `~astropy.units.Quantity`
        Column size of the patches (km).
    basis : `~gongsynth.stages.scene.shifts.ShiftBasis`
    n_e : int
        1 when both analyser states share E (no cross-talk into I±V from Q, U), else 2.
    e_index : tuple of int
        Which stored E each analyser state uses.
    v_sign : tuple of float
        The weight of V in each analyser state (+1, -1 without cross-talk).
    mirror_ok : bool
        Whether patches may be mirrored (a mirror changes the sign of U, so
        only when no analyser state sees U).
    line : `~gongsynth.sun.photosphere.NiLine`
    meta : dict
        Levels, knobs and seeds used.
    """

    patches: np.ndarray
    uniform: np.ndarray
    theta: np.ndarray
    level_net: np.ndarray
    level_patches: tuple
    level_uniform: tuple
    pixel_size: u.Quantity
    basis: object
    n_e: int
    e_index: tuple
    v_sign: tuple
    mirror_ok: bool
    line: NiLine
    meta: dict = field(default_factory=dict)

    @property
    def rank(self):
        """J, the Doppler basis' size."""
        return self.basis.rank

    @property
    def row_size(self):
        """K, the floats stored per column and angle."""
        return self.patches.shape[-1]

    @property
    def shape(self):
        """(ny, nx) of every patch."""
        return self.patches.shape[1:3]

    @property
    def patch_km(self):
        """(ny, nx) extent of every patch in km."""
        return tuple(n * self.pixel_size.to_value(u.km) for n in self.shape)

    @property
    def n_levels(self):
        """Number of levels."""
        return self.level_net.size

    @property
    def nbytes(self):
        """Memory held by the stored rows (bytes)."""
        return self.patches.nbytes + self.uniform.nbytes

    def layout(self):
        """
        Offsets of the parts of a stored row.

        Returns
        -------
        dict
            ``{"e": [offset of E_0, (offset of E_1)], "v": offset of V, "bz": offset of B_z,
            "bx": offset of B_x}``; each E and V part is J + 1 floats (continuum, then coordinates).
        """
        j1 = self.rank + 1
        return {"e": [i * j1 for i in range(self.n_e)], "v": self.n_e * j1, "bz": (self.n_e + 1) * j1,
                "bx": (self.n_e + 1) * j1 + 1}

    def __repr__(self):
        names = self.meta.get("levels", [])
        return (f"<PatchLibrary {len(names)} levels ({', '.join(names)}), {self.patches.shape[0]} patches "
                f"{self.shape[0]}×{self.shape[1]} of {self.pixel_size:g}, {self.theta.size} angles, "
                f"J={self.rank}, {self.nbytes / 2**20:.0f} MiB>")


def _project_rows(photosphere, mu, weights, wavelength, inst, line):
    """(ny, nx, n_out) float64: the spectra seen at ``mu`` from +x, contracted with ``weights``."""
    spectra = DeferredStokes(photosphere, mu=mu, los_azimuth=0 * u.deg, wavelength=wavelength,
                             instrument=inst, line=line)
    return np.moveaxis(spectra.project(weights), 0, -1)


def _uniform_photosphere(field_g, continuum):
    ones = np.ones((1, 1))
    still = np.zeros((1, 1)) * u.km / u.s
    return Photosphere(field_g * ones * u.G, 0 * ones * u.deg, 0 * ones * u.deg, still, still, still,
                       continuum * ones, 100 * u.km)


def build_library(*, seed=0, shape=(256, 256), pixel_size=384 * u.km, seeds_per_level=(2, 1, 1, 1),
                  theta=DEFAULT_THETA, knobs=None, wavelength=None, mueller=None, instrument=None,
                  line=None, max_velocity=4 * u.km / u.s, levels=LEVELS, strong_fields=STRONG_FIELDS):
    """
    Synthesise the patch library of a full-disk scene.

    Parameters
    ----------
    seed : int or `numpy.random.SeedSequence`, optional
        Root seed; patch *v* of level *k* uses the stream ``("library", k, v)``.
    shape : (int, int), optional
        Columns of each patch (default 256 × 256).
    pixel_size : `~astropy.units.Quantity`, optional
        Their size (default 384 km, about GONG's 0.5″ samples at disk centre:
        the default patch is the built-in Sun's 98 Mm box).  The photosphere
        is built on a ~100-200 km grid and block-averaged (fields and flows
        are area averages); finer columns cost proportionally more.
    seeds_per_level : sequence of int, optional
        Patches (independent seeds) of each level of ``levels``.
    theta : sequence of float, optional
        Viewing angles in deg, increasing from 0 to below 90.
    knobs : dict, optional
        `model_photosphere` knobs of the run's built-in Sun (``[photosphere]``);
        the levels override ``network_flux_density`` and ``network_polarity``,
        and set ``spot`` and ``plage`` off.
    wavelength : `~astropy.units.Quantity`, optional
        Spectral grid (default: the paper's 51 points).
    mueller : array_like, optional
        A (4, 4) instrument Mueller matrix (default: identity).  Q and U are
        those of the patch's frame (the observer toward +x), i.e. referred to
        the direction of disk centre on the sky rather than to solar west: a
        matrix that mixes Q or U into the analyser states sees them turned by
        the sample's position angle (I and V, all the identity uses, are not
        affected).
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
    line : `~gongsynth.sun.photosphere.NiLine`, optional
        The Milne-Eddington line (default: the instrument's line, `~gongsynth.sun.photosphere.me_line`:
        Ni I 676.8 nm for GONG, Fe I 617.3 nm for HMI).
    max_velocity : `~astropy.units.Quantity`, optional
        Largest Doppler shift the scene may apply (see `gongsynth.stages.scene.shifts.shift_basis`).
    levels : sequence of (str, dict), optional
        Default `LEVELS`.
    strong_fields : sequence of (Quantity, float), optional
        Default `STRONG_FIELDS`.

    Returns
    -------
    `PatchLibrary`

    Examples
    --------
    >>> import astropy.units as u
    >>> lib = build_library(shape=(16, 16), pixel_size=6 * u.Mm, seeds_per_level=(1, 1, 1, 1),
    ...                     theta=(0, 45, 85))
    >>> lib.n_levels, lib.patches.shape[::3], bool(lib.level_net[-1] > lib.level_net[0])
    (8, (4, 3), True)
    """
    line = me_line(instruments.get(instrument).line) if line is None else line
    lay = library_layout(instrument=instrument, wavelength=wavelength, pixel_size=pixel_size, theta=theta,
                         seeds_per_level=seeds_per_level, levels=levels, mueller=mueller,
                         max_velocity=max_velocity, line=line)
    inst, wavelength, theta, mu, basis, weights, k_row = (lay.instrument, lay.wavelength, lay.theta, lay.mu,
                                                          lay.basis, lay.weights, lay.k_row)
    knobs = dict(knobs or {})
    for fixed in ("shape", "pixel_size", "seed"):
        knobs.pop(fixed, None)
    root = as_seed_sequence(seed)
    n_spec = k_row - 2
    ny, nx = shape
    # (patch, y, x, angle, row): a sample's two angles are neighbours in memory.
    patches = np.empty((sum(seeds_per_level), ny, nx, theta.size, k_row), dtype=_FLOAT)
    level_patches, level_net, names, index = [], [], [], 0
    for number, ((name, overrides), count) in enumerate(zip(levels, seeds_per_level)):
        members, nets = [], []
        for variant in range(count):
            photosphere = model_photosphere(
                shape=tuple(shape), pixel_size=pixel_size,
                seed=child_sequence(root, "library", number, variant),
                **{**knobs, **overrides, "spot": False, "plage": False})
            nets.append(float(photosphere.bz.to_value(u.G).mean()))
            for t, w in enumerate(weights):
                patches[index, :, :, t, :n_spec] = _project_rows(photosphere, float(mu[t]), w, wavelength,
                                                                 inst, line)
            bx, _, bz = photosphere.field_vector()
            patches[index, ..., n_spec] = bz[..., None]
            patches[index, ..., n_spec + 1] = bx[..., None]
            members.append(index)
            index += 1
        level_patches.append(tuple(members))
        level_net.append(float(np.mean(nets)))
        names.append(name)
    uniform = np.empty((len(strong_fields), theta.size, k_row), dtype=_FLOAT)
    for number, (strength, continuum) in enumerate(strong_fields):
        column = _uniform_photosphere(strength.to_value(u.G), continuum)
        for t, w in enumerate(weights):
            uniform[number, t, :n_spec] = _project_rows(column, float(mu[t]), w, wavelength, inst, line)[0, 0]
        uniform[number, :, n_spec] = strength.to_value(u.G)
        uniform[number, :, n_spec + 1] = 0.0
        level_net.append(float(strength.to_value(u.G)))
        names.append(f"uniform {strength.to_value(u.G):.0f} G")
    net = np.array(level_net)
    # The quiet level is balanced by construction; its realisation's small net flux is not a level.
    net[0] = 0.0
    if np.any(np.diff(net) <= 0):
        raise ValueError(f"the levels' net flux densities must increase, got {np.round(net, 2).tolist()} G")
    meta = {"levels": names, "seed_entropy": str(root.entropy),
            "knobs": {k: str(v) for k, v in knobs.items()},
            "seeds_per_level": list(seeds_per_level), "patch_net_G": [round(v, 3) for v in level_net],
            "basis_rank": basis.rank, "basis_error": basis.error,
            # The column photosphere's patches hold 25 Mm supergranules with their outflow.
            "spectra_carry_supergranulation": True}
    return PatchLibrary(patches=patches, uniform=uniform, theta=theta, level_net=net,
                        level_patches=tuple(level_patches),
                        level_uniform=tuple([-1] * len(levels) + list(range(len(strong_fields)))),
                        pixel_size=pixel_size.to(u.km), basis=basis, n_e=lay.n_e, e_index=lay.e_index,
                        v_sign=lay.v_sign, mirror_ok=lay.mirror_ok, line=line, meta=meta)


# ---- caching: the library depends only on its arguments; building it takes ~6 s, loading < 1 s.

_MEMO = {}
# Modules whose code shapes the stored numbers: a change to any of them is a new library.
_SOURCES = ("stages/scene/library.py", "stages/scene/library_layout.py", "stages/scene/shifts.py",
            "instruments/quadrature.py", "stages/channels.py",
            "sun/photosphere/model.py", "sun/photosphere/synthesis.py", "sun/photosphere/_kernel.py",
            "sun/photosphere/line.py", "sun/photosphere/columns.py")
# ... and of the 3-D Sun's library (folders: every module in them).
_SOURCES_3D = ("stages/scene/library_rt.py", "sun/atmosphere.py", "sun/model_atmosphere", "sun/rt")
_ARRAYS = ("patches", "uniform", "theta", "level_net")
_BASIS = ("wavelength", "vectors", "velocity", "amplitudes", "totals")


def cache_directory():
    """
    Where built libraries are kept: ``$GONGSYNTH_CACHE_DIR``, else ``~/.cache/gongsynth``.

    Returns
    -------
    `pathlib.Path` or None
        None when the variable is set to ``""`` or ``"off"`` (no disk cache).
    """
    value = os.environ.get("GONGSYNTH_CACHE_DIR")
    if value is not None and value.strip().lower() in ("", "off", "none"):
        return None
    if value is None:
        base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
        return Path(base) / "gongsynth"
    return Path(value)


#: What of an instrument the stored numbers do not depend on (optics, camera, schedule, reduction,
#: detector maps): a run at another plate scale, seeing or camera shares the library.  Every other
#: parameter of the instrument (its line, Landé factor, filters, quadrature), with its name and line,
#: is part of the key, so that one instrument's library is never taken for another's; a parameter a
#: new instrument adds is in the key until it is listed here (a rebuild, never a wrong reuse).
_NOT_IN_KEY = frozenset((
    "aperture", "plate_scale", "detector_shape", "supersampling", "seeing_fwhm", "seeing_profile",
    "psf_radius", "seeing_wind_speed", "seeing_outer_scale", "seeing_layer_height", "magnetogram_cadence",
    "effective_area",
    "quantum_efficiency", "gain", "read_noise", "full_well", "adc_bits", "exposure_time", "frame_rate",
    "frame_interval", "waveplate_rate", "lcvr_period", "sequence_cadence", "vector_cycle", "vector_window",
    "vector_cadence", "dither_start", "dither_step", "dither_interval", "dither_cycle", "truncate_bits", "v0",
    "reference_line_fwhm", "reference_line_depth", "lut_velocity_max", "lut_velocity_step",
    "detector_map_seed", "flat_tilt", "flat_vignetting", "flat_dust_density", "flat_dust_depth_min",
    "flat_dust_depth_max", "flat_dust_radius_min", "flat_dust_radius_max", "flat_prnu", "dark_level",
    "dark_glow", "dark_glow_length", "dark_hot_fraction", "dark_hot_factor", "wrap_margin"))


def _instrument_key(inst):
    """The instrument's name, line and every parameter that shapes a library's numbers."""
    params = {f.name: getattr(inst, f.name) for f in dataclasses.fields(inst) if f.name not in _NOT_IN_KEY}
    return {"name": inst.name, "line": inst.line, **params}


def _instrument_sources(inst):
    """The modules of the instrument's own package (its filters): their code shapes the numbers too."""
    return sorted(Path(sys.modules[type(inst).__module__].__file__).parent.glob("*.py"))


def _key(arguments, sun):
    arguments = dict(arguments, sun=sun)
    inst = instruments.get(arguments.pop("instrument", None))
    arguments["instrument"] = _instrument_key(inst)
    root = Path(__file__).resolve().parents[2]
    digest = hashlib.sha256()
    for name in _SOURCES + (_SOURCES_3D if sun == "model-atmosphere" else ()):
        for path in (sorted((root / name).glob("*.py")) if (root / name).is_dir() else [root / name]):
            digest.update(path.read_bytes())
    for path in _instrument_sources(inst):
        digest.update(path.read_bytes())
    text = json.dumps({k: repr(v) for k, v in sorted(arguments.items())}, sort_keys=True)
    digest.update(text.encode())
    digest.update(np.__version__.encode())
    digest.update(version.encode())
    return digest.hexdigest()[:24]


_VERIFIED = set()    # entries whose checksums this process has checked


def _save(library, folder):
    """Write an entry atomically (replacing a damaged one), each file's SHA-256 in library.json."""
    def fill(tmp):
        for name in _ARRAYS:
            np.save(tmp / f"{name}.npy", getattr(library, name))
        for name in _BASIS:
            np.save(tmp / f"basis_{name}.npy", getattr(library.basis, name))
        small = {"level_patches": [list(p) for p in library.level_patches],
                 "level_uniform": list(library.level_uniform), "pixel_km": library.pixel_size.to_value(u.km),
                 "n_e": library.n_e, "e_index": list(library.e_index), "v_sign": list(library.v_sign),
                 "mirror_ok": library.mirror_ok, "basis_error": library.basis.error, "meta": library.meta,
                 "sha256": {p.name: fingerprint(p) for p in sorted(tmp.glob("*.npy"))}}
        (tmp / "library.json").write_text(json.dumps(small))

    try:
        write_folder(folder, fill, "library-*")
        _VERIFIED.add(folder)
    except OSError as exc:
        if not (folder / "library.json").is_file():   # not another process's entry that won the race
            warn_cache(f"could not write the patch library to the cache {folder.parent} "
                       f"({exc.strerror or exc}); the run goes on with the library in memory (set "
                       f"GONGSYNTH_CACHE_DIR to a writable folder, or to 'off' for no disk cache)")


def _verify(folder, small):
    """Each stored file's SHA-256 against library.json (once per process): ValueError if one differs."""
    if folder in _VERIFIED:
        return
    sums = small.get("sha256")
    if not isinstance(sums, dict) or set(sums) != {f"{n}.npy" for n in _ARRAYS + tuple(f"basis_{b}" for b in
                                                                                         _BASIS)}:
        raise ValueError("no checksums")
    for name, digest in sums.items():
        if fingerprint(folder / name) != digest:
            raise ValueError(f"{name} does not match its checksum")
    _VERIFIED.add(folder)


def _load(folder, line):
    small = json.loads((folder / "library.json").read_text())
    _verify(folder, small)
    arrays = {name: np.load(folder / f"{name}.npy", mmap_mode="r" if name == "patches" else None)
              for name in _ARRAYS}
    basis = ShiftBasis(**{name: np.load(folder / f"basis_{name}.npy") for name in _BASIS},
                       error=small["basis_error"])
    return PatchLibrary(patches=arrays["patches"], uniform=arrays["uniform"], theta=arrays["theta"],
                        level_net=arrays["level_net"],
                        level_patches=tuple(tuple(p) for p in small["level_patches"]),
                        level_uniform=tuple(small["level_uniform"]), pixel_size=small["pixel_km"] * u.km,
                        basis=basis, n_e=small["n_e"], e_index=tuple(small["e_index"]),
                        v_sign=tuple(small["v_sign"]), mirror_ok=small["mirror_ok"], line=line,
                        meta={**small["meta"], "cache": str(folder)})


def cached_library(*, sun="milne-eddington", progress=False, **arguments):
    """
    The patch library of a built-in Sun, built once per argument set and kept in memory and on disk.

    The disk copy (`cache_directory`; ~300 MB for the Milne-Eddington
    defaults, ~17 MB for GONG's 3-D library) is keyed by the Sun, the
    arguments (the Sun's knobs, the instrument's line and filters, and for the
    3-D Sun the patch grid of `~gongsynth.stages.scene.library_rt.atmosphere_grid`),
    gongsynth's version and the source of every module
    that shapes the numbers (so a code change builds a new one); the patches
    are memory-mapped from it.

    Parameters
    ----------
    sun : {"milne-eddington", "model-atmosphere"}, optional
        `build_library` (Milne-Eddington columns, seconds) or
        `gongsynth.stages.scene.library_rt.build_atmosphere_library` (the 3-D
        Sun by radiative transfer, ~8-30 s for GONG's full disk).
    progress : bool, optional
        A progress bar while the 3-D library builds (not part of the key).
    **arguments
        The builder's arguments (an int seed).

    Returns
    -------
    `PatchLibrary`

    Examples
    --------
    >>> import astropy.units as u
    >>> args = dict(shape=(16, 16), pixel_size=6 * u.Mm, seeds_per_level=(1, 1, 1, 1), theta=(0, 60))
    >>> cached_library(**args) is cached_library(**args)
    True
    """
    if sun == "milne-eddington":
        def build():
            return build_library(**arguments)
    elif sun == "model-atmosphere":
        from gongsynth.stages.scene.library_rt import atmosphere_grid, build_atmosphere_library

        # The default grid, into the key (the same for every instrument: one seed, one Sun).
        shape, pixel_size = atmosphere_grid()
        arguments = {"shape": shape, "pixel_size": pixel_size, **arguments}

        def build():
            return build_atmosphere_library(progress=progress, **arguments)
    else:
        raise ValueError(f"sun must be 'milne-eddington' or 'model-atmosphere', got {sun!r}")
    seed = arguments.get("seed", 0)
    if not isinstance(seed, (int, np.integer)):
        return build()
    key = _key(arguments, sun)
    if key in _MEMO:
        return _MEMO[key]
    folder = None if cache_directory() is None else cache_directory() / f"library-{key}"
    library = None

    def rows_line():
        # ``line`` is the Milne-Eddington NiLine, or the 3-D library's spectral line (then the rows' limb
        # darkening is the Milne-Eddington description's of the instrument's line, see library_rt).
        given = arguments.get("line")
        return given if isinstance(given, NiLine) else me_line(
            instruments.get(arguments.get("instrument")).line)

    if folder is not None and folder.exists():
        try:
            library = _load(folder, rows_line())
        except (OSError, ValueError, KeyError, TypeError) as exc:
            warn_cache(f"the cached patch library {folder} is damaged ({exc}); it is rebuilt and replaced")
            library = None
    if library is None:
        library = build()
        if folder is not None:
            _save(library, folder)
            if folder in _VERIFIED:
                # Written: the run goes on from the memory-mapped copy, as a cached run does (the same
                # library; the built patches, 0.8 GB for HMI's Milne-Eddington one, are freed).
                library = _load(folder, rows_line())
    _MEMO.clear()      # keep one: a library is ~300 MB
    _MEMO[key] = library
    return library
