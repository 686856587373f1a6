"""
Writing TOML with comments (Python's tomllib reads TOML but cannot write it): tomlkit does.

Quantities are written as strings such as ``"3.6 arcsec"`` whose number is the
shortest repr that round-trips exactly; everything else as its TOML type.
"""
import astropy.units as u
import tomlkit

__all__ = ["toml_plain", "toml_value", "toml_table"]


def toml_plain(value):
    """
    A value as a plain TOML-ready Python object (Quantities become strings).

    Parameters
    ----------
    value : str, bool, int, float, tuple, list or `~astropy.units.Quantity`

    Returns
    -------
    str, bool, int, float or list

    Examples
    --------
    >>> import astropy.units as u
    >>> toml_plain(3.6 * u.arcsec), toml_plain((1, 2))
    ('3.6 arcsec', [1, 2])
    """
    if isinstance(value, u.Quantity):
        if value.ndim:  # e.g. a height range: a list of quantities
            return [toml_plain(v) for v in value]
        if value.unit == u.dimensionless_unscaled:
            return float(value.value)
        return f"{float(value.value)!r} {value.unit.to_string()}"
    if isinstance(value, (tuple, list)):
        return [toml_plain(v) for v in value]
    if isinstance(value, (str, bool, int, float)):
        return value
    raise TypeError(f"cannot write {value!r} ({type(value).__name__}) to TOML")


def toml_value(value):
    r"""
    One value as TOML text.

    Parameters
    ----------
    value : str, bool, int, float, tuple, list or `~astropy.units.Quantity`

    Returns
    -------
    str

    Examples
    --------
    >>> import astropy.units as u
    >>> toml_value(3.6 * u.arcsec), toml_value((1, 2)), toml_value('a "b"')
    ('"3.6 arcsec"', '[1, 2]', '"a \\"b\\""')
    """
    return tomlkit.item(toml_plain(value)).as_string()


def toml_table(entries, *, comments=True):
    r"""
    A tomlkit table from ``(key, value, comment)`` entries; ``value=None`` writes a commented example.

    Parameters
    ----------
    entries : iterable of (str, object, str)
        Key, value (or None for "unset") and the comment written above it.
    comments : bool
        Write the comments.

    Returns
    -------
    `tomlkit.items.Table`

    Examples
    --------
    >>> import tomlkit
    >>> doc = tomlkit.document()
    >>> doc.add("run", toml_table([("name", 'a\nb', "a name")]))
    {'run': {'name': 'a\nb'}}
    >>> print(tomlkit.dumps(doc).strip())
    [run]
    # a name
    name = "a\nb"
    """
    table = tomlkit.table()
    for key, value, comment in entries:
        if comments and comment:
            table.add(tomlkit.comment(comment))
        if value is None:
            table.add(tomlkit.comment(f"{key} is unset by default"))
        else:
            table.add(key, toml_plain(value))
    return table
