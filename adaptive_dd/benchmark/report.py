"""Benchmark output: the printed table and targets, CSV, JSON and figures."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.controller_entries import variants_line
from adaptive_dd.benchmark.metrics import SATURATION_LIMIT, judged
from adaptive_dd.benchmark.metrics_files import write_csv, write_json
from adaptive_dd.benchmark.scenario import runtime_line
from adaptive_dd.benchmark.types import BenchmarkResult

__all__ = ["format_report", "write_csv", "write_json"]

TARGET_RATIO_MEAN = 1.1
TARGET_RATIO_P90 = 1.3
TARGET_RATIO_MAX = 3.0
TARGET_FALSE_ALARM_PCT = 1.0
TARGET_RATIO_NOMINAL = 5.0
TARGET_MASS_PCT = 5.0
TARGET_MASS_ABS = 0.05  # kg, for the segments without payload
TARGET_WALL_S = 60.0


TABLES = (
    ("RMS tracking error |e| [mrad] (true q)", "rms_error", 1e3, "{:16.3f}"),
    ("RMS tracking error after the first 0.5 s of the segment [mrad]", "rms_error_settled", 1e3, "{:16.3f}"),
    ("max tracking error |e| [mrad]", "max_error", 1e3, "{:16.2f}"),
    (
        "settling time after the swap [s] (to within 1.5x its own settled peak error, not its floor's)",
        "settling_time",
        1.0,
        "{:16.3f}",
    ),
    ("change detected after the swap [ms] (controllers with a detector)", "detection_delay", 1e3, "{:16.1f}"),
    ("RMS torque [N m]", "rms_torque", 1.0, "{:16.2f}"),
    ("saturated fraction [%]", "saturation_fraction", 100.0, "{:16.2f}"),
    ("payload mass estimated at the end of the segment [kg]", "mass_estimate", 1.0, "{:16.3f}"),
    ("tool frame: RMS position error [mm]", "ee_position_rms", 1.0, "{:16.3f}"),
    ("tool frame: peak position error [mm]", "ee_position_max", 1.0, "{:16.3f}"),
    ("tool frame: RMS orientation error [deg]", "ee_orientation_rms", 1.0, "{:16.4f}"),
)
"""The report's per-segment tables: title, metric key, scale to the printed unit, cell format."""


_ABOVE_FLOOR_GAIN = {
    "adaptive_ct": ("raises its feedback gains after each alarm (boost_duration)", "boost"),
    "sliding_mode": ("adds a robust term, inside its boundary layer a feedback lambda M0_jj s,", "term"),
}
"""The laws whose feedback exceeds their floor's, and how (the report's note under their ratios)."""


def format_report(metrics: dict, res: BenchmarkResult) -> str:
    """Tables per metric (rows: controllers; columns: payload segments) and the targets."""
    ctrls = metrics["controllers"]
    sc = res.scenario
    n_run = len(res.seed_indices) or sc.seeds  # the seeds run (seed_indices may be some of them)
    head = f"{'controller':18s}" + "".join(f"{f'{a:g}-{b:g}s {m:g}kg':>16s}" for a, b, m in sc.segments())
    lines = [
        f"Scenario {_scenario_title(sc)}: {n_run} seeds, {sc.duration} s at T = {sc.sample_period} s, "
        f"bandwidth {sc.bandwidth} rad/s; means over seeds (a failed trial left out of the segments after "
        "its failure)",
        runtime_line(sc),
        *([variants_line(sc)] if variants_line(sc) else []),
        "",
    ]
    for title, key, scale, fmt in TABLES:
        lines += [title, head]
        for name, c in ctrls.items():
            cells = "".join(
                fmt.format(s[key] * scale) if s[key] is not None else f"{'—':>16}" for s in c["segments"]
            )
            lines.append(f"{name:18s}{cells}")
        lines.append("")
    lines += _payload_tables(ctrls, head)
    lines += _seed_tables(ctrls, head, metrics.get("floor_caveat"))
    lines += _failure_lines(ctrls)
    phase = f", after an excitation phase of {sc.excite:g} s ([run] excite)" if sc.excite else ""
    lines += ["", f"Targets{phase} (measured, not asserted):"]
    lines += _targets(metrics, res)
    return "\n".join(lines)


