"""
Where the real GONG map's weak field exceeds the model's: its fall to the limb and east-west anisotropy.

The noise guide found that the weak, network-scale signal of the real Big Bear
map holds up toward the limb.  gongsynth's falls there as a radial field's,
and so does the real MDI map's.  This script maps that signal over the whole
disk.  Each map is taken at GONG's pixels (MDI's degraded) and clipped to
±15 G about its median (the weak field).  The disk within 0.97 R☉ is cut
into 160″ boxes on a grid.  Boxes with more than 2 % of their pixels beyond
50 G (active regions) are left out.  The band power P of each box at
20-50 Mm is fitted (`gongsynth.analysis.limb_power.limb_power_fit`) as

    ln P = a + b ln μ + c (x² − y²),

with x and y the box centre's east-west and north-south offsets from disk
centre, in solar radii, and μ its cosine of the heliocentric angle.  b says
how fast the weak field's power falls toward the limb; c is its excess
east-west over north-south at equal μ, 0 for anything isotropic on the Sun.

The script also measures each spectrum's anisotropy at 3.7-7 and 7-15 Mm.
This is the power of the wavevectors nearer the x axis over that of those
nearer the y axis (`gongsynth.analysis.limb_power.axis_anisotropy`).  It is taken in the
boxes at 0.7 and 0.85 R☉, on the east-west axis and on the north-south axis.
Foreshortening alone gives the limb's radial direction the excess: x on the
east-west axis, y on the north-south one.

Then, as an ablation (not in gongsynth), it adds to the simulated GONG maps
the signal of a fixed offset δ along x between the images of the two
polarisation states.  GONG lists the two states' images not matching in
space among its magnetograms' problems, and "stretches" them to match
(*Status of GONG+ magnetograms*, MUG meeting presentation).  The offset turns
the Doppler shift's gradient into a field: v⁺ − v⁻ = δ ∂v/∂x, and
B = ``gauss_per_velocity`` × (v⁺ − v⁻) / 2 as GONG's reduction has it.  The
Doppler shift is each run's own Dopplergram, and δ is 0.05 and 0.1 pixel.
A second ablation takes the kind of mismatch GONG corrects, a stretch: an
offset that grows from disk centre, δ = S (x, y) in pixels per solar radius,
along x only (S_xx = 0.1 and 0.2, an anamorphic stretch) and on both axes
(S_xx = S_yy = 0.1 and 0.2, a magnification), with
`gongsynth.analysis.state_offset.offset_field`'s ``stretch``.
Each row also holds the issue-25 statistics against the real map
(`gongsynth.analysis.map_statistics.compare_statistics`) and, for the runs,
the offset that `gongsynth.analysis.state_offset.state_offset` reads back
from the map and the run's Dopplergram, as one shift and (``stretch=True``)
as a stretch (the real map's Dopplergram is not in ``shared/data``)::

    python scripts/limb_anisotropy.py --cache runs --table docs/guide/limb_anisotropy.ecsv

About 7 minutes on two cores once the runs are cached; a GONG run without its
Dopplergram in the cache is run again (about 20 s each).  The runs are those
of ``scripts/network_clusters_vs_real.py`` (its ``simulated``, the same cache).
"""
import sys
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from network_clusters_vs_real import REAL_MAPS, runs_parser, simulated  # noqa: E402  (the same runs)

#: The ablation's offsets between the two states' images (pixels).
OFFSETS_PX = (0.05, 0.1)
#: The ablation's stretches (S_xx, S_yy), pixels per solar radius: along x only, then a magnification.
STRETCHES = ((0.1, 0.0), (0.2, 0.0), (0.1, 0.1), (0.2, 0.2))


def limb_fit(smap):
    """(b, its standard error, c, its standard error, boxes used) of the fit in the module notes."""
    from gongsynth.analysis.limb_power import limb_power_fit

    fit = limb_power_fit(smap)
    return fit.mu_exponent, fit.mu_exponent_error, fit.east_west_excess, fit.east_west_excess_error, fit.boxes


def anisotropy(smap):
    """Mean x/y power ratio in each band, on the east-west axis then the north-south (``axis_anisotropy``)."""
    import numpy as np

    from gongsynth.analysis.limb_power import axis_anisotropy

    table = axis_anisotropy(smap)
    return {key: np.asarray(table["xy_ratio"][table["axis"] == axis])
            for key, axis in (("ew", "east-west"), ("ns", "north-south"))}


def with_state_offset(magnetogram, doppler, offset_px, stretch=(0.0, 0.0)):
    """
    The magnetogram plus the signal of an offset between the states' images.

    ``offset_px`` along x at disk centre, growing by ``stretch`` = (S_xx, S_yy) pixels per solar radius.
    """
    import sunpy.map

    from gongsynth.analysis.state_offset import offset_field

    matrix = [[stretch[0], 0.0], [0.0, stretch[1]]]
    return sunpy.map.Map(magnetogram.data + offset_field(doppler, offset_px, stretch=matrix).data,
                         magnetogram.meta)


