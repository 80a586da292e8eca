"""The compact-payload prior of adaptive_ct's N-joint estimator (``prior_radius``), switched off
and at several radii on one scenario: adaptive_ct's ratio to its floor per segment (mean, p90,
max over seeds) and false alarms. Same seeds for every setting.

    python benchmarks/prior_ablation.py [SCENARIO.toml] [--seeds 20] [--radii 0 0.03 0.05 0.08]
"""

from __future__ import annotations

import argparse
import copy
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import parse_scenario, read_toml

UR5 = Path(__file__).resolve().parents[1] / "adaptive_dd" / "scenarios" / "ur5_tool_swap.toml"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario", nargs="?", default=str(UR5))
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--radii", type=float, nargs="+", default=[0.0, 0.03, 0.05, 0.08])
    a = ap.parse_args()
    base = read_toml(Path(a.scenario))
    print(f"{a.scenario}: adaptive_ct / ct_oracle, {a.seeds} seeds")
    print("prior_radius [m]  per segment: mean / p90 / max          false alarms")
    for rho in a.radii:
        d = copy.deepcopy(base)
        d["run"]["seeds"] = a.seeds
        d["run"]["controllers"] = ["ct_oracle", "adaptive_ct"]
        est = d.setdefault("controllers", {}).setdefault("adaptive_ct", {}).setdefault("estimator", {})
        est["prior_radius"] = rho
        df = run_benchmark(parse_scenario(d, a.scenario, Path(a.scenario).stem), progress=False).to_frame()
        c = df[df.controller == "adaptive_ct"]
        cells = []
        for _, s in c.groupby("segment"):
            r = s.ratio_to_floor.to_numpy(dtype=float)
            cells.append(f"{np.nanmean(r):.3f}/{np.nanpercentile(r, 90):.3f}/{np.nanmax(r):.2f}")
        fa = int(np.nansum(c.false_alarms.to_numpy(dtype=float)))
        print(f"{rho:16.3f}  {'  '.join(cells)}   {fa}", flush=True)


if __name__ == "__main__":
    main()
