"""The same arm as a Pinocchio model, and a cross-check of our dynamics against it.

Pinocchio (``pin``) is the rigid-body reference: ``crba`` (mass matrix), ``rnea``
(inverse dynamics), ``aba`` (forward dynamics) and
``computeJointTorqueRegressor``. Pinocchio has no friction, so every comparison
uses sigma with ``b = d = 0``; gravity acts along -z and gives no torque about
the vertical joint axes.

Both functions take an :class:`~adaptive_dd.plant.arm.Arm` of the paper's geometry (its closed
forms' record, :func:`~adaptive_dd.plant.two_link.closed_form_view`), that record (default
:meth:`ClosedFormTwoLink.sice`) or its :class:`PhysicalParameters`. An arm known only by its
base parameters is built from :meth:`ClosedFormTwoLink.equivalent_physical`, a physical set
with the same sigma (rigid-body dynamics depend on sigma alone).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from adaptive_dd.errors import ParameterError
from adaptive_dd.plant.dynamics import (
    coriolis_matrix,
    forward_dynamics,
    inverse_dynamics,
    mass_matrix,
    regressor,
)
from adaptive_dd.plant.parameters import Payload, PhysicalParameters
from adaptive_dd.plant.two_link import ClosedFormTwoLink, closed_form_view

__all__ = [
    "CheckResult",
    "as_physical",
    "base_parameter_map",
    "build_model",
    "two_link_cross_check",
]

# index of each dynamic parameter of one body in Pinocchio's ordering
_M, _MCX, _IZZ = 0, 1, 9


def _link_inertia(mass: float, com_x: float, izz: float) -> pin.Inertia:
    # planar motion only sees Izz; Ixx, Iyy are set to a valid rod-like value
    ixx = max(izz, 1e-6)
    return pin.Inertia(mass, np.array([com_x, 0.0, 0.0]), np.diag([ixx * 0.1, izz, izz]))


def as_physical(arm: ClosedFormTwoLink | PhysicalParameters | None) -> PhysicalParameters:
    """Physical parameters of an arm (default :meth:`ClosedFormTwoLink.sice`); see the module docstring."""
    if arm is None:
        return ClosedFormTwoLink.sice().equivalent_physical()
    view = closed_form_view(arm)  # an Arm of the paper's geometry: its closed forms' record
    if view is not None:
        return view.equivalent_physical()
    if isinstance(arm, PhysicalParameters):
        return arm
    raise ParameterError(f"expected a ClosedFormTwoLink or PhysicalParameters, got {type(arm).__name__}")


def build_model(
    arm: ClosedFormTwoLink | PhysicalParameters | None = None, payload: Payload | None = None
) -> pin.Model:
    """Two revolute joints about z in the horizontal plane, as a ``pinocchio.Model``.

    Link i has mass ``m_i``, centre of mass at ``a_i`` along the link and inertia
    ``I_i`` about its centre (z axis); joint 2 sits at ``l1`` along link 1. A
    payload is a separate body on joint 2: a disk centred at ``l2``.
    """
    params = as_physical(arm)
    model = pin.Model()
    model.name = "two_link_dd_arm"
    j1 = model.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "joint1")
    model.appendBodyToJoint(j1, _link_inertia(params.m1, params.a1, params.I1), pin.SE3.Identity())
    placement = pin.SE3(np.eye(3), np.array([params.l1, 0.0, 0.0]))
    j2 = model.addJoint(j1, pin.JointModelRZ(), placement, "joint2")
    model.appendBodyToJoint(j2, _link_inertia(params.m2, params.a2, params.I2), pin.SE3.Identity())
    if payload is not None and payload.mass > 0:
        disk = pin.Inertia(
            payload.mass,
            np.zeros(3),
            np.diag([payload.inertia / 2, payload.inertia / 2, payload.inertia]),
        )
        model.appendBodyToJoint(j2, disk, pin.SE3(np.eye(3), np.array([params.l2, 0.0, 0.0])))
    return model


def base_parameter_map(l1: float) -> NDArray[np.float64]:
    """Matrix ``K (20, 3)`` with ``Y_pin @ K == regressor[..., :3]`` (columns J1, J2, r).

    ``J1`` acts like ``Izz`` of body 1 about joint 1, ``J2`` like ``Izz`` of body 2
    about joint 2, and ``r = l1 * (m2 a2)`` like ``mc_x`` of body 2 divided by l1.
    """
    k = np.zeros((20, 3))
    k[_IZZ, 0] = 1.0
    k[10 + _IZZ, 1] = 1.0
    k[10 + _MCX, 2] = 1.0 / l1
    return k


@dataclass(frozen=True)
class CheckResult:
    """One comparison: the largest discrepancy over all states, relative to the scale."""

    name: str
    max_error: float
    tolerance: float
    shown: str | None = None
    """What the line prints instead of ``max error ... (tol ...)`` (a check that is no error)."""

    @property
    def passed(self) -> bool:
        return bool(np.isfinite(self.max_error) and self.max_error <= self.tolerance)

    def __str__(self) -> str:
        flag = "ok  " if self.passed else "FAIL"
        what = self.shown or f"max error {self.max_error:9.2e}  (tol {self.tolerance:.0e})"
        return f"{flag} {self.name:<52s} {what}"


def relative_error(a, b) -> float:
    """Largest ``|a - b|`` relative to ``max(1, max|b|)``: the measure of every check here."""
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))) / max(1.0, float(np.max(np.abs(b)))))


def random_states(
    rng: np.random.Generator, q_low, q_high, n_states: int, n_joints: int, speed, accel, torque
):
    """``q, qd, qdd, tau`` of shape ``(n_states, n_joints)``, uniform in ``[q_low, q_high]``,
    ``+-speed``, ``+-accel``, ``+-torque`` (drawn in that order)."""
    size = (n_states, n_joints)
    q = rng.uniform(q_low, q_high, size)
    qd = rng.uniform(-speed, speed, size)
    qdd = rng.uniform(-accel, accel, size)
    tau = rng.uniform(-torque, torque, size)
    return q, qd, qdd, tau


def stack_states(n_states: int, one_state) -> dict[str, NDArray[np.float64]]:
    """``one_state(i)`` (a dict of arrays) for every state ``i``, each key stacked along a first axis."""
    rows = [one_state(i) for i in range(n_states)]
    return {k: np.array([row[k] for row in rows]) for k in rows[0]}


def positive_definite_check(M: NDArray) -> CheckResult:
    """``-min eigenvalue / max`` of the mass matrices ``M (..., n, n)``: passes when not above 0."""
    eig = np.linalg.eigvalsh(M)
    ratio = float(eig.min() / eig.max())
    shown = f"smallest eigenvalue / largest {ratio:9.2e}  (must be > 0)"
    return CheckResult("M positive definite", -ratio, -np.finfo(float).tiny, shown)  # 0: singular, fails


def _two_link_sigma(arm, params: PhysicalParameters, payload: Payload | None) -> NDArray[np.float64]:
    """The sigma compared: a ClosedFormTwoLink's own (with its payload effect), else from the physical set."""
    arm = closed_form_view(arm)
    if arm is not None:  # its own sigma and payload effect, against a disk body in Pinocchio
        return arm.sigma if payload is None else arm.sigma_with_payload(payload.mass, payload.radius)
    return (params if payload is None else params.with_payload(payload)).to_sigma()


