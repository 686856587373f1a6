"""
The package version, from setuptools_scm.

``_version.py`` is written by setuptools_scm when the package is built or
installed; a source checkout that was never installed falls back to the
installed distribution's metadata, then to ``0.0.0.dev0``.
"""
try:
    from gongsynth._version import version
except ImportError:  # pragma: no cover - a checkout that was never built
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as _distribution_version

    try:
        version = _distribution_version("gongsynth")
    except PackageNotFoundError:
        version = "0.0.0.dev0"

__all__ = ["version"]