def _scenario_title(sc) -> str:
    """The scenario's file, and its name when it is not the file's (renamed in code: what the run
    ran may differ from the file; ``metrics.json``'s ``provenance.scenario`` holds every value)."""
    from pathlib import Path

    if not sc.source or Path(str(sc.source)).stem == sc.name:
        return str(sc.source or sc.name)
    return f"{sc.name} (from {sc.source}, as changed in code)"


def _failure_lines(ctrls: dict) -> list[str]:
    """Failed trials per controller, the first three with seed, time and reason; lost measurements."""
    fails = [f"{n}: {c['failed_trials']}" for n, c in ctrls.items() if c["failed_trials"]]
    lines = ["failed trials: " + (", ".join(fails) if fails else "none")]
    for n, c in ctrls.items():
        groups: dict = {}  # the same reason at the same time (a controller that raised): one line
        for f in c.get("failures", []):
            groups.setdefault((f["t"], f["why"]), []).append(f["seed"])
        for (t, why), seeds in list(groups.items())[:3]:
            at = f"t = {t:.3f} s" if t is not None else "time not recorded"  # e.g. raised in compiled code
            who = f"seed {seeds[0]}" if len(seeds) == 1 else f"seeds {_seed_list(seeds)}"
            lines.append(f"  {n}, {who}, {at}: {_brief_reason(why)}")
        if len(groups) > 3:
            lines.append(f"  {n}: {len(groups) - 3} more reasons in metrics.json (failures)")
    drops = [f"{n}: {c['dropped_samples']}" for n, c in ctrls.items() if c.get("dropped_samples")]
    if drops:
        skips = [
            f"{n}: {sum(c['skipped_samples_per_seed'])}"
            for n, c in ctrls.items()
            if c.get("skipped_samples_per_seed") is not None
        ]
        lines.append(
            "lost measurements (noise.dropout; the law holds the last good one): " + ", ".join(drops)
        )
        lines.append(
            "samples the estimators skipped (NaN, the filters' memory after each loss): " + ", ".join(skips)
        )
    for n, c in ctrls.items():
        bad = c.get("nonfinite_estimates") or []
        if bad:
            seeds = sorted({s for s, _ in bad})
            lines.append(
                f"{n}: its estimate is not finite at the end of {len(bad)} segment(s) of trials that did not "
                f"fail (seeds {_seed_list(seeds)}): left out of the payload mass and centre of mass columns"
            )
    return lines


def _seed_list(seeds: list) -> str:
    """``0, 1, 2`` (at most five, then how many more)."""
    shown = ", ".join(str(s) for s in seeds[:5])
    return shown + (f" and {len(seeds) - 5} more" if len(seeds) > 5 else "")


def _brief_reason(why: str) -> str:
    """A failure's reason on one line: a long, multi-line one (numba's typing errors) cut to its
    first line and numba's hint on the argument (``- argument ...``); the whole in metrics.json."""
    lines = [x.strip() for x in why.splitlines() if x.strip()]
    if len(lines) <= 1:
        return why
    hints = [x for x in lines if x.startswith("- argument")]
    return " ... ".join([lines[0], *hints]) + " (the whole message: metrics.json, failures)"


def _payload_tables(ctrls: dict, head: str) -> list[str]:
    """N-joint runs: the payload's centre of mass estimated at the end of each segment, and
    ct_nominal's RMS error over ct_oracle's per segment."""
    lines = []
    rows = [(n, c) for n, c in ctrls.items() if any(s.get("com_estimate") for s in c["segments"])]
    if rows:
        lines += [
            "payload centre of mass estimated at the end of the segment [mm] (x, y, z; -: an axis the "
            "data do not determine)",
            head,
        ]
        first = rows[0][1]["segments"]
        truth = "".join(
            f"{'none':>16}" if s.get("com_true") is None else f"{_xyz(s['com_true']):>16}" for s in first
        )
        lines.append(f"{'(true)':18s}{truth}")
        for name, c in rows:
            lines.append(f"{name:18s}" + "".join(f"{_xyz(s.get('com_estimate')):>16}" for s in c["segments"]))
        lines.append("")
    if "ct_nominal" in ctrls and "ct_oracle" in ctrls and rows:
        cells = ""
        for sn, so in zip(ctrls["ct_nominal"]["segments"], ctrls["ct_oracle"]["segments"], strict=True):
            ok = sn["rms_error"] is not None and so["rms_error"]
            cells += f"{sn['rms_error'] / so['rms_error']:16.1f}" if ok else f"{'—':>16}"
        lines += [
            "RMS error of ct_nominal / ct_oracle (means over seeds)",
            head,
            f"{'ct_nominal':18s}{cells}",
            "",
        ]
    return lines


