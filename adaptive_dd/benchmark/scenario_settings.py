"""The ``[controllers.NAME]`` tables of a scenario: each built-in's settings checked once when
the file is read (:func:`controller_setting_errors`), and the settings that are not scenario
keys because the run derives them from the arm and the scenario (:data:`DERIVED`,
:func:`derived_setting_errors`).

``adaptive_ct``'s estimator and change detector take no settings from a scenario file: on an arm
from a URDF the estimator's mode follows from the model's stated uncertainty (``[model]
uncertainty``, by default the ``[plant.uncertainty]`` levels:
:func:`~adaptive_dd.closed_loop.controllers.with_stated_uncertainty`), its prior from ``[model]
from`` (:mod:`adaptive_dd.closed_loop.model_prior`), its row weights from each equation's error
along the reference carrying ``[arm] payload_capacity`` (the arm's sensors and D/A steps) and the payload
mass it re-opens at an alarm from ``[arm] payload_capacity``
(:func:`~adaptive_dd.benchmark.preflight.derived_estimator_settings`, what ``adaptive-dd
validate`` prints); every other field is the estimator's and the detector's default, the same in
every scenario. Research code that wants other values builds the controller in Python
(``make_controller("adaptive_ct", options={"estimator": {...}})``) or sets ``controller_options``
on a loaded :class:`~adaptive_dd.benchmark.scenario.Scenario`.
"""

from __future__ import annotations

import math
from typing import Any

from adaptive_dd.benchmark.scenario_base import LIMITS
from adaptive_dd.benchmark.scenario_checks import check_number, thaw

__all__ = ["DERIVED", "controller_setting_errors", "derived_setting_errors", "with_settings"]

_FROM_THE_SCENARIO = (
    "its mode from [model] uncertainty (else the [plant.uncertainty] levels), its prior from "
    "[model] from, its row weights from each equation's error along the reference with "
    "[arm] payload_capacity, its re-opening at an alarm from [arm] payload_capacity; every other field is "
    "the default"
)
DERIVED: dict[str, dict[str, str]] = {
    "adaptive_ct": {
        "estimator": "adaptive_ct's estimator settings are derived from the arm and the scenario ("
        + _FROM_THE_SCENARIO
        + ")",
        "detector": "adaptive_ct's change detector settings are derived from the arm and the scenario "
        "(the payload mass it re-opens at an alarm from [arm] payload_capacity; every other field is "
        "the default)",
    },
}
"""Settings of built-in controllers that are not scenario keys: ``{controller: {setting: what it
is derived from}}``. A scenario file that sets one is refused (:func:`derived_setting_errors`)."""


def with_settings(scenario, name: str, settings: dict):
    """``scenario`` with controller ``name``'s settings table replaced by ``settings`` (the other
    controllers' kept): the way to give ``adaptive_ct`` estimator or detector settings, which no
    scenario file sets (:data:`DERIVED`), in research code and measurements. A ``name`` the scenario
    does not list whose ``settings`` name a ``law`` is added to its controllers: a variant.

    Examples
    --------
    >>> from adaptive_dd import load_scenario
    >>> sc = with_settings(load_scenario(), "adaptive_ct", {"detector": {"glr_threshold": 200.0}})
    >>> sc.options("adaptive_ct")
    {'detector': {'glr_threshold': 200.0}}
    >>> with_settings(sc, "no_boost", {"law": "adaptive_ct", "boost_duration": 0.0}).controllers[-1]
    'no_boost'
    """
    import dataclasses

    from adaptive_dd.benchmark.scenario_checks import freeze
    from adaptive_dd.controllers.registry import law_of

    try:
        law_of(name, dict(settings))  # a variant's law, judged before it is added
    except ValueError as exc:
        from adaptive_dd.errors import ScenarioError

        raise ScenarioError(f"with_settings({name!r}, ...): {exc}") from None
    kept = tuple(o for o in scenario.controller_options if o[0] != name)
    added = () if name in scenario.controllers or "law" not in settings else (name,)
    out = dataclasses.replace(
        scenario,
        controllers=(*scenario.controllers, *added),
        controller_options=(*kept, (name, freeze(dict(settings)))),
    )
    values = {f.name: getattr(out, f.name) for f in dataclasses.fields(out) if f.init}
    # a built-in's table checked here, as a file's is when it is read (a plug-in's when the run builds it)
    errs = controller_setting_errors(values, only=name, file_limits=False)
    if errs:
        from adaptive_dd.errors import ScenarioError

        raise ScenarioError(f"with_settings({name!r}, ...): " + "; ".join(errs))
    return out