def _two_link_references(model: pin.Model, q, qd, qdd, tau) -> dict[str, NDArray[np.float64]]:
    """Pinocchio's M, C qd, rnea, aba and joint-torque regressor on every state."""
    data = model.createData()

    def one(i):
        m = pin.crba(model, data, q[i])
        return {
            "M": np.triu(m) + np.triu(m, 1).T,
            "C": pin.rnea(model, data, q[i], qd[i], np.zeros(2)).copy(),
            "rnea": pin.rnea(model, data, q[i], qd[i], qdd[i]).copy(),
            "aba": pin.aba(model, data, q[i], qd[i], tau[i]).copy(),
            "Y": pin.computeJointTorqueRegressor(model, data, q[i], qd[i], qdd[i]).copy(),
        }

    return stack_states(len(q), one)


def _skew_check(q, qd, sigma, C) -> CheckResult:
    """dM/dt along the motion (central difference, error O(h^2)), then dM/dt - 2C + its transpose."""
    h = 1e-6
    mdot = (mass_matrix(q + h * qd, sigma) - mass_matrix(q - h * qd, sigma)) / (2 * h)
    n = mdot - 2 * C
    return CheckResult("dM/dt - 2C skew-symmetric", relative_error(n + np.swapaxes(n, -1, -2), 0 * n), 1e-6)


