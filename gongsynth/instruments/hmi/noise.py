r"""
HMI's photon budget and the photon noise of its 45-s and 720-s LOS magnetograms.

Photon budget.  A filtergram of the disk-centre continuum collects

.. math:: N_e = \frac{I_c\,W_k\,\Omega_\mathrm{pix}\,A_\mathrm{eff}\,\eta\,t}{h c / \lambda_0},
          \qquad W_k = \int R_k\,d\lambda \approx 50\ \mathrm{mÅ},

electrons.  Real HMI continuum images read ≈ 60 500 DN/s at disk centre
(`CONTINUUM_COUNT_RATE`), i.e. N_e ≈ 60 500 × t × gain; `effective_area_from_counts`
solves for the effective area A_eff η that gives that number (it absorbs the
telescope, analyser and CCD efficiencies; ``HMIInstrument.effective_area`` is
its rounded value).

Noise.  Each filtergram carries Poisson noise (variance N_e) and read noise;
`magnetogram_noise` propagates both through the MDI-like reduction
(`gongsynth.instruments.hmi.observables.reduce_hmi`), analytically (linearised,
finite differences) or by a seeded Monte Carlo of the 12 filtergrams.  A 45-s
magnetogram is taken here as one set of 12 filtergrams (the pipeline's
temporal interpolation over 135 s is not modelled); a 720-s magnetogram
averages the vector camera's LCP/RCP sets (one set of 12 per 135-s cycle) over
1215 s with a cosine-tapered weight of 720 s FWHM (`sequence_weights`).
"""
import math

import astropy.units as u
import numpy as np

from gongsynth.instruments.hmi.filters import filter_quadrature
from gongsynth.instruments.hmi.observables import reduce_hmi, reference_filtergrams
from gongsynth.instruments.hmi.parameters import N_TUNINGS, resolve_hmi
from gongsynth.instruments.tunable import filtergram_electrons

__all__ = ["CONTINUUM_COUNT_RATE", "CONTINUUM_INTENSITY", "LIU_2012_NOISE", "continuum_electrons",
           "effective_area_from_counts", "sequence_weights", "magnetogram_noise"]

#: Disk-centre continuum of real HMI, 60 500 DN/s: hmi.Ic_45s 2014-03-01 (sunpy's
#: ``resampled_hmi.fits``; ../shared/data/real/PROVENANCE.md).
CONTINUUM_COUNT_RATE = 60500.0 * u.adu / u.s

#: Disk-centre continuum intensity near 617.3 nm, ≈ 3.2e14 erg s⁻¹ cm⁻² sr⁻¹ cm⁻¹
#: (Neckel & Labs 1984, read off their disk-centre continuum; ±5 %).
CONTINUUM_INTENSITY = 3.2e14 * u.Unit("erg / (s cm2 sr cm)")

#: Documented noise of HMI LOS magnetograms (Liu et al. 2012, Sol. Phys. 279, 295):
#: 10.2 G for 45 s, 6.3 G for 720 s (quiet-Sun disk centre, includes solar signal).
LIU_2012_NOISE = {"45s": 10.2 * u.G, "720s": 6.3 * u.G}


def _filter_widths(inst):
    """W_k = ∫ R_k dλ of the six filtergrams, in mÅ."""
    _, weights, responses = filter_quadrature(inst)
    return responses @ weights


def continuum_electrons(instrument=None, intensity=CONTINUUM_INTENSITY):
    """
    Electrons per filtergram I0..I5 for a continuum of the given intensity.

    Parameters
    ----------
    instrument : `~gongsynth.instruments.hmi.HMIInstrument`, optional
    intensity : `~astropy.units.Quantity`
        Specific intensity (default: disk centre at 617.3 nm).

    Returns
    -------
    `~astropy.units.Quantity`
        Shape (6,), in electron.
    """
    inst = resolve_hmi(instrument)
    return filtergram_electrons(inst, intensity, _filter_widths(inst))


def effective_area_from_counts(instrument=None, count_rate=CONTINUUM_COUNT_RATE,
                               intensity=CONTINUUM_INTENSITY):
    """
    The effective area (× QE) that reproduces a measured continuum count rate.

    Parameters
    ----------
    instrument : `~gongsynth.instruments.hmi.HMIInstrument`, optional
    count_rate : `~astropy.units.Quantity`
        Disk-centre continuum in DN/s (mean over the six filtergrams).
    intensity : `~astropy.units.Quantity`
        The continuum intensity that produced it.

    Returns
    -------
    `~astropy.units.Quantity`
        In cm² (A_eff with ``quantum_efficiency`` = 1).

    Examples
    --------
    >>> round(float(effective_area_from_counts().value), 2)
    3.29
    """
    inst = resolve_hmi(instrument)
    target = count_rate * inst.exposure_time * inst.gain
    unit_area = inst.replace(effective_area=1 * u.cm**2, quantum_efficiency=1.0)
    per_cm2 = continuum_electrons(unit_area, intensity).mean()
    return (target / per_cm2).to(u.one).value * u.cm**2


