"""One scenario's payload schedule over a population of drawn arms (``benchmark FILE --arms N``).

Arm ``k`` of the population is :func:`~adaptive_dd.robots.random_arm.random_arm` of seed
``first + k``. Each one is given the template scenario's ``[run]``, ``[control]``,
``[noise]``, ``[plant]``, ``[model]`` and ``[controllers.*]`` tables and its swap times; its own
URDF, armature, payload capacity and reference (the template's ``[arm]`` robot or urdf and
``[reference]`` are replaced, as their joints would not match). The template's payload masses
are read as a share of its ``[arm] payload_capacity`` (1 kg when it states none) and scaled to
each arm's capacity, the payload's inertia with them; its centre of mass is kept.

:func:`run_population` runs each arm as the benchmark runs a scenario and returns one
:class:`PopulationResult`; :func:`format_population` prints it per arm and pooled, the worst arms
named.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from adaptive_dd.errors import ScenarioError

__all__ = ["PopulationResult", "format_population", "population_scenario", "run_population"]

_ARM_KEYS_REPLACED = ("robot", "urdf", "payload_frame", "payload_capacity", "armature", "torque_limit")


def population_scenario(data: dict, src: str, arm_seed: int, *, draw_swaps: bool = False):
    """The template scenario ``data`` (parsed TOML) on the arm drawn from ``arm_seed`` (module
    docstring); ``draw_swaps``: the swap times drawn too, in order, anywhere in the reference's
    slowest period after the first second (seeded by the arm seed). Returns a checked
    :class:`~adaptive_dd.benchmark.scenario.Scenario`.

    Raises
    ------
    ScenarioError
        The template has no ``[[payload]]`` list, or its ``[arm]`` is the paper's two-link
        closed form (a population is of URDF arms), or the drawn scenario fails a check.
    """
    from adaptive_dd.benchmark.scenario import parse_scenario
    from adaptive_dd.robots.random_arm import random_arm

    data = copy.deepcopy(data)
    arm = data.get("arm") or {}
    two_link = ("sigma", "l1", "l2", "m1", "m2", "a1", "a2", "I1", "I2", "b", "d")
    if not isinstance(arm, dict) or any(k in arm for k in two_link):
        raise ScenarioError(
            f"{src}: [arm]: --arms needs a template of a URDF arm ([arm] robot = ... or none); "
            "the paper's two-link closed form has no population"
        )
    base_capacity = arm.get("payload_capacity", 1.0)
    payloads = data.get("payload")
    if not isinstance(base_capacity, int | float) or isinstance(base_capacity, bool) or not base_capacity > 0:
        raise ScenarioError(f"{src}: key 'arm.payload_capacity' must be a mass > 0 kg, got {base_capacity!r}")
    if not isinstance(payloads, list) or not payloads:
        raise ScenarioError(f"{src}: --arms needs the template's [[payload]] schedule; it has none")
    drawn = random_arm(arm_seed)
    data["arm"] = {**{k: v for k, v in arm.items() if k not in _ARM_KEYS_REPLACED}, **drawn.arm_table()}
    data["reference"] = copy.deepcopy(drawn.reference)
    scale = drawn.payload_capacity / float(base_capacity)
    for p in payloads:
        if isinstance(p, dict) and isinstance(p.get("mass"), int | float):
            p["mass"] = round(float(p["mass"]) * scale, 6)
            if isinstance(p.get("inertia"), list):
                p["inertia"] = [float(x) * scale for x in p["inertia"]]
    if draw_swaps:
        _draw_swaps(payloads, drawn, arm_seed)
    return parse_scenario(data, src, name=f"{Path(src).stem}_arm{arm_seed}")


def _draw_swaps(payloads: list, drawn, arm_seed: int) -> None:
    """Swap times anywhere in the reference's slowest period, one per consecutive window of it."""
    rng = np.random.default_rng([int(arm_seed), 7])
    f_min = min(min(r["frequency"]) for k, r in drawn.reference.items() if k.startswith("joint"))
    times = sorted(p["at"] for p in payloads)
    for i, p in enumerate(sorted(payloads, key=lambda p: p["at"])):
        lo = times[i - 1] + 0.5 if i else 1.0
        hi = min(lo + 1.0 / f_min, times[i + 1] - 0.5 if i + 1 < len(times) else times[i] + 1.0 / f_min)
        hi = max(hi, lo + 0.1)
        p["at"] = round(float(rng.uniform(lo, hi)), 3)
        times[i] = p["at"]


