"""Adaptive computed torque: an online estimator feeds the computed-torque law every sample.

The controller holds no identification logic: it composes
:class:`~adaptive_dd.identification.two_link_online.OnlineEstimator` (filters, RLS, change
detection, re-opening, projection) with :func:`~adaptive_dd.controllers.feedback.computed_torque_law`.

``adaptive_ct``
    The estimator made for payload swaps (:data:`ADAPTIVE_ONLINE`): exact construction,
    aligned torque, data selection, the full 7-parameter RLS with slow constant
    forgetting, a start-up covariance shaped along the payload direction, the change
    detector, re-opening along the payload direction, the control model projected; and
    for ``boost_duration`` after an alarm the feedback gains are raised to
    ``boost_bandwidth`` through the nominal inertia, which holds the arm while the
    estimate converges (at each sample the largest bandwidth up to it that keeps the command
    within the arm's torque limits: :func:`~adaptive_dd.controllers.laws.boost_within_trial`);
    plus the residual observer's torque (``observer``, on by default): what
    the current model leaves unexplained beyond three times its own noise, the N-joint
    ``adaptive_ct``'s observer itself (:mod:`~adaptive_dd.controllers.two_link_observer`).
``adaptive_ct_paper``
    The paper's online M2 estimator (construction of eq. 19, split (15), RLS of eq. 14 with
    the variable forgetting factor), started from the nominal model with the same prior
    covariance as ``adaptive_ct``; no detector. The paper proposes no controller and gives no
    lambda(0), mu or P(0): those, the prior, the trace cap and the projection are ours.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.controllers.base import DEFAULT_GAINS, Controller, Gains
from adaptive_dd.controllers.compiled_form import LAW_ADAPTIVE, CompiledSpec, TwoLinkGains, two_link_gains
from adaptive_dd.controllers.feedback import _sice_sigma, computed_torque_law
from adaptive_dd.controllers.laws import boost_batch
from adaptive_dd.errors import ParameterError
from adaptive_dd.identification.estimators import PAPER_RLS
from adaptive_dd.identification.two_link_online import OnlineEstimator, TwoLinkOnlineConfig
from adaptive_dd.plant.parameters import validate_sigma

__all__ = ["ADAPTIVE_ONLINE", "BOOST_RULE", "PAPER_ONLINE", "AdaptiveCT", "adaptive_ct", "adaptive_ct_paper"]

Array = NDArray[np.float64]

BOOST_RULE = (
    "one rule on every arm: the boost lasts while the estimator learns the payload it models, "
    "at least its slowest learning time after a swap on the arm's shipped scenario: the paper's sigma "
    "models the payload's mass only (at the tip, eq. 9), known within 5 % 0.05-0.15 s after a swap "
    "(payload_swap); an N-joint estimate also holds the payload's centre of mass, within 1 cm "
    "0.11-0.98 s after a swap (ur5_tool_swap); each arm's loaded segments are worse with the "
    "other's default (docs/controllers.md)"
)
"""Why ``adaptive_ct``'s ``boost_duration`` defaults to 0.2 s on the two-link arm and 1 s on an
N-joint arm: one rule, two estimators (``docs/controllers.md``, the measurement)."""

ADAPTIVE_ONLINE = TwoLinkOnlineConfig()
"""Estimator of ``adaptive_ct`` (the defaults of :class:`TwoLinkOnlineConfig`)."""

PAPER_ONLINE = TwoLinkOnlineConfig(
    tau_f=0.006,
    construction="paper",
    split="15",
    rls=dataclasses.replace(PAPER_RLS, p0=1e-6, max_trace=30.0),
    align=False,
    selection=None,
    detector=None,
    project="model",
)
"""Estimator of ``adaptive_ct_paper``: eq. (19), split (15), eq. (14) with lambda(0) = 0.99, mu = 0.002.

