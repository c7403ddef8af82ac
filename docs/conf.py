"""Sphinx configuration of the dustoptics documentation.

Build (from the repository root; warnings are errors)::

    python -m sphinx -W --keep-going -b html docs docs/_build/html

Every example runs during that build: the gallery scripts in ``docs/examples``
(sphinx-gallery, with their figures), the ``>>>`` examples of the pages
(``docs/_ext/run_examples.py``) and the commands shown with ``.. dustoptics-command::``.
The command-line reference is generated from the argument parser itself
(``docs/_ext/argparse_reference.py``) and the API reference from the docstrings
(autodoc, autosummary, numpydoc).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

# numba reads its threading layer and caching choices at import; a build on a
# shared machine keeps to one thread per wavelength pool as the tests do.
os.environ.setdefault("MPLBACKEND", "Agg")

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))

import dustoptics  # noqa: E402

project = "dustoptics"
author = "dustoptics developers"
copyright = "dustoptics developers"
release = dustoptics.__version__
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.intersphinx",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
    "argparse_reference",
    "format_table",
    "run_examples",
    "engine_table",
]

# Warnings are errors (-W): references that cannot resolve must be fixed, not hidden.
nitpicky = False
# numpydoc turns each References entry into a citation that the text need not
# cite (the docstrings list their sources without footnote marks).
suppress_warnings = ["ref.citation"]
exclude_patterns = ["_build", "examples/README.rst"]
templates_path = ["_templates"]
# _static/custom.css: literal blocks wrap long lines instead of cutting them.
html_static_path = ["_static"]
html_theme = "alabaster"
html_theme_options = {
    "description": "Exact, reproducible optics of atmospheric dust",
    "fixed_sidebar": True,
    # Room for 100-column code (the project's line length) beside the sidebar: the body
    # takes the page's width (the basic theme would stop it at 800 px).
    "page_width": "1240px",
    "sidebar_width": "250px",
    "body_max_width": "none",
}
html_title = f"dustoptics {release}"
html_show_sourcelink = False

# ------------------------------------------------------------------ API reference
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"members": True, "show-inheritance": False}
autodoc_typehints = "none"  # numpydoc's Parameters sections carry the types
autodoc_member_order = "bysource"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

# No network during a build: intersphinx has no inventories to fetch.
intersphinx_mapping: dict[str, tuple[str, str | None]] = {}

# ------------------------------------------------------------------ gallery
sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    # A failing example fails the build.
    "abort_on_example_error": True,
    "only_warn_on_example_error": False,
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "reset_modules": ("matplotlib",),
    "show_memory": False,
    "plot_gallery": "True",
}
