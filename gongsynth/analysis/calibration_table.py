"""
Calibration tables: the papers' curves per viewing angle and region, built by simulation.

A table is an `astropy.table.QTable`, one row per (latitude, region), saved as
ECSV with its provenance in the metadata (gongsynth version, input Sun,
seeds, instrument, run configuration, date).  `calibration_table` tabulates
fits (`gongsynth.calibration_sweep.build_calibration_table` runs the sweep that
makes them); `read_calibration_table` reads a saved one, by default the table
shipped with gongsynth (made by ``scripts/build_default_calibration_table.py``,
whose docstring says how to regenerate it); `table_curve` gives back the
curve of one row.

Uncertainties (columns added by this version; older tables without them still
load and calibrate):

- ``uncertainty``: the *statistical* uncertainty of the factor,
  ``sqrt(s² / n + σ_boot²)`` (`seed_uncertainty`): ``s`` the standard
  deviation of the ``n`` seeds' own factors (``seed_spread``), so ``s / √n``
  the standard error of a mean over seeds, which carries the run-to-run
  variation of the Sun's realisation (the spot, the network) that the pooled
  fit's block bootstrap cannot see; ``σ_boot`` that bootstrap (``bootstrap``),
  kept in quadrature as a floor (one seed: the bootstrap alone).  The pixel
  noise is thereby counted twice, which is conservative and small: the
  bootstrap is 10 – 30 × below the seed scatter.
- ``systematic``: the Sun-model ensemble's band (`ensemble_systematic`): the
  largest paired change of the factor from the default Sun over the ensemble
  members that meet their observational constraints, a symmetric half-width.
"""
import importlib.resources

import astropy.units as u
import numpy as np
from astropy.table import QTable

from gongsynth.analysis.weak_flux import PAPER_BINS, FluxConservingCurve
from gongsynth.files import atomic_path

__all__ = ["DEFAULT_TABLE", "TABLE_LATITUDES", "UNCERTAINTY_ESTIMATOR", "SYSTEMATIC_RULE",
           "calibration_table", "seed_uncertainty", "ensemble_systematic", "add_systematic",
           "read_calibration_table", "INSTRUMENT_TABLES",
           "write_calibration_table", "table_curve"]

#: The viewing angles of the papers' tables.
TABLE_LATITUDES = u.Quantity(sorted(PAPER_BINS), u.deg)

#: File name of the table shipped with gongsynth (in ``gongsynth/data``): GONG's.
DEFAULT_TABLE = "calibration_default.ecsv"

#: The shipped table of each instrument of the family (in ``gongsynth/data``; papers' grid, seeds 1-4).
INSTRUMENT_TABLES = {"gong": DEFAULT_TABLE, "hmi": "calibration_hmi.ecsv", "mdi": "calibration_mdi.ecsv"}

#: The statistical estimator (recorded in every table's metadata as ``uncertainty_estimator``).
UNCERTAINTY_ESTIMATOR = ("uncertainty = sqrt(seed_spread**2 / n_seeds + bootstrap**2): seed_spread the "
                         "standard deviation (ddof=1) of the factors fitted to each seed's pixels alone, "
                         "bootstrap the block bootstrap of the fit pooled over the seeds (one seed: the "
                         "bootstrap alone); the factor and curve are the pooled fit")

#: How `ensemble_systematic` fills the angles the ensemble did not measure (metadata ``systematic_rule``).
SYSTEMATIC_RULE = ("systematic = max |paired change of the quiet-Sun factor from the default Sun| over the "
                   "accepted ensemble members (the default itself counts as 0) at each measured latitude; at "
                   "a latitude not measured, the largest value over the measured latitudes (conservative: "
                   "the band shrinks from 0 to 60 deg); sunspot rows: NaN (not measured)")

_MAX_NODES = max(max(bins) for bins in PAPER_BINS.values())


