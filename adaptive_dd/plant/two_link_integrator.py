"""The compiled plant integrator: one sample of the arm under a held torque.

Friction model
--------------
Viscous plus Coulomb friction of eqs. (5)-(6), with *sticking*. A joint at rest
(velocity exactly 0) either sticks, which is consistent while the torque needed
to hold it, ``|tau_i - (C qd)_i - (M qdd)_i|`` with the other joint's motion taken
into account, is at most ``d_i``; or it slides from rest in a direction s, which
is consistent if its acceleration has the sign of s. The modes of the joints at
rest are chosen jointly (the coupled 2x2 problem: at most 9 combinations, sticking
first) at the start of every integration substep; within a substep the modes are
fixed and moving joints see ``d_i sgn(qd_i)``. When a moving joint's velocity
reaches zero within a substep, the substep is split there, the modes are decided
anew and the rest of the substep is integrated. This hybrid model has no
chattering at zero velocity, unlike integrating ``sgn(qd)`` directly.

Smooth plant friction
---------------------
With ``friction_code`` 1 (``"tanh"``) or 2 (``"stribeck"``) the Coulomb term is a
smooth function of the velocity (see :mod:`adaptive_dd.plant.two_link`) and
:func:`_smooth_step_kernel` integrates the ODE with plain RK4, without modes. Near
zero velocity that ODE is stiff (slope ``d_i / v``); each substep is therefore split
into as many equal RK4 steps as keep ``h * rho`` below 2 (RK4 is stable up to
2.78 on the negative real axis), with ``rho`` a bound on the spectral radius of
``M^-1 K``, ``K`` the largest friction slopes, at the current q2.

LuGre plant friction
--------------------
With ``friction_code`` 3 (``"lugre"``) every joint carries a bristle deflection
``z_i`` [rad] (Canudas de Wit, Olsson, Astrom, Lischinsky, IEEE TAC 40(3), 1995)::

    dz/dt = v - sigma0 |v| z / g(v),   g(v) = d + (k d - d) exp(-(v / v_s)^2)
    F     = sigma0 z + sigma1 dz/dt + b v

(``d`` and ``b`` from sigma; ``k``, ``v_s``, ``sigma0``, ``sigma1`` per joint, see
:mod:`adaptive_dd.plant.two_link`). With ``sigma0`` about 1e5 N m/rad the ODE is stiff
(bristle modes near 5000 rad/s on the SICE arm's near-singular inertia; the relaxation
rate ``sigma0 |v| / g`` reaches 5e5 1/s at 3.5 rad/s), so :func:`_lugre_one` does not use
RK4: it takes micro-steps of at most :data:`LUGRE_DT_MAX` with a linearly implicit
(backward) Euler step in ``(v, z)``, the relaxation rate lagged by one micro-step, and
the position advanced with the new velocity (semi-implicit Euler)::

    z+ = (z + h v+) / (1 + h a),   a = sigma0 |v| / g(v)
    (M + h diag(K)) v+ = M v + h (tau - c(q, v) - F0)
    K = (sigma0 h + sigma1) / (1 + h a) + b,   F0 = z (sigma0 - sigma1 a) / (1 + h a)

The step is A-stable on the linear bristle spring-damper and the update of ``z`` is a
contraction (``|z+| <= (|z| + h |v+|) / (1 + h a)``), so no step size makes it diverge;
its first-order error is bounded by the micro-step (tests compare it with ten times
finer steps). A joint without Coulomb friction (``d_i = 0``) keeps ``z_i = 0``.

Sampling
--------
Each call of :meth:`ArmSimulator.step` holds the torque constant for one sample
period ``T`` (zero-order hold) and integrates with ``substeps`` classical RK4 steps.
Nothing stateful (controller, estimator, sensor) runs inside the substeps.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from adaptive_dd.errors import ParameterError

__all__ = ["FRICTION_CODES", "LUGRE_DT_MAX", "N_FRICTION_PARAMS", "lugre_step", "two_link_plant_step"]

FRICTION_CODES = {"stick-slip": 0, "tanh": 1, "stribeck": 2, "lugre": 3}
"""Integer code of each plant friction law (:attr:`adaptive_dd.plant.two_link.TwoLinkArm.friction`)."""

Array = NDArray[np.float64]

LUGRE_DT_MAX = 1e-4
"""Longest micro-step [s] of the LuGre integrator (10 per sample at 1 kHz)."""

N_FRICTION_PARAMS = 7
"""Length of a friction parameter vector: ``(friction_velocity, stribeck_ratio,
stribeck_velocity, sigma0_1, sigma0_2, sigma1_1, sigma1_2)``."""


@njit(cache=True, fastmath=False)
def _accel_hold(q2, v1, v2, t1, t2, sg, st1, st2, sl1, sl2):  # pragma: no cover - compiled
    """Accelerations with stuck joints held, and the torque friction must supply (one arm)."""
    j1, j2, r, b1, b2, d1, d2 = sg[0], sg[1], sg[2], sg[3], sg[4], sg[5], sg[6]
    c2, s2 = np.cos(q2), np.sin(q2)
    m11 = j1 + j2 + 2.0 * r * c2
    m12 = j2 + r * c2
    m22 = j2
    cor1 = -r * s2 * v2 * (2.0 * v1 + v2)
    cor2 = r * s2 * v1 * v1
    sgn1 = np.sign(v1) if v1 != 0.0 else sl1
    sgn2 = np.sign(v2) if v2 != 0.0 else sl2
    r1 = t1 - cor1 - b1 * v1 - d1 * sgn1
    r2 = t2 - cor2 - b2 * v2 - d2 * sgn2
    if st1 and st2:
        a1, a2 = 0.0, 0.0
    elif st1:
        a1, a2 = 0.0, r2 / m22
    elif st2:
        a1, a2 = r1 / m11, 0.0
    else:
        det = m11 * m22 - m12 * m12
        a1 = (m22 * r1 - m12 * r2) / det
        a2 = (m11 * r2 - m12 * r1) / det
    h1 = t1 - cor1 - m11 * a1 - m12 * a2
    h2 = t2 - cor2 - m12 * a1 - m22 * a2
    return a1, a2, h1, h2


@njit(cache=True, fastmath=False)
def _rk4(p1, p2, v1, v2, dt, t1, t2, sg, st1, st2, sl1, sl2):  # pragma: no cover - compiled
    """One classical RK4 step of length dt with the stuck set fixed."""
    a11, a12, _, _ = _accel_hold(p2, v1, v2, t1, t2, sg, st1, st2, sl1, sl2)
    w1, w2 = v1 + 0.5 * dt * a11, v2 + 0.5 * dt * a12
    a21, a22, _, _ = _accel_hold(p2 + 0.5 * dt * v2, w1, w2, t1, t2, sg, st1, st2, sl1, sl2)
    x1, x2 = v1 + 0.5 * dt * a21, v2 + 0.5 * dt * a22
    a31, a32, _, _ = _accel_hold(p2 + 0.5 * dt * w2, x1, x2, t1, t2, sg, st1, st2, sl1, sl2)
    y1, y2 = v1 + dt * a31, v2 + dt * a32
    a41, a42, _, _ = _accel_hold(p2 + dt * x2, y1, y2, t1, t2, sg, st1, st2, sl1, sl2)
    n1 = p1 + (dt / 6.0) * (v1 + 2.0 * w1 + 2.0 * x1 + y1)
    n2 = p2 + (dt / 6.0) * (v2 + 2.0 * w2 + 2.0 * x2 + y2)
    u1 = 0.0 if st1 else v1 + (dt / 6.0) * (a11 + 2.0 * a21 + 2.0 * a31 + a41)
    u2 = 0.0 if st2 else v2 + (dt / 6.0) * (a12 + 2.0 * a22 + 2.0 * a32 + a42)
    # a velocity that changes sign in any stage has met the Coulomb discontinuity:
    # the step is then not to be trusted (the caller splits it at the crossing)
    s1 = np.sign(v1) if v1 != 0.0 else sl1
    s2 = np.sign(v2) if v2 != 0.0 else sl2
    c1 = (not st1) and min(w1 * s1, x1 * s1, y1 * s1, u1 * s1) <= 0.0
    c2 = (not st2) and min(w2 * s2, x2 * s2, y2 * s2, u2 * s2) <= 0.0
    return n1, n2, u1, u2, c1, c2, a11, a12


@njit(cache=True, fastmath=False)
def _resolve(p2, v1, v2, t1, t2, sg, r1, r2, sl1, sl2):  # pragma: no cover - compiled
    """Friction mode of the joints at rest (``r_i``: qd_i == 0), decided jointly.

    Each joint at rest either sticks (consistent if its holding torque is at most
    d_i) or slides from rest in direction s (consistent if its acceleration has
    the sign of s). The combinations are tried, sticking first, and the first
    consistent one is taken; the 2x2 case has at most 9.
    """
    for m1 in range(3 if r1 else 1):
        for m2 in range(3 if r2 else 1):
            st1 = r1 and m1 == 0
            st2 = r2 and m2 == 0
            s1 = 1.0 if (r1 and m1 == 1) else (-1.0 if (r1 and m1 == 2) else sl1)
            s2 = 1.0 if (r2 and m2 == 1) else (-1.0 if (r2 and m2 == 2) else sl2)
            a1, a2, h1, h2 = _accel_hold(p2, v1, v2, t1, t2, sg, st1, st2, s1, s2)
            ok = True
            if r1:
                ok = ok and (abs(h1) <= sg[5] if st1 else a1 * s1 > 0.0)
            if r2:
                ok = ok and (abs(h2) <= sg[6] if st2 else a2 * s2 > 0.0)
            if ok:
                return st1, st2, s1, s2
    return r1, r2, sl1, sl2  # numerically borderline: hold them this substep


@njit(cache=True, fastmath=False)
def _stick_slip_one(q, qd, stuck, slip, i, t1, t2, sg, T, substeps):  # pragma: no cover - compiled
    """One sample of trial i (row i of the state arrays) under the held torque (t1, t2)."""
    h = T / substeps
    p1, p2, v1, v2 = q[i, 0], q[i, 1], qd[i, 0], qd[i, 1]
    st1, st2, sl1, sl2 = stuck[i, 0], stuck[i, 1], slip[i, 0], slip[i, 1]
    cz1, cz2 = sg[5] > 0.0, sg[6] > 0.0  # joints with Coulomb friction
    for _ in range(substeps):
        r1, r2 = v1 == 0.0 and cz1, v2 == 0.0 and cz2
        st1, st2 = False, False
        if r1 or r2:
            st1, st2, sl1, sl2 = _resolve(p2, v1, v2, t1, t2, sg, r1, r2, sl1, sl2)
        n1, n2, u1, u2, c1, c2, a1, a2 = _rk4(p1, p2, v1, v2, h, t1, t2, sg, st1, st2, sl1, sl2)
        c1 = c1 and cz1
        c2 = c2 and cz2
        if c1 or c2:
            # a velocity reaches zero: step to the first crossing (located from the
            # initial acceleration), decide the friction modes there, finish the substep
            f1 = min(1.0, abs(v1) / (h * abs(a1))) if c1 and v1 * a1 < 0.0 else (0.0 if c1 else 1.0)
            f2 = min(1.0, abs(v2) / (h * abs(a2))) if c2 and v2 * a2 < 0.0 else (0.0 if c2 else 1.0)
            f = min(f1, f2)
            if f > 0.0:
                p1, p2, v1, v2, _, _, _, _ = _rk4(p1, p2, v1, v2, f * h, t1, t2, sg, st1, st2, sl1, sl2)
            if c1 and f1 <= f:
                v1 = 0.0
            if c2 and f2 <= f:
                v2 = 0.0
            st1, st2, sl1, sl2 = _resolve(
                p2, v1, v2, t1, t2, sg, v1 == 0.0 and cz1, v2 == 0.0 and cz2, sl1, sl2
            )
            n1, n2, u1, u2, z1, z2, _, _ = _rk4(p1, p2, v1, v2, (1.0 - f) * h, t1, t2, sg, st1, st2, sl1, sl2)
            # another crossing within the same substep: rest there (decided next substep)
            if z1 and cz1 and f < 1.0:
                u1 = 0.0
            if z2 and cz2 and f < 1.0:
                u2 = 0.0
        p1, p2, v1, v2 = n1, n2, u1, u2
    q[i, 0], q[i, 1], qd[i, 0], qd[i, 1] = p1, p2, v1, v2
    stuck[i, 0], stuck[i, 1] = st1 and v1 == 0.0, st2 and v2 == 0.0
    slip[i, 0], slip[i, 1] = sl1, sl2


@njit(cache=True, fastmath=False)
def _plant_step_kernel(q, qd, stuck, slip, tau, sigma, T, substeps):  # pragma: no cover
    for i in range(q.shape[0]):
        _stick_slip_one(q, qd, stuck, slip, i, tau[i, 0], tau[i, 1], sigma[i], T, substeps)


@njit(cache=True, fastmath=False)
def _coulomb(v, d, code, vc, ratio, vs):  # pragma: no cover - compiled
    """Smooth Coulomb torque of one joint: tanh (code 1) or Stribeck (code 2)."""
    g = d
    if code == 2:
        g = d * (1.0 + (ratio - 1.0) * np.exp(-((v / vs) ** 2)))
    return g * np.tanh(v / vc)


@njit(cache=True, fastmath=False)
def _smooth_accel(q2, v1, v2, t1, t2, sg, code, vc, ratio, vs):  # pragma: no cover - compiled
    j1, j2, r, b1, b2, d1, d2 = sg[0], sg[1], sg[2], sg[3], sg[4], sg[5], sg[6]
    c2, s2 = np.cos(q2), np.sin(q2)
    m11 = j1 + j2 + 2.0 * r * c2
    m12 = j2 + r * c2
    m22 = j2
    r1 = t1 + r * s2 * v2 * (2.0 * v1 + v2) - b1 * v1 - _coulomb(v1, d1, code, vc, ratio, vs)
    r2 = t2 - r * s2 * v1 * v1 - b2 * v2 - _coulomb(v2, d2, code, vc, ratio, vs)
    det = m11 * m22 - m12 * m12
    return (m22 * r1 - m12 * r2) / det, (m11 * r2 - m12 * r1) / det


@njit(cache=True, fastmath=False)
def _smooth_one(q, qd, i, t1, t2, sg, T, substeps, code, vc, ratio, vs):  # pragma: no cover - compiled
    """One sample of trial i with a smooth friction law (plain RK4, stiff substeps split)."""
    h = T / substeps
    p1, p2, v1, v2 = q[i, 0], q[i, 1], qd[i, 0], qd[i, 1]
    # largest friction slopes: tanh' <= 1 / vc; Stribeck adds |g'| <= (k - 1) d sqrt(2/e) / vs
    extra = 0.0 if code != 2 else (ratio - 1.0) * 0.8578 / vs
    kpeak = (ratio if code == 2 else 1.0) / vc + extra
    k1 = sg[3] + sg[5] * kpeak
    k2 = sg[4] + sg[6] * kpeak
    for _ in range(substeps):
        c2 = np.cos(p2)
        m11 = sg[0] + sg[1] + 2.0 * sg[2] * c2
        m22 = sg[1]
        det = m11 * m22 - (sg[1] + sg[2] * c2) ** 2
        rho = (k1 * m22 + k2 * m11) / det  # trace of M^-1 K >= its spectral radius
        m = max(1, int(np.ceil(h * rho / 2.0)))
        dt = h / m
        for _ in range(m):
            a11, a12 = _smooth_accel(p2, v1, v2, t1, t2, sg, code, vc, ratio, vs)
            w1, w2 = v1 + 0.5 * dt * a11, v2 + 0.5 * dt * a12
            a21, a22 = _smooth_accel(p2 + 0.5 * dt * v2, w1, w2, t1, t2, sg, code, vc, ratio, vs)
            x1, x2 = v1 + 0.5 * dt * a21, v2 + 0.5 * dt * a22
            a31, a32 = _smooth_accel(p2 + 0.5 * dt * w2, x1, x2, t1, t2, sg, code, vc, ratio, vs)
            y1, y2 = v1 + dt * a31, v2 + dt * a32
            a41, a42 = _smooth_accel(p2 + dt * x2, y1, y2, t1, t2, sg, code, vc, ratio, vs)
            p1 = p1 + (dt / 6.0) * (v1 + 2.0 * w1 + 2.0 * x1 + y1)
            p2 = p2 + (dt / 6.0) * (v2 + 2.0 * w2 + 2.0 * x2 + y2)
            v1 = v1 + (dt / 6.0) * (a11 + 2.0 * a21 + 2.0 * a31 + a41)
            v2 = v2 + (dt / 6.0) * (a12 + 2.0 * a22 + 2.0 * a32 + a42)
    q[i, 0], q[i, 1], qd[i, 0], qd[i, 1] = p1, p2, v1, v2


@njit(cache=True, fastmath=False)
def _smooth_step_kernel(q, qd, tau, sigma, T, substeps, code, vc, ratio, vs):  # pragma: no cover
    for i in range(q.shape[0]):
        _smooth_one(q, qd, i, tau[i, 0], tau[i, 1], sigma[i], T, substeps, code, vc, ratio, vs)


@njit(cache=True, fastmath=False)
def _lugre_joint(v, zj, b, d, ratio, vs, s0, s1, h):  # pragma: no cover - compiled
    """``(1 + h a, K, F0)`` of one joint's implicit LuGre micro-step (module docstring)."""
    if d <= 0.0:
        return 1.0, b, 0.0
    g = d * (1.0 + (ratio - 1.0) * np.exp(-((v / vs) ** 2)))
    a = s0 * abs(v) / g
    den = 1.0 + h * a
    return den, (s0 * h + s1) / den + b, zj * (s0 - s1 * a) / den


