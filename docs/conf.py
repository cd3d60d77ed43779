"""Sphinx configuration of the discrepancy documentation (``make docs``).

The API reference is written from the package at each build (``_ext/api_pages.py``); the
gallery's examples (``examples/``) run during the build (sphinx-gallery); warnings are errors
(``make docs`` passes ``-W --keep-going``) and every Python reference must resolve
(``nitpicky``), except references into other projects, which cannot be linked offline.
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))

from sphinx.ext.napoleon.docstring import GoogleDocstring  # noqa: E402

import discrepancy  # noqa: E402

project = "discrepancy"
author = "the discrepancy developers"
copyright = "the discrepancy developers"  # noqa: A001
release = discrepancy.__version__
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "sphinx_gallery.gen_gallery",
    "myst_parser",
    "api_pages",
]
api_package = "discrepancy"

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "**/sg_execution_times.rst.bak",
                    "auto_examples/*.ipynb", "auto_examples/*.py"]
templates_path = []

# -- API reference ---------------------------------------------------------------------------
autosummary_generate = False          # the pages are written by api_pages
autodoc_member_order = "groupwise"
autodoc_typehints = "description"
autodoc_typehints_description_target = "documented_params"
autodoc_class_signature = "mixed"
autodoc_inherit_docstrings = True
autodoc_preserve_defaults = True
napoleon_google_docstring = True      # the docstrings use Google style ("Args:")
napoleon_numpy_docstring = False
napoleon_use_rtype = False
napoleon_attr_annotations = True
napoleon_use_ivar = True          # "Attributes:" as fields: no second entry for a dataclass field
add_module_names = False
toc_object_entries_show_parents = "hide"
python_maximum_signature_line_length = 88

# Broken references fail the build. Objects of other projects cannot be linked offline
# (intersphinx downloads their inventories): api_pages lets references into any imported
# module or these aliases through; builtins, names from annotations (typing) and private
# names (undocumented by design) are listed here. Everything under discrepancy must resolve.
nitpicky = True
api_foreign_aliases = ("np", "sp", "ca", "plt", "mpl", "da")
BUILTINS = r"(int|float|bool|str|bytes|dict|list|tuple|set|frozenset|object|type|None" \
           r"|slice|callable|complex|Ellipsis|NotImplemented|[A-Za-z]*Error|[A-Za-z]*Warning" \
           r"|Exception|BaseException|Path|Callable|Iterable|Iterator|Sequence|Mapping|Any" \
           r"|ABC|ArrayLike|NDArray)"
nitpick_ignore_regex = [
    (r"py:.*", BUILTINS),
    (r"py:.*", r"(.*\.)?_[A-Za-z]\w*"),      # private names and bases
]



def _prose_attribute(self):
    """Property docstrings here are prose ("The parameters in use: ``params``, ..."), never
    napoleon's ``type: description`` (the type comes from the annotation); napoleon would
    read everything before the first colon as a type."""
    lines = [self._lines.next(), *self._dedent(self._consume_to_end())]
    return "", self.__class__(lines, self._config).lines()


GoogleDocstring._consume_inline_attribute = _prose_attribute

# -- Gallery ---------------------------------------------------------------------------------
sphinx_gallery_conf = {
    "examples_dirs": str(HERE.parent / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"\.py$",             # every example runs at every build
    "within_subsection_order": "FileNameSortKey",
    "doc_module": ("discrepancy",),
    "backreferences_dir": "api/backreferences",
    "image_scrapers": ("matplotlib",),
    "min_reported_time": 0,
    "remove_config_comments": True,
    "abort_on_example_error": False,          # run all, then fail the build on any error
    "only_warn_on_example_error": False,
    "show_memory": False,
    "download_all_examples": False,
    "show_signature": False,
}
os.environ.setdefault("MPLBACKEND", "Agg")

# -- HTML ------------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"discrepancy {release}"
html_static_path = ["_static"]
html_css_files = ["custom.css"]
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_show_sourcelink = False
myst_heading_anchors = 3
