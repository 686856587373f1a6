"""Settings for the whole test run: the suite and the doctests in the package."""
import os
import shutil
import tempfile

from astropy.utils import iers

#: The environment variable that pytest-xdist sets in its worker processes.
_XDIST_WORKER = "PYTEST_XDIST_WORKER"


def pytest_configure(config):
    """Keep astropy from downloading Earth-orientation tables during the tests."""
    # The suite runs offline.  Older astropy releases (the oldest-dependencies
    # environment) find their bundled Earth-orientation table out of date and
    # try to download a new one, which fails and warns (an error here).  The
    # bundled table covers every date the tests use.
    iers.conf.auto_download = False
    # Full-disk patch libraries built by the tests go to a fresh folder, not the user's cache.
    # Under pytest-xdist the main process makes it before starting the workers, which inherit
    # it: every worker shares one cache (saves are atomic), so a library is built once per run.
    if os.environ.get(_XDIST_WORKER):
        return
    config.gongsynth_test_cache = tempfile.mkdtemp(prefix="gongsynth-test-cache-")
    os.environ["GONGSYNTH_CACHE_DIR"] = config.gongsynth_test_cache


def pytest_unconfigure(config):
    """Remove the test run's library cache (the process that made it does)."""
    folder = getattr(config, "gongsynth_test_cache", None)
    if folder is not None:
        shutil.rmtree(folder, ignore_errors=True)
