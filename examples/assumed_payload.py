"""A plug-in controller for any arm (two-link or from a URDF): computed torque on the arm's model
with an assumed payload, the arm and the scenario handed over by the runner.

Run it from a scenario (``examples/plugin_urdf.toml``, the UR5)::

    adaptive-dd benchmark examples/plugin_urdf.toml

It is written only against the public API, as a user's own controller would be. The runner
calls ``AssumedPayload(arm=..., scenario=..., gains=..., assumed_mass=...)``: ``arm`` is the
scenario's arm with its overrides (no URDF to reload), ``scenario`` the whole scenario. The law
is computed torque on the base parameters ``sigma = arm.sigma_with_payload(m)``::

    tau = Y(q, qd, qdd_d + kd (qd_d - qd) + kp (q_d - q)) sigma

with ``Y = arm.regressor`` (``(n_trials, n, p)``: ``Y sigma`` is the joint torque, friction and
armature included). It does not adapt: ``m`` is the ``assumed_mass`` setting, or by default the
mean of the scenario's payload masses (a user's guess between the swaps). It declares the model
it uses as ``sigma_hat`` (one row ``(p,)`` stands for every trial), so the report shows the mass
it assumes.
"""

from __future__ import annotations

import numpy as np

from adaptive_dd.controllers import Controller, Gains


class AssumedPayload(Controller):
    """Computed torque with the arm's model and a payload of an assumed mass.

    Parameters
    ----------
    arm : Arm or ClosedFormTwoLink
        Given by the runner: the arm of the scenario.
    scenario : Scenario or None
        Given by the runner (None outside a scenario).
    gains : Gains
        Given by the runner: ``kp = w^2``, ``kd = 2 zeta w``.
    assumed_mass : float, optional
        The payload's mass [kg] in the model (default: the mean of the scenario's masses, 0
        without a scenario).
    """

    name = "assumed_payload"
    floor = "ct_oracle"

    def __init__(self, arm, scenario=None, gains: Gains | None = None, assumed_mass: float | None = None):
        if assumed_mass is None:
            masses = [0.0, *scenario.swap_masses] if scenario is not None else [0.0]
            assumed_mass = float(np.mean(masses))
        if not (np.isfinite(assumed_mass) and assumed_mass >= 0):
            raise ValueError(f"assumed_mass must be >= 0 kg, got {assumed_mass!r}")
        g = gains or Gains(40.0, 1.0)
        self.arm, self.kp, self.kd = arm, g.kp, g.kd
        self.mass = float(assumed_mass)
        self.sigma = np.asarray(arm.sigma_with_payload(self.mass), dtype=float)

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
        a = qdd_d + self.kd * (qd_d - qd) + self.kp * (q_d - q)  # (n_trials, n)
        return np.einsum("tip,p->ti", self.arm.regressor(q, qd, a), self.sigma)

    @property
    def sigma_hat(self):
        return self.sigma
