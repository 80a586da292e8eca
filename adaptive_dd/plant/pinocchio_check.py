"""Cross-check of an :class:`~adaptive_dd.plant.arm.Arm` against Pinocchio.

What is compared, on random states, with and without a payload (the payload is
appended to Pinocchio's model as a separate body at the payload frame, so the
check covers :meth:`Arm.sigma_with_payload` as well):

- the base-parameter model: ``regressor @ sigma`` against ``pin.rnea`` plus
  friction and armature, and ``mass_matrix`` against ``pin.crba`` plus armature;
- the compiled kernels of :mod:`adaptive_dd.plant.chain`: ``rnea``,
  ``mass_matrix``, ``coriolis_matrix``, ``forward_dynamics``, ``regressor``,
  ``slotine_li_regressor``, ``body_regressor`` against ``rnea``, ``crba``,
  ``computeCoriolisMatrix``, ``aba``, ``computeJointTorqueRegressor``;
- M positive definite.

``adaptive-dd check --arm FILE`` prints these lines.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from adaptive_dd.plant.arm import Arm, payload_parameters
from adaptive_dd.plant.pinocchio_model import (
    CheckResult,
    positive_definite_check,
    random_states,
    relative_error,
    stack_states,
)

__all__ = ["cross_check", "loaded_model"]


def loaded_model(arm: Arm, payload: dict | None):
    """The arm's Pinocchio model with the payload (keyword arguments of
    :func:`payload_parameters`: mass, com, inertia, radius) appended as a body."""
    model = arm.model.copy()
    if payload and payload.get("mass", 0.0) > 0:
        kw = {"radius": arm.payload_radius, **payload}
        pp = payload_parameters(kw["mass"], kw.get("com"), kw.get("inertia"), kw["radius"])
        link, placement = arm._payload_frame
        model.appendBodyToJoint(link + 1, pin.Inertia.FromDynamicParameters(pp), placement)
    return model


def _pinocchio_references(arm: Arm, model, q, qd, qdd, tau) -> dict[str, np.ndarray]:
    """Pinocchio's rnea, crba (symmetrised), Coriolis matrix, gravity, forward dynamics with
    the arm's armature (a crba/rnea solve) and joint-torque regressor on every state."""
    n = arm.n_joints
    data = model.createData()

    def one(i):
        qp = arm.pin_configuration(q[i])
        M = pin.crba(model, data, qp)
        crba = np.triu(M) + np.triu(M, 1).T
        return {
            "rnea": pin.rnea(model, data, qp, qd[i], qdd[i]).copy(),
            "crba": crba,
            "C": pin.computeCoriolisMatrix(model, data, qp, qd[i]).copy(),
            "g": pin.rnea(model, data, qp, np.zeros(n), np.zeros(n)).copy(),
            "aba": np.linalg.solve(
                crba + np.diag(arm.armature), tau[i] - pin.rnea(model, data, qp, qd[i], np.zeros(n))
            ),
            "Y": pin.computeJointTorqueRegressor(model, data, qp, qd[i], qdd[i]).copy(),
        }

    return stack_states(len(q), one)


def _compiled_outputs(arm: Arm, pi, q, qd, qdd, tau) -> dict[str, np.ndarray]:
    """The compiled kernels of :mod:`adaptive_dd.plant.chain` on every state (reference
    velocity ``qd / 2`` for ``slotine_li_regressor`` and ``rnea_ref``; ``body_regressor`` of
    the last link)."""
    from adaptive_dd.plant import chain as ck

    # a writable copy of the armature: the arm's own is read-only, and forward_dynamics compiled
    # for a read-only array is another specialisation than everyone else's (5.5 CPU s once more)
    n, ch, ia = arm.n_joints, arm.chain, np.array(arm.armature, dtype=float)

    def one(i):
        out_n, out_nn, out_y, out_b = np.empty(n), np.empty((n, n)), np.empty((n, 10 * n)), np.empty((n, 10))
        row = {}
        ck.rnea(ch, pi, q[i], qd[i], qdd[i], out_n)
        row["rnea"] = out_n.copy()
        ck.mass_matrix(ch, pi, q[i], out_nn)
        row["crba"] = out_nn.copy()
        ck.coriolis_matrix(ch, pi, q[i], qd[i], out_nn)
        row["C"] = out_nn.copy()
        ck.forward_dynamics(ch, pi, ia, q[i], qd[i], tau[i], out_n)
        row["aba"] = out_n.copy()
        ck.regressor(ch, q[i], qd[i], qdd[i], out_y)
        row["Y"] = out_y.copy()
        ck.slotine_li_regressor(ch, q[i], qd[i], qd[i] * 0.5, qdd[i], out_y)
        row["Ysl"] = out_y @ pi
        ck.rnea_ref(ch, pi, q[i], qd[i], qd[i] * 0.5, qdd[i], out_n)
        row["rnea_ref"] = out_n.copy()
        ck.body_regressor(ch, n - 1, q[i], qd[i], qdd[i], out_b)
        row["body"] = out_b.copy()
        return row

    return stack_states(len(q), one)


