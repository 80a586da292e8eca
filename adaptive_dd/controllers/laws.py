"""Compiled control laws: one trial's torque from its measured state and the reference.

These are the only implementations of the laws: the controller classes call the batched
wrappers (:func:`ct_batch`, :func:`pd_batch`, :func:`boost_batch`) and the compiled closed
loop (:mod:`adaptive_dd.benchmark.compiled`) calls the per-trial functions, so both paths
compute the same numbers to the last bit.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.plant.sampling import limit_crossings, project_trial

__all__ = [
    "boost_batch",
    "boost_trial",
    "boost_within_trial",
    "ct_batch",
    "ct_trial",
    "pd_batch",
    "pd_trial",
    "slotine_li_batch",
    "slotine_li_trial",
]


@njit(cache=True)
def ct_trial(q, qd, q_d, qd_d, qdd_d, sg, kp, kd, lam, out):  # pragma: no cover - compiled
    """Computed torque of eq. (3)-(6) for one trial into ``out (2,)``.

    ``tau = M(q) (qdd_d + kd e' + kp e) + C(q, qd) w + B w + D sgn(w)``, ``e = q_d - q``;
    ``w = qd_d + lam e`` (reference velocity) when ``lam >= 0``, else the textbook law:
    ``C(q, qd) qd + B qd + D sgn(qd_d)``.
    """
    e1, e2 = q_d[0] - q[0], q_d[1] - q[1]
    v1 = qdd_d[0] + kd * (qd_d[0] - qd[0]) + kp * e1
    v2 = qdd_d[1] + kd * (qd_d[1] - qd[1]) + kp * e2
    c2, s2 = np.cos(q[1]), np.sin(q[1])
    j1, j2, r = sg[0], sg[1], sg[2]
    rc = r * c2
    m11, m12, m22 = j1 + j2 + 2.0 * rc, j2 + rc, j2
    rs = r * s2
    if lam >= 0.0:
        w1, w2 = qd_d[0] + lam * e1, qd_d[1] + lam * e2
        s1, s2_ = np.sign(w1), np.sign(w2)
    else:
        w1, w2 = qd[0], qd[1]
        s1, s2_ = np.sign(qd_d[0]), np.sign(qd_d[1])
    cor1 = -rs * (qd[1] * w1 + (qd[0] + qd[1]) * w2)
    cor2 = rs * qd[0] * w1
    out[0] = m11 * v1 + m12 * v2 + cor1 + sg[3] * w1 + sg[5] * s1
    out[1] = m12 * v1 + m22 * v2 + cor2 + sg[4] * w2 + sg[6] * s2_


@njit(cache=True)
def pd_trial(q, qd, q_d, qd_d, kp, kd, out):  # pragma: no cover - compiled
    """``tau = kp e + kd e'`` with per-joint gains ``kp, kd (2,)``."""
    for j in range(2):
        out[j] = kp[j] * (q_d[j] - q[j]) + kd[j] * (qd_d[j] - qd[j])


@njit(cache=True)
def boost_trial(q, qd, q_d, qd_d, sg0, dkp, dkd, out):  # pragma: no cover - compiled
    """Add ``M0(q) [dkp e + dkd e']`` to ``out (2,)`` (feedback raised through the nominal inertia)."""
    v1 = dkp * (q_d[0] - q[0]) + dkd * (qd_d[0] - qd[0])
    v2 = dkp * (q_d[1] - q[1]) + dkd * (qd_d[1] - qd[1])
    rc = sg0[2] * np.cos(q[1])
    m11, m12, m22 = sg0[0] + sg0[1] + 2.0 * rc, sg0[1] + rc, sg0[1]
    out[0] += m11 * v1 + m12 * v2
    out[1] += m12 * v1 + m22 * v2


@njit(cache=True)
def boost_within_trial(q, qd, q_d, qd_d, sg0, dkp, dkd, kp, kd, lim, out):  # pragma: no cover
    """Add the boost of :func:`boost_trial` at the largest bandwidth that keeps ``out (2,)`` within
    the torque limits ``lim (2,)`` [N m] (a command already beyond its limit: not further).

    The boost raises the law's bandwidth ``w`` (``kp = w^2``, ``kd = 2 zeta w``) by ``x`` in
    ``[0, X]`` (``X`` gives ``dkp, dkd``): it adds ``M0(q) [((w + x)^2 - w^2) e + 2 zeta x e']``
    = ``x^2 M0 e + x M0 (2 w e + 2 zeta e')``, and ``x`` is the largest whose command is within
    the limits (0 always is). The error keeps a double pole at ``-(w + x)`` (damping ``zeta``)
    whatever the room: a boost scaled as a whole (``alpha (dkp, dkd)``) lowers the damping, and a
    clipped command loses it, and either drives a saturated arm past its reference.
    """
    w = np.sqrt(kp)
    z = 0.5 * kd / w
    x_max = 0.5 * dkd / z
    e1, e2 = q_d[0] - q[0], q_d[1] - q[1]
    p1, p2 = 2.0 * (w * e1 + z * (qd_d[0] - qd[0])), 2.0 * (w * e2 + z * (qd_d[1] - qd[1]))
    rc = sg0[2] * np.cos(q[1])
    m11, m12, m22 = sg0[0] + sg0[1] + 2.0 * rc, sg0[1] + rc, sg0[1]
    a = (m11 * e1 + m12 * e2, m12 * e1 + m22 * e2)
    b = (m11 * p1 + m12 * p2, m12 * p1 + m22 * p2)
    hi, lo = np.empty(2), np.empty(2)
    for j in range(2):  # up to its limit, or a command already beyond it not further
        room = max(lim[j], abs(out[j])) if np.isfinite(lim[j]) else np.inf
        hi[j], lo[j] = room - out[j], -room - out[j]
    xs = np.empty(9)
    xs[0] = x_max
    n = 1
    for j in range(2):
        if np.isfinite(hi[j]):
            n = limit_crossings(a[j], b[j], hi[j], x_max, xs, n)
            n = limit_crossings(a[j], b[j], lo[j], x_max, xs, n)
    best = 0.0
    for k in range(n):  # the largest candidate (x_max or a crossing) within both limits
        x = xs[k]
        if x <= best:
            continue
        ok = True
        for j in range(2):
            f = a[j] * x * x + b[j] * x
            tol = 1e-9 * (1.0 + abs(hi[j] - lo[j])) if np.isfinite(hi[j]) else 0.0
            if f > hi[j] + tol or f < lo[j] - tol:
                ok = False
        if ok:
            best = x
    if best >= x_max:
        boost_trial(q, qd, q_d, qd_d, sg0, dkp, dkd, out)
        return
    for j in range(2):
        out[j] += a[j] * best * best + b[j] * best


@njit(cache=True)
def slotine_li_trial(
    q, qd, q_d, qd_d, qdd_d, theta, sg0, lam, kd, T, gamma, lo, hi, pj, out
):  # pragma: no cover
    """Slotine-Li (see :mod:`~adaptive_dd.controllers.slotine_li`) for one trial.

    ``tau = Y(q, qd, qd_r, qdd_r) theta + kd M0(q) s`` into ``out``; then, if ``gamma`` is not
    empty, ``theta += T Gamma Y^T s`` (a non-finite step is dropped), clipped to ``[lo, hi]``
    and projected (``pj = (j_min, margin, r_min)``), in place.
    """
    e1, e2 = q_d[0] - q[0], q_d[1] - q[1]
    ed1, ed2 = qd_d[0] - qd[0], qd_d[1] - qd[1]
    s1, s2 = ed1 + lam * e1, ed2 + lam * e2
    v1, v2 = qd_d[0] + lam * e1, qd_d[1] + lam * e2
    a1, a2 = qdd_d[0] + lam * ed1, qdd_d[1] + lam * ed2
    c2, sn2 = np.cos(q[1]), np.sin(q[1])
    y = np.zeros((2, 7))
    y[0, 0] = a1
    y[0, 1] = a1 + a2
    y[1, 1] = a1 + a2
    y[0, 2] = c2 * (2.0 * a1 + a2) - sn2 * (qd[1] * v1 + (qd[0] + qd[1]) * v2)
    y[1, 2] = c2 * a1 + sn2 * qd[0] * v1
    y[0, 3] = v1
    y[1, 4] = v2
    y[0, 5] = np.sign(v1)
    y[1, 6] = np.sign(v2)
    rc = sg0[2] * c2
    m11, m12, m22 = sg0[0] + sg0[1] + 2.0 * rc, sg0[1] + rc, sg0[1]
    for r in range(2):
        acc = 0.0
        for j in range(7):
            acc += y[r, j] * theta[j]
        out[r] = acc
    out[0] += kd * (m11 * s1 + m12 * s2)
    out[1] += kd * (m12 * s1 + m22 * s2)
    if gamma.shape[0] == 0:
        return
    for j in range(7):
        upd = T * gamma[j] * (y[0, j] * s1 + y[1, j] * s2)
        th = theta[j] + (upd if np.isfinite(upd) else 0.0)
        theta[j] = min(max(th, lo[j]), hi[j])
    project_trial(theta, theta, pj[0], pj[1], pj[2])


@njit(cache=True)
def _slotine_loop(
    q, qd, q_d, qd_d, qdd_d, theta, sg0, lam, kd, T, gamma, lo, hi, pj, out
):  # pragma: no cover
    for i in range(q.shape[0]):
        slotine_li_trial(
            q[i], qd[i], q_d[i], qd_d[i], qdd_d[i], theta[i], sg0, lam, kd, T, gamma, lo, hi, pj, out[i]
        )


def slotine_li_batch(q, qd, q_d, qd_d, qdd_d, theta, sg0, lam, kd, T, gamma, lo, hi, pj):
    """:func:`slotine_li_trial` over a batch ``(n, 2)``; ``theta (n, 7)`` updated in place."""
    shape, (a, b, c, d, e) = _flat(q, qd, q_d, qd_d, qdd_d)
    out = np.empty((a.shape[0], 2))
    sg0 = np.array(sg0, dtype=float)  # writable: one compiled type whatever the caller holds
    _slotine_loop(a, b, c, d, e, theta, sg0, float(lam), float(kd), float(T), gamma, lo, hi, pj, out)
    return out.reshape(*shape, 2)


@njit(cache=True)
def _ct_loop(q, qd, q_d, qd_d, qdd_d, sg, kp, kd, lam, out):  # pragma: no cover - compiled
    for i in range(q.shape[0]):
        ct_trial(q[i], qd[i], q_d[i], qd_d[i], qdd_d[i], sg[i], kp, kd, lam, out[i])


@njit(cache=True)
def _pd_loop(q, qd, q_d, qd_d, kp, kd, out):  # pragma: no cover - compiled
    for i in range(q.shape[0]):
        pd_trial(q[i], qd[i], q_d[i], qd_d[i], kp, kd, out[i])


@njit(cache=True)
def _boost_loop(q, qd, q_d, qd_d, sg0, dkp, dkd, kp, kd, lim, on, out):  # pragma: no cover - compiled
    for i in range(q.shape[0]):
        if on[i]:
            boost_within_trial(q[i], qd[i], q_d[i], qd_d[i], sg0, dkp, dkd, kp, kd, lim, out[i])


def _flat(*arrays, width=(2, 2, 2, 2, 2, 7)):
    """Broadcast ``(..., width)`` arrays to one batch shape; return it and C-contiguous (n, width) copies."""
    shape = np.broadcast_shapes(*(np.shape(a)[:-1] for a in arrays))
    flat = [  # copies, writable whether or not a broadcast copied: one compiled type per kernel
        np.array(np.broadcast_to(np.asarray(a, dtype=float), (*shape, w)).reshape(-1, w), order="C")
        for a, w in zip(arrays, width, strict=False)
    ]
    return shape, flat


def ct_batch(q, qd, q_d, qd_d, qdd_d, sigma, kp: float, kd: float, lam: float | None):
    """:func:`ct_trial` over broadcast batch axes; returns ``(..., 2)``."""
    shape, (a, b, c, d, e, s) = _flat(q, qd, q_d, qd_d, qdd_d, sigma)
    out = np.empty((a.shape[0], 2))
    _ct_loop(a, b, c, d, e, s, float(kp), float(kd), -1.0 if lam is None else float(lam), out)
    return out.reshape(*shape, 2)


def pd_batch(q, qd, q_d, qd_d, kp, kd):
    """:func:`pd_trial` over broadcast batch axes; returns ``(..., 2)``."""
    shape, (a, b, c, d) = _flat(q, qd, q_d, qd_d)
    out = np.empty((a.shape[0], 2))
    _pd_loop(a, b, c, d, np.asarray(kp, dtype=float), np.asarray(kd, dtype=float), out)
    return out.reshape(*shape, 2)


def boost_batch(tau, q, qd, q_d, qd_d, sigma0, dkp: float, dkd: float, on, kp=1.0, kd=2.0, lim=None):
    """``tau`` plus :func:`boost_within_trial` where ``on (n,)``; ``tau``, ``q`` and the other arrays
    ``(n, 2)``; ``kp, kd`` the law's gains, ``lim (2,)`` the torque limits (None: none, the whole boost)."""
    shape, (a, b, c, d, t) = _flat(q, qd, q_d, qd_d, tau)
    out = t.copy()
    on = np.array(np.broadcast_to(np.asarray(on, dtype=np.bool_), (a.shape[0],)), order="C")
    lim = np.full(2, np.inf) if lim is None else np.asarray(lim, dtype=float)
    sg0 = np.array(sigma0, dtype=float)  # a copy: writable even when the arm's sigma is not
    _boost_loop(a, b, c, d, sg0, float(dkp), float(dkd), float(kp), float(kd), lim, on, out)
    return out.reshape(*shape, 2)
