"""Rigid-body dynamics of the horizontal two-link arm in base parameters.

All functions broadcast over leading batch axes: ``q.shape == (..., 2)``,
``sigma.shape == (..., 7)``. The public functions check shapes and finiteness;
the underscore kernels skip the checks and are what the simulators call per step.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import SignalError
from adaptive_dd.plant.parameters import validate_sigma

__all__ = [
    "coriolis_matrix",
    "coriolis_vector",
    "forward_dynamics",
    "friction",
    "inverse_dynamics",
    "mass_matrix",
    "mass_matrix_entries",
    "regressor",
    "regressor_reference",
]

Array = NDArray[np.float64]


def as_joint_array(x: ArrayLike, name: str) -> Array:
    """Return ``x`` as a finite float array of shape ``(..., 2)`` or raise SignalError."""
    a = np.asarray(x, dtype=float)
    if a.ndim == 0 or a.shape[-1] != 2:
        raise SignalError(f"{name} must have shape (..., 2), got {a.shape}")
    if not np.all(np.isfinite(a)):
        bad = np.argwhere(~np.isfinite(a))[0]
        raise SignalError(
            f"{name} has a non-finite value {a[tuple(bad)]} at index {tuple(int(i) for i in bad)}"
        )
    return a


# --------------------------------------------------------------------- kernels
def mass_matrix_entries(q2: Array, sigma: Array) -> tuple[Array, Array, Array]:
    """Entries ``(M11, M12, M22)`` of M(q) (eq. 3), each ``(...)``; no checks (a kernel).

    Parameters
    ----------
    q2 : ndarray (...)
        Angle of joint 2 [rad].
    sigma : ndarray (..., 7)
        Base parameters.
    """
    c2 = np.cos(q2)
    j2 = sigma[..., 1]
    rc = sigma[..., 2] * c2
    return sigma[..., 0] + j2 + 2.0 * rc, j2 + rc, j2 + 0.0 * rc


def coriolis_vector(q: Array, qd: Array, sigma: Array) -> Array:
    """``C(q, qd) qd`` of eq. (4), ``(..., 2)`` [N m]; no checks (a kernel)."""
    rs = sigma[..., 2] * np.sin(q[..., 1])
    qd1, qd2 = qd[..., 0], qd[..., 1]
    return np.stack((-rs * qd2 * (2.0 * qd1 + qd2), rs * qd1 * qd1), axis=-1)


_mass_entries = mass_matrix_entries  # old private names, kept for callers not yet moved
_coriolis_vector = coriolis_vector


def _friction(qd: Array, sigma: Array, sgn: Array | None = None) -> Array:
    s = np.sign(qd) if sgn is None else sgn
    return sigma[..., 3:5] * qd + sigma[..., 5:7] * s


def _solve2(m11: Array, m12: Array, m22: Array, rhs: Array) -> Array:
    det = m11 * m22 - m12 * m12
    r1, r2 = rhs[..., 0], rhs[..., 1]
    return np.stack(((m22 * r1 - m12 * r2) / det, (m11 * r2 - m12 * r1) / det), axis=-1)


def _regressor(q: Array, qd: Array, qdd: Array, sgn: Array) -> Array:
    c2, s2 = np.cos(q[..., 1]), np.sin(q[..., 1])
    qd1, qd2 = qd[..., 0], qd[..., 1]
    qdd1, qdd2 = qdd[..., 0], qdd[..., 1]
    phi13 = c2 * (2.0 * qdd1 + qdd2) - s2 * (2.0 * qd1 * qd2 + qd2 * qd2)
    phi23 = c2 * qdd1 + s2 * qd1 * qd1
    shape = np.broadcast_shapes(q.shape, qd.shape, qdd.shape, sgn.shape)[:-1]
    out = np.zeros((*shape, 2, 7))
    out[..., 0, 0] = qdd1
    out[..., :, 1] = (qdd1 + qdd2)[..., None]
    out[..., 0, 2] = phi13
    out[..., 1, 2] = phi23
    out[..., 0, 3] = qd1
    out[..., 1, 4] = qd2
    out[..., 0, 5] = sgn[..., 0]
    out[..., 1, 6] = sgn[..., 1]
    return out


# ------------------------------------------------------------------ public API
def mass_matrix(q: ArrayLike, sigma: ArrayLike) -> Array:
    """Inertia matrix M(q) of eq. (3), shape ``(..., 2, 2)`` [kg m^2]."""
    q = as_joint_array(q, "q")
    s = validate_sigma(sigma)
    m11, m12, m22 = mass_matrix_entries(q[..., 1], s)
    row1 = np.stack((m11, m12), axis=-1)
    row2 = np.stack((m12, m22), axis=-1)
    return np.stack((row1, row2), axis=-2)


def coriolis_matrix(q: ArrayLike, qd: ArrayLike, sigma: ArrayLike) -> Array:
    """Centrifugal and Coriolis matrix C(q, qd) of eq. (4), shape ``(..., 2, 2)``.

    With this factorisation ``dM/dt - 2 C`` is skew-symmetric.
    """
    q = as_joint_array(q, "q")
    qd = as_joint_array(qd, "qd")
    s = validate_sigma(sigma)
    rs = s[..., 2] * np.sin(q[..., 1])
    qd1, qd2 = qd[..., 0], qd[..., 1]
    row1 = np.stack((-rs * qd2, -rs * (qd1 + qd2)), axis=-1)
    row2 = np.stack((rs * qd1, 0.0 * rs * qd1), axis=-1)
    return np.stack((row1, row2), axis=-2)


def friction(qd: ArrayLike, sigma: ArrayLike) -> Array:
    """Friction torque ``B qd + D sgn(qd)`` of eqs. (5)-(6), shape ``(..., 2)`` [N m].

    ``sgn(0) = 0``, as written in the paper. The simulator adds sticking on top
    (see :mod:`adaptive_dd.plant.simulator`).
    """
    qd = as_joint_array(qd, "qd")
    return _friction(qd, validate_sigma(sigma))


def regressor(q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, sgn_qd: ArrayLike | None = None) -> Array:
    """Regressor Phi(q, qd, qdd) of eq. (8), shape ``(..., 2, 7)``.

    ``inverse_dynamics(q, qd, qdd, sigma) == regressor(q, qd, qdd) @ sigma``.

    Parameters
    ----------
    q, qd, qdd : array_like, shape (..., 2)
        Joint angles [rad], velocities [rad/s], accelerations [rad/s^2].
    sgn_qd : array_like, shape (..., 2), optional
        Values for the Coulomb columns in place of ``sign(qd)``; the estimators
        pass a filtered sign here (eq. 17 and 19: ``G0 sgn(qd)``).
    """
    q = as_joint_array(q, "q")
    qd = as_joint_array(qd, "qd")
    qdd = as_joint_array(qdd, "qdd")
    sgn = np.sign(qd) if sgn_qd is None else as_joint_array(sgn_qd, "sgn_qd")
    return _regressor(q, qd, qdd, sgn)


def regressor_reference(q: ArrayLike, qd: ArrayLike, qd_r: ArrayLike, qdd_r: ArrayLike) -> Array:
    """Slotine-Li regressor Y with ``Y sigma = M qdd_r + C(q, qd) qd_r + B qd_r + D sgn(qd_r)``.

    Shape ``(..., 2, 7)``. Uses the factorisation of eq. (4) so that the
    Slotine-Li Lyapunov argument (``dM/dt - 2C`` skew) holds.
    """
    q = as_joint_array(q, "q")
    qd = as_joint_array(qd, "qd")
    qd_r = as_joint_array(qd_r, "qd_r")
    qdd_r = as_joint_array(qdd_r, "qdd_r")
    return _regressor_reference(q, qd, qd_r, qdd_r)


def _regressor_reference(q: Array, qd: Array, qd_r: Array, qdd_r: Array) -> Array:
    c2, s2 = np.cos(q[..., 1]), np.sin(q[..., 1])
    qd1, qd2 = qd[..., 0], qd[..., 1]
    v1, v2 = qd_r[..., 0], qd_r[..., 1]
    a1, a2 = qdd_r[..., 0], qdd_r[..., 1]
    shape = np.broadcast_shapes(q.shape, qd.shape, qd_r.shape, qdd_r.shape)[:-1]
    out = np.zeros((*shape, 2, 7))
    out[..., 0, 0] = a1
    out[..., :, 1] = (a1 + a2)[..., None]
    out[..., 0, 2] = c2 * (2.0 * a1 + a2) - s2 * (qd2 * v1 + (qd1 + qd2) * v2)
    out[..., 1, 2] = c2 * a1 + s2 * qd1 * v1
    out[..., 0, 3] = v1
    out[..., 1, 4] = v2
    sg = np.sign(qd_r)
    out[..., 0, 5] = sg[..., 0]
    out[..., 1, 6] = sg[..., 1]
    return out


def inverse_dynamics(q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, sigma: ArrayLike) -> Array:
    """Joint torque of eq. (7): ``M qdd + C qd + B qd + D sgn(qd)``, shape ``(..., 2)`` [N m]."""
    q = as_joint_array(q, "q")
    qd = as_joint_array(qd, "qd")
    qdd = as_joint_array(qdd, "qdd")
    s = validate_sigma(sigma)
    m11, m12, m22 = mass_matrix_entries(q[..., 1], s)
    mq = np.stack((m11 * qdd[..., 0] + m12 * qdd[..., 1], m12 * qdd[..., 0] + m22 * qdd[..., 1]), -1)
    return mq + coriolis_vector(q, qd, s) + _friction(qd, s)


def forward_dynamics(q: ArrayLike, qd: ArrayLike, tau: ArrayLike, sigma: ArrayLike) -> Array:
    """Joint accelerations ``M^-1 (tau - C qd - B qd - D sgn(qd))``, shape ``(..., 2)``.

    The smooth model of eq. (7), with ``sgn(0) = 0``; the simulator's sticking
    friction is in :func:`adaptive_dd.plant.simulator.plant_step`.
    """
    q = as_joint_array(q, "q")
    qd = as_joint_array(qd, "qd")
    tau = as_joint_array(tau, "tau")
    s = validate_sigma(sigma)
    m11, m12, m22 = mass_matrix_entries(q[..., 1], s)
    return _solve2(m11, m12, m22, tau - coriolis_vector(q, qd, s) - _friction(qd, s))
