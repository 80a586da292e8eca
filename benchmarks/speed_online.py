"""Cost per sample of the N-joint online estimator: ``python benchmarks/speed_online.py``.

UR5 (the shipped URDF), a prescribed exciting motion with the shipped sensor noise,
20 s at 1 kHz, no payload swap. Prints, per mode (``payload``: 10 parameters,
``arm``: the arm's base parameters and the payload's ten), the microseconds per sample of

* ``est_step_trial`` alone, timed inside a numba loop (Python overhead excluded);
* ``est_step_trial`` + ``est_model_trial`` (what a closed loop calls every sample);
* the chain kernels it calls (``rnea``, ``body_regressor``, ``regressor``) for scale;
* ``run_online`` (the recorded whole-record path, from Python).

Compilation is excluded (one warm-up run first). Times are CPU time of the thread
(``time.thread_time``, best of 3), robust to other processes on a shared machine; nothing
is asserted.
"""

from __future__ import annotations

import time

import numpy as np
from numba import njit

from adaptive_dd.identification.online import (
    OnlineConfig,
    est_init,
    est_model_trial,
    est_step_trial,
    run_online,
)
from adaptive_dd.plant import chain as C
from adaptive_dd.plant.arm import Arm, payload_parameters
from adaptive_dd.plant.prescribed import exciting_motion, prescribed_record
from adaptive_dd.robots import ROBOTS, robot_urdf


@njit(cache=True)
def _steps(c, s, q, qd, tau):  # pragma: no cover - compiled
    a = 0
    for k in range(q.shape[0]):
        a += est_step_trial(c, s, 0, q[k], qd[k], tau[k])
    return a


@njit(cache=True)
def _steps_model(c, s, q, qd, tau, pi):  # pragma: no cover - compiled
    a = 0
    for k in range(q.shape[0]):
        a += est_step_trial(c, s, 0, q[k], qd[k], tau[k])
        est_model_trial(c, s, 0, pi)
    return a


@njit(cache=True)
def _rnea(ch, pi, q, qd, out):  # pragma: no cover - compiled
    for k in range(q.shape[0]):
        C.rnea(ch, pi, q[k], qd[k], qd[k], out)


@njit(cache=True)
def _body(ch, j, q, qd, out):  # pragma: no cover - compiled
    for k in range(q.shape[0]):
        C.body_regressor(ch, j, q[k], qd[k], qd[k], out)


@njit(cache=True)
def _reg(ch, q, qd, out):  # pragma: no cover - compiled
    for k in range(q.shape[0]):
        C.regressor(ch, q[k], qd[k], qd[k], out)


def _best(fn, repeat: int = 3) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = time.thread_time()
        fn()
        best = min(best, time.thread_time() - t0)
    return best


def ur5_record(n_samples: int = 20_000):
    """The UR5 and its measured record (1 kHz, seed 0, a 1 kg payload): ``arm, q, qd, tau``
    (``online_digest.py`` digests the estimator over the same record)."""
    arm = Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)
    t = np.arange(n_samples) * 1e-3
    rng = np.random.default_rng(0)
    motion = exciting_motion(arm, t, rng, offset=[0, -1.2, 1.2, -1.5, -1.5, 0], speed=0.5)
    rec = prescribed_record(arm, t, motion, [payload_parameters(1.0, [0, 0, 0.05])], rng=rng)
    return arm, rec.q_meas, rec.qd_meas, rec.tau


def main() -> None:
    N = 20_000
    arm, q, qd, tau = ur5_record(N)
    n = arm.n_joints
    print(f"UR5, {N} samples, base parameters p = {arm.base.count}; CPU microseconds per sample (best of 3)")
    ch, pi = arm.chain, np.ascontiguousarray(arm.pi_links)
    out_n, out_b, out_r = np.empty(n), np.empty((n, 10)), np.empty((n, 10 * n))
    for label, fn in (
        ("chain.rnea", lambda: _rnea(ch, pi, q, qd, out_n)),
        ("chain.body_regressor", lambda: _body(ch, n - 1, q, qd, out_b)),
        ("chain.regressor", lambda: _reg(ch, q, qd, out_r)),
    ):
        fn()
        print(f"  {label:36s} {_best(fn) / N * 1e6:8.2f}")
    for mode in ("payload", "arm"):
        cfg = OnlineConfig(mode=mode)

        def step(cfg=cfg):
            c, s = est_init(cfg, arm, 1)
            _steps(c, s, q, qd, tau)

        def step_model(cfg=cfg):
            c, s = est_init(cfg, arm, 1)
            _steps_model(c, s, q, qd, tau, np.empty(13 * n))

        def record(cfg=cfg):
            run_online(arm, cfg, q, qd, tau)

        for label, fn in (
            ("est_step_trial", step),
            ("est_step_trial + est_model_trial", step_model),
            ("run_online (recorded)", record),
        ):
            fn()
            print(f"  {mode:8s} {label:36s} {_best(fn) / N * 1e6:8.2f}")


if __name__ == "__main__":
    main()
