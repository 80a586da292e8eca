"""Controllers with one interface: PD, computed torque (nominal, oracle), adaptive
computed torque (paper's estimator, payload-swap estimator), Slotine-Li.

:func:`make_controller` builds any of them for any arm; :data:`CONTROLLERS` is the one table of
built-in names (what each knows, its settings and their defaults on each arm, which arms it runs
on). The two-link forms live here, the N-joint forms in :mod:`adaptive_dd.closed_loop.controllers`."""

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
    Builtin,
    Setting,
    controller_label,
    controllers_for,
    gains_for,
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
    "Builtin",
    "ComputedTorque",
    "Controller",
    "Gains",
    "Setting",
    "SlotineLi",
    "adaptive_ct",
    "adaptive_ct_paper",
    "computed_torque_law",
    "controller_label",
    "controllers_for",
    "gains_for",
    "load_controller_class",
    "make_controller",
]
