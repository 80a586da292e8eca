"""PD plus gravity compensation (Takegaki and Arimoto 1981) as a compiled plug-in.

``tau = Kp e + Kd e' + g0(q)``: ``e = q_d - q``, ``e' = qd_d - qd``, ``Kp = omega^2 m0``,
``Kd = 2 zeta omega m0`` per joint (``m0``: the diagonal of the nominal inertia at the middle of
the joint ranges, ``arm.nominal_inertia()``), ``g0`` the gravity torque of the model the scenario
gives the controllers, which the compiled loop computes because the class declares
``needs = ("gravity",)``. The same law as the built-in ``pd_gravity``, written against the public
protocol only (``docs/own_controller.md``); ``adaptive-dd benchmark examples/plugins/pd_gravity.toml``
runs both side by side.
"""

import numpy as np
from numba import njit


class PDGravityPlugin:
    """PD plus the nominal model's gravity, compiled into the closed loop."""

    name = "pd_gravity_plugin"
    floor = "pd_gravity_oracle"  # the report's ratio: against the same law with the true gravity
    needs = ("gravity",)  # the loop hands command g0(q) at the measured q
    state_size = 0  # no per-trial state

    def __init__(self, arm, gains):
        m0 = np.asarray(arm.nominal_inertia(), dtype=float)  # (n,) [kg m^2]
        self.kp = gains.kp * m0  # [N m / rad]
        self.kd = gains.kd * m0  # [N m s / rad]

    def parameters(self, sample_period):
        """What the compiled functions receive as ``p``: any value numba compiles."""
        return (self.kp, self.kd)

    @staticmethod
    @njit
    def reset(p, x):
        """Trial start: ``x`` the trial's state row (unused here)."""

    @staticmethod
    @njit
    def command(p, x, q, qd, q_d, qd_d, qdd_d, terms, tau):
        """Write the torque command into ``tau (n,)`` from the measured ``q, qd (n,)`` and the
        reference; ``terms = (g, M, bias, arm)``: only ``g`` is computed, as declared."""
        kp, kd = p
        g = terms[0]
        for j in range(q.shape[0]):
            tau[j] = kp[j] * (q_d[j] - q[j]) + kd[j] * (qd_d[j] - qd[j]) + g[j]

    @staticmethod
    @njit
    def observe(p, x, q, qd, tau):
        """After the plant moved: the measurement (NaN if lost) and the applied torque. Returns 1
        on a change alarm, else 0 (this law has no estimator)."""
        return 0
