r"""
Could the wind give the seeing a direction? The state offsets frozen-flow seeing leaves, along and across it.

The real Big Bear map's weak field is stronger east-west than north-south
(``scripts/limb_anisotropy.py``), and an offset along x between the two
polarisation states' images would make such a fingerprint (the noise guide).
gongsynth's frame seeing (`gongsynth.stages.seeing`) moves the image the
same way on both axes.  Turbulence carried by the wind is not isotropic in
time: with Taylor's frozen flow at speed v, the image motion at frequency f
comes from the phase screen's wavevectors with :math:`\kappa_\parallel = 2\pi
f / v` along the wind, and the tilt along the wind and across it have
different spectra,

.. math::

    W_\parallel(f) \propto \int d\kappa_\perp\, \kappa_\parallel^2\, \Phi(\kappa)\, A(\kappa)^2,
    \qquad
    W_\perp(f) \propto \int d\kappa_\perp\, \kappa_\perp^2\, \Phi(\kappa)\, A(\kappa)^2,

with the von Kármán spectrum :math:`\Phi \propto (\kappa^2 + \kappa_0^2)^{-11/6}`
(:math:`\kappa_0 = 2\pi / L_0`) and the aperture's centroid filter
:math:`A = 2 J_1(\kappa D/2) / (\kappa D/2)` (Conan, Rousset & Madec 1995,
JOSA A 12, 1559).  For :math:`\kappa_0 \ll \kappa_\parallel \ll 1/D` the ratio
is :math:`\Gamma(3/2)\Gamma(1/3) / (\sqrt\pi\,\Gamma(4/3)) = 3/2`: below the
aperture's frequency the tilt across the wind is the larger.

The two states alternate every ``lcvr_period`` (1 s), so what stays of the
motion in a one-minute magnetogram is its demodulation by a square wave of
0.5 Hz: the odd harmonics k f₀ with weights 8 / (π² k²).  The script takes
the wind from the real file's header (``WIND_SPD``, ``WIND_DIR``, the
direction it blows from), projects its axis onto the solar-north-up image
at the file's time from its site (astropy's AltAz to sunpy's
Helioprojective), and prints the variance of the state offsets along the
image's x axis over that along y that this seeing gives, with the
instrument's aperture and outer scale::

    python scripts/wind_seeing_anisotropy.py --table docs/guide/wind_seeing_anisotropy.ecsv

A second.  The ground wind stands for the wind of the turbulence (the
instrument's ``seeing_layer_height``, 100 m): a choice, as in the stage.
"""
import argparse
import math
from pathlib import Path

import numpy as np

#: The real Big Bear magnetogram (its header holds the wind).
DEFAULT_FILE = "gong/bbbqa090905t1854.fits.gz"
#: Odd harmonics of the state switching taken into the demodulation.
HARMONICS = (1, 3, 5, 7, 9)


def tilt_spectra(frequency, wind_speed, aperture, outer_scale):
    """
    Frozen-flow tilt spectra along and across the wind at ``frequency`` (Hz), unnormalised (module notes).

    ``wind_speed`` in m/s, ``aperture`` and ``outer_scale`` in m; returns (along, across) arrays.
    """
    from scipy.special import j1

    frequency = np.atleast_1d(np.asarray(frequency, dtype=float))
    kappa_0 = 2 * math.pi / outer_scale
    # κ⊥ on a log grid wide enough for every factor: from far below κ0 to far beyond 1/D.
    lowest = 1e-4 * min(kappa_0, 2 * math.pi * frequency.min() / wind_speed)
    across = np.geomspace(lowest, 200 / aperture, 20001)
    along_spectrum, across_spectrum = [], []
    for f in frequency:
        k_along = 2 * math.pi * f / wind_speed
        kappa = np.hypot(k_along, across)
        x = kappa * aperture / 2
        filter_ = (2 * j1(x) / x) ** 2
        common = (kappa**2 + kappa_0**2) ** (-11 / 6) * filter_
        along_spectrum.append(np.trapezoid(k_along**2 * common, across))
        across_spectrum.append(np.trapezoid(across**2 * common, across))
    return np.array(along_spectrum), np.array(across_spectrum)


def demodulated_variances(lcvr_period, wind_speed, aperture, outer_scale):
    """Unnormalised variances of the state offsets along and across the wind: the square wave's harmonics."""
    fundamental = 1 / (2 * lcvr_period)
    along, across = tilt_spectra([k * fundamental for k in HARMONICS], wind_speed, aperture, outer_scale)
    weights = np.array([8 / (math.pi**2 * k**2) for k in HARMONICS])
    return float(weights @ along), float(weights @ across)