def two_link_cross_check(
    arm: ClosedFormTwoLink | PhysicalParameters | None = None,
    payload: Payload | None = None,
    n_states: int = 200,
    rng: np.random.Generator | None = None,
    tol: float = 1e-9,
) -> list[CheckResult]:
    """Compare :mod:`adaptive_dd.plant.dynamics` with Pinocchio on random states.

    Parameters
    ----------
    arm : ClosedFormTwoLink or PhysicalParameters, optional
        The arm (default :meth:`ClosedFormTwoLink.sice`). For a ClosedFormTwoLink, the sigma compared is
        ``arm.sigma`` or ``arm.sigma_with_payload(...)``, so the check covers the
        arm's payload effect too; Pinocchio gets the disk as a separate body.
    payload : Payload, optional
        A tip disk at ``l2``.
    n_states : int
        Random states (q in [-pi, pi], qd in [-5, 5] rad/s, qdd in [-50, 50] rad/s^2).
    rng : numpy.random.Generator, optional
        Source of the states (default: seed 0).
    tol : float
        Tolerance on every discrepancy, relative to ``max(1, |reference|)``.

    Returns
    -------
    list of CheckResult
        Mass matrix, Coriolis, regressor, forward dynamics, Pinocchio regressor,
        positive definiteness and skew symmetry of dM/dt - 2C.
    """
    rng = np.random.default_rng(0) if rng is None else rng
    params = as_physical(arm)
    sigma = _two_link_sigma(arm, params, payload)
    sigma_nf = sigma.copy()
    sigma_nf[3:] = 0.0
    model = build_model(params, payload)
    q, qd, qdd, tau = random_states(rng, -np.pi, np.pi, n_states, 2, 5, 50, 20)
    ref = _two_link_references(model, q, qd, qdd, tau)
    M = mass_matrix(q, sigma)
    C = coriolis_matrix(q, qd, sigma)
    phi = regressor(q, qd, qdd)
    pairs = [
        ("mass_matrix vs pin.crba", M, ref["M"]),
        ("coriolis_matrix @ qd vs pin.rnea(q, qd, 0)", (C @ qd[..., None])[..., 0], ref["C"]),
        ("regressor @ sigma (no friction) vs pin.rnea", phi @ sigma_nf, ref["rnea"]),
        ("inverse_dynamics (no friction) vs pin.rnea", inverse_dynamics(q, qd, qdd, sigma_nf), ref["rnea"]),
        ("forward_dynamics (no friction) vs pin.aba", forward_dynamics(q, qd, tau, sigma_nf), ref["aba"]),
        (
            "pin regressor mapped onto (J1, J2, r) vs regressor[:, :3]",
            ref["Y"] @ base_parameter_map(params.l1),
            phi[..., :3],
        ),
        (
            "pin regressor @ pin params vs regressor[:, :3] @ sigma[:3]",
            ref["Y"] @ np.concatenate([model.inertias[i].toDynamicParameters() for i in (1, 2)]),
            phi[..., :3] @ sigma[:3],
        ),
    ]
    out = [CheckResult(name, relative_error(a, b), tol) for name, a, b in pairs]
    return [*out, positive_definite_check(M), _skew_check(q, qd, sigma, C)]
