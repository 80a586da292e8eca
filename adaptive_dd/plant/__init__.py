"""The arms: the paper's two-link direct-drive arm (:class:`TwoLinkArm`, default the SICE arm: parameters,
closed-form dynamics, simulator, Pinocchio check) and any serial arm from a URDF
(:class:`Arm`, imported on first use: it loads Pinocchio)."""

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
from adaptive_dd.plant.two_link import FRICTION_LAWS, TwoLinkArm
from adaptive_dd.plant.two_link_integrator import two_link_plant_step

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
    "SimulationResult",
    "TwoLinkArm",
    "coriolis_matrix",
    "coriolis_vector",
    "forward_dynamics",
    "friction",
    "inverse_dynamics",
    "mass_matrix",
    "mass_matrix_entries",
    "payload_mass_from_sigma",
    "payload_sigma_delta",
    "project_sigma",
    "regressor",
    "regressor_reference",
    "simulate_open_loop",
    "two_link_plant_step",
    "validate_sigma",
]


def __getattr__(name: str):
    """``Arm`` on first use (its module imports Pinocchio, which takes a second)."""
    if name == "Arm":
        from adaptive_dd.plant.arm import Arm

        return Arm
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
