"""
The figures people look at, pinned by image hashes: the quick-look of a run, the
comparison figure and the calibration figure, of one small seeded run.

A change of any pixel (a colour map, a norm, a label, the data) fails the test;
if the change is intended, regenerate the hashes (CONTRIBUTING.md, "Figure tests")
and look at the new images before committing them.
"""
import astropy.units as u
import matplotlib.text
import pytest
from matplotlib.figure import Figure

import gongsynth
from gongsynth.analysis.calibration import calibration_curve
from gongsynth.analysis.compare import compare
from gongsynth.products.quicklook import quicklook_figure

from .conftest import HASH_LIBRARY, STYLE

figure_test = pytest.mark.mpl_image_compare(hash_library=str(HASH_LIBRARY), style=STYLE,
                                            deterministic=True, savefig_kwargs={"dpi": 60})


@pytest.fixture(scope="module")
def run():
    """A seeded 48 × 48 pixel, one-minute run of the Milne–Eddington Sun (~7 s)."""
    return gongsynth.simulate(duration=1 * u.min, detector_shape=48, resolutions=(1,), seed=1,
                              photosphere_shape=(64, 64), photosphere_pixel_size=1536 * u.km,
                              sun="milne-eddington", progress=False)


def _without_version(fig):
    """Replace gongsynth's version in the figure's texts, so that the hash outlives a commit."""
    texts = [t for t in fig.findobj(matplotlib.text.Text) if gongsynth.__version__ in t.get_text()]
    assert texts, "the quick-look's title no longer names the version; remove _without_version"
    for text in texts:
        text.set_text(text.get_text().replace(gongsynth.__version__, "VERSION"))
    return fig


@figure_test
def test_quicklook(run):
    return _without_version(quicklook_figure(run))


@figure_test
def test_compare(run):
    return compare(run.magnetogram, run.truth_psf, labels=("simulated", "truth through the PSF")).figure


@figure_test
def test_calibration(run):
    fig = Figure(figsize=(6, 5))
    calibration_curve(run, n_boot=20).plot(fig.add_subplot())
    return fig
