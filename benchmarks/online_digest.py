"""Digest and cost of the N-joint online estimator's recorded run: ``python benchmarks/online_digest.py``.

UR5 (the shipped URDF), a prescribed exciting motion with the shipped sensor noise, a 1 kg payload,
20 s at 1 kHz, through ``run_online`` in mode "payload" and mode "arm". Prints, per mode, a
digest (sha256) of every array of the record (estimates, payloads, prior errors, alarms, forgetting
factor, skipped samples) and the CPU microseconds per sample of the thread (best of 3, compilation
excluded). Run it with two source trees on ``PYTHONPATH`` in turn: equal digests are results equal
to the last bit. Asserts nothing.
"""

from __future__ import annotations

import dataclasses
import hashlib
import time

import numpy as np

from adaptive_dd.identification.online import OnlineConfig, run_online
from adaptive_dd.plant.arm import Arm, payload_parameters
from adaptive_dd.plant.prescribed import exciting_motion, prescribed_record
from adaptive_dd.robots import ROBOTS, robot_urdf


def main() -> None:
    arm = Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)
    N = 20_000
    t = np.arange(N) * 1e-3
    rng = np.random.default_rng(0)
    motion = exciting_motion(arm, t, rng, offset=[0, -1.2, 1.2, -1.5, -1.5, 0], speed=0.5)
    rec = prescribed_record(arm, t, motion, [payload_parameters(1.0, [0, 0, 0.05])], rng=rng)
    q, qd, tau = rec.q_meas, rec.qd_meas, rec.tau
    for mode in ("payload", "arm"):
        cfg = OnlineConfig(mode=mode)
        r = run_online(arm, cfg, q, qd, tau)
        h = hashlib.sha256()
        for k, v in sorted(dataclasses.asdict(r).items()):
            if isinstance(v, np.ndarray):
                h.update(k.encode())
                h.update(np.ascontiguousarray(v).tobytes())
        best = np.inf
        for _ in range(3):
            c0 = time.thread_time()
            run_online(arm, cfg, q, qd, tau)
            best = min(best, time.thread_time() - c0)
        print(f"{mode:8s} digest {h.hexdigest()[:16]}  {best / N * 1e6:8.2f} CPU us per sample", flush=True)


if __name__ == "__main__":
    main()