def _padded(values, size):
    out = np.full(size, np.nan)
    out[:values.size] = values
    return out


def seed_uncertainty(per_seed, bootstrap):
    """
    The statistical uncertainty of a pooled factor from its seeds' own factors and its bootstrap.

    Parameters
    ----------
    per_seed : sequence of float
        The factor fitted to each seed's pixels alone (NaN entries are dropped).
    bootstrap : float
        The block-bootstrap standard deviation of the fit pooled over the seeds.

    Returns
    -------
    uncertainty : float
        ``sqrt(s² / n + bootstrap²)`` (see `UNCERTAINTY_ESTIMATOR`);
        ``bootstrap`` with fewer than two seeds.
    spread : float
        ``s``, the seeds' standard deviation (ddof=1; NaN with fewer than two).

    Examples
    --------
    >>> uncertainty, spread = seed_uncertainty([1.2, 1.3, 1.25, 1.35], 0.004)
    >>> round(spread, 4), round(uncertainty, 4)
    (0.0645, 0.0325)
    """
    values = np.asarray(per_seed, float).ravel()
    values = values[np.isfinite(values)]
    bootstrap = float(bootstrap)
    if values.size < 2:
        return bootstrap, float("nan")
    spread = float(np.std(values, ddof=1))
    if not np.isfinite(bootstrap):
        bootstrap = 0.0
    return float(np.hypot(spread / np.sqrt(values.size), bootstrap)), spread


def calibration_table(fits, *, mu, metadata=None, per_seed=None):
    """
    Tabulate weak-flux fits: one row per fit.

    Parameters
    ----------
    fits : sequence of `~gongsynth.analysis.weak_flux.WeakFluxFactor`
        Fits with their latitude set.
    mu : sequence of float
        cos of the viewing angle of each fit.
    metadata : dict, optional
        Provenance for the table's ``meta``.
    per_seed : sequence of sequence of float, optional
        For each fit, the factors of its seeds fitted one by one: then
        ``uncertainty`` is `seed_uncertainty`'s (the fits' own uncertainty is
        kept as ``bootstrap``, the seeds' scatter as ``seed_spread``, their
        number as ``n_seeds``); default the fits' own uncertainty.

    Returns
    -------
    `~astropy.table.QTable`
        Columns ``latitude`` (deg), ``mu``, ``region``, ``factor``,
        ``uncertainty``, ``n_pixels``, ``n_bins``, ``nodes`` and ``values``
        (the curve, G, NaN-padded to a common length); with ``per_seed``
        also ``bootstrap``, ``seed_spread``, ``n_seeds`` and the per-seed
        ``seed_factors`` (NaN-padded).

    Examples
    --------
    >>> import astropy.units as u
    >>> import numpy as np
    >>> from gongsynth.analysis.weak_flux import WeakFluxFactor, flux_conserving_fit
    >>> t = np.random.default_rng(0).normal(0, 100, 5000)
    >>> fit = WeakFluxFactor(2.0, 0.1, flux_conserving_fit(t / 2, t, 7), "quiet", 5000, 0 * u.deg)
    >>> table = calibration_table([fit], mu=[1.0])
    >>> table["latitude"].unit, [str(r) for r in table["region"]], table["nodes"].shape
    (Unit("deg"), ['quiet'], (1, 35))
    """
    fits = list(fits)
    mu = [float(m) for m in mu]
    if len(mu) != len(fits):
        raise ValueError(f"mu must have one entry per fit ({len(fits)}), got {len(mu)}")
    table = QTable()
    table["latitude"] = u.Quantity([u.Quantity(f.latitude, u.deg) for f in fits], u.deg)
    table["mu"] = mu
    table["region"] = [f.region for f in fits]
    table["factor"] = [f.factor for f in fits]
    table["uncertainty"] = [f.uncertainty for f in fits]
    if per_seed is not None:
        per_seed = [np.asarray(p, float).ravel() for p in per_seed]
        if len(per_seed) != len(fits):
            raise ValueError(f"per_seed must have one entry per fit ({len(fits)}), got {len(per_seed)}")
        combined = [seed_uncertainty(p, f.uncertainty) for p, f in zip(per_seed, fits)]
        table["uncertainty"] = [c[0] for c in combined]
        table["bootstrap"] = [f.uncertainty for f in fits]
        table["seed_spread"] = [c[1] for c in combined]
        table["n_seeds"] = [int(np.isfinite(p).sum()) for p in per_seed]
        width = max(p.size for p in per_seed)
        table["seed_factors"] = np.array([_padded(p, width) for p in per_seed]).reshape(len(fits), width)
        table.meta["uncertainty_estimator"] = UNCERTAINTY_ESTIMATOR
    table["n_pixels"] = [f.n_pixels for f in fits]
    table["n_bins"] = [f.curve.nodes.size for f in fits]
    table["nodes"] = u.Quantity([_padded(f.curve.nodes.to_value(u.G), _MAX_NODES) for f in fits], u.G)
    table["values"] = u.Quantity([_padded(f.curve.values.to_value(u.G), _MAX_NODES) for f in fits], u.G)
    table.meta.update(metadata or {})
    return table


