"""The package's rooms by size: modules over about 600 lines, functions over about 60 (STYLE.md).

Usage::

    python tools/room_sizes.py [PACKAGE_DIR]      # default: adaptive_dd next to this folder

Prints the package's line count (every ``.py`` file, blank lines and comments included, as
``wc -l``), then each module over ``MODULE_LINES`` lines and each function or method over
``FUNCTION_LINES`` lines (from its ``def`` to its last line, decorators excluded, as the AST's
``lineno`` / ``end_lineno`` give them; its length without its docstring beside it), longest
first. A compiled kernel may stay longer where splitting costs speed: its docstring or a comment
says so. Asserts nothing.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

MODULE_LINES = 600
FUNCTION_LINES = 60


def _docstring_lines(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """Lines of the function's docstring (0 without one)."""
    first = node.body[0]
    if isinstance(first, ast.Expr) and isinstance(getattr(first, "value", None), ast.Constant):
        if isinstance(first.value.value, str):
            return first.end_lineno - first.lineno + 1
    return 0


def sizes(root: Path) -> tuple[int, list[tuple[int, str]], list[tuple[int, str]]]:
    """``(package lines, [(lines, module)], [(lines, module:function)])``, the lists over the bounds."""
    total, modules, functions = 0, [], []
    for path in sorted(root.rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        n = text.count("\n")
        total += n
        rel = path.relative_to(root.parent).as_posix()
        if n > MODULE_LINES:
            modules.append((n, rel))
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                length = node.end_lineno - node.lineno + 1
                if length > FUNCTION_LINES:
                    functions.append(
                        (
                            length,
                            f"{rel}:{node.name} ({length - _docstring_lines(node)} without its docstring)",
                        )
                    )
    return total, sorted(modules, reverse=True), sorted(functions, reverse=True)


def main() -> None:
    root = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[1] / "adaptive_dd"
    total, modules, functions = sizes(root)
    print(f"{root}: {total} lines of Python")
    print(f"{len(modules)} modules over {MODULE_LINES} lines:")
    for n, name in modules:
        print(f"  {n:5d}  {name}")
    print(f"{len(functions)} functions over {FUNCTION_LINES} lines:")
    for n, name in functions:
        print(f"  {n:5d}  {name}")


if __name__ == "__main__":
    main()
