r"""
Count levels of a simulated GONG observation next to a real one, and the matching effective area.

The paper (Sec. 3.2) chose GONG's effective area, 0.6 cm², "so that simulated
photon counts match those of the real GONG observations".  This module puts
gongsynth's counts and those a real GONG file implies on one scale — **adu per
camera frame per pixel in one of the six planes** — and returns the effective
area that would make them equal.  Simulated counts scale linearly with
``effective_area`` (`gongsynth.stages.optics.photometric_factor`), so the
matching area is :math:`A_\mathrm{eff} \times` real / simulated, with both
levels taken per unit solid angle (the real pixel, 2.56″ in 2009, is not
gongsynth's 2.5″).

**What the real header says, and how it is read here.**  GONG site files
(old header) carry, besides the image:

``ACCUM = 600`` ("per minute accumulations")
    Camera frames accumulated per minute in **each** of the six raw planes:
    60 frames/s × 60 s over 3 phases × 2 LCVR states.  This is gongsynth's
    ``RawPlanes.frames_per_plane`` (600 per minute), *not* the ``ACCUM``
    keyword gongsynth writes into its raw header (1800 per minute: frames per
    polarisation state).
``COUNT = 300`` ("accumulations per magnetogram state")
    300 per minute, the wave-plate turns of a minute at 5 Hz (gongsynth's
    ``COUNT``); it is not needed here.
``DIODE1``–``DIODE3`` ("sum of diode values from phase plane 1..3")
    Read as the sum over the camera's pixels of the mean **per-frame** value
    (adu) of phase plane *k*, i.e. :math:`\sum_\mathrm{pix} R_k\,2^b/\mathrm{ACCUM}`
    with :math:`R_k` the one-minute plane in DN (1 DN = 2\ :sup:`b` adu,
    b = 3 truncated bits).  The evidence is the identity
    :math:`\sum_\mathrm{pix} I = (\mathrm{ACCUM}/2^b)\sum_k D_k` with the
    intensity image *I*, which the 2009 Big Bear files satisfy to 0.2 %
    (75.13 against ACCUM/8 = 75; the image is a 9-minute average and the
    DIODEs belong to one minute).  Per on-disk pixel they give 527, 582 and
    526 adu per frame: 0.84 of the disk-centre level, as the image's own
    limb darkening (disk mean / centre = 0.83) requires.
The intensity image (``IMTYPE = 'INTENSITY'``, ``IUNIT = 'COUNTS'``)
    The mean of ``N_USED`` one-minute intensity images, each the sum over the
    three phase planes of the dark-subtracted, flat-fielded one-minute planes
    in DN, each phase plane the mean of its I+V and I−V planes.  Its
    ``BSCALE``/``BZERO`` (2.2989 / 75651 in 2009) only pack the floating-point
    image into 16 bits (BZERO is the mid-range, BSCALE ≈ range / 65535: a
    2.3-count step); they are not a calibration.  A disk-centre value *I*
    therefore means :math:`I\,2^b / (3\,\mathrm{ACCUM})` adu per frame per
    plane: 146 300 → 650 adu (21 500 e⁻ at 33 e⁻/adu).  The header's image
    mean 71 952 is over all 860 × 860 pixels, sky included; the on-disk mean
    is 122 600 (545 adu per frame).

Other readings, and why they are not the default:

* *The image sums all six planes* (``phase_planes=6``): half the level per
  frame, 325 adu.  gongsynth at 325 adu per frame gives a nine-minute-average
  magnetogram noise of 5.4 G, 1.7 times the real map's whole pixel-difference
  scatter in its quietest box (3.25 G, an upper bound on its noise); at
  650 adu it gives 3.1 G.  GONG's reduction interpolates each image once
  (``GHIST``: UCOR rotates it by 1.8°, `gongsynth.instruments.gong.ucor`);
  only a reduction of the pixel noise by more than 40 % would save this
  reading, and the rotation, modelled, lowers it by 14 % in the simulated
  map's quietest box (by 24 % on white noise far from the rotation's axis),
  so it is disfavoured rather than excluded.
* *The image is the mean of the planes*: 1950 adu per frame, so that a
  one-minute plane would hold (1950 + 182 dither) × 600 / 8 ≈ 160 000 DN,
  which does not fit the 16-bit planes that the 3-bit truncation exists for
  (paper Sec. 3.2); 650 adu gives 62 400 DN, 95 % of the 16-bit range.
* *DIODE is a separate photodiode*: possible (the header does not say), but
  then the 0.2 % identity above would be chance.  The disk-centre level does
  not depend on the DIODE reading.

The real level also contains what gongsynth leaves out: the Earth's
atmosphere (the 2009 file was taken at 30° zenith distance), dirt on the
optics and the real camera's gain (33 e⁻/adu is the paper's value).  The
matching area is therefore the effective area *of that observation*.
"""
import math
from dataclasses import dataclass

