"""The tool frame's error streamed by the closed loop: forward kinematics at every sample of every trial.

The benchmark's per-seed end-effector figures (:mod:`~adaptive_dd.benchmark.end_effector`:
position RMS and peak [mm], orientation RMS [deg] per payload segment) come from three sums the
loop adds to at every sample, for every trial, next to the joint error's
(:class:`~adaptive_dd.closed_loop.types.StreamedSums`): ``ee_sum_p2`` (``|p(q_d) - p(q)|^2``
[m^2]), ``ee_max_p`` (its peak [m]) and ``ee_sum_th2`` (the squared angle of ``R(q_d)^T R(q)``
[rad^2]), ``q`` the true joint positions before the sample's step (the state the joint error
``e`` is taken on), so no trajectory has to be kept.

The kinematics are the tables :func:`tool_tables` reads from the arm's Pinocchio model (the
same product of joint placements and joint motions as
:func:`~adaptive_dd.benchmark.end_effector.frame_placements`, which
``tests/test_end_effector.py`` holds to Pinocchio's ``framePlacement``); the reference's
placements are computed once, before the run, by the same compiled kinematics.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

__all__ = ["ToolTables", "accumulate_tool", "no_tool", "tool_tables"]

REVOLUTE, PRISMATIC, FIXED = 0, 1, 2
"""Row kinds of :attr:`ToolTables.index`: a revolute or prismatic joint, or the tool frame
(a fixed placement on its parent joint)."""


class ToolTables(NamedTuple):
    """The arm's kinematics to the tool frame and the reference's placements (flat arrays, so
    that they pass as fields of :class:`~adaptive_dd.closed_loop.types.RunConstants`).

    Attributes
    ----------
    index : ndarray of int64 (R, 3)
        Per row ``(parent row, kind, q index)``: row 0 the base, rows ``1 .. R - 2`` the joints
        in Pinocchio's order (a parent before its children), row ``R - 1`` the tool frame. No
        rows: the tool frame's error is not computed.
    links : ndarray (R, 15)
        Per row: the placement on the parent at ``q = 0`` (rotation, row-major, 9; translation
        [m], 3) and the joint's unit axis (3).
    ref : ndarray (N, 12)
        The tool frame's placement at the reference of every sample: rotation (row-major, 9) and
        position [m] (3).
    """

    index: NDArray[np.int64]
    links: NDArray[np.float64]
    ref: NDArray[np.float64]


def no_tool(N: int = 0) -> ToolTables:
    """Tables with no rows: the loop leaves the tool frame's sums at zero."""
    return ToolTables(np.zeros((0, 3), np.int64), np.zeros((0, 15)), np.zeros((N, 12)))


def tool_tables(arm, q_d: NDArray[np.float64]) -> ToolTables:
    """The :class:`ToolTables` of ``arm``'s tool frame (``arm.payload_frame``) along ``q_d (N, n)``.

    Parameters
    ----------
    arm : Arm
        Any arm of revolute and prismatic joints (its Pinocchio ``model``).
    q_d : ndarray (N, n)
        The reference at every sample [rad or m].

    Returns
    -------
    ToolTables
    """
    from adaptive_dd.benchmark.end_effector import _joint_motion

    model = arm.model
    J = model.njoints
    index = np.zeros((J + 1, 3), np.int64)
    links = np.zeros((J + 1, 15))
    links[0, [0, 4, 8]] = 1.0
    for r in range(1, J):
        kind, axis = _joint_motion(arm, r)
        place = model.jointPlacements[r]
        index[r] = (model.parents[r], REVOLUTE if kind == "R" else PRISMATIC, model.joints[r].idx_v)
        links[r] = np.concatenate((place.rotation.ravel(), place.translation, axis))
    from adaptive_dd.plant.urdf import frame_id

    f = model.frames[frame_id(model, arm.payload_frame)]
    index[J] = (f.parentJoint, FIXED, 0)
    links[J, :12] = np.concatenate((f.placement.rotation.ravel(), f.placement.translation))
    ref = np.empty((q_d.shape[0], 12))
    _reference_placements(index, links, np.ascontiguousarray(q_d, dtype=float), ref)
    return ToolTables(index, links, ref)


