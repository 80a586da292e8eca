"""Compiled inverse and forward dynamics of a serial chain, one state per call.

The kernels of :mod:`adaptive_dd.plant.chain` that give torques and the mass matrix from the
standard link parameters ``pi`` (conventions there: spatial vectors ``[linear; angular]`` in the
world frame at the world origin):

* :func:`rnea` is the recursive Newton-Euler algorithm (Featherstone, *Rigid Body
  Dynamics Algorithms*, sec. 5.3) with the base accelerating at ``-g``;
* :func:`mass_matrix` is the composite-rigid-body algorithm;
* :func:`rnea_ref` (Slotine-Li torque ``M qddr + C(q, qd) qdr + g``) uses the
  body force ``f = I ar + B(v) vr`` with ``B(v) = 1/2 (v x* I - I v x + (I v) xbar*)``,
  ``(f xbar*) m = m x* f``, the per-body factor whose composite sums Pinocchio's
  ``computeCoriolisMatrix`` uses (Echeandia & Wensing 2021): for ``vr = v`` it gives
  ``v x* I v``, and ``dM/dt - 2C`` is skew-symmetric. :func:`coriolis_matrix` is
  that recursion applied to the unit vectors;
* :func:`bias_and_mass` is the plant integrator's inner step (both in one pass, scalars);
* :func:`forward_dynamics` solves ``(M + diag(armature)) qdd = tau - rnea(q, qd, 0)``
  by Cholesky.

A kernel ``*_in`` takes its scratch ``w = workspace(n)`` (no allocation: a loop allocates it
once); the others allocate it. Each writes into ``out``; the batch forms are in
:mod:`adaptive_dd.plant.chain_batch`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.plant.spatial import (
    add_cross6,
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
    "bias_and_mass",
    "coriolis_matrix",
    "forward_dynamics",
    "mass_matrix",
    "mass_matrix_in",
    "rnea",
    "rnea_in",
    "rnea_ref",
    "rnea_ref_in",
    "workspace",
]


@njit(cache=True)
def workspace(n):  # pragma: no cover - compiled
    """Scratch arrays of one state (a tuple), cut from one allocation: pass to :func:`bias_and_mass`."""
    buf = np.empty(n * 55 + 46)
    rw = buf[: 9 * n].reshape((n, 3, 3))
    pw = buf[9 * n : 12 * n].reshape((n, 3))
    s = buf[12 * n : 18 * n].reshape((n, 6))
    v = buf[18 * n : 24 * n].reshape((n, 6))
    iw = buf[24 * n : 34 * n].reshape((n, 10))
    vr = buf[34 * n : 40 * n].reshape((n, 6))
    ar = buf[40 * n : 46 * n].reshape((n, 6))
    f = buf[46 * n : 52 * n].reshape((n, 6))
    small = buf[52 * n : 52 * n + 36].reshape((6, 6))
    vec = buf[52 * n + 36 : 55 * n + 46]
    return rw, pw, s, v, iw, vr, ar, f, small, vec


@njit(cache=True, inline="always")
def _ref_motion(ch, s, v, qdr, qddr, gscale, vr, ar):  # pragma: no cover - compiled
    """Reference velocity vr_b = sum_{k<=b} S_k qdr_k, acceleration ar_b = -g + sum_{k<=b} dS_k,
    rows read and written by index (no array view: each costs a reference count)."""
    # dS_k = S_k qddr_k + (v_k x S_k) qdr_k
    n = s.shape[0]
    for c in range(6):
        vr[0, c] = 0.0
        ar[0, c] = 0.0
    for c in range(3):
        ar[0, c] = -gscale * ch.gravity[c]
    for b in range(n):
        if b > 0:
            for c in range(6):
                vr[b, c] = vr[b - 1, c]
                ar[b, c] = ar[b - 1, c]
        x = cross6(row6(v, b), row6(s, b))
        u, ud = qdr[b], qddr[b]
        for c in range(6):
            vr[b, c] += s[b, c] * u
        ar[b, 0] += s[b, 0] * ud + x[0] * u
        ar[b, 1] += s[b, 1] * ud + x[1] * u
        ar[b, 2] += s[b, 2] * ud + x[2] * u
        ar[b, 3] += s[b, 3] * ud + x[3] * u
        ar[b, 4] += s[b, 4] * ud + x[4] * u
        ar[b, 5] += s[b, 5] * ud + x[5] * u


@njit(cache=True, inline="always")
def _body_force(y, v, vr, ar, same):  # pragma: no cover - compiled
    """The body force of the inertia ``y`` (10-tuple) at the motions ``v, vr, ar`` (6-tuples), as a
    6-tuple: ``I ar + 1/2 (v x* I vr - I (v x vr) + vr x* I v)``; with same (vr = v): ``I ar + v
    x* I v``."""
    if same:
        return add_cross6(inertia6(y, ar), v, inertia6(y, v), 1.0)
    x = cross6(v, vr)
    t = (ar[0] - 0.5 * x[0], ar[1] - 0.5 * x[1], ar[2] - 0.5 * x[2],
         ar[3] - 0.5 * x[3], ar[4] - 0.5 * x[4], ar[5] - 0.5 * x[5])  # fmt: skip
    out = add_cross6(inertia6(y, t), v, inertia6(y, vr), 0.5)
    return add_cross6(out, vr, inertia6(y, v), 0.5)


@njit(cache=True, inline="always")
def _torque(ch, pi, q, qd, qdr, qddr, gscale, same, w, out):  # pragma: no cover - compiled
    """out = M qddr + C(q, qd) qdr + gscale * g(q) (same: qdr is qd)."""
    s, v, iw, vr, ar, f = w[2], w[3], w[4], w[5], w[6], w[7]
    n = q.shape[0]
    _ref_motion(ch, s, v, qdr, qddr, gscale, vr, ar)
    for b in range(n):
        fb = _body_force(row10(iw, b), row6(v, b), row6(vr, b), row6(ar, b), same)
        f[b, 0], f[b, 1], f[b, 2], f[b, 3], f[b, 4], f[b, 5] = fb
    h0 = h1 = h2 = h3 = h4 = h5 = 0.0
    for b in range(n - 1, -1, -1):
        h0 += f[b, 0]
        h1 += f[b, 1]
        h2 += f[b, 2]
        h3 += f[b, 3]
        h4 += f[b, 4]
        h5 += f[b, 5]
        acc = 0.0
        acc += s[b, 0] * h0
        acc += s[b, 1] * h1
        acc += s[b, 2] * h2
        acc += s[b, 3] * h3
        acc += s[b, 4] * h4
        acc += s[b, 5] * h5
        out[b] = acc


@njit(cache=True)
def rnea(ch, pi, q, qd, qdd, out):  # pragma: no cover - compiled
    """Inverse dynamics ``M(q) qdd + C(q, qd) qd + g(q)`` into out (n,) [N m or N]; == ``pin.rnea``.

    Parameters
    ----------
    ch : Chain
    pi : ndarray, shape (10 n,)
        Standard link parameters (:func:`standard_parameters`).
    q, qd, qdd : ndarray, shape (n,)
        Joint positions [rad or m], velocities, accelerations.
    out : ndarray, shape (n,)
    """
    rnea_in(ch, pi, q, qd, qdd, workspace(q.shape[0]), out)


@njit(cache=True)
def rnea_in(ch, pi, q, qd, qdd, w, out):  # pragma: no cover - compiled
    """:func:`rnea` with its scratch ``w = workspace(n)`` given (no allocation: a loop allocates it once)."""
    kinematics(ch, q, qd, w[0], w[1], w[2], w[3])
    world_inertia(pi, w[0], w[1], w[4])
    _torque(ch, pi, q, qd, qd, qdd, 1.0, np.bool_(True), w, out)


@njit(cache=True)
def rnea_ref(ch, pi, q, qd, qdr, qddr, out):  # pragma: no cover - compiled
    """Slotine-Li torque ``M(q) qddr + C(q, qd) qdr + g(q)`` into out (n,), with Pinocchio's C.

    ``rnea_ref(q, qd, qd, qdd) == rnea(q, qd, qdd)``; shapes as :func:`rnea`.
    """
    rnea_ref_in(ch, pi, q, qd, qdr, qddr, workspace(q.shape[0]), out)


@njit(cache=True)
def rnea_ref_in(ch, pi, q, qd, qdr, qddr, w, out):  # pragma: no cover - compiled
    """:func:`rnea_ref` with its scratch ``w = workspace(n)`` given (no allocation)."""
    kinematics(ch, q, qd, w[0], w[1], w[2], w[3])
    world_inertia(pi, w[0], w[1], w[4])
    _torque(ch, pi, q, qd, qdr, qddr, 1.0, np.bool_(False), w, out)


@njit(cache=True)
def coriolis_matrix(ch, pi, q, qd, out):  # pragma: no cover - compiled
    """Coriolis matrix C(q, qd) into out (n, n); == ``pin.computeCoriolisMatrix`` (dM/dt - 2C skew)."""
    n = q.shape[0]
    w = workspace(n)
    kinematics(ch, q, qd, w[0], w[1], w[2], w[3])
    world_inertia(pi, w[0], w[1], w[4])
    e = np.zeros(n)
    zero = np.zeros(n)
    col = np.empty(n)
    for k in range(n):
        e[k] = 1.0
        _torque(ch, pi, q, qd, e, zero, 0.0, np.bool_(False), w, col)
        for i in range(n):
            out[i, k] = col[i]
        e[k] = 0.0


@njit(cache=True)
def _composite_mass(s, iw, out, yc, t):  # pragma: no cover - compiled
    """Composite-rigid-body algorithm in world frame: M[i, j] = S_i . (Ic_j S_j), i <= j."""
    n = s.shape[0]
    for c in range(10):
        yc[c] = 0.0
    for j in range(n - 1, -1, -1):
        for c in range(10):
            yc[c] += iw[j, c]
        apply_inertia(yc, s[j], t)
        for i in range(j + 1):
            acc = 0.0
            for c in range(6):
                acc += s[i, c] * t[c]
            out[i, j] = acc
            out[j, i] = acc


@njit(cache=True)
def mass_matrix(ch, pi, q, out):  # pragma: no cover - compiled
    """Joint-space mass matrix M(q) into out (n, n), both triangles; == ``pin.crba``."""
    mass_matrix_in(ch, pi, q, workspace(q.shape[0]), out)


@njit(cache=True)
def mass_matrix_in(ch, pi, q, w, out):  # pragma: no cover - compiled
    """:func:`mass_matrix` with its scratch ``w = workspace(n)`` given (no allocation)."""
    n = q.shape[0]
    zero = w[9][n + 10 : 2 * n + 10]
    for i in range(n):
        zero[i] = 0.0
    kinematics(ch, q, zero, w[0], w[1], w[2], w[3])
    world_inertia(pi, w[0], w[1], w[4])
    _composite_mass(w[2], w[4], out, w[9][n : n + 10], w[8][0])


@njit(cache=True, fastmath={"contract", "reassoc"}, inline="always")
def bias_and_mass(ch, pi, q, qd, w, bias, m):  # pragma: no cover - compiled
    """``bias = rnea(q, qd, 0)`` (n,) and ``m = M(q)`` (n, n) in one pass, no allocation.

    The plant integrator's inner step; ``w = workspace(n)`` is scratch. Same
    arithmetic as :func:`rnea` and :func:`mass_matrix`, written with scalars.
    """
    rw, pw, s, v, iw, f = w[0], w[1], w[2], w[3], w[4], w[7]
    n = q.shape[0]
    kinematics(ch, q, qd, rw, pw, s, v)
    world_inertia(pi, rw, pw, iw)
    al0, al1, al2 = -ch.gravity[0], -ch.gravity[1], -ch.gravity[2]
    aa0 = aa1 = aa2 = 0.0
    for i in range(n):
        vl0, vl1, vl2, w0, w1, w2 = v[i, 0], v[i, 1], v[i, 2], v[i, 3], v[i, 4], v[i, 5]
        sl0, sl1, sl2, sa0, sa1, sa2 = s[i, 0], s[i, 1], s[i, 2], s[i, 3], s[i, 4], s[i, 5]
        # a += (v x S) qd: (w x Sl + vl x Sa, w x Sa) qd
        x0, x1, x2 = cross3(w0, w1, w2, sl0, sl1, sl2)
        y0, y1, y2 = cross3(vl0, vl1, vl2, sa0, sa1, sa2)
        z0, z1, z2 = cross3(w0, w1, w2, sa0, sa1, sa2)
        u = qd[i]
        al0 += (x0 + y0) * u
        al1 += (x1 + y1) * u
        al2 += (x2 + y2) * u
        aa0 += z0 * u
        aa1 += z1 * u
        aa2 += z2 * u
        mass, h0, h1, h2 = iw[i, 0], iw[i, 1], iw[i, 2], iw[i, 3]
        ixx, ixy, iyy, ixz, iyz, izz = iw[i, 4], iw[i, 5], iw[i, 6], iw[i, 7], iw[i, 8], iw[i, 9]
        # I a: (m al + aa x h, h x al + I aa)
        c0, c1, c2 = cross3(aa0, aa1, aa2, h0, h1, h2)
        d0, d1, d2 = cross3(h0, h1, h2, al0, al1, al2)
        fl0, fl1, fl2 = mass * al0 + c0, mass * al1 + c1, mass * al2 + c2
        fa0 = d0 + ixx * aa0 + ixy * aa1 + ixz * aa2
        fa1 = d1 + ixy * aa0 + iyy * aa1 + iyz * aa2
        fa2 = d2 + ixz * aa0 + iyz * aa1 + izz * aa2
        # p = I v, then f += v x* p = (w x pl, w x pa + vl x pl)
        c0, c1, c2 = cross3(w0, w1, w2, h0, h1, h2)
        d0, d1, d2 = cross3(h0, h1, h2, vl0, vl1, vl2)
        pl0, pl1, pl2 = mass * vl0 + c0, mass * vl1 + c1, mass * vl2 + c2
        pa0 = d0 + ixx * w0 + ixy * w1 + ixz * w2
        pa1 = d1 + ixy * w0 + iyy * w1 + iyz * w2
        pa2 = d2 + ixz * w0 + iyz * w1 + izz * w2
        x0, x1, x2 = cross3(w0, w1, w2, pl0, pl1, pl2)
        y0, y1, y2 = cross3(w0, w1, w2, pa0, pa1, pa2)
        z0, z1, z2 = cross3(vl0, vl1, vl2, pl0, pl1, pl2)
        f[i, 0], f[i, 1], f[i, 2] = fl0 + x0, fl1 + x1, fl2 + x2
        f[i, 3], f[i, 4], f[i, 5] = fa0 + y0 + z0, fa1 + y1 + z1, fa2 + y2 + z2
    g0 = g1 = g2 = g3 = g4 = g5 = 0.0
    cm = ch0 = ch1 = ch2 = cxx = cxy = cyy = cxz = cyz = czz = 0.0
    for i in range(n - 1, -1, -1):
        g0 += f[i, 0]
        g1 += f[i, 1]
        g2 += f[i, 2]
        g3 += f[i, 3]
        g4 += f[i, 4]
        g5 += f[i, 5]
        sl0, sl1, sl2, sa0, sa1, sa2 = s[i, 0], s[i, 1], s[i, 2], s[i, 3], s[i, 4], s[i, 5]
        bias[i] = sl0 * g0 + sl1 * g1 + sl2 * g2 + sa0 * g3 + sa1 * g4 + sa2 * g5
        cm += iw[i, 0]
        ch0 += iw[i, 1]
        ch1 += iw[i, 2]
        ch2 += iw[i, 3]
        cxx += iw[i, 4]
        cxy += iw[i, 5]
        cyy += iw[i, 6]
        cxz += iw[i, 7]
        cyz += iw[i, 8]
        czz += iw[i, 9]
        # t = Ic S_i
        c0, c1, c2 = cross3(sa0, sa1, sa2, ch0, ch1, ch2)
        d0, d1, d2 = cross3(ch0, ch1, ch2, sl0, sl1, sl2)
        t0, t1, t2 = cm * sl0 + c0, cm * sl1 + c1, cm * sl2 + c2
        t3 = d0 + cxx * sa0 + cxy * sa1 + cxz * sa2
        t4 = d1 + cxy * sa0 + cyy * sa1 + cyz * sa2
        t5 = d2 + cxz * sa0 + cyz * sa1 + czz * sa2
        for k in range(i + 1):
            x = s[k, 0] * t0 + s[k, 1] * t1 + s[k, 2] * t2 + s[k, 3] * t3 + s[k, 4] * t4 + s[k, 5] * t5
            m[k, i] = x
            m[i, k] = x


@njit(cache=True)
def _cholesky_solve(a, b):  # pragma: no cover - compiled
    """Solve a x = b in place (b becomes x, a its Cholesky factor); False if a is not positive definite."""
    n = b.shape[0]
    for j in range(n):
        d = a[j, j]
        for k in range(j):
            d -= a[j, k] * a[j, k]
        if not d > 0.0:
            return False
        d = np.sqrt(d)
        a[j, j] = d
        for i in range(j + 1, n):
            x = a[i, j]
            for k in range(j):
                x -= a[i, k] * a[j, k]
            a[i, j] = x / d
    for i in range(n):
        x = b[i]
        for k in range(i):
            x -= a[i, k] * b[k]
        b[i] = x / a[i, i]
    for i in range(n - 1, -1, -1):
        x = b[i]
        for k in range(i + 1, n):
            x -= a[k, i] * b[k]
        b[i] = x / a[i, i]
    return True


@njit(cache=True)
def forward_dynamics(ch, pi, armature, q, qd, tau, out):  # pragma: no cover - compiled
    """Joint accelerations solving ``(M(q) + diag(armature)) qdd = tau - rnea(q, qd, 0)`` into out (n,).

    == ``pin.aba`` with zero armature. Returns False (out filled with NaN) if the
    mass matrix is not positive definite or a value is not finite.
    """
    n = q.shape[0]
    w = workspace(n)
    m = np.empty((n, n))
    bias_and_mass(ch, pi, q, qd, w, out, m)
    for i in range(n):
        m[i, i] += armature[i]
        out[i] = tau[i] - out[i]
    ok = _cholesky_solve(m, out)
    if ok:
        for i in range(n):
            if not np.isfinite(out[i]):
                ok = False
    if not ok:
        out[:] = np.nan
    return ok
