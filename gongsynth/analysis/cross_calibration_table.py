"""
Conversion tables between instruments: the predicted factors behind ``calibrate(smap, to="hmi")``.

A table is an `astropy.table.QTable`, one row per (viewing latitude, source
instrument, target, field-strength group), saved as ECSV with its provenance
in the metadata (gongsynth version, input Sun, seeds, instruments and their
runs, grid, date).  ``factor`` is the OLS-bisector slope of the target's
magnetogram against the source's on a common grid
(`gongsynth.analysis.cross_calibration.cross_calibrate`), averaged over the
seeds: target ≈ factor × source.  The target is another instrument of the
family, or ``"truth"`` (the true B_LOS on the same grid).
`gongsynth.cross_calibration_sweep.cross_calibration_table` builds a table by
simulation; ``scripts/build_cross_calibration_table.py`` builds the one
shipped with gongsynth (`read_cross_calibration_table` without a path).
"""
import importlib.resources

import astropy.units as u
import numpy as np
from astropy.table import QTable

__all__ = ["DEFAULT_CROSS_TABLE", "CROSS_COLUMNS", "tabulate_cross_calibration",
           "read_cross_calibration_table", "conversion_factors"]

#: File name of the table shipped with gongsynth (in ``gongsynth/data``).
DEFAULT_CROSS_TABLE = "cross_calibration_default.ecsv"

#: The columns every conversion table has.
CROSS_COLUMNS = ("latitude", "mu", "instrument", "target", "strength_min", "strength_max", "n_seeds",
                 "n_pixels", "factor", "uncertainty", "fit_uncertainty", "flux_ratio",
                 "flux_ratio_uncertainty", "correlation")


def tabulate_cross_calibration(comparisons, *, metadata=None):
    """
    Average per-seed comparisons into a conversion table.

    Parameters
    ----------
    comparisons : sequence of dict
        One per (latitude, mu, instrument, target) and seed, each with keys
        ``latitude`` (Quantity), ``mu``, ``instrument``, ``target``, ``seed``
        and ``table`` (a `cross_calibrate` table with one angle group).
    metadata : dict, optional
        Provenance for the table's ``meta``.

    Returns
    -------
    `~astropy.table.QTable`
        Columns `CROSS_COLUMNS`: ``factor`` and ``flux_ratio`` are the means
        over the seeds, ``uncertainty`` and ``flux_ratio_uncertainty`` their
        standard errors from the seed-to-seed scatter (NaN with one seed),
        ``fit_uncertainty`` the bisector's own (Isobe et al. 1990) error of
        the mean, ``correlation`` the mean correlation, ``n_pixels`` the cells
        over all seeds.

    Examples
    --------
    >>> import astropy.units as u
    >>> from astropy.table import QTable
    >>> one = QTable({"strength_min": [0] * u.G, "strength_max": [float("inf")] * u.G, "n_pixels": [100],
    ...               "slope": [1.2], "slope_uncertainty": [0.02], "flux_ratio": [1.1], "correlation": [0.9]})
    >>> two = QTable(one, copy=True)
    >>> two["slope"] = [1.4]
    >>> rows = [dict(latitude=0 * u.deg, mu=1.0, instrument="gong", target="hmi", seed=s, table=t)
    ...         for s, t in ((1, one), (2, two))]
    >>> table = tabulate_cross_calibration(rows)
    >>> round(float(table["factor"][0]), 6), round(float(table["uncertainty"][0]), 6)
    (1.3, 0.1)
    """
    groups = {}
    for item in comparisons:
        key = (float(u.Quantity(item["latitude"], u.deg).value), float(item["mu"]), str(item["instrument"]),
               str(item["target"]))
        groups.setdefault(key, []).append(item)
    rows = []
    for (latitude, mu, instrument, target), items in groups.items():
        first = items[0]["table"]
        for k in range(len(first)):
            slopes = np.array([float(it["table"]["slope"][k]) for it in items])
            sigmas = np.array([float(it["table"]["slope_uncertainty"][k]) for it in items])
            ratios = np.array([float(it["table"]["flux_ratio"][k]) for it in items])
            n = slopes.size
            rows.append((latitude, mu, instrument, target, first["strength_min"][k].to_value(u.G),
                         first["strength_max"][k].to_value(u.G), n,
                         int(sum(int(it["table"]["n_pixels"][k]) for it in items)),
                         slopes.mean(), _standard_error(slopes), float(np.sqrt(np.sum(sigmas**2))) / n,
                         ratios.mean(), _standard_error(ratios),
                         float(np.mean([float(it["table"]["correlation"][k]) for it in items]))))
    table = QTable(rows=rows, names=CROSS_COLUMNS)
    for name, unit in (("latitude", u.deg), ("strength_min", u.G), ("strength_max", u.G)):
        table[name] = table[name] * unit
    table.meta.update(metadata or {})
    return table


