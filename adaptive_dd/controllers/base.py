"""The interface shared by all controllers, and the gains.

At each sample k a controller gets the measured ``q, qd`` (noisy, quantized) and
the reference ``q_d, qd_d, qdd_d`` and returns the torque command
(:meth:`Controller.command`); after the plant step it is told the torque that was
actually applied (:meth:`Controller.observe`), which is when estimators update.
Controllers run at the sample rate; nothing is called inside integrator substeps.
All arrays carry the trial axis first: ``q.shape == (n_trials, 2)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.errors import ParameterError
from adaptive_dd.plant.dynamics import _mass_entries

__all__ = [
    "DECLARED",
    "DEFAULT_GAINS",
    "DEFAULT_MODEL_DELAY",
    "Controller",
    "Gains",
    "declared",
    "delay_samples",
    "model_delay",
]

DEFAULT_MODEL_DELAY = 0.01
"""[s] ``ct_oracle_late``'s default ``delay``: how long after each swap its true model switches."""


def model_delay(value, name: str = "ct_oracle_late") -> float:
    """``ct_oracle_late``'s ``delay`` [s] checked: a finite number >= 0 (else a
    :class:`~adaptive_dd.errors.ParameterError` naming the setting and the value)."""
    from adaptive_dd.errors import is_finite_number

    if not (is_finite_number(value) and value >= 0):
        raise ParameterError(
            f"controllers.{name}.delay: how long after each swap the true model switches, a number "
            f">= 0 s; got {value!r}"
        )
    return float(value)


def delay_samples(delay: float, sample_period: float, name: str = "ct_oracle_late") -> int:
    """``delay`` [s] in samples of ``sample_period`` [s]; a
    :class:`~adaptive_dd.errors.ParameterError` unless it is a whole number of them (a law acts
    once per sample: 0.4 ms at 1 kHz would silently be no delay at all)."""
    n = delay / sample_period
    if abs(n - round(n)) > 1e-6 * max(1.0, n):
        lo, hi = math.floor(n) * sample_period, math.ceil(n) * sample_period
        raise ParameterError(
            f"controllers.{name}.delay: {delay:g} s is {n:g} samples at T = {sample_period:g} s; give a "
            f"whole number of samples (e.g. {lo:g} or {hi:g} s)"
        )
    return round(n)


Array = NDArray[np.float64]


@dataclass(frozen=True)
class Gains:
    """Closed-loop bandwidth shared by all controllers (the scenario's ``[control]`` table).

    Computed torque uses ``Kp = omega^2``, ``Kd = 2 zeta omega`` on the error
    dynamics (a double pole at ``-omega`` for ``zeta = 1``). PD scales these by the
    nominal inertia ``diag M(q = 0)``; Slotine-Li uses ``Lambda = omega`` and
    ``K_D = 2 zeta omega diag M``, which gives the same poles with a perfect model.

    Attributes
    ----------
    bandwidth : float
        omega [rad/s].
    damping : float
        zeta.

    Examples
    --------
    >>> from adaptive_dd.controllers import Gains
    >>> g = Gains(bandwidth=40.0, damping=1.0)
    >>> g.bandwidth**2, 2 * g.damping * g.bandwidth  # computed torque's Kp [1/s^2], Kd [1/s]
    (1600.0, 80.0)
    """

    bandwidth: float = 40.0
    damping: float = 1.0

    def __post_init__(self) -> None:
        if not (np.isfinite(self.bandwidth) and self.bandwidth > 0):
            raise ParameterError(f"bandwidth must be > 0 rad/s, got {self.bandwidth}")
        if not (np.isfinite(self.damping) and self.damping > 0):
            raise ParameterError(f"damping must be > 0, got {self.damping}")

    @property
    def kp(self) -> float:
        return self.bandwidth**2

    @property
    def kd(self) -> float:
        return 2.0 * self.damping * self.bandwidth

    @property
    def lam(self) -> float:
        """``lambda`` of ``s = e_dot + lambda e`` and ``qd_r = qd_d + lambda e``: the smaller root of
        ``x^2 - 2 zeta omega x + omega^2`` (``omega`` for ``zeta <= 1``)."""
        w, z = self.bandwidth, max(self.damping, 1.0)
        return w * z - w * np.sqrt(z * z - 1.0)

    def nominal_inertia(self, sigma: Array | None = None, arm=None) -> Array:
        """``diag M(q = 0)`` of the nominal model, ``(n,)`` [kg m^2]: of ``arm`` (any arm, an
        :class:`~adaptive_dd.plant.arm.Arm` or the closed forms' record; default the SICE arm's
        closed forms, eq. 3) with base parameters ``sigma`` (default the arm's, without payload)."""
        if arm is not None:
            return np.diagonal(arm.mass_matrix(np.zeros(arm.n_joints), sigma)).copy()
        if sigma is None:
            from adaptive_dd.plant.two_link import ClosedFormTwoLink

            sigma = ClosedFormTwoLink.sice().sigma
        m11, _, m22 = _mass_entries(np.zeros(()), np.asarray(sigma, float))
        return np.array([float(m11), float(m22)])