import astropy.units as u
import numpy as np
from astropy.table import QTable

from gongsynth import instruments
from gongsynth.analysis.disk import disk_coordinates
from gongsynth.instruments.gong.header_counts import DIODE_KEYWORDS
from gongsynth.instruments.gong.planes import N_CHANNELS, N_PLANES
from gongsynth.stages.reduction import divide_flat, subtract_dark

__all__ = ["DIODE_KEYWORDS", "PHASE_PLANES", "RealCountLevels", "real_count_levels", "count_levels"]

#: Accepted readings of the intensity image: the sum over 3 phase planes
#: (each the mean of I+V and I-V, the default) or over all 6 planes.
PHASE_PLANES = (3, 6)

#: Pixels darker than this fraction of the region's 90th percentile (sunspots,
#: pores) are left out of a disk-centre level.
_QUIET_FRACTION = 0.9
_PER_PLANE = "frame, pixel, plane"
_PER_DISK = "frame, on-disk pixel, phase plane"


@dataclass(frozen=True)
class RealCountLevels:
    """
    Count levels implied by a real GONG header and intensity image (see `real_count_levels`).

    Attributes
    ----------
    accum : int
        ``ACCUM``: frames per minute in each raw plane.
    centre : `~astropy.units.Quantity`
        Disk-centre level, adu per frame per pixel in one plane (NaN without
        an intensity image).
    centre_image : `~astropy.units.Quantity`
        The same as the intensity image states it (image counts, i.e. DN per
        minute summed over the phase planes; dimensionless).
    diode : `~astropy.units.Quantity`
        (3,) ``DIODE1``-``DIODE3`` in adu (per frame, summed over the pixels).
    diode_per_pixel : `~astropy.units.Quantity`
        (3,) the diode sums per on-disk pixel and per plane, adu per frame
        (NaN when the number of on-disk pixels is unknown).
    n_disk : int or None
        On-disk pixels (ρ < 1) of the map, or π a b from the header's limb fit.
    pixel_area : `~astropy.units.Quantity`
        Solid angle of one pixel, arcsec².
    diode_check : float
        Σ image / ((ACCUM / 2**b) Σ DIODE): 1 when the DIODE reading holds
        (NaN without an intensity image).
    phase_planes : int
        Planes summed in the intensity image (3 or 6).
    truncate_bits : int
        Low bits dropped by GONG after accumulation (1 DN = 2**b adu).
    """

    accum: int
    centre: u.Quantity
    centre_image: u.Quantity
    diode: u.Quantity
    diode_per_pixel: u.Quantity
    n_disk: object
    pixel_area: u.Quantity
    diode_check: float
    phase_planes: int
    truncate_bits: int


def _meta(obj, name):
    """The header (or map metadata) of ``obj`` and whether ``obj`` is a map."""
    meta = getattr(obj, "meta", None)
    if meta is not None and hasattr(obj, "data"):
        return meta, True
    if hasattr(obj, "get") and hasattr(obj, "keys"):
        return obj, False
    raise TypeError(f"{name} must be a sunpy Map or a FITS header, got {type(obj).__name__}")


