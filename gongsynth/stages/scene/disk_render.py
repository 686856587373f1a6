"""
A full-disk scene from a patch library: the large-scale field filled with small scales, Doppler shifted.

`library_scene` is what `gongsynth.stages.scene.fulldisk.full_disk_scene` runs
for a `~gongsynth.stages.scene.library.PatchLibrary`: the large scales
(`gongsynth.stages.scene.surface.large_scale_grid`) on a heliographic grid,
then one pass of `gongsynth.stages.scene.disk_kernel.render_disk` over the
supersampled grid (~1 s for the default 4300² samples on 2 cores).  A grid whose light
would take more than `LIGHT_BYTES` (HMI's 12 planes of 8192² samples) gets its light and truth
where the optics read them, a band of rows of every plane and the truth's same rows per pass of the
renderer (`~gongsynth.stages.scene.scene.DeferredStack` s), and its counts (samples on the disk,
velocities beyond the basis' table) from the sight lines alone (`disk_counts`).
"""
import mmap
import sys
import warnings
from pathlib import Path

import astropy.units as u
import numpy as np

from gongsynth.geometry import as_obstime, pointing_centre, pointing_offset, wcs_header
from gongsynth.seeding import as_seed_sequence
from gongsynth.stages.channels import CHANNEL_UNIT
from gongsynth.stages.scene import shifts
from gongsynth.stages.scene.disk_kernel import cell_table, disk_counts, render_disk
from gongsynth.stages.scene.library_store import derived_arrays
from gongsynth.stages.scene.scene import DeferredStack, Scene, radiance_at_earth, sky_grid
from gongsynth.stages.scene.shifts import reduced_basis
from gongsynth.stages.scene.surface import large_scale_grid
from gongsynth.sun.rotation import CONVECTIVE_BLUESHIFT_FE6302
from gongsynth.validation import check_quantity

__all__ = ["library_scene", "render_rows", "VELOCITY_TERMS", "LIGHT_BYTES"]

#: The large-scale velocity terms `library_scene` can switch.
VELOCITY_TERMS = ("rotation", "observer", "blueshift", "supergranulation")


def _velocity_terms(velocities):
    if isinstance(velocities, bool):
        return dict.fromkeys(VELOCITY_TERMS, velocities)
    if not isinstance(velocities, dict) or set(velocities) - set(VELOCITY_TERMS):
        raise ValueError(f"velocities must be a bool or a dict with keys among {VELOCITY_TERMS}, "
                         f"got {velocities!r}")
    return {term: bool(velocities.get(term, True)) for term in VELOCITY_TERMS}


def _scene_seed(seed):
    """A 64-bit integer for the kernel's hash, from the run's seed."""
    return np.uint64(as_seed_sequence(seed).generate_state(1, np.uint64)[0])


#: The most memory the light of a full-disk grid may hold at once: a grid whose planes need more (HMI's
#: 12 planes of 8192² samples, 3.2 GB in float32) is rendered a group of planes at a time, each group
#: when the optics first read one of its planes (at most 1 GiB; GONG's 6 × 4300² take 0.44 GB at once).
LIGHT_BYTES = 2**30


