"""Speed of the compiled serial-chain kernels and plant: ``python benchmarks/speed_chain.py``.

A 6-joint UR5-like chain (the joint placements, axes and link masses of the UR5
URDF of ``ur_description``; link inertias approximated by uniform rods along the
links, centres of mass as in the URDF). Prints per-call microseconds of the
compiled :mod:`adaptive_dd.plant.chain` kernels, timed inside a numba loop over
many states (Python call overhead excluded), beside Pinocchio's ``aba``, ``rnea``,
``crba`` and ``computeJointTorqueRegressor`` called from Python (as a Python user
calls them), all in this one run.

Then the open-loop plant (:mod:`adaptive_dd.plant.integrator`) of the same
chain at 1 kHz, 2 RK4 substeps, stick-slip friction, one trial: simulated seconds
per wall-clock second of ``plant_run``, beside a Python per-sample loop of
RK4 over ``pin.aba`` with the same viscous and Coulomb (``sgn``) friction.
"""

from __future__ import annotations

import time

import numpy as np
import pinocchio as pin
from numba import njit

from adaptive_dd.plant import chain as C
from adaptive_dd.plant import integrator as S

# (name, joint, placement rotation rpy, placement xyz, link mass [kg], com xyz, rod length [m])
_UR5 = (
    ("shoulder_pan", "RZ", (0, 0, 0), (0, 0, 0.089159), 3.7, (0, 0, 0), 0.15),
    ("shoulder_lift", "RY", (0, np.pi / 2, 0), (0, 0.13585, 0), 8.393, (0, 0, 0.28), 0.425),
    ("elbow", "RY", (0, 0, 0), (0, -0.1197, 0.425), 2.275, (0, 0, 0.25), 0.39225),
    ("wrist_1", "RY", (0, np.pi / 2, 0), (0, 0, 0.39225), 1.219, (0, 0, 0), 0.12),
    ("wrist_2", "RZ", (0, 0, 0), (0, 0.093, 0), 1.219, (0, 0, 0), 0.12),
    ("wrist_3", "RY", (0, 0, 0), (0, 0, 0.09465), 0.1879, (0, 0, 0), 0.05),
)


def ur5_like_model() -> pin.Model:
    """The UR5-like 6-joint Pinocchio model described in the module docstring."""
    model = pin.Model()
    model.name = "ur5_like"
    parent = 0
    for name, kind, rpy, xyz, mass, com, length in _UR5:
        joint = pin.JointModelRZ() if kind == "RZ" else pin.JointModelRY()
        placement = pin.SE3(pin.rpy.rpyToMatrix(*rpy), np.array(xyz, dtype=float))
        parent = model.addJoint(parent, joint, placement, name)
        rod = mass * length**2 / 12.0
        inertia = np.diag([rod + 1e-3, rod + 1e-3, 2e-3 * mass])
        model.appendBodyToJoint(
            parent, pin.Inertia(mass, np.array(com, dtype=float), inertia), pin.SE3.Identity()
        )
    return model


@njit(cache=True)
def _loop_fd(ch, pi, arm, q, qd, tau, out):  # pragma: no cover - compiled
    for b in range(q.shape[0]):
        C.forward_dynamics(ch, pi, arm, q[b], qd[b], tau[b], out[b])


@njit(cache=True)
def _loop_rnea(ch, pi, q, qd, qdd, out):  # pragma: no cover - compiled
    for b in range(q.shape[0]):
        C.rnea(ch, pi, q[b], qd[b], qdd[b], out[b])


@njit(cache=True)
def _loop_mass(ch, pi, q, out):  # pragma: no cover - compiled
    for b in range(q.shape[0]):
        C.mass_matrix(ch, pi, q[b], out[b])


@njit(cache=True)
def _loop_regressor(ch, q, qd, qdd, out):  # pragma: no cover - compiled
    for b in range(q.shape[0]):
        C.regressor(ch, q[b], qd[b], qdd[b], out[b])


def _best_of(fn, n_calls: int, repeats: int = 5, clock=time.perf_counter) -> float:
    """Microseconds per call: best of ``repeats`` runs of ``fn`` (which makes n_calls calls).

    ``clock`` is wall time by default; ``time.thread_time`` (CPU time of this thread)
    is less disturbed by other processes on a shared machine.
    """
    fn()  # compile / warm up
    best = np.inf
    for _ in range(repeats):
        t0 = clock()
        fn()
        best = min(best, clock() - t0)
    return 1e6 * best / n_calls