def _key(meta, key, default=None):
    for k in (key, key.lower()):
        if k in meta:
            return meta[k]
    return default


def _imtype(meta):
    return str(_key(meta, "IMTYPE", "")).strip().upper()


def _pixel_area(smap):
    return (abs(smap.scale.axis1 * smap.scale.axis2) * (u.pix**2)).to(u.arcsec**2)


def _header_pixel_area(meta):
    radius, semi_axis = _key(meta, "RADIUS"), _key(meta, "FNDLMBMI")
    if radius is None or semi_axis is None:
        return np.nan * u.arcsec**2
    return ((float(radius) * u.rad).to(u.arcsec) / float(semi_axis)) ** 2


def _centre_mask(smap, max_radius, name):
    rho, _ = disk_coordinates(smap)
    mask = rho < max_radius
    if not mask.any():
        raise ValueError(f"{name} has no pixel within {max_radius} solar radii of disk centre "
                         f"(simulate at latitude 0 or in full-disk mode, or raise max_radius)")
    return rho, mask


def _quiet_level(values):
    """Median of the quiet-Sun pixels: those at least 0.9 of the 90th percentile."""
    values = values[np.isfinite(values)]
    return float(np.median(values[values >= _QUIET_FRACTION * np.percentile(values, 90)]))


def _check_choice(phase_planes, max_radius):
    if phase_planes not in PHASE_PLANES:
        raise ValueError(f"phase_planes must be one of {PHASE_PLANES}, got {phase_planes!r}")
    if not (isinstance(max_radius, (int, float)) and 0 < max_radius <= 1):
        raise ValueError(f"max_radius must be a number in (0, 1] (solar radii), got {max_radius!r}")


def real_count_levels(real, *, intensity=None, max_radius=0.1, phase_planes=3, truncate_bits=3):
    """
    Count levels implied by a real GONG file: disk centre per frame, and the DIODE sums.

    Parameters
    ----------
    real : `~sunpy.map.GenericMap` or `~astropy.io.fits.Header`
        A real GONG map (magnetogram or intensity image, from
        `~gongsynth.compare.load_observation`) or its header; supplies
        ``ACCUM`` and ``DIODE1``-``DIODE3``.
    intensity : `~sunpy.map.GenericMap`, optional
        The real intensity image; default ``real`` itself when it is one
        (``IMTYPE = 'INTENSITY'``).
    max_radius : float
        Disk-centre region, in solar radii (default 0.1).  The level is the
        median of its quiet pixels: those at least 0.9 of the region's 90th
        percentile (sunspots and pores are left out).
    phase_planes : {3, 6}
        Planes summed in the intensity image (module notes; default 3).
    truncate_bits : int
        Low bits GONG drops after accumulation (3).

    Returns
    -------
    `RealCountLevels`

    Raises
    ------
    TypeError
        If ``real`` is neither a map nor a header.
    ValueError
        If ACCUM is missing or not positive, or an argument is out of range.

    Examples
    --------
    >>> from astropy.io import fits
    >>> header = fits.Header({"ACCUM": 600, "DIODE1": 228773684, "DIODE2": 252631643,
    ...                       "DIODE3": 228385037, "RADIUS": 0.004615724,
    ...                       "FNDLMBMI": 371.5439, "FNDLMBMA": 371.8845})
    >>> levels = real_count_levels(header)
    >>> levels.diode_per_pixel.round(0)
    <Quantity [527., 582., 526.] adu>
    """
    _check_choice(phase_planes, max_radius)
    meta, is_map = _meta(real, "real")
    accum = _key(meta, "ACCUM")
    if accum is None or int(accum) <= 0:
        raise ValueError("the real header has no positive ACCUM (frames per minute in each plane)")
    accum = int(accum)
    if intensity is None and is_map and _imtype(meta) == "INTENSITY":
        intensity = real
    scale = 2**int(truncate_bits)
    diode = np.array([float(_key(meta, k, np.nan)) for k in DIODE_KEYWORDS]) * u.adu
    geometry = intensity if intensity is not None else (real if is_map else None)
    if geometry is not None:
        rho, _ = disk_coordinates(geometry)
        n_disk = int(np.count_nonzero(rho < 1))
        pixel_area = _pixel_area(geometry)
    else:
        a, b = _key(meta, "FNDLMBMI"), _key(meta, "FNDLMBMA")
        n_disk = int(round(math.pi * float(a) * float(b))) if a is not None and b is not None else None
        pixel_area = _header_pixel_area(meta)
    # Per plane: a DIODE sums both LCVR states' mean (3 phase planes) or their sum (6).
    per_pixel = diode * (3 / phase_planes) / n_disk if n_disk else np.full(3, np.nan) * u.adu
    centre_image, check = np.nan, np.nan
    if intensity is not None:
        rho, mask = _centre_mask(intensity, max_radius, "the intensity image")
        values = np.asarray(intensity.data, dtype=float)
        centre_image = _quiet_level(values[mask])
        check = float(np.nansum(values) / (accum / scale * np.sum(diode.value)))
    centre = centre_image * scale / (phase_planes * accum) * u.adu
    return RealCountLevels(accum=accum, centre=centre, centre_image=centre_image * u.one, diode=diode,
                           diode_per_pixel=per_pixel, n_disk=n_disk, pixel_area=pixel_area,
                           diode_check=check, phase_planes=phase_planes, truncate_bits=int(truncate_bits))


