"""Sweep files: a grid over scenario fields x controllers x seeds, read and checked.

A sweep file is TOML::

    [sweep]
    scenario = "short_swap.toml"   # relative to this file; "default" (or omitted): the shipped one
    seeds = 4                      # seed indices 0 .. seeds-1 (optional: the scenario's)
    seed = 0                       # base seed (optional: the scenario's)
    block = 2                      # seeds per task (optional: all seeds in one task)
    controllers = ["ct_oracle", "adaptive_ct"]   # optional: the scenario's
    swap = 0                       # which [[payload]] of the scenario the grid's
                                   # payload_mass and swap_time change (0-based; default 0)
    duration = 5.0                 # optional: override run.duration [s]

    [grid]                         # every combination is one grid point (file order)
    payload_mass = [0.5, 2.0, 5.0, 10.0]   # kg, of payload `swap`
    swap_time = [1.5, 2.0, 2.5]            # s, of payload `swap`
    bandwidth = [30.0, 40.0]               # rad/s (control.bandwidth)
    noise_scale = [1.0, 4.0]               # multiplies both noise variances

    [grid.controller.adaptive_ct]  # controller settings, each checked as in a scenario's table
    boost_bandwidth = [150.0, 300.0]

    [heatmap]                      # optional; defaults shown
    x = "payload_mass"             # grid axes (default: the first two with > 1 value;
    y = "swap_time"                #   one varied axis: x alone, a map of one row)
    adaptive = "adaptive_ct"
    floor = "ct_oracle"
    segment = 1                    # segment index (default: the one starting at payload `swap`)

Axis names of controller settings are ``"<controller>.<key>"`` (e.g.
``"adaptive_ct.boost_bandwidth"``).
Every grid point is checked when the file is read (swap times increasing and before the
end, masses >= 0, ...): errors name the file, the key and the reason.
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from adaptive_dd.benchmark.scenario import Scenario, default_scenario_path, load_scenario
from adaptive_dd.controllers import CONTROLLERS, controllers_for
from adaptive_dd.controllers.registry import law_of
from adaptive_dd.errors import ScenarioError
from adaptive_dd.io import read_toml

__all__ = ["SCENARIO_AXES", "GridPoint", "Sweep", "SweepError", "cell_scenario", "load_sweep", "parse_sweep"]

SCENARIO_AXES = ("payload_mass", "swap_time", "bandwidth", "noise_scale")
"""Scenario fields a grid may vary."""

_SWEEP_KEYS = {"scenario", "seeds", "seed", "block", "controllers", "swap", "duration"}
_HEATMAP_KEYS = {"x", "y", "adaptive", "floor", "segment"}


class SweepError(ScenarioError):
    """A sweep file is invalid; names the file, the key and the reason.

    Examples
    --------
    >>> from adaptive_dd.sweep_spec import parse_sweep
    >>> parse_sweep({"grid": 3}, src="mine.toml")
    Traceback (most recent call last):
    ...
    adaptive_dd.sweep_spec.SweepError: mine.toml: [grid] must be a table
    """


@dataclass(frozen=True)
class GridPoint:
    """One point of the grid.

    Attributes
    ----------
    index : int
        Position in the expanded grid (file order, last axis fastest).
    values : tuple of (axis, value)
        The grid coordinates, scenario axes and ``"<controller>.<key>"`` axes.
    scenario : Scenario
        The base scenario with the scenario axes applied.
    settings : tuple of (controller, tuple of (key, value))
        Controller settings of this point (opaque to the sweep).
    """

    index: int
    values: tuple[tuple[str, Any], ...]
    scenario: Scenario
    settings: tuple[tuple[str, tuple[tuple[str, Any], ...]], ...] = ()

    def settings_for(self, controller: str) -> dict[str, Any]:
        """The settings dict of one controller (empty if none)."""
        return dict(dict(self.settings).get(controller, ()))


@dataclass(frozen=True)
class Sweep:
    """A checked sweep: base scenario, seeds, controllers, grid and heatmap choice."""

    source: str
    base: Scenario
    seeds: int
    block: int
    controllers: tuple[str, ...]
    axes: tuple[tuple[str, tuple[Any, ...]], ...]
    points: tuple[GridPoint, ...]
    heatmap: dict[str, Any] | None

    def seed_blocks(self) -> list[tuple[int, ...]]:
        """Seed indices ``0 .. seeds-1`` cut into blocks of ``block``."""
        idx = range(self.seeds)
        return [tuple(idx[i : i + self.block]) for i in range(0, self.seeds, self.block)]


def load_sweep(path: str | Path) -> Sweep:
    """Read and check a sweep file (see the module docstring).


    Parameters
    ----------
    path : str or Path
        A sweep TOML file (``[sweep]``, ``[grid]``, ``[heatmap]``).

    Returns
    -------
    Sweep
        The checked sweep with its grid expanded.


    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> from adaptive_dd.benchmark.scenario import default_scenario_path
    >>> from adaptive_dd.sweep_spec import load_sweep
    >>> path = Path(tempfile.mkdtemp()) / "sweep.toml"
    >>> _ = path.write_text(f'''
    ... [sweep]
    ... scenario = "{default_scenario_path().as_posix()}"
    ... seeds = 2
    ... controllers = ["ct_oracle", "adaptive_ct"]
    ... [grid]
    ... payload_mass = [0.5, 2.5]
    ... swap_time = [5.0, 7.5]
    ... [heatmap]
    ... x = "payload_mass"
    ... y = "swap_time"
    ... adaptive = "adaptive_ct"
    ... floor = "ct_oracle"
    ... segment = 1
    ... ''')
    >>> [dict(p.values) for p in load_sweep(path).points][:2]
    [{'payload_mass': 0.5, 'swap_time': 5.0}, {'payload_mass': 0.5, 'swap_time': 7.5}]

    Raises
    ------
    SweepError
        Naming the file, the key and the reason.
    """
    path = Path(path)
    src = str(path)
    if not path.is_file():
        raise SweepError(f"{src}: no such sweep file")
    data = read_toml(path, SweepError)
    return parse_sweep(data, src, base_dir=path.parent)


def _int(src: str, key: str, v: Any, minimum: int) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or v < minimum:
        raise SweepError(f"{src}: key '{key}' must be an integer >= {minimum}, got {v!r}")
    return v


def _base_scenario(src: str, sw: dict, base_dir: Path) -> tuple[Scenario, float | None]:
    name = sw.get("scenario", "default")
    if not isinstance(name, str):
        raise SweepError(f"{src}: key 'sweep.scenario' must be a path or \"default\", got {name!r}")
    path = default_scenario_path() if name == "default" else base_dir / name
    if not path.is_file():
        raise SweepError(f"{src}: key 'sweep.scenario': no such scenario file {str(path)!r}")
    try:
        sc = load_scenario(path)
    except ScenarioError as exc:
        raise SweepError(f"{src}: key 'sweep.scenario': {exc}") from None
    if "duration" not in sw:
        return sc, None
    d = sw["duration"]
    if isinstance(d, bool) or not isinstance(d, int | float) or not d > 0:
        raise SweepError(f"{src}: key 'sweep.duration' must be a number > 0 s, got {d!r}")
    return sc, float(d)  # applied per grid point, after the grid's swap time (_apply)


def _controllers(src: str, sw: dict, base: Scenario) -> tuple[str, ...]:
    ctrls = sw.get("controllers", list(base.controllers))
    if not isinstance(ctrls, list) or not ctrls or not all(isinstance(c, str) for c in ctrls):
        raise SweepError(f"{src}: key 'sweep.controllers' must be a non-empty list of names, got {ctrls!r}")
    known = controllers_for(base.closed_forms or base.arm)
    # the list the sweep reads: its own, else the scenario's run.controllers (named as such)
    where = (
        "key 'sweep.controllers'"
        if "controllers" in sw
        else f"{base.source}'s run.controllers (the sweep gives no sweep.controllers)"
    )
    for c in ctrls:
        law = law_of(c, base.options(c)) if c in base.controllers else c  # a variant's law
        if law not in known:
            kind = "the two-link arm" if base.closed_forms is not None else f"this {base.n_joints}-joint arm"
            if ":" in law:
                raise SweepError(
                    f"{src}: {where}: {c!r} is a plug-in{'' if c == law else f' ({law})'}; a sweep runs "
                    "built-in controllers and their variants only "
                    f"({known}): set sweep.controllers to some of those, run a plug-in over arms and seeds "
                    "with `adaptive-dd leaderboard --plugin`, or over one scenario with `adaptive-dd "
                    "benchmark` (docs/sweeps.md)"
                )
            if law not in CONTROLLERS:
                raise SweepError(
                    f"{src}: {where}: unknown controller {c!r}; known: {known}, or a variant of one of them "
                    f"that the base scenario {base.source} lists, its [controllers.NAME] table naming its law"
                )
            raise SweepError(
                f"{src}: {where}: controller {c!r} is not for {kind} "
                f"({CONTROLLERS[law].only}); known for it: {known}"
            )
    if len(set(ctrls)) != len(ctrls):
        raise SweepError(f"{src}: key 'sweep.controllers' lists a controller twice: {ctrls}")
    return tuple(ctrls)


def _values(src: str, key: str, v: Any, *, numeric: bool) -> tuple[Any, ...]:
    if not isinstance(v, list) or not v:
        raise SweepError(f"{src}: key '{key}' must be a non-empty list of values, got {v!r}")
    for x in v:
        if numeric and (isinstance(x, bool) or not isinstance(x, int | float)):
            raise SweepError(f"{src}: key '{key}': values must be numbers, got {x!r}")
    same = [float(x) if isinstance(x, int | float) and not isinstance(x, bool) else x for x in v]  # 1 == 1.0
    if len(set(map(repr, same))) != len(v):
        raise SweepError(f"{src}: key '{key}' lists a value twice: {v!r}")
    return tuple(float(x) for x in v) if numeric else tuple(v)


def _axes(src: str, grid: Any, ctrls: tuple[str, ...]) -> tuple[tuple[str, tuple[Any, ...]], ...]:
    if not isinstance(grid, dict):
        raise SweepError(f"{src}: [grid] must be a table")
    axes = []
    for key, v in grid.items():
        if key == "controller":
            if not isinstance(v, dict):
                raise SweepError(f"{src}: key 'grid.controller' must be a table of [grid.controller.NAME]")
            for name, table in v.items():
                if name not in ctrls:
                    raise SweepError(
                        f"{src}: key 'grid.controller.{name}': {name!r} is not in sweep.controllers {ctrls}"
                    )
                if not isinstance(table, dict) or not table:
                    raise SweepError(f"{src}: key 'grid.controller.{name}' must be a table of settings lists")
                for k, vals in table.items():
                    full = f"grid.controller.{name}.{k}"
                    if k == "law":  # a law is an entry of the list, not a value of a grid
                        raise SweepError(
                            f"{src}: key '{full}': a law is not a grid axis; give each law its entry in "
                            'sweep.controllers (a variant: its [controllers.NAME] table with law = "...")'
                        )
                    axes.append((f"{name}.{k}", _values(src, full, vals, numeric=False)))
        elif key in SCENARIO_AXES:
            axes.append((key, _values(src, f"grid.{key}", v, numeric=True)))
        else:
            from adaptive_dd.benchmark.key_hints import did_you_mean

            hint = did_you_mean(str(key), [*SCENARIO_AXES, "controller"], lambda k: repr(f"grid.{k}"))
            raise SweepError(
                f"{src}: unknown key 'grid.{key}'{hint}; allowed: {[*SCENARIO_AXES, 'controller']}"
            )
    return tuple(axes)


_AXIS_WORDS = {
    "payload_mass": ("].mass",),
    "swap_time": ("].at",),
    "bandwidth": ("bandwidth",),
    "noise_scale": ("noise.", "_variance"),
}
"""What a scenario's error names when a grid axis made it (the axes blamed in a grid point's error)."""


def _apply(
    src: str, base: Scenario, swap: int, coords: dict[str, float], duration: float | None = None
) -> Scenario:
    """The base scenario with the scenario axes of one grid point applied, and ``sweep.duration``
    (checked against the grid point's swaps: a swap the grid moves before it is no error)."""
    times, masses = list(base.swap_times), list(base.swap_masses)
    changes: dict[str, Any] = {} if duration is None else {"duration": duration}
    where = ", ".join(f"{k} = {v}" for k, v in coords.items())
    if "payload_mass" in coords:
        if coords["payload_mass"] < 0:
            m = coords["payload_mass"]
            raise SweepError(f"{src}: key 'grid.payload_mass': mass must be >= 0 kg, got {m}")
        masses[swap] = coords["payload_mass"]
    if "swap_time" in coords:
        t = coords["swap_time"]
        lo = times[swap - 1] if swap > 0 else 0.0
        hi = times[swap + 1] if swap + 1 < len(times) else changes.get("duration", base.duration)
        if not lo < t < hi:
            raise SweepError(
                f"{src}: key 'grid.swap_time' = {t} s (at {where}): payload {swap} must swap "
                f"strictly between {lo} s and {hi} s (the neighbouring swaps or the run's end)"
            )
        times[swap] = t
    late = [] if duration is None else [i for i, t in enumerate(times) if t >= duration]
    if late:  # the grid point named only where it moved that swap
        moved = "swap_time" in coords and late[0] == swap
        raise SweepError(
            f"{src}: key 'sweep.duration' = {duration:g} s ends before the scenario's swap at "
            f"{times[late[0]]:g} s" + (f" (at {where})" if moved else "")
        )
    if "bandwidth" in coords:
        if not coords["bandwidth"] > 0:
            raise SweepError(f"{src}: key 'grid.bandwidth' must be > 0 rad/s, got {coords['bandwidth']}")
        changes["bandwidth"] = coords["bandwidth"]
    if "noise_scale" in coords:
        s = coords["noise_scale"]
        if not s >= 0:
            raise SweepError(f"{src}: key 'grid.noise_scale' must be >= 0, got {s}")
        changes["position_variance"] = tuple(s * v for v in base.position_variance)
        changes["velocity_variance"] = tuple(s * v for v in base.velocity_variance)
    try:
        return dataclasses.replace(base, swap_times=tuple(times), swap_masses=tuple(masses), **changes)
    except ScenarioError as exc:  # the grid point's values, not the base scenario's file, are wrong
        why = str(exc).replace(f"Scenario from {base.source}, as changed in code: ", "")
        why = why.replace(f"{base.source}: ", "")
        blamed = [k for k in coords if any(w in why for w in _AXIS_WORDS.get(k, ()))] or list(coords)
        keys = ", ".join(f"'grid.{k}'" for k in blamed)
        raise SweepError(f"{src}: key {keys} (at {where}): {why}") from None


def cell_scenario(scenario: Scenario, controller: str, settings: Mapping[str, Any] | None) -> Scenario:
    """The scenario running ``controller`` alone, with its own ``[controllers.NAME]`` settings and
    the grid point's over them: the benchmark then builds it as for any arm (two-link or URDF)."""
    from adaptive_dd.benchmark.scenario_checks import freeze

    opts = {**scenario.options(controller), **dict(settings or {})}
    table = ((controller, freeze(opts)),) if opts else ()
    return dataclasses.replace(scenario, controllers=(controller,), controller_options=table)


def _check_settings(src: str, points: list) -> None:
    """Each grid point's controller settings checked as a scenario's ``[controllers.NAME]`` table
    is (an unknown key, a value out of range): an error of the sweep file, not of every task."""
    from adaptive_dd.benchmark.scenario_checks import freeze
    from adaptive_dd.benchmark.scenario_settings import controller_setting_errors

    seen = set()
    for p in points:
        for name, kv in p.settings:
            sc = cell_scenario(p.scenario, name, dict(kv))
            key = (name, freeze(dict(kv)), sc.duration, sc.sample_period, sc.bandwidth, sc.damping)
            if key in seen:
                continue
            seen.add(key)
            fields = {f.name: getattr(sc, f.name) for f in dataclasses.fields(sc) if f.init}
            errors = controller_setting_errors(fields, floors=False)  # its floor: judged on the list
            if errors:
                where = ", ".join(f"{a} = {v}" for a, v in p.values)
                raise SweepError(f"{src}: key 'grid.controller.{name}' (at {where}): {'; '.join(errors)}")


def _heatmap(src: str, hm: Any, axes, ctrls, swap: int, n_segments: int) -> dict[str, Any] | None:
    if not isinstance(hm, dict):
        raise SweepError(f"{src}: [heatmap] must be a table")
    for key in hm:
        if key not in _HEATMAP_KEYS:
            raise SweepError(f"{src}: unknown key 'heatmap.{key}'; allowed: {sorted(_HEATMAP_KEYS)}")
    names = [a for a, _ in axes]
    varied = [a for a, v in axes if len(v) > 1]
    out = {
        "x": hm.get("x", varied[0] if varied else None),
        "y": hm.get("y", varied[1] if len(varied) > 1 else None),
        "adaptive": hm.get("adaptive", "adaptive_ct"),
        "floor": hm.get("floor", "ct_oracle"),
        "segment": hm.get("segment", swap + 1),
    }
    explicit = bool(hm)
    for key in ("x", "y"):
        if key == "y" and out["y"] is None and "y" not in hm:  # one axis varied: a one-row map
            continue
        if out[key] is None or out[key] not in names:
            if not explicit:
                return None
            raise SweepError(f"{src}: key 'heatmap.{key}' = {out[key]!r} must name a grid axis: {names}")
    if out["x"] == out["y"]:
        raise SweepError(f"{src}: keys 'heatmap.x' and 'heatmap.y' name the same axis {out['x']!r}")
    for key in ("adaptive", "floor"):
        if out[key] not in ctrls:
            if not explicit:
                return None
            raise SweepError(f"{src}: key 'heatmap.{key}' = {out[key]!r} is not in sweep.controllers {ctrls}")
    seg = _int(src, "heatmap.segment", out["segment"], 0)
    if seg >= n_segments:
        raise SweepError(f"{src}: key 'heatmap.segment' = {seg}: the scenario has {n_segments} segments")
    return out


def parse_sweep(data: dict, src: str = "<memory>", base_dir: str | Path = ".") -> Sweep:
    """Check a sweep given as a dict (the parsed TOML) and expand its grid.

    Parameters
    ----------
    data : dict
        The sweep's tables, as :func:`load_sweep` reads them from TOML.
    src : str
        Where the data came from, named in error messages.
    base_dir : str or Path
        The folder a relative ``scenario`` path is read from.

    Returns
    -------
    Sweep
        The checked sweep with its grid expanded.

    Examples
    --------
    >>> from adaptive_dd.benchmark.scenario import default_scenario_path
    >>> table = {"sweep": {"scenario": str(default_scenario_path()), "seeds": 2,
    ...                    "controllers": ["ct_oracle", "adaptive_ct"]},
    ...          "grid": {"payload_mass": [1.0, 3.0], "bandwidth": [20.0, 40.0]},
    ...          "heatmap": {"x": "payload_mass", "y": "bandwidth", "adaptive": "adaptive_ct",
    ...                      "floor": "ct_oracle", "segment": 1}}
    >>> from adaptive_dd.sweep_spec import parse_sweep
    >>> sweep = parse_sweep(table)
    >>> len(sweep.points), sweep.points[0].values
    (4, (('payload_mass', 1.0), ('bandwidth', 20.0)))
    >>> sweep.points[3].scenario.swap_masses[0], sweep.points[3].scenario.bandwidth
    (3.0, 40.0)
    """
    for table in data:
        if table not in ("sweep", "grid", "heatmap"):
            raise SweepError(f"{src}: unknown table [{table}]; allowed: ['grid', 'heatmap', 'sweep']")
    sw = data.get("sweep", {})
    if not isinstance(sw, dict):
        raise SweepError(f"{src}: [sweep] must be a table")
    for key in sw:
        if key not in _SWEEP_KEYS:
            from adaptive_dd.benchmark.key_hints import did_you_mean

            raise SweepError(
                f"{src}: unknown key 'sweep.{key}'{did_you_mean(key, _SWEEP_KEYS)}; allowed: "
                f"{sorted(_SWEEP_KEYS)}"
            )
    base, duration = _base_scenario(src, sw, Path(base_dir))
    seeds = _int(src, "sweep.seeds", sw.get("seeds", base.seeds), 1)
    block = _int(src, "sweep.block", sw.get("block", seeds), 1)
    ctrls = _controllers(src, sw, base)
    seed = _int(src, "sweep.seed", sw["seed"], 0) if "seed" in sw else base.seed
    try:  # the scenario's own bounds on them, named as the sweep's keys
        base = dataclasses.replace(base.with_controllers(ctrls), seeds=seeds, seed=seed)
    except ScenarioError as exc:
        raise SweepError(f"{src}: key 'sweep.seeds' = {seeds} or 'sweep.seed' = {seed}: {exc}") from None
    axes = _axes(src, data.get("grid", {}), ctrls)
    swap = _int(src, "sweep.swap", sw.get("swap", 0), 0)
    if any(a in ("payload_mass", "swap_time") for a, _ in axes) and swap >= len(base.swap_times):
        raise SweepError(
            f"{src}: key 'sweep.swap' = {swap}: the scenario has {len(base.swap_times)} payload swap(s)"
        )
    points = []
    for i, combo in enumerate(itertools.product(*(v for _, v in axes))):
        values = tuple((a, v) for (a, _), v in zip(axes, combo, strict=True))
        coords = {a: v for a, v in values if a in SCENARIO_AXES}
        settings: dict[str, list] = {}
        for a, v in values:
            if a not in SCENARIO_AXES:
                name, key = a.split(".", 1)
                settings.setdefault(name, []).append((key, v))
        sc = _apply(src, base, swap, coords, duration)
        points.append(GridPoint(i, values, sc, tuple((n, tuple(kv)) for n, kv in settings.items())))
    _check_settings(src, points)
    hm = _heatmap(src, data.get("heatmap", {}), axes, ctrls, swap, len(base.swap_times) + 1)
    return Sweep(src, base, seeds, min(block, seeds), ctrls, axes, tuple(points), hm)


def gains_apart(sweep: Sweep) -> dict[int, str]:
    """``{grid point: why}`` where the heat map's law runs at another ``bandwidth`` or ``damping``
    than its floor (the grid or the scenario's tables set one and not the other): the cell's ratio
    then compares two gains as well as two laws. :func:`~adaptive_dd.sweep.run_sweep` marks those
    cells and the command says so before it runs (the benchmark's warning,
    :func:`~adaptive_dd.benchmark.preflight.floor_problems`)."""
    from adaptive_dd.benchmark.preflight import gains_apart as differ

    hm = sweep.heatmap
    out: dict[int, str] = {}
    for p in sweep.points if hm else ():
        sc = p.scenario
        law, floor = ({**sc.options(c), **p.settings_for(c)} for c in (hm["adaptive"], hm["floor"]))
        why = [
            f"{hm['adaptive']}.{k} = {a} but its floor {hm['floor']}'s is {b}"
            for k, a, b in differ(law, floor, sc)
        ]
        if why:
            out[p.index] = "; ".join(why) + ": a ratio of two gains as well as two laws"
    return out


def mark_gains_apart(ratios, sweep: Sweep):
    """``ratios`` (:func:`~adaptive_dd.sweep.ratio_medians`) with the cells of
    :func:`gains_apart` marked, their other marks kept."""
    for i, why in gains_apart(sweep).items():
        at = ratios["point"] == i
        ratios.loc[at, "marked"] = ["; ".join(filter(None, (m, why))) for m in ratios.loc[at, "marked"]]
    return ratios
