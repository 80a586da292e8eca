"""The tool frame's error of ``ct_oracle`` and ``adaptive_ct`` on every shipped scenario, every seed.

    python benchmarks/end_effector_table.py [--seeds N] [--scenarios NAME ...]

One benchmark run per shipped scenario (``adaptive_dd/scenarios/*.toml``, its own seeds unless
``--seeds``), the two controllers alone; per controller and payload segment the mean over the
seeds of the position RMS and peak [mm] and the orientation RMS [deg] that the loop streams for
every seed (:mod:`adaptive_dd.closed_loop.tool_frame`), as Markdown table rows, and the number of
seeds in each mean (a seed whose trial failed before the segment's end is left out).
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.metrics import per_seed_segment_metrics
from adaptive_dd.benchmark.runner import run_benchmark, scenario_controller
from adaptive_dd.benchmark.scenario import load_scenario

ROOT = Path(__file__).resolve().parent.parent
SHIPPED = (
    "payload_swap", "ur5_tool_swap", "ur5_tool_swap_exact", "panda_payload", "panda_payload_exact",
    "iiwa14_payload", "iiwa14_payload_exact", "vertical3_payload", "vertical3_payload_exact",
)  # fmt: skip
CONTROLLERS = ("ct_oracle", "adaptive_ct")


def _cells(x: np.ndarray, fmt: str) -> str:
    with np.errstate(all="ignore"):
        return " / ".join(fmt.format(np.nanmean(c)) for c in x.T)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=None, help="seeds per scenario (default: its own)")
    ap.add_argument("--scenarios", nargs="+", default=list(SHIPPED), choices=SHIPPED)
    args = ap.parse_args()
    print(
        "| scenario | controller | seeds | position RMS [mm] per segment | peak [mm] "
        "| orientation RMS [deg] |"
    )
    print("|---|---|---|---|---|---|")
    for name in args.scenarios:
        sc = load_scenario(ROOT / "adaptive_dd" / "scenarios" / f"{name}.toml")
        if args.seeds is not None:
            sc = dataclasses.replace(sc, seeds=args.seeds)
        ctrls = dict(scenario_controller(sc, c) for c in CONTROLLERS)
        res = run_benchmark(sc, progress=False, controllers=ctrls, keep_trajectories=0)
        for c in CONTROLLERS:
            m = per_seed_segment_metrics(res, res.runs[c], settling=False)
            n = np.isfinite(m["ee_position_rms"]).sum(axis=0)
            seeds = f"{n.min()}" if n.min() == n.max() else f"{n.min()}-{n.max()}"
            print(
                f"| `{name}` | {c} | {seeds} | {_cells(m['ee_position_rms'], '{:.3f}')} | "
                f"{_cells(m['ee_position_max'], '{:.3f}')} | {_cells(m['ee_orientation_rms'], '{:.4f}')} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
