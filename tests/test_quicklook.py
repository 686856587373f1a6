"""The quick-look draws a large map from its block means (issue 22: a 4096² HMI map)."""
import warnings

import numpy as np

from gongsynth.products import quicklook


def test_display_is_the_nan_ignoring_block_mean_and_trims_the_extent():
    rng = np.random.default_rng(3)
    ny, nx = 2 * quicklook._DISPLAY_PIXELS + 5, 2 * quicklook._DISPLAY_PIXELS - 7   # f = 3
    data = rng.normal(0, 50, (ny, nx)).astype(np.float32)
    data[rng.random((ny, nx)) < 0.3] = np.nan    # scattered sky
    data[:3, :6] = np.nan                        # two whole blocks of sky
    image, extent = quicklook._display(data, (-10.0, 10.0, -20.0, 20.0))
    f = 3
    my, mx = ny // f, nx // f
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)      # the all-NaN blocks
        expected = np.nanmean(data[:my * f, :mx * f].astype(np.float64).reshape(my, f, mx, f), axis=(1, 3))
    assert image.shape == (my, mx) and image.dtype == np.float32
    np.testing.assert_array_equal(np.isnan(image), np.isnan(expected))
    np.testing.assert_allclose(image[~np.isnan(image)], expected[~np.isnan(expected)], rtol=1e-6, atol=1e-5)
    assert np.allclose(extent, (-10.0, -10.0 + 20.0 * mx * f / nx, -20.0, -20.0 + 40.0 * my * f / ny))
    small = data[:100, :60]
    same, same_extent = quicklook._display(small, (0.0, 1.0, 0.0, 1.0))
    assert same is small and same_extent == (0.0, 1.0, 0.0, 1.0)
