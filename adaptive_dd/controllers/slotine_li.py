"""Slotine-Li direct adaptive controller on the seven base parameters.

With ``e = q_d - q``, ``s = e_dot + Lambda e``, ``qd_r = qd_d + Lambda e``,
``qdd_r = qdd_d + Lambda e_dot``::

    tau         = Y(q, qd, qd_r, qdd_r) sigma_hat + K_D(q) s
    sigma_hat' = Gamma Y^T s        (integrated at the sample rate, then projected)

``Lambda = lambda I`` and ``K_D(q) = k M0(q)``, with M0 the nominal (Table 1)
inertia matrix and ``lambda, k`` the roots of ``x^2 - 2 zeta omega x + omega^2``
(both ``omega`` for ``zeta <= 1``): with a perfect model the error poles are then
those of computed torque, ``s^2 + 2 zeta omega s + omega^2``. Any positive definite
K_D keeps the Lyapunov argument, and scaling by the full M0(q) gives every
direction the same rate. A constant diagonal
K_D would give the soft direction of the nearly singular M(q) (q2 near 0) a rate
of ~1700 1/s, beyond what a 1 kHz loop can hold (it oscillates at the Nyquist
rate). Estimates are projected onto ``bounds`` (a priori box) and onto
physically consistent values after every step.

``Y sigma = M qdd_r + C(q, qd) qd_r + B qd_r + D sgn(qd_r)`` (see
:func:`adaptive_dd.plant.regressor_reference`); the skew symmetry of
``dM/dt - 2C`` makes ``V = s^T M s / 2 + sigma_tilde^T Gamma^-1 sigma_tilde / 2``
non-increasing for the continuous-time, noise-free loop.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from adaptive_dd.controllers.base import DEFAULT_GAINS, Controller, Gains
from adaptive_dd.controllers.compiled_form import (
    LAW_SLOTINE,
    LAW_SLOTINE_ORACLE,
    CompiledSpec,
    two_link_gains,
)
from adaptive_dd.controllers.feedback import _sice_sigma
from adaptive_dd.controllers.laws import slotine_li_batch
from adaptive_dd.errors import ParameterError
from adaptive_dd.plant.parameters import PROJECTION_J_MIN, PROJECTION_MARGIN, R_MIN, validate_sigma

__all__ = ["SlotineLi"]

NO_ADAPTATION = np.zeros(0)
PROJECTION = np.array([PROJECTION_J_MIN, PROJECTION_MARGIN, R_MIN])
"""``(j_min, margin, r_min)`` of :func:`adaptive_dd.plant.project_sigma`, for the compiled law."""

DEFAULT_GAMMA = np.array([0.05, 0.05, 0.05, 0.5, 0.1, 0.5, 0.1])
"""Adaptation gains Gamma (diagonal), per parameter."""


MAX_MASS, COM_RADIUS = 5.0, 0.1
"""Defaults of the box's payload on the two-link arm: up to 5 kg, a disk of radius 0.1 m."""


def default_bounds(sigma0, arm=None, max_mass: float = MAX_MASS, com_radius: float = COM_RADIUS) -> tuple:
    """A priori box for the estimates: half the nominal up to 1.5x nominal plus a payload of
    ``max_mass`` [kg] (5) as a disk of radius ``com_radius`` [m] (0.1) at the arm's tip (the SICE
    arm's geometry unless ``arm`` is given)."""
    from adaptive_dd.plant.two_link import ClosedFormTwoLink

    arm = arm or ClosedFormTwoLink.sice()
    s = np.asarray(sigma0, dtype=float)
    return 0.5 * s, 1.5 * s + arm.payload_direction(com_radius) * max_mass


class SlotineLi(Controller):
    """Slotine-Li adaptive control.

    Parameters
    ----------
    gains : Gains
        Sets ``Lambda`` and ``K_D(q) = k M0(q)`` for the poles of computed torque.
    gamma : array_like (7,)
        Diagonal adaptation gains, > 0.
    theta0 : array_like (7,)
        Initial estimate (default Table 1); also the model M0 of K_D.
    bounds : (array_like, array_like)
        Lower and upper bounds of the estimates.
    oracle : bool
        The same law with the true model at every sample and no adaptation
        (``slotine_li_oracle``): the floor Slotine-Li is measured against.

    Examples
    --------
    >>> from adaptive_dd.controllers import SlotineLi
    >>> law = SlotineLi()
    >>> law.name, law.floor  # measured against the same law given the true model
    ('slotine_li', 'slotine_li_oracle')
    >>> SlotineLi(oracle=True).needs_true_model
    True
    """

    name = "slotine_li"

    def __init__(
        self,
        gains: Gains = DEFAULT_GAINS,
        gamma: ArrayLike = DEFAULT_GAMMA,
        theta0: ArrayLike | None = None,
        bounds: tuple | None = None,
        oracle: bool = False,
    ) -> None:
        self.gains, self.oracle = gains, oracle
        self.needs_true_model = oracle
        self.name = "slotine_li_oracle" if oracle else "slotine_li"
        self.floor = None if oracle else "slotine_li_oracle"
        theta0 = _sice_sigma() if theta0 is None else theta0
        bounds = default_bounds(theta0) if bounds is None else bounds
        self.lo, self.hi = (np.asarray(b, dtype=float) for b in bounds)
        try:
            self.gamma = np.asarray(gamma, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError(f"gamma must be 7 positive gains, got {gamma!r}") from None
        if self.gamma.shape != (7,) or np.any(~(self.gamma > 0)):
            raise ParameterError(f"gamma must be 7 positive gains, got {gamma}")
        self.theta0 = validate_sigma(theta0, "theta0")
        w, z = gains.bandwidth, max(gains.damping, 1.0)
        root = w * np.sqrt(z * z - 1.0)
        self.lam, self.kd = w * z - root, w * z + root

    def reset(self, n_trials: int, sample_period: float) -> None:
        super().reset(n_trials, sample_period)
        self.theta = np.broadcast_to(self.theta0, (n_trials, 7)).copy()

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
        if self.oracle:
            if sigma_true is None:
                raise ValueError("slotine_li_oracle needs the true sigma at every sample")
            theta, gamma = np.array(sigma_true, dtype=float), NO_ADAPTATION
        else:
            theta, gamma = self.theta, self.gamma
        return slotine_li_batch(
            q, qd, q_d, qd_d, qdd_d, theta, self.theta0, self.lam, self.kd, self.T, gamma, self.lo, self.hi,
            PROJECTION,
        )  # fmt: skip

    @property
    def sigma_hat(self):
        return None if self.oracle else self.theta

    def compiled_spec(self, sample_period: float) -> CompiledSpec:
        """The compiled loop's form: the gains, the start of the estimate (the model of M0), the box."""
        law = LAW_SLOTINE_ORACLE if self.oracle else LAW_SLOTINE
        box = {k: np.array(getattr(self, k), dtype=float) for k in ("gamma", "lo", "hi")}
        g = two_link_gains(
            law, self.theta0, kd=float(self.kd), lam=float(self.lam), projection=PROJECTION.copy(), **box
        )
        return CompiledSpec(g, None)
