"""
Centre-to-limb curves of intensity maps, and the comparison of two of them.

`limb_darkening` bins an intensity map (continuum, pseudo-continuum) in
μ = cos θ, normalised to its disk-centre level, and fits the quadratic law
I(μ)/I(1) = 1 - a(1 - μ) - b(1 - μ)²; `compare_limb_darkening` puts a
simulated and an observed curve side by side (the count levels of the two
maps), after degrading the finer of them to GONG.
"""
from dataclasses import dataclass

import astropy.units as u
import numpy as np
from astropy.table import QTable

from gongsynth import instruments
from gongsynth.analysis.degrade import degrade_if_finer
from gongsynth.analysis.disk import check_map, disk_coordinates, map_values
from gongsynth.analysis.noise import disk_centre_level
from gongsynth.analysis.statistics import check_fraction

__all__ = ["LimbDarkeningProfile", "limb_darkening", "LimbDarkeningComparison", "compare_limb_darkening"]


@dataclass(frozen=True)
class LimbDarkeningProfile:
    """
    Centre-to-limb profile of an intensity map, normalised to disk centre.

    Attributes
    ----------
    mu : `numpy.ndarray`
        Mean μ = cos θ of the pixels in each bin (decreasing from disk centre).
    rho : `numpy.ndarray`
        Matching distance from disk centre, solar radii.
    intensity : `numpy.ndarray`
        Mean intensity in each μ bin divided by ``centre_level``.
    scatter : `numpy.ndarray`
        Standard deviation in each bin divided by ``centre_level``.
    counts : `numpy.ndarray`
        Pixels per bin.
    centre_level : `~astropy.units.Quantity`
        Disk-centre level (see `disk_centre_level`), map unit.
    coefficients : tuple
        (a, b) of the quadratic law I(μ)/I(1) = 1 - a(1 - μ) - b(1 - μ)²,
        least-squares fit to the profile (weights = pixel counts).
    """

    mu: np.ndarray
    rho: np.ndarray
    intensity: np.ndarray
    scatter: np.ndarray
    counts: np.ndarray
    centre_level: u.Quantity
    coefficients: tuple

    def law(self, mu):
        """
        The fitted quadratic law 1 - a(1-μ) - b(1-μ)² at ``mu``.

        Parameters
        ----------
        mu : array_like
            cos θ, dimensionless.

        Returns
        -------
        `numpy.ndarray`
            I(μ) / I(disk centre), dimensionless.
        """
        a, b = self.coefficients
        x = 1 - np.asarray(mu, dtype=float)
        return 1 - a * x - b * x**2

    def to_table(self):
        """
        The profile as a table, one row per μ bin (disk centre first).

        Returns
        -------
        `~astropy.table.QTable`
            Columns ``mu``, ``rho`` (solar radii, dimensionless),
            ``intensity``, ``scatter`` (relative to the disk-centre level,
            dimensionless), ``law`` (the fitted law at ``mu``) and ``counts``;
            ``meta`` holds ``centre_level`` (map unit) and the law's
            coefficients ``a`` and ``b``.
        """
        columns = {"mu": self.mu * u.one, "rho": self.rho * u.one, "intensity": self.intensity * u.one,
                   "scatter": self.scatter * u.one, "law": self.law(self.mu) * u.one,
                   "counts": self.counts}
        a, b = self.coefficients
        return QTable(columns, meta={"centre_level": self.centre_level, "a": a, "b": b})