@dataclass
class PopulationResult:
    """The runs of a population.

    Attributes
    ----------
    arms : list of dict
        Per arm: ``arm_seed``, ``joints``, ``kind``, ``capacity_kg``, ``segments`` (per segment
        ``mean``, ``p90``, ``max`` of adaptive_ct / its floor over the seeds), ``floor`` (that floor's
        name), ``false_alarm_trials``,
        ``trials``, ``missed_swaps``, ``swaps``.
    floor_caveat : str or None
        Why the floor is no floor on these arms' plants
        (:func:`~adaptive_dd.benchmark.metrics.floor_caveat`; the same for every arm of a template).
    frame : pandas.DataFrame
        The per-seed tables of every arm (:func:`~adaptive_dd.benchmark.results.to_frame`),
        ``arm_seed`` as their first column.
    laws : dict
        ``{controller: its arms' summaries, as arms}`` for every controller of the run measured
        against a floor (``arms`` is ``laws[lead]``).
    lead : str
        The controller ``arms`` and the per-arm table are of: ``adaptive_ct`` when it runs, else the
        first controller with a floor.
    """

    arms: list[dict] = field(default_factory=list)
    frame: object = None
    floor_caveat: str | None = None
    laws: dict = field(default_factory=dict)
    lead: str = "adaptive_ct"


def run_population(data: dict, src: str, arm_seeds, *, seeds=None, controllers=None, progress=False,
                   draw_swaps=False, on_arm=None, settings=None) -> PopulationResult:  # fmt: skip
    """Run the template over the arms ``arm_seeds`` (:func:`population_scenario`).

    Parameters
    ----------
    data, src : dict, str
        The template (parsed TOML) and its file.
    arm_seeds : iterable of int
    seeds : int, optional
        Trials per arm (default the template's).
    controllers : callable, optional
        ``controllers(scenario) -> tuple of names``, to narrow the template's list.
    on_arm : callable, optional
        ``on_arm(summary)`` after each arm (the CLI prints a line).
    settings : dict, optional
        ``{controller: settings table}`` set on every arm's scenario
        (:func:`~adaptive_dd.benchmark.scenario_settings.with_settings`): settings no scenario file
        sets, such as ``adaptive_ct``'s estimator table, for measurements.
    """
    import dataclasses

    import pandas as pd

    from adaptive_dd.benchmark.metrics import compute_metrics, release_error_norm
    from adaptive_dd.benchmark.runner import run_benchmark
    from adaptive_dd.benchmark.scenario_settings import with_settings
    from adaptive_dd.robots.random_arm import random_arm

    out = PopulationResult()
    frames = []
    for arm_seed in arm_seeds:
        sc = population_scenario(data, src, int(arm_seed), draw_swaps=draw_swaps)
        if seeds is not None:
            sc = dataclasses.replace(sc, seeds=seeds)
        for name, table in (settings or {}).items():
            sc = with_settings(sc, name, table)
        if controllers is not None:  # the tables of the controllers left out go with them
            sc = sc.with_controllers(controllers(sc))
        res = run_benchmark(sc, progress=progress, on_run=release_error_norm)
        metrics = compute_metrics(res)
        out.floor_caveat = metrics["floor_caveat"]
        drawn = random_arm(int(arm_seed))
        measured = [n for n, c in metrics["controllers"].items() if c.get("floor")]
        if not measured:
            raise ScenarioError(
                f"{src}: --arms reports each law against its floor: none of {list(metrics['controllers'])} "
                "has one that ran (list a law that adapts or a plug-in beside the oracles)"
            )
        out.lead = "adaptive_ct" if "adaptive_ct" in measured else measured[0]
        for name in measured:
            out.laws.setdefault(name, []).append(arm_summary(metrics, int(arm_seed), drawn, sc, name))
        summary = out.laws[out.lead][-1]
        out.arms.append(summary)
        frame = res.to_frame()
        frame.insert(0, "arm_seed", int(arm_seed))
        frames.append(frame)
        if on_arm is not None:
            on_arm(summary)
    out.frame = pd.concat(frames, ignore_index=True) if frames else None
    return out


def arm_summary(metrics: dict, arm_seed: int, drawn, sc, name: str = "adaptive_ct") -> dict:
    """One arm's figures of controller ``name`` from its metrics (:func:`compute_metrics`)."""
    a = metrics["controllers"].get(name)
    if a is None:
        raise ScenarioError(f"{sc.source}: --arms reports {name} against its floor: list {name}")
    segs = []
    for s in a["segments"]:
        st = s.get("ratio_to_floor") or {}
        segs.append(
            {
                "start": s["start"],
                "end": s["end"],
                "mass": s["mass"],
                "mean": st.get("mean", math.nan),
                "p90": st.get("p90", math.nan),
                "max": st.get("max", math.nan),
                "floor_saturated": bool(s.get("floor_saturated")),
            }
        )
    fa = [x for x in a.get("false_alarms_per_seed") or [] if x is not None]
    ms = [x for x in a.get("missed_swaps_per_seed") or [] if x is not None]
    return {
        "arm_seed": arm_seed,
        "controller": name,
        "floor": a.get("floor"),
        "joints": drawn.n_joints,
        "kind": drawn.kind,
        "capacity_kg": drawn.payload_capacity,
        "segments": segs,
        "false_alarm_trials": int(a.get("trials_with_false_alarms") or 0),
        "trials": len(fa),
        "missed_swaps": int(a.get("missed_swaps") or 0),
        "swaps": len(ms) * (len(segs) - 1),
    }


