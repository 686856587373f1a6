import astropy.units as u
import numpy as np
import pytest

from gongsynth import GONGInstrument
from gongsynth.stages.camera.detector import normalise_flat
from gongsynth.stages.reduction import reduce

GONG = GONGInstrument()


def test_line_at_rest_gives_zero_velocity_and_field(shifted_planes):
    obs = reduce(shifted_planes(0 * u.G, 0 * u.m / u.s, GONG))
    assert abs(obs.doppler) < 0.5 * u.m / u.s
    assert obs.magnetogram == 0 * u.G


def test_field_is_linear_from_minus_to_plus_4_kG(shifted_planes):
    fields = np.linspace(-4000, 4000, 41) * u.G
    measured = u.Quantity([reduce(shifted_planes(b, 0 * u.m / u.s, GONG)).magnetogram for b in fields])
    slope, offset = np.polyfit(fields.value, measured.value, 1)
    # Line physics: the effective phase slope of a real line is ~1 % above v0 (design 3.6).
    assert 0.97 < slope < 1.0
    assert abs(offset) < 0.1
    nonlinearity = np.max(np.abs(measured.value - slope * fields.value)) / 4000
    assert nonlinearity < 5e-3  # the paper quotes ~0.5 %; a shifted Gaussian line is far better
    # No saturation: the response keeps rising to the end of the range.
    assert np.all(np.diff(measured.value) > 0)


def test_doppler_is_linear_with_correct_sign(shifted_planes):
    velocities = np.linspace(-3000, 3000, 25) * u.m / u.s
    measured = u.Quantity([reduce(shifted_planes(0 * u.G, v, GONG)).doppler for v in velocities])
    slope, offset = np.polyfit(velocities.value, measured.value, 1)
    assert 0.97 < slope < 1.0  # redshift measured positive
    assert abs(offset) < 1
    assert np.max(np.abs(measured.value - np.polyval([slope, offset], velocities.value))) < 2


def test_field_and_velocity_separate(shifted_planes):
    obs = reduce(shifted_planes(1500 * u.G, -2000 * u.m / u.s, GONG))
    at_rest = reduce(shifted_planes(1500 * u.G, 0 * u.m / u.s, GONG))
    assert obs.magnetogram.value == pytest.approx(at_rest.magnetogram.value, rel=2e-3)
    assert obs.doppler.value == pytest.approx(-2000 * 0.987, rel=5e-3)


def test_swapping_prefilter_form_changes_field_by_under_0p2_percent(shifted_planes):
    ideal = GONG.replace(prefilter_form="ideal")
    b_memo = reduce(shifted_planes(1000 * u.G, 0 * u.m / u.s, GONG), GONG).magnetogram
    b_ideal = reduce(shifted_planes(1000 * u.G, 0 * u.m / u.s, ideal), ideal).magnetogram
    assert abs(b_ideal / b_memo - 1) < 2e-3


def test_wrap_risk_is_flagged(shifted_planes):
    safe = reduce(shifted_planes(4000 * u.G, 0 * u.m / u.s, GONG))
    risky = reduce(shifted_planes(4600 * u.G, 0 * u.m / u.s, GONG))
    wrapped = reduce(shifted_planes(4900 * u.G, 0 * u.m / u.s, GONG))
    assert not safe.wrapped and risky.wrapped and wrapped.wrapped
    assert wrapped.magnetogram < 0 * u.G  # it has wrapped: that is why it is flagged


def test_dark_and_flat_bookkeeping(shifted_planes):
    rng = np.random.default_rng(0)
    clean = shifted_planes(800 * u.G, 300 * u.m / u.s, GONG)
    planes = np.broadcast_to(clean[:, None, None], (6, 4, 5)) * 1e6
    flat = rng.uniform(0.8, 1.2, (6, 4, 5))
    dark = rng.uniform(10, 20, (4, 5)) * u.electron
    frames = np.array([6000] * 6)
    dark_dn = (dark / GONG.gain).value / 8
    raw = planes * normalise_flat(flat, planes.shape[1:]) + frames[:, None, None] * dark_dn
    obs = reduce(raw, GONG, dark=dark, flat=flat, frames_per_plane=frames)
    ref = reduce(clean)
    assert np.allclose(obs.magnetogram.value, ref.magnetogram.value, atol=1e-6)
    assert np.allclose(obs.doppler.value, ref.doppler.value, atol=1e-6)
    assert np.allclose(obs.continuum.value, planes.sum(axis=0), rtol=1e-12)
    # Without the corrections the answer is wrong.
    assert not np.allclose(reduce(raw).magnetogram.value, ref.magnetogram.value, atol=1)


def test_works_on_any_shape(shifted_planes):
    one = shifted_planes(300 * u.G, 0 * u.m / u.s, GONG)
    cube = np.broadcast_to(one.reshape(6, 1, 1, 1), (6, 2, 3, 4))
    assert reduce(cube).magnetogram.shape == (2, 3, 4)
    assert reduce(one).magnetogram.shape == ()


def test_bad_input():
    with pytest.raises(ValueError, match="leading axis of 6"):
        reduce(np.ones((5, 3, 3)))
    with pytest.raises(ValueError, match="non-finite"):
        reduce(np.full((6, 2), np.nan))
    with pytest.raises(ValueError, match="flat must have shape"):
        reduce(np.ones((6, 2, 2)), flat=np.ones((3, 3)))
    with pytest.raises(ValueError, match="strictly positive"):
        reduce(np.ones((6, 2, 2)), flat=np.zeros((2, 2)))
    with pytest.raises(TypeError, match="dark"):
        reduce(np.ones((6, 2, 2)), dark=np.ones((2, 2)), frames_per_plane=6000)
    with pytest.raises(ValueError, match="frames_per_plane"):
        reduce(np.ones((6, 2, 2)), dark=np.ones((2, 2)) * u.electron)


@pytest.mark.parametrize("name", ["gong", "hmi"])
def test_bands_of_rows_give_the_same_bits(name):
    """The reduction works pixel by pixel: a frame reduced a band of rows at a time (bounded memory),
    whatever the band and the threads reducing bands, has the same bits as reduced whole; so has the
    camera's output for any chunk."""
    import dataclasses

    from gongsynth import instruments
    from gongsynth.stages.camera.integrate import integrate
    inst = instruments.get(name)
    k, shape = len(inst.analysers), (11, 17)
    expected = np.random.default_rng(2).uniform(1e4, 6e4, (k,) + shape) * u.electron
    raws = [integrate(expected, instrument=inst, duration=inst.default_duration, seed=5, chunk_rows=rows,
                      progress=False) for rows in (None, 3)]
    np.testing.assert_array_equal(raws[0].data, raws[1].data)
    whole = reduce(raws[0], inst)
    for pixels, workers in ((17, 1), (17, 3), (3 * 17 + 5, 2)):  # one row a band; 3 rows and a remainder
        banded = reduce(raws[1], inst, band_pixels=pixels, workers=workers)
        for field in dataclasses.fields(whole):
            a, b = getattr(whole, field.name), getattr(banded, field.name)
            assert getattr(a, "unit", None) == getattr(b, "unit", None)
            np.testing.assert_array_equal(getattr(b, "value", b), getattr(a, "value", a))
    with pytest.raises(ValueError, match="band_pixels"):
        reduce(raws[0], inst, band_pixels=0)
