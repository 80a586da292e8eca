"""A reference given as a path of the tool frame, solved to joints by inverse kinematics.

A scenario's ``[reference]`` may give, in place of ``joint1 .. jointN``, a closed path of the
arm's tool frame (its ``payload_frame``) in the base frame::

    [reference]
    ramp = 1.0
    cartesian = { circle = 0.05, normal = [0, 0, 1], period = 4.0, q0 = [0, -1.3, 1.5, -1.8, -1.57, 0] }
    # or: waypoints = [[0, 0, 0], [0.05, 0, 0], [0.05, 0.05, 0.02], [0, 0.05, 0]] (offsets [m])

``q0`` [rad] is the configuration the path starts from (default zeros): the tool's position
there is the path's origin ``p0``, and its orientation is held along the path on an arm of six
joints or more (position only on fewer). The path is one of

- ``circle`` (radius [m]) in the plane of ``normal`` (default ``[0, 0, 1]``), through ``p0`` at
  ``t = 0``; or, with ``center`` [m], about ``p0 + center``, starting at the angle of ``p0``;
- ``waypoints``: offsets [m] from ``p0``, joined in order and back to the first by a periodic
  cubic spline, equally spaced in time;

travelled once per ``period`` [s]. At ``samples`` (default 256) times of one period the joints
are solved by damped least squares (Wampler, "Manipulator inverse kinematic solutions based on
vector formulations and damped least-squares methods", IEEE Trans. SMC 16(1), 1986; Buss,
"Introduction to inverse kinematics with Jacobian transpose, pseudoinverse and damped least
squares methods", 2004), each from the previous solution, with Pinocchio's frame Jacobian and
``log6`` as in its inverse-kinematics example (``examples/inverse-kinematics.py`` of
stack-of-tasks/pinocchio); a redundant arm's null space is pulled towards ``q0`` so that the
joints close the loop. The path's clock is the run's: waypoint ``i`` of ``W`` is reached at
``t = i period / W`` (modulo the period); during the reference's ``ramp`` the tool moves from the
joints' mean pose onto the path. The joint path is then written as the scenario's multi-sine reference:
its Fourier series over the period, with the fewest harmonics whose tool path stays within
``tolerance`` (default 1e-4 m) of the path asked for. So the benchmark, ``validate`` and every
tool that reads a reference see an ordinary ``[reference]``; the path it came from is kept
(:class:`CartesianReference`) so that a limit crossed is named by its waypoint.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.benchmark.scenario_base import Reference

__all__ = ["CartesianPath", "CartesianReference", "cartesian_reference", "path_points", "solve_path"]

Array = NDArray[np.float64]

KEYS = ("circle", "waypoints", "center", "normal", "period", "q0", "samples", "tolerance")
"""The keys of ``[reference] cartesian``."""
MAX_ITER = 200
"""Damped least-squares iterations per sample of the path (at most)."""
DAMPING = 1e-3
"""The damping ``lambda`` of the least squares [m or rad]."""
CONVERGED = 1e-9
"""Norm of the pose error [m, rad] at which a sample's solution is taken."""
REACHED = 1e-6
"""Largest pose error [m, rad] of a sample accepted as on the path (beyond: unreachable)."""


@dataclass(frozen=True)
class CartesianPath:
    """A closed path of the tool frame (module docstring); lengths [m], times [s], angles [rad]."""

    period: float
    q0: tuple[float, ...]
    circle: float | None = None
    waypoints: tuple[tuple[float, ...], ...] = ()
    center: tuple[float, ...] | None = None
    normal: tuple[float, ...] = (0.0, 0.0, 1.0)
    samples: int = 256
    tolerance: float = 1e-4

    def where(self, t: float) -> str:
        """The path's point at time ``t`` [s], in words: the waypoint just passed, or the circle's angle."""
        phase = (t % self.period) / self.period
        if self.waypoints:
            i = math.floor(phase * len(self.waypoints) + 1e-9) % len(self.waypoints)
            return f"waypoint {i + 1} {list(self.waypoints[i])} m (or after it)"
        return f"the circle at {360.0 * phase:.0f} deg"


@dataclass(frozen=True)
class CartesianReference(Reference):
    """A :class:`~adaptive_dd.benchmark.scenario_base.Reference` solved from ``path``."""

    path: CartesianPath | None = None
    path_error: float = 0.0
    """Largest distance [m] of the series' tool path from the path asked for (at the solved samples)."""


def _basis(normal: Array) -> tuple[Array, Array]:
    n = normal / np.linalg.norm(normal)
    a = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(n, a)
    u /= np.linalg.norm(u)
    return u, np.cross(n, u)