def _standard_error(values):
    return float(np.std(values, ddof=1) / np.sqrt(values.size)) if values.size > 1 else float("nan")


def read_cross_calibration_table(path=None):
    """
    Read a conversion table; by default the one shipped with gongsynth.

    Parameters
    ----------
    path : str or path-like, optional

    Returns
    -------
    `~astropy.table.QTable`

    Examples
    --------
    >>> table = read_cross_calibration_table()
    >>> table["latitude"].unit, sorted(str(t) for t in set(table["target"]))
    (Unit("deg"), ['gong', 'hmi', 'mdi', 'truth'])
    """
    if path is None:
        resource = importlib.resources.files("gongsynth") / "data" / DEFAULT_CROSS_TABLE
        with importlib.resources.as_file(resource) as file:
            table = QTable.read(file, format="ascii.ecsv")
        table.meta["source"] = f"gongsynth/data/{DEFAULT_CROSS_TABLE}"
        return table
    table = QTable.read(path, format="ascii.ecsv")
    missing = set(CROSS_COLUMNS) - set(table.colnames)
    if missing:
        raise ValueError(f"{path} is not a gongsynth conversion table: columns {sorted(missing)} are missing")
    table.meta["source"] = str(path)
    return table


def conversion_factors(table, instrument, target):
    """
    The factors from one instrument to a target over all field strengths, by viewing latitude.

    Parameters
    ----------
    table : `~astropy.table.QTable`
        A conversion table.
    instrument : str
        The source instrument (``"gong"``, ...).
    target : str
        Another instrument of the table, or ``"truth"``.

    Returns
    -------
    latitude : `~astropy.units.Quantity`
        Increasing, deg.
    factor, uncertainty : `numpy.ndarray`

    Examples
    --------
    >>> latitude, factor, _ = conversion_factors(read_cross_calibration_table(), "gong", "hmi")
    >>> latitude.unit, bool(np.all(factor > 0))
    (Unit("deg"), True)
    """
    sources = sorted({str(name) for name in table["instrument"]})
    targets = sorted({str(name) for name in table["target"]})
    if instrument not in sources:
        raise ValueError(f"the conversion table has no {instrument!r} rows; it converts from {sources}")
    if target not in targets:
        raise ValueError(f"the conversion table has no target {target!r}; its targets are {targets}")
    rows = ((np.asarray(table["instrument"]) == instrument) & (np.asarray(table["target"]) == target)
            & (table["strength_min"].to_value(u.G) == 0) & np.isinf(table["strength_max"].to_value(u.G)))
    if not rows.any():
        raise ValueError(f"the conversion table has no {instrument!r} -> {target!r} rows over all field "
                         "strengths")
    latitude = table["latitude"][rows].to_value(u.deg)
    order = np.argsort(latitude)
    return (latitude[order] * u.deg, np.asarray(table["factor"][rows])[order],
            np.asarray(table["uncertainty"][rows])[order])