def bars(smap, real):
    """KS distance (as measured, medians removed), mean |B| and the two noises, simulated/real."""
    import astropy.units as u

    from gongsynth.analysis.map_statistics import compare_statistics

    table = compare_statistics(smap, real).table
    ratio = {k: float(u.Quantity(table[k][0] / table[k][1]))
             for k in ("mean_abs", "noise_box", "noise_difference")}
    return [float(table["ks"][0]), float(table["ks_centred"][0]), ratio["mean_abs"], ratio["noise_box"],
            ratio["noise_difference"]]


def main(argv=None):
    """Measure the real and simulated maps and the ablation, write the table, print it."""
    parser = runs_parser(__doc__, seeds=(1, 2, 3, 4))
    args = parser.parse_args(argv)

    import astropy.units as u
    import numpy as np
    from astropy.table import QTable

    import gongsynth
    from gongsynth.analysis.degrade import degrade_if_finer
    from gongsynth.analysis.state_offset import state_offset

    warnings.simplefilter("ignore", category=UserWarning)
    real_gong = gongsynth.load_observation(REAL_MAPS["gong"][1])
    rows = []

    def measure(instrument, kind, seed, offset_px, stretch, smap, doppler=None):
        smap = degrade_if_finer(smap)[0]
        ratios = anisotropy(smap)
        statistics = bars(smap, real_gong) if instrument == "gong" else [np.nan] * 5
        read_back = [np.nan] * 6
        if doppler is not None:
            shift = state_offset(smap, doppler)[0]
            grown = state_offset(smap, doppler, stretch=True)[0]
            read_back = [shift["offset_x"].to_value(u.pix), shift["offset_x_error"].to_value(u.pix)]
            read_back += [grown[name].to_value(u.pix / u.R_sun)
                          for name in ("stretch_xx", "stretch_xx_error", "stretch_yy", "stretch_yy_error")]
        rows.append((instrument, REAL_MAPS[instrument][0], kind, seed, offset_px, *stretch, *limb_fit(smap),
                     *ratios["ew"], *ratios["ns"], *statistics, *read_back))
        print(" ".join(f"{v:.3f}" if isinstance(v, float) else str(v) for v in rows[-1]), flush=True)

    for instrument in ("gong", "mdi"):
        none = (0.0, 0.0)
        measure(instrument, "real", -1, 0.0, none, gongsynth.load_observation(REAL_MAPS[instrument][1]))
        for seed in args.seeds:
            runs = simulated(instrument, seed, args.cache, doppler=instrument == "gong")
            measure(instrument, "simulated", seed, 0.0, none, runs["magnetogram"], runs.get("doppler"))
            if instrument == "gong":
                for offset_px in OFFSETS_PX:
                    shifted = with_state_offset(runs["magnetogram"], runs["doppler"], offset_px)
                    measure(instrument, "simulated+offset", seed, offset_px, none, shifted, runs["doppler"])
                for stretch in STRETCHES:
                    stretched = with_state_offset(runs["magnetogram"], runs["doppler"], 0.0, stretch)
                    measure(instrument, "simulated+stretch", seed, 0.0, stretch, stretched, runs["doppler"])
    from gongsynth.analysis.limb_power import ANISOTROPY_BANDS

    bands = [f"{lo.to_value(u.Mm):g}_{hi.to_value(u.Mm):g}_Mm".replace(".", "p")
             for lo, hi in ANISOTROPY_BANDS]
    names = (["instrument", "date", "kind", "seed", "offset_px", "stretch_xx", "stretch_yy",
              "mu_exponent", "mu_exponent_error",
              "east_west_excess", "east_west_excess_error", "boxes"]
             + [f"xy_ratio_ew_{b}" for b in bands] + [f"xy_ratio_ns_{b}" for b in bands]
             + ["ks", "ks_centred", "mean_abs_ratio", "noise_box_ratio", "noise_difference_ratio",
                "read_offset_x", "read_offset_x_error", "read_stretch_xx", "read_stretch_xx_error",
                "read_stretch_yy", "read_stretch_yy_error"])
    table = QTable(rows=rows, names=names)
    for name in ("offset_px", "read_offset_x", "read_offset_x_error"):
        table[name].unit = u.pix
    for name in ("stretch_xx", "stretch_yy", "read_stretch_xx", "read_stretch_xx_error", "read_stretch_yy",
                 "read_stretch_yy_error"):
        table[name].unit = u.pix / u.R_sun
    table.meta["description"] = __doc__.splitlines()[1]
    table.meta["gongsynth_version"] = gongsynth.__version__
    args.table.parent.mkdir(parents=True, exist_ok=True)
    table.write(args.table, overwrite=True)
    print(f"wrote {args.table}")


if __name__ == "__main__":
    main()
