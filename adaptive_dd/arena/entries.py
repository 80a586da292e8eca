"""The controllers a leaderboard run of one scenario builds: each asked-for one with its floor, and
the law each runs (a variant's, or its own name)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from adaptive_dd.errors import ParameterError


def _with_floors(sc, names: Sequence[str]) -> tuple[tuple[str, ...], dict, dict]:
    """The names to run (each asked-for one and its floor), each one's floor by the label its
    results carry, and why a floor that does not build is missing (its row then has no ratio and
    says so)."""
    from adaptive_dd.controllers.plugins import DEFAULT_FLOOR
    from adaptive_dd.controllers.registry import scenario_controller

    floors: dict[str, str | None] = {}
    missing: dict[str, str] = {}
    run: list[str] = []
    for name in names:
        try:
            label, ctrl = scenario_controller(sc, name)  # results carry the label (a plug-in's class)
        except ParameterError as exc:  # named by its file once (a plug-in's table names it already)
            where = "" if str(exc).startswith(str(sc.source)) else f"{sc.source}: "
            raise ParameterError(f"leaderboard: {where}{exc}") from None
        floor = floors[label] = getattr(ctrl, "floor", DEFAULT_FLOOR)
        if floor is not None and floor not in run and floor not in missing:
            try:
                scenario_controller(sc, floor)
            except ParameterError as exc:
                missing[floor] = f"its floor {floor} cannot run here: {exc}"
        for n in (name, floor):
            if n is not None and n not in run and n not in missing:
                run.append(n)
    return tuple(run), floors, missing


def _laws(sc, names) -> dict[str, str]:
    """``{the name a controller's results carry: the law it runs}`` (a variant's ``law``, else the
    entry itself: a built-in name or an import path)."""
    from adaptive_dd.benchmark.scenario_settings import result_names
    from adaptive_dd.controllers.plugins import table_name
    from adaptive_dd.controllers.registry import law_of

    src = Path(str(sc.source))
    opts = {n: sc.options(n) for n in (*names, *map(table_name, names))}
    labels = result_names(names, opts, (src.parent, Path.cwd()) if src.is_file() else None)
    return {labels[n]: law_of(n, sc.options(table_name(n))) for n in names}