def limb_darkening(smap, *, bins=20, max_radius=0.98, box=60 * u.arcsec):
    """
    Limb-darkening curve of an intensity map (continuum, pseudo-continuum).

    Parameters
    ----------
    smap : `~sunpy.map.GenericMap`
        Intensity map (any unit: DN, counts, arbitrary).
    bins : int
        Number of equal-width bins in μ between μ(max_radius) and 1.
    max_radius : float
        Outermost distance used, solar radii.
    box : `~astropy.units.Quantity`
        Side of the disk-centre box that defines the normalisation.

    Returns
    -------
    `LimbDarkeningProfile`

    Examples
    --------
    >>> import astropy.units as u
    >>> import numpy as np
    >>> import sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> m = sunpy.map.Map(np.ones((200, 200)), sunpy.map.make_fitswcs_header(
    ...     (200, 200), ref, scale=[12, 12] * u.arcsec / u.pix))
    >>> rho, mu = disk_coordinates(m)
    >>> m = sunpy.map.Map(np.nan_to_num(1 - 0.6 * (1 - mu)), m.meta)   # linear law, a = 0.6
    >>> profile = limb_darkening(m)
    >>> [round(float(c), 2) for c in profile.coefficients]
    [0.6, 0.0]
    >>> profile.to_table().colnames
    ['mu', 'rho', 'intensity', 'scatter', 'law', 'counts']
    """
    check_map(smap)
    max_radius = check_fraction(max_radius, "max_radius", upper=1)
    if isinstance(bins, bool) or not isinstance(bins, (int, np.integer)) or bins < 2:
        raise ValueError(f"bins must be an int >= 2, got {bins!r}")
    level = disk_centre_level(smap, box=box)
    level_value = level.to_value(level.unit)
    if not np.isfinite(level_value) or level_value <= 0:
        raise ValueError(f"limb_darkening: the disk-centre level must be positive, got {level}")
    data = map_values(smap) / level_value
    rho, mu = disk_coordinates(smap)
    mu_min = np.sqrt(1 - max_radius**2)
    with np.errstate(invalid="ignore"):
        keep = np.isfinite(data) & np.isfinite(mu) & (rho < max_radius)
    edges = np.linspace(mu_min, 1, bins + 1)
    idx = np.clip(np.digitize(mu[keep], edges) - 1, 0, bins - 1)
    vals = data[keep]
    counts = np.bincount(idx, minlength=bins)
    sums = np.bincount(idx, weights=vals, minlength=bins)
    sq = np.bincount(idx, weights=vals**2, minlength=bins)
    mu_sum = np.bincount(idx, weights=mu[keep], minlength=bins)
    good = counts > 0
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = sums / counts
        scatter = np.sqrt(np.clip(sq / counts - mean**2, 0, None))
        # Mean μ of the pixels in each bin: exact abscissa for laws linear in μ.
        centres = np.where(good, mu_sum / counts, 0.5 * (edges[1:] + edges[:-1]))
    if good.sum() < 2:
        raise ValueError("limb_darkening: fewer than two populated μ bins; is the disk on the map?")
    x = 1 - centres[good]
    w = np.sqrt(counts[good])
    design = np.stack([-x, -x**2], axis=1) * w[:, None]
    coef, *_ = np.linalg.lstsq(design, (mean[good] - 1) * w, rcond=None)
    order = np.argsort(centres)[::-1]
    return LimbDarkeningProfile(
        mu=centres[order],
        rho=np.sqrt(1 - centres[order] ** 2),
        intensity=mean[order],
        scatter=scatter[order],
        counts=counts[order],
        centre_level=level,
        coefficients=(float(coef[0]), float(coef[1])),
    )


@dataclass
class LimbDarkeningComparison:
    """
    Result of `compare_limb_darkening`: two centre-to-limb profiles and their difference.

    Attributes
    ----------
    sim, obs : `~gongsynth.analysis.statistics.LimbDarkeningProfile`
        Profiles normalised to each map's own disk-centre level, on the same μ bins.
    max_difference, rms_difference : float
        Largest and rms |I_sim/I_sim(0) - I_obs/I_obs(0)| over the μ bins both maps fill.
    centre_ratio : float
        Ratio of the disk-centre levels, sim / obs (meaningful when both are in
        the same unit, e.g. DN of the same exposure).
    figure : `matplotlib.figure.Figure` or None
    """

    sim: LimbDarkeningProfile
    obs: LimbDarkeningProfile
    max_difference: float
    rms_difference: float
    centre_ratio: float
    figure: object = None


