"""Compiled regressors of a serial chain: torques linear in the standard link parameters.

The regressors write each body force (:func:`~adaptive_dd.plant.chain_dynamics.rnea`'s, or the
Slotine-Li one of :func:`~adaptive_dd.plant.chain_dynamics.rnea_ref`) in its own joint frame,
where it is linear in that link's ``pi`` (10 per link, :func:`~adaptive_dd.plant.chain.standard_parameters`),
and project it on the joint axes of the links before it: :func:`regressor` and
:func:`slotine_li_regressor` give all links' columns, ``body_*`` one link's in O(n) work, and
:func:`momentum_form` the dynamics in momentum form ``tau = d/dt p + wv`` (no acceleration).
A kernel ``*_in`` takes its scratch (``w = workspace(n)`` and a small array); the batch forms
are in :mod:`adaptive_dd.plant.chain_batch`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.plant.chain_dynamics import _body_force, _ref_motion, _torque, workspace
from adaptive_dd.plant.spatial import (
    apply_inertia,
    cross3,
    cross6,
    inertia6,
    kinematics,
    row6,
    row10,
    world_inertia,
)

__all__ = [
    "body_regressor",
    "body_regressor_in",
    "body_slotine_li_regressor",
    "body_slotine_li_regressor_in",
    "momentum_columns_in",
    "momentum_form",
    "momentum_form_in",
    "momentum_in",
    "regressor",
    "rnea_body_regressor_in",
    "slotine_li_regressor",
]


@njit(cache=True, inline="always")
def _unit10(k):  # pragma: no cover - compiled
    """The unit standard parameter ``k`` (0 .. 9) as a 10-tuple."""
    return (
        1.0 if k == 0 else 0.0, 1.0 if k == 1 else 0.0, 1.0 if k == 2 else 0.0, 1.0 if k == 3 else 0.0,
        1.0 if k == 4 else 0.0, 1.0 if k == 5 else 0.0, 1.0 if k == 6 else 0.0, 1.0 if k == 7 else 0.0,
        1.0 if k == 8 else 0.0, 1.0 if k == 9 else 0.0,
    )  # fmt: skip


@njit(cache=True)
def _local_regressor(v, vr, ar, same, a):  # pragma: no cover - compiled
    """a (6, 10): the body force of :func:`_body_force` per unit standard parameter, at the motions
    ``v, vr, ar`` (6-tuples, local frame)."""
    for k in range(10):
        f = _body_force(_unit10(k), v, vr, ar, same)
        a[0, k], a[1, k], a[2, k], a[3, k], a[4, k], a[5, k] = f


@njit(cache=True)
def _regressor_blocks(ch, q, qd, qdr, qddr, same, j0, j1, out, col0):  # pragma: no cover - compiled
    """Columns of links j0..j1-1 of the (Slotine-Li) regressor into out[:, col0 + 10 (j - j0) ...]."""
    _regressor_blocks_in(
        ch, q, qd, qdr, qddr, same, j0, j1, workspace(q.shape[0]), np.empty((6, 10)), out, col0
    )


@njit(cache=True)
def _regressor_blocks_in(ch, q, qd, qdr, qddr, same, j0, j1, w, a, out, col0):  # pragma: no cover
    """:func:`_regressor_blocks` with its scratch given: ``w = workspace(n)``, ``a (6, 10)``."""
    rw, pw, s, v, _, vr, ar = w[:7]
    kinematics(ch, q, qd, rw, pw, s, v)
    _ref_motion(ch, s, v, qdr, qddr, 1.0, vr, ar)
    _columns_from_motion(same, j0, j1, w, a, out, col0)


@njit(cache=True)
def _columns_from_motion(same, j0, j1, w, a, out, col0):  # pragma: no cover - compiled
    """The per-link part of :func:`_regressor_blocks_in`, its kinematics and reference motion
    (``vr, ar``) already in the workspace ``w``."""
    rw, pw, s, v, _, vr, ar, _, small, _ = w
    n = s.shape[0]
    sl = small[3]
    for j in range(j0, j1):
        _local_row(rw, pw, j, v, j, small[0])  # small[0 .. 2]: v, vr, ar in link j's frame
        _local_row(rw, pw, j, vr, j, small[1])
        _local_row(rw, pw, j, ar, j, small[2])
        _local_regressor(row6(small, 0), row6(small, 1), row6(small, 2), same, a)
        c0 = col0 + 10 * (j - j0)
        for i in range(n):
            if i > j:
                for k in range(10):
                    out[i, c0 + k] = 0.0
                continue
            _local_row(rw, pw, j, s, i, sl)
            for k in range(10):
                acc = 0.0
                for c in range(6):
                    acc += sl[c] * a[c, k]
                out[i, c0 + k] = acc


@njit(cache=True)
def regressor(ch, q, qd, qdd, out):  # pragma: no cover - compiled
    """Joint torque regressor Y (n, 10 n) into out, ``Y @ pi == rnea``; == pin.computeJointTorqueRegressor."""
    n = q.shape[0]
    _regressor_blocks(ch, q, qd, qd, qdd, np.bool_(True), np.int64(0), n, out, 0)


@njit(cache=True)
def slotine_li_regressor(ch, q, qd, qdr, qddr, out):  # pragma: no cover - compiled
    """Slotine-Li regressor (n, 10 n) into out, ``@ pi == rnea_ref(q, qd, qdr, qddr)``."""
    n = q.shape[0]
    _regressor_blocks(ch, q, qd, qdr, qddr, np.bool_(False), np.int64(0), n, out, 0)


@njit(cache=True)
def body_regressor(ch, j, q, qd, qdd, out):  # pragma: no cover - compiled
    """Columns of link j (0-based) of :func:`regressor`, out (n, 10), O(n) work."""
    _regressor_blocks(ch, q, qd, qd, qdd, np.bool_(True), j, j + 1, out, 0)


@njit(cache=True)
def body_slotine_li_regressor(ch, j, q, qd, qdr, qddr, out):  # pragma: no cover - compiled
    """Columns of link j (0-based) of :func:`slotine_li_regressor`, out (n, 10), O(n) work."""
    _regressor_blocks(ch, q, qd, qdr, qddr, np.bool_(False), j, j + 1, out, 0)


@njit(cache=True)
def body_regressor_in(ch, j, q, qd, qdd, w, a, out):  # pragma: no cover - compiled
    """:func:`body_regressor` with its scratch given: ``w = workspace(n)``, ``a (6, 10)`` (no allocation)."""
    _regressor_blocks_in(ch, q, qd, qd, qdd, np.bool_(True), j, j + 1, w, a, out, 0)


@njit(cache=True)
def rnea_body_regressor_in(ch, pi, j, q, qd, qdd, w, a, tau, y):  # pragma: no cover - compiled
    """:func:`rnea_in` into ``tau (n,)`` and :func:`body_regressor_in` of link ``j`` into ``y (n, 10)``
    at the same state, with the kinematics and the reference motion computed once (the same
    numbers as the two calls); scratch as :func:`body_regressor_in`."""
    kinematics(ch, q, qd, w[0], w[1], w[2], w[3])
    world_inertia(pi, w[0], w[1], w[4])
    _torque(ch, pi, q, qd, qd, qdd, 1.0, np.bool_(True), w, tau)  # leaves vr, ar at (qd, qdd) in w[5], w[6]
    _columns_from_motion(np.bool_(True), j, j + 1, w, a, y, 0)


@njit(cache=True)
def body_slotine_li_regressor_in(ch, j, q, qd, qdr, qddr, w, a, out):  # pragma: no cover - compiled
    """:func:`body_slotine_li_regressor` with its scratch given (as :func:`body_regressor_in`)."""
    _regressor_blocks_in(ch, q, qd, qdr, qddr, np.bool_(False), j, j + 1, w, a, out, 0)


@njit(cache=True)
def momentum_form(ch, pi, j, q, qd, p, wv, py, wy):  # pragma: no cover - compiled
    """The dynamics in momentum form, ``tau = d/dt p + wv``, without the acceleration.

    ``p = M(q) qd`` (generalised momentum) and ``wv = g(q) - C(q, qd)^T qd`` (Pinocchio's
    C, ``dM/dt = C + C^T``) of the links' standard parameters ``pi``, and the same two per
    unit standard parameter of link ``j`` (about its joint frame, as
    :func:`body_regressor`): ``py @ pi_j`` and ``wy @ pi_j``. Filtering both sides of
    ``tau = d/dt p + wv`` with a filter F gives ``F tau = (s F) p + F wv`` exactly, the
    regressor included: no acceleration and no equation error from evaluating the
    regressor at filtered signals.

    Parameters
    ----------
    ch : Chain
    pi : ndarray, shape (10 n,)
    j : int
        Link (0-based) whose columns go to ``py, wy``.
    q, qd : ndarray, shape (n,)
    p, wv : ndarray, shape (n,)
        Out [N m s], [N m].
    py, wy : ndarray, shape (n, 10)
        Out; rows after ``j`` are zero.
    """
    momentum_form_in(ch, pi, j, q, qd, workspace(q.shape[0]), np.empty((2, 6, 10)), p, wv, py, wy)


@njit(cache=True, inline="always")
def _cross_row(V, vb, X, xb, out):  # pragma: no cover - compiled
    """``V[vb] x X[xb]`` (:func:`~adaptive_dd.plant.spatial.cross6`) of rows read by index, into ``out``."""
    out[0], out[1], out[2], out[3], out[4], out[5] = cross6(row6(V, vb), row6(X, xb))


@njit(cache=True, inline="always")
def _local_row(R, Pw, j, X, xb, out):  # pragma: no cover - compiled
    """The world motion row ``X[xb]`` (at the world origin) in link j's frame (axes ``R[j]``, origin
    ``Pw[j]``), ``(R^T (xl + xa x p), R^T xa)``, read by index, into ``out``."""
    c0, c1, c2 = cross3(X[xb, 3], X[xb, 4], X[xb, 5], Pw[j, 0], Pw[j, 1], Pw[j, 2])
    l0, l1, l2 = X[xb, 0] + c0, X[xb, 1] + c1, X[xb, 2] + c2
    for k in range(3):
        out[k] = R[j, 0, k] * l0 + R[j, 1, k] * l1 + R[j, 2, k] * l2
        out[3 + k] = R[j, 0, k] * X[xb, 3] + R[j, 1, k] * X[xb, 4] + R[j, 2, k] * X[xb, 5]


@njit(cache=True)
def momentum_form_in(ch, pi, j, q, qd, w, a, p, wv, py, wy):  # pragma: no cover - compiled
    """:func:`momentum_form` with its scratch given: ``w = workspace(n)``, ``a (2, 6, 10)``.
    Rows of the workspace are read by index (tuples of scalars, :func:`_cross_row`,
    :func:`_local_row`), not through views."""
    # world frame: S_i fixed in link i moves as dS_i/dt = v_i x S_i; the subtree momentum
    # H_i = sum_{k>=i} I_k v_k has dH_i/dt = sum of the subtree's forces, so
    # tau_i = S_i . (dH_i/dt + I_sub a_0) = d/dt (S_i . H_i) - (v_i x S_i) . H_i + S_i . I_sub a_0,
    # a_0 = [-g; 0] the base acceleration that stands for gravity.
    momentum_in(ch, pi, q, qd, w, p, wv)
    momentum_columns_in(j, w, a, py, wy)


@njit(cache=True)
def momentum_in(ch, pi, q, qd, w, p, wv):  # pragma: no cover - compiled
    """The momentum ``p`` and ``wv`` of :func:`momentum_form_in` alone (no link's columns); it leaves
    in ``w`` what :func:`momentum_columns_in` reads."""
    rw, pw, s, v, iw, _, _, _, small, _ = w
    n = q.shape[0]
    kinematics(ch, q, qd, rw, pw, s, v)
    world_inertia(pi, rw, pw, iw)
    ag = (-ch.gravity[0], -ch.gravity[1], -ch.gravity[2], 0.0, 0.0, 0.0)
    small[0, 0], small[0, 1], small[0, 2], small[0, 3], small[0, 4], small[0, 5] = ag  # for the columns
    h0 = h1 = h2 = h3 = h4 = h5 = 0.0  # the subtree's momentum
    g0 = g1 = g2 = g3 = g4 = g5 = 0.0  # its inertia times ag
    for b in range(n - 1, -1, -1):
        y = row10(iw, b)
        t = inertia6(y, row6(v, b))
        h0, h1, h2, h3, h4, h5 = h0 + t[0], h1 + t[1], h2 + t[2], h3 + t[3], h4 + t[4], h5 + t[5]
        t = inertia6(y, ag)
        g0, g1, g2, g3, g4, g5 = g0 + t[0], g1 + t[1], g2 + t[2], g3 + t[3], g4 + t[4], g5 + t[5]
        x = cross6(row6(v, b), row6(s, b))
        s0, s1, s2, s3, s4, s5 = row6(s, b)
        pb = 0.0
        pb += s0 * h0
        pb += s1 * h1
        pb += s2 * h2
        pb += s3 * h3
        pb += s4 * h4
        pb += s5 * h5
        wb = 0.0
        wb += s0 * g0 - x[0] * h0
        wb += s1 * g1 - x[1] * h1
        wb += s2 * g2 - x[2] * h2
        wb += s3 * g3 - x[3] * h3
        wb += s4 * g4 - x[4] * h4
        wb += s5 * g5 - x[5] * h5
        p[b] = pb
        wv[b] = wb


@njit(cache=True, inline="always")
def momentum_columns_in(j, w, a, py, wy):  # pragma: no cover - compiled
    """Link j's part of :func:`momentum_form_in` (``py, wy``) from the kinematics that a call of
    :func:`momentum_form_in` at the same state left in ``w`` (the base acceleration in ``w``'s
    ``small[0]``): the same numbers as that call with link j, for another link without the
    kinematics and the momentum again."""
    rw, pw, s, v, _, _, _, _, small, vec = w
    n = s.shape[0]
    t, sl, tl = small[3], small[4], small[5]
    # link j per unit parameter, in its own frame: I v_j and I a_0 as (6, 10) maps
    y = vec[:10]
    _local_row(rw, pw, j, v, j, sl)
    _local_row(rw, pw, j, small, 0, tl)  # ag
    for k in range(10):
        y[k] = 0.0
    for k in range(10):
        y[k] = 1.0
        apply_inertia(y, sl, t)
        for c in range(6):
            a[0, c, k] = t[c]
        apply_inertia(y, tl, t)
        for c in range(6):
            a[1, c, k] = t[c]
        y[k] = 0.0
    for i in range(n):
        if i > j:
            for k in range(10):
                py[i, k] = 0.0
                wy[i, k] = 0.0
            continue
        _local_row(rw, pw, j, s, i, sl)
        _cross_row(v, i, s, i, t)
        _local_row(rw, pw, j, small, 3, tl)  # small[3]: t
        for k in range(10):
            acc_p = 0.0
            acc_w = 0.0
            for c in range(6):
                acc_p += sl[c] * a[0, c, k]
                acc_w += sl[c] * a[1, c, k] - tl[c] * a[0, c, k]
            py[i, k] = acc_p
            wy[i, k] = acc_w
