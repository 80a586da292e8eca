"""adaptive_ct against ct_oracle in the closed loop with the detector's settings changed: per
segment the ratio of RMS tracking errors per seed (mean / p90 / max), the detection delay per
swap (median, p90, max), and the trials with a false alarm (an alarm not within 0.3 s after a
swap, the benchmark's rule). The same closed loop and seeds as ``adaptive-dd benchmark``
(without its information and detection limits, which take most of its time).

    python studies/detector_closed_loop.py SCENARIO.toml [--seeds 50] [--first-seed 0]
        [--detector '{"fast_window": 0.004}'] [--adaptive '{"boost_duration": 0.3}']

``--detector`` updates adaptive_ct's detector table (the scenario's own, else the estimator's);
``--adaptive`` updates adaptive_ct's table (boost settings).
"""

from __future__ import annotations

import argparse
import copy
import json
import time
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.metrics import FALSE_ALARM_WINDOW
from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop.runner import run_closed_loop
from adaptive_dd.closed_loop.types import run_constants


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario")
    ap.add_argument("--seeds", type=int, default=50)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--detector", type=json.loads, default={})
    ap.add_argument("--adaptive", type=json.loads, default={})
    a = ap.parse_args()
    d = copy.deepcopy(read_toml(Path(a.scenario)))
    d["run"]["controllers"] = ["ct_oracle", "adaptive_ct"]
    ac = d.setdefault("controllers", {}).setdefault("adaptive_ct", {})
    ac.update(a.adaptive)
    if a.detector:
        if isinstance(ac.get("detector"), dict):
            ac["detector"] = {**ac["detector"], **a.detector}
        else:
            ac.setdefault("estimator", {})["detector"] = a.detector
    sc = parse_scenario(d, a.scenario, Path(a.scenario).stem)
    t0 = time.time()
    seeds = tuple(range(a.first_seed, a.first_seed + a.seeds))
    res = run_closed_loop(sc, seed_indices=seeds, keep_trajectories=0)
    rc = run_constants(sc)
    ea = res.runs["adaptive_ct"].e_norm.astype(float) ** 2
    eo = res.runs["ct_oracle"].e_norm.astype(float) ** 2
    cells = []
    for g in range(len(rc.seg_start)):
        k0, k1 = int(rc.seg_start[g]), int(rc.seg_end[g])
        r = np.sqrt(ea[:, k0:k1].mean(1) / eo[:, k0:k1].mean(1))
        cells.append(f"{r.mean():.3f}/{np.percentile(r, 90):.3f}/{r.max():.2f}")
    sw = np.array(sc.swap_times)
    delays, false = [], []
    for i, times in enumerate(res.runs["adaptive_ct"].alarm_times):
        t = np.array(times)
        row = []
        for s in sw:
            hit = t[(t >= s) & (t < s + FALSE_ALARM_WINDOW)]
            row.append(round((hit[0] - s) * 1000) if hit.size else 999)
        delays.append(row)
        fa = [round(float(x), 3) for x in t if not np.any((x >= sw) & (x < sw + FALSE_ALARM_WINDOW))]
        if fa:
            false.append((seeds[i], fa))
    D = np.array(delays)
    print(f"{a.scenario} detector {a.detector} adaptive_ct {a.adaptive}, seeds {seeds[0]}-{seeds[-1]}")
    print("  adaptive_ct / ct_oracle per segment, mean/p90/max: " + "  ".join(cells))
    p90 = np.percentile(D, 90, 0)
    print(f"  detection delay [ms] per swap: median {np.median(D, 0)} p90 {p90} max {D.max(0)}")
    print(f"  trials with a false alarm: {len(false)} of {len(seeds)} {false}  ({time.time() - t0:.0f} s)")


if __name__ == "__main__":
    main()
