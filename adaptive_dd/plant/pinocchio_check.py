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
from adaptive_dd.plant.pinocchio_model import CheckResult

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


def _rel(a, b) -> float:
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))) / max(1.0, float(np.max(np.abs(b)))))


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
    from adaptive_dd.plant import chain as ck

    rng = np.random.default_rng(0) if rng is None else rng
    n = arm.n_joints
    model = loaded_model(arm, payload)
    data = model.createData()
    lim = arm.position_limits
    lo = np.where(np.isfinite(lim[:, 0]), lim[:, 0], -np.pi)
    hi = np.where(np.isfinite(lim[:, 1]), lim[:, 1], np.pi)
    q = rng.uniform(lo, hi, (n_states, n))
    qd = rng.uniform(-2, 2, (n_states, n))
    qdd = rng.uniform(-10, 10, (n_states, n))
    tau = rng.uniform(-10, 10, (n_states, n))
    sigma = arm.sigma if not payload else arm.sigma_with_payload(**{"radius": arm.payload_radius, **payload})
    ch = arm.chain
    pi = np.concatenate([model.inertias[i].toDynamicParameters() for i in range(1, model.njoints)])
    ia = arm.armature
    fric = arm.viscous * qd + arm.coulomb * np.sign(qd)

    names = ("rnea", "crba", "C", "aba", "Y", "g")
    ref = {k: [] for k in names}
    mine = {k: [] for k in (*names, "Ysl", "body", "rnea_ref")}
    for i in range(n_states):
        qp = arm.pin_configuration(q[i])
        ref["rnea"].append(pin.rnea(model, data, qp, qd[i], qdd[i]).copy())
        M = pin.crba(model, data, qp)
        ref["crba"].append(np.triu(M) + np.triu(M, 1).T)
        ref["C"].append(pin.computeCoriolisMatrix(model, data, qp, qd[i]).copy())
        ref["g"].append(pin.rnea(model, data, qp, np.zeros(n), np.zeros(n)).copy())
        Mi = ref["crba"][-1] + np.diag(ia)
        ref["aba"].append(np.linalg.solve(Mi, tau[i] - pin.rnea(model, data, qp, qd[i], np.zeros(n))))
        ref["Y"].append(pin.computeJointTorqueRegressor(model, data, qp, qd[i], qdd[i]).copy())
        out_n, out_nn, out_y = np.empty(n), np.empty((n, n)), np.empty((n, 10 * n))
        ck.rnea(ch, pi, q[i], qd[i], qdd[i], out_n)
        mine["rnea"].append(out_n.copy())
        ck.mass_matrix(ch, pi, q[i], out_nn)
        mine["crba"].append(out_nn.copy())
        ck.coriolis_matrix(ch, pi, q[i], qd[i], out_nn)
        mine["C"].append(out_nn.copy())
        ck.forward_dynamics(ch, pi, ia, q[i], qd[i], tau[i], out_n)
        mine["aba"].append(out_n.copy())
        ck.regressor(ch, q[i], qd[i], qdd[i], out_y)
        mine["Y"].append(out_y.copy())
        ck.slotine_li_regressor(ch, q[i], qd[i], qd[i] * 0.5, qdd[i], out_y)
        mine["Ysl"].append(out_y @ pi)
        ck.rnea_ref(ch, pi, q[i], qd[i], qd[i] * 0.5, qdd[i], out_n)
        mine["rnea_ref"].append(out_n.copy())
        j = n - 1
        out_b = np.empty((n, 10))
        ck.body_regressor(ch, j, q[i], qd[i], qdd[i], out_b)
        mine["body"].append(out_b.copy())
    ref = {k: np.array(v) for k, v in ref.items()}
    mine = {k: np.array(v) for k, v in mine.items()}
    sl_ref = (
        np.einsum("sij,sj->si", ref["crba"], qdd) + np.einsum("sij,sj->si", ref["C"], 0.5 * qd) + ref["g"]
    )
    full = ref["rnea"] + fric + ia * qdd
    out = [
        CheckResult(
            "regressor @ sigma vs pin.rnea + friction + armature",
            _rel(arm.inverse_dynamics(q, qd, qdd, sigma), full),
            tol,
        ),
        CheckResult(
            "mass_matrix(sigma) vs pin.crba + armature",
            _rel(arm.mass_matrix(q, sigma), ref["crba"] + np.diag(ia)),
            tol,
        ),
        CheckResult("compiled rnea vs pin.rnea", _rel(mine["rnea"], ref["rnea"]), tol),
        CheckResult("compiled mass_matrix vs pin.crba", _rel(mine["crba"], ref["crba"]), tol),
        CheckResult("compiled coriolis_matrix vs pin.computeCoriolisMatrix", _rel(mine["C"], ref["C"]), tol),
        CheckResult(
            "compiled forward_dynamics vs crba/rnea solve (armature)", _rel(mine["aba"], ref["aba"]), tol
        ),
        CheckResult("compiled regressor vs pin.computeJointTorqueRegressor", _rel(mine["Y"], ref["Y"]), tol),
        CheckResult(
            "compiled slotine_li_regressor @ pi vs crba qdd_r + C qd_r + g", _rel(mine["Ysl"], sl_ref), tol
        ),
        CheckResult("compiled rnea_ref vs crba qdd_r + C qd_r + g", _rel(mine["rnea_ref"], sl_ref), tol),
        CheckResult(
            "compiled body_regressor (last link) vs regressor columns",
            _rel(mine["body"], ref["Y"][:, :, -10:]),
            tol,
        ),
    ]
    if not arm.armature.any():
        aba = np.array(
            [pin.aba(model, data, arm.pin_configuration(q[i]), qd[i], tau[i]) for i in range(n_states)]
        )
        out.append(CheckResult("compiled forward_dynamics vs pin.aba", _rel(mine["aba"], aba), tol))
    eig = np.linalg.eigvalsh(ref["crba"] + np.diag(ia))
    out.append(CheckResult("M positive definite: -min eigenvalue / max", float(-eig.min() / eig.max()), 0.0))
    return out
