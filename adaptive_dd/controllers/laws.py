"""Compiled control laws: one trial's torque from its measured state and the reference.

These are the only implementations of the laws: the controller classes call the batched
wrappers (:func:`ct_batch`, :func:`pd_batch`, :func:`boost_batch`) and the compiled closed
loop (:mod:`adaptive_dd.benchmark.compiled`) calls the per-trial functions, so both paths
compute the same numbers to the last bit.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.plant.sampling import project_trial

__all__ = [
    "boost_batch",
    "boost_trial",
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
def _boost_loop(q, qd, q_d, qd_d, sg0, dkp, dkd, on, out):  # pragma: no cover - compiled
    for i in range(q.shape[0]):
        if on[i]:
            boost_trial(q[i], qd[i], q_d[i], qd_d[i], sg0, dkp, dkd, out[i])


def _flat(*arrays, width=(2, 2, 2, 2, 2, 7)):
    """Broadcast ``(..., width)`` arrays to one batch shape; return it and C-contiguous (n, width) copies."""
    shape = np.broadcast_shapes(*(np.shape(a)[:-1] for a in arrays))
    flat = [
        np.ascontiguousarray(np.broadcast_to(np.asarray(a, dtype=float), (*shape, w)).reshape(-1, w))
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


def boost_batch(tau, q, qd, q_d, qd_d, sigma0, dkp: float, dkd: float, on):
    """``tau`` plus :func:`boost_trial` where ``on (n,)``; ``tau``, ``q`` and the other arrays ``(n, 2)``."""
    shape, (a, b, c, d, t) = _flat(q, qd, q_d, qd_d, tau)
    out = t.copy()
    on = np.ascontiguousarray(np.broadcast_to(np.asarray(on, dtype=np.bool_), (a.shape[0],)))
    _boost_loop(a, b, c, d, np.asarray(sigma0, dtype=float), float(dkp), float(dkd), on, out)
    return out.reshape(*shape, 2)