@njit(cache=True, fastmath=False)
def _lugre_one(q, qd, z, i, t1, t2, sg, T, substeps, fp):  # pragma: no cover - compiled
    """One sample of trial i with LuGre friction (module docstring: implicit micro-steps)."""
    n = max(substeps, int(np.ceil(T / LUGRE_DT_MAX - 1e-9)))
    h = T / n
    j1, j2, r = sg[0], sg[1], sg[2]
    ratio, vs = fp[1], fp[2]
    p1, p2, v1, v2 = q[i, 0], q[i, 1], qd[i, 0], qd[i, 1]
    z1, z2 = z[i, 0], z[i, 1]
    for _ in range(n):
        c2, s2 = np.cos(p2), np.sin(p2)
        m11 = j1 + j2 + 2.0 * r * c2
        m12 = j2 + r * c2
        m22 = j2
        cor1 = -r * s2 * v2 * (2.0 * v1 + v2)
        cor2 = r * s2 * v1 * v1
        den1, k1, f1 = _lugre_joint(v1, z1, sg[3], sg[5], ratio, vs, fp[3], fp[5], h)
        den2, k2, f2 = _lugre_joint(v2, z2, sg[4], sg[6], ratio, vs, fp[4], fp[6], h)
        a11 = m11 + h * k1
        a22 = m22 + h * k2
        r1 = m11 * v1 + m12 * v2 + h * (t1 - cor1 - f1)
        r2 = m12 * v1 + m22 * v2 + h * (t2 - cor2 - f2)
        det = a11 * a22 - m12 * m12
        v1 = (a22 * r1 - m12 * r2) / det
        v2 = (a11 * r2 - m12 * r1) / det
        z1 = (z1 + h * v1) / den1 if sg[5] > 0.0 else 0.0
        z2 = (z2 + h * v2) / den2 if sg[6] > 0.0 else 0.0
        p1 += h * v1
        p2 += h * v2
    q[i, 0], q[i, 1], qd[i, 0], qd[i, 1] = p1, p2, v1, v2
    z[i, 0], z[i, 1] = z1, z2


