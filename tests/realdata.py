"""
Access to the real observations in ``shared/data/real`` and GONG-format test files.

The real files are never part of the repository: they live in the ``shared``
folder beside it (see its ``PROVENANCE.md``), or wherever the environment
variable ``GONGSYNTH_REAL_DATA`` points.  Tests that need a file skip, saying
which file and where it was looked for, when it is absent; a file that is
present but differs from PROVENANCE.md (sha256) fails the test.

GONG full-disk magnetograms in FITS are not among the real files, so GONG-format
files are built from sunpy's real GONG magnetogram header
(``sunpy.data.test``, ``gong_magnetogram.header``) and a data array, stored as
NSO stores them: 16-bit integers with BSCALE = 0.09504 G and the sky set to
SKYVALUE = -2000 G.
"""
import functools
import hashlib
import os
import warnings
from pathlib import Path

import numpy as np
import pytest
import sunpy.data.test
from astropy.io import fits

__all__ = ["REAL_DATA", "real_file", "load_real", "gong_header", "gong_rho", "write_gong_fits", "SHA256"]

#: Folder of the real data files.
REAL_DATA = Path(os.environ.get("GONGSYNTH_REAL_DATA")
                 or Path(__file__).resolve().parents[1].parent / "shared" / "data" / "real")

#: sha256 of the files used here, from PROVENANCE.md.
SHA256 = {
    "mdi/mdi.fd_m_96m_lev182.20101015_000000_TAI.data.fits":
        "9d2f242542925ad4c35777840fd5e0b091603b2ed4ee8ed399310b48c87e0c98",
    "mdi/mdi.fd_ic.20101015_230100_TAI.data.fits":
        "4e03c62d728132a5434d3e60129d97c146a15ca3737df78e794db7dbe8c4011b",
    "mdi/mdi_fd_M_96m_01d.5874.0005_s.fits":
        "c6eec533ffc4aa69c00030640b7e34d4c802ce6c3be77d33cc66374a0c51b86a",
    "hmi/JSOC_hmi.m_45s.20101020_000000_TAI.2.magnetogram.fits":
        "f19f258af85dcf02c50fa799cbfaf90904c5382369331fc1c785cd75c4820054",
    "gong/adapt40311_03k012_201707200800_i00015600n1.fts.gz":
        "7e2603bb803ba923d92345ee233b034735fa9a76590a619a2c5b09ba039b79e5",
    "gong/bbzqa240209t1734_dim-860.jpg":
        "5dbe557540ffb4375a58024968ed33c3c8a5ee38ae15107bde19431a045572ca",
    "gong/bbbqa090905t1854.fits.gz":
        "390ae520af45eb4d998b78082de308c382093f73408a843679c90a068d4badbf",
    "gong/bbiqa090905t1854.fits.gz":
        "a0ee9ef198b5964a5e7ce683227eb718adc2b0b43e1858f6c58359d0208497d9",
    "gong/mrbqs221029t0304c2263_067.fits":
        "5cef09c69b9f34e6bbe734c61ad609c99a63b2d816b77b6a521fd83b66f48fba",
}

_checked = set()


def real_file(relpath):
    """Path of a real data file; skip the test if it is absent, fail if it is corrupt."""
    path = REAL_DATA / relpath
    if not path.is_file():
        pytest.skip(f"real data file {relpath} not found in {REAL_DATA} (set GONGSYNTH_REAL_DATA or "
                    f"put the shared/ folder beside the repository; see shared/data/real/PROVENANCE.md)")
    if relpath in SHA256 and relpath not in _checked:
        digest = hashlib.sha256(path.read_bytes()).hexdigest()
        assert digest == SHA256[relpath], f"{path} differs from PROVENANCE.md (sha256 {digest})"
        _checked.add(relpath)
    return path


def gong_header():
    """sunpy's real GONG magnetogram header (860 x 860, 2025-01-09, Learmonth) as a fits.Header."""
    return fits.Header.fromtextfile(sunpy.data.test.get_test_filepath("gong_magnetogram.header"))


@functools.lru_cache(maxsize=1)
def gong_rho():
    """Distance from disk centre in solar radii of every pixel of the GONG header's grid (read-only)."""
    from gongsynth.analysis.disk import disk_coordinates

    dummy = sunpy.data.test.get_dummy_map_from_header(
        sunpy.data.test.get_test_filepath("gong_magnetogram.header"))
    rho = disk_coordinates(dummy)[0]
    rho.flags.writeable = False
    return rho


def write_gong_fits(path, data, header=None, *, sky=True):
    """
    Write ``data`` (860 x 860, gauss) as a GONG zqa-style FITS file.

    Off-disk pixels get SKYVALUE (if ``sky``); values are stored as int16 with
    the header's BSCALE, as NSO does.
    """
    header = gong_header() if header is None else header.copy()
    data = np.array(data, dtype=np.float64)
    if sky:
        data[~(gong_rho() < 1)] = header["SKYVALUE"]
    bscale = header["BSCALE"]
    for key in ("BSCALE", "BZERO"):
        header.remove(key, ignore_missing=True)
    hdu = fits.PrimaryHDU(data=data.astype(np.float32), header=header)
    hdu.scale("int16", bscale=bscale, bzero=0)
    hdu.writeto(path, overwrite=True)
    return Path(path)


def load_real(relpath, kind):
    """A real file through `gongsynth.load_observation` (skips when absent), header fixes silenced."""
    import gongsynth

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", fits.verify.VerifyWarning)
        return gongsynth.load_observation(real_file(relpath), kind=kind)
