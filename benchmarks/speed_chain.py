"""Speed of the compiled serial-chain kernels: ``python benchmarks/speed_chain.py``.

A 6-joint UR5-like chain (the joint placements, axes and link masses of the UR5
URDF of ``ur_description``; link inertias approximated by uniform rods along the
links, centres of mass as in the URDF). Prints per-call microseconds of the
compiled :mod:`adaptive_dd.plant.chain` kernels, timed inside a numba loop over
many states (Python call overhead excluded), beside Pinocchio's ``aba``, ``rnea``,
``crba`` and ``computeJointTorqueRegressor`` called from Python (as a Python user
calls them), all in this one run.
"""

from __future__ import annotations

import time

import numpy as np
import pinocchio as pin
from numba import njit

from adaptive_dd.plant import chain as C

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


def _best_of(fn, n_calls: int, repeats: int = 5) -> float:
    """Microseconds per call: best of ``repeats`` runs of ``fn`` (which makes n_calls calls)."""
    fn()  # compile / warm up
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
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

    def py_loop(fn):
        def run():
            for b in range(n_python):
                fn(model, data, q[b], qd[b], qdd[b])

        return run

    rows = [
        (
            "forward dynamics",
            _best_of(lambda: _loop_fd(ch, pi, arm, q, qd, qdd, out), n_states),
            "aba",
            _best_of(py_loop(pin.aba), n_python),
        ),
        (
            "rnea",
            _best_of(lambda: _loop_rnea(ch, pi, q, qd, qdd, out), n_states),
            "rnea",
            _best_of(py_loop(pin.rnea), n_python),
        ),
        (
            "mass_matrix",
            _best_of(lambda: _loop_mass(ch, pi, q, mats), n_states),
            "crba",
            _best_of(py_loop(lambda m, d, a, b, c: pin.crba(m, d, a)), n_python),
        ),
        (
            "regressor",
            _best_of(lambda: _loop_regressor(ch, q, qd, qdd, regs), n_states),
            "computeJointTorqueRegressor",
            _best_of(py_loop(pin.computeJointTorqueRegressor), n_python),
        ),
    ]
    print(f"6-joint UR5-like chain, {n_states} random states; best of 5 runs")
    print("compiled kernels timed inside a numba loop over the states (no Python call overhead);")
    print("Pinocchio called from a Python loop (includes the Python call overhead)")
    print(f"{'kernel':<18s} {'compiled [us]':>14s}   {'pinocchio from Python':<32s} {'[us]':>7s}")
    for name, ours, pin_name, theirs in rows:
        print(f"{name:<18s} {ours:14.2f}   pin.{pin_name:<28s} {theirs:7.2f}")


if __name__ == "__main__":
    bench_kernels()
