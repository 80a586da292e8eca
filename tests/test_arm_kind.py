"""One place decides an arm's path (issue 27): :func:`adaptive_dd.plant.two_link.closed_form_view`
asks the arm (``closed_form``), and no other module tests the arm's class (the two arm classes'
own ``__eq__`` aside) nor reads ``closed_form``, found by an AST scan of the package as
``tests/test_import_graph.py`` does for imports."""

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
            # the class by its name: type(x).__name__ != "Arm"
            by_name = any(isinstance(s, ast.Attribute) and s.attr == "__name__" for s in sides)
            if by_name and any(isinstance(s, ast.Constant) and s.value in ARM_CLASSES for s in sides):
                out.append(node.lineno)
    return out


def test_the_scan_finds_planted_type_tests():
    src = (
        "if isinstance(a, Arm): pass\n"
        "ok = isinstance(u, ArmUncertainty)\n"
        "b = isinstance(x, (int, plant.two_link.ClosedFormTwoLink))\n"
        "c = type(x) is Arm\n"
        "d = issubclass(k, Arm | ClosedFormTwoLink)\n"
        'e = type(v).__name__ != "Arm"\n'
        'f = type(v).__name__ == "Reference"\n'
    )
    assert arm_type_tests(src) == [1, 3, 4, 5, 6]


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
        "(arm_kind, require_two_link), closed_form_view(arm) or the scenario's closed_forms instead"
    )


def test_kind_names_each_arm():
    two, sice, chain = ClosedFormTwoLink.sice(), Arm.sice(), Arm.sice(general=True)
    assert (is_two_link(two), is_chain(two), arm_kind(two)) == (True, False, "two_link")
    # the paper's arm as an Arm has the closed forms too: the kind asks closed_form_view, not the class
    assert (is_two_link(sice), is_chain(sice), arm_kind(sice)) == (True, False, "two_link")
    assert (is_two_link(chain), is_chain(chain), arm_kind(chain)) == (False, True, "chain")
    assert not is_two_link(None) and not is_chain(None)
    with pytest.raises(ParameterError, match="expected an arm"):
        arm_kind(np.zeros(7))
    assert require_two_link(two, "here") is two
    assert require_two_link(sice, "here") is closed_form_view(sice)  # the paper's geometry: its record
    with pytest.raises(ParameterError, match=r"here: needs an arm of the paper's two-link geometry.*general"):
        require_two_link(Arm.sice(general=True), "here")
    with pytest.raises(ParameterError, match=r"here: needs an arm of the paper's two-link geometry"):
        require_two_link(np.zeros(7), "here")


def closed_form_reads(source: str) -> list[int]:
    """Lines that read an arm's ``closed_form`` class attribute (``x.closed_form``,
    ``getattr(x, "closed_form", ...)``) or call the old kind tests ``is_two_link`` / ``is_chain``."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Attribute) and node.attr == "closed_form":
            out.append(node.lineno)
        elif isinstance(node, ast.Call):
            name = getattr(node.func, "id", getattr(node.func, "attr", None))
            if (
                name == "getattr"
                and len(node.args) >= 2
                and getattr(node.args[1], "value", None) == "closed_form"
            ):
                out.append(node.lineno)
            elif name in ("is_two_link", "is_chain"):
                out.append(node.lineno)
    return out


ONE_PLACE = {"plant/two_link.py", "plant/two_link_view.py", "plant/kind.py", "_numba_cache.py"}
"""Where the arm's class is asked: the fast path's section of ``plant/two_link.py``
(``closed_form_view``, ``as_arm``) and its ``paper_sigma``, moved to ``plant/two_link_view.py``
to keep ``two_link.py`` under 600 lines, ``plant/kind.py``'s old ``is_two_link`` /
``is_chain`` (which ask ``closed_form_view``), and ``_numba_cache.py``'s callers of them (another
helper's room; they ask ``closed_form_view`` through them)."""


def test_the_scan_finds_planted_closed_form_reads():
    src = (
        "a = arm.closed_form\n"
        'b = getattr(arm, "closed_form", None)\n'
        "c = is_two_link(arm)\n"
        "d = closed_form_view(arm)\n"
    )
    assert closed_form_reads(src) == [1, 2, 3]


def test_only_the_one_place_asks_the_arm_its_class():
    found = {}
    for path in sorted(ROOT.rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()
        lines = closed_form_reads(path.read_text(encoding="utf-8"))
        if lines and rel not in ONE_PLACE:
            found[rel] = lines
    assert not found, (
        f"the arm's kind asked outside the one place: {found}; ask closed_form_view(arm) or the "
        "scenario's closed_forms instead"
    )
