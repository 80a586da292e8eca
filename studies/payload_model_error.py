"""Where adaptive computed torque's model is wrong: per segment and joint, the torque error of the
model the controller used against the true one along the reference, and the estimated payload.

    python studies/payload_model_error.py adaptive_dd/scenarios/ur5_tool_swap_exact.toml --seeds 2

Prints, per kept seed and segment (after its first 0.5 s): the RMS per joint of
``Y(q_d, qd_d, qdd_d) (sigma_hat - sigma_true)`` [N m], and the payload the model holds at
the segment's end (mass [kg], |c| [m], inertia diagonal about the payload frame [kg m^2]),
against the truth.
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.closed_loop.runner import run_closed_loop, run_constants
from adaptive_dd.closed_loop.types import segment_starts


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario")
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--controller", default="adaptive_ct")
    a = ap.parse_args()
    sc = load_scenario(a.scenario)
    sc = dataclasses.replace(sc, seeds=a.seeds, controllers=("ct_oracle", a.controller))
    res = run_closed_loop(sc, keep_trajectories=a.seeds)
    run = res.runs[a.controller]
    rc = run_constants(sc)
    arm = sc.arm
    N = sc.n_samples
    start = segment_starts(sc)
    end = np.append(start[1:], N)
    settle = round(0.5 / sc.sample_period)
    sub = 10  # every 10th sample
    ks = np.arange(0, N, sub)
    Y = np.stack([arm.regressor(rc.q_d[k], rc.qd_d[k], rc.qdd_d[k]) for k in ks])  # (N', n, p)
    for s in range(a.seeds):
        for g in range(len(start)):
            sel = (ks >= start[g] + settle) & (ks < end[g])
            d = run.sigma_hat[s, ks[sel]] - res.sigma_true[ks[sel]]
            err = np.einsum("knp,kp->kn", Y[sel], d)
            rms = np.sqrt(np.mean(err**2, axis=0))
            k_end = end[g] - 1
            ph = arm.payload_from_sigma(run.sigma_hat[s, k_end]).params
            pt = arm.payload_from_sigma(res.sigma_true[k_end]).params
            print(
                f"seed {s} seg {g}: tau err RMS per joint [N m] {np.array2string(rms, precision=4)}\n"
                f"    payload hat m {ph[0]:.4f} |mc| {np.linalg.norm(ph[1:4]):.4f} "
                f"I {np.array2string(ph[[4, 6, 9]], precision=4)}  true m {pt[0]:.4f} "
                f"|mc| {np.linalg.norm(pt[1:4]):.4f} I {np.array2string(pt[[4, 6, 9]], precision=4)}"
            )
    e = res.runs[a.controller].acc
    print("done", e is not None)


if __name__ == "__main__":
    main()
