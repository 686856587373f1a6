import math

import astropy.units as u
import numpy as np
import pytest

from gongsynth import GONGInstrument
from gongsynth.stages import filters

from .lines import gaussian_line

LAM = np.linspace(676.5, 677.06, 8001) * u.nm


def _sector_average_numerically(lam, sector, n=600):
    """Average R_GONG over a 30 degree sector by brute force (midpoint rule)."""
    angles = (sector + (np.arange(n) + 0.5) / n) * 30 * u.deg
    return filters.waveplate_transmission(lam[None, :], angles[:, None]).value.mean(axis=0)


def test_closed_form_sector_average():
    resp = filters.channel_responses(LAM).value
    for i in range(3):
        assert np.allclose(resp[i], _sector_average_numerically(LAM, i), rtol=0, atol=2e-6)


def test_response_repeats_every_90_degrees():
    angles = np.linspace(0, 90, 37) * u.deg
    t0 = filters.waveplate_transmission(LAM[None, :], angles[:, None]).value
    t90 = filters.waveplate_transmission(LAM[None, :], angles[:, None] + 90 * u.deg).value
    assert np.allclose(t0, t90, atol=1e-12)
    # ... and sectors 3, 4, 5 (the next 90 degrees) equal sectors 0, 1, 2.
    for i in range(3):
        assert np.allclose(_sector_average_numerically(LAM, i + 3, n=200),
                           _sector_average_numerically(LAM, i, n=200), atol=1e-12)
    # Not every 45 degrees: the half-wave plate doubles the angle once, not twice.
    t45 = filters.waveplate_transmission(LAM[None, :], angles[:, None] + 45 * u.deg).value
    assert not np.allclose(t0, t45, atol=1e-3)


def test_sectors_are_120_degrees_apart_in_modulation_phase():
    gong = GONGInstrument()
    envelope = (filters.prefilter_transmission(LAM) * filters.lyot_transmission(LAM)).value
    psi = filters.michelson_phase(LAM).value
    keep = envelope > 0.05
    phases = []
    for i in range(3):
        modulated = 2 * _sector_average_numerically(LAM, i) / envelope - 1
        # Least-squares fit of a cos(psi) + b sin(psi) = A cos(psi + phase).
        design = np.stack([np.cos(psi[keep]), np.sin(psi[keep])], axis=1)
        (a, b), *_ = np.linalg.lstsq(design, modulated[keep], rcond=None)
        phases.append(np.arctan2(-b, a))
        # Modulation contrast of a 30 degree sector is sinc(pi/3).
        amplitude = math.hypot(a, b)
        assert amplitude == pytest.approx(math.sin(math.pi / 3) / (math.pi / 3), rel=2e-3)
    steps = np.degrees(np.angle(np.exp(1j * np.diff(phases))))
    assert np.allclose(steps, -120, atol=0.1)
    assert filters.modulation_amplitude(gong) == pytest.approx(0.8270, abs=1e-4)


def test_lyot_tuning():
    lam = np.linspace(676.7, 676.86, 16001) * u.nm
    t = filters.lyot_transmission(lam).value
    peak = lam[np.argmax(t)]
    assert t.max() > 0.99
    assert abs(peak - 676.78 * u.nm) < 5 * u.pm
    # The paper's literal +45.3 deg puts a null on the line (design 3.3).
    literal = GONGInstrument(lyot_angle_2=45.3 * u.deg)
    assert filters.lyot_transmission(676.78 * u.nm, literal).value < 1e-3


def test_prefilter_forms():
    memo = GONGInstrument()
    ideal = GONGInstrument(prefilter_form="ideal")
    for inst in (memo, ideal):
        half = filters.prefilter_transmission(inst.prefilter_center + 0.25 * u.nm, inst).value
        assert half == pytest.approx(0.5, abs=0.01)  # both have FWHM = w_p
        assert filters.prefilter_transmission(inst.prefilter_center, inst).value == 1


def test_channel_weights_integrate_piecewise_linear_spectra_exactly():
    gong = GONGInstrument()
    # A non-uniform grid over the line.
    rng = np.random.default_rng(3)
    lam = np.sort(rng.uniform(676.73, 676.83, 60)) * u.nm
    lam = np.concatenate([[676.72], lam.value, [676.84]]) * u.nm
    weights = filters.channel_weights(lam, gong).value
    spectrum = 1 + 0.3 * np.sin((lam.value - 676.7) * 300)
    # The reference: dense quadrature of the interpolant, padded with the edge values.
    half = gong.integration_half_width.to_value(u.nm)
    fine = np.linspace(676.78 - half, 676.78 + half, 600001)
    interp = np.interp(fine, lam.value, spectrum)
    reference = np.trapezoid(filters.channel_responses(fine * u.nm).value * interp, fine, axis=1)
    assert np.allclose(weights @ spectrum, reference, rtol=1e-6)


def test_continuum_padding_equals_wide_window():
    """A 51-point RH window padded with its continuum equals a wide window of the same spectrum."""
    gong = GONGInstrument()
    narrow = np.linspace(676.73, 676.83, 1001) * u.nm  # fine: test the padding, not sampling
    wide = np.linspace(676.78 - 3, 676.78 + 3, 300001) * u.nm
    line = dict(fwhm=6 * u.pm, depth=0.6)  # negligible absorption at the window edges
    got = filters.channel_weights(narrow, gong).value @ gaussian_line(narrow, gong.line_wavelength, **line)
    want = filters.channel_weights(wide, gong).value @ gaussian_line(wide, gong.line_wavelength, **line)
    assert np.allclose(got, want, rtol=1e-4)


def test_narrow_integration_range_would_bias_the_field():
    """Design 3.8: integrating over +-0.05 nm instead of +-3 nm gives B about 30 % low."""
    from gongsynth.stages.reduction import reduce

    from .lines import zeeman_shift
    field = 1000 * u.G
    results = []
    for half in (3 * u.nm, 0.05 * u.nm):
        gong = GONGInstrument(integration_half_width=half)
        lam = np.linspace(676.78 - half.to_value(u.nm), 676.78 + half.to_value(u.nm), 4001) * u.nm
        w = filters.channel_weights(lam, gong).value
        delta = zeeman_shift(field, gong)
        planes = np.concatenate([w @ gaussian_line(lam, gong.line_wavelength + delta),
                                 w @ gaussian_line(lam, gong.line_wavelength - delta)])
        results.append(reduce(planes, gong).magnetogram.to_value(u.G))
    assert results[0] == pytest.approx(1000, rel=0.03)
    assert results[1] < 0.85 * results[0]


@pytest.mark.parametrize("bad, error, match", [
    (np.linspace(676.80, 676.90, 51) * u.nm, ValueError, "does not cover the line"),
    (np.linspace(676.83, 676.73, 51) * u.nm, ValueError, "strictly increasing"),
    (np.linspace(676.73, 676.83, 51), TypeError, "wavelength"),
    (np.linspace(676.73, 676.83, 51) * u.s, u.UnitsError, "wavelength"),
    (np.array([676.7, np.nan, 676.9]) * u.nm, ValueError, "non-finite"),
])
def test_channel_weights_bad_input(bad, error, match):
    with pytest.raises(error, match=match):
        filters.channel_weights(bad)


def test_instrument_argument_is_checked():
    with pytest.raises(TypeError, match="instrument must be a name"):
        filters.channel_responses(LAM, instrument={"gain": 33})