def _xyz(v) -> str:
    """A centre of mass [m] as ``x,y,z`` in mm; a component the data do not determine (None: a
    planar arm's axis along its joints) as ``-``; the whole ``—`` when there is none."""
    if v is None or all(x is None for x in v):
        return "—"
    return ",".join("-" if x is None else f"{1e3 * x:.0f}" for x in v)


def _seed_tables(ctrls: dict, head: str, caveat: str | None = None) -> list[str]:
    """Per-seed ratio to each controller's floor: mean [95 % CI], median, p90, max and worst seed;
    ``caveat``: why the floor is no floor here (:func:`~adaptive_dd.benchmark.metrics.floor_caveat`)."""
    rows = [(n, c) for n, c in ctrls.items() if c.get("floor")]
    if not rows:
        return []
    lines = [
        "Per-seed RMS error ratio to the floor (the same law with the true model; common random numbers)"
    ]
    if caveat:
        lines.append(f"  note: {caveat}")
    for name, (why, what) in _ABOVE_FLOOR_GAIN.items():  # more feedback than its floor: below 1
        c = ctrls.get(name) or {}  # is that feedback, not a model better than the true one
        if c.get("floor") and any(
            (s.get("ratio_to_floor") or {}).get("mean", 1.0) < 1.0 for s in c["segments"]
        ):
            lines.append(f"  note: {name} {why} and its floor does not: a ratio below 1 is that {what}, not "
                         "a model better than the true one")  # fmt: skip
    sat = {c["floor"] for _, c in rows if any(s.get("floor_saturated") for s in c["segments"])}
    if sat:
        lines.append(
            f"  ! the floor ({', '.join(sorted(sat))}) saturates in more than {100 * SATURATION_LIMIT:g} % "
            "of the segment's samples: no verdict there (the ratio compares two laws held by the torque "
            "limits; the table 'saturated fraction [%]' above)"
        )
    for label, key in (("mean", "mean"), ("median", "median"), ("p90", "p90"), ("max", "max")):
        lines += [f"  {label}", head]
        for name, c in rows:
            cells = "".join(_ratio_cell(s, key) for s in c["segments"])
            lines.append(f"{name:18s}" + cells + f"   (floor: {c['floor']})")
    n = max(
        (s["ratio_to_floor"].get("n", 0) for _, c in rows for s in c["segments"] if s.get("ratio_to_floor")),
        default=0,
    )
    few = 1 < n < FEW_SEEDS  # the bootstrap resamples only the seeds there are
    lines += [
        "  95 % confidence interval of the mean, and the worst seed"
        + (f" (a bootstrap over {n} seeds: too narrow below about {FEW_SEEDS})" if few else ""),
        head,
    ]
    for name, c in rows:
        cells = ""
        for s in c["segments"]:
            st = s.get("ratio_to_floor")
            ci = st and st["ci95"]
            text = f"[{_ci_end(ci[0])}, {_ci_end(ci[1])}]" if ci else ""  # brackets: -2.09-8.27 read as one
            cells += " " + f"{text + ' #' + str(st['worst_seed']):>15}" if ci else f"{'—':>16}"
        lines.append(f"{name:18s}{cells}")
    lines += [time_to_floor_line(n, c) for n, c in rows if c["segments"][0].get("time_to_floor")]
    fa = [(n, c) for n, c in ctrls.items() if c.get("false_alarms_per_seed") is not None]
    for name, c in fa:
        n_ok = sum(1 for x in c["false_alarms_per_seed"] if x is not None)
        total = sum(x for x in c["false_alarms_per_seed"] if x is not None)
        lines.append(
            f"{name}: false alarms (not within 0.3 s after a swap) in {c['trials_with_false_alarms']} of "
            f"{n_ok} trials, {total} in all"
        )
        seen = judged_swaps(c)
        n_swaps = n_ok * sum(seen)
        per_swap = ", ".join(
            f"{s['start']:g} s: " + (f"{s['missed']}" if ok else "not judged (the run ends within 0.3 s)")
            for s, ok in zip(c["segments"][1:], seen, strict=True)
        )
        lines.append(
            f"{name}: missed swaps (no alarm within 0.3 s after the swap) {c['missed_swaps']} of {n_swaps}"
            + (f" ({per_swap})" if per_swap else "")
        )
    return [*lines, ""]


