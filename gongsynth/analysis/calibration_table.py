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
"""
import importlib.resources

import astropy.units as u
import numpy as np
from astropy.table import QTable

from gongsynth.analysis.weak_flux import PAPER_BINS, FluxConservingCurve
from gongsynth.files import atomic_path

__all__ = ["DEFAULT_TABLE", "TABLE_LATITUDES", "calibration_table", "read_calibration_table",
           "write_calibration_table", "table_curve"]

#: The viewing angles of the papers' tables.
TABLE_LATITUDES = u.Quantity(sorted(PAPER_BINS), u.deg)

#: File name of the table shipped with gongsynth (in ``gongsynth/data``).
DEFAULT_TABLE = "calibration_default.ecsv"

_MAX_NODES = max(max(bins) for bins in PAPER_BINS.values())


def _padded(values, size):
    out = np.full(size, np.nan)
    out[:values.size] = values
    return out


def calibration_table(fits, *, mu, metadata=None):
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

    Returns
    -------
    `~astropy.table.QTable`
        Columns ``latitude`` (deg), ``mu``, ``region``, ``factor``,
        ``uncertainty``, ``n_pixels``, ``n_bins``, ``nodes`` and ``values``
        (the curve, G, NaN-padded to a common length).

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
    table["n_pixels"] = [f.n_pixels for f in fits]
    table["n_bins"] = [f.curve.nodes.size for f in fits]
    table["nodes"] = u.Quantity([_padded(f.curve.nodes.to_value(u.G), _MAX_NODES) for f in fits], u.G)
    table["values"] = u.Quantity([_padded(f.curve.values.to_value(u.G), _MAX_NODES) for f in fits], u.G)
    table.meta.update(metadata or {})
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


def read_calibration_table(path=None):
    """
    Read a calibration table; by default the one shipped with gongsynth.

    Parameters
    ----------
    path : str or path-like, optional

    Returns
    -------
    `~astropy.table.QTable`

    Examples
    --------
    >>> table = read_calibration_table()
    >>> sorted(str(r) for r in set(table["region"]))
    ['quiet', 'sunspot']
    """
    if path is None:
        resource = importlib.resources.files("gongsynth") / "data" / DEFAULT_TABLE
        with importlib.resources.as_file(resource) as file:
            table = QTable.read(file, format="ascii.ecsv")
        table.meta["source"] = f"gongsynth/data/{DEFAULT_TABLE}"
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
