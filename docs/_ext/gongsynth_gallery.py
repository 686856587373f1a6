"""
The order of the gallery: a walk through the simulator, not the alphabet.

Used by sphinx-gallery as ``within_subsection_order = "gongsynth_gallery.StoryOrder"``.
Examples not listed in `ORDER` follow the listed ones, by file name.
"""
__all__ = ["ORDER", "StoryOrder"]

#: Gallery examples in reading order: the whole chain first, then stage by stage,
#: then the products and how they compare.
ORDER = [
    "plot_quickstart.py",
    "plot_model_photosphere.py",
    "plot_channel_responses.py",
    "plot_field_linearity.py",
    "plot_tiling.py",
    "plot_frame_schedule.py",
    "plot_magnetograms.py",
    "plot_one_sun_gong_and_hmi.py",
    "plot_why_instruments_disagree.py",
    "plot_full_disk.py",
    "plot_full_disk_vs_real.py",
    "plot_compare_real.py",
    "plot_latitude_sweep.py",
    "plot_why_gong_under_measures.py",
]


class StoryOrder:
    """Sort key: position in `ORDER`, then file name."""

    def __init__(self, src_dir):
        self.src_dir = src_dir

    def __call__(self, filename):
        position = ORDER.index(filename) if filename in ORDER else len(ORDER)
        return (position, filename)

    def __repr__(self):
        return f"<{self.__class__.__name__}>"