def _ratio_cell(seg: dict, key: str) -> str:
    """A segment's ratio statistic ``key`` in 16 characters, ``!`` after it where the floor
    saturates (:data:`~adaptive_dd.benchmark.metrics.SATURATION_LIMIT`), a dash without one."""
    st = seg.get("ratio_to_floor")
    if not st:
        return f"{'—':>16}"
    return f"{st[key]:15.3f}!" if seg.get("floor_saturated") else f"{st[key]:16.3f}"


def _ci_end(x: float) -> str:
    """An end of a ratio's confidence interval: two decimals below 10, one below 100, none above."""
    return f"{x:.2f}" if abs(x) < 10 else f"{x:.1f}" if abs(x) < 100 else f"{x:.0f}"


def _seconds(t) -> str:
    return "never" if t == "never" else ("—" if t is None else f"{t:.2f} s")


def time_to_floor_line(name: str, c: dict) -> str:
    """The first segment's time to come within 1.2x of the floor
    (:mod:`~adaptive_dd.benchmark.time_to_floor`)."""
    tf = c["segments"][0]["time_to_floor"]
    return (
        f"{name}: first segment, time until its {tf['window']:g} s moving RMS error stays within "
        f"{tf['level']:g}x {c['floor']}'s: median {_seconds(tf['median'])}, p90 {_seconds(tf['p90'])}, "
        f"max {_seconds(tf['max'])}; never within it by the segment's end "
        f"({tf['segment_length']:g} s) in {tf['never']} of {tf['n']} trials"
    )


FEW_SEEDS = 10
"""Below this many seeds the report says its 95 % interval is too narrow (a percentile bootstrap
resamples only the seeds there are: on four about half a Student-t interval's width)."""

TARGET_INFO_RATIO = 3.0


def _information_lines(c: dict, all_unknown: bool) -> list[str]:
    """Per swap: the information-limited time to know the payload mass within 5 %, and each
    adaptive controller's time (median over the seeds with kept trajectories); the centre of
    mass's where it is computed. ``all_unknown``: the arm computes ``unknown`` (the two-link arm)."""
    out = []
    first = next(iter(c.values()))
    for i, seg in enumerate(first["segments"][1:], start=1):
        info = seg.get("information_time") or {}
        if info.get("known") is None:
            continue
        estimators = [n for n, x in c.items() if x["segments"][i].get("learning_seeds", 0) > 0]
        took = {n: c[n]["segments"][i]["mass_learning_time"] for n in estimators}
        took = {
            n: t for n, t in took.items() if t is not None
        }  # the others' median trajectory never learns it
        n_learn = {c[n]["segments"][i].get("learning_seeds", 0) for n in (took or estimators)}
        best = min(took.values()) if took else None
        ok = best is not None and best <= TARGET_INFO_RATIO * info["known"]
        unk = info.get("unknown")
        unk_s = f"{1e3 * unk:.0f} ms" if unk is not None else "not within the segment"
        unk_s = f", {unk_s} (all unknown)" if all_unknown else " (arm known, payload mode)"
        out.append(
            f"  payload mass within 5 % of the change after the swap at {seg['start']:g} s "
            f"({seg['mass']:g} kg): "
            f"information limit {1e3 * info['known']:.0f} ms (other parameters known){unk_s} "
            f"(median over {info.get('seeds', 1)} seed(s) of {info.get('reference', 'the oracle')}'s "
            "trajectory)"
            + (
                "; "
                + ", ".join(f"{n} {1e3 * took[n]:.0f} ms" if n in took else f"{n} never" for n in estimators)
                + (f" (median over {max(n_learn)} seed(s) with kept trajectories)" if n_learn else "")
                + f" (target best <= {TARGET_INFO_RATIO:g}x the known-parameters limit: "
                + ("met)" if ok else "NOT met)")
                if estimators
                else ": no controller here estimates the payload, no target to judge"
            )
        )
        if info.get("com_axes") is not None:
            out.append(_com_information_line(c, i, seg, info, estimators, n_learn))
    return out


