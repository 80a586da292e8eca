"""The paper's geometry read from an arm: whether an :class:`~adaptive_dd.plant.arm.Arm` is of it
(:func:`is_paper_geometry`: two revolute joints about parallel z axes, joint 2 on link 1's x axis,
centres of mass on the links' x axes, gravity along z, no armature, the payload frame on link 2's
x axis), its physical parameters of eq. (10) (:func:`physical_parameters`), and the linear map
from its base parameters onto the paper's ``sigma = [J1 J2 r b1 b2 d1 d2]`` (:func:`paper_map`).

What :func:`~adaptive_dd.plant.two_link.closed_form_view` and
:func:`~adaptive_dd.plant.two_link_view.paper_sigma` build on; reads the arm, never its class.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.plant import dynamics
from adaptive_dd.plant.parameters import PhysicalParameters

__all__ = ["equivalent_physical", "is_paper_geometry", "paper_map", "physical_parameters"]

Array = NDArray[np.float64]


def is_paper_geometry(arm, atol: float) -> bool:
    """Whether ``arm`` (an :class:`~adaptive_dd.plant.arm.Arm`) has the geometry of the paper's closed
    forms (:func:`~adaptive_dd.plant.two_link.as_two_link`), within ``atol``."""
    if arm.n_joints != 2 or np.any(arm.armature != 0) or arm.locked:
        return False
    m = arm.model
    for i in (1, 2):
        j = m.joints[i]
        if j.shortname() not in ("JointModelRZ", "JointModelRUBZ"):
            return False
        if not np.allclose(m.jointPlacements[i].rotation, np.eye(3), atol=atol):
            return False
    p2 = m.jointPlacements[2].translation
    if abs(p2[1]) > atol or p2[0] <= 0:
        return False
    if abs(arm.gravity[0]) > atol or abs(arm.gravity[1]) > atol:
        return False
    link, placement = arm._payload_frame
    pt = placement.translation
    if (
        link != 1
        or abs(pt[1]) > atol
        or pt[0] <= 0
        or not np.allclose(placement.rotation, np.eye(3), atol=atol)
    ):
        return False
    return not any(abs(m.inertias[i].lever[1]) > atol for i in (1, 2))


def physical_parameters(arm) -> PhysicalParameters:
    """The physical parameters (eq. 10) of an arm of the paper's geometry."""
    m = arm.model
    inert = [m.inertias[i] for i in (1, 2)]
    return PhysicalParameters(
        I1=float(inert[0].inertia[2, 2]),
        I2=float(inert[1].inertia[2, 2]),
        m1=float(inert[0].mass),
        m2=float(inert[1].mass),
        a1=float(inert[0].lever[0]),
        a2=float(inert[1].lever[0]),
        b1=float(arm.viscous[0]),
        b2=float(arm.viscous[1]),
        d1=float(arm.coulomb[0]),
        d2=float(arm.coulomb[1]),
        l1=float(m.jointPlacements[2].translation[0]),
        l2=float(arm._payload_frame[1].translation[0]),
    )


def paper_map(arm) -> Array:
    """``S (7, p)``: ``paper sigma = S @ sigma`` on an arm of the paper's geometry
    (:func:`~adaptive_dd.plant.two_link_view.paper_sigma`)."""

    def make():
        rng = np.random.default_rng(0)
        q, qd, qdd = (rng.uniform(-2.0, 2.0, (40, 2)) for _ in range(3))
        phi7 = dynamics.regressor(q, qd, qdd).reshape(-1, 7)
        phi = arm.regressor(q, qd, qdd).reshape(-1, len(arm.sigma))
        S, *_ = np.linalg.lstsq(phi7, phi, rcond=None)
        scale = np.linalg.norm(phi, axis=0)
        outside = np.linalg.norm(phi7 @ S - phi, axis=0) > 1e-9 * np.maximum(scale, 1.0)
        S[:, outside] = 0.0  # a direction the closed forms have no term for (my2, Ia2): zero on them
        S[np.abs(S) < 1e-12 * np.abs(S).max()] = 0.0
        return S

    return arm._cached("paper_map", make)


def equivalent_physical(sigma, l1: float, l2: float) -> PhysicalParameters:
    """Physical parameters (eq. 10) that map onto the paper's ``sigma (7,)`` with link lengths
    ``l1, l2`` [m]: ``a2 = l1 sqrt(J2 / J1)``, ``m2 = r / (l1 a2)``, ``I2 = J2 - m2 a2^2``,
    ``a1 = l1 / 2`` and ``m1 a1^2 = I1 = (J1 - m2 l1^2) / 2``, strictly inside the admissible set
    whenever ``J1 J2 > r^2``."""
    j1, j2, r, b1, b2, d1, d2 = (float(x) for x in sigma)
    a2 = l1 * math.sqrt(j2 / j1)
    m2 = r / (l1 * a2)
    rest = j1 - m2 * l1**2
    a1 = l1 / 2
    return PhysicalParameters(
        I1=rest / 2,
        I2=j2 - m2 * a2**2,
        m1=rest / (2 * a1**2),
        m2=m2,
        a1=a1,
        a2=a2,
        b1=b1,
        b2=b2,
        d1=d1,
        d2=d2,
        l1=l1,
        l2=l2,
    )
