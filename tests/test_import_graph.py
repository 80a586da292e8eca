"""No import circle among the package's modules (issue 27), counting function-level imports too
(only imports under ``if TYPE_CHECKING:`` are left out: they never run)."""

from __future__ import annotations

import ast
from pathlib import Path

import adaptive_dd

ROOT = Path(adaptive_dd.__file__).resolve().parent


def _modules() -> dict[str, Path]:
    out = {}
    for p in ROOT.rglob("*.py"):
        parts = ("adaptive_dd", *p.relative_to(ROOT).with_suffix("").parts)
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        out[name] = p
    return out


class _Imports(ast.NodeVisitor):
    def __init__(self) -> None:
        self.names: set[str] = set()

    def visit_If(self, node: ast.If) -> None:
        t = node.test
        if getattr(t, "id", None) == "TYPE_CHECKING" or getattr(t, "attr", None) == "TYPE_CHECKING":
            for n in node.orelse:
                self.visit(n)
            return
        self.generic_visit(node)

    def visit_ImportFrom(self, node: ast.ImportFrom) -> None:
        if node.module and node.module.startswith("adaptive_dd"):
            self.names.update(f"{node.module}.{a.name}" for a in node.names)
            self.names.add(node.module)

    def visit_Import(self, node: ast.Import) -> None:
        self.names.update(a.name for a in node.names if a.name.startswith("adaptive_dd"))


def import_graph() -> dict[str, set[str]]:
    """Module -> the package's modules it imports (a package's own parents left out: importing a
    submodule runs its package's ``__init__``, which is not a dependency of the submodule)."""
    mods = _modules()
    graph = {}
    for name, path in mods.items():
        v = _Imports()
        v.visit(ast.parse(path.read_text(encoding="utf-8")))
        graph[name] = {
            o
            for o in v.names
            if o in mods and o != name and not name.startswith(o + ".") and o != "adaptive_dd"
        }
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected groups of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                out.append(sorted(group))

    for v in graph:
        if v not in index:
            visit(v)
    return out


def test_the_cycle_finder_finds_a_planted_circle():
    g = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert cycles(g) == [["a", "b", "c"]]


def test_no_import_circle_in_the_package():
    graph = import_graph()
    assert "adaptive_dd.benchmark.metrics" in graph and graph["adaptive_dd.plant.two_link"]  # it parsed
    assert cycles(graph) == []
