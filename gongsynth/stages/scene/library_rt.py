r"""
The full disk's patch library from the 3-D Sun: `model_atmosphere` patches by LTE Stokes radiative transfer.

The same `~gongsynth.stages.scene.library.PatchLibrary` as the
Milne-Eddington build (`gongsynth.stages.scene.library.build_library`), so
the full-disk renderer does not know which Sun it maps, but every number comes
from the built-in 3-D Sun:

- **levels** of magnetic activity (`ATMOSPHERE_LEVELS`): seeded
  `gongsynth.sun.model_atmosphere.model_atmosphere` boxes without a sunspot,
  with the element flux densities and polarities of the Milne-Eddington
  levels (quiet 8 G balanced, enhanced network 30 G, weak plage 100 G, plage
  300 G, increasingly unipolar), the plage levels with Solanki's plage
  flux-tube stratification (``element_model="plage"``, which the builder
  offers for plage) instead of the network one;
- **strong-field levels** (`STRONG_COLUMNS`): uniform vertical-field columns
  with the built-in sunspot's penumbra (del Toro Iniesta et al. 1994, at
  ``penumbra_field``) and umbra (Maltby et al. 1986, ``umbra_model`` at
  ``umbra_field``) stratifications, each sunk by its own Wilson depression
  as the builder places them; the renderer mixes the two linearly in between;
- every patch is synthesised by `gongsynth.sun.rt.synthesize` (inclined rays
  through the periodic box) in the library's ``line`` (a name of
  `gongsynth.sun.rt.LINES`, default Ni I 676.8 nm, with the line's measured
  Landé factor) at the viewing angles ``theta`` with the observer
  toward +x, and each spectrum is stored as its continuum and Doppler-basis
  coordinates (`gongsynth.stages.scene.library_layout.row_weights`), divided by the
  continuum limb darkening at that angle;
- the truth is the radiative transfer's (B·n where the line forms, the
  ``"paper"`` definition of `gongsynth.sun.rt.truth`), which depends on the
  angle: the row's B_z slot holds it divided by μ and the B_x slot is zero,
  so the renderer's ``B_z μ + B_x sin θ`` gives it back exactly at the
  library's angles and interpolates it in between.  The truth is the same
  quantity for every line (τ_c at the line's own wavelength).

The patches' granulation keeps no flow beyond `PATCH_FLOW_CUTOFF` (10 Mm,
`model_atmosphere`'s ``flow_cutoff``): granules and mesogranules (5-10 Mm,
Rincon & Rieutord 2018, Living Rev. Sol. Phys. 15, 6, §2.1.4) are theirs,
while the supergranular flow is the disk's, one pattern with the network
(`gongsynth.sun.surface_field.supergranulation`).  A patch of one surface
cell would otherwise carry, from its granulation's large-scale tail,
horizontal flows of 300-700 m/s rms over 14 Mm (measured at 200 km, two
seeds), a second and random supergranulation cut at the cells' edges.

The rows are divided by, and the renderer multiplies them again by, the
continuum limb darkening of the Milne-Eddington description of the instrument's
line (`gongsynth.sun.photosphere.me_line`: Neckel & Labs at 676.8 or 617.3 nm):
the same polynomial both ways, so it only enters through the interpolation
between the library's angles.

The spectra of the 3-D Sun carry their own granular flows, hence their own
convective blueshift; the renderer leaves out the tabulated one for such a
library (``meta["spectra_carry_blueshift"]``).

Cost: ~200-400 µs per column and angle on 2 cores (the equation of state
along every ray dominates).  The default grid (`atmosphere_grid`) is the same
for every instrument: the tiled run's 384 km columns and patches of one
surface cell (`gongsynth.stages.scene.fulldisk.DEFAULT_CELL`, 30 Mm: 79²
columns), 4 patches × 6241 columns × 7 angles, ~8 s here, once: it is cached
like the Milne-Eddington library
(`gongsynth.stages.scene.library.cached_library`).  One grid because the
builder draws its granulation, elements and internetwork on its grid: a
coarser grid of the same seed is another Sun (its B_z at z = 0 correlates
with the 384 km one's, block-averaged, to |r| < 0.05), so GONG's full disk on
768 km columns (the default until a session measured it) was not the Sun that
HMI and MDI saw: on the full-disk comparison's 1° Carrington cells the truths
differed by 7 G rms.  ``benchmarks/validate_library_rt.py`` compares a
coarser library's spectra with the default's.
"""
import inspect

