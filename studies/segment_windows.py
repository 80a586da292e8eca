"""Where in a segment, and at which joint, adaptive_ct's excess over ct_oracle lies: per window
after the swap that starts the segment, the per-joint RMS ratio adaptive_ct / ct_oracle (mean
over seeds), the saturated samples per joint and the RMS errors [mrad]; with ``--set`` adaptive_ct
is given settings (TOML, its ``[controllers.adaptive_ct]`` table) to compare.

    python studies/segment_windows.py benchmarks/scenarios/gen3_exact.toml --segment 1 --seeds 3
    python studies/segment_windows.py benchmarks/scenarios/gen3_exact.toml --set 'boost_duration = 0.2'
"""

from __future__ import annotations

import argparse
import copy
import itertools
import tomllib
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop.runner import run_closed_loop
from adaptive_dd.closed_loop.types import run_constants

EDGES = (0.0, 0.1, 0.5, 1.0, 1.3, 2.0, 3.0, 5.0)
"""[s] after the swap: the windows' edges (cut at the segment's end)."""


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario")
    ap.add_argument("--segment", type=int, default=1)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--set", default="", help="TOML for adaptive_ct's [controllers.adaptive_ct] table")
    a = ap.parse_args()
    d = copy.deepcopy(read_toml(Path(a.scenario)))
    d["run"]["controllers"] = ["ct_oracle", "adaptive_ct"]
    if a.set:
        d.setdefault("controllers", {})["adaptive_ct"] = tomllib.loads(a.set)
    sc = parse_scenario(d, str(Path(a.scenario).resolve()), Path(a.scenario).stem)
    res = run_closed_loop(sc, seed_indices=tuple(range(a.seeds)), keep_trajectories=a.seeds)
    rc, T = run_constants(sc), sc.sample_period
    ra, ro = res.runs["adaptive_ct"], res.runs["ct_oracle"]
    print("alarms [s]", [np.round(x, 3).tolist() for x in ra.alarm_times])
    for g in range(len(rc.seg_start)):
        whole = np.sqrt(ra.acc.sum_e2[:, g] / ro.acc.sum_e2[:, g])
        joints = np.sqrt(ra.acc.sum_e2_joint[:, g] / ro.acc.sum_e2_joint[:, g]).mean(0)
        print(f"segment {g}: ratio per seed {np.round(whole, 3)}, per joint (mean) {np.round(joints, 2)}")
    ea, eo = rc.q_d[None] - ra.q, rc.q_d[None] - ro.q
    k0, k1 = int(rc.seg_start[a.segment]), int(rc.seg_end[a.segment])
    print(f"segment {a.segment}, windows after its swap:")
    for lo, hi in itertools.pairwise(EDGES):
        i, j = k0 + round(lo / T), min(k1, k0 + round(hi / T))
        if i >= j:
            break
        r = np.sqrt((ea[:, i:j] ** 2).sum(1) / (eo[:, i:j] ** 2).sum(1)).mean(0)
        sat = ra.saturated[:, i:j].sum((0, 1))
        rms_a = 1e3 * np.sqrt((ea[:, i:j] ** 2).mean((0, 1)))
        rms_o = 1e3 * np.sqrt((eo[:, i:j] ** 2).mean((0, 1)))
        print(f"  [{lo:.1f}, {hi:.1f}) s: ratio per joint {np.round(r, 2)}; saturated samples {sat}")
        print(f"      RMS error [mrad] adaptive_ct {np.round(rms_a, 3)}, ct_oracle {np.round(rms_o, 3)}")


if __name__ == "__main__":
    main()
