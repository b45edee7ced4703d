"""Sphinx configuration of the empact site (`make docs`; warnings are errors)."""
from __future__ import annotations

import importlib
import os
import sys
from pathlib import Path

os.environ.setdefault("MPLBACKEND", "Agg")
HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from _apipages import write_api_pages  # noqa: E402

import empact  # noqa: E402

project = "empact"
author = "The empact maintainers"
copyright = "2026, The empact maintainers"
release = version = empact.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "numpydoc",
    "matplotlib.sphinxext.plot_directive",
    "sphinx_gallery.gen_gallery",
]

exclude_patterns = ["_build", "**.ipynb_checkpoints", "sg_execution_times.rst"]
templates_path = ["_templates"]
default_role = "py:obj"     # docstrings write `name` for a Python object
nitpicky = False

# --- API pages: one per subpackage, from its __all__ (docs/api/*.rst are generated) ----------
write_api_pages(HERE / "api")
autosummary_generate = True
autosummary_imported_members = True
autodoc_default_options = {"members": False}
autodoc_typehints = "none"          # numpydoc's Parameters sections carry the types
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

# --- figures drawn at build time by the package's own plotting functions ------------------------
plot_include_source = True
plot_html_show_source_link = False
plot_html_show_formats = False
plot_formats = [("png", 100)]
plot_rcparams = {"figure.autolayout": False}

# --- the gallery: examples/plot_*.py, each run when the docs build ------------------------------
sphinx_gallery_conf = {
    "examples_dirs": str(HERE.parent / "examples"),
    "gallery_dirs": str(HERE / "gallery"),
    "filename_pattern": r"/plot_",
    "within_subsection_order": "FileNameSortKey",
    "download_all_examples": False,
    "remove_config_comments": True,
    "matplotlib_animations": False,
    "image_scrapers": ("_scraper.plot_scraper", "_scraper.pyplot_scraper"),
    "reset_modules": ("matplotlib",),
    "abort_on_example_error": True,
    "show_memory": False,
    "capture_repr": ("_repr_html_", "__repr__"),
    "min_reported_time": 1,
    "write_computation_times": False,
}

html_theme = "pydata_sphinx_theme"
html_title = f"empact {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": [],
}
html_show_sourcelink = False
# nothing wider than its column (tests/test_docs_site.py): long names break, code is set a
# little smaller, and the API pages, whose docstrings hold code and diagrams of up to 110
# columns, give the article the width of the section navigation (the navbar links the
# pages; the page's own contents stay on the right)
html_static_path = ["_static"]
html_css_files = ["empact.css"]
html_sidebars = {"api/**": []}

# the docs import every public module; importing here fails the build early with its name
for _name in empact.SUBMODULES:
    importlib.import_module(f"empact.{_name}")

from _claims import write_sections_table  # noqa: E402

write_sections_table(HERE / "reproduction_sections.inc")
