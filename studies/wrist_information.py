"""How well the payload can be known at each joint after a pick-up, by the information its
path carries: the Cramér-Rao-style covariance of the payload's ten parameters estimated from the
rows after the swap (white-noise model of the filtered sensor noise, every ``--every``-th sample
with that many times the per-sample covariance; ``adaptive_dd.identification.payload_information``),
for three row weightings: the rows whitened by their joint noise covariance (the estimator's
default, ``OnlineConfig.whiten``), independent rows weighted by the torque limits (before), and by
their own noise. Prints, at times after the swap, the standard deviation of the torque the
estimate's error leaves at the wrist's joints (mean over the next 0.5 s of the path) [N m] and of
the first moment along the payload frame's y axis [kg m].

    python studies/wrist_information.py benchmarks/scenarios/gen3_exact.toml [--segment 1]
"""

from __future__ import annotations

import argparse

import numpy as np

from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.closed_loop.types import run_constants
from adaptive_dd.identification.online import derived_row_weights
from adaptive_dd.identification.payload_information import payload_regression_noise
from adaptive_dd.plant.arm import payload_parameters


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario")
    ap.add_argument("--segment", type=int, default=1)
    ap.add_argument("--every", type=int, default=10)
    ap.add_argument("--seconds", type=float, default=3.0)
    a = ap.parse_args()
    sc = load_scenario(a.scenario)
    arm, rc, T, sub = sc.arm, run_constants(sc), sc.sample_period, a.every
    p = sc.payload_of(a.segment - 1)
    pay = payload_parameters(p["mass"], p.get("com"), p.get("inertia"), p["radius"])
    k0 = int(rc.seg_start[a.segment])
    ks = np.arange(k0, min(int(rc.seg_end[a.segment]), k0 + round(a.seconds / T)), sub)
    Phi, R = payload_regression_noise(
        arm, rc.q_d[ks], rc.qd_d[ks], rc.qdd_d[ks], pay, sample_period=T,
        position_variance=np.asarray(sc.position_variance),
        velocity_variance=np.asarray(sc.velocity_variance),
    )  # fmt: skip
    R = R * sub  # one sample in `sub`, the filtered noise correlated over about that many
    std = np.sqrt(np.diagonal(R / sub, 0, 1, 2)).mean(0)
    print(f"row noise std [N m] (mean over the path): {np.round(std, 4)}")
    wl = derived_row_weights(arm)
    wn = np.sqrt(np.diagonal(R, 0, 1, 2)).mean(0)
    wn = wn / wn.max()
    schemes = {
        "whitened (the rows' joint covariance)": np.linalg.inv(R),
        "independent, torque-limit weights": np.broadcast_to(np.diag(1 / wl**2), R.shape),
        "independent, own-noise weights": np.broadcast_to(np.diag(1 / wn**2), R.shape),
    }
    wrist = slice(max(arm.n_joints - 3, 0), arm.n_joints)
    for name, W in schemes.items():
        A = np.cumsum(np.einsum("kia,kij,kjb->kab", Phi, W, Phi), 0)
        B = np.cumsum(np.einsum("kia,kij,kjl,klm,kmb->kab", Phi, W, R, W, Phi), 0)
        print(name)
        for t in (0.3, 0.5, 1.0, 1.3, 2.0, 3.0):
            i = round(t / (T * sub)) - 1
            if i >= len(ks):
                break
            Ai = np.linalg.inv(A[i] + 1e-12 * np.eye(10))
            C = Ai @ B[i] @ Ai
            nxt = Phi[i : i + round(0.5 / (T * sub))]
            s = np.sqrt(np.einsum("kja,ab,kjb->kj", nxt, C, nxt)).mean(0)
            sy = np.sqrt(C[2, 2])
            print(f"  +{t:.1f} s: torque std at the wrist [N m] {np.round(s[wrist], 4)}; m c_y std {sy:.4f}")


if __name__ == "__main__":
    main()
