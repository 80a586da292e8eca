"""A sweep task's key: what the cell's rows depend on (the scenario's fields, the controller, its
settings, the seeds, the rows' format and the package's own code), hashed; a cell whose key is on
disk is read back, not run (:mod:`adaptive_dd.sweep`)."""

from __future__ import annotations

import functools
import hashlib
import json
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from adaptive_dd.benchmark.scenario import Scenario

__all__ = ["CELL_VERSION"]

CELL_VERSION = 3
"""Part of every task key, with a hash of the package's sources (:func:`_code_id`: cells written by
other code are run again): bump it when the rows a task returns change meaning (2: the
``saturation_fraction`` column; 3: ``detector`` and ``detection_delay``)."""


def _task_key(scenario: Scenario, controller: str, settings, seeds) -> str:
    return _seeds_key(_cell_text(scenario, controller, settings), seeds)


def _cell_text(scenario: Scenario, controller: str, settings) -> str:
    """What a cell's rows depend on but its seeds, as text: the scenario's fields with the
    controller's own ``[controllers.NAME]`` table alone (another controller's setting changed does
    not run this one's cells again), the controller, the grid's settings, the code."""
    from adaptive_dd.benchmark.provenance import scenario_dict
    from adaptive_dd.sweep_spec import cell_scenario

    sc = scenario_dict(cell_scenario(scenario, controller, None))  # every field, the arm by Arm.to_dict
    for k in ("name", "source", "seeds", "controllers", "defaulted"):
        sc.pop(k, None)
    blob = {"v": CELL_VERSION, "scenario": sc, "controller": controller, "settings": settings}
    blob["code"] = _code_id()  # a cell of other code (a default changed) is run again, not reused
    return json.dumps(blob, sort_keys=True, default=repr)


def _seeds_key(cell_text: str, seeds) -> str:
    """The task's key: :func:`_cell_text` with its block of seeds, hashed."""
    text = cell_text + json.dumps({"seeds": list(seeds)})
    return hashlib.sha256(text.encode()).hexdigest()[:20]


@functools.lru_cache(maxsize=1)
def _code_id() -> str:
    """A hash of the package's own source files (every ``.py`` under ``adaptive_dd``, by path and
    content): part of every task key, so that a cell written by other code is run again. Exact
    whether or not the code is a git checkout, and blind to the docs."""
    from pathlib import Path

    root = Path(__file__).resolve().parent
    h = hashlib.sha256()
    for f in sorted(root.rglob("*.py")):
        h.update(str(f.relative_to(root)).encode())
        h.update(f.read_bytes())
    return h.hexdigest()[:16]