def compare_limb_darkening(sim_map, obs_map, *, instrument=None, degrade="auto", bins=20, max_radius=0.98,
                           labels=("simulated", "observed"), plot=True, fig=None):
    """
    Compare the count levels of two intensity maps: limb-darkening curves normalised to disk centre.

    Maps finer than ``AUTO_DEGRADE_FRACTION`` × GONG's pixels are first
    degraded to GONG (``degrade="auto"``), so the limb is blurred alike.

    Parameters
    ----------
    sim_map, obs_map : `~sunpy.map.GenericMap`
        Intensity maps (pseudo-continuum, continuum; any unit).
    instrument : `~gongsynth.GONGInstrument`, optional
    degrade : {"auto", True, False}
    bins : int
        Number of μ bins.
    max_radius : float
        Outermost distance from disk centre used, solar radii.
    labels : (str, str)
    plot : bool
        Draw the two curves and their difference.
    fig : `matplotlib.figure.Figure`, optional

    Returns
    -------
    `LimbDarkeningComparison`

    Examples
    --------
    >>> import numpy as np, astropy.units as u, sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> from gongsynth.analysis.disk import disk_coordinates
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> hdr = sunpy.map.make_fitswcs_header((200, 200), ref, scale=[10, 10] * u.arcsec / u.pix)
    >>> _, mu = disk_coordinates(sunpy.map.Map(np.zeros((200, 200)), hdr))
    >>> a = sunpy.map.Map(np.nan_to_num(1 - 0.6 * (1 - mu)), hdr)
    >>> b = sunpy.map.Map(np.nan_to_num(2 * (1 - 0.5 * (1 - mu))), hdr)
    >>> result = compare_limb_darkening(a, b, plot=False)
    >>> round(result.centre_ratio, 2), round(result.max_difference, 2)
    (0.5, 0.08)
    """
    if len(labels) != 2:
        raise ValueError(f"labels must be two strings, got {labels!r}")
    inst = instruments.get(instrument)
    profiles = []
    for smap, name in ((sim_map, "sim_map"), (obs_map, "obs_map")):
        check_map(smap, name, finite=True)
        smap, _ = degrade_if_finer(smap, inst, degrade=degrade)
        profiles.append(limb_darkening(smap, bins=bins, max_radius=max_radius))
    sim, obs = profiles
    both = (sim.counts > 0) & (obs.counts > 0)
    diff = np.abs(sim.intensity[both] - obs.intensity[both])
    ratio = sim.centre_level / obs.centre_level
    result = LimbDarkeningComparison(
        sim=sim, obs=obs, max_difference=float(diff.max()),
        rms_difference=float(np.sqrt(np.mean(diff**2))),
        centre_ratio=float(ratio.to_value(u.one)) if ratio.unit.is_equivalent(u.one) else float("nan"),
    )
    if plot:
        if fig is None:
            from matplotlib.figure import Figure

            fig = Figure(figsize=(7, 6))
        top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=[3, 1])
        for profile, label, colour in ((sim, labels[0], "C0"), (obs, labels[1], "C3")):
            top.plot(profile.mu, profile.intensity, "o", ms=3, color=colour,
                     label=f"{label}: centre {profile.centre_level:.4g}")
            top.plot(profile.mu, profile.law(profile.mu), "-", lw=0.8, color=colour)
        top.set_ylabel("I(μ) / I(disk centre)")
        top.legend(fontsize=8)
        bottom.plot(sim.mu[both], sim.intensity[both] - obs.intensity[both], "ko", ms=3)
        bottom.axhline(0, color="0.5", lw=0.8)
        bottom.set_xlabel("μ = cos θ")
        bottom.set_ylabel("difference")
        result.figure = fig
    return result
