"""Adaptive computed torque: the online estimator updates the model every sample.

``adaptive_ct_paper``
    The paper's online M2 estimator as the paper has it: construction "paper"
    (eq. 19), split (15), RLS of eq. (14) with the variable forgetting factor
    (lambda -> 1, so it slowly stops adapting).
``adaptive_ct``
    The same controller with an estimator made for payload swaps: construction
    "exact" with aligned torque and data selection, the full 7-parameter RLS with
    constant forgetting, a change detector on the prediction error that re-opens
    the covariance of the inertial parameters (a payload changes J1, J2 and r,
    not friction), projection onto physically consistent parameters (M positive
    definite, friction >= 0), and a cap on the covariance trace.

Both start from the nominal Table 1 model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.controllers.base import DEFAULT_GAINS, Controller, Gains
from adaptive_dd.controllers.feedback import computed_torque_law
from adaptive_dd.errors import ParameterError
from adaptive_dd.identification.estimators import PAPER_RLS, SplitRLS
from adaptive_dd.identification.regressors import OnlineRegressor
from adaptive_dd.identification.rls import RLSConfig
from adaptive_dd.plant.parameters import TABLE1_SIGMA, payload_sigma_delta, project_sigma

__all__ = [
    "AdaptiveCT",
    "ChangeDetector",
    "OnlineEstimator",
    "adaptive_ct",
    "adaptive_ct_paper",
]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class ChangeDetector:
    """Detects a sudden change of the plant from the prior prediction error.

    An alarm is raised when the short-window mean square of the prediction error
    exceeds ``threshold**2`` times its long-run level (frozen during alarms).

    Attributes
    ----------
    short_window, long_window : float
        Time constants [s] of the two exponential averages.
    threshold : float
        Ratio of RMS errors that raises an alarm.
    warmup : float
        No alarm before this time [s] (the long-run level is being learned).
    holdoff : float
        No new alarm for this long after one [s].
    p_mass : float
        Variance [kg^2] re-opened along the payload direction: a tip mass m moves
        sigma by ``m [l1^2, l2^2, l1 l2, 0, 0, 0, 0]``, so the covariance gets
        ``p_mass d d^T`` added with that d, after the old inertial covariance is
        cleared. Re-estimation is then nearly one-dimensional and fast.
    p_j2 : float
        Extra variance on J2 alone (the disk's own inertia, radius unknown).
    freeze : float
        After an alarm, no update for this many filter time constants: the
        filtered equation ``G0 tau = (G0 Phi) sigma`` holds only once the filter's
        memory no longer spans the change.
    reopen_again : bool
        Instead of freezing: keep updating through the change, and re-open the
        covariance a second time when the freeze time has passed, so the samples
        that straddled the change lose their weight.
    """

    short_window: float = 0.005
    long_window: float = 1.0
    threshold: float = 4.0
    warmup: float = 0.5
    holdoff: float = 1.0
    p_mass: float = 25.0
    p_j2: float = 1e-3
    freeze: float = 3.0
    reopen_again: bool = True

    def __post_init__(self) -> None:
        if not (0 < self.short_window < self.long_window):
            raise ParameterError(
                f"need 0 < short_window < long_window, got {self.short_window}, {self.long_window}"
            )
        if self.threshold <= 1 or self.p_mass <= 0 or self.p_j2 < 0 or self.warmup < 0 or self.holdoff < 0:
            raise ParameterError(f"invalid ChangeDetector settings: {self}")


class OnlineEstimator:
    """Online estimate of sigma from measured (q, qd, tau), batched over trials.

    Parameters
    ----------
    n_trials : int
    sample_period : float
    construction : {"paper", "exact"}
    split : {"15", "16", "full"}
    rls : RLSConfig
    tau_f : float
        Filter time constant of the M2 bank [s].
    theta0 : array_like (7,)
        Initial estimate.
    align : bool
        Use ``(tau(t-1) + tau(t)) / 2`` (see :func:`~adaptive_dd.identification.align_torque`).
    selection : (float, float) or None
        Data selection ``(threshold [rad/s], memory in units of tau_f)``.
    detector : ChangeDetector or None
    project : bool
        Project onto physically consistent parameters after every update.
    """

    def __init__(
        self,
        n_trials: int,
        sample_period: float,
        *,
        construction: str = "exact",
        split: str = "full",
        rls: RLSConfig = PAPER_RLS,
        tau_f: float = 0.006,
        theta0: ArrayLike = TABLE1_SIGMA,
        align: bool = False,
        selection: tuple[float, float] | None = None,
        detector: ChangeDetector | None = None,
        project: bool = False,
    ) -> None:
        self.T = float(sample_period)
        self.regressor = OnlineRegressor(
            (n_trials,), method="M2", construction=construction, tau_f=tau_f, sample_period=self.T
        )
        self.rls = SplitRLS(split, rls, (n_trials,), theta0)
        self.align, self.detector, self.project = align, detector, project
        self.selection = selection
        self.memory = 0 if selection is None else int(np.ceil(selection[1] * tau_f / self.T))
        self.since_slow = np.zeros((n_trials, 2), dtype=int)
        self.tau_prev: Array | None = None
        self.k = 0
        self.short = np.zeros((n_trials, 2))
        self.long = np.zeros((n_trials, 2))
        self.since_alarm = np.full(n_trials, 10**9)
        self.alarms = np.zeros(n_trials, dtype=int)
        self.alarm_times: list[list[float]] = [[] for _ in range(n_trials)]
        self.frozen_until = np.zeros(n_trials, dtype=int)
        self.freeze_samples = 0 if detector is None else int(np.ceil(detector.freeze * tau_f / self.T))
        self.reopen_at = np.full(n_trials, -1)

    @property
    def theta(self) -> Array:
        return self.rls.theta

    def update(self, q: Array, qd: Array, tau: Array) -> Array:
        """Feed the sample's measured q, qd and applied torque; return the new estimate."""
        tau_used = tau
        if self.align:
            tau_used = 0.5 * (tau + (tau if self.tau_prev is None else self.tau_prev))
            self.tau_prev = tau
        phi, y = self.regressor(q, tau_used, qd)
        active = None
        if self.selection is not None:
            slow = np.abs(qd) <= self.selection[0]
            self.since_slow = np.where(slow, 0, self.since_slow + 1)
            active = self.since_slow > self.memory
        det_active = active
        if self.detector is not None and not self.detector.reopen_again:
            thawed = (self.k >= self.frozen_until)[:, None]
            active = thawed if active is None else active & thawed
        theta = self.rls.step(phi, y, active)
        if self.detector is not None:
            again = self.reopen_at == self.k
            if again.any():
                self._reopen(again)
            self._detect(det_active)
        if self.project:
            self._set_theta(project_sigma(self.rls.theta))
        self.k += 1
        return theta if not self.project else self.rls.theta

    def _set_theta(self, theta: Array) -> None:
        s = self.rls.states[0]
        self.rls.states[0] = s._replace(theta=theta)

    def _reopen(self, which: NDArray[np.bool_]) -> None:
        """Clear the inertial covariance and open it along the payload direction."""
        det = self.detector
        s = self.rls.states[0]
        p = s.P.copy()
        d = payload_sigma_delta(1.0, 0.0)
        reopen = det.p_mass * np.outer(d, d)
        reopen[1, 1] += det.p_j2
        for b in np.flatnonzero(which):
            p[b, :3, :] = 0.0
            p[b, :, :3] = 0.0
            p[b] += reopen
        self.rls.states[0] = s._replace(P=p)

    def _detect(self, active: NDArray[np.bool_] | None) -> None:
        det = self.detector
        e2 = self.rls.last_eps**2
        ok = np.isfinite(e2) if active is None else (np.isfinite(e2) & active)
        e2 = np.where(ok, e2, 0.0)
        a_s, a_l = self.T / det.short_window, self.T / det.long_window
        self.short = np.where(ok, self.short + a_s * (e2 - self.short), self.short)
        t = self.k * self.T
        quiet = self.since_alarm * self.T > det.holdoff
        learn = ok & quiet[:, None]
        self.long = np.where(learn, self.long + a_l * (e2 - self.long), self.long)
        self.since_alarm += 1
        if t < det.warmup:
            return
        alarm = quiet & np.any(self.short > det.threshold**2 * self.long + 1e-12, axis=-1)
        if not alarm.any():
            return
        self._reopen(alarm)
        for b in np.flatnonzero(alarm):
            self.alarm_times[b].append(t)
        self.alarms += alarm
        if det.reopen_again:
            self.reopen_at = np.where(alarm, self.k + self.freeze_samples, self.reopen_at)
        self.frozen_until = np.where(alarm, self.k + self.freeze_samples, self.frozen_until)
        self.since_alarm = np.where(alarm, 0, self.since_alarm)
        self.short = np.where(alarm[:, None], self.long, self.short)


class AdaptiveCT(Controller):
    """Computed torque whose model is the online estimate, updated every sample.

    Parameters
    ----------
    name : str
    gains : Gains
    estimator_factory : callable ``(n_trials, T) -> OnlineEstimator``
    """

    adaptive = True

    def __init__(self, name: str, gains: Gains, estimator_factory) -> None:
        self.name, self.gains, self.factory = name, gains, estimator_factory
        self.estimator: OnlineEstimator | None = None

    def reset(self, n_trials: int, sample_period: float) -> None:
        super().reset(n_trials, sample_period)
        self.estimator = self.factory(n_trials, sample_period)
        self._q = self._qd = None

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
        self._q, self._qd = q, qd
        est = self.estimator
        # a usable model even mid-transient; an estimator that projects already did it
        sigma = est.theta if est.project else project_sigma(est.theta)
        return computed_torque_law(q, qd, q_d, qd_d, qdd_d, sigma, self.gains.kp, self.gains.kd)

    def observe(self, q, qd, tau):
        self.estimator.update(q, qd, tau)

    @property
    def sigma_hat(self) -> Array:
        return self.estimator.theta


def adaptive_ct_paper(gains: Gains = DEFAULT_GAINS, tau_f: float = 0.006) -> AdaptiveCT:
    """Computed torque on the paper's online M2 estimator, as the paper has it."""

    def factory(n, T):
        return OnlineEstimator(n, T, construction="paper", split="15", rls=PAPER_RLS, tau_f=tau_f)

    return AdaptiveCT("adaptive_ct_paper", gains, factory)


ADAPTIVE_RLS = RLSConfig(lam0=0.99995, mu=0.0, p0=0.01, max_trace=30.0)
"""RLS of ``adaptive_ct``: slow constant forgetting (a ~20 s memory; the change detector does the
fast work), started at the nominal model with a small covariance."""


def adaptive_ct(
    gains: Gains = DEFAULT_GAINS,
    tau_f: float = 0.01,
    detector: ChangeDetector = ChangeDetector(),
    rls: RLSConfig = ADAPTIVE_RLS,
) -> AdaptiveCT:
    """Computed torque on the payload-swap estimator (see the module docstring)."""

    def factory(n, T):
        return OnlineEstimator(
            n,
            T,
            construction="exact",
            split="full",
            rls=rls,
            tau_f=tau_f,
            align=True,
            selection=(0.05, 6.0),
            detector=detector,
            project=True,
        )

    return AdaptiveCT("adaptive_ct", gains, factory)
