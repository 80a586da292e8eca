"""The package's modules stay within 600 lines each (issue 41's target: a module a reader can hold
in mind; ``python tools/room_sizes.py`` prints the sizes and the longest functions)."""

from __future__ import annotations

from pathlib import Path

import adaptive_dd

MAX_LINES = 600


def test_no_module_over_600_lines():
    root = Path(adaptive_dd.__file__).parent
    long = {
        str(p.relative_to(root.parent)): n
        for p in sorted(root.rglob("*.py"))
        if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES
    }
    assert not long, f"modules over {MAX_LINES} lines (split them by what they hold): {long}"