def _plane_group(n_planes, grid):
    """How many light planes of ``grid`` are rendered at once (all, if they fit `LIGHT_BYTES`)."""
    per_plane = grid[0] * grid[1] * np.dtype(np.float32).itemsize
    return int(min(n_planes, max(1, LIGHT_BYTES // per_plane)))


def _deferred_scene(render, n_planes, truth, unit, patches=None):
    """
    The light and its truth as `DeferredStack` s, made in the same passes of the renderer.

    The light: every plane of a band of rows in one pass (`DeferredStack.band`: what the optics
    read), or one plane's rows, its group of planes rendered whole (`_plane_group`) when first asked
    for.  A whole plane is given as a copy, so that a reader that keeps one
    (`gongsynth.stages.imagers.image_planes` keeps the first) does not keep its group.

    The truth: each pass of the light writes its rows of ``truth`` too (the same numbers as a pass
    for the truth alone), so the optics, which read the truth after the light, find it made; rows
    asked for before their light are made by a pass without the light's sums.
    """
    grid = truth.shape
    group = _plane_group(n_planes, grid)
    cache = {"start": None, "block": None}
    made = np.zeros(grid[0], dtype=bool)     # the truth's rows written so far

    def rows(i, start, stop):
        g0 = (i // group) * group
        if cache["start"] != g0 or cache["block"] is None:
            cache["block"] = None    # free the old group before the new one is made
            block = np.zeros((min(group, n_planes - g0),) + grid, dtype=np.float32)
            render(block, g0)
            made[:] = True
            cache["start"], cache["block"] = g0, block
        out = cache["block"][i - g0, start:stop]
        return out.copy() if (start, stop) == (0, grid[0]) else out

    def bands(start, stop):
        block = np.zeros((n_planes, stop - start, grid[1]), dtype=np.float32)
        render(block, 0, start)
        made[start:stop] = True
        return block

    def release():
        cache["block"] = None
        _drop_pages(patches)

    def truth_rows(i, start, stop):
        missing = np.flatnonzero(~made[start:stop])
        if missing.size:
            first, last = start + missing[0], start + missing[-1] + 1
            render(np.zeros((0, last - first, grid[1]), dtype=np.float32), 0, first)
            made[first:last] = True
        return truth[start:stop]

    return (DeferredStack((n_planes,) + grid, np.float32, unit, rows, release, bands),
            DeferredStack(grid, np.float32, u.G, truth_rows))


def _drop_pages(array):
    """
    Give back the resident pages of a memory-mapped (read-only) library array: they are read again
    from the file if used later.  A full-disk render touches most of HMI's 0.9-GB library, which
    would otherwise stay in the process's resident memory through the camera and the reduction.
    """
    mapped = getattr(array, "_mmap", None)
    if mapped is not None and hasattr(mmap, "MADV_DONTNEED"):
        mapped.madvise(mmap.MADV_DONTNEED)


#: Library rows transformed at a time (bounds the memory of a large, memory-mapped library).
_ROWS_PER_CHUNK = 2**18


def _row_chunks(library):
    """The library's stored rows, (n, K) views a chunk at a time (patches, then the uniform levels)."""
    for array in (library.patches, library.uniform):
        flat = np.asarray(array).reshape(-1, array.shape[-1])
        for start in range(0, flat.shape[0], _ROWS_PER_CHUNK):
            yield flat[start:start + _ROWS_PER_CHUNK]


def render_rows(library, tolerance=None):
    """
    The library's rows and Doppler amplitudes as the renderer reads them: as stored, or on a lower rank.

    With a ``tolerance``, the basis is reduced (`gongsynth.stages.scene.shifts.reduced_basis`) for the
    spectra the library holds, both analyser states (every stored E part plus and minus V), so that
    every filtergram of every stored row, at every tabulated velocity, stays within ``tolerance`` of
    the filtergram of its continuum; a sample mixes rows with positive weights and scales them alike
    (limb darkening), so its error obeys the same bound.  Each E and V part of a row is replaced by
    its continuum and its r new coordinates; B_z and B_x are kept.  The reduced rows of a cached
    library are kept in its cache entry (`~gongsynth.stages.scene.library_store.derived_arrays`, keyed by
    the tolerance and the source of the code that reduces them): computed once, read back after.

    Parameters
    ----------
    library : `~gongsynth.stages.scene.library.PatchLibrary`
    tolerance : float, optional
        Largest relative error of a filtergram; None keeps the stored basis (the same bits).

    Returns
    -------
    patches, uniform : `numpy.ndarray`
        float32, the library's shapes with rows of K' = (n_e + 1)(r + 1) + 2 floats.
    amplitudes : `numpy.ndarray`
        (nv, C, r) float64.
    bound : float
        The bound on the filtergrams' relative error (0 for the stored basis).
    """
    if tolerance is None:
        return np.asarray(library.patches), np.asarray(library.uniform), library.basis.amplitudes, 0.0
    # Kept with a cached library: its key, the tolerance and the code that reduces (this module's and
    # the basis') name them.
    key = [repr(float(tolerance)), np.__version__] + [Path(module.__file__).read_bytes()
                                                       for module in (sys.modules[__name__], shifts)]
    rows = derived_arrays(library, "render-rows", lambda: _reduced_rows(library, tolerance), key)
    if rows["patches"].size == 0:       # no lower rank within the tolerance: the stored rows
        return np.asarray(library.patches), np.asarray(library.uniform), library.basis.amplitudes, 0.0
    return rows["patches"], rows["uniform"], rows["amplitudes"], float(rows["bound"])


def _reduced_rows(library, tolerance):
    """
    `render_rows` with a tolerance, computed: a dict of patches, uniform, amplitudes and bound (empty
    rows where no lower rank is within the tolerance: the stored ones are not copied into the cache).
    """
    basis = library.basis
    j1 = basis.rank + 1
    lay = library.layout()
    parts = lay["e"] + [lay["v"]]

    def spectra():
        for rows in _row_chunks(library):
            v = rows[:, lay["v"]:lay["v"] + j1].astype(np.float64)
            for e in lay["e"]:
                yield from (rows[:, e:e + j1] + v, rows[:, e:e + j1] - v)

    transform, amplitudes, bound = reduced_basis(basis, spectra, tolerance)
    if transform is None:
        return dict(patches=np.zeros(0, np.float32), uniform=np.zeros(0, np.float32),
                    amplitudes=basis.amplitudes, bound=np.float64(0.0))
    r1 = transform.shape[0] + 1
    # The stored E and V parts (continuum, J coordinates) to (continuum, r coordinates).
    block = np.zeros((j1, r1))
    block[0, 0] = 1.0
    block[1:, 1:] = transform.T
    out = []
    for array in (library.patches, library.uniform):
        flat = np.asarray(array).reshape(-1, array.shape[-1])
        rows = np.empty((flat.shape[0], len(parts) * r1 + 2), dtype=np.float32)
        for start in range(0, flat.shape[0], _ROWS_PER_CHUNK):
            chunk = flat[start:start + _ROWS_PER_CHUNK].astype(np.float64)
            for i, offset in enumerate(parts):
                rows[start:start + chunk.shape[0], i * r1:(i + 1) * r1] = chunk[:, offset:offset + j1] @ block
            rows[start:start + chunk.shape[0], -2:] = chunk[:, lay["bz"]:lay["bx"] + 1]
        out.append(rows.reshape(array.shape[:-1] + (rows.shape[1],)))
    return dict(patches=out[0], uniform=out[1], amplitudes=amplitudes, bound=np.float64(bound))


def library_scene(library, *, obstime=None, instrument=None, detector_shape=None, supersampling=None,
                  surface_field=None, seed=0, site=None, velocities=True, cell_size=30 * u.Mm,
                  pointing=None, network=None, basis_tolerance="instrument"):
    """
    The light and true B·n of the whole disk from a patch library.

    Parameters
    ----------
    library : `~gongsynth.stages.scene.library.PatchLibrary`
    obstime : `~astropy.time.Time` or str, optional
        Observer at Earth; default `gongsynth.geometry.DEFAULT_OBSTIME`.
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
        Must be the one the library was built with (its filters are in the
        Doppler basis).
    detector_shape : int or (int, int), optional
        Detector pixels; default the instrument's.
    supersampling : int, optional
        Samples per pixel along each axis; default the instrument's (5).
    surface_field : `sunpy.map.GenericMap`, optional
        Heliographic B_r (G); None: the quiet Sun everywhere.
    seed : int or `numpy.random.SeedSequence`, optional
        The cells' random offsets, mirrors, variants and quiet polarities.
    site : `~astropy.coordinates.EarthLocation`, optional
        Ground site (its daily rotation adds to the observer's velocity).
    velocities : bool or dict, optional
        Which large-scale velocities shift the spectra (`VELOCITY_TERMS`;
        ``supergranulation``: the network's cells' flow, only with a network); the
        tabulated convective blueshift is left out for a library whose spectra
        carry their own (the 3-D Sun's, ``meta["spectra_carry_blueshift"]``),
        the supergranulation for one whose patches hold theirs (the
        Milne-Eddington library's, ``meta["spectra_carry_supergranulation"]``).
    cell_size : `~astropy.units.Quantity`, optional
        Side of the surface cells (default 30 Mm).
    pointing : `~astropy.units.Quantity`, optional
        Helioprojective (Tx, Ty) of the detector's centre (default the Sun's centre).
    network : `~gongsynth.sun.surface_field.network.SupergranularNetwork`, optional
        The magnetic network laid on the large-scale field (`large_scale_grid`).
    basis_tolerance : float or None or "instrument", optional
        Render on a Doppler basis of lower rank whose filtergrams stay within this fraction of their
        continuum's (`render_rows`); None: the library's own basis; "instrument" (default): the
        instrument's ``render_tolerance`` if it has one (HMI), else None.

    Returns
    -------
    light : `~gongsynth.stages.scene.scene.Scene`
        (6, NY, NX) float32 radiance at Earth per arcsec², zero beyond the limb.
    truth : `~gongsynth.stages.scene.scene.Scene`
        True B·n (NY, NX) float32 in G at the same samples; ``meta["large_scale"]``
        holds the `~gongsynth.stages.scene.surface.LargeScale` grid.

    Examples
    --------
    >>> import astropy.units as u
    >>> from gongsynth import GONGInstrument
    >>> from gongsynth.stages.scene.library import build_library
    >>> lib = build_library(shape=(16, 16), pixel_size=6 * u.Mm, seeds_per_level=(1, 1, 1, 1),
    ...                     theta=(0, 45, 85))
    >>> light, truth = library_scene(lib, instrument=GONGInstrument(plate_scale=25 * u.arcsec),
    ...                              detector_shape=86, supersampling=1)
    >>> light.shape, bool(light.data[0, 43, 43].value > 0), bool(light.data[0, 0, 0].value == 0)
    ((6, 86, 86), True, True)
    """
    from sunpy.coordinates import get_earth, sun
    from sunpy.sun.constants import radius

    from gongsynth import instruments
    inst = instruments.get(instrument)
    supersampling = inst.supersampling if supersampling is None else supersampling
    if isinstance(supersampling, bool) or not isinstance(supersampling, (int, np.integer)) \
            or supersampling < 1:
        raise ValueError(f"supersampling must be a positive int, got {supersampling!r}")
    cell_km = check_quantity(cell_size, u.km, "cell_size").to_value(u.km)
    if cell_km <= 0:
        raise ValueError(f"cell_size must be positive, got {cell_size}")
    terms = _velocity_terms(velocities)
    if library.meta.get("spectra_carry_blueshift"):
        terms["blueshift"] = False      # the 3-D Sun's granulation shifts its own spectra
    if library.meta.get("spectra_carry_supergranulation") or network is None:
        terms["supergranulation"] = False   # the column photosphere's patches hold their own; no cells
    time = as_obstime(obstime)
    _, _, det = sky_grid(inst, detector_shape=detector_shape)
    grid = (det[0] * supersampling, det[1] * supersampling)
    scale = inst.plate_scale / supersampling
    large = large_scale_grid(time, surface_field, site=site, rotation=terms["rotation"],
                             observer=terms["observer"],
                             blueshift=CONVECTIVE_BLUESHIFT_FE6302 if terms["blueshift"] else None,
                             network=network, supergranulation=terms["supergranulation"])
    n_planes = len(inst.analysers)
    blos = np.zeros(grid, dtype=np.float32)
    to_earth = radiance_at_earth(1 * CHANNEL_UNIT)
    basis = library.basis
    level_first = np.array([p[0] if p else -1 for p in library.level_patches], dtype=np.int64)
    level_count = np.array([max(len(p), 1) for p in library.level_patches], dtype=np.int64)
    distance, b0 = get_earth(time).radius.to_value(u.km), sun.B0(time).to_value(u.rad)
    r_sun = radius.to_value(u.km)
    cells, (cell_j0, cell_i0) = cell_table(r_sun, cell_km, distance, b0)
    if isinstance(basis_tolerance, str):
        if basis_tolerance != "instrument":
            raise ValueError("basis_tolerance must be a float, None or 'instrument', "
                             f"got {basis_tolerance!r}")
        basis_tolerance = getattr(inst, "render_tolerance", None)
    patches, uniform, amplitudes, bound = render_rows(library, basis_tolerance)

    def render(light, plane0, row0=0):
        return render_disk(
            light, blos, scale.to_value(u.rad), *pointing_offset(pointing), distance, b0, r_sun,
            large.field, large.velocity, float(large.longitude[0]), float(large.latitude[0]),
            float(large.longitude[1] - large.longitude[0]),
            cell_km, cells, cell_j0, cell_i0, _scene_seed(seed), np.radians(library.theta),
            np.asarray(library.line.limb_darkening, float),
            library.level_net.astype(np.float64), level_first, level_count,
            np.asarray(library.level_uniform, dtype=np.int64), patches, uniform,
            library.pixel_size.to_value(u.km), bool(library.mirror_ok), int(library.n_e),
            np.asarray(library.e_index, dtype=np.int64), np.asarray(library.v_sign, dtype=np.float64),
            amplitudes, basis.totals, float(basis.velocity[0]),
            float(basis.velocity[1] - basis.velocity[0]),
            # The basis integrates over wavelength in nm; the channel unit is per cm of spectrum × cm.
            float(to_earth.value * (1 * u.nm).to_value(u.cm)), plane0, row0)

    if _plane_group(n_planes, grid) < n_planes:
        # The light and the truth where the optics read them, a band of rows at a time, in one pass
        # of the renderer; the counts now, from the sight lines alone.
        on_disk, outside = disk_counts(
            grid, scale.to_value(u.rad), *pointing_offset(pointing), distance, b0, r_sun, large.field,
            large.velocity, float(large.longitude[0]), float(large.latitude[0]),
            float(large.longitude[1] - large.longitude[0]), float(basis.velocity[0]),
            float(basis.velocity[1] - basis.velocity[0]), basis.totals.shape[0])
        light, truth_data = _deferred_scene(render, n_planes, blos, to_earth.unit, library.patches)
    else:
        light = np.zeros((n_planes,) + grid, dtype=np.float32)
        on_disk, outside = render(light, 0)
        truth_data = u.Quantity(blos, u.G, copy=False)
    if outside:
        warnings.warn(f"{outside} samples have a large-scale velocity beyond the library's Doppler basis "
                      f"(±{basis.max_velocity:.0f}): clamped", stacklevel=3)
    centre = pointing_centre(pointing, time)
    header = wcs_header(grid, scale, centre, wavelength=inst.line_wavelength)
    meta = dict(mode="full-disk", obstime=time, supersampling=int(supersampling), source="library",
                photosphere_pixel_size=library.pixel_size, cell_size=cell_km * u.km, velocities=terms,
                render_rank=amplitudes.shape[-1], render_error_bound=bound,
                on_disk_samples=int(on_disk), large_scale=large, library=repr(library))
    common = dict(boundary="zero", instrument=inst, detector_shape=det, centre=centre)
    truth = Scene(truth_data, scale, header, meta={**meta, "quantity": "blos"}, **common)
    data = light if isinstance(light, DeferredStack) else u.Quantity(light, to_earth.unit, copy=False)
    light_scene = Scene(data, scale, header, blos=truth_data,
                        meta={**meta, "quantity": "radiance"}, **common)
    return light_scene, truth
