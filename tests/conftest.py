"""Shared fixtures."""
import astropy.units as u
import numpy as np
import pytest

from .lines import C_LIGHT, gaussian_line, zeeman_shift


@pytest.fixture
def shifted_planes():
    """Build the six channel integrals of I+V and I-V for a given B and v."""
    from gongsynth.stages.filters import channel_weights

    def build(field, velocity, instrument, wavelength=None, **line):
        lam = wavelength if wavelength is not None else np.linspace(676.6, 676.96, 1801) * u.nm
        weights = channel_weights(lam, instrument).value
        centre = instrument.line_wavelength * (1 + velocity.to_value(u.m / u.s) / C_LIGHT)
        delta = zeeman_shift(field, instrument)
        plus = weights @ gaussian_line(lam, centre + delta, **line)
        minus = weights @ gaussian_line(lam, centre - delta, **line)
        return np.concatenate([plus, minus])

    return build
