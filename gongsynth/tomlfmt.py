"""
Formatting of scalar values as TOML (Python's tomllib reads TOML but cannot write it).
"""
import astropy.units as u

__all__ = ["toml_value"]


def toml_value(value):
    """
    Format one value as TOML.

    Quantities become strings such as ``"3.6 arcsec"`` whose number is the
    shortest repr that round-trips exactly.

    Parameters
    ----------
    value : str, bool, int, float, tuple or `~astropy.units.Quantity`

    Returns
    -------
    str

    Examples
    --------
    >>> import astropy.units as u
    >>> toml_value(3.6 * u.arcsec), toml_value((1, 2)), toml_value('a "b"')
    ('"3.6 arcsec"', '[1, 2]', '"a \\\\"b\\\\""')
    """
    if isinstance(value, u.Quantity):
        return toml_value(f"{float(value.value)!r} {value.unit.to_string()}")
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (tuple, list)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, (int, float)):
        return repr(value)
    raise TypeError(f"cannot write {value!r} ({type(value).__name__}) to TOML")
