"""The arm's kernels a compiled plug-in calls: its adaptive law in a few lines over the arm's dynamics.

A compiled plug-in that declares ``needs = ("regressor",)`` writes its law over the kernels the
built-in adaptive laws use (``adaptive_dd.closed_loop.laws``), at the reference velocity and
acceleration of its own choosing. The loop hands ``command`` ``terms[3]``, the arm's kernels: a
tuple ``(ch, pi, payload_joint, payload_map, scratch...)`` of the model whose terms the plug-in
gets (the controllers' model, or for a plug-in that needs the true model the trial's plant in the
current segment); treat it as opaque and pass it to

* :func:`reference_torque`: ``Y(q, qd, qd_r, qdd_r) pi``, the model's torque with the Coriolis
  term at ``qd, qd_r`` (Slotine and Li's ``C(q, qd) qd_r``), friction at ``qd_r`` and the
  armature at ``qdd_r`` [N m];
* :func:`payload_regressor`: ``Y_p (n, 10)``, the same torque's derivative with respect to the
  payload's ten parameters about the payload frame (``m``, ``m c``, ``I``): what the built-in
  ``slotine_li`` adapts.

Both are ``numba.njit`` functions, compiled with the plug-in's loop (cached under its key: a later
run loads it; :mod:`adaptive_dd.closed_loop.plugin_loop`), over the cached dynamics kernels of
:mod:`adaptive_dd.plant.chain`. ``examples/plugins/slotine_li_plugin.py`` writes Slotine-Li with
them (``docs/own_controller.md``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.plant.chain import body_slotine_li_regressor_in, rnea_ref_in, workspace

__all__ = ["arm_kernels", "payload_regressor", "reference_torque"]


def _arm_kernels(ch, pi, payload_joint, payload_map):  # pragma: no cover - compiled
    """The kernels' tuple of the model ``pi (13 n,)`` (``[links, fv, fc, Ia]``) of chain ``ch``,
    its scratch allocated here (once per trial, never per sample)."""
    n = (pi.shape[0]) // 13
    return (ch, pi, payload_joint, payload_map, workspace(n), np.empty((6, 10)), np.empty((n, 10)))


def _with_model(kin, pi):  # pragma: no cover - compiled
    """``kin`` on the model ``pi`` (the same scratch): the loop's per-sample update."""
    return (kin[0], pi, kin[2], kin[3], kin[4], kin[5], kin[6])


def _reference_torque(kin, q, qd, qd_r, qdd_r, out):  # pragma: no cover - compiled
    """``Y(q, qd, qd_r, qdd_r) pi`` into ``out (n,)`` [N m]: ``rnea_ref(links, q, qd, qd_r, qdd_r)
    + fv qd_r + fc sgn(qd_r) + Ia qdd_r`` (the built-in laws' model torque at the reference
    velocity; ``q, qd, qd_r (n,)`` [rad, rad/s], ``qdd_r (n,)`` [rad/s^2])."""
    ch, pi, w = kin[0], kin[1], kin[4]
    n = q.shape[0]
    rnea_ref_in(ch, pi[: 10 * n], q, qd, qd_r, qdd_r, w, out)
    for j in range(n):
        out[j] += pi[10 * n + j] * qd_r[j] + pi[11 * n + j] * np.sign(qd_r[j]) + pi[12 * n + j] * qdd_r[j]


def _payload_regressor(kin, q, qd, qd_r, qdd_r, out):  # pragma: no cover - compiled
    """``Y_p = Y_j(q, qd, qd_r, qdd_r) P`` into ``out (n, 10)``: the payload link j's block of the
    Slotine-Li regressor times the payload map ``P`` (payload frame -> joint frame), so that a
    payload ``theta (10,)`` adds ``Y_p theta`` to :func:`reference_torque`."""
    ch, j, pmap, w, blk, yb = kin[0], kin[2], kin[3], kin[4], kin[5], kin[6]
    body_slotine_li_regressor_in(ch, j, q, qd, qd_r, qdd_r, w, blk, yb)
    for r in range(q.shape[0]):
        for k in range(10):
            acc = 0.0
            for c in range(10):
                acc += yb[r, c] * pmap[c, k]
            out[r, k] = acc


arm_kernels = njit(_arm_kernels)
with_model = njit(inline="always")(_with_model)
# no reference counting (numba's ``_nrt=False``): the built-in laws' kernels are compiled so, and
# with it a call of either costs the plug-in no update of the counts of the arrays it unpacks
reference_torque = njit(_nrt=False)(_reference_torque)
payload_regressor = njit(_nrt=False)(_payload_regressor)
