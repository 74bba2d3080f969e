"""Sphinx configuration of the superfacets documentation (``make docs``)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))  # _cli.py: the command-line page, made from the parser

import superfacets  # noqa: E402

os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

project = "superfacets"
author = "superfacets developers"
copyright = "2026, superfacets developers"
release = version = superfacets.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "results", "guide/parameter_table.md", "examples/README.rst",
                    "auto_examples/*.ipynb",
                    "auto_examples/*.py", "auto_examples/*.zip", "**/*.md5",
                    "auto_examples/*.codeobj.json", "sg_execution_times.rst"]
root_doc = "index"

autosummary_generate = True
autodoc_default_options = {"members": False}
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_validation_checks = set()  # the tests check the sections (tests/test_docstrings.py)

myst_heading_anchors = 3
myst_enable_extensions = ["dollarmath"]

sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "image_scrapers": ("matplotlib",),
    "within_subsection_order": "FileNameSortKey",
    "download_all_examples": False,
    "remove_config_comments": True,
    "show_memory": False,
    "reference_url": {},
    "write_computation_times": False,  # (its page loads scripts from CDNs: none offline)
}

html_theme = "pydata_sphinx_theme"
html_title = f"superfacets {release}"
html_theme_options = {"navigation_with_keys": False, "show_toc_level": 2,
                      "secondary_sidebar_items": ["page-toc"],
                      # (the search as a button: the top bar's links on one line at 1,280 px)
                      "navbar_persistent": ["search-button"]}
html_static_path = ["_static"]
html_css_files = ["custom.css"]
#: No navigation sidebar on the pages at the top of the site (it had nothing to list)
html_sidebars = {"index": [], "benchmarks": [], "changelog": [], "api": [],
                 "auto_examples/index": [], "notes/index": []}
html_show_sourcelink = False


def setup(app):
    from _cli import write_cli_pages, write_parameter_table

    write_cli_pages(HERE / "guide" / "cli")
    write_parameter_table(HERE / "guide" / "parameter_table.md")
