"""Write the API reference's pages from the package's own ``__all__`` lists.

One page per public module (``docs/api/<module>.rst``): the module's docstring, then an
autosummary table of the functions, classes and exceptions it defines (each with its own
page, rendered by numpydoc), then the names it re-exports from elsewhere, linked to the
module that defines them (so no object is documented twice). Modules whose name starts
with ``_`` are private and skipped. The pages are rewritten at every build, so a new
public name appears without editing the docs.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import shutil
from pathlib import Path

PACKAGE = "adaptive_dd"
GROUPS = {
    "adaptive_dd": "The package and its command line",
    "adaptive_dd.plant": "Arms and plants",
    "adaptive_dd.identification": "Identification and estimation",
    "adaptive_dd.controllers": "Controllers",
    "adaptive_dd.closed_loop": "The N-joint closed loop",
    "adaptive_dd.benchmark": "The benchmark",
    "adaptive_dd.arena": "The leaderboard",
    "adaptive_dd.robots": "Shipped robots",
    "adaptive_dd.cli": "The command line (one module per command: its options and its run)",
}


def public_modules() -> list[str]:
    """Every importable module of the package whose dotted name has no ``_``-prefixed part."""
    pkg = importlib.import_module(PACKAGE)
    names = [PACKAGE]
    for info in pkgutil.walk_packages(pkg.__path__, PACKAGE + "."):
        if not any(part.startswith("_") for part in info.name.split(".")):
            names.append(info.name)
    return sorted(names)


def _home(obj) -> str | None:
    mod = getattr(obj, "__module__", None)
    if mod is None and hasattr(obj, "py_func"):  # a numba dispatcher
        mod = obj.py_func.__module__
    return mod


def _attribute_docs(name: str) -> set[str]:
    """Module-level names with a docstring or ``#:`` comment of their own."""
    from sphinx.pycode import ModuleAnalyzer

    try:
        docs = ModuleAnalyzer.for_module(name).find_attr_docs()
    except Exception:  # no source: document the names without their docstrings
        return set()
    return {attr for (scope, attr) in docs if scope == ""}


def _describe(obj) -> str:
    shape = getattr(obj, "shape", None)
    if shape is not None:
        return f"{type(obj).__name__} of shape {tuple(shape)}"
    if isinstance(obj, dict | tuple | list | frozenset | set):
        return f"{type(obj).__name__} of {len(obj)} items"
    return type(obj).__name__


def _kind(obj) -> str:
    if inspect.isclass(obj):
        return "exceptions" if issubclass(obj, BaseException) else "classes"
    if callable(obj):
        return "functions"
    return "data"


def module_page(name: str) -> str:
    mod = importlib.import_module(name)
    exported = list(getattr(mod, "__all__", []))
    own: dict[str, list[str]] = {"classes": [], "exceptions": [], "functions": [], "data": []}
    reexported: list[tuple[str, str]] = []
    for item in exported:
        if item.startswith("__"):
            continue
        obj = getattr(mod, item)
        home = _home(obj)
        kind = _kind(obj)
        if kind != "data" and home is not None and home != name:
            reexported.append((item, f"{home}.{getattr(obj, '__name__', item)}"))
        else:
            own[kind].append(item)
    title = f"``{name}``"
    lines = [title, "=" * len(title), "", f".. automodule:: {name}", "   :no-members:", ""]
    lines += [f".. currentmodule:: {name}", ""]
    for kind, heading in (
        ("classes", "Classes"),
        ("exceptions", "Exceptions"),
        ("functions", "Functions"),
    ):
        if own[kind]:
            lines += [
                f".. rubric:: {heading}",
                "",
                ".. autosummary::",
                "   :toctree: generated",
                "   :nosignatures:",
                "",
            ]
            lines += [f"   {x}" for x in own[kind]] + [""]
    if own["data"]:
        documented = _attribute_docs(name)
        lines += [".. rubric:: Data", ""]
        for x in own["data"]:
            if x in documented:  # a docstring after the assignment: autodoc renders it
                lines += [f".. autodata:: {x}", "   :no-value:", ""]
            else:  # no docstring of its own: say what it is rather than show its type's docstring
                lines += [f".. py:data:: {x}", f"   :type: {_describe(getattr(mod, x))}", ""]
    if reexported:
        lines += [
            ".. rubric:: Re-exported here",
            "",
            "Importable from this module, documented where they are defined:",
            "",
        ]
        lines += [f"- ``{name}.{x}``: :py:obj:`{target}`" for x, target in reexported] + [""]
    return "\n".join(lines)


def index_page(modules: list[str]) -> str:
    lines = [
        "API reference",
        "=============",
        "",
        "Generated from the docstrings of every public module (its ``__all__``). Each function",
        "and class has its own page with its numpydoc sections (parameters with shapes and units,",
        "returns, raises, and the paper's equation it implements where it implements one).",
        "",
        "What a plug-in controller receives is documented on",
        ":py:class:`adaptive_dd.controllers.base.Controller` (two-link arms) and in the",
        ":doc:`controllers guide <../controllers>` (both kinds of arm).",
        "",
    ]
    for group, heading in GROUPS.items():
        members = [m for m in modules if m == group or (group != PACKAGE and m.startswith(group + "."))]
        if group == PACKAGE:
            members = [m for m in modules if m == PACKAGE or (m.count(".") == 1 and m not in GROUPS)]
        if not members:
            continue
        lines += [heading, "-" * len(heading), "", ".. toctree::", "   :maxdepth: 1", ""]
        lines += [f"   {m}" for m in members] + [""]
    return "\n".join(lines)


def _write(path: Path, text: str) -> None:
    if not path.exists() or path.read_text() != text:  # unchanged pages keep their mtime
        path.write_text(text)


def generate(app) -> None:
    out = Path(app.srcdir) / "api"
    out.mkdir(exist_ok=True)
    modules = public_modules()
    for m in modules:
        _write(out / f"{m}.rst", module_page(m))
    _write(out / "index.rst", index_page(modules))
    for page in out.glob("adaptive_dd*.rst"):  # a renamed or removed module's page goes with it
        if page.stem not in modules:
            page.unlink()
    # autosummary's pages of each object: written afresh, so a removed function's page goes too
    shutil.rmtree(out / "generated", ignore_errors=True)


def setup(app):
    generate(app)  # at setup, before Sphinx lists the source files (autosummary reads them then)
    return {"parallel_read_safe": True, "version": "1"}
