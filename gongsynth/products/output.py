"""
Writing a simulation's products to disk: FITS maps, raw planes, the run
configuration and a PNG quick-look, each file atomically.
"""
from pathlib import Path

from astropy.io import fits

from gongsynth.files import atomic_path, check_writable

__all__ = ["save_result", "planned_files", "PRODUCT_FILES"]

#: File name of each map product.
PRODUCT_FILES = {
    "magnetogram": "magnetogram.fits",
    "doppler": "doppler.fits",
    "continuum": "continuum.fits",
    "truth": "truth.fits",
    "truth_psf": "truth_psf.fits",
}
RAW_FILE = "raw.fits"
CONFIG_FILE = "config.toml"
QUICKLOOK_FILE = "quicklook.png"


def planned_files(directory, *, quicklook=True, truth=True):
    """
    The files `save_result` writes into ``directory`` (to check them before a long run).

    Parameters
    ----------
    directory : path-like
    quicklook : bool
    truth : bool
        Whether the result has ground-truth maps.

    Returns
    -------
    list of `pathlib.Path`

    Examples
    --------
    >>> [p.name for p in planned_files("run", quicklook=False, truth=False)]
    ['magnetogram.fits', 'doppler.fits', 'continuum.fits', 'raw.fits', 'config.toml']
    """
    directory = Path(directory)
    names = [f for k, f in PRODUCT_FILES.items() if truth or not k.startswith("truth")]
    names += [RAW_FILE, CONFIG_FILE] + ([QUICKLOOK_FILE] if quicklook else [])
    return [directory / n for n in names]


def save_result(result, directory, *, overwrite=False, quicklook=True):
    """
    Write a `~gongsynth.pipeline.SimulationResult` into ``directory``.

    Nothing is written if any target exists and ``overwrite`` is false; each
    file goes to a temporary name first and is renamed when complete.

    Parameters
    ----------
    result : `~gongsynth.pipeline.SimulationResult`
    directory : path-like
        Created if missing.
    overwrite : bool
    quicklook : bool
        Also write a PNG of the magnetogram, Dopplergram, continuum and truth.

    Returns
    -------
    list of `pathlib.Path`

    Examples
    --------
    >>> import tempfile
    >>> import astropy.units as u
    >>> from gongsynth import simulate
    >>> result = simulate(duration=1 * u.min, detector_shape=16, resolutions=(1,), seed=1,
    ...                   photosphere_shape=(64, 64), photosphere_pixel_size=1536 * u.km,
    ...                   progress=False)
    >>> paths = save_result(result, tempfile.mkdtemp(), quicklook=False)
    >>> sorted(p.name for p in paths)[:3]
    ['config.toml', 'continuum.fits', 'doppler.fits']
    """
    directory = Path(directory)
    maps = {name: getattr(result, name) for name in PRODUCT_FILES if getattr(result, name) is not None}
    check_writable(planned_files(directory, quicklook=quicklook, truth=result.truth is not None),
                   overwrite)
    directory.mkdir(parents=True, exist_ok=True)

    written = []
    for name, smap in maps.items():
        path = directory / PRODUCT_FILES[name]
        with atomic_path(path, overwrite=overwrite) as tmp:
            hdu = fits.PrimaryHDU(smap.data, fits.Header(smap.fits_header))
            hdu.writeto(tmp, overwrite=True)
        written.append(path)
    path = directory / RAW_FILE
    result.raw.to_fits(path, overwrite=overwrite)
    written.append(path)
    path = directory / CONFIG_FILE
    with atomic_path(path, overwrite=overwrite) as tmp:
        tmp.write_text(result.config.to_toml())
    written.append(path)
    if quicklook:
        path = directory / QUICKLOOK_FILE
        with atomic_path(path, overwrite=overwrite) as tmp:
            _quicklook(result).savefig(tmp, format="png", dpi=110)
        written.append(path)
    return written


def _quicklook(result):
    """Figure with the measured products and the truth side by side."""
    from matplotlib.figure import Figure

    panels = [m for m in (result.magnetogram, result.truth, result.doppler, result.continuum)
              if m is not None]
    fig = Figure(figsize=(4.2 * len(panels), 4.6), layout="constrained")
    for i, smap in enumerate(panels):
        ax = fig.add_subplot(1, len(panels), i + 1, projection=smap)
        image = smap.plot(axes=ax, title=smap.measurement.lower())
        fig.colorbar(image, ax=ax, shrink=0.8, label=str(smap.unit))
    fig.suptitle(result.summary().splitlines()[0], fontsize="small")
    return fig