def judged_rows(pop: PopulationResult):
    """``pop.frame`` without the rows of a segment whose floor saturated on that arm (per law: no
    verdict there), as :func:`pooled` leaves them out: what the ratio figure plots."""
    f = pop.frame
    saturated = {
        (a.get("controller", pop.lead), a["arm_seed"], i)
        for arms in (pop.laws or {pop.lead: pop.arms}).values()
        for a in arms
        for i, s in enumerate(a["segments"])
        if s["floor_saturated"]
    }
    keep = [
        (c, a, s) not in saturated
        for c, a, s in zip(f["controller"], f["arm_seed"], f["segment"], strict=True)
    ]
    return f[np.array(keep, bool)]


def pooled(pop: PopulationResult, name: str | None = None) -> list[dict]:
    """Per segment index: ``mean``, ``p90``, ``max`` of controller ``name`` (default the lead's,
    ``adaptive_ct``) / its floor over every arm and seed (trials that failed or whose floor saturated
    left out), the worst ``(arm_seed, seed)``."""
    name = name or pop.lead
    f = judged_rows(pop)
    rows = f[(f["controller"] == name) & f["ratio_to_floor"].notna()]
    out = []
    for s, g in rows.groupby("segment", sort=True):
        r = g["ratio_to_floor"].to_numpy(float)
        k = int(np.argmax(r))
        share = (g["mass_kg"] / g["arm_seed"].map({a["arm_seed"]: a["capacity_kg"] for a in pop.arms})).mean()
        out.append(
            {
                "segment": int(s),
                "capacity_share": float(share),
                "n": int(r.size),
                "mean": float(r.mean()),
                "p90": float(np.quantile(r, 0.9)),
                "max": float(r[k]),
                "worst": (int(g["arm_seed"].iloc[k]), int(g["seed"].iloc[k])),
            }
        )
    return out