import astropy.units as u
import numpy as np

from gongsynth import instruments
from gongsynth.seeding import as_seed_sequence, child_sequence
from gongsynth.stages.scene.fulldisk import DEFAULT_CELL
from gongsynth.stages.scene.library import LEVELS, PatchLibrary
from gongsynth.stages.scene.library_layout import library_layout
from gongsynth.sun.atmosphere import Atmosphere
from gongsynth.sun.model_atmosphere import model_atmosphere
from gongsynth.sun.model_atmosphere.builder import reference_stratifications
from gongsynth.sun.photosphere import me_line
from gongsynth.sun.rt import default_wavelength, get_line
from gongsynth.sun.rt import synthesize as rt_synthesize
from gongsynth.sun.surface_field.supergranulation import GRANULAR_FLOW_SCALE

__all__ = ["ATMOSPHERE_LEVELS", "STRONG_COLUMNS", "ATMOSPHERE_THETA", "TILED_COLUMN", "PATCH_FLOW_CUTOFF",
           "atmosphere_grid", "build_atmosphere_library"]


def _as_atmosphere_knobs(knobs):
    """The Milne-Eddington level knobs as `model_atmosphere` ones."""
    return {"element_flux_density": knobs["network_flux_density"],
            "positive_fraction": knobs["network_polarity"]}


#: The patch levels: name and the `model_atmosphere` knobs that set them (flux densities and
#: polarities of `gongsynth.stages.scene.library.LEVELS`; Solanki's plage tubes for the plage levels).
ATMOSPHERE_LEVELS = tuple(
    (name, {**_as_atmosphere_knobs(knobs), **({"element_model": "plage"} if "plage" in name else {})})
    for name, knobs in LEVELS)

#: The uniform strong-field columns: the builder's sunspot stratifications (and their field knobs).
STRONG_COLUMNS = (("penumbra", "penumbra_field"), ("umbra", "umbra_field"))

#: Default viewing angles (deg) of the 3-D library: every 15° in μ-spacing to 76°, then toward the limb.
ATMOSPHERE_THETA = (0.0, 30.0, 48.0, 61.0, 72.0, 81.0, 87.0)

#: The largest scale of the patches' granular flow (`model_atmosphere`'s ``flow_cutoff``): above it
#: the disk's supergranular flow takes over (see the module docstring).
PATCH_FLOW_CUTOFF = GRANULAR_FLOW_SCALE

#: The column size of a tiled run's 3-D Sun (`gongsynth.suns.RUN_GRIDS`): the finest a library takes.
TILED_COLUMN = 384 * u.km

_FLOAT = np.float32
_BUILDER = {name: p.default for name, p in inspect.signature(model_atmosphere).parameters.items()}


def _contract(cube, weights):
    """(ny, nx, n_out) float64 rows of a StokesCube contracted with ``weights`` (n_out, 4, nλ)."""
    nl = cube.shape[-1]
    out = 0.0
    for s, name in enumerate(("I", "Q", "U", "V")):
        w = weights[:, s]
        if np.any(w):
            out = out + getattr(cube, name).value.reshape(-1, nl).astype(np.float64) @ w.T
    return np.asarray(out).reshape(cube.shape[:2] + (weights.shape[0],))


def _strong_column(kind, knobs):
    """A (nz, 1, 1) Atmosphere: the sunspot's ``kind`` stratification with its uniform vertical field."""
    get = {**_BUILDER, **knobs}.get
    nz, (z_lo, z_hi) = int(get("nz")), get("height_range").to_value(u.km)
    zg = np.linspace(z_lo, z_hi, nz)
    fields = {key: float(get(key).to_value(u.G))
              for key in ("element_field", "umbra_field", "penumbra_field")}
    ref = reference_stratifications(tuple(zg), get("granulation_models"), float(get("granulation_amplitude")),
                                    get("element_model"), fields["element_field"], get("umbra_model"),
                                    fields["umbra_field"], fields["penumbra_field"],
                                    bool(get("element_depression")), True)
    strength = fields[dict(STRONG_COLUMNS)[kind]]
    column = np.ones((nz, 1, 1))
    magnetic = np.zeros((3, nz, 1, 1))
    magnetic[2] = strength
    atm = Atmosphere(ref[f"{kind}_t"][:, None, None] * column * u.K, zg * u.km, 384 * u.km,
                     gas_pressure=np.exp(ref[f"{kind}_lnp"])[:, None, None] * column * u.Unit("dyn cm-2"),
                     magnetic_field=magnetic * u.G, microturbulence=get("microturbulence"),
                     meta={"origin": f"gongsynth sunspot {kind} column", "field_G": strength})
    return atm, strength


