"""The gradient laws' adaptation gains: derived from the arm and the task, against one constant.

Usage (from the repository's root)::

    python benchmarks/adaptation_gains.py [--arms 6] [--seeds 2] [--laws slotine_li composite ...]

For each law, on the first ``--arms`` drawn arms (``benchmarks/scenarios/population.toml``'s
schedule, URDF exact) and the shipped exact UR5, Panda and vertical3 scenarios, ``--seeds``
seeds each: the law against its floor per segment with the constant gains
(:data:`~adaptive_dd.closed_loop.adaptation_gain.DEFAULT_PAYLOAD_GAMMA`; ``natural_adaptive``: its
gain from that mass gain) and with what the run derives
(:func:`~adaptive_dd.closed_loop.adaptation_gain.payload_gains`; ``craig_hsu_sastry``, which keeps
the constant, with ``slotine_li``'s derived gains: why it keeps it). Prints each case's per-segment
means and max, then per law the mean over the cases of each segment, and how many trials
failed. Asserts nothing: a measurement (the controllers page quotes it).
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.population import population_scenario
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.benchmark.scenario_settings import with_settings
from adaptive_dd.closed_loop.adaptation_gain import DEFAULT_PAYLOAD_GAMMA
from adaptive_dd.controllers.registry import scenario_controller
from adaptive_dd.io import read_toml

ROOT = Path(__file__).resolve().parents[1]
TEMPLATE = ROOT / "benchmarks" / "scenarios" / "population.toml"
SHIPPED = ("ur5_tool_swap_exact.toml", "panda_payload_exact.toml", "vertical3_payload_exact.toml")
LAWS = ("slotine_li", "composite", "icl", "natural_adaptive", "craig_hsu_sastry")


def cases(arms: int):
    data = read_toml(TEMPLATE)
    for a in range(arms):
        yield f"random:{a}", population_scenario(data, str(TEMPLATE), a)
    for name in SHIPPED:
        yield name.removesuffix(".toml"), load_scenario(str(ROOT / "adaptive_dd" / "scenarios" / name))


def constant(sc, law: str):
    """``sc`` with ``law`` given the constant gains (what it ran with before they were derived)."""
    if law == "natural_adaptive":
        return with_settings(
            sc, law, {"gain": scenario_controller(sc, law)[1]._gain(DEFAULT_PAYLOAD_GAMMA[0])}
        )
    return with_settings(sc, law, {"gamma": list(DEFAULT_PAYLOAD_GAMMA)})


def ratios(sc, law: str) -> tuple[np.ndarray, float, int]:
    """Per-segment mean ratio, the largest trial's, the failed trials."""
    f = run_benchmark(sc, progress=False).to_frame()
    a = f[f.controller == law]
    by = a.groupby("segment")["ratio_to_floor"]
    return by.mean().to_numpy(), float(by.max().max()), int(a.groupby("seed")["failed"].any().sum())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--arms", type=int, default=6)
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--laws", nargs="+", default=list(LAWS))
    args = ap.parse_args()
    pooled: dict = {}
    for name, sc in cases(args.arms):
        for law in args.laws:
            floor = "ct_oracle_textbook" if law == "craig_hsu_sastry" else "slotine_li_oracle"
            base = dataclasses.replace(sc, seeds=args.seeds, controllers=(floor, law), controller_options=())
            row = []
            derived = base
            if law == "craig_hsu_sastry":  # it keeps the constant: shown with slotine_li's derived gains
                gains = scenario_controller(base, "slotine_li")[1].gamma
                derived = with_settings(base, law, {"gamma": [float(g) for g in gains]})
            for kind, s in (("constant", constant(base, law)), ("derived", derived)):
                mean, worst, failed = ratios(s, law)
                pooled.setdefault((law, kind), []).append((mean, failed))
                shown = " / ".join(f"{m:.3g}" for m in mean)
                row.append(f"{kind} {shown} (max {worst:.3g}{f', {failed} failed' if failed else ''})")
            print(f"{name:24s} {law:17s} " + "  |  ".join(row), flush=True)
    print("\nmean over the cases of each segment's mean ratio (segments as each case numbers them):")
    for (law, kind), rows in pooled.items():
        n = min(len(m) for m, _ in rows)
        mean = np.mean([m[:n] for m, _ in rows], axis=0)
        failed = sum(f for _, f in rows)
        print(
            f"  {law:17s} {kind:8s} " + " / ".join(f"{x:.3g}" for x in mean) + f"   failed trials: {failed}"
        )


if __name__ == "__main__":
    main()