def projected_wind_angle(obstime, location, wind_from_azimuth):
    """
    Angle (deg, from the image's +x toward +y, in [0, 180)) of the wind's axis on a solar-north-up image.

    The wind blows horizontally from ``wind_from_azimuth`` (deg east of north); its axis is projected
    onto the sky at the Sun's place seen from ``location`` at ``obstime``.
    """
    import astropy.units as u
    from astropy.coordinates import AltAz, SkyCoord, get_body
    from sunpy.coordinates import frames

    altaz = AltAz(obstime=obstime, location=location)
    sun = get_body("sun", obstime, location).transform_to(altaz)
    east, north, up = (np.array(v) for v in ((1, 0, 0), (0, 1, 0), (0, 0, 1)))

    def unit(azimuth, altitude):
        a, h = math.radians(azimuth), math.radians(altitude)
        return math.sin(a) * math.cos(h) * east + math.cos(a) * math.cos(h) * north + math.sin(h) * up

    line_of_sight = unit(sun.az.deg, sun.alt.deg)
    wind = unit(wind_from_azimuth, 0.0)
    wind = wind - wind @ line_of_sight * line_of_sight        # its part across the line of sight
    # A small step along it on the sky, as altitude and azimuth, taken to the helioprojective frame.
    step = 1e-3 * wind / np.linalg.norm(wind)
    end = (line_of_sight + step) / np.linalg.norm(line_of_sight + step)
    altitude = math.degrees(math.asin(np.clip(end @ up, -1, 1)))
    azimuth = math.degrees(math.atan2(end @ east, end @ north))
    helioprojective = frames.Helioprojective(observer=location.get_itrs(obstime), obstime=obstime)
    distance = [sun.distance.to_value(u.AU)] * 2 * u.AU
    ends = SkyCoord([sun.az.deg, azimuth] * u.deg, [sun.alt.deg, altitude] * u.deg, distance=distance,
                    frame=altaz).transform_to(helioprojective)
    dx, dy = (np.diff(c.to_value(u.arcsec))[0] for c in (ends.Tx, ends.Ty))
    return math.degrees(math.atan2(dy, dx)) % 180.0


def main(argv=None):
    """Read the header's wind, write and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--file", type=Path, default=None,
                        help=f"a GONG site file with WIND_SPD and WIND_DIR (default: {DEFAULT_FILE} "
                             "under GONGSYNTH_REAL_DATA)")
    parser.add_argument("--table", type=Path, required=True, help="ECSV file to write")
    args = parser.parse_args(argv)

    import os

    import astropy.units as u
    from astropy.io import fits
    from astropy.table import QTable
    from astropy.time import Time

    import gongsynth
    from gongsynth import GONGInstrument
    from gongsynth.observing import site_location

    path = args.file or Path(os.environ.get("GONGSYNTH_REAL_DATA", "../shared/data/real")) / DEFAULT_FILE
    header = fits.getheader(path)
    obstime = Time(header["DATE-OBS"].replace("/", "-") + "T" + header["TIME-OBS"])
    wind_speed, wind_from = float(header["WIND_SPD"]), float(header["WIND_DIR"])
    instrument = GONGInstrument()
    aperture = instrument.aperture.to_value(u.m)
    outer_scale = instrument.seeing_outer_scale.to_value(u.m)
    lcvr_period = instrument.lcvr_period.to_value(u.s)
    angle = projected_wind_angle(obstime, site_location(header["SITE"].strip()), wind_from)
    along, across = tilt_spectra(1 / (2 * lcvr_period), wind_speed, aperture, outer_scale)
    var_along, var_across = demodulated_variances(lcvr_period, wind_speed, aperture, outer_scale)
    c, s = math.cos(math.radians(angle)), math.sin(math.radians(angle))
    x_over_y = (var_along * c**2 + var_across * s**2) / (var_along * s**2 + var_across * c**2)
    table = QTable(rows=[(str(path.name), obstime.isot, wind_speed, wind_from, angle,
                          float(across[0] / along[0]), var_across / var_along, x_over_y)],
                   names=("file", "obstime", "wind_speed", "wind_from_azimuth", "wind_axis_angle",
                          "across_over_along_fundamental", "across_over_along_demodulated",
                          "offset_variance_x_over_y"))
    table["wind_speed"].unit = u.m / u.s
    table["wind_from_azimuth"].unit = table["wind_axis_angle"].unit = u.deg
    table.meta["description"] = __doc__.splitlines()[1]
    table.meta["gongsynth_version"] = gongsynth.__version__
    table.meta["instrument"] = {"aperture_m": aperture, "outer_scale_m": outer_scale,
                                "lcvr_period_s": lcvr_period}
    args.table.parent.mkdir(parents=True, exist_ok=True)
    table.write(args.table, overwrite=True)
    table.pprint_all()
    print(f"wrote {args.table}")


if __name__ == "__main__":
    main()
