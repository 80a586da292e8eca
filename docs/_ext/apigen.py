"""Write the API reference: the curated objects by task, and the internals apart.

``docs/api/index.rst`` lists the objects of :mod:`api_list` (``docs/_ext/api_list.py``) grouped
by task, each with its one-line summary (autosummary) and its own page rendered by numpydoc.
``docs/api/internals.rst`` names every other public module with the first line of its
docstring, without pages: they are importable and documented in their source, but not part of
what a user needs. The pages are rewritten at every build, so the reference follows the list.
"""

from __future__ import annotations

import importlib
import pkgutil
import shutil
from pathlib import Path

from api_list import GROUPS, listed

PACKAGE = "adaptive_dd"
TOP_LEVEL = ("Simulation", "run_trial", "load_scenario", "run_benchmark", "make_controller")


def public_modules() -> list[str]:
    """Every importable module of the package whose dotted name has no ``_``-prefixed part."""
    pkg = importlib.import_module(PACKAGE)
    names = [PACKAGE]
    for info in pkgutil.walk_packages(pkg.__path__, PACKAGE + "."):
        if not any(part.startswith("_") for part in info.name.split(".")):
            names.append(info.name)
    return sorted(names)


def _summary(module: str) -> str:
    """The module docstring's first paragraph, its cross-references as literals (an internal's
    target may have no page: ``:func:`~a.b.c``` reads ``c``; a role's backticks were turned into
    quotes, which the page printed curly around the role's name)."""
    import re

    doc = importlib.import_module(module).__doc__ or ""
    first = doc.strip().split("\n\n")[0].replace("\n", " ").strip()

    def literal(m: re.Match) -> str:
        target = m.group(2)
        return f"``{target.rsplit('.', 1)[-1] if m.group(1) else target}``"

    first = re.sub(
        r":[a-z]+:`(~?)([^`]+)`", lambda m: literal(m) if m.group(1) else f"``{m.group(2)}``", first
    )
    first = re.sub(r"(?<!`)`([^`<]+)`(?![`_])", r"``\1``", first)  # a name in `...`: a literal (not a link)
    return first or "(no docstring)"


def index_page() -> str:
    """The reference's index: one section per task, an autosummary table of its objects."""
    lines = [
        "API reference",
        "=============",
        "",
        "The objects a user needs, by task, each with its own page (parameters with shapes and",
        "units, what it returns, the errors it raises and an example that runs). The most used",
        "are importable from the package itself: "
        + ", ".join(f"``adaptive_dd.{n}``" for n in TOP_LEVEL)
        + ", and the errors.",
        "",
        "What a plug-in controller receives: :doc:`../controllers`. Every other module is an",
        "internal, listed in :doc:`internals`.",
        "",
    ]
    for title, summary, names in GROUPS:
        lines += [title, "-" * len(title), "", summary, "", ".. autosummary::"]
        lines += ["   :toctree: generated", "   :nosignatures:", ""]
        lines += [f"   {n}" for n in names] + [""]
    lines += [".. toctree::", "   :hidden:", "", "   internals", ""]
    return "\n".join(lines)


def internals_page(modules: list[str]) -> str:
    """Every public module, with the first paragraph of its docstring; no pages of their own."""
    homes = {n.rpartition(".")[0] for n in listed()}
    lines = [
        "Internals",
        "=========",
        "",
        "The package's other modules: importable, each with its docstrings in the source, but",
        "not part of the reference (their names may change between versions). Modules that hold",
        "a listed object are marked with a star.",
        "",
        ".. list-table::",
        "   :header-rows: 1",
        "   :widths: 35 65",
        "",
        "   * - module",
        "     - what it holds",
    ]
    for m in modules:
        star = " (*)" if m in homes else ""
        lines += [f"   * - ``{m}``{star}", f"     - {_summary(m)}"]
    return "\n".join(lines) + "\n"


def _write(path: Path, text: str) -> None:
    if not path.exists() or path.read_text() != text:  # unchanged pages keep their mtime
        path.write_text(text)


def generate(app) -> None:
    out = Path(app.srcdir) / "api"
    out.mkdir(exist_ok=True)
    for page in out.glob("*.rst"):  # the pages of another layout go
        if page.stem not in {"index", "internals"}:
            page.unlink()
    _write(out / "index.rst", index_page())
    _write(out / "internals.rst", internals_page(public_modules()))
    # autosummary's pages of each object: written afresh, so a removed object's page goes too
    shutil.rmtree(out / "generated", ignore_errors=True)


def setup(app):
    generate(app)  # at setup, before Sphinx lists the source files (autosummary reads them then)
    return {"parallel_read_safe": True, "version": "2"}