def _simulated_parts(simulated, instrument):
    raw = getattr(simulated, "raw", None)
    continuum = getattr(simulated, "continuum", None)
    if raw is None or continuum is None or not hasattr(raw, "frames_per_plane"):
        raise TypeError("simulated must be a SimulationResult, or an object with .raw (RawPlanes) "
                        f"and .continuum (the pseudo-continuum map); got {type(simulated).__name__}")
    config = getattr(simulated, "config", None)
    if instrument is None and config is not None:
        instrument = getattr(config, "instrument", None)
    inst = instruments.get(instrument)
    return raw, continuum, getattr(simulated, "expected_counts", None), inst, getattr(config, "mode", None)


def _corrected_planes(raw, inst):
    """Dark-subtracted, flat-divided planes (DN), as the reduction makes them."""
    planes = np.asarray(raw.data, dtype=float)
    dark = getattr(raw, "dark", None)
    if dark is not None:
        planes = subtract_dark(planes, dark, raw.frames_per_plane, inst)
    flat = getattr(raw, "flat", None)
    if flat is not None:
        planes = divide_flat(planes, flat)
    return planes


def _is_full_disk(continuum, mode, rho, values):
    """Whether a simulated map shows the whole disk on a dark sky (a full-disk run)."""
    mode = continuum.meta.get("simmode", mode)
    on_disk = rho < 1
    radius_px = (continuum.rsun_obs / _pixel_area(continuum) ** 0.5).to_value(u.one)
    if (mode is not None and mode != "full-disk") or on_disk.sum() < 0.98 * math.pi * radius_px**2:
        return False
    sky = values[(rho > 1.05) & np.isfinite(values)]  # gongsynth blanks its sky (NaN)
    return sky.size == 0 or np.mean(sky) < 0.05 * np.nanmean(values[on_disk])


