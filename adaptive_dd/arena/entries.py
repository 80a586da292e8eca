"""The controllers a leaderboard run of one scenario builds: each asked-for one with its floor, and
the law each runs (a variant's, or its own name)."""

from __future__ import annotations

from collections.abc import Sequence

from adaptive_dd.errors import ParameterError


def _with_floors(sc, names: Sequence[str]) -> tuple[tuple[str, ...], dict, dict, dict]:
    """The names to run (each asked-for one and its floor), each one's floor by the label its
    results carry, why a floor that does not build is missing (its row then has no ratio and says
    so), and the law each asked-for one runs by its label (a variant's ``law``, else its own name)."""
    from adaptive_dd.controllers.plugins import floor_of, table_name
    from adaptive_dd.controllers.registry import law_of, scenario_controller

    floors: dict[str, str | None] = {}
    laws: dict[str, str] = {}
    missing: dict[str, str] = {}
    run: list[str] = []
    for name in names:
        try:
            label, ctrl = scenario_controller(sc, name)  # results carry the label (a plug-in's class)
        except ParameterError as exc:  # named by its file once (a plug-in's table names it already)
            where = "" if str(exc).startswith(str(sc.source)) else f"{sc.source}: "
            raise ParameterError(f"leaderboard: {where}{exc}") from None
        floor = floors[label] = floor_of(ctrl)
        laws[label] = law_of(name, sc.options(table_name(name)))
        if floor is not None and floor not in run and floor not in missing:
            try:
                scenario_controller(sc, floor)
            except ParameterError as exc:
                missing[floor] = f"its floor {floor} cannot run here: {exc}"
        for n in (name, floor):
            if n is not None and n not in run and n not in missing:
                run.append(n)
    return tuple(run), floors, missing, laws
