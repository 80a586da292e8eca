"""PD plus gravity compensation as a plain-Python plug-in: the law of ``pd_gravity_plugin.py``
written with numpy over the batch of trials. It runs on the Python path (one ``command`` per
sample for every trial at once), which the run says when it starts."""

import numpy as np


class PDGravityPython:
    """``tau = Kp e + Kd e' + g0(q)`` with ``g0(q) = Y(q, 0, 0) sigma0`` from the arm's regressor."""

    name = "pd_gravity_python"
    floor = "pd_gravity_oracle"

    def __init__(self, arm, gains):
        self.arm = arm
        m0 = np.asarray(arm.nominal_inertia(), dtype=float)
        self.kp, self.kd = gains.kp * m0, gains.kd * m0

    def reset(self, n_trials, sample_period):
        pass

    def command(self, q, qd, q_d, qd_d, qdd_d):
        zero = np.zeros_like(q)
        gravity = self.arm.regressor(q, zero, zero) @ self.arm.sigma  # (n_trials, n)
        return self.kp * (q_d - q) + self.kd * (qd_d - qd) + gravity

    def observe(self, q, qd, tau):
        pass
