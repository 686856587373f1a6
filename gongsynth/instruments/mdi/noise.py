r"""
MDI's photon budget and the photon noise of its 1-minute and 5-minute (96-minute product) magnetograms.

Photon budget.  SOI-TN-132 (Hoeksema 1996) gives a typical full-disk
filtergram of 3000 DN for F0, F1 and F4 (2500 DN for F2, F3) with a shot
noise of 5.48 DN: :math:`N_e = (3000 / 5.48)^2 = 3.0\times10^5` electrons per
continuum filtergram, i.e. 100 e⁻ per DN.  A
filtergram of the disk-centre continuum collects

.. math:: N_e = \frac{I_c\,W_k\,\Omega_\mathrm{pix}\,A_\mathrm{eff}\,\eta\,t}{h c / \lambda_0},
          \qquad W_k = \int R_k\,d\lambda,

and `effective_area_from_counts` solves for the effective area that gives
the TN's number (it absorbs the telescope, filter and CCD efficiencies;
``MDIInstrument.effective_area`` is its rounded value).

Noise.  Each filtergram carries Poisson noise (variance N_e) and read noise.
A one-minute magnetogram accumulates two frames of each of the ten planes
(`~gongsynth.instruments.mdi.MDIInstrument.schedule`);
`magnetogram_noise` propagates the noise through the onboard algorithm
(`gongsynth.instruments.mdi.observables.reduce_mdi`) analytically
(linearised, finite differences) or by a seeded Monte Carlo.  The 96-minute
synoptic product is the average of five one-minute magnetograms (MDI
Lev1.8 page: "one-minute and lower-noise 5-minute averaged magnetograms");
the Monte Carlo averages five independent reductions, exactly that.
"""
import math

import astropy.units as u
import numpy as np

from gongsynth.instruments.mdi.filters import filter_quadrature
from gongsynth.instruments.mdi.observables import reduce_mdi, reference_filtergrams
from gongsynth.instruments.mdi.parameters import N_MDI_PLANES, resolve_mdi
from gongsynth.instruments.tunable import filtergram_electrons

__all__ = ["FILTERGRAM_COUNTS", "FILTERGRAM_SHOT_NOISE", "CONTINUUM_INTENSITY", "DOCUMENTED_NOISE",
           "continuum_electrons", "effective_area_from_counts", "magnetogram_noise"]

#: A typical continuum filtergram (F0, F1, F4) and its shot noise (SOI-TN-132, Hoeksema 1996).
FILTERGRAM_COUNTS = 3000.0 * u.adu
FILTERGRAM_SHOT_NOISE = 5.48 * u.adu

#: Disk-centre continuum near 676.8 nm, 3.0e14 erg s⁻¹ cm⁻² sr⁻¹ cm⁻¹ (Neckel & Labs 1984;
#: the built-in Sun's, `gongsynth.sun.photosphere.NiLine`).
CONTINUUM_INTENSITY = 3.0e14 * u.Unit("erg / (s cm2 sr cm)")

#: Documented noise of MDI full-disk magnetograms: 20 G for one minute (Scherrer et al.
#: 1995, as quoted by the MDI team, soi.stanford.edu/~yliu/offset); about 9 G for the
#: 5-minute average of the 96-minute product (the level-1.8 file in shared/data/real:
#: robust sigma 9.7 G in the quietest 60-arcsec box near disk centre, solar signal included).
DOCUMENTED_NOISE = {1: 20.0 * u.G, 5: 9.0 * u.G}


def _filter_widths(inst):
    """W_k = ∫ R_k dλ of F0..F4, in mÅ."""
    _, weights, responses = filter_quadrature(inst)
    return responses @ weights


def continuum_electrons(instrument=None, intensity=CONTINUUM_INTENSITY):
    """
    Electrons per filtergram F0..F4 (one frame) for a continuum of the given intensity.

    Parameters
    ----------
    instrument : `~gongsynth.instruments.mdi.MDIInstrument`, optional
    intensity : `~astropy.units.Quantity`
        Specific intensity (default: disk centre near 676.8 nm).

    Returns
    -------
    `~astropy.units.Quantity`
        Shape (5,), in electron.
    """
    inst = resolve_mdi(instrument)
    return filtergram_electrons(inst, intensity, _filter_widths(inst))