@njit(cache=True, fastmath=False)
def step_trials(q, qd, stuck, slip, z, tau, sigma, T, substeps, code, fp):  # pragma: no cover
    """Compiled dispatch of one sample on ``(n, 2)`` arrays.

    Stick-slip (code 0) runs :func:`_plant_step_kernel` unchanged; the smooth laws
    run :func:`_smooth_step_kernel` and LuGre :func:`_lugre_one` (bristle state ``z``);
    both leave ``stuck`` False, ``slip`` unchanged. ``fp (N_FRICTION_PARAMS,)``.
    """
    if code == 0:
        _plant_step_kernel(q, qd, stuck, slip, tau, sigma, T, substeps)
        return
    if code == 3:
        for i in range(q.shape[0]):
            _lugre_one(q, qd, z, i, tau[i, 0], tau[i, 1], sigma[i], T, substeps, fp)
    else:
        _smooth_step_kernel(q, qd, tau, sigma, T, substeps, code, fp[0], fp[1], fp[2])
    stuck[:, :] = False


@njit(cache=True, fastmath=False)
def step_one(q, qd, stuck, slip, z, i, tau, sg, T, substeps, code, fp):  # pragma: no cover
    """Trial i of ``(n, 2)`` state arrays by one sample under ``tau (2,)`` with ``sg (7,)``
    (what the compiled closed loop calls; the same arithmetic as :func:`step_trials`)."""
    if code == 0:
        _stick_slip_one(q, qd, stuck, slip, i, tau[0], tau[1], sg, T, substeps)
        return
    if code == 3:
        _lugre_one(q, qd, z, i, tau[0], tau[1], sg, T, substeps, fp)
    else:
        _smooth_one(q, qd, i, tau[0], tau[1], sg, T, substeps, code, fp[0], fp[1], fp[2])
    stuck[i, 0] = False
    stuck[i, 1] = False


