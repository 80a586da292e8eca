"""The model of N-joint identification: compiled dynamics of an :class:`Arm` in base parameters.

Parameters
----------
Standard parameters ``pi`` (13 n) as :mod:`adaptive_dd.plant.base_parameters`: ten per
link (Pinocchio's order, about the joint frame), then ``fv``, ``fc``, ``Ia`` per joint.
Base parameters ``sigma = B pi`` (p). Any ``pi`` with ``B pi = sigma`` gives the same
torques for every motion, so the dynamics of a base-parameter vector are computed from

    pi(sigma) = pi_ref + B^+ (sigma - B pi_ref)

(``pi_ref`` the URDF's parameters): a full parameter set close to the URDF's, with the
exact torques of ``sigma``; the compiled kernels (:mod:`adaptive_dd.plant.chain`) then
run on it (Cholesky of the total mass matrix, which is that of ``sigma``).

Friction
--------
``tau_f = fv qd + fc tanh(qd / v_f)`` with ``v_f`` the arm's ``friction_velocity``
(0.02 rad/s by default): the Coulomb column of every regressor here is
``tanh(qd / v_f)``, so the model is smooth (output-error sensitivities exist) and the
records simulated by :mod:`adaptive_dd.identification.records` match it exactly.
A plant with stick-slip friction differs from it only within ``v_f`` of zero velocity.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError, RunWarning, SignalError
from adaptive_dd.plant.chain import Chain, forward_dynamics_batch, mass_matrix_batch, regressor_batch

__all__ = [
    "Model",
    "arm_model",
    "base_regressor",
    "forward_dynamics",
    "mass_matrix",
    "pi_from_sigma",
    "pi_with_payload",
    "rk4_step",
    "standard_regressor",
    "state_jacobian",
]

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class Model:
    """Arrays an N-joint identification needs, taken once from an :class:`Arm`.

    Attributes
    ----------
    chain : Chain
        Kinematics for the compiled kernels.
    n, p : int
        Joints and base parameters.
    independent : ndarray of int (p,)
        Base columns of the standard regressor.
    B : ndarray (p, 13 n)
        ``sigma = B pi``.
    B_pinv : ndarray (13 n, p)
        Its pseudo-inverse (``B B_pinv = I``).
    pi_ref : ndarray (13 n,)
        The URDF's standard parameters (links, friction, armature).
    sigma_ref : ndarray (p,)
        ``B pi_ref``.
    friction_velocity : float
        ``v_f`` [rad/s] of the smooth Coulomb law.
    names : tuple of str (p,)
        Base parameter names.
    """

    chain: Chain
    n: int
    p: int
    independent: NDArray[np.int64]
    B: Array
    B_pinv: Array
    pi_ref: Array
    sigma_ref: Array
    friction_velocity: float
    names: tuple[str, ...]


def arm_model(arm) -> Model:
    """The :class:`Model` of an :class:`~adaptive_dd.plant.arm.Arm`."""
    base = arm.base
    B = np.asarray(base.B, dtype=float)
    pi_ref = np.asarray(arm.pi, dtype=float)
    return Model(
        chain=arm.chain,
        n=arm.n_joints,
        p=base.count,
        independent=np.asarray(base.independent),
        B=B,
        B_pinv=np.linalg.pinv(B),
        pi_ref=pi_ref,
        sigma_ref=B @ pi_ref,
        friction_velocity=float(arm.friction_velocity),
        names=tuple(base.names),
    )


def pi_from_sigma(model: Model, sigma: ArrayLike) -> Array:
    """Standard parameters ``(13 n,)`` with ``B pi = sigma`` nearest to the URDF's (least change)."""
    s = np.asarray(sigma, dtype=float)
    if s.shape != (model.p,) or not np.all(np.isfinite(s)):
        raise ParameterError(f"sigma must be {model.p} finite values, got shape {s.shape}")
    return model.pi_ref + model.B_pinv @ (s - model.sigma_ref)


