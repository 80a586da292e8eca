"""Speed of the closed-loop simulation: simulated seconds per wall-clock second.

Compares, for the same computed-torque loop at T = 1 ms with 2 RK4 substeps:

* adaptive_dd's simulator (numba-compiled integrator, one vectorised batch), for
  one trial and for a batch of 256 trials;
* the same loop stepped with ``pinocchio.aba`` per RK4 stage (per trial, in
  Python), with viscous and smooth Coulomb friction added to the torque;
* the full default benchmark's adaptive controller (estimator included).

Usage: ``python benchmarks/closed_loop_speed.py [--duration S]``. Prints figures;
asserts nothing.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import pinocchio as pin

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.controllers import ComputedTorque, adaptive_ct
from adaptive_dd.controllers.feedback import computed_torque_law
from adaptive_dd.plant import TABLE1_PHYSICAL, TABLE1_SIGMA
from adaptive_dd.plant.pinocchio_model import build_model


def ours(n_trials: int, duration: float, controller) -> float:
    import dataclasses

    sc = dataclasses.replace(
        load_scenario(), seeds=n_trials, duration=duration, swap_times=(duration / 2,), swap_masses=(3.0,)
    )
    t0 = time.perf_counter()
    run_benchmark(sc, progress=False, controllers={"c": controller})
    return n_trials * duration / (time.perf_counter() - t0)


def pinocchio_loop(n_trials: int, duration: float, substeps: int = 2) -> float:
    """The same CT loop with the plant integrated by RK4 on pin.aba (friction as torque)."""
    model = build_model(TABLE1_PHYSICAL)
    data = model.createData()
    sc = load_scenario()
    T = 1e-3
    n = round(duration / T)
    q_d, qd_d, qdd_d = sc.reference.sample(np.arange(n) * T)
    b, d = TABLE1_SIGMA[3:5], TABLE1_SIGMA[5:7]
    rng = np.random.default_rng(0)

    def accel(q, v, tau):
        return pin.aba(model, data, q, v, tau - b * v - d * np.tanh(v / 1e-3))

    t0 = time.perf_counter()
    for _ in range(n_trials):
        q, v = q_d[0].copy(), qd_d[0].copy()
        for k in range(n):
            qm = q + 1e-4 * rng.standard_normal(2)
            vm = v + 7e-3 * rng.standard_normal(2)
            tau = computed_torque_law(qm, vm, q_d[k], qd_d[k], qdd_d[k], TABLE1_SIGMA, 1600.0, 80.0)
            h = T / substeps
            for _ in range(substeps):
                a1 = accel(q, v, tau)
                a2 = accel(q + 0.5 * h * v, v + 0.5 * h * a1, tau)
                a3 = accel(q + 0.5 * h * (v + 0.5 * h * a1), v + 0.5 * h * a2, tau)
                a4 = accel(q + h * (v + 0.5 * h * a2), v + h * a3, tau)
                q = q + h * v + h * h / 6 * (a1 + a2 + a3)
                v = v + h / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
    return n_trials * duration / (time.perf_counter() - t0)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--duration", type=float, default=2.0, help="simulated seconds per trial")
    args = p.parse_args()
    d = args.duration
    ours(1, 0.05, ComputedTorque(oracle=True))  # compile numba kernels first
    rows = [
        ("adaptive_dd, ct_oracle, 1 trial", ours(1, d, ComputedTorque(oracle=True))),
        ("adaptive_dd, ct_oracle, 256 trials", ours(256, d, ComputedTorque(oracle=True))),
        ("adaptive_dd, adaptive_ct, 1 trial", ours(1, d, adaptive_ct())),
        ("adaptive_dd, adaptive_ct, 256 trials", ours(256, d, adaptive_ct())),
        ("pinocchio.aba RK4 loop, ct, 1 trial", pinocchio_loop(1, d)),
        ("pinocchio.aba RK4 loop, ct, 256 trials (est. from 8)", pinocchio_loop(8, d / 4)),
    ]
    print(f"closed loop at T = 1 ms, 2 RK4 substeps, {d} s simulated per trial")
    print(f"{'configuration':55s} {'sim s / wall s':>15s}")
    for name, v in rows:
        print(f"{name:55s} {v:15.2f}")


if __name__ == "__main__":
    main()
