"""
The package version, from setuptools_scm.

``_version.py`` is written by setuptools_scm when the package is built or
installed; a source checkout that was never installed falls back to the
installed distribution's metadata, then to ``0.0.0.dev0``.  An editable
install's version does not follow later commits, so tables and scripts also
record `git_commit`.
"""
import subprocess
from pathlib import Path

try:
    from gongsynth._version import version
except ImportError:  # pragma: no cover - a checkout that was never built
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as _distribution_version

    try:
        version = _distribution_version("gongsynth")
    except PackageNotFoundError:
        version = "0.0.0.dev0"

__all__ = ["version", "git_commit"]


def git_commit():
    """
    The commit of the gongsynth checkout (``git describe --always --dirty``), or "" outside one.

    Returns
    -------
    str
        The description of the checkout that holds this module; empty for an
        installed (non-editable) package, or where git is missing or slow.
    """
    try:
        done = subprocess.run(["git", "describe", "--always", "--dirty"], cwd=Path(__file__).resolve().parent,
                              capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.SubprocessError):
        return ""
    return done.stdout.strip() if done.returncode == 0 else ""
