"""Where adaptive_ct saturates on drawn arms, and what it costs: per trial and segment of
``benchmarks/scenarios/population.toml`` on ``random:ARM``, adaptive_ct / ct_oracle, the share of
samples on which adaptive_ct's command is at a torque limit (any joint), the share of those inside
the boost after an alarm (``boost_duration + boost_ramp`` = 1.25 s), and the excess squared error
``sum(e_a^2 - e_o^2) / sum(e_o^2)`` split into the saturated samples and the others (the two add up
to ratio^2 - 1). Then pooled per segment: mean, p90, max (the worst trial), trials saturated beyond
the benchmark's 1 %, false-alarm trials and missed swaps (as the benchmark counts them: an alarm
not within 0.3 s after a swap; a swap with none).

Run: ``PYTHONPATH=. python benchmarks/boost_saturation.py --first-arm 100 --arms 30 --seeds 3``
(``--template FILE`` another population template, e.g. ``population_drawn.toml``;
``--scenario FILE --seeds 50`` a scenario's own arm instead of drawn ones);
``--cap`` runs the boost capped at ``boost_bandwidth`` on every joint (no noise criterion:
``adaptive_dd.closed_loop.boost``; the per-sample limit on the command stays); ``--no-boost`` runs
adaptive_ct without it (``boost_duration`` and ``boost_ramp`` 0).
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.population import population_scenario
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import load_scenario, read_toml
from adaptive_dd.benchmark.scenario_settings import with_settings

TEMPLATE = Path(__file__).resolve().parent / "scenarios" / "population.toml"
BOOST = 1.25  # [s] boost_duration + boost_ramp, the N-joint defaults
DETECTED = 0.3  # [s] an alarm this soon after a swap is its detection


def trial(res, s: int, edges) -> tuple[list, list]:
    t = res.t
    a, o = res.runs["adaptive_ct"], res.runs["ct_oracle"]
    ea, eo = a.e_norm[s].astype(float), o.e_norm[s].astype(float)
    sat = np.asarray(a.saturated[s]).reshape(len(t), -1).any(axis=1)
    alarms = [float(x) for x in (a.alarm_times or [[]])[s]]
    boost = np.zeros(len(t), dtype=bool)
    for x in alarms:
        boost |= (t >= x) & (t < x + BOOST)
    segs = []
    for lo, hi in itertools.pairwise(edges):
        m = (t >= lo) & (t < hi)
        ex, den = ea[m] ** 2 - eo[m] ** 2, float(np.sum(eo[m] ** 2))
        n_sat = int(sat[m].sum())
        segs.append(
            dict(
                ratio=float(np.sqrt(np.mean(ea[m] ** 2) / np.mean(eo[m] ** 2))),
                sat=n_sat / int(m.sum()),
                in_boost=float((sat & boost)[m].sum() / max(n_sat, 1)),
                excess_sat=float(ex[sat[m]].sum() / den),
                excess_other=float(ex[~sat[m]].sum() / den),
            )
        )
    return alarms, segs


def main() -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False)
    ap.add_argument("--first-arm", type=int, default=0)
    ap.add_argument("--arms", type=int, default=20)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--cap", action="store_true", help="the boost at boost_bandwidth on every joint")
    ap.add_argument("--no-boost", action="store_true", help="adaptive_ct without the boost")
    ap.add_argument("--template", default=str(TEMPLATE), help="population template")
    ap.add_argument("--scenario", help="a scenario file: its own arm, not drawn ones")
    args = ap.parse_args()
    if args.cap:
        from adaptive_dd.closed_loop.controllers import AdaptiveCT

        AdaptiveCT.state_task = lambda self, scenario: None
    rows = []
    arms = [None] if args.scenario else range(args.first_arm, args.first_arm + args.arms)
    for arm in arms:
        where = args.scenario or f"random:{arm}"
        if arm is None:
            sc = load_scenario(args.scenario)
        else:
            sc = population_scenario(read_toml(args.template), args.template, arm)
        sc = dataclasses.replace(sc, seeds=args.seeds, controllers=("ct_oracle", "adaptive_ct"))
        if args.no_boost:
            sc = with_settings(sc, "adaptive_ct", {"boost_duration": 0.0, "boost_ramp": 0.0})
        res = run_benchmark(sc, progress=False, keep_trajectories=args.seeds)
        edges = [0.0, *sc.swap_times, sc.duration]
        for s in range(args.seeds):
            alarms, segs = trial(res, s, edges)
            false = [x for x in alarms if not any(0.0 <= x - w < DETECTED for w in sc.swap_times)]
            missed = sum(not any(0.0 <= x - w < DETECTED for x in alarms) for w in sc.swap_times)
            rows.append((arm, s, false, missed, segs))
            print(f"{where} seed {s}: alarms {[round(x, 3) for x in alarms]}", flush=True)
            for i, g in enumerate(segs):
                print(
                    f"  segment {i}: ratio {g['ratio']:.3f}, saturated {100 * g['sat']:.2f} % "
                    f"({100 * g['in_boost']:.0f} % of it in a boost), ratio^2 - 1 from saturated samples "
                    f"{g['excess_sat']:+.3f}, from the others {g['excess_other']:+.3f}",
                    flush=True,
                )
    r = np.array([[g["ratio"] for g in row[4]] for row in rows])
    sat = np.array([[g["sat"] for g in row[4]] for row in rows])
    names = [f"{args.scenario or f'random:{row[0]}'} seed {row[1]}" for row in rows]
    print(f"pooled over {len(rows)} trials, adaptive_ct / ct_oracle per segment:")
    for i in range(r.shape[1]):
        k = int(r[:, i].argmax())
        print(
            f"  segment {i}: mean {r[:, i].mean():.3f}, p90 {np.percentile(r[:, i], 90):.3f}, "
            f"max {r[k, i]:.2f} ({names[k]}); saturated on {100 * sat[:, i].mean():.2f} % of it on average, "
            f"beyond 1 % in {(sat[:, i] > 0.01).sum()} trials, the most {100 * sat[:, i].max():.1f} %; "
            f"ratio^2 - 1 on average {np.mean([row[4][i]['excess_sat'] for row in rows]):+.4f} from "
            f"saturated samples, {np.mean([row[4][i]['excess_other'] for row in rows]):+.4f} from the others"
        )
    n_sat = int((sat > 0.01).any(axis=1).sum())
    print(f"trials saturated beyond 1 % in some segment: {n_sat} of {len(rows)}")
    fa = [f"{n} at {[round(x, 3) for x in row[2]]}" for n, row in zip(names, rows, strict=True) if row[2]]
    print(f"false-alarm trials: {len(fa)} of {len(rows)}" + (f" ({'; '.join(fa)})" if fa else ""))
    print(f"missed swaps: {sum(row[3] for row in rows)} of {len(rows) * (r.shape[1] - 1)}")


if __name__ == "__main__":
    main()
