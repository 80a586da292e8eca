"""The arm: :class:`Arm`, any serial arm from a URDF or the paper's (:meth:`Arm.sice`), imported on
first use (it loads Pinocchio); the paper's closed forms (eqs. 3-9) as its fast path
(:func:`closed_form_view`, whose record is :class:`ClosedFormTwoLink`, formerly ``TwoLinkArm``:
parameters, closed-form dynamics, simulator, Pinocchio check) and the paper's sigma of an arm's
base parameters (:func:`paper_sigma`)."""

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
from adaptive_dd.plant.two_link import FRICTION_LAWS, ClosedFormTwoLink, closed_form_view
from adaptive_dd.plant.two_link_integrator import two_link_plant_step
from adaptive_dd.plant.two_link_view import paper_sigma

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
    "ClosedFormTwoLink",
    "Payload",
    "PayloadSchedule",
    "PhysicalParameters",
    "SensorConfig",
    "SimulationResult",
    "closed_form_view",
    "coriolis_matrix",
    "coriolis_vector",
    "forward_dynamics",
    "friction",
    "inverse_dynamics",
    "mass_matrix",
    "mass_matrix_entries",
    "paper_sigma",
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
    """``Arm`` on first use (its module imports Pinocchio, which takes a second); ``SerialArm``, its
    old name, and ``TwoLinkArm``, the old name of :class:`ClosedFormTwoLink` (each a FutureWarning)."""
    if name == "Arm":
        from adaptive_dd.plant.arm import Arm

        return Arm
    if name == "SerialArm":  # its name before the serial_ prefix went (issue 27)
        import warnings

        from adaptive_dd.plant.arm import Arm

        warnings.warn(
            "adaptive_dd.plant.SerialArm is now adaptive_dd.plant.Arm, the one arm type (any serial arm; "
            "Arm.sice() is the paper's)",
            FutureWarning,
            stacklevel=2,
        )
        return Arm
    if name == "TwoLinkArm":  # deprecated: a FutureWarning (adaptive_dd.plant.two_link.__getattr__)
        from adaptive_dd.plant import two_link

        return two_link.__getattr__(name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
