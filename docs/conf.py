"""Sphinx configuration of the documentation site (``docs/``).

Build: ``python -m sphinx -W --keep-going -b html docs docs/_build/html`` (warnings fail;
``tests/test_docs.py`` runs it). Pages are Markdown (myst-parser); the Python reference comes from
the docstrings (autodoc + napoleon, Google style), the CLI page from ``app.cli.build_parser()``
(sphinx-argparse), and three pages are generated at build time by ``docs/_ext/generated.py``
into ``docs/_generated/`` (git-ignored): the Python API of ``core.__all__``, the HTTP API from
``app.api.create_api().openapi()`` and the benchmark tables from ``bench/results/*.json``.
"""

from __future__ import annotations

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(DOCS / "_ext"))

project = "Ellipse & ellipsoid interference"
author = "the ellipsoid-interference authors"
copyright = "the ellipsoid-interference authors, BSD-3-Clause"  # noqa: A001  (Sphinx's name)
release = "0.1.0"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinxarg.ext",
    "generated",
]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
exclude_patterns = ["_build", "_generated", "data", "img/README.md", "**/__pycache__"]
myst_enable_extensions = ["colon_fence", "dollarmath", "deflist"]
myst_heading_anchors = 3
suppress_warnings = ["myst.header", "myst.domains"]  # sphinx-argparse's domain has no resolve_any_xref

html_theme = "furo"
html_title = "Ellipse & ellipsoid interference"
html_static_path: list[str] = []

autodoc_typehints = "description"
autodoc_member_order = "bysource"
autodoc_inherit_docstrings = False
napoleon_google_docstring = True
napoleon_numpy_docstring = False
napoleon_use_rtype = False
# nitpicky is off: type hints name numpy and flint types that have no page here