def _com_information_line(c: dict, i: int, seg: dict, info: dict, estimators: list, n_learn: set) -> str:
    """The centre of mass's information limit after swap i, beside the time of each controller that
    estimates the payload (``estimators``; "never" where its median trajectory never learns it)."""
    com = {n: x["segments"][i].get("com_learning_time") for n, x in c.items()}
    lim = info["com_known"]
    lim_s = f"{1e3 * lim:.0f} ms" if lim is not None else "not within the segment"
    took_s = [
        f"{n} {'never' if t is None else f'{1e3 * t:.0f} ms'}" for n, t in com.items() if n in estimators
    ]
    partial = info["com_axes"] != "xyz"
    return (
        f"  payload centre of mass within 1 cm after the swap at {seg['start']:g} s"
        + (f" ({info['com_axes']} only: the rest is not identifiable)" if partial else "")
        + f": information limit {lim_s}"
        + (f"; {', '.join(took_s)}" if took_s else " (no controller of the run estimates the payload)")
        + (f" (median over {max(n_learn)} seed(s))" if n_learn and took_s else "")
    )


def judged_swaps(c: dict) -> list[bool]:
    """Per swap of a controller's metrics, whether the run lasts the detection window beyond it
    (:func:`~adaptive_dd.benchmark.metrics.judged`): only then can it be counted missed."""
    end = c["segments"][-1]["end"]  # the run's duration
    return [judged(s["start"], end) for s in c["segments"][1:]]


TARGET_DETECTION_RATIO = 2.0


def detection_limit_lines(c: dict) -> list[str]:
    """Per swap: each detector's median delay (and p90, max) beside the detection limit of an
    optimal test (:mod:`adaptive_dd.identification.two_link_detection_limit`), and the target on it."""
    out = []
    first = next(iter(c.values()))
    for i, seg in enumerate(first["segments"][1:], start=1):
        lim = seg.get("detection_limit")
        parts = []
        ok = None
        for name, x in c.items():
            per = x["segments"][i].get("detection_delay_per_seed")
            if per is None:
                continue
            d = np.array([v for v in per if v is not None])
            # the segment's own count: failed trials and a swap at the run's end are not in it
            n_miss = x["segments"][i].get("missed") or 0
            if d.size:
                med = float(np.median(d))
                parts.append(
                    f"{name} median {1e3 * med:.0f} ms (p90 {1e3 * np.percentile(d, 90):.0f}, "
                    f"max {1e3 * d.max():.0f}), missed in {n_miss} trials"
                )
                if lim is not None and lim > 0:
                    ok = med <= TARGET_DETECTION_RATIO * lim if ok is None else ok and med <= 2 * lim
            elif n_miss:
                parts.append(f"{name} missed in all {n_miss} trials")
            else:
                parts.append(f"{name}: no trial to judge (failed before it, or the run ends within 0.3 s)")
        if not parts:
            continue
        if "detection_limit" not in seg:  # a result written before the limit was computed
            lim_s = "not computed for this arm"
        else:
            lim_s = f"{1e3 * lim:.0f} ms" if lim is not None else "not reached in the window"
        verdict = (
            ""
            if ok is None
            else f" (target median <= {TARGET_DETECTION_RATIO:g}x: {'met' if ok else 'NOT met'})"
        )
        out.append(
            f"  change detected after the swap at {seg['start']:g} s: "
            + "; ".join(parts)
            + f"; detection limit {lim_s} (GLR at 1 % false alarms per trial, rest of the arm known)"
            + verdict
        )
    return out


