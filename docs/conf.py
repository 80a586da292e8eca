"""Sphinx configuration of the adaptive_dd documentation.

Build (from the repository's root, with ``pip install -e ".[docs]"``)::

    python -m sphinx -W --keep-going -b html docs docs/_build/html

Generated at build time (and ignored by git): ``docs/api/`` (the curated reference of
``docs/_ext/api_list.py``, one page per object, and the list of internal modules), ``docs/guide/scenario_keys.md`` (every scenario key, from
the tables the scenario checks use) and ``docs/auto_examples/`` (the gallery, run by
sphinx-gallery).
"""

from __future__ import annotations

import os
import sys
import warnings
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(DOCS / "_ext"))
os.environ.setdefault("MPLBACKEND", "Agg")

import adaptive_dd  # noqa: E402

# numpydoc reports a docstring section it does not know (and drops it) as a Python warning, which
# Sphinx's -W does not see: make it stop the build instead.
warnings.filterwarnings("error", message="Unknown section", category=UserWarning)

project = "adaptive_dd"
author = "the adaptive_dd contributors"
copyright = "2026, the adaptive_dd contributors"
release = version = adaptive_dd.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "apigen",  # docs/_ext/apigen.py: docs/api/ from the curated list docs/_ext/api_list.py
    "scenario_keys",  # docs/_ext/scenario_keys.py: docs/guide/scenario_keys.md from the checks' tables
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "auto_examples/*.ipynb", "auto_examples/*.py"]
templates_path = ["_templates"]
suppress_warnings = ["myst.header"]  # the older guide pages start at "##"

myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3

autosummary_generate = True
autosummary_imported_members = False
autodoc_typehints = "none"  # numpydoc's Parameters sections carry the types
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples" / "gallery"),
    "gallery_dirs": str(DOCS / "auto_examples"),
    "filename_pattern": r"/plot_",
    "within_subsection_order": "FileNameSortKey",
    "download_all_examples": False,
    "remove_config_comments": True,
    "matplotlib_animations": False,
    "reset_modules": ("matplotlib",),
    "capture_repr": (),
    "abort_on_example_error": True,
}

html_theme = "pydata_sphinx_theme"
html_title = f"adaptive_dd {release}"
html_theme_options = {
    "navigation_depth": 2,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_static_path: list[str] = []
html_show_sourcelink = False


REAL_LOG_TEXT = "The guide's pages on identification list the\ncommands for records of a real arm."


def _list_real_log(app, docname, source):
    """Link ``real_log`` (identification from a real arm's log) from the identification
    guide's contents and from Getting started once the page exists; until then it is left out
    rather than broken."""
    if not (DOCS / "real_log.md").exists():
        return
    if docname == "guide/identification":
        entry = "../identification_urdf\n"
        source[0] = source[0].replace(entry, entry + "../real_log\n", 1)
    elif docname == "getting_started":
        source[0] = source[0].replace(REAL_LOG_TEXT, "Records of a real arm, step by step: {doc}`real_log`.")


def _reread_on_real_log(app, env, added, changed, removed):
    """Read the pages that link ``real_log`` or the other pages again when a page appears or goes
    (incremental builds)."""
    if not any("/" not in d for d in added | removed):
        return []
    return ["guide/identification", "getting_started", "guide/index"]


LISTED = {"index", "getting_started", "results", "limits", "changelog", "real_log"}


def _other_pages() -> list[str]:
    """Top-level pages of docs/ that no contents list names (a page another branch adds): the
    user guide lists them under its own, so a new page is never left out of the site."""
    guide = ("index.md", "estimators.md", "identification.md")
    text = "".join((DOCS / "guide" / f).read_text() for f in guide)
    return sorted(p.stem for p in DOCS.glob("*.md") if p.stem not in LISTED and f"../{p.stem}\n" not in text)


def _list_other_pages(app, docname, source):
    if docname == "guide/index" and _other_pages():
        extra = "".join(f"../{name}\n" for name in _other_pages())
        source[0] = source[0].replace("library\n```", "library\n" + extra + "```", 1)


def _skip_borrowed_docs(app, what, name, obj, skip, options):
    """Leave out class members whose only text is not theirs: a named tuple's "Alias for field
    number N", or a builtin type's docstring shown for a member without one."""
    if isinstance(obj, property) and not (obj.fget is not None and obj.fget.__doc__):
        return True  # autodoc would show the docstring of what a base class holds under the name
    doc = getattr(obj, "__doc__", None) or ""
    if doc.startswith("Alias for field number") or any(doc == t.__doc__ for t in (bool, int, float, str)):
        return True
    return skip


def setup(app):
    app.connect("autodoc-skip-member", _skip_borrowed_docs)
    app.connect("source-read", _list_real_log)
    app.connect("source-read", _list_other_pages)
    app.connect("env-get-outdated", _reread_on_real_log)
