"""Compiled rigid-body kernels for any serial chain of revolute and prismatic joints.

A :class:`Chain` holds the kinematics (joint types, axes, placements, gravity) as
numpy arrays; the standard link parameters ``pi`` (10 per link, Pinocchio's order
``[m, m cx, m cy, m cz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]`` about the joint frame's
origin, see :func:`standard_parameters`) are passed apart, so that one chain serves
any payload or estimate. Every kernel handles one state and writes into ``out``;
the ``*_batch`` wrappers loop over a leading batch axis.

Algorithms (all spatial vectors ``[linear; angular]`` as in Pinocchio, expressed in
the world frame at the world origin, so that composite inertias simply add):

* kinematics: ``R_i = R_{i-1} rot_i exp(axis_i q_i)``, world joint motion ``S_i``,
  body velocity ``v_i = v_{i-1} + S_i qd_i``, and ``dS_i/dt = v_i x S_i``;
* :func:`rnea` is the recursive Newton-Euler algorithm (Featherstone, *Rigid Body
  Dynamics Algorithms*, sec. 5.3) with the base accelerating at ``-g``;
* :func:`mass_matrix` is the composite-rigid-body algorithm;
* :func:`rnea_ref` (Slotine-Li torque ``M qddr + C(q, qd) qdr + g``) uses the
  body force ``f = I ar + B(v) vr`` with ``B(v) = 1/2 (v x* I - I v x + (I v) xbar*)``,
  ``(f xbar*) m = m x* f``, the per-body factor whose composite sums Pinocchio's
  ``computeCoriolisMatrix`` uses (Echeandia & Wensing 2021): for ``vr = v`` it gives
  ``v x* I v``, and ``dM/dt - 2C`` is skew-symmetric. :func:`coriolis_matrix` is
  that recursion applied to the unit vectors;
* the regressors write each body force in its own joint frame, where it is linear
  in that link's ``pi``, and project it on the joint axes of the links before it;
* :func:`forward_dynamics` solves ``(M + diag(armature)) qdd = tau - rnea(q, qd, 0)``
  by Cholesky.

Compilation: numba compiles a kernel once per tuple of argument types, and a constant
``True``, ``False`` or ``0`` passed to a compiled callee is a literal type of its own (one
copy for ``True``, another for ``False``); the callers here pass ``np.bool_(...)`` and
``np.int64(...)`` instead, and the batch wrappers pass writable arrays (a read-only one is
another type), so that each kernel is compiled once for all its callers
(``tests/test_compile_once.py``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import pinocchio as pin
from numba import njit
from numpy.typing import NDArray

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.plant.spatial import (
    add_cross_force,
    apply_inertia,
    cross3,
    kinematics,
    motion_cross,
    to_local,
    world_inertia,
)

__all__ = [
    "Chain",
    "bias_and_mass",
    "body_regressor",
    "body_regressor_in",
    "body_slotine_li_regressor",
    "body_slotine_li_regressor_in",
    "chain_from_model",
    "coriolis_matrix",
    "coriolis_matrix_batch",
    "forward_dynamics",
    "forward_dynamics_batch",
    "mass_matrix",
    "mass_matrix_batch",
    "mass_matrix_in",
    "momentum_form",
    "momentum_form_in",
    "pin_configuration",
    "regressor",
    "regressor_batch",
    "rnea",
    "rnea_batch",
    "rnea_body_regressor_in",
    "rnea_in",
    "rnea_ref",
    "rnea_ref_batch",
    "rnea_ref_in",
    "slotine_li_regressor",
    "slotine_li_regressor_batch",
    "standard_parameters",
    "workspace",
]

REVOLUTE, PRISMATIC = 0, 1
"""Joint type codes of :attr:`Chain.jtype`."""

_ALLOWED_JOINTS = {
    "JointModelRX",
    "JointModelRY",
    "JointModelRZ",
    "JointModelRevoluteUnaligned",
    "JointModelRUBX",
    "JointModelRUBY",
    "JointModelRUBZ",
    "JointModelRevoluteUnboundedUnaligned",
    "JointModelPX",
    "JointModelPY",
    "JointModelPZ",
    "JointModelPrismaticUnaligned",
}


class Chain(NamedTuple):
    """Kinematics of a serial chain, as the compiled kernels take it.

    Attributes
    ----------
    jtype : ndarray of int64, shape (n,)
        0 revolute, 1 prismatic.
    axis : ndarray, shape (n, 3)
        Unit joint axis in the joint's own frame.
    rot : ndarray, shape (n, 3, 3)
        Rotation of joint i's frame in its parent joint's frame (joint 0: in the base
        frame) at q = 0.
    trans : ndarray, shape (n, 3)
        Origin of joint i's frame in its parent's frame [m].
    gravity : ndarray, shape (3,)
        Gravity in the world frame [m/s^2], e.g. ``[0, 0, -9.81]``.
    """

    jtype: NDArray[np.int64]
    axis: NDArray[np.float64]
    rot: NDArray[np.float64]
    trans: NDArray[np.float64]
    gravity: NDArray[np.float64]


# ----------------------------------------------------------------------------- from Pinocchio


def chain_from_model(model: pin.Model) -> Chain:
    """The :class:`Chain` of a Pinocchio model of a serial chain.

    Parameters
    ----------
    model : pinocchio.Model
        Every joint's parent is the previous joint (joint 1's is the universe); joints
        revolute (``RX/RY/RZ``, ``RevoluteUnaligned``, the continuous ``RUBX/RUBY/RUBZ``
        and ``RevoluteUnboundedUnaligned``) or prismatic (``PX/PY/PZ``,
        ``PrismaticUnaligned``). Gravity is ``model.gravity.linear``.

    Raises
    ------
    ParameterError
        Naming the joint and the reason, for any other joint type or a branch.
    """
    n = model.njoints - 1
    if n < 1:
        raise ParameterError(f"model {model.name!r} has no joint")
    jtype = np.zeros(n, dtype=np.int64)
    axis = np.zeros((n, 3))
    rot = np.zeros((n, 3, 3))
    trans = np.zeros((n, 3))
    data = model.createData()
    q0 = pin.neutral(model)
    for i in range(1, n + 1):
        jm = model.joints[i]
        name = model.names[i]
        kind = jm.shortname()
        if kind not in _ALLOWED_JOINTS:
            raise ParameterError(
                f"joint {i} {name!r} of model {model.name!r} is a {kind}: only revolute and prismatic "
                "joints (RX/RY/RZ, RevoluteUnaligned, RUB*, PX/PY/PZ, PrismaticUnaligned) are supported"
            )
        if model.parents[i] != i - 1:
            raise ParameterError(
                f"joint {i} {name!r} of model {model.name!r} has parent {model.parents[i]}, not {i - 1}: "
                "not a serial chain"
            )
        if jm.idx_v != i - 1:
            raise ParameterError(f"joint {i} {name!r}: velocity index {jm.idx_v}, expected {i - 1}")
        # the joint's motion subspace in its own frame: its velocity for a unit rate, parents at rest
        v = np.zeros(model.nv)
        v[jm.idx_v] = 1.0
        pin.forwardKinematics(model, data, q0, v)
        s = data.v[i].vector
        lin, ang = s[:3], s[3:]
        if np.linalg.norm(ang) > 1e-12:
            if np.linalg.norm(lin) > 1e-12:
                raise ParameterError(f"joint {i} {name!r} is neither revolute nor prismatic (helical?)")
            jtype[i - 1], ax = REVOLUTE, ang
        else:
            jtype[i - 1], ax = PRISMATIC, lin
        axis[i - 1] = ax / np.linalg.norm(ax)
        placement = model.jointPlacements[i]
        rot[i - 1] = placement.rotation
        trans[i - 1] = placement.translation
    return Chain(jtype, axis, rot, trans, np.array(model.gravity.linear, dtype=np.float64))


def standard_parameters(model: pin.Model) -> NDArray[np.float64]:
    """Standard link parameters, shape (10 n,): ``model.inertias[1:]`` ``.toDynamicParameters()`` stacked.

    Per link ``[m, m cx, m cy, m cz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]`` [kg, kg m, kg m^2]
    about the joint frame's origin, in the joint frame.
    """
    return np.concatenate([np.asarray(y.toDynamicParameters()) for y in model.inertias[1:]])


def pin_configuration(model: pin.Model, q: NDArray) -> NDArray[np.float64]:
    """Pinocchio configuration, shape (nq,), of joint angles/displacements ``q`` (n,).

    Continuous joints (nq = 2) become ``(cos q_i, sin q_i)``; others are copied.
    """
    q = np.asarray(q, dtype=np.float64)
    n = model.njoints - 1
    if q.shape != (n,):
        raise SignalError(f"q has shape {q.shape}, expected ({n},) for model {model.name!r}")
    out = np.zeros(model.nq)
    for i in range(1, n + 1):
        jm = model.joints[i]
        if jm.nq == 2:
            out[jm.idx_q] = np.cos(q[i - 1])
            out[jm.idx_q + 1] = np.sin(q[i - 1])
        else:
            out[jm.idx_q] = q[i - 1]
    return out


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


@njit(cache=True)
def _ref_motion(ch, s, v, qdr, qddr, gscale, vr, ar, tmp):  # pragma: no cover - compiled
    """Reference velocity vr_b = sum_{k<=b} S_k qdr_k, acceleration ar_b = -g + sum_{k<=b} dS_k."""
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
        motion_cross(v[b], s[b], tmp)
        for c in range(6):
            vr[b, c] += s[b, c] * qdr[b]
            ar[b, c] += s[b, c] * qddr[b] + tmp[c] * qdr[b]


@njit(cache=True)
def _body_force(y, v, vr, ar, same, out, t1, t2):  # pragma: no cover - compiled
    """out = I ar + 1/2 (v x* I vr - I (v x vr) + vr x* I v); with same (vr = v): I ar + v x* I v."""
    if same:
        apply_inertia(y, ar, out)
        apply_inertia(y, v, t1)
        add_cross_force(v, t1, out, 1.0)
        return
    motion_cross(v, vr, t1)
    for c in range(6):
        t1[c] = ar[c] - 0.5 * t1[c]
    apply_inertia(y, t1, out)
    apply_inertia(y, vr, t1)
    add_cross_force(v, t1, out, 0.5)
    apply_inertia(y, v, t2)
    add_cross_force(vr, t2, out, 0.5)


@njit(cache=True)
def _torque(ch, pi, q, qd, qdr, qddr, gscale, same, w, out):  # pragma: no cover - compiled
    """out = M qddr + C(q, qd) qdr + gscale * g(q) (same: qdr is qd)."""
    s, v, iw, vr, ar, f, small = w[2], w[3], w[4], w[5], w[6], w[7], w[8]
    n = q.shape[0]
    _ref_motion(ch, s, v, qdr, qddr, gscale, vr, ar, small[0])
    for b in range(n):
        _body_force(iw[b], v[b], vr[b], ar[b], same, f[b], small[1], small[2])
    for c in range(6):
        small[3, c] = 0.0
    for b in range(n - 1, -1, -1):
        acc = 0.0
        for c in range(6):
            small[3, c] += f[b, c]
            acc += s[b, c] * small[3, c]
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


@njit(cache=True)
def _local_regressor(v, vr, ar, same, a, y, f, t1, t2):  # pragma: no cover - compiled
    """a (6, 10): the body force of :func:`_body_force` per unit standard parameter (local frame)."""
    for k in range(10):
        y[k] = 0.0
    for k in range(10):
        y[k] = 1.0
        _body_force(y, v, vr, ar, same, f, t1, t2)
        for c in range(6):
            a[c, k] = f[c]
        y[k] = 0.0


@njit(cache=True)
def _regressor_blocks(ch, q, qd, qdr, qddr, same, j0, j1, out, col0):  # pragma: no cover - compiled
    """Columns of links j0..j1-1 of the (Slotine-Li) regressor into out[:, col0 + 10 (j - j0) ...]."""
    _regressor_blocks_in(
        ch, q, qd, qdr, qddr, same, j0, j1, workspace(q.shape[0]), np.empty((6, 10)), out, col0
    )


@njit(cache=True)
def _regressor_blocks_in(ch, q, qd, qdr, qddr, same, j0, j1, w, a, out, col0):  # pragma: no cover
    """:func:`_regressor_blocks` with its scratch given: ``w = workspace(n)``, ``a (6, 10)``."""
    rw, pw, s, v, _, vr, ar, _, small, _ = w
    kinematics(ch, q, qd, rw, pw, s, v)
    _ref_motion(ch, s, v, qdr, qddr, 1.0, vr, ar, small[0])
    _columns_from_motion(same, j0, j1, w, a, out, col0)


@njit(cache=True)
def _columns_from_motion(same, j0, j1, w, a, out, col0):  # pragma: no cover - compiled
    """The per-link part of :func:`_regressor_blocks_in`, its kinematics and reference motion
    (``vr, ar``) already in the workspace ``w``."""
    rw, pw, s, v, _, vr, ar, f, small, vec = w
    n = s.shape[0]
    y = vec[:10]
    vl, vrl, arl = small[0], small[1], small[2]
    sl = small[3]
    for j in range(j0, j1):
        to_local(rw[j], pw[j], v[j], vl)
        to_local(rw[j], pw[j], vr[j], vrl)
        to_local(rw[j], pw[j], ar[j], arl)
        _local_regressor(vl, vrl, arl, same, a, y, f[0], small[4], small[5])
        c0 = col0 + 10 * (j - j0)
        for i in range(n):
            if i > j:
                for k in range(10):
                    out[i, c0 + k] = 0.0
                continue
            to_local(rw[j], pw[j], s[i], sl)
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


@njit(cache=True)
def momentum_form_in(ch, pi, j, q, qd, w, a, p, wv, py, wy):  # pragma: no cover - compiled
    """:func:`momentum_form` with its scratch given: ``w = workspace(n)``, ``a (2, 6, 10)``."""
    # world frame: S_i fixed in link i moves as dS_i/dt = v_i x S_i; the subtree momentum
    # H_i = sum_{k>=i} I_k v_k has dH_i/dt = sum of the subtree's forces, so
    # tau_i = S_i . (dH_i/dt + I_sub a_0) = d/dt (S_i . H_i) - (v_i x S_i) . H_i + S_i . I_sub a_0,
    # a_0 = [-g; 0] the base acceleration that stands for gravity.
    rw, pw, s, v, iw, _, _, _, small, vec = w
    n = q.shape[0]
    kinematics(ch, q, qd, rw, pw, s, v)
    world_inertia(pi, rw, pw, iw)
    ag, hs, gs, t, sl, tl = small[0], small[1], small[2], small[3], small[4], small[5]
    for c in range(6):
        hs[c] = 0.0
        gs[c] = 0.0
        ag[c] = 0.0
    for c in range(3):
        ag[c] = -ch.gravity[c]
    for b in range(n - 1, -1, -1):
        apply_inertia(iw[b], v[b], t)
        for c in range(6):
            hs[c] += t[c]
        apply_inertia(iw[b], ag, t)
        for c in range(6):
            gs[c] += t[c]
        motion_cross(v[b], s[b], t)
        pb = 0.0
        wb = 0.0
        for c in range(6):
            pb += s[b, c] * hs[c]
            wb += s[b, c] * gs[c] - t[c] * hs[c]
        p[b] = pb
        wv[b] = wb
    # link j per unit parameter, in its own frame: I v_j and I a_0 as (6, 10) maps
    y = vec[:10]
    to_local(rw[j], pw[j], v[j], sl)
    to_local(rw[j], pw[j], ag, tl)
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
        to_local(rw[j], pw[j], s[i], sl)
        motion_cross(v[i], s[i], t)
        to_local(rw[j], pw[j], t, tl)
        for k in range(10):
            acc_p = 0.0
            acc_w = 0.0
            for c in range(6):
                acc_p += sl[c] * a[0, c, k]
                acc_w += sl[c] * a[1, c, k] - tl[c] * a[0, c, k]
            py[i, k] = acc_p
            wy[i, k] = acc_w


# ----------------------------------------------------------------------------- batch wrappers


@njit(cache=True)
def _rnea_loop(ch, pi, q, qd, qdd, out):  # pragma: no cover - compiled
    for b in range(q.shape[0]):
        rnea(ch, pi, q[b], qd[b], qdd[b], out[b])


@njit(cache=True)
def _rnea_ref_loop(ch, pi, q, qd, qdr, qddr, out):  # pragma: no cover - compiled
    for b in range(q.shape[0]):
        rnea_ref(ch, pi, q[b], qd[b], qdr[b], qddr[b], out[b])


@njit(cache=True)
def _mass_loop(ch, pi, q, out):  # pragma: no cover - compiled
    for b in range(q.shape[0]):
        mass_matrix(ch, pi, q[b], out[b])


@njit(cache=True)
def _coriolis_loop(ch, pi, q, qd, out):  # pragma: no cover - compiled
    for b in range(q.shape[0]):
        coriolis_matrix(ch, pi, q[b], qd[b], out[b])


@njit(cache=True)
def _fd_loop(ch, pi, armature, q, qd, tau, out):  # pragma: no cover - compiled
    ok = True
    for b in range(q.shape[0]):
        ok &= forward_dynamics(ch, pi, armature, q[b], qd[b], tau[b], out[b])
    return ok


@njit(cache=True)
def _regressor_loop(ch, q, qd, qdd, out):  # pragma: no cover - compiled
    for b in range(q.shape[0]):
        regressor(ch, q[b], qd[b], qdd[b], out[b])


@njit(cache=True)
def _sl_regressor_loop(ch, q, qd, qdr, qddr, out):  # pragma: no cover - compiled
    for b in range(q.shape[0]):
        slotine_li_regressor(ch, q[b], qd[b], qdr[b], qddr[b], out[b])


def _states(ch: Chain, *arrays: NDArray) -> tuple[tuple[int, ...], list[NDArray]]:
    """Broadcast joint arrays (..., n) to one batch shape and flatten them to (B, n), finite checked."""
    n = ch.jtype.shape[0]
    arrs = [np.asarray(a, dtype=np.float64) for a in arrays]
    for k, a in enumerate(arrs):
        if a.ndim == 0 or a.shape[-1] != n:
            raise SignalError(f"joint array {k} has shape {a.shape}, expected (..., {n})")
        if not np.all(np.isfinite(a)):
            raise SignalError(f"joint array {k} has non-finite values")
    batch = np.broadcast_shapes(*(a.shape[:-1] for a in arrs))
    # writable copies where needed: a read-only view (broadcast_to's) is another numba type, and
    # each kernel would be compiled once more for it than the closed loop compiles it
    flat = [np.require(np.broadcast_to(a, (*batch, n)).reshape(-1, n), requirements="CW") for a in arrs]
    return batch, flat


def _pi(ch: Chain, pi: NDArray) -> NDArray[np.float64]:
    pi = np.require(pi, dtype=np.float64, requirements="CW")
    if pi.shape != (10 * ch.jtype.shape[0],):
        raise ParameterError(f"pi has shape {pi.shape}, expected ({10 * ch.jtype.shape[0]},)")
    return pi


def rnea_batch(ch: Chain, pi: NDArray, q: NDArray, qd: NDArray, qdd: NDArray) -> NDArray[np.float64]:
    """:func:`rnea` over a batch: q, qd, qdd (..., n) -> torques (..., n)."""
    batch, (q, qd, qdd) = _states(ch, q, qd, qdd)
    out = np.empty_like(q)
    _rnea_loop(ch, _pi(ch, pi), q, qd, qdd, out)
    return out.reshape(batch + out.shape[1:])


def rnea_ref_batch(
    ch: Chain, pi: NDArray, q: NDArray, qd: NDArray, qdr: NDArray, qddr: NDArray
) -> NDArray[np.float64]:
    """:func:`rnea_ref` over a batch: (..., n) arrays -> torques (..., n)."""
    batch, (q, qd, qdr, qddr) = _states(ch, q, qd, qdr, qddr)
    out = np.empty_like(q)
    _rnea_ref_loop(ch, _pi(ch, pi), q, qd, qdr, qddr, out)
    return out.reshape(batch + out.shape[1:])


def mass_matrix_batch(ch: Chain, pi: NDArray, q: NDArray) -> NDArray[np.float64]:
    """:func:`mass_matrix` over a batch: q (..., n) -> M (..., n, n)."""
    batch, (q,) = _states(ch, q)
    n = q.shape[1]
    out = np.empty((q.shape[0], n, n))
    _mass_loop(ch, _pi(ch, pi), q, out)
    return out.reshape((*batch, n, n))


def coriolis_matrix_batch(ch: Chain, pi: NDArray, q: NDArray, qd: NDArray) -> NDArray[np.float64]:
    """:func:`coriolis_matrix` over a batch: q, qd (..., n) -> C (..., n, n)."""
    batch, (q, qd) = _states(ch, q, qd)
    n = q.shape[1]
    out = np.empty((q.shape[0], n, n))
    _coriolis_loop(ch, _pi(ch, pi), q, qd, out)
    return out.reshape((*batch, n, n))


def forward_dynamics_batch(
    ch: Chain, pi: NDArray, armature: NDArray, q: NDArray, qd: NDArray, tau: NDArray
) -> NDArray[np.float64]:
    """:func:`forward_dynamics` over a batch: (..., n) arrays -> qdd (..., n).

    Raises
    ------
    SignalError
        If the mass matrix is not positive definite or the result not finite in some state.
    """
    batch, (q, qd, tau) = _states(ch, q, qd, tau)
    arm = np.ascontiguousarray(armature, dtype=np.float64)
    if arm.shape != (q.shape[1],):
        raise ParameterError(f"armature has shape {arm.shape}, expected ({q.shape[1]},)")
    out = np.empty_like(q)
    if not _fd_loop(ch, _pi(ch, pi), arm, q, qd, tau, out):
        bad = np.flatnonzero(~np.all(np.isfinite(out), axis=1))
        raise SignalError(f"forward dynamics failed (mass matrix not positive definite?) at states {bad[:5]}")
    return out.reshape(batch + out.shape[1:])


def regressor_batch(ch: Chain, q: NDArray, qd: NDArray, qdd: NDArray) -> NDArray[np.float64]:
    """:func:`regressor` over a batch: (..., n) arrays -> Y (..., n, 10 n)."""
    batch, (q, qd, qdd) = _states(ch, q, qd, qdd)
    n = q.shape[1]
    out = np.empty((q.shape[0], n, 10 * n))
    _regressor_loop(ch, q, qd, qdd, out)
    return out.reshape((*batch, n, 10 * n))


def slotine_li_regressor_batch(
    ch: Chain, q: NDArray, qd: NDArray, qdr: NDArray, qddr: NDArray
) -> NDArray[np.float64]:
    """:func:`slotine_li_regressor` over a batch: (..., n) arrays -> Y (..., n, 10 n)."""
    batch, (q, qd, qdr, qddr) = _states(ch, q, qd, qdr, qddr)
    n = q.shape[1]
    out = np.empty((q.shape[0], n, 10 * n))
    _sl_regressor_loop(ch, q, qd, qdr, qddr, out)
    return out.reshape((*batch, n, 10 * n))