def _targets(metrics: dict, res: BenchmarkResult) -> list[str]:
    """The report's target lines: each measured figure beside its target, met or not."""
    c = metrics["controllers"]
    caveat = metrics.get("floor_caveat")
    out = [f"  note: {caveat}"] if caveat and "adaptive_ct" in c else []
    ratios = _adaptive_ct_targets(c["adaptive_ct"]) if "adaptive_ct" in c else []
    out += ratios + _no_armature_note(res.scenario, ratios)
    out += _information_lines(c, all_unknown=res.scenario.closed_forms is not None)
    out += detection_limit_lines(c)
    out += _nominal_target(c) + _mass_targets(c, res.scenario)
    if "ct_oracle" in c:
        sat = max((s["saturation_fraction"] or 0.0) for s in c["ct_oracle"]["segments"])
        verdict = "met" if sat <= SATURATION_LIMIT else "NOT met: the saturated segments have no verdict"
        out.append(
            f"  ct_oracle saturated fraction (max over segments): {100 * sat:.3f} % "
            f"(target <= {100 * SATURATION_LIMIT:g} %: {verdict})"
        )
    w = metrics["wall_time_s"]
    from adaptive_dd.benchmark.scenario import default_scenario_path

    source = getattr(res.scenario, "source", None)
    default = source is not None and Path(str(source)).resolve() == Path(default_scenario_path()).resolve()
    out.append(
        f"  wall time: {w:.1f} s for {len(c)} controllers x {len(res.seed_indices) or res.scenario.seeds} "
        "seeds" + (f" (target < {TARGET_WALL_S:g} s for the default scenario)" if default else "")
    )
    return out


def _no_armature_note(sc, ratio_lines: list[str]) -> list[str]:
    """A line pointing back to the warning before the run when a ratio target is not met on an arm
    with no armature (the hard case of adaptive_ct against its floor: a light arm)."""
    from adaptive_dd.benchmark.preflight import lacks_armature

    if not any("NOT met" in x for x in ratio_lines) or not lacks_armature(sc):
        return []
    return [
        "  note: no joint of this arm has an armature (the warning before the run): a geared drive's "
        "rotor inertia, [arm] armature from the data sheet, brings a light arm's ratio towards 1"
    ]


def _adaptive_ct_targets(a: dict) -> list[str]:
    """adaptive_ct's ratio to its floor per segment, time to the floor, missed swaps, false alarms."""
    out = []
    for seg in a["segments"]:
        st = seg.get("ratio_to_floor")
        if st is None:
            continue
        where = (
            f"  adaptive_ct / {a['floor']} per seed, {seg['start']:g}-{seg['end']:g} s ({seg['mass']:g} kg): "
        )
        if seg.get("floor_saturated"):
            out.append(
                where + f"mean {st['mean']:.3f}: no verdict, {a['floor']} saturates "
                f"{100 * seg['floor_saturation']:.2f} % of samples (> {100 * SATURATION_LIMIT:g} %)"
            )
            continue
        ok = (
            st["mean"] <= TARGET_RATIO_MEAN
            and st["p90"] <= TARGET_RATIO_P90
            and st["max"] <= TARGET_RATIO_MAX
        )
        out.append(
            where
            + f"mean {st['mean']:.3f}, p90 {st['p90']:.3f}, max {st['max']:.3f} (seed {st['worst_seed']}) "
            f"(target mean <= {TARGET_RATIO_MEAN}, p90 <= {TARGET_RATIO_P90}, max <= {TARGET_RATIO_MAX}: "
            f"{'met' if ok else 'NOT met'})"
        )
    if a["segments"][0].get("time_to_floor"):
        out.append("  " + time_to_floor_line("adaptive_ct", a) + " (printed, no target)")
    if a.get("missed_swaps") is not None:
        n_ok = sum(1 for x in a["missed_swaps_per_seed"] if x is not None)
        n_sw = n_ok * sum(judged_swaps(a))
        out.append(
            f"  adaptive_ct missed swaps: {a['missed_swaps']} of {n_sw} "
            f"(target 0: {'met' if a['missed_swaps'] == 0 else 'NOT met'})"
        )
    if a.get("trials_with_false_alarms") is not None:
        n_ok = sum(1 for x in a["false_alarms_per_seed"] if x is not None)
        pct = 100.0 * a["trials_with_false_alarms"] / max(n_ok, 1)
        ok = "met" if pct <= TARGET_FALSE_ALARM_PCT else "NOT met"
        out.append(
            f"  adaptive_ct trials with a false alarm: {a['trials_with_false_alarms']} of {n_ok} "
            f"({pct:.1f} %) (target <= {TARGET_FALSE_ALARM_PCT:g} %: {ok})"
        )
    return out


