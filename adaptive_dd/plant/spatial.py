"""Compiled spatial-algebra helpers of :mod:`adaptive_dd.plant.chain`.

Spatial vectors are ``[linear; angular]`` (Pinocchio's order), expressed in the
world frame at the world origin unless said otherwise. A link inertia is held as
10 numbers ``(m, h, Ixx, Ixy, Iyy, Ixz, Iyz, Izz)``: mass, first moment ``h = m c``
and rotational inertia about the frame's origin (Pinocchio's dynamic-parameter
order), so that composite inertias add entry by entry.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = [
    "add_cross6",
    "apply_inertia",
    "cross3",
    "cross6",
    "inertia6",
    "kinematics",
    "row6",
    "row10",
    "world_inertia",
]


@njit(cache=True, inline="always")
def cross3(a0, a1, a2, b0, b1, b2):  # pragma: no cover - compiled
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@njit(cache=True, fastmath={"contract", "reassoc"}, inline="always")
def kinematics(ch, q, qd, rw, pw, s, v):  # pragma: no cover - compiled
    """World pose (rw (n,3,3), pw (n,3)), joint motion s (n,6) and body velocity v (n,6).

    ``R_i = R_{i-1} rot_i E_i``, ``E_i = exp([axis_i]x q_i)`` (revolute) or the identity
    (prismatic, which moves the origin by ``R_{i-1} rot_i axis_i q_i``). Written with
    scalar indexing only (no array views in the loop: each costs reference counting).
    """
    n = q.shape[0]
    axis, rot, trans, jtype = ch.axis, ch.rot, ch.trans, ch.jtype
    p0, p1, p2 = 0.0, 0.0, 0.0
    vl0 = vl1 = vl2 = va0 = va1 = va2 = 0.0
    for i in range(n):
        a0, a1, a2 = axis[i, 0], axis[i, 1], axis[i, 2]
        t0, t1, t2 = trans[i, 0], trans[i, 1], trans[i, 2]
        # B = R_{i-1} rot_i (into rw[i]) and the joint origin o = p_{i-1} + R_{i-1} t_i
        if i == 0:
            for r in range(3):
                for c in range(3):
                    rw[0, r, c] = rot[0, r, c]
            o0, o1, o2 = t0, t1, t2
        else:
            k = i - 1
            for r in range(3):
                for c in range(3):
                    rw[i, r, c] = (
                        rw[k, r, 0] * rot[i, 0, c] + rw[k, r, 1] * rot[i, 1, c] + rw[k, r, 2] * rot[i, 2, c]
                    )
            o0 = p0 + rw[k, 0, 0] * t0 + rw[k, 0, 1] * t1 + rw[k, 0, 2] * t2
            o1 = p1 + rw[k, 1, 0] * t0 + rw[k, 1, 1] * t1 + rw[k, 1, 2] * t2
            o2 = p2 + rw[k, 2, 0] * t0 + rw[k, 2, 1] * t1 + rw[k, 2, 2] * t2
        # world axis B a (unchanged by the joint's own motion)
        w0 = rw[i, 0, 0] * a0 + rw[i, 0, 1] * a1 + rw[i, 0, 2] * a2
        w1 = rw[i, 1, 0] * a0 + rw[i, 1, 1] * a1 + rw[i, 1, 2] * a2
        w2 = rw[i, 2, 0] * a0 + rw[i, 2, 1] * a1 + rw[i, 2, 2] * a2
        if jtype[i] == 0:
            cq, sq = np.cos(q[i]), np.sin(q[i])
            kc = 1.0 - cq
            e00, e01, e02 = cq + kc * a0 * a0, kc * a0 * a1 - sq * a2, kc * a0 * a2 + sq * a1
            e10, e11, e12 = kc * a1 * a0 + sq * a2, cq + kc * a1 * a1, kc * a1 * a2 - sq * a0
            e20, e21, e22 = kc * a2 * a0 - sq * a1, kc * a2 * a1 + sq * a0, cq + kc * a2 * a2
            for r in range(3):
                b0, b1, b2 = rw[i, r, 0], rw[i, r, 1], rw[i, r, 2]
                rw[i, r, 0] = b0 * e00 + b1 * e10 + b2 * e20
                rw[i, r, 1] = b0 * e01 + b1 * e11 + b2 * e21
                rw[i, r, 2] = b0 * e02 + b1 * e12 + b2 * e22
            p0, p1, p2 = o0, o1, o2
            l0, l1, l2 = cross3(p0, p1, p2, w0, w1, w2)
            s[i, 0], s[i, 1], s[i, 2], s[i, 3], s[i, 4], s[i, 5] = l0, l1, l2, w0, w1, w2
        else:
            p0, p1, p2 = o0 + w0 * q[i], o1 + w1 * q[i], o2 + w2 * q[i]
            s[i, 0], s[i, 1], s[i, 2], s[i, 3], s[i, 4], s[i, 5] = w0, w1, w2, 0.0, 0.0, 0.0
        pw[i, 0], pw[i, 1], pw[i, 2] = p0, p1, p2
        u = qd[i]
        vl0 += s[i, 0] * u
        vl1 += s[i, 1] * u
        vl2 += s[i, 2] * u
        va0 += s[i, 3] * u
        va1 += s[i, 4] * u
        va2 += s[i, 5] * u
        v[i, 0], v[i, 1], v[i, 2], v[i, 3], v[i, 4], v[i, 5] = vl0, vl1, vl2, va0, va1, va2


@njit(cache=True, fastmath={"contract", "reassoc"}, inline="always")
def world_inertia(pi, rw, pw, iw):  # pragma: no cover - compiled
    """Each link's inertia about the world origin in world axes, iw (n, 10), Pinocchio's order."""
    n = rw.shape[0]
    for j in range(n):
        b = 10 * j
        m = pi[b]
        r = rw[j]
        h0 = r[0, 0] * pi[b + 1] + r[0, 1] * pi[b + 2] + r[0, 2] * pi[b + 3]
        h1 = r[1, 0] * pi[b + 1] + r[1, 1] * pi[b + 2] + r[1, 2] * pi[b + 3]
        h2 = r[2, 0] * pi[b + 1] + r[2, 1] * pi[b + 2] + r[2, 2] * pi[b + 3]
        ixx, ixy, iyy, ixz, iyz, izz = pi[b + 4], pi[b + 5], pi[b + 6], pi[b + 7], pi[b + 8], pi[b + 9]
        # R I R^T (symmetric): first T = R I
        t00 = r[0, 0] * ixx + r[0, 1] * ixy + r[0, 2] * ixz
        t01 = r[0, 0] * ixy + r[0, 1] * iyy + r[0, 2] * iyz
        t02 = r[0, 0] * ixz + r[0, 1] * iyz + r[0, 2] * izz
        t10 = r[1, 0] * ixx + r[1, 1] * ixy + r[1, 2] * ixz
        t11 = r[1, 0] * ixy + r[1, 1] * iyy + r[1, 2] * iyz
        t12 = r[1, 0] * ixz + r[1, 1] * iyz + r[1, 2] * izz
        t20 = r[2, 0] * ixx + r[2, 1] * ixy + r[2, 2] * ixz
        t21 = r[2, 0] * ixy + r[2, 1] * iyy + r[2, 2] * iyz
        t22 = r[2, 0] * ixz + r[2, 1] * iyz + r[2, 2] * izz
        jxx = t00 * r[0, 0] + t01 * r[0, 1] + t02 * r[0, 2]
        jxy = t00 * r[1, 0] + t01 * r[1, 1] + t02 * r[1, 2]
        jyy = t10 * r[1, 0] + t11 * r[1, 1] + t12 * r[1, 2]
        jxz = t00 * r[2, 0] + t01 * r[2, 1] + t02 * r[2, 2]
        jyz = t10 * r[2, 0] + t11 * r[2, 1] + t12 * r[2, 2]
        jzz = t20 * r[2, 0] + t21 * r[2, 1] + t22 * r[2, 2]
        # shift to the world origin: I_O = I_P + m(|p|^2 1 - p p^T) + 2 (p.h) 1 - h p^T - p h^T
        p0, p1, p2 = pw[j, 0], pw[j, 1], pw[j, 2]
        pp = p0 * p0 + p1 * p1 + p2 * p2
        ph = p0 * h0 + p1 * h1 + p2 * h2
        d = m * pp + 2.0 * ph
        iw[j, 0] = m
        iw[j, 1] = h0 + m * p0
        iw[j, 2] = h1 + m * p1
        iw[j, 3] = h2 + m * p2
        iw[j, 4] = jxx + d - m * p0 * p0 - 2.0 * h0 * p0
        iw[j, 5] = jxy - m * p0 * p1 - h0 * p1 - p0 * h1
        iw[j, 6] = jyy + d - m * p1 * p1 - 2.0 * h1 * p1
        iw[j, 7] = jxz - m * p0 * p2 - h0 * p2 - p0 * h2
        iw[j, 8] = jyz - m * p1 * p2 - h1 * p2 - p1 * h2
        iw[j, 9] = jzz + d - m * p2 * p2 - 2.0 * h2 * p2


@njit(cache=True, inline="always")
def apply_inertia(y, x, out):  # pragma: no cover - compiled
    """out = I x: lin = m xl + xa x h, ang = h x xl + I xa; y = (m, h, Ixx, Ixy, Iyy, Ixz, Iyz, Izz)
    (:func:`inertia6` on arrays)."""
    t = inertia6(
        (y[0], y[1], y[2], y[3], y[4], y[5], y[6], y[7], y[8], y[9]), (x[0], x[1], x[2], x[3], x[4], x[5])
    )
    out[0], out[1], out[2], out[3], out[4], out[5] = t


# Spatial operations on tuples of scalars (a motion or force a 6-tuple, an inertia a 10-tuple): a
# kernel that reads its rows by index passes no array view, each of which costs a reference count.


@njit(cache=True, inline="always")
def row6(x, b):  # pragma: no cover - compiled
    """Row ``b`` of ``x (m, 6)`` as a 6-tuple."""
    return x[b, 0], x[b, 1], x[b, 2], x[b, 3], x[b, 4], x[b, 5]


@njit(cache=True, inline="always")
def row10(y, b):  # pragma: no cover - compiled
    """Row ``b`` of ``y (m, 10)`` (an inertia) as a 10-tuple."""
    return y[b, 0], y[b, 1], y[b, 2], y[b, 3], y[b, 4], y[b, 5], y[b, 6], y[b, 7], y[b, 8], y[b, 9]


@njit(cache=True, inline="always")
def inertia6(y, x):  # pragma: no cover - compiled
    """``I x`` of the inertia ``y`` (10-tuple) and the motion ``x`` (6-tuple): lin = m xl + xa x h,
    ang = h x xl + I xa (:func:`apply_inertia` is its array form)."""
    m, h0, h1, h2 = y[0], y[1], y[2], y[3]
    l0, l1, l2 = cross3(x[3], x[4], x[5], h0, h1, h2)
    a0, a1, a2 = cross3(h0, h1, h2, x[0], x[1], x[2])
    return (
        m * x[0] + l0,
        m * x[1] + l1,
        m * x[2] + l2,
        a0 + y[4] * x[3] + y[5] * x[4] + y[7] * x[5],
        a1 + y[5] * x[3] + y[6] * x[4] + y[8] * x[5],
        a2 + y[7] * x[3] + y[8] * x[4] + y[9] * x[5],
    )


@njit(cache=True, inline="always")
def cross6(v, x):  # pragma: no cover - compiled
    """``v x x`` of two motions (6-tuples): ``(w x xl + vl x xa, w x xa)``."""
    a0, a1, a2 = cross3(v[3], v[4], v[5], x[0], x[1], x[2])
    b0, b1, b2 = cross3(v[0], v[1], v[2], x[3], x[4], x[5])
    c0, c1, c2 = cross3(v[3], v[4], v[5], x[3], x[4], x[5])
    return a0 + b0, a1 + b1, a2 + b2, c0, c1, c2


@njit(cache=True, inline="always")
def add_cross6(out, v, f, scale):  # pragma: no cover - compiled
    """``out + scale * (v x* f)`` of 6-tuples, ``v x* f = (w x fl, w x fa + vl x fl)``."""
    a0, a1, a2 = cross3(v[3], v[4], v[5], f[0], f[1], f[2])
    b0, b1, b2 = cross3(v[3], v[4], v[5], f[3], f[4], f[5])
    c0, c1, c2 = cross3(v[0], v[1], v[2], f[0], f[1], f[2])
    return (
        out[0] + scale * a0,
        out[1] + scale * a1,
        out[2] + scale * a2,
        out[3] + scale * (b0 + c0),
        out[4] + scale * (b1 + c1),
        out[5] + scale * (b2 + c2),
    )