The paper identifies from scratch (large P(0)); inside a controller that starts from the
correct nominal model that prior would throw the model away at start-up, so this rendering
starts from the same prior as ``adaptive_ct`` (small isotropic covariance plus the payload
direction)."""


class AdaptiveCT(Controller):
    """Computed torque whose model is the online estimate, updated every sample.

    Parameters
    ----------
    online : TwoLinkOnlineConfig
        The estimator (its ``sample_period`` is set at :meth:`reset`).
    gains : Gains
    sigma_nominal : array_like (7,)
        The model the estimator starts from; its inertia scales the boost.
    boost_bandwidth : float or None
        Bandwidth [rad/s] of the feedback for ``boost_duration`` after an alarm.
    boost_duration : float
        [s]; default 0.2 s: the boost lasts while the estimator learns the payload it models
        (:data:`BOOST_RULE`), here the paper's sigma, whose payload is its mass at the tip.
    observer : bool
        Feed forward the residual observer's torque (default true; ``adaptive_ct_paper``: false).
    observer_bandwidth : float or None
        [rad/s] of each of the observer's two stages; None: ``0.4 / T`` (the N-joint rule).
    torque_limit : array_like (2,) or None
        The arm's torque limits [N m]: the boost's bandwidth is lowered, sample by sample, so
        that it does not drive the command beyond them; None: no limit (the whole boost).
    name : str

    Examples
    --------
    >>> from adaptive_dd.controllers import AdaptiveCT
    >>> law = AdaptiveCT()  # the two-link arm's; make_controller builds either arm's
    >>> law.name, law.floor, law.online.tau_f
    ('adaptive_ct', 'ct_oracle', 0.01)
    """

    def __init__(
        self,
        online: TwoLinkOnlineConfig = ADAPTIVE_ONLINE,
        gains: Gains = DEFAULT_GAINS,
        sigma_nominal: ArrayLike | None = None,
        boost_bandwidth: float | None = 300.0,
        boost_duration: float = 0.2,
        name: str = "adaptive_ct",
        observer: bool = True,
        observer_bandwidth: float | None = None,
        torque_limit: ArrayLike | None = None,
    ) -> None:
        if not isinstance(online, TwoLinkOnlineConfig):
            raise ParameterError(f"online must be an TwoLinkOnlineConfig, got {type(online).__name__}")
        if boost_bandwidth is not None and not (np.isfinite(boost_bandwidth) and boost_bandwidth > 0):
            raise ParameterError(f"boost_bandwidth must be > 0 rad/s or None, got {boost_bandwidth!r}")
        if not (np.isfinite(boost_duration) and boost_duration >= 0):
            raise ParameterError(f"boost_duration must be >= 0 s, got {boost_duration!r}")
        if boost_bandwidth is not None and online.detector is None and boost_duration > 0:
            raise ParameterError("a boost after alarms needs an estimator with a change detector")
        self.online, self.gains, self.name = online, gains, name
        self.sigma_nominal = validate_sigma(
            _sice_sigma() if sigma_nominal is None else sigma_nominal, "sigma_nominal"
        )
        self.boost_bandwidth, self.boost_duration = boost_bandwidth, boost_duration
        if not isinstance(observer, bool | np.bool_):
            raise ParameterError(f"observer must be true or false, got {observer!r}")
        bw = observer_bandwidth
        if bw is not None and not (isinstance(bw, int | float) and np.isfinite(bw) and bw > 0):
            raise ParameterError(f"observer_bandwidth must be > 0 rad/s or None, got {observer_bandwidth!r}")
        self.observer = bool(observer)
        self.observer_bandwidth = None if observer_bandwidth is None else float(observer_bandwidth)
        lim = np.full(2, np.inf) if torque_limit is None else np.array(torque_limit, dtype=float).reshape(-1)
        if lim.shape != (2,) or not np.all(lim > 0):
            raise ParameterError(f"torque_limit must be two limits > 0 N m or None, got {torque_limit!r}")
        self.torque_limit = lim
        self.estimator: OnlineEstimator | None = None

    def reset(self, n_trials: int, sample_period: float) -> None:
        super().reset(n_trials, sample_period)
        cfg = self.online
        if cfg.sample_period != self.T:
            cfg = dataclasses.replace(cfg, sample_period=self.T)
        self.estimator = OnlineEstimator(cfg, n_trials, self.sigma_nominal)

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
        g = self.gains
        tau = computed_torque_law(q, qd, q_d, qd_d, qdd_d, self.estimator.sigma_model, g.kp, g.kd, g.lam)
        if self.observer:
            from adaptive_dd.controllers.two_link_observer import observe_batch

            st = self.estimator.state
            tau = observe_batch(self.observer_settings(self.T), st.sigma_model, q, qd, st.obs, tau)
        if self.boost_bandwidth is not None and self.boost_duration > 0:  # on the whole command
            boosted = self.estimator.state.since_alarm * self.T < self.boost_duration
            if boosted.any():
                dkp, dkd = self.boost_gains
                sg0, lim = self.sigma_nominal, self.torque_limit
                tau = boost_batch(tau, q, qd, q_d, qd_d, sg0, dkp, dkd, boosted, g.kp, g.kd, lim)
        return tau

    def observer_settings(self, sample_period: float) -> TwoLinkGains:
        """The observer's settings at ``sample_period`` (in a :class:`TwoLinkGains`, as the
        compiled loop has them): the N-joint ``adaptive_ct``'s defaults
        (:mod:`adaptive_dd.closed_loop.controllers`: ``0.4 / T``, 3x, 1 s, 0.5 s)."""
        from adaptive_dd.closed_loop.controllers import (
            OBSERVER_LEVEL_WINDOW,
            OBSERVER_THRESHOLD,
            OBSERVER_WARMUP,
            observer_bandwidth,
        )

        T = float(sample_period)
        beta = self.observer_bandwidth if self.observer_bandwidth is not None else observer_bandwidth(T)
        return two_link_gains(
            LAW_ADAPTIVE, observer=self.observer, T=T, obs_a=float(np.exp(-beta * T)), obs_stages=2,
            obs_kappa=float(OBSERVER_THRESHOLD), obs_alpha=min(1.0, T / OBSERVER_LEVEL_WINDOW),
            obs_warmup=round(OBSERVER_WARMUP / T),
        )  # fmt: skip

    @property
    def boost_gains(self) -> tuple[float, float]:
        """``(wb^2 - w^2, 2 zeta (wb - w))``: the feedback added during a boost, through M0(q)."""
        w, wb, z = self.gains.bandwidth, self.boost_bandwidth, self.gains.damping
        return wb**2 - w**2, 2.0 * z * (wb - w)

    def observe(self, q, qd, tau):
        self.estimator.update(q, qd, tau)
        if self.observer:
            from adaptive_dd.controllers.two_link_observer import observe_applied_batch

            observe_applied_batch(self.estimator.state.obs, tau)

    @property
    def sigma_hat(self) -> Array:
        return self.estimator.theta

    @property
    def skipped_samples(self):
        return self.estimator.state.n_skipped.copy()

    @property
    def alarm_times(self) -> list[list[float]] | None:
        return self.estimator.alarm_times if self.online.detector is not None else None

    def compiled_spec(self, sample_period: float) -> CompiledSpec:
        """The compiled loop's form: the gains, the nominal model (start and boost), the boost
        after an alarm, and the estimator at ``sample_period``."""
        g = self.gains
        boost = {}
        if self.boost_bandwidth is not None:
            dkp, dkd = self.boost_gains
            boost = dict(boost_kp=float(dkp), boost_kd=float(dkd), boost_lim=self.torque_limit.copy())
            boost["boost_samples"] = float(self.boost_duration / sample_period)
        obs = self.observer_settings(sample_period)._asdict()
        obs = {k: v for k, v in obs.items() if k == "observer" or k == "T" or k.startswith("obs_")}
        gains = two_link_gains(
            LAW_ADAPTIVE, self.sigma_nominal, kp=float(g.kp), kd=float(g.kd), lam=float(g.lam), **boost, **obs
        )
        online = self.online
        if online.sample_period != sample_period:
            online = dataclasses.replace(online, sample_period=sample_period)
        return CompiledSpec(gains, online)


def adaptive_ct(
    gains: Gains = DEFAULT_GAINS,
    sigma_nominal: ArrayLike | None = None,
    online: TwoLinkOnlineConfig = ADAPTIVE_ONLINE,
    **kwargs,
) -> AdaptiveCT:
    """Computed torque on the payload-swap estimator (see the module docstring)."""
    return AdaptiveCT(online, gains, sigma_nominal, name="adaptive_ct", **kwargs)


def adaptive_ct_paper(gains: Gains = DEFAULT_GAINS, sigma_nominal: ArrayLike | None = None) -> AdaptiveCT:
    """Computed torque on the paper's online M2 estimator (eqs. 14, 15, 19); the settings the paper
    leaves open (lambda(0), mu, the prior, a trace cap, the projection) are ours
    (:data:`PAPER_ONLINE`): the paper proposes no controller."""
    return AdaptiveCT(
        PAPER_ONLINE, gains, sigma_nominal, boost_bandwidth=None, name="adaptive_ct_paper", observer=False
    )
