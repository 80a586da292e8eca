"""How fast the N-joint estimator knows a new payload, against the information limit, on
open-loop UR5 records (``exciting_motion``; 2 kg then 5 kg at 4 s, the UR5 scenario's tools):
the centre of mass's error and the mass's error at times after the swap (per seed), the time to
1 cm and to 5 % (median over seeds), and the Cramér-Rao times along the first seed's motion.
``--noise-scale 0`` switches the sensor noise off: what is left is the estimator's own equation
error (the filtered regression after a swap).

    python studies/payload_settling.py [--seeds 3] [--noise-scale 1] [--tau-f 0.01] [--regression signals]

The records' torques are exact at the sample instants (no zero-order hold), so the estimator
runs with ``align=False``.
"""

from __future__ import annotations

import argparse

import numpy as np

from adaptive_dd.closed_loop.information import com_learning_time, mass_learning_time
from adaptive_dd.identification.online import OnlineConfig, run_online
from adaptive_dd.identification.payload_information import (
    payload_com_information_time,
    payload_information_time,
)
from adaptive_dd.plant.arm import Arm, payload_parameters
from adaptive_dd.plant.prescribed import exciting_motion, prescribed_record
from adaptive_dd.robots import ROBOTS, robot_urdf

T = 1e-3
SWAP = 4_000
POSTURE = [0.0, -1.3, 1.5, -1.8, -1.57, 0.0]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--noise-scale", type=float, default=1.0)
    ap.add_argument("--tau-f", type=float, default=0.01)
    ap.add_argument("--regression", choices=("signals", "momentum"), default="momentum")
    a = ap.parse_args()
    ur5 = Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)
    A = payload_parameters(2.0, [0.04, 0.0, 0.06], [0.004, 0.004, 0.003, 0, 0, 0])
    B = payload_parameters(5.0, [0.0, 0.03, 0.08], [0.015, 0.015, 0.01, 0, 0, 0])
    t = np.arange(8_000) * T
    recs = []
    for seed in range(a.seeds):
        rng = np.random.default_rng(seed)
        motion = exciting_motion(ur5, t, rng, offset=POSTURE, speed=0.5)
        recs.append(prescribed_record(ur5, t, motion, [A, B], [SWAP], rng=rng, noise_scale=a.noise_scale))
    stack = [np.stack([getattr(r, f) for r in recs]) for f in ("q_meas", "qd_meas", "tau")]
    cfg = OnlineConfig(
        tau_f=a.tau_f,
        row_weights=(1.0, 1.0, 1.0, 0.2, 0.2, 0.2),
        regression=a.regression,
        align=False,  # the record's torques are exact at the sample instants (no zero-order hold)
    )
    rec = run_online(ur5, cfg, *stack)
    com_true = B[1:4] / B[0]
    e_com = 1e3 * np.linalg.norm(rec.com[:, SWAP:] - com_true, axis=-1)
    e_m = np.abs(rec.mass[:, SWAP:] - B[0])
    print(f"UR5, 2 -> 5 kg at {SWAP * T:g} s, {a.seeds} seeds, noise x {a.noise_scale:g}, tau_f {a.tau_f}")
    print("alarms [s]:", [np.round(x, 3).tolist() for x in rec.alarm_times()])
    for dt in (20, 40, 60, 100, 150, 200, 300, 500, 1000):
        c, m = np.round(e_com[:, dt], 1), np.round(e_m[:, dt], 3)
        print(f"  +{dt:4d} ms  com error [mm] {c}  mass error [kg] {m}")
    tc = com_learning_time(rec.com[:, SWAP:], com_true, T)
    tm = mass_learning_time(rec.mass[:, SWAP:], B[0], A[0], T)
    r = recs[0]
    kw = dict(sample_period=T, tau_f=a.tau_f)
    lim_m = payload_information_time(ur5, r.q, r.qd, r.qdd, B, SWAP, **kw)
    lim_c = payload_com_information_time(ur5, r.q, r.qd, r.qdd, B, SWAP, **kw)
    print(
        f"centre of mass within 1 cm: estimator {1e3 * np.nanmedian(tc):.0f} ms (median), information "
        f"limit {1e3 * lim_c:.0f} ms; mass within 5 %: estimator {1e3 * np.nanmedian(tm):.0f} ms, "
        f"limit {1e3 * lim_m:.0f} ms"
    )


if __name__ == "__main__":
    main()
