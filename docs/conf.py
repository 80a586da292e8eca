"""Sphinx configuration of the adaptive_dd documentation.

Build (from the repository's root, with ``pip install -e ".[docs]"``)::

    python -m sphinx -W --keep-going -b html docs docs/_build/html

Generated at build time (and ignored by git): ``docs/api/`` (the curated reference of
``docs/_ext/api_list.py``, one page per object, and the list of internal modules),
``docs/guide/scenario_keys.md`` (every scenario key, from the tables the scenario checks use)
and ``docs/auto_examples/`` (the gallery, run by sphinx-gallery).
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
    "figure_count",  # docs/_ext/figure_count.py: the built site's figures counted, alt text checked
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "auto_examples/*.ipynb", "auto_examples/*.py"]
templates_path = ["_templates"]
suppress_warnings = ["myst.header"]  # the changelog quotes old rounds' notes with their own heading levels

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
    "header_links_before_dropdown": 7,
    "navigation_depth": 2,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_static_path: list[str] = []
html_show_sourcelink = False


LANDING = ("tutorials", "howto", "reference", "background")
"""The four sections of the site: each lists its pages in a toctree."""


def _toctree_entries() -> set[str]:
    """Every document some toctree of the hand-written pages names (as a path from docs/)."""
    found = set()
    for page in DOCS.rglob("*.md"):
        if "_build" in page.parts:
            continue
        text = page.read_text(encoding="utf-8")
        for block in text.split("```{toctree}")[1:]:
            for line in block.split("```")[0].splitlines():
                line = line.strip()
                if line and not line.startswith(":"):
                    target = (page.parent / line).resolve()
                    found.add(target.relative_to(DOCS.resolve()).as_posix())
    return found


def _other_pages() -> list[str]:
    """Top-level pages of docs/ that no toctree names (a page another branch adds): the how-to
    section lists them at its end, so a new page is never left out of the site."""
    listed = _toctree_entries() | {"index"}
    return sorted(p.stem for p in DOCS.glob("*.md") if p.stem not in listed)


def _list_other_pages(app, docname, source):
    if docname == "howto" and _other_pages():
        head, sep, tree = source[0].partition("```{toctree}")
        body, fence, tail = tree.partition("\n```")  # the toctree's closing fence
        extra = "".join(f"\n{name}" for name in _other_pages())
        source[0] = head + sep + body + extra + fence + tail


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
    app.connect("source-read", _list_other_pages)
