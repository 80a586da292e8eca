"""The checks an :class:`~adaptive_dd.plant.arm.Arm`'s fields pass when it is made: each error
names the field, what it must be and the value given."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.errors import ParameterError
from adaptive_dd.errors import is_finite_number as _is_num

MAX_CAPACITY = 50.0
"""[kg] the largest ``payload_capacity`` of an arm: the largest payload mass a scenario takes
(``benchmark.scenario_base.LIMITS["max_mass"]``)."""

FRICTION_LAWS = ("stick-slip", "tanh", "stribeck", "lugre")
"""Plant friction laws (the index is the integrator's code)."""


def _vec(name: str, v, n: int, lo: float = 0.0) -> NDArray[np.float64]:
    a = np.array(v, dtype=float).reshape(-1)
    if a.shape != (n,) or not np.all(np.isfinite(a)) or np.any(a < lo):
        raise ParameterError(f"Arm.{name} must be {n} finite values >= {lo:g}, got {v!r}")
    a.setflags(write=False)
    return a


def check_fields(arm) -> None:
    """Check and normalise ``arm``'s fields in place (a frozen dataclass: ``object.__setattr__``);
    raise :class:`~adaptive_dd.errors.ParameterError` naming the first bad one."""
    object.__setattr__(arm, "urdf", Path(arm.urdf))
    n = len(arm.joint_names)
    if n < 1:
        raise ParameterError("Arm needs at least one joint")
    g = np.array(arm.gravity, dtype=float)
    if g.shape != (3,) or not np.all(np.isfinite(g)) or np.linalg.norm(g) > 100:
        raise ParameterError(
            f"Arm.gravity must be 3 finite numbers of norm <= 100 m/s^2, got {arm.gravity!r}"
        )
    g.setflags(write=False)
    object.__setattr__(arm, "gravity", g)
    for name in ("viscous", "coulomb", "armature"):
        object.__setattr__(arm, name, _vec(name, getattr(arm, name), n))
    lim = np.array(arm.position_limits, dtype=float)
    if lim.shape != (n, 2) or np.any(np.isnan(lim)) or np.any(lim[:, 0] >= lim[:, 1]):
        raise ParameterError(f"Arm.position_limits must be (n, 2) with lower < upper, got {lim!r}")
    lim.setflags(write=False)
    object.__setattr__(arm, "position_limits", lim)
    vel = np.array(arm.velocity_limits, dtype=float)
    if vel.shape != (n,) or np.any(np.isnan(vel)) or np.any(vel <= 0):
        raise ParameterError(f"Arm.velocity_limits must be {n} values > 0, got {vel!r}")
    vel.setflags(write=False)
    object.__setattr__(arm, "velocity_limits", vel)
    if len(arm.actuator.torque_limit) != n or len(arm.sensor.encoder_counts) != n:
        raise ParameterError(
            f"Arm: actuator and sensor must have {n} joints, got "
            f"{len(arm.actuator.torque_limit)} and {len(arm.sensor.encoder_counts)}"
        )
    if not (math.isfinite(arm.payload_radius) and 0 <= arm.payload_radius <= 10):
        raise ParameterError(f"Arm.payload_radius must be in [0, 10] m, got {arm.payload_radius!r}")
    if not (math.isfinite(arm.payload_offset) and 0 <= arm.payload_offset <= 10):
        raise ParameterError(f"Arm.payload_offset must be in [0, 10] m, got {arm.payload_offset!r}")
    cap = arm.payload_capacity
    if cap is not None and not (_is_num(cap) and 0 < cap <= MAX_CAPACITY):
        raise ParameterError(f"Arm.payload_capacity must be in (0, {MAX_CAPACITY:g}] kg or None, got {cap!r}")
    if arm.friction not in FRICTION_LAWS:
        raise ParameterError(f"Arm.friction must be one of {FRICTION_LAWS}, got {arm.friction!r}")
    for name in ("friction_velocity", "stribeck_velocity"):
        v = getattr(arm, name)
        if not (math.isfinite(v) and v > 0):
            raise ParameterError(f"Arm.{name} must be > 0, got {v!r}")
    if not isinstance(arm.general, bool):
        raise ParameterError(f"Arm.general must be True or False, got {arm.general!r}")
    for name, low in (("lugre_stiffness", 0.0), ("lugre_damping", -1.0)):
        v = getattr(arm, name)
        if v is None and name == "lugre_damping":
            continue
        a = np.array(v, dtype=float)
        a = np.broadcast_to(a, (n,)) if a.ndim == 0 else a
        if a.shape != (n,) or not (np.all(np.isfinite(a)) and np.all(a > low)):
            bound = "> 0" if low == 0.0 else ">= 0"
            raise ParameterError(f"Arm.{name} must be one value or {n}, finite and {bound}, got {v!r}")
        object.__setattr__(arm, name, tuple(float(x) for x in a))
    if not (math.isfinite(arm.stribeck_ratio) and arm.stribeck_ratio >= 1):
        raise ParameterError(f"Arm.stribeck_ratio must be >= 1, got {arm.stribeck_ratio!r}")
    object.__setattr__(arm, "_cache", {})
