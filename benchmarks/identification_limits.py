"""Estimators against the Cramér-Rao bound on the Table 2 + 4 experiment (issue 12).

Usage::

    PYTHONPATH=. python benchmarks/identification_limits.py --seeds 20

Simulates ``--seeds`` noisy runs of the paper's experiment (Table 2 torques, Table 2 + 4
sensor noise, encoder and D/A quantization, 10 000 samples), computes the bound, runs the
estimators of :mod:`adaptive_dd.identification.limits` and prints per parameter the bound,
each estimator's bias and std over seeds and the ratio std / bound, with the targets
(offline <= 3x, online <= 10x at the end of the record) marked met or NOT met.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from adaptive_dd.experiments import table2_torque, trial_rngs
from adaptive_dd.identification.fisher import mass_information_time
from adaptive_dd.identification.limits import (
    LIMIT_ESTIMATORS,
    LimitsResult,
    run_information_estimators,
    table2_bound,
)
from adaptive_dd.identification.sensitivity import simulate_trajectory
from adaptive_dd.plant.parameters import TABLE1_SIGMA, payload_sigma_delta
from adaptive_dd.plant.simulator import simulate_open_loop


def swap_demo(mass: float = 3.0, t_swap: float = 5.0, samples: int = 10_000) -> str:
    """Information-limited time to know a payload put on at ``t_swap`` in the Table 2 experiment."""
    tau = table2_torque(1, samples)[0]
    k = round(t_swap / 1e-3)
    q1, qd1 = simulate_trajectory(TABLE1_SIGMA, tau[: k + 1], 1e-3)
    after = TABLE1_SIGMA + payload_sigma_delta(mass)
    q2, qd2 = simulate_trajectory(after, tau[k:], 1e-3, q1[-1], qd1[-1])
    q, qd = np.concatenate((q1[:k], q2)), np.concatenate((qd1[:k], qd2))
    lines = [f"Payload swap: {mass} kg disk put on at t = {t_swap} s of the Table 2 experiment (open loop)"]
    for others in ("known", "unknown"):
        for measured in (("q", "qd"), ("qd",)):
            t = mass_information_time(
                q,
                qd,
                tau,
                k,
                1e-3,
                after,
                payload_sigma_delta(1.0),
                mass=mass,
                others=others,
                measured=measured,
            )
            shown = "not within the record" if t is None else f"{1e3 * t:.0f} ms"
            lines.append(
                f"  1.96 x CRB std <= 5 % of the mass after {shown:>8s}  (other parameters {others}, "
                f"measured {', '.join(measured)})"
            )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=int, default=20)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--samples", type=int, default=10_000)
    p.add_argument("--estimators", nargs="+", default=list(LIMIT_ESTIMATORS), choices=LIMIT_ESTIMATORS)
    p.add_argument("--json", help="write the rows as JSON here")
    p.add_argument("--swap-only", action="store_true", help="only the payload-swap information time")
    args = p.parse_args(argv)
    if args.swap_only:
        print(swap_demo())
        return 0

    t0 = time.perf_counter()
    sim = simulate_open_loop(table2_torque(args.seeds, args.samples), trial_rngs(args.seed, args.seeds))
    t_sim = time.perf_counter() - t0
    t0 = time.perf_counter()
    crb = table2_bound(sim.tau[0])
    crb_qd = table2_bound(sim.tau[0], measured=("qd",))
    t_crb = time.perf_counter() - t0
    print(
        f"Table 2 + 4 experiment, {args.samples} samples, {args.seeds} seeds (seed {args.seed}); "
        f"simulation {t_sim:.1f} s, bounds {t_crb:.1f} s"
    )
    print("Cramér-Rao bound, q and qd measured:")
    print(crb.format())
    print("Cramér-Rao bound, qd only:")
    print(crb_qd.format())
    print()
    est, secs = run_information_estimators(
        sim.q_meas, sim.qd_meas, sim.tau, tuple(args.estimators), progress=lambda n: print(f"  ran {n}")
    )
    res = LimitsResult(crb, est, secs)
    print()
    print(res.format())
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"crb": crb.to_dict(), "rows": res.rows()}, fh, indent=1)
        print(f"wrote {args.json}")
    worst = {n: max(r["std_over_crb"] for r in res.rows() if r["estimator"] == n) for n in est}
    print("worst std/bound: " + ", ".join(f"{n} {w:.2f}" for n, w in worst.items()))
    print()
    print(swap_demo())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