def bench_kernels(n_states: int = 20000, n_python: int = 5000, seed: int = 0) -> None:
    """Print per-call microseconds of the compiled kernels and of Pinocchio from Python."""
    model = ur5_like_model()
    data = model.createData()
    ch, pi = C.chain_from_model(model), C.standard_parameters(model)
    n = model.nv
    rng = np.random.default_rng(seed)
    q, qd, qdd = (rng.uniform(-2, 2, size=(n_states, n)) for _ in range(3))
    out, mats, regs = np.empty((n_states, n)), np.empty((n_states, n, n)), np.empty((n_states, n, 10 * n))
    arm = np.zeros(n)

    def best(fn, n_calls):
        return _best_of(fn, n_calls, clock=time.thread_time)

    def py_loop(fn):
        def run():
            for b in range(n_python):
                fn(model, data, q[b], qd[b], qdd[b])

        return run

    rows = [
        (
            "forward dynamics",
            best(lambda: _loop_fd(ch, pi, arm, q, qd, qdd, out), n_states),
            "aba",
            best(py_loop(pin.aba), n_python),
        ),
        (
            "rnea",
            best(lambda: _loop_rnea(ch, pi, q, qd, qdd, out), n_states),
            "rnea",
            best(py_loop(pin.rnea), n_python),
        ),
        (
            "mass_matrix",
            best(lambda: _loop_mass(ch, pi, q, mats), n_states),
            "crba",
            best(py_loop(lambda m, d, a, b, c: pin.crba(m, d, a)), n_python),
        ),
        (
            "regressor",
            best(lambda: _loop_regressor(ch, q, qd, qdd, regs), n_states),
            "computeJointTorqueRegressor",
            best(py_loop(pin.computeJointTorqueRegressor), n_python),
        ),
    ]
    print(f"6-joint UR5-like chain, {n_states} random states; best of 5 runs, CPU time of this thread")
    print("compiled kernels timed inside a numba loop over the states (no Python call overhead);")
    print("Pinocchio called from a Python loop (includes the Python call overhead)")
    print(f"{'kernel':<18s} {'compiled [us]':>14s}   {'pinocchio from Python':<32s} {'[us]':>7s}")
    for name, ours, pin_name, theirs in rows:
        print(f"{name:<18s} {ours:14.2f}   pin.{pin_name:<28s} {theirs:7.2f}")


def _plant_case(duration: float):
    """UR5-like plant with friction, and a torque: gravity at the start pose plus sinusoids."""
    model = ur5_like_model()
    ch, pi = C.chain_from_model(model), C.standard_parameters(model)
    n = model.nv
    fv, fc, armature = np.full(n, 0.5), np.full(n, 1.0), np.full(n, 0.05)
    pp = S.plant_params(ch, pi, fv, fc, armature, law="stick-slip")
    q0 = np.array([0.0, -1.2, 1.0, -0.5, 0.3, 0.0])
    g0 = np.empty(n)
    C.rnea(ch, pi, q0, np.zeros(n), np.zeros(n), g0)
    t = np.arange(round(duration / 1e-3)) * 1e-3
    amp = np.array([5.0, 5.0, 3.0, 1.0, 1.0, 0.3])
    tau = g0 + amp * np.sin(2 * np.pi * 0.5 * t[:, None] + np.arange(n))
    return model, ch, pp, q0, tau


def bench_plant(duration: float = 10.0, python_duration: float = 1.0) -> None:
    """Print simulated seconds per wall second: compiled plant vs Python RK4 over pin.aba."""
    model, ch, pp, q0, tau = _plant_case(duration)
    n, T, substeps = model.nv, 1e-3, 2
    q_out, qd_out = np.empty_like(tau), np.empty_like(tau)

    def compiled():
        q, qd = q0.copy(), np.zeros(n)
        done = S.plant_run(ch, pp, q, qd, tau, T, substeps, q_out, qd_out)
        if done != tau.shape[0]:
            raise RuntimeError(f"plant step failed at sample {done}")

    us = _best_of(compiled, tau.shape[0], repeats=3)
    us_cpu = _best_of(compiled, tau.shape[0], repeats=3, clock=time.thread_time)
    stuck_share = float(np.mean(qd_out == 0.0))

    model.armature = pp.armature
    data = model.createData()
    n_py = round(python_duration / T)

    def accel(q, qd, u):
        return pin.aba(model, data, q, qd, u - pp.fv * qd - pp.fc * np.sign(qd))

    def python_loop():
        q, qd = q0.copy(), np.zeros(n)
        h = T / substeps
        for k in range(n_py):
            u = tau[k]
            for _ in range(substeps):
                a1 = accel(q, qd, u)
                w = qd + 0.5 * h * a1
                a2 = accel(q + 0.5 * h * qd, w, u)
                x = qd + 0.5 * h * a2
                a3 = accel(q + 0.5 * h * w, x, u)
                y = qd + h * a3
                a4 = accel(q + h * x, y, u)
                q = q + h / 6 * (qd + 2 * w + 2 * x + y)
                qd = qd + h / 6 * (a1 + 2 * a2 + 2 * a3 + a4)

    us_py = _best_of(python_loop, n_py, repeats=3)
    us_py_cpu = _best_of(python_loop, n_py, repeats=3, clock=time.thread_time)
    print()
    print(f"open-loop 6-joint plant, T = 1 ms, {substeps} RK4 substeps, one trial, {duration:g} s simulated")
    print(f"(stick-slip friction fv = 0.5, fc = 1.0; {100 * stuck_share:.1f} % of joint-samples at rest)")
    print(f"{'':<44s} {'wall clock':>31s}   {'CPU time of this thread':>31s}")
    for name, wall, cpu in (
        ("compiled plant_run", us, us_cpu),
        ("Python loop, RK4 over pin.aba (sgn friction)", us_py, us_py_cpu),
    ):
        print(
            f"{name:<44s} {wall:8.2f} us/sample {1e3 / wall:7.0f} x real time   "
            f"{cpu:8.2f} us/sample {1e3 / cpu:7.0f} x real time"
        )
    print(f"compiled / Python speed-up: {us_py / us:.1f} (wall), {us_py_cpu / us_cpu:.1f} (CPU)")


if __name__ == "__main__":
    bench_kernels()
    bench_plant()
