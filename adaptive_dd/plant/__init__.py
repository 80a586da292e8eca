"""The arms: the paper's two-link direct-drive arm (:class:`Arm`, default the SICE arm: parameters,
closed-form dynamics, simulator, Pinocchio check) and any serial arm from a URDF
(:class:`SerialArm`, imported on first use: it loads Pinocchio)."""

from adaptive_dd.plant.arm import FRICTION_LAWS, Arm
from adaptive_dd.plant.devices import ActuatorConfig, SensorConfig
from adaptive_dd.plant.dynamics import (
    coriolis_matrix,
    coriolis_vector,
    forward_dynamics,
    friction,
    inverse_dynamics,
    mass_matrix,
    mass_matrix_entries,
    regressor,
    regressor_reference,
)
from adaptive_dd.plant.integrator import plant_step
from adaptive_dd.plant.parameters import (
    L1,
    L2,
    SIGMA_NAMES,
    TABLE1_PHYSICAL,
    TABLE1_SIGMA,
    TORQUE_LIMITS,
    Payload,
    PhysicalParameters,
    payload_mass_from_sigma,
    payload_sigma_delta,
    project_sigma,
    validate_sigma,
)
from adaptive_dd.plant.simulator import (
    ArmSimulator,
    PayloadSchedule,
    SimulationResult,
    simulate_open_loop,
)

__all__ = [
    "FRICTION_LAWS",
    "L1",
    "L2",
    "SIGMA_NAMES",
    "TABLE1_PHYSICAL",
    "TABLE1_SIGMA",
    "TORQUE_LIMITS",
    "ActuatorConfig",
    "Arm",
    "ArmSimulator",
    "Payload",
    "PayloadSchedule",
    "PhysicalParameters",
    "SensorConfig",
    "SerialArm",
    "SimulationResult",
    "coriolis_matrix",
    "coriolis_vector",
    "forward_dynamics",
    "friction",
    "inverse_dynamics",
    "mass_matrix",
    "mass_matrix_entries",
    "payload_mass_from_sigma",
    "payload_sigma_delta",
    "plant_step",
    "project_sigma",
    "regressor",
    "regressor_reference",
    "simulate_open_loop",
    "validate_sigma",
]


def __getattr__(name: str):
    """``SerialArm`` on first use (its module imports Pinocchio, which takes a second)."""
    if name == "SerialArm":
        from adaptive_dd.plant.serial_arm import SerialArm

        return SerialArm
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
