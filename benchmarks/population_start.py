"""The population's first seconds: adaptive_ct / ct_oracle per arm, the run cut short.

Runs ``benchmarks/scenarios/population.toml`` over the arms ``random:FIRST`` .. (as ``benchmark
--arms`` does) for ``--duration`` seconds only (the payloads after it dropped), with optional
settings of adaptive_ct's estimator, and prints per arm the mean (max) of each segment and the
pooled mean, p90 and max: the unloaded first segment measured at a fraction of a full run's cost.

Run: ``PYTHONPATH=. python benchmarks/population_start.py FIRST N SEEDS [--duration 4.5]
[--estimator JSON]``. With ``--duration 4.5`` the second segment is the half second after the
pick-up.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from adaptive_dd.benchmark.population import pooled, run_population
from adaptive_dd.benchmark.scenario import read_toml

TEMPLATE = Path(__file__).resolve().parent / "scenarios" / "population.toml"


def main() -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False)
    ap.add_argument("first", type=int, help="seed of the first arm")
    ap.add_argument("n", type=int, help="arms")
    ap.add_argument("seeds", type=int, help="trials per arm")
    ap.add_argument("--duration", type=float, default=4.5, help="s of each trial")
    ap.add_argument("--estimator", default="{}", help="adaptive_ct's estimator table, as JSON")
    args = ap.parse_args()
    data = read_toml(TEMPLATE)
    data["run"]["duration"] = args.duration
    data["payload"] = [p for p in data["payload"] if p["at"] < args.duration - 0.25]
    est = json.loads(args.estimator)
    settings = {"adaptive_ct": {"estimator": est}} if est else None  # no scenario key: set on the scenario

    def on_arm(s: dict) -> None:
        segs = " / ".join(f"{g['mean']:.3f} ({g['max']:.2f})" for g in s["segments"])
        arm = f"random:{s['arm_seed']} ({s['joints']} joints, {s['kind']}, {s['capacity_kg']} kg)"
        print(f"{arm}: {segs}", flush=True)

    arms = range(args.first, args.first + args.n)
    pop = run_population(data, str(TEMPLATE), arms, seeds=args.seeds, on_arm=on_arm, settings=settings)
    for p in pooled(pop):
        print(
            f"segment {p['segment'] + 1}: mean {p['mean']:.3f}, p90 {p['p90']:.3f}, max {p['max']:.2f} "
            f"(random:{p['worst'][0]} seed {p['worst'][1]})"
        )
    fa = sum(a["false_alarm_trials"] for a in pop.arms)
    print(f"trials with a false alarm: {fa} of {sum(a['trials'] for a in pop.arms)}")


if __name__ == "__main__":
    main()
