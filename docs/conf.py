"""Sphinx configuration of the scatterbench documentation site.

Build: ``python -m sphinx -W -b html docs OUT`` (``pip install ".[docs]"`` first).
The gallery runs its scripts at build time (sphinx-gallery); the API reference is
generated from the docstrings (autosummary + numpydoc), so it follows the code.
"""

import os
import sys
import tomllib
from importlib import metadata

import matplotlib

matplotlib.use("Agg")

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
# The site documents the installed ``scatterbench`` (its folders map under one namespace only
# through the installation: pyproject.toml's package-dir); to document a checkout, install it
# editable first (``pip install -e ".[docs]"``).
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "_ext"))

project = "scatterbench"
author = "scatterbench contributors"
copyright = "scatterbench contributors"  # noqa: A001 - Sphinx's name
_PYPROJECT = os.path.join(ROOT, "pyproject.toml")
if os.path.exists(_PYPROJECT):  # the checkout's version (it is the code documented)
    with open(_PYPROJECT, "rb") as _fh:
        release = version = tomllib.load(_fh)["project"]["version"]
else:
    release = version = metadata.version("scatterbench")

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "matplotlib.sphinxext.plot_directive",
    "sbdocs",
]
templates_path = ["_templates"]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "gallery", "auto_examples/*.ipynb", "auto_examples/*.py"]
myst_enable_extensions = ["colon_fence", "dollarmath", "deflist"]
myst_heading_anchors = 3

autosummary_generate = True
# importing validation/cli/__main__.py runs the CLI: autosummary must not import it
autosummary_mock_imports = ["scatterbench.validation.cli.__main__"]
autodoc_default_options = {"members": True, "inherited-members": False}
autodoc_typehints = "none"  # numpydoc's Parameters sections carry the types
numpydoc_show_class_members = False  # autosummary tables list the members
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False


sphinx_gallery_conf = {
    "examples_dirs": "gallery",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "within_subsection_order": "FileNameSortKey",
}

plot_include_source = True
plot_html_show_source_link = False
plot_html_show_formats = False
plot_formats = [("png", 100)]

html_theme = "pydata_sphinx_theme"
html_title = "scatterbench"
html_static_path = ["_static"]
html_theme_options = {
    "navigation_with_keys": False,
    "show_prev_next": True,
    "secondary_sidebar_items": ["page-toc"],
}
# an explicit mode: without it the theme logs "invalid theme mode" to the console on a first visit
html_context = {"default_mode": "light"}
html_show_sourcelink = False
html_copy_source = False