@njit(cache=True, inline="always")
def _placements(index, links, q, w, r0):  # pragma: no cover - compiled
    """Each row's placement at the joint positions ``q (n,)`` into ``w (R, 12)`` (rotation
    row-major, 9; position [m], 3): the tool frame's in the last row; ``r0 (9,)`` scratch."""
    rows = index.shape[0]
    for a in range(12):
        w[0, a] = links[0, a]
    for r in range(1, rows):
        par = index[r, 0]
        # the row's frame at q = 0: R0 = R_parent rot, p0 = p_parent + R_parent pos
        for a in range(3):
            pa = w[par, 9 + a]
            for b in range(3):
                pa += w[par, 3 * a + b] * links[r, 9 + b]
                t = 0.0
                for c in range(3):
                    t += w[par, 3 * a + c] * links[r, 3 * c + b]
                r0[3 * a + b] = t
            w[r, 9 + a] = pa
        kind = index[r, 1]
        if kind == 0:  # revolute: R = R0 (cos I + sin [u]x + (1 - cos) u u^T)
            x = q[index[r, 2]]
            cs, sn = np.cos(x), np.sin(x)
            u0, u1, u2 = links[r, 12], links[r, 13], links[r, 14]
            m00, m11, m22 = cs + (1 - cs) * u0 * u0, cs + (1 - cs) * u1 * u1, cs + (1 - cs) * u2 * u2
            m01, m10 = (1 - cs) * u0 * u1 - sn * u2, (1 - cs) * u0 * u1 + sn * u2
            m02, m20 = (1 - cs) * u0 * u2 + sn * u1, (1 - cs) * u0 * u2 - sn * u1
            m12, m21 = (1 - cs) * u1 * u2 - sn * u0, (1 - cs) * u1 * u2 + sn * u0
            for a in range(3):
                ra0, ra1, ra2 = r0[3 * a], r0[3 * a + 1], r0[3 * a + 2]
                w[r, 3 * a] = ra0 * m00 + ra1 * m10 + ra2 * m20
                w[r, 3 * a + 1] = ra0 * m01 + ra1 * m11 + ra2 * m21
                w[r, 3 * a + 2] = ra0 * m02 + ra1 * m12 + ra2 * m22
        else:
            for a in range(9):
                w[r, a] = r0[a]
            if kind == 1:  # prismatic: p = p0 + R0 u q
                x = q[index[r, 2]]
                for a in range(3):
                    w[r, 9 + a] += (r0[3 * a] * links[r, 12] + r0[3 * a + 1] * links[r, 13]
                                    + r0[3 * a + 2] * links[r, 14]) * x  # fmt: skip


@njit(cache=True)
def _reference_placements(index, links, q_d, out):  # pragma: no cover - compiled
    """The tool frame's placement at each sample of ``q_d (N, n)`` into ``out (N, 12)``
    (:attr:`ToolTables.ref`), by the loop's own kinematics (:func:`_placements`)."""
    rows = index.shape[0]
    if rows == 0:  # no tool frame (:func:`no_tool`'s tables): nothing to place
        return
    w, r0 = np.empty((rows, 12)), np.empty(9)
    for k in range(q_d.shape[0]):
        _placements(index, links, q_d[k], w, r0)
        for a in range(12):
            out[k, a] = w[rows - 1, a]


@njit(cache=True, inline="always")
def accumulate_tool(
    index, links, ref, ee_sum_p2, ee_max_p, ee_sum_th2, i, s, k, q, w, r0
):  # pragma: no cover - compiled
    """Add sample k (segment s) of trial i, true joint positions ``q (n,)``, to the tool frame's
    sums ``ee_sum_p2, ee_max_p, ee_sum_th2 (S, G)`` (module docstring); ``index, links, ref`` a
    :class:`ToolTables`; ``w (max(R, 1), 12), r0 (9,)`` scratch."""
    rows = index.shape[0]
    if rows == 0:
        return
    _placements(index, links, q, w, r0)
    t = rows - 1
    d2 = 0.0
    for a in range(3):
        d = ref[k, 9 + a] - w[t, 9 + a]
        d2 += d * d
    # the angle of R_d^T R from its skew part and its trace (as end_effector.rotation_angle)
    rel = r0  # reused: the rows are done
    for a in range(3):
        for b in range(3):
            v = 0.0
            for c in range(3):
                v += ref[k, 3 * c + a] * w[t, 3 * c + b]
            rel[3 * a + b] = v
    wx, wy, wz = rel[7] - rel[5], rel[2] - rel[6], rel[3] - rel[1]
    th = np.arctan2(0.5 * np.sqrt(wx * wx + wy * wy + wz * wz), 0.5 * (rel[0] + rel[4] + rel[8] - 1.0))
    ee_sum_p2[i, s] += d2
    dn = np.sqrt(d2)
    if dn > ee_max_p[i, s]:
        ee_max_p[i, s] = dn
    ee_sum_th2[i, s] += th * th