def derived_setting_errors(data: Any) -> list[str]:
    """``key: reason`` for each setting of :data:`DERIVED` a scenario's tables (the parsed TOML)
    set, naming what the setting is derived from and what to do."""
    tables = data.get("controllers") if isinstance(data, dict) else None
    if not isinstance(tables, dict):
        return []
    errs = []
    for name, table in tables.items():
        if not isinstance(table, dict):
            continue
        law = table.get("law", name)  # a variant's table is its law's (controller_entries judges the law)
        derived = DERIVED.get(law if isinstance(law, str) else name, {})
        for key in sorted(derived.keys() & table.keys()):
            errs.append(
                f"controllers.{name}.{key}: not a scenario key: {derived[key]}; remove it "
                "(`adaptive-dd validate FILE` prints the derived values)"
            )
    return errs


def _numbers(x: Any, key: str):
    """Every number in a (nested) setting as ``(key, value)``."""
    if isinstance(x, dict):
        for k, y in x.items():
            yield from _numbers(y, f"{key}.{k}")
    elif isinstance(x, list | tuple):
        for y in x:
            yield from _numbers(y, key)
    elif isinstance(x, int | float) and not isinstance(x, bool):
        yield key, float(x)


def _check_delay(errs: list[str], name: str, delay, T: float) -> None:
    """``ct_oracle_late``'s ``delay`` (given, or the default): a number >= 0 and a whole number of
    samples at ``T`` (:func:`~adaptive_dd.controllers.base.delay_samples`)."""
    from adaptive_dd.controllers.base import delay_samples
    from adaptive_dd.errors import ParameterError

    if check_number(errs, f"controllers.{name}.delay", delay, 0, LIMITS["max_setting"]):
        try:
            delay_samples(float(delay), T, name)
        except ParameterError as exc:
            errs.append(str(exc))


def result_names(controllers, opts: dict, source, origin: str | None = None) -> dict[str, str]:
    """``{entry of run.controllers: the name its results carry}``: a ``label``, a built-in's name,
    else a plug-in's declared ``name`` (its class name when it declares none or does not import),
    the plug-ins looked up as the run looks them up for the scenario file ``source``
    (:func:`~adaptive_dd.controllers.plugins.plugin_search`)."""
    from adaptive_dd.controllers.plugins import (
        controller_label,
        load_controller_class,
        plugin_search,
        table_name,
    )

    search = plugin_search(source, origin)

    out = {}
    for c in controllers:
        out[c] = controller_label(c, opts.get(table_name(c)))
        if ":" in c and "label" not in opts.get(table_name(c), {}):
            try:  # the name the plug-in declares, which its results carry
                declared = getattr(load_controller_class(c, search), "name", None)
            except Exception:  # a plug-in that does not import: the run's own check names it
                declared = None
            if isinstance(declared, str) and declared:
                out[c] = declared
    return out


def _check_gains(errs: list, where: str, o: dict, T: float) -> None:
    """A controller's table ``o`` (``where``: ``controllers.NAME``): its ``bandwidth`` and
    ``boost_bandwidth`` within what the sample period ``T`` carries, its ``damping`` within bounds."""
    for bw, limit in (("bandwidth", "max_bandwidth_T"), ("boost_bandwidth", "max_boost_bandwidth_T")):
        key = f"{where}.{bw}"
        if bw in o and check_number(errs, key, o[bw], 0, 1e5, lo_open=True) and o[bw] * T > LIMITS[limit]:
            errs.append(
                f"{key}: {o[bw]} rad/s at T = {T} s gives {bw} * T = {o[bw] * T:.3g} > {LIMITS[limit]}"
            )
    if "damping" in o:
        check_number(errs, f"{where}.damping", o["damping"], 0, LIMITS["max_damping"], lo_open=True)


