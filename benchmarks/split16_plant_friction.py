"""What our plant's sticking and the torque's timing do to the paper's estimator (Tables 3 and 5).

    python benchmarks/split16_plant_friction.py [--seeds 4]

The paper's experiment (Tables 2 and 4: a 1 Hz sine for 10 s, its noise) on the paper's arm with
two plant friction laws: the stick-slip Coulomb plant the package simulates by default (a joint at
rest sticks until its torque beats the friction) and a smooth one (``tanh``, v = 0.02 rad/s, which
barely sticks). For each: the fraction of samples each joint is stuck, and the worst mean
|error| over the seven parameters [%] of the paper's estimator with splits (15) and (16), methods
M1 and M2, at two filter time constants. The paper's model, eq. (6), has d sgn(qd) only: a stuck
joint's samples break it. Then, with noise-free sensors (one seed), M2's split (15) error per
parameter at tau_f = 8 ms (Table 5's b1 is 16 times the paper's there): with the torque held over
each sample paired with its start (the paper's estimator) and averaged over the sample's two
halves (``align_torque``, as the exact estimator does), on both plants. Asserts nothing.
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from adaptive_dd.experiments import table2_torque, trial_rngs
from adaptive_dd.identification.estimators import align_torque, estimate, prepare_regression, solve_regression
from adaptive_dd.plant.simulator import simulate_open_loop
from adaptive_dd.plant.two_link import ClosedFormTwoLink


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=4)
    args = ap.parse_args()
    for friction in ("stick-slip", "tanh"):
        kw = {} if friction == "stick-slip" else {"friction": "tanh"}
        arm = ClosedFormTwoLink.sice(**kw)
        sim = simulate_open_loop(table2_torque(args.seeds), trial_rngs(0, args.seeds), arm=arm)
        stuck = (sim.qd == 0).mean(axis=(0, 1))
        print(f"plant friction {friction}: stuck fraction per joint {np.round(stuck, 4).tolist()}")
        for method in ("M1", "M2"):
            for tau_f in (0.006, 0.02):
                phi, y, act = prepare_regression(
                    sim.q_meas, sim.tau, sim.qd_meas, estimator="paper", method=method, tau_f=tau_f
                )
                worst = []
                for split in ("15", "16"):
                    theta, _, _ = solve_regression(phi, y, act, estimator="paper", split=split)
                    err = np.abs(100.0 * (theta[..., -1, :] - arm.sigma) / arm.sigma).mean(axis=0)
                    worst.append(f"split ({split}) {err.max():6.1f} %")
                print(f"  {method}, tau_f = {1e3 * tau_f:g} ms: worst mean error " + ", ".join(worst))
    print("noise-free, M2, split (15), tau_f = 8 ms: error per parameter [%] (J1 J2 r b1 b2 d1 d2)")
    for friction in ("stick-slip", "tanh"):
        kw = {} if friction == "stick-slip" else {"friction": "tanh"}
        arm = ClosedFormTwoLink.sice(**kw)
        quiet = dataclasses.replace(
            arm.sensor, position_variance=(0, 0), velocity_variance=(0, 0), quantize=False
        )
        sim = simulate_open_loop(table2_torque(1), trial_rngs(0, 1), arm=arm, sensor=quiet)
        for timing, tau in (
            ("held, paired with its start", sim.tau),
            ("averaged over the sample", align_torque(sim.tau)),
        ):
            r = estimate(sim.q_meas, tau, sim.qd_meas, estimator="paper", method="M2", tau_f=0.008)
            err = 100.0 * (r.final[0] - arm.sigma) / arm.sigma
            print(f"  {friction:10s} torque {timing:28s} " + " ".join(f"{e:+6.2f}" for e in err))


if __name__ == "__main__":
    main()
