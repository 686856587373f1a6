"""
Figure tests: the product figures against a library of image hashes (pytest-mpl).

They run only when images are compared or hashes generated (``--mpl``,
``--mpl-generate-hash-library``), which the tox ``figure`` environment does, and
only with the matplotlib and FreeType versions the hashes were made with (the
same figure rasterises to other bytes with another version of either).  Without
``--mpl`` they are skipped, so the default test run does not pay for them.  How
to run them and regenerate the hashes: CONTRIBUTING.md, "Figure tests".
"""
from pathlib import Path

import matplotlib
import matplotlib.ft2font
import pytest

__all__ = ["MPL_VERSION", "FREETYPE_VERSION", "HASH_LIBRARY", "STYLE"]

#: The versions the hashes were made with (pinned in tox.ini's figure environment).
MPL_VERSION = "3.11.2"
FREETYPE_VERSION = "2.14.3"

#: One file per version pair, as sunpy names its figure hash libraries.
HASH_LIBRARY = Path(__file__).with_name(
    f"figure_hashes_mpl_{MPL_VERSION.replace('.', '')}_ft_{FREETYPE_VERSION.replace('.', '')}.json")

#: rcParams of every figure test: matplotlib's defaults with its own test-suite font settings
#: (DejaVu Sans, shipped with matplotlib, so no system font enters; FreeType's default hinting).
STYLE = {"font.family": "DejaVu Sans", "text.hinting": "default"}


def pytest_runtest_setup(item):
    """Skip figure tests unless images are compared or hashes generated, with the pinned versions."""
    if item.get_closest_marker("mpl_image_compare") is None:
        return
    generating = item.config.getoption("--mpl-generate-hash-library", None)
    if not (item.config.getoption("--mpl", False) or generating):
        pytest.skip("figure tests compare images only with --mpl: run `tox -e figure` "
                    "(CONTRIBUTING.md, 'Figure tests')")
    versions = (matplotlib.__version__, matplotlib.ft2font.__freetype_version__)
    if versions != (MPL_VERSION, FREETYPE_VERSION) and not generating:
        pytest.skip(f"{HASH_LIBRARY.name} holds the hashes of matplotlib {MPL_VERSION} with FreeType "
                    f"{FREETYPE_VERSION}; this is matplotlib {versions[0]} with FreeType {versions[1]} "
                    f"(run `tox -e figure`, which pins them)")
