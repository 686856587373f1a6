"""
Real and synthetic maps keep to their own map sources (DESIGN decision 22; sunpy issue 7294).

Importing gongsynth registers its map source(s) with `sunpy.map.Map`.  A source
that also matched a real file would make ``sunpy.map.Map`` raise
``MultipleMatchError`` on that file for every user who imports gongsynth; a real
source (GONG, HMI, MDI) that matched a synthetic file would pass a simulation off
as an observation.  Each real FITS file in ``shared/data/real`` (see
`tests.realdata`) is checked twice: header by header against gongsynth's sources,
and end to end, ``sunpy.map.Map(path)`` with gongsynth imported against the same
call in a fresh interpreter without it.
"""
import json
import subprocess
import sys
from pathlib import Path

import astropy.units as u
import numpy as np
import pytest
import sunpy.map
from astropy.io import fits
from sunpy.util import MetaDict

import gongsynth
from gongsynth.geometry import field_centre
from gongsynth.products.maps import PRODUCTS, GONGSynthMap, make_product_map

from .map_outcomes import map_outcome
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


def _own_sources():
    """The map sources that importing gongsynth registers with `sunpy.map.Map`."""
    return [cls for cls in sunpy.map.Map.registry if cls.__module__.partition(".")[0] == "gongsynth"]


def _claimants(header, *, own):
    """Registered sources (gongsynth's if ``own``, else sunpy's and others') whose test accepts ``header``."""
    meta = MetaDict(dict(header))
    return [cls.__name__ for cls, accepts in sunpy.map.Map.registry.items()
            if (cls in _own_sources()) == own and accepts(None, meta)]


def test_gongsynth_registers_a_map_source():
    assert GONGSynthMap in _own_sources(), gongsynth.__name__


@pytest.mark.parametrize("name", _real_fits())
def test_real_file_is_not_claimed_by_gongsynth(name):
    with fits.open(real_file(name)) as hdus:
        headers = [hdu.header for hdu in hdus]  # headers only: the data are never read
    for index, header in enumerate(headers):
        assert _claimants(header, own=True) == [], f"{name} HDU {index}"


def test_map_gives_the_same_class_as_sunpy_alone():
    """End to end: ``sunpy.map.Map(path)`` here and in an interpreter that never imports gongsynth."""
    present = [name for name in _real_fits() if (REAL_DATA / name).is_file()]
    if not present:
        pytest.skip(f"no real FITS files in {REAL_DATA} (set GONGSYNTH_REAL_DATA; see tests/realdata.py)")
    script = Path(__file__).with_name("map_outcomes.py")
    run = subprocess.run([sys.executable, str(script), str(REAL_DATA), *present],
                         capture_output=True, text=True, timeout=600, check=False)
    assert run.returncode == 0, run.stderr
    without = json.loads(run.stdout)
    with_gongsynth = {name: map_outcome(REAL_DATA / name) for name in present}
    assert with_gongsynth == without


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
    assert map_outcome(path) == "GONGSynthMap"
