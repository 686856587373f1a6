"""Settings for the whole test run: the suite and the doctests in the package."""
import os
import shutil
import tempfile

from astropy.utils import iers

_CACHE = tempfile.mkdtemp(prefix="gongsynth-test-cache-")


def pytest_configure(config):
    """Keep astropy from downloading Earth-orientation tables during the tests."""
    # The suite runs offline.  Older astropy releases (the oldest-dependencies
    # environment) find their bundled Earth-orientation table out of date and
    # try to download a new one, which fails and warns (an error here).  The
    # bundled table covers every date the tests use.
    iers.conf.auto_download = False
    # Full-disk patch libraries built by the tests go to a fresh folder, not the user's cache.
    os.environ["GONGSYNTH_CACHE_DIR"] = _CACHE


def pytest_unconfigure(config):
    """Remove the test run's library cache."""
    shutil.rmtree(_CACHE, ignore_errors=True)
