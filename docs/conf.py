"""Sphinx configuration of bsdfkit's documentation (built by scripts/docs with -W)."""
import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))
if not any((Path(p) / "bsdfkit" / "__init__.py").exists() for p in sys.path if p):
    sys.path.insert(1, str(HERE.parent / "python"))   # a source tree with the extension built in place

import bsdfkit  # noqa: E402

project = "bsdfkit"
author = "the bsdfkit authors"
copyright = "the bsdfkit authors"
release = bsdfkit.__version__
version = ".".join(release.split(".")[:2])

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "myst_parser",
    "matplotlib.sphinxext.plot_directive",
    "bsdfkit_docs",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "SPECTRAL.md", "**/*.rst.inc", "README.md"]
templates_path = ["_templates"]
html_static_path = ["_static"]
html_theme = "furo"
html_title = f"bsdfkit {release}"

myst_enable_extensions = ["dollarmath"]
myst_heading_anchors = 3
autosummary_generate = True
autosummary_imported_members = True
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_ivar = True   # Attributes as fields: no second description of a dataclass's fields
nitpicky = False
suppress_warnings = ["myst.header"]

# matplotlib's plot directive (the gallery): figures drawn at build time from the code shown
plot_formats = [("png", 80)]
plot_html_show_formats = False
plot_html_show_source_link = False
plot_rcparams = {"figure.max_open_warning": 0}

# The notebook gallery (docs/gallery/, generated) shows the notebooks with the outputs they are
# committed with; scripts/docs --notebooks re-executes them in place first.
