"""Random serial chains as Pinocchio models, shared by the chain and serial-plant tests."""

from __future__ import annotations

import numpy as np
import pinocchio as pin


def _random_rotation(rng: np.random.Generator) -> np.ndarray:
    qr, r = np.linalg.qr(rng.normal(size=(3, 3)))
    qr = qr * np.sign(np.diag(r))
    return qr if np.linalg.det(qr) > 0 else -qr


def _random_inertia(rng: np.random.Generator) -> pin.Inertia:
    """Positive mass, principal moments from positive second moments (strict triangle inequality)."""
    mass = rng.uniform(0.2, 5.0)
    com = rng.uniform(-0.4, 0.4, size=3)
    second = mass * rng.uniform(0.001, 0.05, size=3)  # sum m x^2, sum m y^2, sum m z^2 about the com
    principal = np.array([second[1] + second[2], second[0] + second[2], second[0] + second[1]])
    rot = _random_rotation(rng)
    return pin.Inertia(mass, com, rot @ np.diag(principal) @ rot.T)


def _unit_axis(rng: np.random.Generator) -> np.ndarray:
    a = rng.normal(size=3)
    return a / np.linalg.norm(a)


_JOINT_MAKERS = (
    lambda rng: pin.JointModelRX(),
    lambda rng: pin.JointModelRY(),
    lambda rng: pin.JointModelRZ(),
    lambda rng: pin.JointModelRevoluteUnaligned(*_unit_axis(rng)),
    lambda rng: pin.JointModelRUBX(),
    lambda rng: pin.JointModelRUBZ(),
    lambda rng: pin.JointModelPX(),
    lambda rng: pin.JointModelPZ(),
    lambda rng: pin.JointModelPrismaticUnaligned(*_unit_axis(rng)),
)


def random_chain_model(n: int, rng: np.random.Generator) -> pin.Model:
    """A serial chain of n joints of mixed types, random placements, inertias and gravity."""
    model = pin.Model()
    model.name = f"random_chain_{n}"
    g = rng.normal(size=3)
    model.gravity.linear = rng.uniform(1.0, 12.0) * g / np.linalg.norm(g)
    parent = 0
    for i in range(n):
        joint = _JOINT_MAKERS[rng.integers(len(_JOINT_MAKERS))](rng)
        placement = pin.SE3(_random_rotation(rng), rng.uniform(-0.5, 0.5, size=3))
        parent = model.addJoint(parent, joint, placement, f"joint{i}")
        body_placement = pin.SE3(_random_rotation(rng), rng.uniform(-0.2, 0.2, size=3))
        model.appendBodyToJoint(parent, _random_inertia(rng), body_placement)
    return model
