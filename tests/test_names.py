"""Issue 27's names: no ``serial_`` prefix (the paper's arm is serial too), and the old name of the
one arm type still resolves, with a FutureWarning."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import adaptive_dd

ROOT = Path(adaptive_dd.__file__).resolve().parent


def serial_names(source: str) -> list[str]:
    """Functions, classes and module-level names called ``serial_*`` / ``Serial*`` / ``SERIAL_*``."""
    out = []
    for node in ast.walk(ast.parse(source)):
        names = []
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            names = [node.name]
        elif isinstance(node, ast.Assign):
            names = [t.id for t in node.targets if isinstance(t, ast.Name)]
        out += [n for n in names if n.lower().startswith("serial_") or n.startswith("Serial")]
    return out


def test_the_scan_finds_planted_serial_names():
    src = "def serial_step(): pass\nclass SerialArm: pass\nSERIAL_CONTROLLERS = {}\ndef step(): pass\n"
    assert serial_names(src) == ["serial_step", "SerialArm", "SERIAL_CONTROLLERS"]


def test_no_serial_prefix_in_the_package():
    modules = sorted(p.relative_to(ROOT).as_posix() for p in ROOT.rglob("serial_*.py"))
    assert modules == [], f"modules with the serial_ prefix: {modules}"
    found = {}
    for path in sorted(ROOT.rglob("*.py")):
        names = serial_names(path.read_text(encoding="utf-8"))
        if names:
            found[path.relative_to(ROOT).as_posix()] = names
    assert not found, f"serial_ names (the paper's arm is serial too): {found}"


def test_the_old_name_of_the_arm_warns_and_is_the_arm():
    from adaptive_dd.plant.arm import Arm

    with pytest.warns(FutureWarning, match=r"SerialArm is now adaptive_dd\.plant\.Arm"):
        from adaptive_dd.plant import SerialArm
    assert SerialArm is Arm