def ensemble_systematic(latitudes, changes, members):
    """
    The Sun-model systematic of the quiet-Sun factor at each latitude, from the ensemble's paired changes.

    Parameters
    ----------
    latitudes : `~astropy.units.Quantity`
        Where the systematic is wanted.
    changes : `~astropy.table.Table`
        The ensemble's weak-flux table (``scripts/sun_ensemble.py --weak-flux``):
        columns ``variant``, ``latitude`` and ``change`` (the paired change of
        the factor from the default Sun, same seeds).
    members : sequence of str
        The variants accepted by their observational constraints; the others'
        rows are ignored.  The default Sun is always counted (change 0).

    Returns
    -------
    `~numpy.ndarray`
        One value per latitude (`SYSTEMATIC_RULE`).

    Examples
    --------
    >>> from astropy.table import Table
    >>> changes = Table({"variant": ["a", "b", "c", "a", "b"], "latitude": [0.0, 0, 0, 60, 60] * u.deg,
    ...                  "change": [-0.07, 0.1, 0.5, -0.04, 0.001]})
    >>> ensemble_systematic([0, 45, 60] * u.deg, changes, members=["a", "b"]).round(3).tolist()
    [0.1, 0.1, 0.04]
    """
    latitudes = u.Quantity(latitudes, u.deg).ravel().to_value(u.deg)
    members = set(members)
    variant = np.asarray(changes["variant"]).astype(str)
    unknown = members - set(variant)
    if unknown:
        raise ValueError(f"members {sorted(unknown)} are not in the ensemble table "
                         f"(variants {sorted(set(variant))})")
    at = u.Quantity(changes["latitude"], u.deg).to_value(u.deg)
    change = np.abs(np.asarray(changes["change"], float))
    accepted = np.isin(variant, sorted(members)) & np.isfinite(change)
    measured = {float(a): float(np.max(change[accepted & np.isclose(at, a)], initial=0.0))
                for a in np.unique(at[accepted])}
    if not measured:
        raise ValueError("the ensemble table has no finite change for any of the members")
    envelope = max(measured.values())
    return np.array([next((v for a, v in measured.items() if np.isclose(a, lat)), envelope)
                     for lat in latitudes])


