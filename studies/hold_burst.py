"""The N-joint detector on the UR5 burst record of ``tests/test_online.py`` (5 s prescribed motion,
2.5 kg payload throughout, +10 N m on the elbow for 60 ms from 2.5 s): the alarms of the test's
three-row detector (unit row weights, slow factor 2, no fast average) without the hold, with the
derived hold, held for 50 / 200 ms / 10 s, and with the learning gate; with ``--trace``, each row's
short average over its level every 5 ms from 2.49 to 2.80 s under the gate (``learn_below = 0.5``),
the estimator stepped sample by sample.

    python studies/hold_burst.py [--trace]
"""

from __future__ import annotations

import argparse

import numpy as np

from adaptive_dd.identification import online_kernel as K
from adaptive_dd.identification.online import Detector, OnlineConfig, est_init, est_step, run_online
from adaptive_dd.plant.arm import Arm, payload_parameters
from adaptive_dd.plant.prescribed import exciting_motion, prescribed_record
from adaptive_dd.robots import ROBOTS, robot_urdf

T = 1e-3
POSTURE = [0.0, -1.2, 1.2, -1.5, -1.5, 0.0]
VARIANTS = {
    "no hold": {"hold_above": 0.0},
    "hold (derived, 94 ms)": {},
    "hold 50 ms": {"hold_time": 0.05},
    "hold 200 ms": {"hold_time": 0.2},
    "hold 10 s": {"hold_time": 10.0},
    "gate (learn_below 0.5)": {"hold_above": 0.0, "learn_below": 0.5},
}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--trace", action="store_true")
    a = ap.parse_args()
    ur5 = Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)
    n = 4_000
    t = np.arange(n) * T
    rng = np.random.default_rng(5)
    pay = payload_parameters(2.5, [0.03, 0.0, 0.08], radius=0.05)
    r = prescribed_record(ur5, t, exciting_motion(ur5, t, rng, offset=POSTURE, speed=0.5), [pay], (), rng=rng)
    tau = r.tau.copy()
    tau[2_500:2_560, 2] += 10.0

    def cfg(**kw):
        det = Detector(min_rows=3, fast_window=None, slow_factor=2.0, **kw)
        return OnlineConfig(detector=det, row_weights=(1.0,) * 6)

    for name, kw in VARIANTS.items():
        alarms = run_online(ur5, cfg(**kw), r.q_meas, r.qd_meas, tau).alarm_times()[0]
        print(f"{name:24s} alarms [s] {[round(float(x), 3) for x in alarms]}", flush=True)
    if not a.trace:
        return
    c, s = est_init(cfg(**VARIANTS["gate (learn_below 0.5)"]), ur5, 1)
    a_l, floor2 = c.floats[K.F_ALPHA_LONG], c.floats[K.F_FLOOR2]
    print("gate: time, per row short / level (mean square), level (RMS)")
    for k in range(2_801):
        info = est_step(c, s, r.q_meas[k][None], r.qd_meas[k][None], tau[k][None])
        nl = np.maximum(s.learned[0], 1)
        level = np.maximum(s.long[0] / (1.0 - (1.0 - a_l) ** nl), floor2)
        if (k >= 2_490 and k % 5 == 0) or info.alarm[0]:
            ratio = " ".join(f"{x:6.1f}" for x in s.short[0] / level)
            lv = " ".join(f"{x:.3f}" for x in np.sqrt(level))
            print(f"{k * T:.3f}{' ALARM' if info.alarm[0] else ''}  {ratio}   {lv}")


if __name__ == "__main__":
    main()