def path_points(path: CartesianPath, p0: Array, t: Array) -> Array:
    """The path's positions ``(len(t), 3)`` [m] at times ``t`` [s] (module docstring)."""
    t = np.asarray(t, dtype=float)
    phase = (t % path.period) / path.period
    if path.waypoints:
        from scipy.interpolate import CubicSpline

        w = np.asarray(path.waypoints, dtype=float)
        knots = np.linspace(0.0, 1.0, len(w) + 1)
        spline = CubicSpline(knots, np.vstack((w, w[:1])), bc_type="periodic", axis=0)
        return p0 + spline(phase)
    u, v = _basis(np.asarray(path.normal, dtype=float))
    r = float(path.circle)
    if path.center is None:
        c, a0 = p0 - r * u, 0.0
    else:
        c = p0 + np.asarray(path.center, dtype=float)
        d = p0 - c
        a0 = math.atan2(float(d @ v), float(d @ u))
    a = a0 + 2.0 * np.pi * phase
    return c + r * (np.cos(a)[:, None] * u + np.sin(a)[:, None] * v)


def solve_path(arm, path: CartesianPath) -> tuple[Array, Array, Array]:
    """Joint positions along one period of ``path`` and the last sample again (closing the loop):
    ``(t (M + 1,), q (M + 1, n), err (M + 1,))``, ``err`` the pose error [m, rad] left at each
    sample (damped least squares, module docstring); cut after the first sample out of reach
    (``err > REACHED``)."""
    import pinocchio as pin

    from adaptive_dd.benchmark.end_effector import frame_placements

    model, data = arm.model, arm.model.createData()
    from adaptive_dd.plant.urdf import frame_id

    fid = frame_id(model, arm.payload_frame)
    n = arm.n_joints
    full = n >= 6
    q0 = np.asarray(path.q0, dtype=float)
    p0, r0 = frame_placements(arm, q0)
    M = int(path.samples)
    t = np.arange(M + 1) * path.period / M  # the last one closes the loop
    target = path_points(path, p0, t)
    q = q0.copy()
    qs, errs = np.empty((M + 1, n)), np.empty(M + 1)
    for m in range(M + 1):
        want = pin.SE3(r0, target[m])
        for _ in range(MAX_ITER):
            qp = arm.pin_configuration(q)
            pin.forwardKinematics(model, data, qp)
            now = pin.updateFramePlacement(model, data, fid)
            if full:  # the pose error in the frame, its Jacobian: Pinocchio's example
                i_m_d = now.actInv(want)
                err = pin.log6(i_m_d).vector
                J = pin.computeFrameJacobian(model, data, qp, fid, pin.LOCAL)
                J = -pin.Jlog6(i_m_d.inverse()) @ J
                rhs = -err
            else:
                err = target[m] - now.translation
                J = pin.computeFrameJacobian(model, data, qp, fid, pin.LOCAL_WORLD_ALIGNED)[:3]
                rhs = err
            # a redundant arm (or one whose joints move the tool in fewer directions than the
            # task has): its self-motion pulled towards q0, so that the joints are a function of
            # the pose and close the loop
            pull = (np.eye(n) - np.linalg.pinv(J, rcond=1e-6) @ J) @ (q0 - q)
            if np.linalg.norm(err) < CONVERGED and np.linalg.norm(pull) < CONVERGED:
                break
            A = J @ J.T + DAMPING**2 * np.eye(J.shape[0])
            dq = J.T @ np.linalg.solve(A, rhs) + 0.5 * pull
            q = q + dq
            if np.linalg.norm(dq) < CONVERGED:  # at the closest pose it can reach
                break
        qs[m], errs[m] = q, np.linalg.norm(err)
        if errs[m] > REACHED:  # out of reach: the samples so far, this one last
            return t[: m + 1], qs[: m + 1], errs[: m + 1]
    return t, qs, errs


def _series(q: Array, period: float, H: int) -> tuple[Array, Array, Array, Array]:
    """The first H harmonics of one period of samples ``q (M, n)``: offset ``(n,)``, amplitude,
    frequency [Hz], phase [rad] ``(n, H)`` of ``offset + sum a sin(2 pi f t + phase)``."""
    M = q.shape[0]
    c = np.fft.rfft(q, axis=0) / M
    k = np.arange(1, H + 1)
    amp = 2.0 * np.abs(c[k]).T
    phase = (np.angle(c[k]) + np.pi / 2).T
    return c[0].real, amp, np.broadcast_to(k / period, amp.shape), phase