def friction_vector(friction_params) -> Array:
    """``friction_params`` (3 or :data:`N_FRICTION_PARAMS` values) as the kernels' float vector.

    Three values are the smooth laws' ``(friction_velocity, stribeck_ratio, stribeck_velocity)``;
    the LuGre stiffness and damping then default to 0 (only LuGre reads them).
    """
    fp = np.zeros(N_FRICTION_PARAMS)
    vals = np.asarray(friction_params, dtype=float).ravel()
    if vals.size not in (3, N_FRICTION_PARAMS) or not np.all(np.isfinite(vals)):
        raise ParameterError(
            f"friction_params must be 3 or {N_FRICTION_PARAMS} finite values, got {friction_params!r}"
        )
    fp[: vals.size] = vals
    return fp


def step_kernel(
    q, qd, stuck, slip, tau, sigma, T, substeps, friction_code=0, friction_params=(0.02, 1.5, 0.1), z=None
):
    """Advance contiguous ``(n, 2)`` state arrays in place by one sample (no checks).

    ``z (n, 2)``: the LuGre bristle state (required with ``friction_code`` 3, else unused).
    """
    if z is None:
        if friction_code == 3:
            raise ParameterError("the LuGre plant (friction_code 3) needs its bristle state z")
        z = np.zeros((q.shape[0], 2))
    fp = friction_vector(friction_params)
    step_trials(q, qd, stuck, slip, z, tau, sigma, float(T), int(substeps), int(friction_code), fp)