def _simulated_levels(raw, continuum, expected, inst, max_radius, scale, mode=None):
    """Per-frame, per-plane levels (adu) of a simulation: centre (expected, continuum), disk DIODEs."""
    rho, mask = _centre_mask(continuum, max_radius, "the simulated map")
    frames = np.asarray(raw.frames_per_plane, dtype=float)
    if frames.shape != (N_PLANES,) or np.any(frames <= 0):
        raise ValueError(f"raw.frames_per_plane must be {N_PLANES} positive numbers, got {frames!r}")
    gain = inst.gain.to_value(u.electron / u.adu)
    # The pseudo-continuum is the sum of the six corrected planes in DN (1 DN = 2**b adu).
    values = np.asarray(getattr(continuum.data, "value", continuum.data), dtype=float)
    from_continuum = _quiet_level(values[mask]) * scale / frames.sum()
    from_expected = np.nan
    if expected is not None:
        counts = u.Quantity(expected).to_value(u.electron)
        if counts.shape != (N_PLANES,) + values.shape:
            raise ValueError(f"expected counts of shape {counts.shape} do not match the map {values.shape}")
        from_expected = _quiet_level(counts.mean(axis=0)[mask]) / gain
    diodes = np.full(N_CHANNELS, np.nan)
    if _is_full_disk(continuum, mode, rho, values):
        per_frame = _corrected_planes(raw, inst) * scale / frames[:, None, None]
        phase = 0.5 * (per_frame[:N_CHANNELS] + per_frame[N_CHANNELS:])
        diodes = np.nansum(phase, axis=(1, 2)) / np.count_nonzero(rho < 1)
    mu = float(np.mean(np.sqrt(np.clip(1 - rho[mask] ** 2, 0, None))))
    return from_expected, from_continuum, diodes, mu


