"""The wavelength window and sampling a Stokes cube needs for the GONG channel integrals (issue 12 #2)."""
import astropy.units as u
import numpy as np
import pytest

from gongsynth.instrument import GONGInstrument
from gongsynth.instruments.gong.reduction import measured_phase, phase_to_velocity
from gongsynth.stages.channels import channel_images
from gongsynth.sun.photosphere.columns import Photosphere
from gongsynth.sun.photosphere.synthesis import default_wavelength, synthesize
from gongsynth.sun.sampling import check_spectral_sampling, spectral_requirement
from gongsynth.sun.stokes import StokesCube

LAM0 = 676.78
PAPER = np.linspace(676.73, 676.83, 51) * u.nm


def _grid(half_pm, step_pm):
    n = int(np.ceil(2 * half_pm / step_pm)) + 1
    return np.linspace(LAM0 - half_pm / 1000, LAM0 + half_pm / 1000, n) * u.nm


def test_requirement_from_the_line_zeeman_and_doppler():
    half, step = spectral_requirement()
    # 2 x 10 pm line width + 12.8 pm (sigma components at 4 kG, g = 1.5) + 6.8 pm (3 km/s).
    assert half.to_value(u.pm) == pytest.approx(39.60, abs=0.01)
    assert step.to_value(u.pm) == pytest.approx(2.0)
    weak, _ = spectral_requirement(max_field=0 * u.G, max_velocity=0 * u.km / u.s)
    assert weak.to_value(u.pm) == pytest.approx(20.0)


def test_the_paper_grid_and_the_built_in_synthesis_pass():
    check_spectral_sampling(PAPER)
    check_spectral_sampling(default_wavelength())
    check_spectral_sampling(_grid(39.61, 2.0))
    # Coarse far wings do not matter, only the window around the line.
    wings = np.concatenate([np.arange(676.50, 676.74, 0.02), np.arange(676.74, 676.82, 0.002),
                            np.arange(676.82, 677.0, 0.02)])
    check_spectral_sampling(wings * u.nm)


@pytest.mark.parametrize(("grid", "words"), [
    (PAPER[24:27], "covers only 676.77800-676.78200 nm"),     # the 3-point window
    (PAPER[::25], "steps of up to 50.00 pm"),                  # the 3 points 50 pm apart
    (_grid(10, 0.5), "covers only"),                           # the issue's +-0.01 nm window
    (_grid(39.5, 2.0), "covers only"),                         # just short of the window
    (_grid(45, 2.5), "steps of up to 2.50 pm"),                # just too coarse
])
def test_grids_short_of_the_requirement_are_refused(grid, words):
    with pytest.raises(ValueError, match="need 676.74040-676.81960 nm") as info:
        check_spectral_sampling(grid)
    assert words in str(info.value)
    assert "sampled every 2.0 pm or finer" in str(info.value)


def test_a_cube_checks_its_own_grid():
    shape = (2, 2, 51)
    ones = np.ones(shape, dtype=np.float32) * u.Unit("erg / (s cm2 sr cm)")
    cube = StokesCube(ones, 0 * ones, 0 * ones, 0 * ones, PAPER, 96 * u.km)
    cube.check_spectral_sampling()
    with pytest.raises(ValueError, match="the cube's wavelength grid covers only"):
        cube[:, :, 24:27].check_spectral_sampling()
    with pytest.raises(ValueError, match="steps of up to 50.00 pm"):
        cube[:, :, ::25].check_spectral_sampling()


def _measure(photosphere, lam, inst):
    cube = synthesize(photosphere, mu=1.0, wavelength=lam, instrument=inst)
    ch = channel_images(cube, instrument=inst).value
    vp = phase_to_velocity(measured_phase(ch[0:3]), inst).value
    vm = phase_to_velocity(measured_phase(ch[3:6]), inst).value
    return inst.gauss_per_velocity.value * (vp - vm) / 2, (vp + vm) / 2


def test_the_threshold_is_where_the_errors_pass_5_gauss_or_5_metres_per_second():
    """Grids just inside the requirement measure B and v within 5 G and 5 m/s of a converged grid."""
    inst = GONGInstrument()
    field = np.array([0, 1000, 2500, 4000.0])
    flow = np.array([-3, 0, 3.0])
    bb, vv = np.meshgrid(field, flow)
    worst = {}
    for inclination in (0, 60):
        ones = np.ones(bb.shape)
        ph = Photosphere(bb * u.G, inclination * ones * u.deg, 0 * ones * u.deg, 0 * ones * u.km / u.s,
                         0 * ones * u.km / u.s, vv * u.km / u.s, ones, 96 * u.km)
        ref_b, ref_v = _measure(ph, _grid(300, 0.25), inst)
        for name, grid in (("paper", PAPER), ("inside", _grid(40, 2.0)), ("short", _grid(33, 2.0)),
                           ("coarse", _grid(50, 2.5))):
            b, v = _measure(ph, grid, inst)
            errors = (np.abs(b - ref_b).max(), np.abs(v - ref_v).max())
            worst[name] = np.maximum(worst.get(name, (0, 0)), errors)
    for name in ("paper", "inside"):
        assert worst[name][0] < 5 and worst[name][1] < 5, (name, worst[name])
    for name in ("short", "coarse"):
        assert worst[name][0] > 5 or worst[name][1] > 5, (name, worst[name])
