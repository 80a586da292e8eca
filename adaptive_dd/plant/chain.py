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
  body velocity ``v_i = v_{i-1} + S_i qd_i``, and ``dS_i/dt = v_i x S_i``
  (:mod:`adaptive_dd.plant.spatial`);
* the dynamics (RNEA, the Slotine-Li torque, CRBA, Pinocchio's Coriolis matrix, the forward
  dynamics): :mod:`adaptive_dd.plant.chain_dynamics`;
* the regressors and the momentum form, linear in ``pi``: :mod:`adaptive_dd.plant.chain_regressor`;
* the batch wrappers: :mod:`adaptive_dd.plant.chain_batch`.

This module builds the :class:`Chain` from a Pinocchio model and re-exports every kernel, so
``from adaptive_dd.plant.chain import rnea`` works as before the split.

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
from numpy.typing import NDArray

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.plant.chain_batch import (
    coriolis_matrix_batch,
    forward_dynamics_batch,
    mass_matrix_batch,
    regressor_batch,
    rnea_batch,
    rnea_ref_batch,
    slotine_li_regressor_batch,
)
from adaptive_dd.plant.chain_dynamics import (
    bias_and_mass,
    coriolis_matrix,
    forward_dynamics,
    mass_matrix,
    mass_matrix_in,
    rnea,
    rnea_in,
    rnea_ref,
    rnea_ref_in,
    workspace,
)
from adaptive_dd.plant.chain_regressor import (
    body_regressor,
    body_regressor_in,
    body_slotine_li_regressor,
    body_slotine_li_regressor_in,
    momentum_form,
    momentum_form_in,
    momentum_in,
    regressor,
    rnea_body_regressor_in,
    slotine_li_regressor,
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
    "momentum_in",
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