def _comparisons(arm: Arm, sigma, q, qd, qdd, ref: dict, mine: dict) -> list[tuple[str, object, object]]:
    """``(name, ours, reference)`` of every comparison of the module docstring."""
    ia = arm.armature
    fric = arm.viscous * qd + arm.coulomb * np.sign(qd)
    sl_ref = (
        np.einsum("sij,sj->si", ref["crba"], qdd) + np.einsum("sij,sj->si", ref["C"], 0.5 * qd) + ref["g"]
    )
    return [
        (
            "regressor @ sigma vs pin.rnea + friction + armature",
            np.einsum("sij,j->si", arm.regressor(q, qd, qdd), sigma),
            ref["rnea"] + fric + ia * qdd,
        ),
        ("mass_matrix(sigma) vs pin.crba + armature", arm.mass_matrix(q, sigma), ref["crba"] + np.diag(ia)),
        ("compiled rnea vs pin.rnea", mine["rnea"], ref["rnea"]),
        ("compiled mass_matrix vs pin.crba", mine["crba"], ref["crba"]),
        ("compiled coriolis_matrix vs pin.computeCoriolisMatrix", mine["C"], ref["C"]),
        ("compiled forward_dynamics vs crba/rnea solve (armature)", mine["aba"], ref["aba"]),
        ("compiled regressor vs pin.computeJointTorqueRegressor", mine["Y"], ref["Y"]),
        ("compiled slotine_li_regressor @ pi vs crba qdd_r + C qd_r + g", mine["Ysl"], sl_ref),
        ("compiled rnea_ref vs crba qdd_r + C qd_r + g", mine["rnea_ref"], sl_ref),
        ("compiled body_regressor (last link) vs regressor columns", mine["body"], ref["Y"][:, :, -10:]),
    ]


def cross_check(
    arm: Arm,
    payload: dict | None = None,
    n_states: int = 50,
    rng: np.random.Generator | None = None,
    tol: float = 1e-9,
) -> list[CheckResult]:
    """Compare the arm's models and compiled kernels with Pinocchio (module docstring).

    Parameters
    ----------
    arm : Arm
    payload : dict, optional
        ``mass`` [kg] and optionally ``com`` (3,), ``inertia`` (6,), ``radius``.
    n_states : int
        Random states: q within the position limits (``+-pi`` where unbounded),
        qd in ``+-2`` rad/s, qdd in ``+-10`` rad/s^2.
    rng : numpy.random.Generator, optional
        Default seed 0.
    tol : float
        Tolerance of every comparison, relative to ``max(1, |reference|)``.
    """
    rng = np.random.default_rng(0) if rng is None else rng
    model = loaded_model(arm, payload)
    lim = arm.position_limits
    lo = np.where(np.isfinite(lim[:, 0]), lim[:, 0], -np.pi)
    hi = np.where(np.isfinite(lim[:, 1]), lim[:, 1], np.pi)
    q, qd, qdd, tau = random_states(rng, lo, hi, n_states, arm.n_joints, 2, 10, 10)
    sigma = arm.sigma if not payload else arm.sigma_with_payload(**{"radius": arm.payload_radius, **payload})
    pi = np.concatenate([model.inertias[i].toDynamicParameters() for i in range(1, model.njoints)])
    ref = _pinocchio_references(arm, model, q, qd, qdd, tau)
    mine = _compiled_outputs(arm, pi, q, qd, qdd, tau)
    comparisons = _comparisons(arm, sigma, q, qd, qdd, ref, mine)
    out = [CheckResult(name, relative_error(a, b), tol) for name, a, b in comparisons]
    if not arm.armature.any():
        data = model.createData()
        aba = np.array(
            [pin.aba(model, data, arm.pin_configuration(q[i]), qd[i], tau[i]) for i in range(n_states)]
        )
        out.append(CheckResult("compiled forward_dynamics vs pin.aba", relative_error(mine["aba"], aba), tol))
    return [*out, positive_definite_check(ref["crba"] + np.diag(arm.armature))]
