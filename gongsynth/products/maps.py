"""
sunpy Maps of gongsynth products, and the map source that reads them back.

Synthetic files must never pass for real GONG observations: they carry
``ORIGIN = 'gongsynth'``, ``DTYPE = 'SIMULATED'`` and a ``TELESCOP`` that does
not end in "GONG", so sunpy's GONG sources do not claim them.  Importing
gongsynth registers `GONGSynthMap` with `sunpy.map.Map`, which then returns a
GONGSynthMap with the right units and plot settings for any gongsynth FITS file.
"""
import astropy.units as u
import matplotlib.colors as mcolors
import numpy as np
from sunpy.map import GenericMap

from gongsynth import instruments
from gongsynth.geometry import TELESCOPE, wcs_header
from gongsynth.version import version as __version__

__all__ = ["GONGSynthMap", "PRODUCTS", "product_header", "make_product_map", "simulated_telescope"]

#: Product names, their FITS ``CONTENT`` and ``BUNIT``.
PRODUCTS = {
    "magnetogram": ("MAGNETOGRAM", u.G),
    "doppler": ("DOPPLERGRAM", u.m / u.s),
    "continuum": ("PSEUDO-CONTINUUM", u.adu),
    "truth": ("TRUE B_LOS", u.G),
    "truth_psf": ("TRUE B_LOS PSF", u.G),
}

#: Symmetric display range of each signed product.
_DISPLAY_RANGE = {"MAGNETOGRAM": 150, "TRUE B_LOS": 150, "TRUE B_LOS PSF": 150, "DOPPLERGRAM": 1500}


def _product(product):
    """(CONTENT, unit) of a product name, or a clear error."""
    if product not in PRODUCTS:
        raise ValueError(f"product must be one of {sorted(PRODUCTS)}, got {product!r}")
    return PRODUCTS[product]


def simulated_telescope(instrument):
    """
    The TELESCOP of a simulated instrument's products: never a real source's name (design §3.22).

    Parameters
    ----------
    instrument : `~gongsynth.instruments.base.Instrument`

    Returns
    -------
    str
        ``"gongsynth (simulated GONG)"``, ``"gongsynth (simulated HMI)"``, ...

    Examples
    --------
    >>> from gongsynth import instruments
    >>> simulated_telescope(instruments.get("gong"))
    'gongsynth (simulated GONG)'
    """
    return TELESCOPE.replace("GONG", instrument.label)


def product_header(shape, *, centre, scale, product, instrument=None, duration=None, extra=None):
    """
    FITS header of a gongsynth product map with a helioprojective WCS.

    Parameters
    ----------
    shape : tuple of int
        (ny, nx) of the image.
    centre : `~astropy.coordinates.SkyCoord`
        Helioprojective coordinate of the image centre (see `gongsynth.geometry.field_centre`).
    scale : `~astropy.units.Quantity`
        Pixel size (angle per pixel).
    product : str
        One of `PRODUCTS`.
    instrument : `~gongsynth.instruments.base.Instrument` or str, optional
        Supplies the telescope and detector names, the line wavelength
        (WAVELNTH) and the frame exposure (default GONG).
    duration : `~astropy.units.Quantity`, optional
        Length of the integration that starts at ``centre.obstime``
        (DATE-OBS): written as DATE-BEG, DATE-AVG, DATE-END and XPOSURE
        (FITS standard 4.0 time keywords), so that sunpy's ``Map.date``
        and ``Map.reference_date`` say when the magnetogram was taken.
    extra : dict, optional
        More header cards (≤ 8-character keys), e.g. run parameters; a value
        may be a ``(value, comment)`` pair.

    Returns
    -------
    `sunpy.util.MetaDict`

    Examples
    --------
    >>> import astropy.units as u
    >>> from gongsynth.geometry import field_centre
    >>> centre, _ = field_centre(60 * u.deg)
    >>> h = product_header((8, 8), centre=centre, scale=2.5 * u.arcsec, product="doppler",
    ...                    extra={"seed": ("1", "root random seed")})
    >>> h["content"], h["bunit"], h["dtype"], h["seed"]
    ('DOPPLERGRAM', 'm s-1', 'SIMULATED', '1')
    >>> h = product_header((8, 8), centre=centre, scale=2.5 * u.arcsec, product="magnetogram",
    ...                    duration=10 * u.min)
    >>> h["date-beg"], h["date-end"], h["xposure"], round(h["exptime"], 5)
    ('2019-06-07T00:20:00.000', '2019-06-07T00:30:00.000', 600.0, 0.01667)
    """
    content, unit = _product(product)
    inst = instruments.get(instrument)
    header = wcs_header(shape, scale, centre, wavelength=inst.line_wavelength, unit=unit)
    header["telescop"] = simulated_telescope(inst)
    header["origin"] = "gongsynth"
    header["dtype"] = "SIMULATED"
    header["content"] = content
    header["detector"] = f"simulated {inst.label} camera"
    header["gsvers"] = __version__
    header["exptime"] = float(inst.exposure_time.to_value(u.s))
    comments = dict(header.get("keycomments", {}))
    comments["EXPTIME"] = "[s] exposure of one camera frame"
    if duration is not None:
        start = centre.obstime
        header["date-beg"] = start.isot
        header["date-avg"] = (start + duration / 2).isot
        header["date-end"] = (start + duration).isot
        # Frames follow each other without gaps: accumulated exposure = frames x exposure.
        frames = inst.schedule(u.Quantity(duration)).n_frames
        header["xposure"] = float(frames * inst.exposure_time.to_value(u.s))
        comments["XPOSURE"] = "[s] accumulated exposure of all frames"
    for key, value in (extra or {}).items():
        if isinstance(value, tuple):
            value, comments[key.upper()] = value
        header[key.lower()] = value
    header["keycomments"] = comments
    return header


