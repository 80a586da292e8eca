"""Fixed-model controllers: PD, and computed torque with a fixed or the true model."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.controllers.base import DEFAULT_GAINS, Controller, Gains, delay_samples
from adaptive_dd.controllers.base import model_delay as _model_delay
from adaptive_dd.controllers.compiled_form import LAW_CT, LAW_CT_ORACLE, LAW_PD, CompiledSpec, two_link_gains
from adaptive_dd.controllers.laws import ct_batch, pd_batch
from adaptive_dd.plant.parameters import validate_sigma

__all__ = ["PD", "ComputedTorque", "computed_torque_law"]

Array = NDArray[np.float64]


def computed_torque_law(
    q: Array,
    qd: Array,
    q_d: Array,
    qd_d: Array,
    qdd_d: Array,
    sigma: Array,
    kp: float,
    kd: float,
    lam: float | None = None,
) -> Array:
    """Computed torque (pure function), shape ``(..., 2)`` [N m].

    ``tau = M(q) (qdd_d + Kd e_dot + Kp e) + C(q, qd) w + B w + D sgn(w)``, ``e = q_d - q``.

    With ``lam`` (the default of every controller here) the velocity terms use the
    reference velocity ``w = qd_r = qd_d + lam e``; with ``lam=None`` they use the
    textbook ``w = qd`` (measured) for Coriolis and viscous friction and ``sgn(qd_d)``
    for Coulomb friction (``sgn(qd)`` would chatter on a noisy measurement).

    With the true model the error obeys ``M (e'' + Kd e' + Kp e) + (C + B) s = f_err``,
    ``s = e' + lam e``, where f_err is what the friction model misses while a joint
    sticks: the ``(C + B) s`` term is dissipative and it is what makes Slotine-Li track
    6x better than the textbook law on this arm at the same bandwidth (README,
    "What the ratios mean"). With ``lam`` this law is Slotine-Li's with the true model,
    up to its ``K_D`` (``M(q) Kd`` here).
    """
    return ct_batch(q, qd, q_d, qd_d, qdd_d, sigma, kp, kd, lam)


def _sice_sigma():
    """The default nominal model: the SICE arm's base parameters (``ClosedFormTwoLink.sice()``)."""
    from adaptive_dd.plant.two_link import ClosedFormTwoLink

    return ClosedFormTwoLink.sice().sigma


class PD(Controller):
    """``tau = Kp' e + Kd' e_dot`` with ``Kp' = diag(M0) omega^2``, ``Kd' = diag(M0) 2 zeta omega``.

    Parameters
    ----------
    gains : Gains
        Bandwidth omega [rad/s] and damping zeta.
    sigma_nominal : array_like, shape (7,), optional
        The nominal model whose inertia ``M0 = M(q = 0)`` scales the gains; default Table 1.

    Examples
    --------
    >>> import numpy as np
    >>> from adaptive_dd.controllers import PD, Gains
    >>> pd = PD(Gains(bandwidth=40.0))
    >>> pd.reset(n_trials=1, sample_period=1e-3)
    >>> z = np.zeros((1, 2))
    >>> pd.command(z, z, np.full((1, 2), 0.01), z, z).round(3)  # [N m] for 10 mrad of error
    array([[13.184,  1.136]])
    """

    name = "pd"

    def __init__(self, gains: Gains = DEFAULT_GAINS, sigma_nominal: ArrayLike | None = None) -> None:
        self.gains = gains
        sigma_nominal = _sice_sigma() if sigma_nominal is None else sigma_nominal
        m0 = gains.nominal_inertia(validate_sigma(sigma_nominal))
        self.kp, self.kd = m0 * gains.kp, m0 * gains.kd

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
        return pd_batch(q, qd, q_d, qd_d, self.kp, self.kd)

    def compiled_spec(self, sample_period: float) -> CompiledSpec:
        """The compiled loop's form: PD's gains per joint."""
        kp, kd = (np.array(np.broadcast_to(x, (2,)), dtype=float) for x in (self.kp, self.kd))
        return CompiledSpec(two_link_gains(LAW_PD, pd_kp=kp, pd_kd=kd), None)


class ComputedTorque(Controller):
    """Computed torque with a fixed model (``ct_nominal``) or the true one (``ct_oracle``).

    Parameters
    ----------
    gains : Gains
    sigma : array_like (7,), optional
        The fixed model; default Table 1 (no payload).
    oracle : bool
        Use the true sigma at every sample (payload included): the reference floor.
    reference_velocity : bool
        Velocity terms at ``qd_r = qd_d + lam e`` (default) or the textbook law
        (see :func:`computed_torque_law`).
    model_delay : float, optional
        [s] With ``oracle``: the true model switches this long after each swap (``ct_oracle_late``,
        measured against ``ct_oracle``: what knowing each payload that late costs the law).

    Examples
    --------
    >>> import numpy as np
    >>> from adaptive_dd.controllers import ComputedTorque
    >>> ct = ComputedTorque()  # ct_nominal: Table 1's model, no payload
    >>> ct.reset(n_trials=1, sample_period=1e-3)
    >>> z = np.zeros((1, 2))
    >>> ct.name, ct.command(z, z, np.full((1, 2), 0.01), z, z).round(3)
    ('ct_nominal', array([[22.214,  6.053]]))
    >>> ComputedTorque(oracle=True).needs_true_model  # ct_oracle: the floor
    True
    """

    def __init__(
        self,
        gains: Gains = DEFAULT_GAINS,
        sigma: ArrayLike | None = None,
        oracle: bool = False,
        reference_velocity: bool = True,
        model_delay: float | None = None,
    ) -> None:
        self.gains, self.oracle, self.reference = gains, oracle, reference_velocity
        self.needs_true_model = oracle
        self.floor = None if oracle else ("ct_oracle" if reference_velocity else "ct_oracle_textbook")
        self.sigma = validate_sigma(_sice_sigma() if sigma is None else sigma)
        base = "ct_oracle" if oracle else "ct_nominal"
        self.name = base if reference_velocity else base + "_textbook"
        self.model_delay = 0.0
        if model_delay is not None:
            if not (oracle and reference_velocity):
                raise ValueError("model_delay is ct_oracle_late's: an oracle at the reference velocity")
            self.model_delay = _model_delay(model_delay)
            self.name, self.floor = "ct_oracle_late", "ct_oracle"

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
        if self.oracle and sigma_true is None:
            raise ValueError("ct_oracle needs the true sigma at every sample")
        sigma = sigma_true if self.oracle else self.sigma
        g = self.gains
        return computed_torque_law(
            q, qd, q_d, qd_d, qdd_d, sigma, g.kp, g.kd, g.lam if self.reference else None
        )

    def compiled_spec(self, sample_period: float) -> CompiledSpec:
        """The compiled loop's form: the fixed model (or the true one) and the gains."""
        g = self.gains
        lam = float(g.lam) if self.reference else -1.0
        law = LAW_CT_ORACLE if self.oracle else LAW_CT
        late = delay_samples(self.model_delay, sample_period)
        gains = two_link_gains(law, self.sigma, kp=float(g.kp), kd=float(g.kd), lam=lam, model_delay=late)
        return CompiledSpec(gains, None)
