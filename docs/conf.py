"""Sphinx configuration of fe_beam's documentation site (`./bootstrap docs`)."""

import os
import re
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(DOCS / "_ext"))
sys.path.insert(0, str(DOCS / "gallery"))  # the examples share docs/gallery/_gallery.py
sys.path.insert(0, str(ROOT))
os.environ.setdefault("FE_BEAM_PROGRESS", "0")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MPLBACKEND", "agg")

import fe_beam  # noqa: E402

project = "fe_beam"
author = "fe_beam developers"
copyright = "fe_beam developers, MIT licence"
release = version = fe_beam.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.viewcode",
    "sphinx_gallery.gen_gallery",
    "fe_beam_docs",
]

# technical text: "--set" stays two hyphens, quotes stay straight
smartquotes = False
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "notes", "gallery/README.rst", "Thumbs.db", ".DS_Store",
                    "auto_examples/*.ipynb", "auto_examples/*.py", "auto_examples/*.zip",
                    "auto_examples/*.json", "auto_examples/*.md5"]

myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 4

autosummary_generate = True
autosummary_imported_members = False
autosummary_ignore_module_all = False
autodoc_default_options = {"members": True, "show-inheritance": False}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_mock_imports = []
napoleon_google_docstring = False
napoleon_numpy_docstring = True

html_theme = "furo"
html_title = f"fe_beam {release}"
html_static_path = ["_static"]
templates_path = ["_templates"]
html_css_files = ["fe_beam.css"]
html_theme_options = {"sidebar_hide_name": False, "navigation_with_keys": True}
html_show_sourcelink = False

suppress_warnings = []
nitpicky = False

sphinx_gallery_conf = {
    "examples_dirs": "gallery",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "ignore_pattern": r"(^|/)_[^/]*\.py$",  # shared helpers (docs/gallery/_gallery.py)
    "abort_on_example_error": True,
    "only_warn_on_example_error": False,
    "download_all_examples": False,
    "remove_config_comments": True,
    "image_scrapers": ("matplotlib",),
    "matplotlib_animations": False,
    "reset_modules": ("matplotlib",),
    "within_subsection_order": "FileNameSortKey",
    "show_memory": False,
    "plot_gallery": "True",
    "capture_repr": (),
}


# fe_beam's docstrings are plain text with math such as |r - p| (absolute values), which reST
# would read as substitution references: escape a bar outside ``literals`` before autodoc parses.
_LITERAL = re.compile(r"(``.*?``)")


def _plain_bars(app, what, name, obj, options, lines):
    for i, line in enumerate(lines):
        if "|" in line:
            lines[i] = "".join(part if part.startswith("``") else part.replace("|", r"\|")
                               for part in _LITERAL.split(line))


def setup(app):
    app.connect("autodoc-process-docstring", _plain_bars)
