"""The tool frame's error: forward kinematics of recorded joint trajectories, per segment.

The benchmark judges tracking on the joints (``|q_d - q|`` [rad]); manipulation papers report
the end-effector's error in millimetres (Nakanishi et al., "Operational Space Control: A
Theoretical and Empirical Comparison", IJRR 2008). Here the tool frame (the arm's
``payload_frame``, e.g. the UR5's ``tool0``) is placed by forward kinematics at the true joint
angles ``q`` and at the reference ``q_d``, sample by sample, and per payload segment:

ee_position_rms [mm]
    ``sqrt(mean |p(q_d) - p(q)|^2)``, ``p`` the frame's origin in the base frame.
ee_position_max [mm]
    ``max |p(q_d) - p(q)|``.
ee_orientation_rms [deg]
    ``sqrt(mean theta^2)``, ``theta`` the angle of the rotation ``R(q_d)^T R(q)`` (the geodesic
    distance on SO(3)). On a planar arm (the paper's two-link arm) it is the error of the tip's
    angle about the plane's normal, ``|e1 + e2|``.

In a benchmark run the closed loop streams these figures for every seed, keeping no trajectory
(:mod:`~adaptive_dd.closed_loop.tool_frame`: the same product of placements, sample by sample);
:func:`end_effector_errors` computes them from trajectories (a policy's episodes, a recorded
trial), and ``tests/test_end_effector.py`` holds the two to each other.

:func:`frame_placements` is a vectorised product of the joints' placements (Pinocchio's
``jointPlacements`` and joint axes), held to Pinocchio's ``framePlacement`` by
``tests/test_end_effector.py``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError

__all__ = ["EE_KEYS", "end_effector_errors", "frame_placements", "rotation_angle"]

Array = NDArray[np.float64]

EE_KEYS = ("ee_position_rms", "ee_position_max", "ee_orientation_rms")
"""The per-seed, per-segment keys this module adds (units: mm, mm, deg)."""


def _joint_motion(arm, i: int) -> tuple[str, Array]:
    """``("R" or "P", unit axis (3,))`` of joint ``i`` (Pinocchio's index, 1-based) of ``arm``, from
    the arm's :class:`~adaptive_dd.plant.chain.Chain` (its motion subspace, for every joint type
    the chain accepts: aligned, unaligned, continuous, prismatic)."""
    from adaptive_dd.plant.chain import REVOLUTE

    ch = arm.chain
    return ("R" if ch.jtype[i - 1] == REVOLUTE else "P"), np.asarray(ch.axis[i - 1], dtype=float)


def _axis_rotation(axis: Array, angle: Array) -> Array:
    """Rodrigues' rotation about the unit ``axis (3,)`` by ``angle (...)`` -> ``(..., 3, 3)``."""
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    s, c = np.sin(angle)[..., None, None], np.cos(angle)[..., None, None]
    return np.eye(3) + s * k + (1 - c) * (k @ k)


def frame_placements(arm, q: ArrayLike, frame: str | None = None) -> tuple[Array, Array]:
    """Placement of a frame of the arm in the base frame at joint positions ``q (..., n)``.

    Parameters
    ----------
    arm : Arm
        Any arm (its Pinocchio ``model``).
    q : array_like (..., n)
        Joint positions [rad or m], one per joint (continuous joints as angles).
    frame : str, optional
        A frame of the model; default the tool frame, ``arm.payload_frame``.

    Returns
    -------
    position : ndarray (..., 3)
        The frame's origin [m].
    rotation : ndarray (..., 3, 3)
        Its orientation (columns: the frame's axes in the base frame).
    """
    model = arm.model
    name = arm.payload_frame if frame is None else frame
    if not model.existFrame(name):
        raise ParameterError(f"{arm.urdf}: frame {name!r} is not in the model; give one of its links")
    q = np.asarray(q, dtype=float)
    n = model.njoints - 1
    if q.shape[-1:] != (n,):
        raise ParameterError(f"frame_placements: q must have shape (..., {n}), got {q.shape}")
    batch = q.shape[:-1]
    rot = [np.broadcast_to(np.eye(3), (*batch, 3, 3))]
    pos = [np.zeros((*batch, 3))]
    for i in range(1, model.njoints):
        kind, axis = _joint_motion(arm, i)
        place = model.jointPlacements[i]
        parent = model.parents[i]
        r0 = rot[parent] @ place.rotation  # the joint's frame at q = 0
        p0 = pos[parent] + rot[parent] @ place.translation
        qi = q[..., model.joints[i].idx_v]
        if kind == "R":
            rot.append(r0 @ _axis_rotation(axis, qi))
            pos.append(p0)
        else:
            rot.append(r0)
            pos.append(p0 + (r0 @ axis) * qi[..., None])
    from adaptive_dd.plant.urdf import frame_id

    f = model.frames[frame_id(model, name)]
    j = f.parentJoint
    return pos[j] + rot[j] @ f.placement.translation, rot[j] @ f.placement.rotation


def rotation_angle(r_a: ArrayLike, r_b: ArrayLike) -> Array:
    """Angle [rad] of the rotation ``r_a^T r_b`` between two orientations ``(..., 3, 3)``."""
    r_a, r_b = np.asarray(r_a, float), np.asarray(r_b, float)
    rel = np.swapaxes(r_a, -1, -2) @ r_b
    # from the skew part and the trace: accurate near 0 and near pi (arccos alone is not near 0)
    w = np.stack(
        [rel[..., 2, 1] - rel[..., 1, 2], rel[..., 0, 2] - rel[..., 2, 0], rel[..., 1, 0] - rel[..., 0, 1]]
    )
    s = 0.5 * np.linalg.norm(w, axis=0)
    c = 0.5 * (np.trace(rel, axis1=-2, axis2=-1) - 1.0)
    return np.arctan2(s, c)


def end_effector_errors(arm, q: ArrayLike, q_d: ArrayLike, start, end) -> dict[str, Array]:
    """The tool frame's error per recorded trial and segment (module docstring).

    Parameters
    ----------
    arm : Arm
    q : array_like (K, N, n)
        The true joint positions of K recorded trials over N samples [rad].
    q_d : array_like (N, n)
        The reference at the same samples.
    start, end : array_like of int (G,)
        Each segment's first sample and one past its last.

    Returns
    -------
    dict
        :data:`EE_KEYS`, each ``(K, G)``: position RMS and peak [mm], orientation RMS [deg].
    """
    q, q_d = np.asarray(q, float), np.asarray(q_d, float)
    start, end = np.asarray(start, int), np.asarray(end, int)
    K, G = q.shape[0], start.size
    out = {k: np.full((K, G), np.nan) for k in EE_KEYS}
    if K == 0:
        return out
    p_d, r_d = frame_placements(arm, q_d)
    for i in range(K):  # one trial at a time: (N, 3, 3) work arrays
        ok = np.all(np.isfinite(q[i]), axis=-1)
        p, r = frame_placements(arm, np.where(ok[:, None], q[i], 0.0))
        dp = np.linalg.norm(p_d - p, axis=-1) * 1e3
        th = np.degrees(rotation_angle(r_d, r))
        for s, (a, b) in enumerate(zip(start, end, strict=True)):
            if b <= a or not ok[a:b].all():
                continue
            out["ee_position_rms"][i, s] = np.sqrt(np.mean(dp[a:b] ** 2))
            out["ee_position_max"][i, s] = dp[a:b].max()
            out["ee_orientation_rms"][i, s] = np.sqrt(np.mean(th[a:b] ** 2))
    return out
