"""
What `sunpy.map.Map` makes of a file, as a short comparable string.

Run as a script (``python tests/map_outcomes.py ROOT FILE...``) it prints, as JSON,
the outcome for every file in a fresh interpreter that never imports gongsynth:
the baseline against which ``test_map_sources.py`` compares the outcome with
gongsynth imported (sunpy issue 7294: a package's map source that also matches
real files makes ``Map`` raise ``MultipleMatchError`` for everyone who imports it).
This module must not import gongsynth.
"""
import json
import sys
import warnings
from pathlib import Path

__all__ = ["map_outcome"]


def map_outcome(path):
    """
    The class name `sunpy.map.Map` gives ``path``, or the exception it raises.

    Returns
    -------
    str
        ``"HMIMap"``, ``"A,B"`` for a file with several image HDUs, or
        ``"raises MapMetaValidationError"`` (e.g. old GONG headers without CUNIT,
        which sunpy refuses after choosing the class; ``MultipleMatchError`` when
        two sources claim the file).
    """
    import sunpy.map

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # header fixes of old files; not what is tested
        try:
            smap = sunpy.map.Map(path)
        except Exception as error:  # the outcome to compare, whatever it is
            return f"raises {type(error).__name__}"
    maps = smap if isinstance(smap, list) else [smap]
    return ",".join(type(m).__name__ for m in maps)


if __name__ == "__main__":
    root = Path(sys.argv[1])
    outcomes = {name: map_outcome(root / name) for name in sys.argv[2:]}
    if "gongsynth" in sys.modules:
        sys.exit("map_outcomes.py: gongsynth was imported; the baseline must be sunpy alone")
    print(json.dumps(outcomes))