def effective_area_from_counts(instrument=None, counts=FILTERGRAM_COUNTS, shot_noise=FILTERGRAM_SHOT_NOISE,
                               intensity=CONTINUUM_INTENSITY):
    """
    The effective area (× QE) that gives a continuum filtergram SOI-TN-132's photo-electrons.

    Parameters
    ----------
    instrument : `~gongsynth.instruments.mdi.MDIInstrument`, optional
        Supplies the exposure time, pixel and filters.
    counts, shot_noise : `~astropy.units.Quantity`
        A continuum filtergram's counts and their shot noise: N_e = (counts / shot_noise)².
    intensity : `~astropy.units.Quantity`
        The continuum intensity that produced it.

    Returns
    -------
    `~astropy.units.Quantity`
        In cm² (A_eff with ``quantum_efficiency`` = 1).

    Examples
    --------
    >>> round(float(effective_area_from_counts().value), 4)
    0.0607
    """
    inst = resolve_mdi(instrument)
    target = (counts / shot_noise).to_value(u.one) ** 2
    unit_area = inst.replace(effective_area=1 * u.cm**2, quantum_efficiency=1.0)
    return target / continuum_electrons(unit_area, intensity)[0].value * u.cm**2


def magnetogram_noise(minutes=1, instrument=None, *, method="analytic", n_trials=4000, seed=0):
    """
    Photon (and read) noise of a disk-centre quiet-Sun MDI magnetogram.

    The scene is the instrument's reference line at rest at the continuum
    level of `continuum_electrons`; each plane holds the frames of one
    minute (`~gongsynth.instruments.mdi.MDIInstrument.schedule`).  The
    result is at the instrument's ``level`` (× 1.7 at level 1.8).

    Parameters
    ----------
    minutes : int
        One-minute magnetograms averaged: 1, or 5 for the 96-minute product.
    instrument : `~gongsynth.instruments.mdi.MDIInstrument`, optional
    method : {"analytic", "montecarlo"}
        Linearised propagation through `reduce_mdi` (σ of one minute / √minutes),
        or the standard deviation over ``n_trials`` seeded averages of
        ``minutes`` independent one-minute reductions.
    n_trials : int
        Monte Carlo draws.
    seed : int
        Seed of the Monte Carlo generator.

    Returns
    -------
    `~astropy.units.Quantity`
        σ of B_LOS in G.
    """
    inst = resolve_mdi(instrument)
    if isinstance(minutes, bool) or not isinstance(minutes, (int, np.integer)) or minutes < 1:
        raise ValueError(f"minutes must be a positive int, got {minutes!r}")
    frames = inst.schedule(inst.magnetogram_cadence).frames_per_plane
    line = reference_filtergrams(0.0, inst)[:, 0] / _filter_widths(inst)   # relative to the continuum
    mean = np.concatenate([line, line]) * np.tile(continuum_electrons(inst).value, 2) * frames
    read = (inst.read_noise * inst.gain).to_value(u.electron)
    sigma = np.sqrt(mean + frames * read**2)
    if method == "analytic":
        # Central differences, plane j perturbed by ±1e-3 σ_j in column j.
        step = np.diag(1e-3 * sigma)
        probes = np.concatenate([mean[:, None] + step, mean[:, None] - step], axis=1)
        b = reduce_mdi(probes, inst).magnetogram.value
        one = math.sqrt(np.sum(((b[:N_MDI_PLANES] - b[N_MDI_PLANES:]) / 2e-3) ** 2))
        return one / math.sqrt(minutes) * u.G
    if method == "montecarlo":
        rng = np.random.default_rng(seed)
        shape = (N_MDI_PLANES, minutes, n_trials)
        draws = mean[:, None, None] + sigma[:, None, None] * rng.standard_normal(shape)
        b = reduce_mdi(draws, inst).magnetogram.value.mean(axis=0)
        return float(np.std(b, ddof=1)) * u.G
    raise ValueError(f"method must be 'analytic' or 'montecarlo', got {method!r}")