def format_population(pop: PopulationResult, worst: int = 3) -> str:
    """The per-arm table, the pooled figures against the targets, the worst arms named."""
    from adaptive_dd.benchmark.report import (
        TARGET_FALSE_ALARM_PCT,
        TARGET_RATIO_MAX,
        TARGET_RATIO_MEAN,
        TARGET_RATIO_P90,
    )

    floors = sorted({a.get("floor") or "its floor" for a in pop.arms}) or ["its floor"]
    floor = " or ".join(floors)
    lead = pop.lead
    targets = lead == "adaptive_ct"  # the targets are adaptive_ct's
    lines = [f"{lead} / {floor} per seed, per arm (mean per segment; max over segments):"]
    for a in pop.arms:
        means = " / ".join(f"{s['mean']:.3f}" for s in a["segments"])
        mx = max((s["max"] for s in a["segments"] if not math.isnan(s["max"])), default=math.nan)
        alarms = (
            f"; false alarms in {a['false_alarm_trials']} of {a['trials']} trials; missed swaps "
            f"{a['missed_swaps']} of {a['swaps']}"
            if a["trials"]  # (a law with no detector has no alarm to count)
            else ""
        )
        lines.append(
            f"  random:{a['arm_seed']} ({a['joints']} joints, {a['kind']}, {a['capacity_kg']:g} kg): {means} "
            f"(max {mx:.2f}){alarms}"
        )
    arms = f"{len(pop.arms)} arm{'s' if len(pop.arms) != 1 else ''}"
    lines.append(f"pooled over {arms} (segments numbered from 0, as in per_seed.csv):")
    if pop.floor_caveat:
        lines.append(f"  note: {pop.floor_caveat}")
    for p in pooled(pop):
        ok = p["mean"] <= TARGET_RATIO_MEAN and p["p90"] <= TARGET_RATIO_P90 and p["max"] <= TARGET_RATIO_MAX
        verdict = (
            f" (target mean <= {TARGET_RATIO_MEAN}, p90 <= {TARGET_RATIO_P90}, max <= {TARGET_RATIO_MAX}: "
            f"{'met' if ok else 'NOT met'})"
            if targets
            else ""
        )
        lines.append(
            f"  segment {p['segment']} ({p['capacity_share']:.2f} x capacity), {p['n']} trials: mean "
            f"{p['mean']:.3f}, p90 {p['p90']:.3f}, max {p['max']:.2f} (random:{p['worst'][0]} seed "
            f"{p['worst'][1]}){verdict}"
        )
    n_fa = sum(a["false_alarm_trials"] for a in pop.arms)
    n_tr = sum(a["trials"] for a in pop.arms)
    n_ms = sum(a["missed_swaps"] for a in pop.arms)
    n_sw = sum(a["swaps"] for a in pop.arms)
    if n_tr:  # a law with a change detector
        pct = 100.0 * n_fa / n_tr
        fa_ok, ms_ok = pct <= TARGET_FALSE_ALARM_PCT, n_ms == 0
        fa_t = (
            f" (target <= {TARGET_FALSE_ALARM_PCT:g} %: {'met' if fa_ok else 'NOT met'})" if targets else ""
        )
        ms_t = f" (target 0: {'met' if ms_ok else 'NOT met'})" if targets else ""
        lines.append(f"  trials with a false alarm: {n_fa} of {n_tr} ({pct:.1f} %){fa_t}")
        lines.append(f"  missed swaps: {n_ms} of {n_sw}{ms_t}")
    sat = sum(s["floor_saturated"] for a in pop.arms for s in a["segments"])
    if sat:
        lines.append(f"  {sat} arm segment(s) where {floor} saturates: no verdict there (left out above)")
    ranked = sorted(pop.arms, key=_badness, reverse=True)[:worst]
    lines.append(
        "  worst arms: "
        + "; ".join(
            f"random:{a['arm_seed']} (max {_badness(a)[1]:.2f}, {a['false_alarm_trials']} false-alarm "
            f"trials, {a['missed_swaps']} missed)"
            for a in ranked
        )
    )
    others = [n for n in pop.laws if n != lead]
    if others:
        lines.append(
            f"every law against its floor, pooled over {arms} (per segment from 0: mean; p90; max and its "
            "arm and seed):"
        )
        for name in (lead, *others):
            p = pooled(pop, name)
            fl = sorted({a.get("floor") or "?" for a in pop.laws[name]})
            worst_one = max(p, key=lambda x: x["max"], default=None)
            where = f" (random:{worst_one['worst'][0]} seed {worst_one['worst'][1]})" if worst_one else ""
            by_seg = {x["segment"]: x for x in p}  # a segment with no row left (floor saturated): "-"
            segs = range(max((len(a["segments"]) for a in pop.laws[name]), default=0))
            mean, p90, mx = (
                " / ".join(format(by_seg[i][k], f) if i in by_seg else "-" for i in segs)
                for k, f in KEYS_FORMATS
            )
            lines.append(f"  {name} / {' or '.join(fl)}: mean {mean}; p90 {p90}; max {mx}{where}")
    return "\n".join(lines)


KEYS_FORMATS = (("mean", ".3f"), ("p90", ".3f"), ("max", ".2f"))
"""The pooled statistics the every-law lines print, with their formats."""


def _badness(a: dict) -> tuple:
    """Missed swaps first, then the largest ratio, then false alarms."""
    mx = max((s["max"] for s in a["segments"] if not math.isnan(s["max"])), default=0.0)
    return (a["missed_swaps"], mx, a["false_alarm_trials"])


def arms_frame(pop: PopulationResult):
    """One row per controller, arm and segment: the per-arm table of every law measured against a
    floor, as a DataFrame (``arms.csv``)."""
    import pandas as pd

    rows = []
    for a in (a for arms in (pop.laws or {pop.lead: pop.arms}).values() for a in arms):
        for i, s in enumerate(a["segments"]):
            rows.append(
                {
                    "controller": a.get("controller", pop.lead),
                    "floor": a.get("floor"),
                    "arm_seed": a["arm_seed"],
                    "joints": a["joints"],
                    "kind": a["kind"],
                    "capacity_kg": a["capacity_kg"],
                    "segment": i,
                    "start_s": s["start"],
                    "end_s": s["end"],
                    "mass_kg": s["mass"],
                    "ratio_mean": s["mean"],
                    "ratio_p90": s["p90"],
                    "ratio_max": s["max"],
                    "floor_saturated": s["floor_saturated"],
                    "false_alarm_trials": a["false_alarm_trials"],
                    "trials": a["trials"],
                    "missed_swaps": a["missed_swaps"],
                    "swaps": a["swaps"],
                }
            )
    return pd.DataFrame(rows)
