"""The change detector's acceptance table: every shipped scenario x plant friction law.

``python benchmarks/detector_acceptance.py --seeds 200`` runs ``ct_oracle`` and ``adaptive_ct``
on every shipped scenario (``adaptive_dd/scenarios/payload_swap.toml``,
``benchmarks/scenarios/*.toml``), each with its own plant and with the plant's friction
replaced by stick-slip, tanh (v = 0.02 and 0.1 rad/s: the second creeps about 0.1 rad/s at
80 % of d, as the soft-constraint engine of issue 19 does), stribeck and LuGre (the
detector's settings are the same everywhere). A plant an arm cannot take is skipped and said
so; a run that fails is printed as
failed and the others go on (the exit status is then non-zero). Per scenario and plant it prints, per segment,
the per-seed ratio adaptive_ct / ct_oracle (mean, p90, max and worst seed), the trials with a
false alarm, the swaps missed (no alarm within 0.3 s after the swap), the median detection
delay and the detection limit (:mod:`adaptive_dd.identification.two_link_detection_limit`) beside it.
``--detector KEY=VALUE ...`` runs ``adaptive_ct`` with those :class:`ChangeDetector` settings in
place of the defaults (the same ones everywhere), to judge a setting before it becomes the default.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.metrics import compute_metrics, missed_swap_counts
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import default_scenario_path, load_scenario
from adaptive_dd.benchmark.scenario_checks import freeze
from adaptive_dd.errors import ParameterError
from adaptive_dd.identification.two_link_online import ChangeDetector

ROOT = Path(__file__).resolve().parent
PLANTS = {
    "own": None,
    "stick-slip": {"friction": "stick-slip"},
    "tanh-0.02": {"friction": "tanh", "friction_velocity": 0.02},
    "tanh-0.1": {"friction": "tanh", "friction_velocity": 0.1},
    "stribeck": {"friction": "stribeck"},
    "lugre": {"friction": "lugre"},
}


def scenario_paths() -> list[Path]:
    return [default_scenario_path(), *sorted((ROOT / "scenarios").rglob("*.toml"))]


def detector_settings(pairs: list[str]) -> dict:
    """``["glr_threshold=300", ...]`` -> ``{"glr_threshold": 300.0}`` (typed as the defaults)."""
    fields = {f.name: f for f in dataclasses.fields(ChangeDetector)}
    out = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or key not in fields:
            raise SystemExit(f"--detector: expected KEY=VALUE with KEY one of {sorted(fields)}, got {pair!r}")
        default = getattr(ChangeDetector(), key)
        out[key] = value.lower() == "true" if isinstance(default, bool) else type(default)(value)
    ChangeDetector(**out)  # a bad value fails here, by name
    return out


def evaluate(sc, plant: dict | None, seeds: int, detector: dict | None = None) -> tuple[list[str], dict]:
    arm = sc.arm if plant is None else dataclasses.replace(sc.arm, **plant)
    sc = dataclasses.replace(sc.with_controllers(("ct_oracle", "adaptive_ct")), arm=arm, seeds=seeds)
    if detector:
        sc = dataclasses.replace(sc, controller_options=(("adaptive_ct", freeze({"detector": detector})),))
    res = run_benchmark(sc, progress=False, keep_trajectories=1)
    m = compute_metrics(res)
    a = m["controllers"]["adaptive_ct"]
    run = res.runs["adaptive_ct"]
    miss = missed_swap_counts(run.alarm_times, sc.swap_times, run.failed)
    lines = []
    worst = {"mean": 0.0, "p90": 0.0, "max": 0.0, "delay_ratio": 0.0}
    for seg in a["segments"]:
        st = seg["ratio_to_floor"]
        d = [x for x in (seg.get("detection_delay_per_seed") or []) if x is not None]
        lim = seg.get("detection_limit")
        extra = ""
        if seg["start"] > 0:
            extra = f"  delay median {1e3 * np.median(d):5.1f} ms" if d else "  delay -"
            extra += f" (limit {1e3 * lim:4.1f} ms)" if lim is not None else ""
        lines.append(
            f"    {seg['start']:4.1f}-{seg['end']:4.1f} s {seg['mass']:3g} kg: mean {st['mean']:.3f} "
            f"p90 {st['p90']:.3f} max {st['max']:.2f} (seed {st['worst_seed']}){extra}"
        )
        for key in ("mean", "p90", "max"):
            worst[key] = max(worst[key], st[key])
        if d and lim:
            worst["delay_ratio"] = max(worst["delay_ratio"], float(np.median(d)) / lim)
    head = (
        f"  false-alarm trials {a['trials_with_false_alarms']} of {seeds}, missed swaps {int(miss.sum())} "
        f"(in {int((miss > 0).sum())} trials), failed {a['failed_trials']}"
    )
    return [head, *lines], {"fa": a["trials_with_false_alarms"], "missed": int(miss.sum()), **worst}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=50)
    ap.add_argument("--scenarios", nargs="*", help="scenario files (default: every shipped one)")
    ap.add_argument("--plants", nargs="*", default=list(PLANTS), choices=list(PLANTS))
    ap.add_argument("--detector", nargs="*", default=[], metavar="KEY=VALUE", help="ChangeDetector settings")
    args = ap.parse_args()
    detector = detector_settings(args.detector)
    if detector:
        print(f"adaptive_ct detector settings: {detector} (else the defaults)", flush=True)
    paths = [Path(p) for p in args.scenarios] if args.scenarios else scenario_paths()
    t0 = time.perf_counter()
    tot = {
        "fa": 0,
        "missed": 0,
        "runs": 0,
        "fa_max": 0,
        "mean": 0.0,
        "p90": 0.0,
        "max": 0.0,
        "delay_ratio": 0.0,
        "skipped": 0,
        "failed": 0,
    }
    seen: dict = {}
    for path in paths:
        sc = load_scenario(path)
        if detector and sc.closed_forms is None:  # the settings are the two-link detector's
            print(
                f"{os.path.relpath(path)}: skipped, --detector sets the two-link detector and this "
                "scenario runs the general N-joint kernels",
                flush=True,
            )
            tot["skipped"] += 1
            continue
        for plant in args.plants:
            spec = PLANTS[plant]
            label = sc.arm.friction if spec is None else plant
            name = f"{os.path.relpath(path)} [plant {label}]"
            try:
                arm = sc.arm if spec is None else dataclasses.replace(sc.arm, **spec)
            except ParameterError as exc:  # a law's parameters the arm refuses
                print(f"{name}: skipped, the arm cannot take this plant ({exc})", flush=True)
                tot["skipped"] += 1
                continue
            key = dataclasses.replace(sc, arm=arm, source="", name="", defaulted=frozenset())
            if key in seen:  # the same run under another name
                print(f"{name}: the same run as {seen[key]}", flush=True)
                continue
            seen[key] = name
            try:
                lines, s = evaluate(sc, spec, args.seeds, detector)
            except Exception as exc:  # one run's failure does not take the table down
                print(f"{name}: FAILED ({type(exc).__name__}: {exc})", flush=True)
                tot["failed"] += 1
                continue
            print(name, flush=True)
            print("\n".join(lines), flush=True)
            tot["fa"] += s["fa"]
            tot["missed"] += s["missed"]
            tot["runs"] += 1
            tot["fa_max"] = max(tot["fa_max"], s["fa"])
            for key in ("mean", "p90", "max", "delay_ratio"):
                tot[key] = max(tot[key], s[key])
    n = args.seeds
    print(
        f"all: {tot['runs']} scenario x plant runs of {n} seeds: false-alarm trials {tot['fa']} "
        f"(at most {tot['fa_max']} = {100 * tot['fa_max'] / n:.1f} % in one run; target <= 1 %), "
        f"missed swaps {tot['missed']} (target 0); worst segment mean {tot['mean']:.3f} (target <= 1.1), "
        f"p90 {tot['p90']:.3f} (<= 1.3), max {tot['max']:.2f} (<= 3); worst median delay / detection limit "
        f"{tot['delay_ratio']:.2f} (target <= 2); {tot['skipped']} skipped (a plant the arm cannot take), "
        f"{tot['failed']} failed; wall {time.perf_counter() - t0:.0f} s"
    )
    if tot["failed"]:
        raise SystemExit(f"{tot['failed']} run(s) failed (above)")


if __name__ == "__main__":
    main()
