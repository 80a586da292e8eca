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
from adaptive_dd.controllers.slotine_li import SlotineLi

CONTROLLERS = (
    "pd",
    "ct_nominal",
    "ct_oracle",
    "ct_oracle_textbook",
    "adaptive_ct_paper",
    "adaptive_ct",
    "slotine_li",
    "slotine_li_oracle",
)
"""Names a scenario may list."""


def make_controller(name: str, gains: Gains | None = None) -> Controller:
    """A controller by name (see :data:`CONTROLLERS`) with the given gains."""
    g = gains or DEFAULT_GAINS
    factories = {
        "pd": lambda: PD(g),
        "ct_nominal": lambda: ComputedTorque(g),
        "ct_oracle": lambda: ComputedTorque(g, oracle=True),
        "ct_oracle_textbook": lambda: ComputedTorque(g, oracle=True, reference_velocity=False),
        "adaptive_ct_paper": lambda: adaptive_ct_paper(g),
        "adaptive_ct": lambda: adaptive_ct(g),
        "slotine_li": lambda: SlotineLi(g),
        "slotine_li_oracle": lambda: SlotineLi(g, oracle=True),
    }
    if name not in factories:
        raise ValueError(f"unknown controller {name!r}; choose from {CONTROLLERS}")
    return factories[name]()


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
    "make_controller",
]
