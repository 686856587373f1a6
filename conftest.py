"""Settings for the whole test run: the suite and the doctests in the package."""
from astropy.utils import iers


def pytest_configure(config):
    """Keep astropy from downloading Earth-orientation tables during the tests."""
    # The suite runs offline.  Older astropy releases (the oldest-dependencies
    # environment) find their bundled Earth-orientation table out of date and
    # try to download a new one, which fails and warns (an error here).  The
    # bundled table covers every date the tests use.
    iers.conf.auto_download = False