def make_product_map(data, *, centre, scale, product, instrument=None, duration=None, extra=None):
    """
    A `GONGSynthMap` of one product.

    Parameters
    ----------
    data : `~astropy.units.Quantity`
        Image (ny, nx) in units convertible to the product's (G, m/s or adu).
    centre, scale, product, instrument, duration, extra
        As for `product_header`.

    Returns
    -------
    `GONGSynthMap`

    Examples
    --------
    >>> import astropy.units as u
    >>> import numpy as np
    >>> from gongsynth.geometry import field_centre
    >>> centre, _ = field_centre(0 * u.deg)
    >>> m = make_product_map(np.ones((4, 4)) * u.kG, centre=centre, scale=2.5 * u.arcsec,
    ...                      product="truth")
    >>> float(m.data[0, 0]), m.unit
    (1000.0, Unit("G"))
    """
    unit = _product(product)[1]
    values = u.Quantity(data).to_value(unit)
    header = product_header(values.shape, centre=centre, scale=scale, product=product,
                            instrument=instrument, duration=duration, extra=extra)
    return GONGSynthMap(np.asarray(values, dtype=np.float32), header)


class GONGSynthMap(GenericMap):
    """
    A map produced by gongsynth: a simulated GONG magnetogram, Dopplergram,
    pseudo-continuum or the ground truth they are compared with.

    Recognised by ``ORIGIN = 'gongsynth'`` in the header.  Magnetograms and
    truth maps are shown as GONG shows them, grey from -150 G (black) to
    +150 G (white); Dopplergrams with a diverging map over ±1.5 km/s;
    continua grey.

    Examples
    --------
    >>> import astropy.units as u
    >>> import numpy as np
    >>> from gongsynth.geometry import field_centre
    >>> centre, _ = field_centre(0 * u.deg)
    >>> m = make_product_map(np.zeros((4, 4)) * u.G, centre=centre, scale=2.5 * u.arcsec,
    ...                      product="magnetogram")
    >>> type(m).__name__, m.unit, m.measurement
    ('GONGSynthMap', Unit("G"), 'MAGNETOGRAM')
    """

    def __init__(self, data, header, **kwargs):
        super().__init__(data, header, **kwargs)
        content = str(self.meta.get("content", ""))
        limit = _DISPLAY_RANGE.get(content)
        if content in ("MAGNETOGRAM", "TRUE B_LOS"):
            self.plot_settings["cmap"] = "gray"  # GONG's own display: black -150 G, white +150 G
        elif content == "DOPPLERGRAM":
            self.plot_settings["cmap"] = "RdBu_r"
        else:
            self.plot_settings["cmap"] = "gray"
        if limit is not None:
            self.plot_settings["norm"] = mcolors.Normalize(-limit, limit)

    @property
    def measurement(self):
        """What the map holds (the header's ``CONTENT``)."""
        return str(self.meta.get("content", ""))

    @property
    def observatory(self):
        """Always "gongsynth": these are simulations, not observations."""
        return "gongsynth"

    @classmethod
    def is_datasource_for(cls, data, header, **kwargs):
        """
        Whether a file was written by gongsynth (``ORIGIN = 'gongsynth'``).

        Parameters
        ----------
        data : array_like
            Unused.
        header : dict-like
            The FITS header.
        **kwargs
            Unused.

        Returns
        -------
        bool
        """
        return str(header.get("origin", "")).strip().lower() == "gongsynth"