def count_levels(real, simulated, *, intensity=None, instrument=None, max_radius=0.1, phase_planes=3):
    """
    Simulated and real GONG count levels side by side, and the effective area that would match.

    Every level is in adu per camera frame per pixel in one plane (see the
    module notes for how the real header is read).

    Parameters
    ----------
    real : `~sunpy.map.GenericMap` or `~astropy.io.fits.Header`
        A real GONG map or header (``ACCUM``, ``DIODE1``-``DIODE3``); if it is
        the intensity image, it also gives the disk-centre level.
    simulated : `~gongsynth.pipeline.SimulationResult` or object
        A simulation, or anything with ``.raw`` (`~gongsynth.stages.camera.integrate.RawPlanes`)
        and ``.continuum`` (the pseudo-continuum map, DN) and optionally
        ``.expected_counts`` and ``.config``.
    intensity : `~sunpy.map.GenericMap`, optional
        The real intensity image, when ``real`` is not it.
    instrument : `~gongsynth.GONGInstrument`, optional
        The simulation's instrument (gain, truncation, effective area);
        default ``simulated.config.instrument``, else the default GONG.
    max_radius : float
        Disk-centre region in solar radii (default 0.1).  Levels are medians
        of its quiet pixels (at least 0.9 of the region's 90th percentile), so
        the sunspots of gongsynth's tiled Sun do not pull them down.
    phase_planes : {3, 6}
        Planes summed in the real intensity image (default 3; module notes).

    Returns
    -------
    `~astropy.table.QTable`
        One row per level: ``quantity``, ``per`` (what a level is per),
        ``real`` and ``simulated`` (adu; the simulation on its own pixels),
        ``ratio`` = real / simulated per unit solid angle and
        ``effective_area`` = the simulation's area × ``ratio`` (cm²), the
        area at which the simulation would reach the real level.  Rows:
        the disk centre from the expected (noise-free) counts and from the
        pseudo-continuum, and the DIODE sums per on-disk pixel (simulated only
        for a full-disk run, whose sky is dark: the sum of each channel's
        per-frame level over the field, per on-disk pixel; NaN otherwise).  ``meta`` holds the inputs of the
        conversion (``accum``, ``frames_per_plane``, ``truncate_bits``,
        ``gain``, ``pixel_area_ratio``, ``effective_area``, ``diode_check``,
        the disk-centre levels in image counts, ``simulated_mu``).

    Raises
    ------
    TypeError
        If ``real`` or ``simulated`` is not of a kind listed above.
    ValueError
        If a map has no pixel within ``max_radius`` of disk centre, or the
        header lacks ACCUM.

    Examples
    --------
    A real intensity image of 146 250 counts at disk centre (650 adu per frame)
    next to a simulation that reaches 2600 adu per frame with 0.6 cm²:

    >>> import types, numpy as np, astropy.units as u, sunpy.map
    >>> from astropy.coordinates import SkyCoord
    >>> from sunpy.coordinates import frames
    >>> ref = SkyCoord(0 * u.arcsec, 0 * u.arcsec, frame=frames.Helioprojective,
    ...                observer="earth", obstime="2020-01-01")
    >>> def image(value):
    ...     return sunpy.map.Map(np.full((9, 9), value), sunpy.map.make_fitswcs_header(
    ...         (9, 9), ref, scale=[2.5, 2.5] * u.arcsec / u.pix))
    >>> real = image(146250.0)
    >>> real.meta.update({"imtype": "INTENSITY", "accum": 600})
    >>> raw = types.SimpleNamespace(data=np.full((6, 9, 9), 195000.0), frames_per_plane=[600] * 6)
    >>> simulated = types.SimpleNamespace(raw=raw, continuum=image(6 * 195000.0))
    >>> table = count_levels(real, simulated, max_radius=0.05)
    >>> row = table[1]
    >>> str(row["quantity"]), row["real"], row["simulated"], row["effective_area"].round(3)
    ('disk centre (pseudo-continuum)', <Quantity 650. adu>, <Quantity 2600. adu>, <Quantity 0.15 cm2>)
    """
    _check_choice(phase_planes, max_radius)
    raw, continuum, expected, inst, mode = _simulated_parts(simulated, instrument)
    real_levels = real_count_levels(real, intensity=intensity, max_radius=max_radius,
                                    phase_planes=phase_planes, truncate_bits=inst.truncate_bits)
    header = getattr(raw, "header", None) or {}
    bits = int(header.get("TRUNCBIT", inst.truncate_bits))
    scale = 2**bits
    from_expected, from_continuum, sim_diodes, sim_mu = _simulated_levels(
        raw, continuum, expected, inst, max_radius, scale, mode)
    area_ratio = float(real_levels.pixel_area / _pixel_area(continuum))
    if not np.isfinite(area_ratio):
        area_ratio = float((inst.plate_scale**2 / _pixel_area(continuum)).to_value(u.one))
    centre = real_levels.centre.to_value(u.adu)
    diode = real_levels.diode_per_pixel.to_value(u.adu)
    rows = [("disk centre (expected counts)", _PER_PLANE, centre, from_expected),
            ("disk centre (pseudo-continuum)", _PER_PLANE, centre, from_continuum)]
    rows += [(f"{key} / on-disk pixels", _PER_DISK, diode[k], sim_diodes[k])
             for k, key in enumerate(DIODE_KEYWORDS)]
    rows.append(("mean DIODE / on-disk pixels", _PER_DISK, float(np.mean(diode)), float(np.mean(sim_diodes))))
    real_col = np.array([r[2] for r in rows]) * u.adu
    sim_col = np.array([r[3] for r in rows]) * u.adu
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = (real_col / (sim_col * area_ratio)).to(u.one)
    table = QTable({"quantity": [r[0] for r in rows], "per": [r[1] for r in rows],
                    "real": real_col, "simulated": sim_col, "ratio": ratio,
                    "effective_area": (inst.effective_area * ratio).to(u.cm**2)})
    table.meta.update({
        "accum": real_levels.accum,
        "frames_per_plane": [int(f) for f in raw.frames_per_plane],
        "simulated_accum_keyword": header.get("ACCUM"),
        "truncate_bits": bits,
        "phase_planes": phase_planes,
        "gain": inst.gain,
        "effective_area": inst.effective_area,
        "pixel_area_ratio": area_ratio,
        "diode_check": real_levels.diode_check,
        "real_centre_image": real_levels.centre_image,
        "simulated_centre_image": from_continuum * phase_planes * real_levels.accum / scale * u.one,
        "simulated_mu": sim_mu,
        "max_radius": max_radius,
    })
    return table