DEFAULT_GAINS = Gains()
"""40 rad/s, critically damped."""


class Controller:
    """Base class. Subclasses set ``name`` and implement :meth:`command`.

    A two-link built-in also defines ``compiled_spec(sample_period)`` on its own class: its law
    and gains as a typed tuple (:mod:`adaptive_dd.controllers.compiled_form`), which the
    benchmark runs compiled; a class without it (a plug-in, a subclass) runs on the Python path.

    Attributes
    ----------
    name : str
        The label in reports.
    needs_true_model : bool
        Receives ``sigma_true`` in :meth:`command` (oracles only).

    Examples
    --------
    A plug-in subclasses it (or only has the same methods) and is named in a scenario by import
    path, ``controllers = ["my_package.laws:Damped"]``:

    >>> import numpy as np
    >>> from adaptive_dd.controllers import Controller
    >>> class Damped(Controller):
    ...     name = "damped"
    ...     def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
    ...         return 50.0 * (q_d - q) + 5.0 * (qd_d - qd)  # (n_trials, 2) [N m]
    >>> law = Damped()
    >>> law.reset(n_trials=1, sample_period=1e-3)
    >>> z = np.zeros((1, 2))
    >>> law.command(z, z, np.full((1, 2), 0.01), z, z)
    array([[0.5, 0.5]])
    """

    name = "controller"
    floor: str | None = "ct_oracle"
    """Name of the controller this one is measured against (the same law with the true model);
    None for oracles. The benchmark reports per-seed ratios to it when it is in the run."""
    needs_true_model = False
    """Oracles set this: the runner then passes the true sigma to :meth:`command`; no other
    controller ever sees it."""

    def reset(self, n_trials: int, sample_period: float) -> None:
        """Start a run of ``n_trials`` trials at sample period T."""
        self.n_trials, self.T = int(n_trials), float(sample_period)

    def command(
        self, q: Array, qd: Array, q_d: Array, qd_d: Array, qdd_d: Array, sigma_true: Array | None = None
    ) -> Array:
        """Torque command ``(n_trials, n)`` [N m] at this sample, ``n`` the arm's joints.

        ``sigma_true (n_trials, p)`` is the true model's ``p`` base parameters (``arm.sigma``'s
        order); only an oracle (``needs_true_model``) is given it.
        """
        raise NotImplementedError

    def observe(self, q: Array, qd: Array, tau: Array) -> None:
        """The measured state and the torque applied over this sample (after saturation)."""

    # Plain attributes, not read-only properties: a subclass sets them (``self.sigma_hat = ...``
    # in ``reset`` or ``observe``) or defines a property of its own over them.
    sigma_hat: Array | None = None
    """Current estimate of the base parameters ``(n_trials, p)`` (``arm.sigma``'s order), or None
    for a fixed-model controller."""
    skipped_samples = None
    """Per trial, samples its estimator skipped as non-finite (sensor dropouts); None if none."""
    alarm_times: list[list[float]] | None = None
    """Per trial, the times [s] a change detector raised an alarm; None without a detector."""

    @property
    def adaptive(self) -> bool:
        """True for controllers that expose an estimate (:attr:`sigma_hat`)."""
        return self.sigma_hat is not None


DECLARED = {
    "name": None,
    "needs_true_model": False,
    "floor": "ct_oracle",
    "sigma_hat": None,
    "alarm_times": None,
    "skipped_samples": None,
}
"""What a controller may declare and the default a class without it gets (docs/controllers.md)."""


def declared(ctrl, attr: str):
    """A controller's declared attribute, or the documented default (:data:`DECLARED`).

    The runner reads every optional attribute through this, so a class written against
    ``reset / command / observe`` alone, with no base class, runs as the docs say;
    ``"adaptive"`` is whether it exposes an estimate (``sigma_hat`` not None)."""
    if attr == "adaptive":
        return declared(ctrl, "sigma_hat") is not None
    default = type(ctrl).__name__ if attr == "name" else DECLARED[attr]
    value = getattr(ctrl, attr, default)
    return None if attr == "floor" and value is False else value  # floor = False: none, as in a table
