"""
Input checks shared by every stage, with error messages that name the argument.
"""
import astropy.units as u
import numpy as np

__all__ = ["check_quantity", "check_scalar", "check_wavelength_grid", "check_finite"]


def check_quantity(value, unit, name, *, equivalencies=None):
    """
    Check that ``value`` is a Quantity convertible to ``unit``.

    Parameters
    ----------
    value : object
        What the user passed.
    unit : `~astropy.units.UnitBase`
        A unit of the expected physical type.
    name : str
        The argument's name, used in the message.
    equivalencies : list, optional
        Astropy equivalencies allowed in the conversion.

    Returns
    -------
    `~astropy.units.Quantity`
        ``value`` itself.

    Raises
    ------
    TypeError
        If ``value`` is not a Quantity.
    astropy.units.UnitsError
        If its unit cannot be converted to ``unit``.

    Examples
    --------
    >>> import astropy.units as u
    >>> check_quantity(3 * u.arcsec, u.deg, "seeing")
    <Quantity 3. arcsec>
    >>> check_quantity(3.0, u.deg, "seeing")
    Traceback (most recent call last):
    ...
    TypeError: seeing must be an astropy Quantity with units of angle (e.g. deg), got float
    """
    if not isinstance(value, u.Quantity):
        raise TypeError(
            f"{name} must be an astropy Quantity with units of {u.Unit(unit).physical_type} "
            f"(e.g. {u.Unit(unit)}), got {type(value).__name__}"
        )
    if not value.unit.is_equivalent(unit, equivalencies=equivalencies or []):
        raise u.UnitsError(
            f"{name} must have units convertible to {u.Unit(unit)}, got {value.unit}"
        )
    return value


def check_scalar(value, unit, name, positive=True):
    """
    A finite scalar Quantity, positive (or non-negative), as a float in ``unit``.

    Parameters
    ----------
    value : `~astropy.units.Quantity`
    unit : `~astropy.units.Unit`
    name : str
        The argument's name, for the message.
    positive : bool
        Require > 0 (default); False: >= 0.

    Returns
    -------
    float

    Examples
    --------
    >>> import astropy.units as u
    >>> check_scalar(1.5 * u.Mm, u.km, "granule_size")
    1500.0
    """
    check_quantity(value, unit, name)
    bad_sign = value.value <= 0 if positive else value.value < 0
    if np.ndim(value) != 0 or not np.isfinite(value.value) or bad_sign:
        kind = "positive" if positive else "non-negative"
        raise ValueError(f"{name} must be a {kind} finite scalar, got {value}")
    return float(value.to_value(unit))


def check_finite(array, name):
    """
    Raise ValueError naming ``name`` if ``array`` holds NaN or infinity.

    Parameters
    ----------
    array : array_like or `~astropy.units.Quantity`
    name : str
        Argument name for the message.

    Returns
    -------
    object
        ``array`` itself.

    Examples
    --------
    >>> check_finite([1.0, float("nan")], "flat")
    Traceback (most recent call last):
    ...
    ValueError: flat contains 1 non-finite value(s) (NaN or inf)
    """
    values = getattr(array, "value", array)
    bad = ~np.isfinite(values)
    if np.any(bad):
        raise ValueError(f"{name} contains {int(bad.sum())} non-finite value(s) (NaN or inf)")
    return array


def check_wavelength_grid(wavelength, line_wavelength, name="wavelength"):
    """
    Check a spectral axis: 1-D length Quantity, finite, strictly increasing, covering the line.

    Parameters
    ----------
    wavelength : `~astropy.units.Quantity`
        The grid to check.
    line_wavelength : `~astropy.units.Quantity`
        Rest wavelength of the line that the grid must contain.
    name : str
        Argument name for messages.

    Returns
    -------
    `~astropy.units.Quantity`
        The grid, unchanged.

    Examples
    --------
    >>> import astropy.units as u
    >>> check_wavelength_grid([676.9, 677.0] * u.nm, 676.78 * u.nm)
    Traceback (most recent call last):
    ...
    ValueError: wavelength (676.9000-677.0000 nm) does not cover the line at 676.7800 nm
    """
    check_quantity(wavelength, u.nm, name)
    lam = np.atleast_1d(wavelength.to_value(u.nm))
    if lam.ndim != 1 or lam.size < 2:
        raise ValueError(f"{name} must be one-dimensional with at least 2 points, got shape {lam.shape}")
    check_finite(lam, name)
    if np.any(np.diff(lam) <= 0):
        raise ValueError(f"{name} must be strictly increasing")
    lam0 = line_wavelength.to_value(u.nm)
    if not lam[0] < lam0 < lam[-1]:
        raise ValueError(
            f"{name} ({lam[0]:.4f}-{lam[-1]:.4f} nm) does not cover the line at {lam0:.4f} nm"
        )
    return wavelength
