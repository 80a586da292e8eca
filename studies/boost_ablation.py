"""adaptive_ct's feedback boost after an alarm (``[controllers.adaptive_ct] boost_duration``):
how long the feedback stays raised to ``boost_bandwidth`` while the new payload is learnt.

For each duration: adaptive_ct / ct_oracle per segment (mean / p90 / max over seeds, trials with
a false alarm, swaps missed), and the same boost on the true model: ``ct_oracle_textbook`` told
of each swap one sample late and boosted as adaptive_ct is (``delayed_oracle.py``'s plug-in),
against its own floor. If high gains alone beat the floor, the second row would fall below 1;
it shows what the boost costs in sensor noise. The first row also prints adaptive_ct's RMS
torque over ct_oracle's per segment and its saturated fraction [%]: the price of the boost.

    python studies/boost_ablation.py [SCENARIO.toml] [--seeds 20] [--durations 0.2 0.5 1.0]
"""

from __future__ import annotations

import argparse
import copy
from pathlib import Path

from _ablation import UR5, ablation_row, segment_cells
from delayed_oracle import DelayedOracle

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop.controllers import JointGains
from adaptive_dd.closed_loop.runner import make_controllers


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario", nargs="?", default=str(UR5))
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--durations", type=float, nargs="+", default=[0.2, 0.5, 1.0])
    a = ap.parse_args()
    base = read_toml(Path(a.scenario))
    print(f"{a.scenario}: {a.seeds} seeds; per segment, ratio to the floor per seed: mean / p90 / max")
    for dur in a.durations:
        row = ablation_row(base, a.scenario, a.seeds, {}, controller={"boost_duration": dur}, torque=True)
        print(f"boost {dur:4.2f} s  adaptive_ct / ct_oracle                 {row}", flush=True)
        d = copy.deepcopy(base)
        d["run"]["seeds"] = a.seeds
        d["run"]["controllers"] = ["ct_oracle_textbook", "adaptive_ct"]
        d.setdefault("controllers", {}).setdefault("adaptive_ct", {})["boost_duration"] = dur
        sc = parse_scenario(d, a.scenario, Path(a.scenario).stem)
        ctrls = make_controllers(sc)
        ac = ctrls.pop("adaptive_ct")
        gains = JointGains.of(sc.bandwidth, sc.damping, sc.arm.n_joints)
        c = DelayedOracle(sc.arm, gains, sc.sample_period, (ac.boost_bandwidth, ac.boost_duration))
        df = run_benchmark(sc, controllers={**ctrls, c.name: c}, progress=False).to_frame()
        cells = segment_cells(df[df.controller == c.name])
        print(f"boost {dur:4.2f} s  true model told 1 sample late / its floor {'  '.join(cells)}", flush=True)


if __name__ == "__main__":
    main()
