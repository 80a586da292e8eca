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
from speed_online import ur5_record  # the same record (this script's folder is on sys.path)

from adaptive_dd.identification.online import OnlineConfig, run_online


def main() -> None:
    arm, q, qd, tau = ur5_record()
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
        print(
            f"{mode:8s} digest {h.hexdigest()[:16]}  {best / q.shape[0] * 1e6:8.2f} CPU us per sample",
            flush=True,
        )


if __name__ == "__main__":
    main()