def _floor_errors(v: dict, opts: dict, only: str | None) -> list[str]:
    """Each ``[controllers.NAME] floor`` names one of the run's controllers by the name its results
    carry (:func:`result_names`), or is ``false``. Plug-ins are imported only when a floor is set."""

    from adaptive_dd.controllers.plugins import floor_setting, table_name
    from adaptive_dd.errors import ParameterError

    asked = [
        c for c in v["controllers"] if (only is None or c == only) and "floor" in opts.get(table_name(c), {})
    ]
    if not asked:
        return []
    names = result_names(v["controllers"], opts, v.get("source", ""), v.get("origin"))
    errs = []
    for c in asked:
        table = table_name(c)
        try:
            floor = floor_setting(table, opts[table]["floor"])
        except ParameterError as exc:
            errs.append(str(exc))
            continue
        if floor is not None and floor == names[c]:
            errs.append(
                f"controllers.{table}.floor: {floor!r} is this controller itself (a ratio of 1 by "
                "construction); name another of the run's controllers, or false for none"
            )
            continue
        if floor is None or floor in names.values():
            continue
        from adaptive_dd.controllers import CONTROLLERS

        if floor in names:  # an entry of run.controllers, by its spec: results carry another name
            errs.append(
                f"controllers.{table}.floor: name {floor!r} by the name its results carry, {names[floor]!r}"
            )
        elif floor in CONTROLLERS:  # a built-in the run lacks: the benchmark adds it (said, or why not)
            continue
        else:
            errs.append(
                f"controllers.{table}.floor: {floor!r} is not one of the run's controllers (by the names "
                f"their results carry: {', '.join(names.values())}); add it to run.controllers, or name one "
                "of them"
            )
    return errs


def controller_setting_errors(
    v: dict, only: str | None = None, file_limits: bool = True, floors: bool = True
) -> list[str]:
    """Each built-in controller with a ``[controllers.NAME]`` table built once, so a bad setting
    (a negative gain, a bandwidth the sample period cannot carry, an unknown key) is an error of
    the file, not of the run. ``bandwidth``, ``boost_bandwidth`` and ``damping`` have the bounds
    of ``[control]``; ``boost_duration`` is at most the run; every number is finite and within
    ``LIMITS["max_setting"]`` (``file_limits``: a file's bound; research code setting the estimator
    through :func:`with_settings` is not held to it). ``only``: that controller's table alone."""
    from adaptive_dd.controllers import CONTROLLERS, gains_for, make_controller
    from adaptive_dd.controllers.plugins import table_name
    from adaptive_dd.controllers.registry import law_of

    errs: list[str] = []
    opts = {n: thaw(o) for n, o in v["controller_options"]}
    T = v["sample_period"]
    if floors:  # (a sweep's cell runs one controller of the list: its floor is judged on the list)
        errs += _floor_errors(v, opts, only)
    for name in v["controllers"] if only is None else [c for c in v["controllers"] if c == only]:
        try:
            law = law_of(name, opts.get(name))  # a variant's law (judged by the list's check)
        except ValueError:
            continue
        if law in CONTROLLERS and "delay" in CONTROLLERS[law].settings:  # its default too
            default = CONTROLLERS[law].settings["delay"].chain  # the same on every arm
            _check_delay(errs, name, opts.get(name, {}).get("delay", default), T)
        if ":" in law and table_name(name) in opts:  # a plug-in's gains: its table, as a built-in's
            _check_gains(errs, f"controllers.{table_name(name)}", opts[table_name(name)], T)
        if law not in CONTROLLERS or name not in opts:
            continue
        o, n0 = opts[name], len(errs)
        _check_gains(errs, f"controllers.{name}", o, T)
        if "boost_duration" in o:
            check_number(errs, f"controllers.{name}.boost_duration", o["boost_duration"], 0, v["duration"])
        said = {e.split(":", 1)[0] for e in errs[n0:]}  # a key its own bound refused: said once
        for key, x in _numbers(o, f"controllers.{name}"):
            if key in said:
                continue
            if not math.isfinite(x) or (file_limits and abs(x) > LIMITS["max_setting"]):
                errs.append(f"{key}: must be finite and within +-{LIMITS['max_setting']:g}, got {x!r}")
                said.add(key)  # a list's elements: its first bad one, once
        if len(errs) > n0:
            continue
        try:
            o = {k: x for k, x in o.items() if k != "floor"}  # judged once, above (_floor_errors)
            make_controller(name, gains_for(v["arm"], v["bandwidth"], v["damping"]), o, arm=v["arm"])
        except (ValueError, TypeError, ArithmeticError) as exc:
            msg = str(exc)
            while msg.startswith(f"controllers.{name}"):  # the registry names the controller too
                msg = msg.removeprefix(f"controllers.{name}").removeprefix(": ")
            errs.append(f"controllers.{name}{'' if msg.startswith('.') else ': '}{msg}")
    return errs