def atmosphere_grid(cell=DEFAULT_CELL):
    """
    The default patch grid of a 3-D library: (shape, pixel_size), the same for every instrument.

    The tiled run's `TILED_COLUMN` (384 km) and enough of them to hold one
    surface ``cell`` of the full-disk renderer (30 Mm): one seed is one Sun
    whichever instrument observes it (see the module docstring).

    Parameters
    ----------
    cell : `~astropy.units.Quantity`, optional
        Patch side to cover (default `gongsynth.stages.scene.fulldisk.DEFAULT_CELL`).

    Returns
    -------
    shape : (int, int)
    pixel_size : `~astropy.units.Quantity`
        km.

    Examples
    --------
    >>> atmosphere_grid()
    ((79, 79), <Quantity 384. km>)
    """
    column = TILED_COLUMN.to_value(u.km)
    n = max(8, int(np.ceil(cell.to_value(u.km) / column)))    # model_atmosphere's smallest box
    return (n, n), column * u.km


def build_atmosphere_library(*, seed=0, shape=None, pixel_size=None,
                             seeds_per_level=(1, 1, 1, 1), theta=ATMOSPHERE_THETA, knobs=None,
                             wavelength=None, mueller=None, instrument=None, max_velocity=4 * u.km / u.s,
                             levels=ATMOSPHERE_LEVELS, strong_columns=STRONG_COLUMNS, progress=False,
                             line=None):
    """
    Synthesise the patch library of a full-disk scene from the built-in 3-D Sun.

    Parameters
    ----------
    seed : int or `numpy.random.SeedSequence`, optional
        Root seed; patch *v* of level *k* uses the stream ``("library", k, v)``.
    shape : (int, int), optional
        Columns of each patch (default: `atmosphere_grid`, 79²).
    pixel_size : `~astropy.units.Quantity`, optional
        Their size (default: `atmosphere_grid`, 384 km).
    seeds_per_level : sequence of int, optional
        Patches (independent seeds) of each level of ``levels``.
    theta : sequence of float, optional
        Viewing angles in deg, increasing from 0 to below 90 (default `ATMOSPHERE_THETA`).
    knobs : dict, optional
        `model_atmosphere` knobs of the run's built-in Sun (``[photosphere]``);
        the levels override theirs, ``spot`` is off and ``flow_cutoff``, unless
        given, is `PATCH_FLOW_CUTOFF`.
    wavelength : `~astropy.units.Quantity`, optional
        Spectral grid (default: `gongsynth.sun.rt.default_wavelength` of the
        line, for Ni I the paper's 51 points).
    mueller : array_like, optional
        A (4, 4) instrument Mueller matrix (default: identity), as in
        `gongsynth.stages.scene.library.build_library`.
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
    max_velocity : `~astropy.units.Quantity`, optional
        Largest Doppler shift the scene may apply.
    levels : sequence of (str, dict), optional
        Default `ATMOSPHERE_LEVELS`.
    strong_columns : sequence of (str, str), optional
        Default `STRONG_COLUMNS`: the sunspot components and their field knobs.
    progress : bool, optional
        A progress bar over the patches and angles.
    line : str or `~gongsynth.sun.rt.LineData`, optional
        The spectral line synthesised (a name of `gongsynth.sun.rt.LINES`,
        e.g. ``"Fe I 617.3"``; default: the instrument's line, Ni I 676.8 nm for
        GONG, Fe I 617.3 nm for HMI).  Part of the cache key of
        `gongsynth.stages.scene.library.cached_library` (as the instrument's line is).

    Returns
    -------
    `~gongsynth.stages.scene.library.PatchLibrary`

    Examples
    --------
    >>> import astropy.units as u
    >>> lib = build_atmosphere_library(shape=(8, 8), pixel_size=3 * u.Mm, theta=(0, 60),
    ...                                knobs={"nz": 40})
    >>> lib.n_levels, lib.patches.shape[:4], bool(lib.level_net[-1] > lib.level_net[3])
    (6, (4, 8, 8, 2), True)
    """
    inst = instruments.get(instrument)
    grid_shape, grid_pixel = atmosphere_grid()
    shape = grid_shape if shape is None else shape
    pixel_size = grid_pixel if pixel_size is None else pixel_size
    rt_line = get_line(inst.line if line is None else line)
    line = me_line(inst.line)
    wavelength = default_wavelength(rt_line) if wavelength is None else wavelength
    lay = library_layout(instrument=instrument, wavelength=wavelength, pixel_size=pixel_size, theta=theta,
                         seeds_per_level=seeds_per_level, levels=levels, mueller=mueller,
                         max_velocity=max_velocity, line=line)
    wavelength, theta, mu, basis, weights, k_row = (lay.wavelength, lay.theta, lay.mu, lay.basis,
                                                    lay.weights, lay.k_row)
    knobs = dict(knobs or {})
    for fixed in ("shape", "pixel_size", "seed", "spot"):
        knobs.pop(fixed, None)
    if not knobs.get("flow_cutoff", 0 * u.Mm) > 0:      # not given: the disk's supergranulation takes over
        knobs["flow_cutoff"] = PATCH_FLOW_CUTOFF
    root = as_seed_sequence(seed)
    n_spec = k_row - 2
    ny, nx = shape
    patches = np.zeros((sum(seeds_per_level), ny, nx, theta.size, k_row), dtype=_FLOAT)
    uniform = np.zeros((len(strong_columns), theta.size, k_row), dtype=_FLOAT)
    bar = None
    if progress:
        from tqdm.auto import tqdm
        bar = tqdm(total=(patches.shape[0] + uniform.shape[0]) * theta.size,
                   desc="patch library (3-D Sun)", unit="synthesis")

    def fill(atmosphere, rows):
        """Synthesise ``atmosphere`` at every angle into ``rows`` (..., n_theta, K)."""
        for t, m in enumerate(mu):
            cube = rt_synthesize(atmosphere, mu=float(m), azimuth=0 * u.deg, wavelength=wavelength,
                                 progress=False, line=rt_line)
            block = _contract(cube, weights[t])
            rows[..., t, :n_spec] = block.reshape(rows[..., t, :n_spec].shape)
            rows[..., t, n_spec] = (cube.blos.value / m).reshape(rows[..., t, n_spec].shape)
            if bar is not None:
                bar.update()

    level_patches, level_net, names, index = [], [], [], 0
    try:
        for number, ((name, overrides), count) in enumerate(zip(levels, seeds_per_level)):
            members, nets = [], []
            for variant in range(count):
                atmosphere = model_atmosphere(tuple(shape), pixel_size=pixel_size,
                                              seed=child_sequence(root, "library", number, variant),
                                              **{**knobs, **overrides, "spot": False, "network": False})
                fill(atmosphere, patches[index])
                nets.append(float(patches[index, :, :, 0, n_spec].mean()))
                members.append(index)
                index += 1
            level_patches.append(tuple(members))
            level_net.append(float(np.mean(nets)))
            names.append(name)
        for number, (kind, _) in enumerate(strong_columns):
            column, strength = _strong_column(kind, knobs)
            fill(column, uniform[number])
            level_net.append(float(uniform[number, 0, n_spec]))
            names.append(f"{kind} {strength:.0f} G")
    finally:
        if bar is not None:
            bar.close()
    net = np.array(level_net)
    net[0] = 0.0      # the quiet level is balanced by construction
    if np.any(np.diff(net) <= 0):
        raise ValueError(f"the levels' net flux densities must increase, got {np.round(net, 2).tolist()} G")
    meta = {"sun": "model-atmosphere", "line": rt_line.name, "lande_g": rt_line.lande, "levels": names,
            "seed_entropy": str(root.entropy),
            "knobs": {k: str(v) for k, v in knobs.items()}, "seeds_per_level": list(seeds_per_level),
            "patch_net_G": [round(v, 3) for v in level_net], "basis_rank": basis.rank,
            "basis_error": basis.error, "truth": "rt paper definition, stored as B_z = B·n / mu",
            "spectra_carry_blueshift": True}
    return PatchLibrary(patches=patches, uniform=uniform, theta=theta, level_net=net,
                        level_patches=tuple(level_patches),
                        level_uniform=tuple([-1] * len(levels) + list(range(len(strong_columns)))),
                        pixel_size=pixel_size.to(u.km), basis=basis, n_e=lay.n_e, e_index=lay.e_index,
                        v_sign=lay.v_sign, mirror_ok=lay.mirror_ok, line=line, meta=meta)