def pi_with_payload(arm, pi: ArrayLike, payload: ArrayLike) -> Array:
    """``pi (13 n,)`` with a rigid body of ten parameters ``payload`` (about the payload frame) added."""
    out = np.array(pi, dtype=float)
    j = arm.payload_joint
    out[10 * j : 10 * j + 10] += arm.payload_map @ np.asarray(payload, dtype=float)
    return out


def _friction_columns(model: Model, qd: Array, qdd: Array) -> Array:
    n = model.n
    eye = np.eye(n)
    coul = np.tanh(qd / model.friction_velocity)
    return np.concatenate(
        [eye * qd[..., None, :], eye * coul[..., None, :], eye * qdd[..., None, :]], axis=-1
    )


def standard_regressor(model: Model, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> Array:
    """``W(q, qd, qdd)`` of the standard parameters, ``(..., n, 13 n)`` (compiled; smooth Coulomb)."""
    q, qd, qdd = (np.asarray(x, dtype=float) for x in (q, qd, qdd))
    shape = np.broadcast_shapes(q.shape, qd.shape, qdd.shape)
    q, qd, qdd = (np.broadcast_to(x, shape) for x in (q, qd, qdd))
    Y = regressor_batch(model.chain, q, qd, qdd)
    return np.concatenate([Y, _friction_columns(model, qd, qdd)], axis=-1)


def base_regressor(model: Model, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> Array:
    """Base regressor ``(..., n, p)``: ``base_regressor @ sigma`` is the joint torque [N m]."""
    return standard_regressor(model, q, qd, qdd)[..., model.independent]


def _split(model: Model, pi: Array) -> tuple[Array, Array, Array, Array]:
    n = model.n
    return pi[: 10 * n], pi[10 * n : 11 * n], pi[11 * n : 12 * n], pi[12 * n :]


def forward_dynamics(model: Model, pi: ArrayLike, q: ArrayLike, qd: ArrayLike, tau: ArrayLike) -> Array:
    """Joint accelerations ``(..., n)`` under applied torque ``tau`` (friction and armature included).

    Raises
    ------
    SignalError
        Non-finite states or a mass matrix that is not positive definite.
    """
    pi = np.asarray(pi, dtype=float)
    links, fv, fc, ia = _split(model, pi)
    qd = np.asarray(qd, dtype=float)
    tau_eff = np.asarray(tau, dtype=float) - fv * qd - fc * np.tanh(qd / model.friction_velocity)
    return forward_dynamics_batch(model.chain, links, ia, q, qd, tau_eff)


def mass_matrix(model: Model, pi: ArrayLike, q: ArrayLike) -> Array:
    """``M(q) + diag(Ia)``, ``(..., n, n)``."""
    links, _, _, ia = _split(model, np.asarray(pi, dtype=float))
    return mass_matrix_batch(model.chain, links, q) + np.diag(ia)


MAX_SPLIT = 1024
"""The most RK4 steps :func:`rk4_step` splits a substep into (``h rho`` up to 2048)."""


def rk4_step(
    model: Model, pi: Array, q: Array, qd: Array, tau: Array, T: float, substeps: int = 2
) -> tuple[Array, Array]:
    """One sample under torque held over ``T`` [s]: RK4 with ``substeps`` steps, batch ``(..., n)``,
    each split so that ``h rho <= 2``: ``rho = sum_i (fv_i + fc_i / v_f) ((M + Ia)^-1)_ii`` at the
    sample's start (the steepest friction slope over the inertia, as the benchmark's plant splits
    its steps, :mod:`adaptive_dd.plant.chain_rk4`), the most over the batch: RK4 is unstable past
    ``h rho`` = 2.79 (the SICE arm's is 5.1 at T = 1 ms and 2 substeps). More than 8 steps per
    substep (a URDF without armature) is warned of, more than :data:`MAX_SPLIT` refused."""
    _, fv, fc, _ = _split(model, np.asarray(pi, dtype=float))
    slope = fv + fc / model.friction_velocity
    try:
        dinv = np.diagonal(np.linalg.inv(mass_matrix(model, pi, q)), axis1=-2, axis2=-1)
    except np.linalg.LinAlgError:  # forward_dynamics names a mass matrix that is not positive definite
        dinv = np.zeros(1)
    rho = float(np.max(np.sum(slope * dinv, axis=-1)))
    if np.isfinite(rho) and rho > 0:
        split = max(1, int(np.ceil(T / substeps * rho / 2.0)))
        if split > MAX_SPLIT:
            raise SignalError(
                f"rk4_step: the smooth friction is stiff at T = {T:g} s (h rho = {T / substeps * rho:.3g}: "
                f"{split} RK4 steps per substep, more than {MAX_SPLIT}); state the joints' armature in "
                "[arm] or a wider friction_velocity"
            )
        if split > 8:
            warnings.warn(
                f"rk4_step: the smooth friction is stiff at T = {T:g} s: {split} RK4 steps per substep "
                "(slow); the joints' armature in [arm], if the arm has any, makes it cheaper",
                RunWarning,
                stacklevel=2,
            )
        substeps *= split
    h = T / substeps
    for _ in range(substeps):
        a1 = forward_dynamics(model, pi, q, qd, tau)
        v2 = qd + 0.5 * h * a1
        a2 = forward_dynamics(model, pi, q + 0.5 * h * qd, v2, tau)
        v3 = qd + 0.5 * h * a2
        a3 = forward_dynamics(model, pi, q + 0.5 * h * v2, v3, tau)
        v4 = qd + h * a3
        a4 = forward_dynamics(model, pi, q + h * v3, v4, tau)
        q = q + h / 6.0 * (qd + 2.0 * v2 + 2.0 * v3 + v4)
        qd = qd + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd))):
        raise SignalError("rk4_step: the state became non-finite")
    return q, qd


