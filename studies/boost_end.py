"""How adaptive_ct's boost ends: the tracking error around the end of the boost after each swap,
per variant of the boost's end (``boost_ramp``, ``boost_duration``), against ct_oracle on the same
seeds, noise and drawn plants (the benchmark's closed loop).

Per variant: adaptive_ct / ct_oracle per segment (mean over seeds), then per swap the RMS ratio
(median over seeds) in the window where the boost ends (from 0.9 s after the swap to 0.6 s
after the longest variant's boost has ended: the same window for every variant), and the
trials with a false alarm.

    python studies/boost_end.py SCENARIO.toml [--seeds 20] [--ramps 0 0.5 1.0] [--duration 1.0]
"""

from __future__ import annotations

import argparse
import copy
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
    ap.add_argument("--ramps", type=float, nargs="+", default=[0.0, 0.5, 1.0])
    ap.add_argument("--duration", type=float, default=1.0, help="boost_duration [s] of every variant")
    a = ap.parse_args()
    base = read_toml(Path(a.scenario))
    idx = tuple(range(a.seeds))
    print(f"{a.scenario}, {a.seeds} seeds, boost_duration {a.duration} s")
    oracle = None
    for ramp in a.ramps:
        d = copy.deepcopy(base)
        d["run"]["controllers"] = ["ct_oracle", "adaptive_ct"] if oracle is None else ["adaptive_ct"]
        ac = d.setdefault("controllers", {}).setdefault("adaptive_ct", {})
        ac["boost_ramp"], ac["boost_duration"] = ramp, a.duration
        sc = parse_scenario(d, a.scenario, Path(a.scenario).stem)
        res = run_closed_loop(sc, seed_indices=idx, keep_trajectories=a.seeds)
        rc = run_constants(sc)
        if oracle is None:
            oracle = res.runs["ct_oracle"]
        run = res.runs["adaptive_ct"]
        n = (rc.seg_end - rc.seg_start).astype(float)
        seg = np.sqrt(run.acc.sum_e2 / n) / np.sqrt(oracle.acc.sum_e2 / n)
        T = sc.sample_period
        cells = []
        for w in sc.swap_times:
            k0, k1 = round((w + 0.9) / T), round((w + a.duration + max(a.ramps) + 0.6) / T)
            k1 = min(k1, rc.q_d.shape[0])

            def rms(r, k0=k0, k1=k1, rc=rc):
                e = rc.q_d[k0:k1] - r.q[:, k0:k1]
                return np.sqrt(np.mean(e**2, axis=(1, 2)))

            cells.append(np.median(rms(run) / rms(oracle)))
        swaps = sc.swap_times
        fa = sum(
            any(not any(0 <= x - w < FALSE_ALARM_WINDOW for w in swaps) for x in at) for at in run.alarm_times
        )
        print(
            f"ramp {ramp:4.2f} s: per segment "
            + " / ".join(f"{x:.3f}" for x in np.nanmean(seg, 0))
            + "; boost's end, per swap "
            + " / ".join(f"{x:.2f}" for x in cells)
            + f"; trials with a false alarm {fa}",
            flush=True,
        )


if __name__ == "__main__":
    main()
