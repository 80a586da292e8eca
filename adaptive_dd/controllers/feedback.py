"""Fixed-model controllers: PD, and computed torque with a fixed or the true model."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.controllers.base import DEFAULT_GAINS, Controller, Gains
from adaptive_dd.plant.dynamics import _coriolis_vector, _mass_entries
from adaptive_dd.plant.parameters import TABLE1_SIGMA, validate_sigma

__all__ = ["PD", "ComputedTorque", "computed_torque_law"]

Array = NDArray[np.float64]


def computed_torque_law(
    q: Array, qd: Array, q_d: Array, qd_d: Array, qdd_d: Array, sigma: Array, kp: float, kd: float
) -> Array:
    """``tau = M(q) (qdd_d + Kd e_dot + Kp e) + C(q, qd) qd + B qd + D sgn(qd_d)`` (pure function).

    ``e = q_d - q``. Coulomb friction is compensated with the sign of the desired
    velocity, which does not chatter on a noisy measurement.
    """
    v = qdd_d + kd * (qd_d - qd) + kp * (q_d - q)
    m11, m12, m22 = _mass_entries(q[..., 1], sigma)
    mv = np.stack((m11 * v[..., 0] + m12 * v[..., 1], m12 * v[..., 0] + m22 * v[..., 1]), axis=-1)
    return mv + _coriolis_vector(q, qd, sigma) + sigma[..., 3:5] * qd + sigma[..., 5:7] * np.sign(qd_d)


class PD(Controller):
    """``tau = Kp' e + Kd' e_dot`` with ``Kp' = diag(M0) omega^2``, ``Kd' = diag(M0) 2 zeta omega``."""

    name = "pd"

    def __init__(self, gains: Gains = DEFAULT_GAINS, sigma_nominal: ArrayLike = TABLE1_SIGMA) -> None:
        self.gains = gains
        m0 = gains.nominal_inertia(validate_sigma(sigma_nominal))
        self.kp, self.kd = m0 * gains.kp, m0 * gains.kd

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
        return self.kp * (q_d - q) + self.kd * (qd_d - qd)


class ComputedTorque(Controller):
    """Computed torque with a fixed model (``ct_nominal``) or the true one (``ct_oracle``).

    Parameters
    ----------
    gains : Gains
    sigma : array_like (7,), optional
        The fixed model; default Table 1 (no payload).
    oracle : bool
        Use the true sigma at every sample (payload included): the reference floor.
    """

    def __init__(
        self,
        gains: Gains = DEFAULT_GAINS,
        sigma: ArrayLike = TABLE1_SIGMA,
        oracle: bool = False,
    ) -> None:
        self.gains, self.oracle = gains, oracle
        self.sigma = validate_sigma(sigma)
        self.name = "ct_oracle" if oracle else "ct_nominal"

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
        if self.oracle and sigma_true is None:
            raise ValueError("ct_oracle needs the true sigma at every sample")
        sigma = sigma_true if self.oracle else self.sigma
        return computed_torque_law(q, qd, q_d, qd_d, qdd_d, sigma, self.gains.kp, self.gains.kd)