def add_systematic(table, changes, members, *, source):
    """
    Add the ``systematic`` column (`ensemble_systematic`) to a calibration table, in place.

    Quiet-Sun rows get the ensemble's band; sunspot rows NaN (the ensemble
    measured the quiet-Sun factor only).  The metadata records the rule, the
    members and ``source``.

    Parameters
    ----------
    table : `~astropy.table.QTable`
    changes : `~astropy.table.Table`
        See `ensemble_systematic`.
    members : sequence of str
    source : str
        Where the ensemble's numbers come from (file, grid, instrument).

    Returns
    -------
    `~astropy.table.QTable`
        ``table``.
    """
    quiet = np.asarray(table["region"]) == "quiet"
    systematic = np.full(len(table), np.nan)
    systematic[quiet] = ensemble_systematic(table["latitude"][quiet], changes, members)
    table["systematic"] = systematic
    table.meta["systematic_rule"] = SYSTEMATIC_RULE
    table.meta["ensemble_members"] = sorted(set(members))
    table.meta["ensemble_source"] = str(source)
    return table


def write_calibration_table(table, path, *, overwrite=False):
    """
    Save a calibration table as ECSV, atomically.

    Parameters
    ----------
    table : `~astropy.table.QTable`
    path : str or path-like
    overwrite : bool
        Replace an existing file (default: refuse).
    """
    with atomic_path(path, overwrite=overwrite) as tmp:
        table.write(tmp, format="ascii.ecsv", overwrite=True)  # the temporary file exists already


def read_calibration_table(path=None, *, instrument="gong"):
    """
    Read a calibration table; by default the one shipped with gongsynth for ``instrument``.

    Parameters
    ----------
    path : str or path-like, optional
    instrument : {"gong", "hmi", "mdi"}
        Without ``path``: whose shipped table (`INSTRUMENT_TABLES`).

    Returns
    -------
    `~astropy.table.QTable`

    Examples
    --------
    >>> table = read_calibration_table()
    >>> sorted(str(r) for r in set(table["region"]))
    ['quiet', 'sunspot']
    >>> read_calibration_table(instrument="hmi").meta["source"]
    'gongsynth/data/calibration_hmi.ecsv'
    """
    if path is None:
        if instrument not in INSTRUMENT_TABLES:
            raise ValueError(f"instrument must be one of {tuple(INSTRUMENT_TABLES)}, got {instrument!r}")
        name = INSTRUMENT_TABLES[instrument]
        resource = importlib.resources.files("gongsynth") / "data" / name
        with importlib.resources.as_file(resource) as file:
            table = QTable.read(file, format="ascii.ecsv")
        table.meta["source"] = f"gongsynth/data/{name}"
        return table
    table = QTable.read(path, format="ascii.ecsv")
    missing = {"latitude", "region", "factor", "nodes", "values", "n_bins"} - set(table.colnames)
    if missing:
        raise ValueError(f"{path} is not a gongsynth calibration table: "
                         f"columns {sorted(missing)} are missing")
    table.meta["source"] = str(path)
    return table


def table_curve(table, latitude, region="quiet"):
    """
    The curve of the row at exactly ``latitude`` for ``region``.

    Parameters
    ----------
    table : `~astropy.table.QTable`
    latitude : `~astropy.units.Quantity`
    region : {"quiet", "sunspot"}

    Returns
    -------
    `~gongsynth.analysis.weak_flux.FluxConservingCurve`
    """
    latitude = u.Quantity(latitude, u.deg)
    match = (np.isclose(table["latitude"].to_value(u.deg), latitude.to_value(u.deg))
             & (np.asarray(table["region"]) == region))
    if not match.any():
        raise KeyError(f"no {region!r} curve at {latitude} in the table")
    row = table[np.nonzero(match)[0][0]]
    n = int(row["n_bins"])
    nodes = u.Quantity(row["nodes"][:n], u.G)
    spacing = np.diff(nodes.to_value(u.G))
    edges = np.concatenate([[nodes[0].value - spacing[0] / 2], nodes.value[:-1] + spacing / 2,
                            [nodes[-1].value + spacing[-1] / 2]]) * u.G
    return FluxConservingCurve(nodes=nodes, values=u.Quantity(row["values"][:n], u.G), edges=edges,
                               counts=np.zeros(n, int))
