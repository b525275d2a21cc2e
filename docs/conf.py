"""Sphinx configuration of the eclipsebench documentation (``make docs``).

The chapters are the Markdown pages of this folder (read by myst-parser);
the API reference is generated from the docstrings (autodoc, autosummary,
numpydoc). The build imports the checkout's own code (``../src``), so the
reference always describes the code beside it.
"""

from __future__ import annotations

import sys
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"
if str(SRC) not in sys.path:
    sys.path.insert(0, str(SRC))

import eclipsebench  # noqa: E402

project = "eclipsebench"
author = "the eclipsebench developers"
copyright = "the eclipsebench developers, BSD 3-Clause"  # noqa: A001 - Sphinx's name
release = version = eclipsebench.__version__

extensions = [
    "myst_parser",            # the Markdown chapters
    "sphinx.ext.autodoc",     # the API reference from the docstrings
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",               # numpydoc docstrings (the astropy-affiliated convention)
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
# benchmarks-history.md: the old benchmark notebook kept verbatim (git has it too); not a
# chapter of the site, and its headings are the notebook's, not the site's.
exclude_patterns = ["_build", "_templates", "benchmarks-history.md"]

# The Markdown pages were written for GitHub: ```` ``` ```` blocks without a
# language are plain text, "Heading" anchors are made for levels 1-3.
highlight_language = "none"
myst_heading_anchors = 3
myst_enable_extensions = ["dollarmath"]

autosummary_generate = True
autodoc_typehints = "none"           # numpydoc's Parameters section says the types
autodoc_member_order = "bysource"
numpydoc_show_class_members = False  # no stub page per method of every class
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

html_theme = "alabaster"
html_title = f"eclipsebench {release}"
html_static_path: list[str] = []
templates_path = ["_templates"]
