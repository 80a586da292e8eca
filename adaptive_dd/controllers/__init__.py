"""Controllers with one interface: PD, computed torque (nominal, oracle), adaptive
computed torque (paper's estimator, payload-swap estimator), Slotine-Li."""

from adaptive_dd.controllers.adaptive import (
    ADAPTIVE_ONLINE,
    PAPER_ONLINE,
    AdaptiveCT,
    adaptive_ct,
    adaptive_ct_paper,
)
from adaptive_dd.controllers.base import DEFAULT_GAINS, Controller, Gains
from adaptive_dd.controllers.feedback import PD, ComputedTorque, computed_torque_law
from adaptive_dd.controllers.registry import (
    CONTROLLERS,
    controller_label,
    load_controller_class,
    make_controller,
)
from adaptive_dd.controllers.slotine_li import SlotineLi

__all__ = [
    "ADAPTIVE_ONLINE",
    "CONTROLLERS",
    "DEFAULT_GAINS",
    "PAPER_ONLINE",
    "PD",
    "AdaptiveCT",
    "ComputedTorque",
    "Controller",
    "Gains",
    "SlotineLi",
    "adaptive_ct",
    "adaptive_ct_paper",
    "computed_torque_law",
    "controller_label",
    "load_controller_class",
    "make_controller",
]
