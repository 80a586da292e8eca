"""The compact-payload prior of adaptive_ct's N-joint estimator (``prior_radius``), switched off
and at several radii on one scenario: adaptive_ct's ratio to its floor per segment (mean, p90,
max over seeds), trials with a false alarm and swaps missed. Same seeds for every setting.

    python studies/prior_ablation.py [SCENARIO.toml] [--seeds 20] [--radii 0 0.03 0.05 0.08]
"""

from __future__ import annotations

import argparse
from pathlib import Path

from _ablation import UR5, ablation_row

from adaptive_dd.benchmark.scenario import read_toml


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario", nargs="?", default=str(UR5))
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--radii", type=float, nargs="+", default=[0.0, 0.03, 0.05, 0.08])
    a = ap.parse_args()
    base = read_toml(Path(a.scenario))
    print(f"{a.scenario}: adaptive_ct / ct_oracle, {a.seeds} seeds")
    print("prior_radius [m]  per segment: mean / p90 / max          trials with a false alarm, swaps missed")
    for rho in a.radii:
        print(f"{rho:16.3f}  {ablation_row(base, a.scenario, a.seeds, {'prior_radius': rho})}", flush=True)


if __name__ == "__main__":
    main()