def state_jacobian(
    model: Model, pi: Array, q: Array, qd: Array, tau: Array, eps: float = 1e-7
) -> tuple[Array, Array, Array]:
    """Linearisation of the continuous dynamics at ``(q, qd)``, batch ``(B, n)``.

    Returns
    -------
    F : ndarray (B, 2n, 2n)
        ``d[qd, qdd] / d[q, qd]`` (``d qdd / d x`` by forward differences of step ``eps``
        times ``max(1, |x_k|)``: relative error ~1e-7, enough for information matrices and
        Gauss-Newton steps).
    G : ndarray (B, 2n, p)
        ``d[qd, qdd] / d sigma = [0; -(M + Ia)^-1 Y_base(q, qd, qdd)]``.
    qdd : ndarray (B, n)
    """
    n, b = model.n, q.shape[0]
    qdd = forward_dynamics(model, pi, q, qd, tau)
    x = np.concatenate([q, qd], axis=1)
    h = eps * np.maximum(1.0, np.abs(x))  # (B, 2n)
    xp = x[:, None, :] + h[:, :, None] * np.eye(2 * n)[None]  # (B, 2n perturbations, 2n)
    tp = np.broadcast_to(tau[:, None], (b, 2 * n, n))
    ap = forward_dynamics(model, pi, xp[..., :n], xp[..., n:], tp)  # (B, 2n, n)
    dadx = (ap - qdd[:, None, :]) / h[:, :, None]  # row k = d qdd / d x_k
    F = np.zeros((b, 2 * n, 2 * n))
    F[:, :n, n:] = np.eye(n)
    F[:, n:, :] = np.swapaxes(dadx, 1, 2)
    Y = base_regressor(model, q, qd, qdd)
    M = mass_matrix(model, pi, q)
    G = np.zeros((b, 2 * n, model.p))
    G[:, n:] = -np.linalg.solve(M, Y)
    return F, G, qdd
