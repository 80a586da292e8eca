"""The floor that detection delay alone puts under adaptive control of an N-joint arm.

``DelayedOracle`` (:mod:`adaptive_dd.closed_loop.delayed_oracle`) is computed torque with the
textbook law of ``ct_oracle_textbook`` and the
TRUE model, except that it learns of each payload change only ``delay`` seconds after it: what
an estimator that knew the new payload exactly at its alarm would reach (adaptive_ct detects a
swap 5-10 ms after it on the UR5). Its ratio to ``ct_oracle_textbook`` per segment and seed,
beside adaptive_ct's ratio to ct_oracle, tells how much of adaptive_ct's excess the delay alone
explains. With ``delay = 0`` it is ``ct_oracle_textbook`` itself (ratio 1 to rounding: the
check that the plug-in is the same law). ``--boost`` adds adaptive_ct's feedback boost
(``M0(q) (dkp e + dkd e')`` raising the bandwidth to ``boost_bandwidth`` for ``boost_duration``)
from the moment the model switches, as adaptive_ct does from its alarm.

    python studies/delayed_oracle.py [SCENARIO.toml] [--seeds 20] [--delays 0 0.005 0.01 0.02] [--boost]

The plug-in runs on the Python path (one compiled ``model_torque`` call per trial and sample).
"""

from __future__ import annotations

import argparse
import copy
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop.controllers import JointGains
from adaptive_dd.closed_loop.delayed_oracle import DelayedOracle
from adaptive_dd.closed_loop.runner import make_controllers

UR5 = Path(__file__).resolve().parents[1] / "adaptive_dd" / "scenarios" / "ur5_tool_swap_exact.toml"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario", nargs="?", default=str(UR5))
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--delays", type=float, nargs="+", default=[0.0, 0.005, 0.01, 0.02])
    ap.add_argument("--boost", action="store_true", help="adaptive_ct's feedback boost after each switch")
    a = ap.parse_args()
    d = copy.deepcopy(read_toml(Path(a.scenario)))
    d["run"]["seeds"] = a.seeds
    d["run"]["controllers"] = ["ct_oracle", "ct_oracle_textbook", "adaptive_ct"]
    sc = parse_scenario(d, a.scenario, Path(a.scenario).stem)
    ctrls = make_controllers(sc)
    gains = JointGains.of(sc.bandwidth, sc.damping, sc.arm.n_joints)
    for delay in a.delays:
        boost = None
        if a.boost:
            ac = ctrls["adaptive_ct"]
            boost = (ac.boost_bandwidth, ac.boost_duration)
        c = DelayedOracle(sc.arm, gains, delay, boost)
        ctrls[c.name] = c
    df = run_benchmark(sc, controllers=ctrls).to_frame()
    print(f"{a.scenario}: {a.seeds} seeds; per segment, ratio to the floor per seed: mean / p90 / max")
    for name, c in df.groupby("controller", sort=False):
        if c.floor.iloc[0] in (None, "", "None") or c.ratio_to_floor.isna().all():
            continue
        cells = []
        for _, s in c.groupby("segment"):
            r = s.ratio_to_floor.to_numpy(dtype=float)
            cells.append(f"{np.nanmean(r):.3f}/{np.nanpercentile(r, 90):.3f}/{np.nanmax(r):.2f}")
        print(f"{name:24s} (floor {c.floor.iloc[0]:18s}) {'  '.join(cells)}", flush=True)


if __name__ == "__main__":
    main()
