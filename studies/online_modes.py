"""Payload mode against full mode on UR5 records: ``python studies/online_modes.py [--seeds 5]``.

UR5 (shipped URDF), a prescribed exciting motion with the shipped sensor noise, 20 s at
1 kHz, a 1 kg payload swapped for 2.5 kg (another centre of mass) at 10 s. Two cases:

* ``exact arm``: the estimator's arm is the simulated one;
* ``friction off``: the estimator's arm has viscous and Coulomb friction 30 % too high
  (payload mode keeps it; full mode estimates every base parameter, ``p0_arm = 1e-2``).

Printed per mode and case (mean over seeds; the delay over the trials that detected the
swap): alarms per trial, detection delay, time
after the swap until the mass stays within 5 % (and the Cramér-Rao limit for that, the
colored model of :mod:`adaptive_dd.identification.payload_information`), the mass and
centre-of-mass errors at the end of each segment, and the RMS torque error of the model
control uses (``est_model_trial``, rigid body plus friction) over the last 5 s of each
segment.
"""

from __future__ import annotations

import argparse

import numpy as np

from adaptive_dd.identification.online import (
    OnlineConfig,
    est_init,
    est_model_trial,
    est_payload_trial,
    est_step_trial,
)
from adaptive_dd.identification.payload_information import payload_information_time
from adaptive_dd.plant.arm import Arm, payload_parameters
from adaptive_dd.plant.chain import rnea_batch
from adaptive_dd.plant.prescribed import exciting_motion, prescribed_record
from adaptive_dd.robots import ROBOTS, robot_urdf

T = 1e-3
N = 20_000
SWAP = 10_000
PAYLOADS = [payload_parameters(1.0, [0, 0, 0.05]), payload_parameters(2.5, [0.03, 0, 0.08])]


def _run(arm_est, cfg, r, n):
    """Step the estimator, keeping the payload and the model's torques at every 50th sample."""
    c, s = est_init(cfg, arm_est, 1)
    pay = np.empty((N, 10))
    alarms = []
    pis = {}
    p = np.empty(10)
    pi = np.empty(13 * n)
    for k in range(N):
        if est_step_trial(c, s, 0, r.q_meas[k], r.qd_meas[k], r.tau[k]):
            alarms.append(k)
        est_payload_trial(c, s, 0, p)
        pay[k] = p
        if k % 50 == 0:
            est_model_trial(c, s, 0, pi)
            pis[k] = pi.copy()
    return pay, alarms, pis


def _torque(arm, pi, q, qd, qdd):
    n = arm.n_joints
    return (
        rnea_batch(arm.chain, pi[: 10 * n], q, qd, qdd)
        + pi[10 * n : 11 * n] * qd
        + pi[11 * n : 12 * n] * np.sign(qd)
    )


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=5)
    args = ap.parse_args()
    arm = Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)
    n = arm.n_joints
    off = arm.with_(viscous=1.3 * arm.viscous, coulomb=1.3 * arm.coulomb)
    cases = {"exact arm": arm, "friction off": off}
    modes = {
        "payload": OnlineConfig(),
        "full": OnlineConfig(mode="full", p0_arm=1e-2),
    }
    t = np.arange(N) * T
    recs = []
    limits = []
    for seed in range(args.seeds):
        rng = np.random.default_rng(seed)
        motion = exciting_motion(arm, t, rng, offset=[0, -1.2, 1.2, -1.5, -1.5, 0], speed=0.5)
        r = prescribed_record(arm, t, motion, PAYLOADS, [SWAP], rng=rng)
        recs.append(r)
        limits.append(payload_information_time(arm, r.q, r.qd, r.qdd, PAYLOADS[1], SWAP, sample_period=T))
    print(f"UR5, {args.seeds} seeds, 20 s, 1 kg -> 2.5 kg at 10 s; means over seeds")
    print(f"Cramer-Rao limit, mass within 5 % after the swap: {1e3 * np.mean(limits):.1f} ms (colored model)")
    head = (
        f"{'case':13s} {'mode':8s} {'alarms':>6s} {'delay ms':>8s} {'5% ms':>7s} "
        f"{'m err A %':>9s} {'m err B %':>9s} {'com A mm':>8s} {'com B mm':>8s} "
        f"{'tau A Nm':>8s} {'tau B Nm':>8s}"
    )
    print(head)
    for case, arm_est in cases.items():
        for mode, cfg in modes.items():
            rows = []
            for r in recs:
                pay, alarms, pis = _run(arm_est, cfg, r, n)
                m_true = np.array([PAYLOADS[0][0], PAYLOADS[1][0]])
                ends = [SWAP - 1, N - 1]
                m_err = [100 * abs(pay[e, 0] - m) / m for e, m in zip(ends, m_true, strict=True)]
                com_err = [
                    1e3 * np.linalg.norm(pay[e, 1:4] / pay[e, 0] - P[1:4] / P[0])
                    for e, P in zip(ends, PAYLOADS, strict=True)
                ]
                rel = np.abs(pay[SWAP:, 0] - m_true[1]) / m_true[1]
                bad = np.flatnonzero(rel > 0.05)
                conv = (bad[-1] + 1 if len(bad) else 0) * T * 1e3
                after = [a for a in alarms if a >= SWAP]
                delay = (after[0] - SWAP) * T * 1e3 if after else np.nan
                tau_rms = []
                for lo, hi, P in ((SWAP - 5_000, SWAP, PAYLOADS[0]), (N - 5_000, N, PAYLOADS[1])):
                    ks = [k for k in pis if lo <= k < hi]
                    true_pi = arm.pi.copy()
                    j = arm.payload_joint
                    true_pi[10 * j : 10 * j + 10] += arm.payload_map @ P
                    err = [
                        _torque(arm, pis[k], r.q[k], r.qd[k], r.qdd[k])
                        - _torque(arm, true_pi, r.q[k], r.qd[k], r.qdd[k])
                        for k in ks
                    ]
                    tau_rms.append(float(np.sqrt(np.mean(np.square(err)))))
                rows.append([len(alarms), delay, conv, *m_err, *com_err, *tau_rms])
            a = np.array(rows, dtype=float)
            finite = np.isfinite(a)
            m = np.where(
                finite.any(axis=0),
                np.where(finite, a, 0).sum(axis=0) / np.maximum(finite.sum(axis=0), 1),
                np.nan,
            )
            print(
                f"{case:13s} {mode:8s} {m[0]:6.1f} {m[1]:8.1f} {m[2]:7.0f} {m[3]:9.2f} {m[4]:9.2f} "
                f"{m[5]:8.1f} {m[6]:8.1f} {m[7]:8.3f} {m[8]:8.3f}"
            )


if __name__ == "__main__":
    main()
