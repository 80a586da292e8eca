"""The reference page of the built-in controllers lists every one, with its floor: it listed 8 of the
17 (the arena's laws missing) and said every built-in is the same kind of law."""

import inspect
from pathlib import Path

from adaptive_dd.closed_loop import arena_laws, controllers
from adaptive_dd.controllers.builtins import CONTROLLERS

PAGE = Path(__file__).resolve().parent.parent / "docs" / "guide" / "controllers_known.md"


def _floors() -> dict:
    out = {"adaptive_ct_paper": "ct_oracle"}  # the two-link runtime's law (its class has the same floor)
    for module in (controllers, arena_laws):
        for cls in vars(module).values():
            if inspect.isclass(cls) and isinstance(getattr(cls, "name", None), str) and hasattr(cls, "floor"):
                out[cls.name] = cls.floor
    return out


def test_every_builtin_is_on_the_page_with_its_floor():
    rows = {line.split("|")[1].strip().strip("`"): line.split("|") for line in PAGE.read_text().splitlines()
            if line.startswith("| `")}  # fmt: skip
    assert set(rows) == set(CONTROLLERS), set(CONTROLLERS) ^ set(rows)
    floors = _floors()
    for name, cells in rows.items():
        floor = floors[name]
        assert cells[4].strip() == ("none: a floor" if floor is None else f"`{floor}`"), name
