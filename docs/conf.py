"""Sphinx configuration of the beatsync site (``make docs``).

Sphinx with myst-nb: the site is built by the same pinned Python environment as the
package (uv.lock), reads the committed, executed notebooks as they are
(``nb_execution_mode = "off"``), documents the API from the docstrings and the CLI from
its argparse parser, and every asset it writes is local: MathJax comes from the
``sphinx-mathjax-offline`` package, the furo theme uses the system's fonts, and the
ipywidgets loader (which myst-nb fetches from a CDN by default) is switched off:
widget outputs show their ``text/html`` form, precomputed sliders in plain HTML and
JavaScript (``beatsync.learn.widgets``).
"""

from __future__ import annotations

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))
sys.path.insert(0, str(DOCS.parent / "src"))

import beatsync  # noqa: E402

project = "beatsync"
author = "beatsync developers"
copyright = "beatsync developers (MIT licence)"
version = release = beatsync.__version__

extensions = [
    "beatsync_site",  # copies notebooks/ into docs/notebooks/ (docs/_ext)
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",  # MathJax 3 copied into _static/, mathjax_path set to it
    "sphinxarg.ext",
]

root_doc = "index"
exclude_patterns = ["_build", "**.ipynb_checkpoints", "README.md"]
templates_path: list[str] = []
html_static_path = ["_static"]
html_css_files = ["site.css"]
html_theme = "furo"
html_title = f"beatsync {release}"
html_last_updated_fmt = None
html_show_sourcelink = False
html_copy_source = False
smartquotes = False  # `--fps` stays two hyphens, quotes stay straight, as in `--help`

# --- MyST and the notebooks --------------------------------------------------------------
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
nb_execution_mode = "off"  # the committed outputs are the ones shown
# The ipywidgets views need a widget manager from a CDN: never loaded. A widget output
# that also carries text/html (the precomputed sliders) shows that instead.
nb_ipywidgets_js: dict[str, dict[str, str]] = {}
nb_mime_priority_overrides = [
    ("html", "application/vnd.jupyter.widget-view+json", None),
    ("html", "application/vnd.jupyter.widget-state+json", None),
]
nb_merge_streams = True

# --- API reference -----------------------------------------------------------------------
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_preserve_defaults = True
napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_rtype = False
# free-text sections of the package's docstrings, kept as headed paragraphs
napoleon_custom_sections = [
    ("Data contract", "notes_style"),
    ("Exit status", "notes_style"),
]

