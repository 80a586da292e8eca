"""One place decides an arm's path (issue 27): ``adaptive_dd/plant/kind.py`` asks the arm
(``closed_form``), and no module tests the arm's class (the two arm classes' own ``__eq__``
aside), found by an AST scan of the package as ``tests/test_import_graph.py`` does for imports."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

import adaptive_dd
from adaptive_dd.errors import ParameterError
from adaptive_dd.plant.arm import Arm
from adaptive_dd.plant.kind import arm_kind, is_chain, is_two_link, require_two_link
from adaptive_dd.plant.two_link import ClosedFormTwoLink, closed_form_view

ROOT = Path(adaptive_dd.__file__).resolve().parent
ARM_CLASSES = {"Arm", "ClosedFormTwoLink", "TwoLinkArm"}
ALLOWED = {"plant/arm.py": 1, "plant/two_link.py": 1}
"""Files allowed type tests on the arm's class, with how many: each class's own ``__eq__``."""


def _names(node: ast.AST) -> set[str]:
    """Class names a type-test argument refers to (``Arm``, ``mod.Arm``, ``(Arm, X)``)."""
    if isinstance(node, ast.Name):
        return {node.id}
    if isinstance(node, ast.Attribute):
        return {node.attr}
    if isinstance(node, ast.Tuple | ast.BinOp):  # (A, B) and A | B
        parts = node.elts if isinstance(node, ast.Tuple) else [node.left, node.right]
        return set().union(*(_names(p) for p in parts))
    return set()


def arm_type_tests(source: str) -> list[int]:
    """Lines of ``isinstance(x, Arm)``, ``issubclass(c, ClosedFormTwoLink)``, ``type(x) is Arm`` and
    ``type(x) == ClosedFormTwoLink`` (and the negations) in ``source``."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Call) and getattr(node.func, "id", None) in ("isinstance", "issubclass"):
            if len(node.args) == 2 and _names(node.args[1]) & ARM_CLASSES:
                out.append(node.lineno)
        elif isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            is_type = any(isinstance(s, ast.Call) and getattr(s.func, "id", None) == "type" for s in sides)
            if is_type and any(_names(s) & ARM_CLASSES for s in sides):
                out.append(node.lineno)
    return out


def test_the_scan_finds_planted_type_tests():
    src = (
        "if isinstance(a, Arm): pass\n"
        "ok = isinstance(u, ArmUncertainty)\n"
        "b = isinstance(x, (int, plant.two_link.ClosedFormTwoLink))\n"
        "c = type(x) is Arm\n"
        "d = issubclass(k, Arm | ClosedFormTwoLink)\n"
    )
    assert arm_type_tests(src) == [1, 3, 4, 5]


def test_no_type_test_on_the_arm_class_in_the_package():
    found = {}
    for path in sorted(ROOT.rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()
        lines = arm_type_tests(path.read_text(encoding="utf-8"))
        if lines:
            found[rel] = lines
    assert set(found) >= set(ALLOWED)  # the scan sees the classes' own __eq__
    bad = {rel: lines for rel, lines in found.items() if len(lines) != ALLOWED.get(rel, 0)}
    assert not bad, (
        f"type tests on the arm's class: {bad}; ask adaptive_dd.plant.kind "
        "(is_two_link, is_chain, arm_kind, require_two_link) instead"
    )


def test_kind_names_each_arm():
    two, chain = ClosedFormTwoLink.sice(), Arm.sice()
    assert (is_two_link(two), is_chain(two), arm_kind(two)) == (True, False, "two_link")
    assert (is_two_link(chain), is_chain(chain), arm_kind(chain)) == (False, True, "chain")
    assert not is_two_link(None) and not is_chain(None)
    with pytest.raises(ParameterError, match="expected an arm"):
        arm_kind(np.zeros(7))
    assert require_two_link(two, "here") is two
    assert require_two_link(chain, "here") is closed_form_view(chain)  # the paper's geometry: its record
    with pytest.raises(ParameterError, match=r"here: needs an arm of the paper's two-link geometry.*general"):
        require_two_link(Arm.sice(general=True), "here")
    with pytest.raises(ParameterError, match=r"here: needs an arm of the paper's two-link geometry"):
        require_two_link(np.zeros(7), "here")
