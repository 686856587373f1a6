"""
Real and synthetic maps keep to their own map sources (DESIGN decision 22; sunpy issue 7294).

Importing gongsynth registers its map source(s) with `sunpy.map.Map`.  A source
that also matched a real file would make ``sunpy.map.Map`` raise
``MultipleMatchError`` on that file for every user who imports gongsynth; a real
source (GONG, HMI, MDI) that matched a synthetic file would pass a simulation off
as an observation.  Each real FITS file in ``shared/data/real`` (see
`tests.realdata`) is checked twice: header by header against gongsynth's sources,
and end to end, ``sunpy.map.Map(path)`` with gongsynth's sources registered
against the same call with them taken out of the map factory's registry, the only
way through which importing gongsynth changes the class ``Map`` chooses.
"""
import contextlib
import warnings

import astropy.units as u
import numpy as np
import pytest
import sunpy.map
from astropy.io import fits
from sunpy.util import MetaDict

import gongsynth
from gongsynth.geometry import field_centre
from gongsynth.products.maps import PRODUCTS, GONGSynthMap, make_product_map

from .realdata import REAL_DATA, real_file

#: The real FITS files of shared/data/real (PROVENANCE.md); any other FITS file found there is added.
REAL_FITS = [
    "gong/SWMF_util_fitsfile_GONG_synoptic_20220302t0614.fits",
    "gong/adapt40311_03k012_201707200800_i00015600n1.fts.gz",
    "gong/bbbqa090905t1854.fits.gz",
    "gong/bbiqa090905t1854.fits.gz",
    "gong/mrbqs221029t0304c2263_067.fits",
    "hinode/FGMG4_20110214_030443.7.fits",
    "hinode/HinodeSOT.fits",
    "hinode/hinode4d.20130912.sample.fits",
    "hmi/JSOC_hmi.m_45s.20101020_000000_TAI.2.magnetogram.fits",
    "mdi/mdi.fd_ic.20101015_230100_TAI.data.fits",
    "mdi/mdi.fd_m_96m_lev182.20101015_000000_TAI.data.fits",
    "mdi/mdi_fd_M_96m_01d.5874.0005_s.fits",
    "pairs/gong_mrzqs_c2253.fits",
    "pairs/gong_mrzqs_c2254.fits",
    "pairs/gong_mrzqs_c2255.fits",
    "pairs/hmi.Synoptic_Mr_small.2253.fits",
    "pairs/hmi.Synoptic_Mr_small.2254.fits",
    "pairs/hmi.Synoptic_Mr_small.2255.fits",
]
_FITS_SUFFIXES = (".fits", ".fts", ".fit", ".fits.gz", ".fts.gz", ".fits.fz")


def _real_fits():
    """REAL_FITS and every other FITS file under REAL_DATA, as paths relative to it."""
    found = []
    if REAL_DATA.is_dir():
        found = [path.relative_to(REAL_DATA).as_posix() for path in REAL_DATA.rglob("*")
                 if path.name.lower().endswith(_FITS_SUFFIXES)]
    return sorted(set(REAL_FITS) | set(found))


def _map_outcome(path):
    """
    The class name `sunpy.map.Map` gives ``path``, or the exception it raises.

    ``"HMIMap"``, ``"A,B"`` for a file with several image HDUs, or e.g.
    ``"raises MapMetaValidationError"`` (old GONG headers without CUNIT, which sunpy
    refuses after choosing the class; ``MultipleMatchError`` when two sources claim it).
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # header fixes of old files; not what is tested
        try:
            smap = sunpy.map.Map(path)
        except Exception as error:  # the outcome to compare, whatever it is
            return f"raises {type(error).__name__}"
    return ",".join(type(m).__name__ for m in (smap if isinstance(smap, list) else [smap]))


def _own_sources():
    """The map sources that importing gongsynth registers with `sunpy.map.Map`."""
    return [cls for cls in sunpy.map.Map.registry if cls.__module__.partition(".")[0] == "gongsynth"]


def _claimants(header, *, own):
    """Registered sources (gongsynth's if ``own``, else sunpy's and others') whose test accepts ``header``."""
    meta = MetaDict(dict(header))
    return [cls.__name__ for cls, accepts in sunpy.map.Map.registry.items()
            if (cls in _own_sources()) == own and accepts(None, meta)]


@contextlib.contextmanager
def _sunpy_alone():
    """`sunpy.map.Map` as without gongsynth: its sources out of the factory's registry, then back."""
    registry = sunpy.map.Map.registry
    own = {cls: registry.pop(cls) for cls in _own_sources()}
    try:
        yield
    finally:
        registry.update(own)


def test_gongsynth_registers_a_map_source():
    assert GONGSynthMap in _own_sources(), gongsynth.__name__


@pytest.mark.parametrize("name", _real_fits())
def test_real_file_keeps_its_sunpy_class(name):
    path = real_file(name)
    with fits.open(path) as hdus:
        headers = [hdu.header for hdu in hdus]  # headers only: the data are not read here
    for index, header in enumerate(headers):
        assert _claimants(header, own=True) == [], f"{name} HDU {index}"
    # End to end: the class ``sunpy.map.Map`` gives (or the error it raises) is sunpy's own.
    with _sunpy_alone():
        alone = _map_outcome(path)
    assert _map_outcome(path) == alone


@pytest.mark.parametrize("product", sorted(PRODUCTS))
def test_synthetic_map_is_not_claimed_by_real_sources(product, tmp_path):
    smap = make_product_map(np.zeros((4, 4)) * PRODUCTS[product][1], centre=field_centre(30 * u.deg)[0],
                            scale=2.5 * u.arcsec, product=product, duration=10 * u.min)
    path = tmp_path / f"{product}.fits"
    smap.save(path)
    header = fits.getheader(path)
    # sunpy's GONG, HMI and MDI sources (and any other) reject it; only gongsynth's accepts it.
    assert _claimants(header, own=False) == []
    assert _claimants(header, own=True) == ["GONGSynthMap"]
    assert _map_outcome(path) == "GONGSynthMap"
