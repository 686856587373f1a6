"""
Sphinx configuration for the gongsynth documentation.

Build (warnings are errors, every gallery example is executed)::

    python -m sphinx -W --keep-going -b html docs docs/_build/html

The build needs no network: intersphinx is off unless
``GONGSYNTH_DOCS_INTERSPHINX=1`` is set, and the sunpy theme's remote search
and analytics are switched off.
"""
import importlib.util
import os
import re
import shutil
import sys
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # examples must never open a window

DOCS = Path(__file__).parent
sys.path.insert(0, str(DOCS / "_ext"))
# The gallery's real-data examples read the project's shared/data/real, kept
# beside the repository (never in it); a user may point elsewhere.
os.environ.setdefault("GONGSYNTH_REAL_DATA", str(DOCS.parent.parent / "shared" / "data" / "real"))

import gongsynth  # noqa: E402

# -- Project -----------------------------------------------------------------
project = "gongsynth"
author = "The gongsynth developers"
copyright = "2026, The gongsynth developers"  # noqa: A001
release = gongsynth.__version__
version = ".".join(release.split(".")[:2])

# -- General -----------------------------------------------------------------
extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "sphinx_automodapi.automodapi",
    "sphinx_automodapi.smart_resolver",
    "sphinx_gallery.gen_gallery",
    "gongsynth_params",
    "gongsynth_config",
    "gongsynth_layout",
    "sphinxarg.ext",
    "gongsynth_validation",
]
# MathJax served from the built site itself, so equations render offline; without
# the package the pages fall back to MathJax from its CDN (renders when online).
if importlib.util.find_spec("sphinx-mathjax-offline") is not None:
    extensions.append("sphinx-mathjax-offline")
if os.environ.get("GONGSYNTH_DOCS_INTERSPHINX") == "1":  # needs the network
    extensions.append("sphinx.ext.intersphinx")
    intersphinx_mapping = {
        "python": ("https://docs.python.org/3/", None),
        "numpy": ("https://numpy.org/doc/stable/", None),
        "astropy": ("https://docs.astropy.org/en/stable/", None),
        "sunpy": ("https://docs.sunpy.org/en/stable/", None),
        "matplotlib": ("https://matplotlib.org/stable/", None),
        "dask": ("https://docs.dask.org/en/stable/", None),
    }