def two_link_plant_step(
    q: Array,
    qd: Array,
    stuck: NDArray[np.bool_],
    slip: Array,
    tau: Array,
    sigma: Array,
    T: float,
    substeps: int = 2,
    friction_code: int = 0,
    friction_params: tuple[float, float, float] = (0.02, 1.5, 0.1),
) -> tuple[Array, Array, NDArray[np.bool_], Array]:
    """Advance the arm by one sample with torque ``tau`` held constant (pure function).

    Compiled with numba: one loop over the batch, scalar 2x2 algebra inside.

    Parameters
    ----------
    q, qd : ndarray, shape (..., 2)
        State at the start of the sample.
    stuck : ndarray of bool, shape (..., 2)
        Joints currently stuck by Coulomb friction.
    slip : ndarray, shape (..., 2)
        Direction (+-1) a joint last broke away in; used as sgn(qd) while qd == 0.
    tau : ndarray, shape (..., 2)
        Applied torque [N m], held over the sample.
    sigma : ndarray, shape (..., 7)
        True base parameters.
    T : float
        Sample period [s].
    substeps : int
        RK4 steps per sample.
    friction_code : int
        Plant friction law, :data:`FRICTION_CODES`: 0 stick-slip, 1 tanh, 2 stribeck
        (LuGre carries a bristle state: :func:`lugre_step`).
    friction_params : (float, float, float)
        ``(friction_velocity, stribeck_ratio, stribeck_velocity)`` of the smooth laws.

    Returns
    -------
    q, qd, stuck, slip : the state after ``T`` (new arrays; inputs are not changed).
    """
    shape = np.broadcast_shapes(q.shape, qd.shape, tau.shape, (*sigma.shape[:-1], 2))
    flat = (-1, 2)
    q_ = np.ascontiguousarray(np.broadcast_to(q, shape), dtype=float).reshape(flat).copy()
    qd_ = np.ascontiguousarray(np.broadcast_to(qd, shape), dtype=float).reshape(flat).copy()
    st_ = np.ascontiguousarray(np.broadcast_to(stuck, shape), dtype=np.bool_).reshape(flat).copy()
    sl_ = np.ascontiguousarray(np.broadcast_to(slip, shape), dtype=float).reshape(flat).copy()
    tau_ = np.array(np.broadcast_to(tau, shape), dtype=float, order="C").reshape(flat)  # writable: one type
    sig_ = np.array(np.broadcast_to(sigma, (*shape[:-1], 7)), dtype=float, order="C").reshape(-1, 7)
    if friction_code not in FRICTION_CODES.values():
        raise ParameterError(f"friction_code must be one of {FRICTION_CODES}, got {friction_code!r}")
    if friction_code == FRICTION_CODES["lugre"]:
        raise ParameterError("plant_step has no bristle state: step a LuGre plant with lugre_step")
    step_kernel(q_, qd_, st_, sl_, tau_, sig_, float(T), int(substeps), friction_code, friction_params)
    return q_.reshape(shape), qd_.reshape(shape), st_.reshape(shape), sl_.reshape(shape)


