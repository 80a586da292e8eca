"""A plug-in controller for adaptive_dd: Slotine-Li adaptation of the payload mass alone.

Run it from a scenario (``examples/plugin.toml``)::

    adaptive-dd benchmark examples/plugin.toml

It is written only against the public API (``adaptive_dd.controllers.Controller`` and
``adaptive_dd.plant``), as a user's own controller would be. The law is Slotine-Li's with
the model restricted to ``sigma = sigma_nominal + m d`` (d: how a tip mass moves sigma),
so only one parameter adapts::

    tau = Y(q, qd, qd_r, qdd_r) (sigma_nominal + m d) + kd M0(q) s
    m'  = gamma d^T Y^T s,  m clipped to [0, m_max]
"""

from __future__ import annotations

import numpy as np

from adaptive_dd.controllers import DEFAULT_GAINS, Controller, Gains
from adaptive_dd.plant import TABLE1_SIGMA, mass_matrix, payload_sigma_delta, regressor_reference


class PayloadGradient(Controller):
    """Payload-mass-only Slotine-Li.

    Parameters
    ----------
    gains : Gains
        Sets lambda and kd as for Slotine-Li (the poles of computed torque).
    sigma_nominal : array_like (7,)
        The arm without payload (given by the runner).
    gamma : float
        Adaptation gain [kg per (N m rad/s ... )], > 0.
    m_max : float
        Largest payload mass the estimate may take [kg].
    """

    name = "payload_gradient"
    floor = "slotine_li_oracle"  # measured against Slotine-Li with the true model

    def __init__(
        self,
        gains: Gains = DEFAULT_GAINS,
        sigma_nominal=TABLE1_SIGMA,
        gamma: float = 200.0,
        m_max: float = 20.0,
    ) -> None:
        if not (np.isfinite(gamma) and gamma > 0):
            raise ValueError(f"gamma must be > 0, got {gamma!r}")
        self.gains, self.gamma, self.m_max = gains, float(gamma), float(m_max)
        self.sigma0 = np.asarray(sigma_nominal, dtype=float)
        self.d = payload_sigma_delta(1.0, 0.0)
        self.lam, self.kd = gains.lam, 2.0 * gains.damping * gains.bandwidth - gains.lam

    def reset(self, n_trials: int, sample_period: float) -> None:
        super().reset(n_trials, sample_period)
        self.m = np.zeros(n_trials)

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
        e, e_dot = q_d - q, qd_d - qd
        s = e_dot + self.lam * e
        y = regressor_reference(q, qd, qd_d + self.lam * e, qdd_d + self.lam * e_dot)
        theta = self.sigma0 + self.m[:, None] * self.d
        m0 = mass_matrix(q, self.sigma0)
        tau = np.einsum("nij,nj->ni", y, theta) + self.kd * np.einsum("nij,nj->ni", m0, s)
        grad = np.einsum("nij,j,ni->n", y, self.d, s)
        self.m = np.clip(self.m + self.T * self.gamma * grad, 0.0, self.m_max)
        return tau

    @property
    def sigma_hat(self):
        return self.sigma0 + self.m[:, None] * self.d