source_suffix = {".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "**.ipynb_checkpoints", "generated/gallery/*.ipynb",
                    "generated/gallery/*.py", "generated/gallery/*.zip",
                    "generated/gallery/*.md5", "generated/gallery/*.codeobj.json"]
templates_path = ["_templates"]
# `Quantity`-style single backticks in docstrings are object references; an
# unresolved one (third-party, without intersphinx) renders as code, no warning.
default_role = "obj"
nitpicky = False
suppress_warnings = []

# -- autodoc / napoleon / automodapi -------------------------------------------
autoclass_content = "class"
autodoc_typehints = "none"  # units live in the docstrings, not in annotations
autodoc_member_order = "bysource"
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
napoleon_use_ivar = True
automodapi_toctreedirnm = "api"
# automodapi writes one page per object into docs/api but never removes the page
# of an object that left a module's __all__; start from an empty folder.
shutil.rmtree(DOCS / automodapi_toctreedirnm, ignore_errors=True)
automodapi_writereprocessed = False
automodsumm_inherited_members = False
numpydoc_show_class_members = False

# -- sphinx-gallery ------------------------------------------------------------
sphinx_gallery_conf = {
    "examples_dirs": "../examples",
    "gallery_dirs": "generated/gallery",
    "filename_pattern": r"plot_",
    "ignore_pattern": r"__init__\.py",
    "abort_on_example_error": True,
    "only_warn_on_example_error": False,
    "plot_gallery": "True",
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "reset_modules": ("matplotlib",),
    "remove_config_comments": True,
    "download_all_examples": False,
    "show_signature": False,
    "doc_module": ("gongsynth",),
    "reference_url": {"gongsynth": None},
    "backreferences_dir": "generated/modules",
    "within_subsection_order": "gongsynth_gallery.StoryOrder",
    "min_reported_time": 1,
    # Two examples at a time (joblib processes): in CI the documentation builds beside the tests and
    # outlives them by minutes, when one example process would leave the second core idle.
    "parallel": 2,
    # Show printed output, not the repr of a cell's last expression (Legend objects...).
    "capture_repr": (),
}
# Examples run headless; a plt.show() at the end of a script is a no-op under Agg.
warnings.filterwarnings(
    "ignore", category=UserWarning,
    message="(Matplotlib is currently using agg|FigureCanvasAgg is non-interactive)",
)

# -- HTML ----------------------------------------------------------------------
html_theme = "sunpy"
html_title = f"gongsynth {release}"
html_static_path = ["_static"]
html_css_files = ["gongsynth.css"]
html_theme_options = {
    # Offline build and pages: no sunpy.org search, no analytics beacons.
    "rtd_search": False,
    "goatcounter_analytics_url": False,
    "sst_is_root": True,
    "sst_project_name": "gongsynth",
    "navbar_links": [
        ["User guide", "guide/index.html", 1],
        ["Gallery", "generated/gallery/index.html", 1],
        ["API", "api.html", 1],
        ["Validation", "validation.html", 1],
    ],
    "footer_links": [
        ["Changelog", "changelog.html", 1],
        ["Citation", "citation.html", 1],
    ],
}
html_last_updated_fmt = None
ogp_site_url = "https://gongsynth.readthedocs.io/"
ogp_use_first_image = False

# sphinxext-opengraph (loaded by the theme): no generated social-card images.
ogp_social_cards = {"enable": False}


# -- Docstring conventions --------------------------------------------------------
# gongsynth docstrings write magnitudes as |B| or |true B|, readable in a
# terminal.  In RST |...| is a substitution reference (an error under -W), so
# escape such pairs in prose (docstrings and gallery text), leaving code
# (`...`), doctests, literal blocks, directive bodies and tables alone.
_BARS = re.compile(r"(?<![\\|])\|(?=[^\s|])([^|`\n]*?[^\s|\\])\|(?!\|)")


def _escape_magnitude_bars(app, what, name, obj, options, lines):
    literal_indent = None
    for i, line in enumerate(lines):
        stripped = line.lstrip()
        indent = len(line) - len(stripped)
        if literal_indent is not None:
            if stripped and indent <= literal_indent:
                literal_indent = None
            else:
                continue
        if stripped.endswith("::") or (stripped.startswith(".. ") and "::" in stripped):
            literal_indent = indent  # literal block or directive body: leave it alone
            continue
        # doctests, line blocks ("| text") and grid tables stay as they are
        if not stripped or stripped == "|" or stripped.startswith((">>>", "...", "| ", "+-", "+=")):
            continue
        parts = line.split("`")
        parts[::2] = [_BARS.sub(r"\\|\1\\|", part) for part in parts[::2]]
        lines[i] = "`".join(parts)


def _escape_gallery_bars(app, docname, source):
    """The same for the prose of gallery examples (their generated RST pages)."""
    if docname.startswith("generated/gallery/"):
        lines = source[0].split("\n")
        _escape_magnitude_bars(app, "gallery", docname, None, None, lines)
        source[0] = "\n".join(lines)


# -- Roles used by third-party docstrings we inherit ----------------------------
def setup(app):
    """Render sphinxcontrib-bibtex's :cite:t: / :cite:p: as the plain citation key.

    sunpy's GenericMap appends a note citing ``:cite:t:`...``` to the docstring
    of every map subclass, so gongsynth's map source inherits it.
    """
    from docutils import nodes
    from sphinx.domains import Domain

    def as_text(name, rawtext, text, lineno, inliner, options=None, content=None):
        return [nodes.emphasis(rawtext, text)], []

    class CitationAsText(Domain):
        name = "cite"
        label = "citations rendered as their key"
        roles = {"t": as_text, "p": as_text}

    app.add_domain(CitationAsText)
    app.connect("autodoc-process-docstring", _escape_magnitude_bars)
    app.connect("source-read", _escape_gallery_bars)
