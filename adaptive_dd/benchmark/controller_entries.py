"""Checks of a scenario's ``run.controllers`` and ``[controllers.NAME]`` tables: each entry a built-in
name, an import path, or a name of the user's own whose table names its law (a variant); each
table a listed controller's, of plain values."""

from __future__ import annotations

import json
import math
from typing import Any

from adaptive_dd.benchmark.frozen import _Table, thaw
from adaptive_dd.benchmark.key_hints import repeated_entries
from adaptive_dd.benchmark.number_checks import _short
from adaptive_dd.controllers import CONTROLLERS
from adaptive_dd.controllers.plugins import table_name


def _check_controllers(e: list, c: Any, arm: Any = None, opts: Any = ()) -> bool:
    from adaptive_dd.controllers.registry import IMPORT_PATH, law_of

    if not isinstance(c, tuple) or not c or not all(isinstance(x, str) for x in c):
        e.append(f"run.controllers: must be a non-empty list of names, got {_short(c)}")
        return False
    ok, laws = True, {}
    pairs = [o for o in opts if isinstance(o, tuple) and len(o) == 2] if isinstance(opts, tuple) else []
    tables = {n: t for n, t in pairs if isinstance(n, str)}  # a malformed entry: _check_options names it
    for x in c:
        try:  # a variant's law (its table's `law`), else the entry itself
            t = thaw(tables.get(table_name(x)))
            laws[x] = law_of(x, t if isinstance(t, dict) else None)
        except ValueError as exc:
            e.append(str(exc))
            ok = False
            continue
        if laws[x] not in CONTROLLERS and not IMPORT_PATH.match(laws[x]):
            e.append(
                f"run.controllers: unknown controller {x!r}; known: {', '.join(CONTROLLERS)}, "
                "an import path 'package.module:Class', or a name of your own whose [controllers.NAME] "
                'table names its law (law = "adaptive_ct")'
            )
            ok = False

    if arm is not None:  # the general kernels' run
        for x in c:
            law = laws.get(x, x)
            if law in CONTROLLERS and not CONTROLLERS[law].applies_to("chain"):
                named = repr(x) if law == x else f"{x!r} (law {law!r})"
                e.append(
                    f"run.controllers: {named} is for the two-link arm only, not for this "
                    f"{arm.n_joints}-joint arm: {CONTROLLERS[law].only}"
                )
                ok = False
    if len(set(c)) != len(c) or len({table_name(x) for x in c}) != len(c):
        e.append(
            f"run.controllers: {repeated_entries(c, table_name)}: each needs its own name and table (two "
            'settings of one law: a new name per setting, its table naming the law, law = "adaptive_ct")'
        )
        return False
    carried: dict = {}  # the name each entry's results carry (a plug-in's declared one: when it is built)
    for x in c:
        t = thaw(tables.get(table_name(x)))
        label = t.get("label") if isinstance(t, dict) else None
        if isinstance(label, str) or ":" not in x:
            carried.setdefault(label if isinstance(label, str) else x, []).append(x)
        if isinstance(label, str) and label in CONTROLLERS and label != x:
            e.append(
                f"controllers.{table_name(x)}.label: {label!r} is a built-in's name: results under it read "
                "as that law with its defaults (the report's targets judge it so); choose another label"
            )
            ok = False
    for name, xs in carried.items():
        if len(xs) > 1:
            e.append(
                f"run.controllers: {' and '.join(map(repr, xs))} would both carry the name {name!r} in the "
                "results (a label equal to another entry's name or label); give each its own label"
            )
            ok = False
    return ok


def _plain(e: list, key: str, x: Any) -> None:
    if isinstance(x, _Table):
        for k, y in x:
            _plain(e, f"{key}.{k}", y)
    elif isinstance(x, tuple):
        for y in x:
            _plain(e, key, y)
    elif isinstance(x, float) and not math.isfinite(x):
        e.append(f"{key}: must be finite, got {x!r}")
    elif not isinstance(x, str | int | float | bool):
        e.append(f"{key}: must be a plain value (number, string, boolean, list, table), got {_short(x)}")


_WITH = (
    "; set a controller's table with adaptive_dd.benchmark.scenario_settings.with_settings(scenario, "
    "name, {...})"
)


def _check_options(e: list, opts: Any, ctrls: tuple) -> None:
    if not isinstance(opts, tuple):
        e.append(f"controllers: options must be a tuple of (name, settings), got {_short(opts)}" + _WITH)
        return
    names = set(ctrls) | {table_name(c) for c in ctrls}
    for item in opts:
        if not (isinstance(item, tuple) and len(item) == 2 and isinstance(item[1], _Table)):
            e.append(f"controllers: each entry must be (name, frozen table), got {_short(item)}" + _WITH)
            continue
        name, table = item
        if ctrls and name not in names:
            law = dict(table).get("law")
            e.append(
                f"controllers.{name}: a variant of {law!r} that run.controllers ({', '.join(ctrls)}) does "
                f"not list: add {name!r} to run.controllers to run it (--controllers picks among those), "
                "or remove the table"
                if isinstance(law, str)
                else f"controllers.{name}: not a controller of run.controllers ({', '.join(ctrls)})"
                + _hint(name, ctrls)
            )
        _plain(e, f"controllers.{name}", table)


def _hint(name: str, ctrls: tuple) -> str:
    """What a table ``[controllers.NAME]`` no entry of ``ctrls`` owns most likely means: a plug-in
    entry whose class is spelt near ``name`` (either the entry or the table is misspelt), else how
    a plug-in's table is named."""
    from adaptive_dd.benchmark.key_hints import nearest_keys

    plugins = {table_name(c): c for c in ctrls if ":" in c}
    near = nearest_keys(name, plugins)
    if near:
        return (
            f"; run.controllers lists {plugins[near[0]]!r}: if its class is {name}, correct that entry, "
            f"else name the table [controllers.{near[0]}] (a plug-in's table is named by its class)"
        )
    return (
        f"; a plug-in's table is named by its class ({', '.join(f'[controllers.{t}]' for t in plugins)})"
        if plugins
        else ""
    )


def _shown(v) -> str:
    """A setting's value as TOML reads it; a long one (a matrix) by its size."""
    text = v if v == "its default" else json.dumps(v)
    return text if len(text) <= 60 else f"({len(text)} characters)"


def variants_line(sc) -> str | None:
    """One line naming each variant of the scenario ``sc`` (an entry whose table names its ``law``)
    with the settings it changes, for the report and ``validate``; None when there is none."""
    out = []
    for name in sc.controllers:
        table = sc.options(name)
        if "law" not in table:
            continue
        law = table["law"]
        base = sc.options(law) if law in sc.controllers else {}  # what the law itself is given
        rest = {k: v for k, v in table.items() if k not in ("law", "label") and base.get(k) != v}
        rest |= {k: "its default" for k in base if k not in table and k not in ("label", "floor")}
        said = ", ".join(f"{k} = {_shown(v)}" for k, v in sorted(rest.items()))
        same = f" (as {law} runs here)" if base else " (its defaults)"
        out.append(f"{name} = {law}" + (f" with {said}" if said else same))
    return "variants: " + "; ".join(out) if out else None