def cartesian_reference(arm, path: CartesianPath, ramp: float, sample_period: float) -> CartesianReference:
    """The multi-sine :class:`CartesianReference` of ``path`` on ``arm`` (module docstring).

    Raises
    ------
    ValueError
        A point of the path the arm's tool does not reach (naming it), joints that do not close
        the loop, or a path the series cannot follow within ``tolerance`` under the reference's
        limits (at most 50 harmonics, each at most 0.1 / T Hz). The scenario's parser turns it
        into a :class:`~adaptive_dd.errors.ScenarioError` naming ``reference.cartesian``.
    """
    from adaptive_dd.benchmark.end_effector import frame_placements
    from adaptive_dd.benchmark.scenario_base import LIMITS

    t, q, err = solve_path(arm, path)
    bad = np.flatnonzero(err > REACHED)
    if bad.size:
        m = int(bad[np.argmax(err[bad])])
        raise ValueError(
            f"{path.where(t[m])} (t = {t[m]:.3f} s of the period) is out of the tool's reach from q0: "
            f"the closest pose found is {err[m]:.3g} m/rad off; move the path or q0"
        )
    gap = np.abs(q[-1] - q[0])
    if gap.max() > 1e-6:
        j = int(np.argmax(gap))
        raise ValueError(
            f"the joints do not close the loop: joint{j + 1} ends {gap[j]:.3g} rad from where it "
            "started (a path through a singularity, or a redundant arm that drifted); change q0 or the path"
        )
    q, t = q[:-1], t[:-1]
    p_want = path_points(path, frame_placements(arm, np.asarray(path.q0, float))[0], t)
    top = min(int(LIMITS["max_terms"]), q.shape[0] // 2 - 1)
    top = min(top, math.floor(LIMITS["nyquist_fraction"] / sample_period * path.period))
    worst = math.inf
    for H in range(1, top + 1):
        off, amp, freq, ph = _series(q, path.period, H)
        qf = off + np.sum(amp[None] * np.sin(2 * np.pi * freq[None] * t[:, None, None] + ph[None]), axis=2)
        worst = float(np.max(np.linalg.norm(frame_placements(arm, qf)[0] - p_want, axis=1)))
        if worst <= path.tolerance:
            tup = lambda a: tuple(tuple(float(x) for x in row) for row in a)  # noqa: E731
            return CartesianReference(
                tuple(float(x) for x in off), tup(amp), tup(freq), tup(ph), float(ramp), path, worst
            )
    raise ValueError(
        f"the joints' series of at most {top} harmonics (limits: 50 terms, each at most 0.1 / T Hz) "
        f"leaves the tool {worst:.3g} m from the path, beyond tolerance = {path.tolerance:g} m; "
        "make the path smoother or slower (a longer period), or raise the tolerance"
    )


def parse_cartesian(e: list, spec: Any, arm, ramp: float, sample_period: float | None):
    """``[reference] cartesian`` checked (each error appended to ``e`` as ``key: reason``) and
    solved; None when it cannot be."""
    key = "reference.cartesian"
    if not isinstance(spec, dict):
        e.append(f"{key}: must be an inline table {{ circle = ..., period = ... }}, got {spec!r}")
        return None
    n0 = len(e)
    for k in spec:
        if k not in KEYS:
            e.append(f"{key}.{k}: unknown key; allowed: {', '.join(KEYS)}")
    if arm is None or getattr(arm, "model", None) is None:
        e.append(f"{key}: needs an arm with a tool frame ([arm] urdf or robot)")
        return None
    n = arm.n_joints

    def num(k, lo, hi, default=None):
        x = spec.get(k, default)
        ok = isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x) and lo < x <= hi
        if not ok:
            e.append(f"{key}.{k}: must be a number in ({lo:g}, {hi:g}], got {x!r}")
        return float(x) if ok else None

    def vec(k, size, default=None):
        x = spec.get(k, default)
        ok = (
            isinstance(x, list | tuple)
            and len(x) == size
            and all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in x)
        )
        if not ok:
            e.append(f"{key}.{k}: must be a list of {size} finite numbers, got {x!r}")
        return tuple(float(v) for v in x) if ok else None

    if ("circle" in spec) == ("waypoints" in spec):
        e.append(f"{key}: give exactly one of circle (a radius [m]) or waypoints (offsets [m])")
        return None
    period = num("period", 0.0, 3600.0)
    q0 = vec("q0", n, [0.0] * n)
    normal = vec("normal", 3, [0.0, 0.0, 1.0])
    if normal is not None and np.linalg.norm(normal) == 0:
        e.append(f"{key}.normal: must not be zero, got {list(normal)}")
    samples = spec.get("samples", 256)
    if not isinstance(samples, int) or isinstance(samples, bool) or not 16 <= samples <= 4096:
        e.append(f"{key}.samples: must be an integer in [16, 4096], got {samples!r}")
    tol = num("tolerance", 0.0, 0.1, 1e-4)
    circle, points, center = None, (), None
    if "circle" in spec:
        circle = num("circle", 0.0, 5.0)
        if "center" in spec:
            center = vec("center", 3)
    else:
        w = spec["waypoints"]
        if not isinstance(w, list | tuple) or len(w) < 2:
            e.append(f"{key}.waypoints: must be a list of at least 2 points [x, y, z] [m], got {w!r}")
        else:
            for i, p in enumerate(w):
                ok = isinstance(p, list | tuple) and len(p) == 3
                ok = ok and all(
                    isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in p
                )
                if not ok:
                    e.append(f"{key}.waypoints[{i + 1}]: must be [x, y, z] in m (finite), got {p!r}")
            points = tuple(tuple(float(v) for v in p) for p in w)
    if len(e) > n0 or sample_period is None:
        return None
    path = CartesianPath(period, q0, circle, points, center, normal, samples, tol)
    ok = isinstance(ramp, int | float) and not isinstance(ramp, bool) and math.isfinite(ramp)
    ramp = float(ramp) if ok else 0.0  # a bad ramp is reported as reference.ramp
    try:
        return cartesian_reference(arm, path, ramp, sample_period)
    except ValueError as exc:
        e.append(f"{key}: {exc}")
        return None