def sequence_weights(product="45s", instrument=None):
    """
    Times and weights of the 12-filtergram sets averaged into one magnetogram.

    Parameters
    ----------
    product : {"45s", "720s"}
        ``"45s"``: one set.  ``"720s"``: the vector camera's sets, one per
        ``vector_cycle`` (135 s), over ``vector_window`` (1215 s), weighted by a
        flat top with cos² tapers whose half-maximum points lie at
        ±``vector_cadence``/2 (the taper shape is chosen; Couvidat et al. 2016
        describe a tapered average of 720 s effective length).
    instrument : `~gongsynth.instruments.hmi.HMIInstrument`, optional

    Returns
    -------
    times : `~astropy.units.Quantity`
        Centre of each set relative to the product's time, in s.
    weights : `numpy.ndarray`
        Normalised to a sum of 1.

    Examples
    --------
    >>> t, w = sequence_weights("720s")
    >>> len(t), round(float(1 / (w**2).sum()), 2)      # 9 sets, 6.4 effective
    (9, 6.44)
    """
    inst = resolve_hmi(instrument)
    if product == "45s":
        return u.Quantity([0.0], u.s), np.ones(1)
    if product != "720s":
        raise ValueError(f"product must be '45s' or '720s', got {product!r}")
    cycle = inst.vector_cycle.to_value(u.s)
    half = inst.vector_window.to_value(u.s) / 2
    n = int(round(2 * half / cycle))
    times = (np.arange(n) - (n - 1) / 2) * cycle
    fwhm_half = inst.vector_cadence.to_value(u.s) / 2
    taper = 2 * (half - fwhm_half)      # taper length: half maximum at its middle
    flat = half - taper
    x = np.clip((np.abs(times) - flat) / taper, 0, 1)
    weights = np.cos(math.pi * x / 2) ** 2
    return u.Quantity(times, u.s), weights / weights.sum()


def magnetogram_noise(product="45s", instrument=None, *, method="analytic", n_trials=4000, seed=0):
    """
    Photon (and read) noise of a disk-centre quiet-Sun LOS magnetogram.

    The scene is the instrument's reference line at rest at the continuum
    level of `continuum_electrons`.  A product averaging sets with weights
    w_i (`sequence_weights`) has σ_B = σ_B,set × sqrt(Σ w_i²).

    Parameters
    ----------
    product : {"45s", "720s"}
    instrument : `~gongsynth.instruments.hmi.HMIInstrument`, optional
    method : {"analytic", "montecarlo"}
        Linearised propagation through `reduce_hmi`, or the standard deviation
        over ``n_trials`` seeded draws of the 12 filtergrams.
    n_trials : int
        Monte Carlo draws.
    seed : int
        Seed of the Monte Carlo generator.

    Returns
    -------
    `~astropy.units.Quantity`
        σ of B_LOS in G.
    """
    inst = resolve_hmi(instrument)
    _, weights = sequence_weights(product, inst)
    line = reference_filtergrams(0.0, inst)[:, 0]  # relative to the continuum
    electrons = continuum_electrons(inst).value * line / _filter_widths(inst)
    mean = np.concatenate([electrons, electrons])            # LCP and RCP alike
    read = (inst.read_noise * inst.gain).to_value(u.electron)
    sigma = np.sqrt(mean + read**2)
    if method == "analytic":
        # Central differences, plane j perturbed by ±1e-3 σ_j in column j.
        step = np.diag(1e-3 * sigma)
        probes = np.concatenate([mean[:, None] + step, mean[:, None] - step], axis=1)
        b = reduce_hmi(probes, inst).magnetogram.value
        slope_times_sigma = (b[:2 * N_TUNINGS] - b[2 * N_TUNINGS:]) / 2e-3
        set_sigma = math.sqrt(np.sum(slope_times_sigma**2))
    elif method == "montecarlo":
        rng = np.random.default_rng(seed)
        draws = mean[:, None] + sigma[:, None] * rng.standard_normal((2 * N_TUNINGS, n_trials))
        set_sigma = float(np.std(reduce_hmi(draws, inst).magnetogram.value, ddof=1))
    else:
        raise ValueError(f"method must be 'analytic' or 'montecarlo', got {method!r}")
    return set_sigma * math.sqrt(float((weights**2).sum())) * u.G