def lugre_step(
    q: Array,
    qd: Array,
    z: Array,
    tau: Array,
    sigma: Array,
    T: float,
    friction_params,
    substeps: int = 2,
) -> tuple[Array, Array, Array]:
    """Advance an arm with LuGre friction by one sample under a held torque (pure function).

    Parameters
    ----------
    q, qd : ndarray, shape (..., 2)
        State at the start of the sample [rad], [rad/s].
    z : ndarray, shape (..., 2)
        Bristle deflection per joint [rad] (0: relaxed).
    tau : ndarray, shape (..., 2)
        Applied torque [N m], held over the sample.
    sigma : ndarray, shape (..., 7)
        True base parameters (``b_i`` the viscous term sigma2, ``d_i`` the Coulomb level Fc).
    T : float
        Sample period [s].
    friction_params : sequence of 7 floats
        :attr:`adaptive_dd.plant.two_link.TwoLinkArm.friction_params` (``stribeck_ratio``,
        ``stribeck_velocity``, ``sigma0`` and ``sigma1`` per joint are read).
    substeps : int
        Lower bound on the micro-steps (at least ``T / LUGRE_DT_MAX`` are taken).

    Returns
    -------
    q, qd, z : the state after ``T`` (new arrays).
    """
    fp = friction_vector(friction_params)
    shape = np.broadcast_shapes(q.shape, qd.shape, z.shape, tau.shape, (*sigma.shape[:-1], 2))
    flat = (-1, 2)
    q_, qd_, z_ = (
        np.ascontiguousarray(np.broadcast_to(x, shape), dtype=float).reshape(flat).copy() for x in (q, qd, z)
    )
    tau_ = np.array(np.broadcast_to(tau, shape), dtype=float, order="C").reshape(flat)  # writable: one type
    sig_ = np.array(np.broadcast_to(sigma, (*shape[:-1], 7)), dtype=float, order="C").reshape(-1, 7)
    stuck = np.zeros(q_.shape, dtype=np.bool_)
    slip = np.ones(q_.shape)
    step_trials(q_, qd_, stuck, slip, z_, tau_, sig_, float(T), int(substeps), 3, fp)
    return q_.reshape(shape), qd_.reshape(shape), z_.reshape(shape)
