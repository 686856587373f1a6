"""
Optional dependencies: import them where they are used, with a clear message when missing.

gongsynth's core runs on numpy, scipy, astropy, sunpy, matplotlib and numba.
A few features need more and name it through an *extra* of the package:

============ ================================ ====================================
extra        provides                         used by
============ ================================ ====================================
``dask``     ``dask[array,distributed]``      `gongsynth.simulate_many` on a cluster
``h5py``     ``h5py``                         ``StokesCube.from_rh15d`` (RH 1.5D)
``rt``       ``lightweaver``                  radiative transfer check of the line
``pfss``     ``sunkit-magex``                 `gongsynth.open_flux` (PFSS)
============ ================================ ====================================

``pip install 'gongsynth[all]'`` installs the ``dask``, ``h5py`` and ``pfss`` extras.
"""
import importlib

__all__ = ["import_optional"]


def import_optional(module, extra):
    """
    Import an optional dependency, or explain how to install it.

    Parameters
    ----------
    module : str
        Dotted name of the module to import (``"h5py"``, ``"dask.distributed"``).
    extra : str
        The gongsynth extra that installs it (``"h5py"``, ``"dask"``).

    Returns
    -------
    module
        The imported module.

    Raises
    ------
    ImportError
        If the module cannot be imported; the message names the extra to install.

    Examples
    --------
    >>> from gongsynth.optional import import_optional
    >>> import_optional("json", "none").__name__
    'json'
    >>> import_optional("not_a_module_gongsynth_needs", "rt")
    Traceback (most recent call last):
    ...
    ImportError: this feature of gongsynth needs the optional dependency ...: pip install 'gongsynth[rt]'
    """
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        top = module.split(".")[0]
        raise ImportError(
            f"this feature of gongsynth needs the optional dependency {top}: "
            f"pip install 'gongsynth[{extra}]'"
        ) from exc
