"""A payload as a rigid body: its ten inertial parameters (:func:`payload_parameters`) and what an
estimate of an arm's base parameters says of it (:class:`PayloadEstimate`,
:meth:`Arm.payload_from_sigma <adaptive_dd.plant.arm.Arm.payload_from_sigma>`).

The ten parameters about the payload frame's origin, in Pinocchio's order: ``m, m c_x, m c_y,
m c_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz`` (the inertia about the origin, parallel-axis theorem).
Also importable from :mod:`adaptive_dd.plant.arm`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError

__all__ = ["PayloadEstimate", "payload_parameters"]

Array = NDArray[np.float64]


def payload_parameters(
    mass: float, com: ArrayLike | None = None, inertia: ArrayLike | None = None, radius: float = 0.0
) -> Array:
    """The ten inertial parameters of a rigid body about its frame's origin, ``(10,)``.

    Parameters
    ----------
    mass : float
        [kg], >= 0.
    com : array_like (3,), optional
        Centre of mass in the body frame [m] (default the origin).
    inertia : array_like (6,) or (3, 3), optional
        Inertia about the centre of mass ``[ixx, iyy, izz, ixy, ixz, iyz]`` [kg m^2];
        default a disk of ``radius`` about the frame's z axis.
    radius : float
        Disk radius [m] when ``inertia`` is not given.

    Returns
    -------
    ndarray, shape (10,)
        ``[m, m cx, m cy, m cz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]`` about the frame's origin
        (Pinocchio's order) [kg, kg m, kg m^2].

    Examples
    --------
    >>> from adaptive_dd.plant.payload import payload_parameters
    >>> payload_parameters(2.0, com=[0.0, 0.0, 0.05]).round(4)
    array([2.   , 0.   , 0.   , 0.1  , 0.005, 0.   , 0.005, 0.   , 0.   , 0.   ])
    """
    m = float(mass)
    if not math.isfinite(m) or m < 0:
        raise ParameterError(f"payload mass must be finite and >= 0 kg, got {mass!r}")
    c = np.zeros(3) if com is None else np.asarray(com, dtype=float)
    if c.shape != (3,) or not np.all(np.isfinite(c)):
        raise ParameterError(f"payload com must be 3 finite numbers [m], got {com!r}")
    if inertia is None:
        r2 = float(radius) ** 2
        Ic = m * np.diag([r2 / 4, r2 / 4, r2 / 2])
    else:
        v = np.asarray(inertia, dtype=float)
        if v.shape == (6,):
            ixx, iyy, izz, ixy, ixz, iyz = v
            Ic = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
        elif v.shape == (3, 3):
            Ic = v
        else:
            raise ParameterError(f"payload inertia must be [ixx, iyy, izz, ixy, ixz, iyz], got {inertia!r}")
        lam = np.linalg.eigvalsh(0.5 * (Ic + Ic.T))
        if not np.all(np.isfinite(lam)) or lam[0] < -1e-12 or lam[2] > lam[0] + lam[1] + 1e-12:
            raise ParameterError(
                f"payload inertia {v.tolist()} is not a rigid body's (principal moments {lam.tolist()}: "
                "each must be >= 0 and at most the sum of the other two)"
            )
    Io = Ic + m * (c @ c * np.eye(3) - np.outer(c, c))
    return np.array([m, *(m * c), Io[0, 0], Io[0, 1], Io[1, 1], Io[0, 2], Io[1, 2], Io[2, 2]])


class PayloadEstimate(NamedTuple):
    """A payload recovered from base parameters (:meth:`Arm.payload_from_sigma`).

    Attributes
    ----------
    mass : ndarray
        [kg].
    com : ndarray, shape (..., 3)
        Centre of mass [m] in the payload frame (nan where not identifiable).
    params : ndarray, shape (..., 10)
        Least-squares parameters about the frame origin.
    identifiable : ndarray of bool, shape (10,)
        Which of the ten the base parameters determine.

    Examples
    --------
    >>> import numpy as np
    >>> from adaptive_dd.plant import Arm
    >>> from adaptive_dd.robots import robot_urdf
    >>> ur5 = Arm.from_urdf(robot_urdf("ur5"))
    >>> est = ur5.payload_from_sigma(ur5.sigma_with_payload(2.0, com=[0.0, 0.04, 0.0]))
    >>> float(est.mass.round(6)), (est.com.round(6) + 0.0).tolist()
    (2.0, [0.0, 0.04, 0.0])
    """

    mass: Array
    com: Array
    params: Array
    identifiable: NDArray[np.bool_]