def _nominal_target(c: dict) -> list[str]:
    """ct_nominal's RMS error over adaptive_ct's in the heaviest payload's segment."""
    if "adaptive_ct" not in c or "ct_nominal" not in c:
        return []
    heaviest = max(s["mass"] for s in c["adaptive_ct"]["segments"])
    for sa, sn in zip(c["adaptive_ct"]["segments"], c["ct_nominal"]["segments"], strict=True):
        if sa["mass"] == heaviest and sa["mass"] > 0:
            if not (sa["rms_error"] and sn["rms_error"]):
                return []
            r = sn["rms_error"] / sa["rms_error"]
            ok = "met" if r >= TARGET_RATIO_NOMINAL else "NOT met"
            if sa.get("floor_saturated"):
                ok = "no verdict: the floor saturates"
            return [
                f"  ct_nominal / adaptive_ct RMS error in the {sa['mass']:g} kg segment: {r:5.1f}x "
                f"(target >= {TARGET_RATIO_NOMINAL}x: {ok})"
            ]
    return []


def _mass_targets(c: dict, sc=None) -> list[str]:
    """Each estimating controller's payload mass at the end of each segment against the truth; on
    a plant that is not the URDF, a note on what the estimate also holds (:func:`_drawn_link_note`)."""
    out = []
    for name in ("adaptive_ct", "adaptive_ct_paper", "slotine_li"):
        if name not in c:
            continue
        parts = []
        for s in c[name]["segments"]:
            m, est = s["mass"], s["mass_estimate"]
            if est is None:
                continue
            ok = abs(est - m) <= (TARGET_MASS_PCT / 100 * m if m > 0 else TARGET_MASS_ABS)
            parts.append(f"{m:g} kg -> {est:.3f} ({'ok' if ok else 'off'})")
        out.append(
            f"  payload mass by {name} (target within {TARGET_MASS_PCT:g} %, or "
            f"{TARGET_MASS_ABS} kg at 0 kg): " + ", ".join(parts)
        )
    return out + (_drawn_link_note(sc) if out and sc is not None else [])


def _drawn_link_note(sc) -> list[str]:
    """On an N-joint arm whose plant is not its URDF (drawn around it, or a URDF of its own), the
    payload estimated is the difference of the payload frame's body from the URDF's: the link's
    own error is in it, a payload that is not there at 0 kg."""
    plant, arm = getattr(sc, "plant", None), sc.arm
    if sc.closed_forms is not None or plant is None:
        return []
    j = arm.payload_joint
    link = f"the link of joint {arm.joint_names[j]!r}"
    unc = getattr(plant, "uncertainty", None)
    if getattr(plant, "urdf", None) is not None:
        how = "the plant is a URDF of its own"
    elif unc is not None and (unc.mass > 0 or unc.com > 0 or unc.inertia > 0):
        m = float(arm.pi_links[10 * j])
        normal = getattr(unc, "distribution", "uniform") == "normal"
        level = f"std {100 * unc.mass:g} % (drawn up to 3 std)" if normal else f"within {100 * unc.mass:g} %"
        spread = f": its {m:.3g} kg {level}, +- {unc.mass * m:.3g} kg" if unc.mass > 0 else ""
        how = f"the plant is drawn around the URDF ({link}{spread})"
    else:
        return []
    return [
        f"  note: {how}: the payload estimated is the payload frame's body less the URDF's link, "
        "so it also holds that link's own error (a mass at 0 kg, a shift of the centre of mass) as "
        "the estimator sees it"
    ]
