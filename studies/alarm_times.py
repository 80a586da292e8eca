"""adaptive_ct's alarms, seed by seed: when each trial alarmed, which were false, and the ratio to
ct_oracle per segment (the two controllers alone; the seeds, noise and drawn plants are the
benchmark's, so the figures are those of ``adaptive-dd benchmark SCENARIO --seeds N``).

    python studies/alarm_times.py SCENARIO.toml [--seeds 20] [--first-seed 0] [--set 'KEY = VALUE' ...]

``--set`` (TOML) updates adaptive_ct's estimator table (a ``detector = {...}`` table is merged).
"""

from __future__ import annotations

import argparse
import copy
import tomllib
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.metrics import FALSE_ALARM_WINDOW
from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop.runner import run_closed_loop
from adaptive_dd.closed_loop.types import run_constants


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario")
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    a = ap.parse_args()
    d = copy.deepcopy(read_toml(Path(a.scenario)))
    d["run"]["controllers"] = ["ct_oracle", "adaptive_ct"]
    est = d.setdefault("controllers", {}).setdefault("adaptive_ct", {}).setdefault("estimator", {})
    for k, v in tomllib.loads("\n".join(a.set)).items():
        est[k] = {**est[k], **v} if isinstance(v, dict) and isinstance(est.get(k), dict) else v
    sc = parse_scenario(d, a.scenario, Path(a.scenario).stem)
    idx = tuple(range(a.first_seed, a.first_seed + a.seeds))
    res = run_closed_loop(sc, seed_indices=idx, keep_trajectories=0)
    ac, oracle = res.runs["adaptive_ct"], res.runs["ct_oracle"]
    rc = run_constants(sc)
    n = (rc.seg_end - rc.seg_start).astype(float)
    ratio = np.sqrt(ac.acc.sum_e2 / n) / np.sqrt(oracle.acc.sum_e2 / n)
    swaps = sc.swap_times
    n_false, missed, delays = 0, 0, [[] for _ in swaps]
    for r, seed in enumerate(idx):
        at = ac.alarm_times[r]
        false = [x for x in at if not any(0 <= x - w < FALSE_ALARM_WINDOW for w in swaps)]
        n_false += bool(false)
        for i, w in enumerate(swaps):
            d_ = [x - w for x in at if 0 <= x - w < FALSE_ALARM_WINDOW]
            if d_:
                delays[i].append(min(d_))
            else:
                missed += 1
        print(
            f"seed {seed}: "
            + " / ".join(f"{x:.3f}" for x in ratio[r])
            + f"  alarms [s] {[round(float(x), 3) for x in at]}"
            + (f"  false: {[round(float(x), 3) for x in false]}" if false else "")
        )
    cells = (
        ("mean", np.nanmean(ratio, 0)),
        ("p90", np.nanpercentile(ratio, 90, 0)),
        ("max", np.nanmax(ratio, 0)),
    )
    print(
        "adaptive_ct / ct_oracle per segment: "
        + "; ".join(f"{k} " + " / ".join(f"{x:.3f}" for x in v) for k, v in cells)
    )
    print(
        f"trials with a false alarm {n_false} of {len(idx)}, swaps missed {missed}, median delay ms "
        + " / ".join(f"{1e3 * np.median(x):.0f}" if x else "-" for x in delays)
    )


if __name__ == "__main__":
    main()
