"""adaptive_ct's alarm times and segment ratios per trial on drawn arms.

Runs ``benchmarks/scenarios/population.toml`` on ``random:ARM`` (as ``benchmark --arms`` does) for
each ARM given, SEEDS seeds each, and prints per trial the times [s] adaptive_ct's detector alarmed
and its RMS error over ct_oracle's per segment: which trials hold a false alarm, and what it did.

Run: ``PYTHONPATH=. python benchmarks/alarm_times.py SEEDS ARM [ARM ...]``.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.population import population_scenario
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import read_toml

TEMPLATE = Path(__file__).resolve().parent / "scenarios" / "population.toml"


def main() -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False)
    ap.add_argument("seeds", type=int, help="seeds per arm")
    ap.add_argument("arms", type=int, nargs="+", help="the arms' seeds (random:ARM)")
    args = ap.parse_args()
    for arm in args.arms:
        sc = population_scenario(read_toml(TEMPLATE), str(TEMPLATE), arm)
        sc = dataclasses.replace(sc, seeds=args.seeds, controllers=("ct_oracle", "adaptive_ct"))
        res = run_benchmark(sc, progress=False, keep_trajectories=0)
        a, o = res.runs["adaptive_ct"], res.runs["ct_oracle"]
        ratio = np.sqrt(a.acc.sum_e2 / o.acc.sum_e2)
        for s in range(args.seeds):
            alarms = [round(float(x), 3) for x in a.alarm_times[s]]
            r = np.round(ratio[s], 3).tolist()
            print(f"random:{arm} seed {s}: alarms {alarms} ratios {r}", flush=True)


if __name__ == "__main__":
    main()
