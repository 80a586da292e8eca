"""Online identification of sigma as a pure step: filters, RLS, change detection, re-opening, projection.

The estimator that adaptive control runs every sample, and that ``adaptive-dd identify
--online`` runs over a recorded experiment::

    state = online_init(cfg, n_trials, theta0)
    state, info = online_step(state, q, qd, tau, cfg)      # pure: returns a new state
    est = OnlineEstimator(cfg, n_trials, theta0)           # thin stateful wrapper
    rec = run_two_link_online(q, qd, tau, cfg, theta0)              # a whole record at once

One sample does, per trial (arrays carry the trial axis first):

1. **Filtered regression** of the M2 method (eqs. 19-20, Tustin): the paper's
   construction or the exact one (:mod:`~adaptive_dd.identification.regressors`),
   the torque optionally aligned to the sample instants, an equation used only when
   its joint moved for the filter's memory (data selection).
2. **RLS** of eq. (14) on the chosen split (``"15"``, ``"16"`` cascaded, or ``"full"``).
3. **Change detection** on the prior prediction errors (:class:`ChangeDetector`).
4. **Re-opening** of the covariance along the direction in which a tip payload moves
   sigma, at the alarm and once more when the filters' memory has passed it.
5. **Projection** of the model used for control onto physically consistent parameters
   (``project="model"``); the estimator's own state stays unprojected (projecting it
   biases least squares), unless ``project="state"``.

The arithmetic lives in one compiled kernel
(:func:`adaptive_dd.identification.two_link_online_kernel.online_step_trial`) that the Python
path and the compiled closed loop both call. The settings (:class:`TwoLinkOnlineConfig`,
:class:`ChangeDetector`, :func:`rearm_time`) are defined in
:mod:`adaptive_dd.identification.two_link_online_config` and importable from here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.identification import two_link_online_kernel as K
from adaptive_dd.identification.two_link_online_config import ChangeDetector, TwoLinkOnlineConfig, rearm_time
from adaptive_dd.plant.parameters import PROJECTION_J_MIN, PROJECTION_MARGIN, project_sigma

__all__ = [
    "ChangeDetector",
    "OnlineEstimator",
    "OnlineInfo",
    "OnlineState",
    "TwoLinkOnlineConfig",
    "TwoLinkOnlineRecord",
    "online_init",
    "online_step",
    "raise_alarm",
    "rearm_time",
    "run_two_link_online",
]

Array = NDArray[np.float64]


def raise_alarm(state: OnlineState, cfg: TwoLinkOnlineConfig, trials: ArrayLike | None = None) -> OnlineState:
    """The state after an alarm raised from outside (pure function), e.g. a gripper's signal.

    Does to each trial in ``trials`` (default: all) exactly what a detector alarm does
    (:func:`~adaptive_dd.identification.two_link_online_kernel.on_alarm`): re-opens the covariance along
    the payload direction and restarts the detector's levels, so the detector is re-armed
    within :func:`rearm_time`. The alarm is counted in ``state.alarms``.
    """
    if cfg.detector is None:
        raise ParameterError("raise_alarm: the TwoLinkOnlineConfig has no detector")
    new = state.copy()
    n = new.theta.shape[0]
    idx = np.arange(n) if trials is None else np.atleast_1d(np.asarray(trials, dtype=np.int64))
    if idx.size and (idx.min() < 0 or idx.max() >= n):
        raise ParameterError(f"raise_alarm: trials must lie in [0, {n - 1}], got {trials!r}")
    ci, cf, *_, d, group, _ = cfg.packed
    for i in idx:
        K.on_alarm(int(i), new.P, new.cnt, new.long, new.short, group, d, ci, cf)
    return new


class OnlineState(NamedTuple):
    """Estimator state of a batch of trials; every array has the trial axis first.

    xf : (n, 9, 2) filter states per channel; u_last : (n, 9) last finite channel sample;
    cnt : (n, 11) int counters (see ``online_kernel.C_*``: samples, alarms, skips, ...);
    tau_prev : (n, 2); theta : (n, 7) RLS estimate; P : (n, 7, 7); lam : (n, 2) forgetting
    factor per stage; short : (n, N_SHORT) detector statistics (``online_kernel.S_*``: short
    averages, payload-direction sums, persistence window, weights); long : (n, 2) long-run
    levels; sigma_model : (n, 7) the model for control (projected); obs : (n, OBS_ROWS, 2) the
    residual observer's state of the law that controls with ``sigma_model`` (``adaptive_ct``:
    :mod:`adaptive_dd.controllers.two_link_observer`; rows ``O_*`` of
    :mod:`adaptive_dd.closed_loop.laws`), not read by the estimator.
    """

    xf: Array
    u_last: Array
    cnt: NDArray[np.int64]
    tau_prev: Array
    theta: Array
    P: Array
    lam: Array
    short: Array
    long: Array
    sigma_model: Array
    obs: Array

    def copy(self) -> OnlineState:
        return OnlineState(*(a.copy() for a in self))

    @property
    def alarms(self) -> NDArray[np.int64]:
        """Alarms raised so far per trial."""
        return self.cnt[:, K.C_ALARMS]

    @property
    def n_skipped(self) -> NDArray[np.int64]:
        """Samples with an equation skipped as non-finite (sensor dropouts), per trial."""
        return self.cnt[:, K.C_SKIPPED]

    @property
    def since_alarm(self) -> NDArray[np.int64]:
        """Samples since the last alarm (large if none)."""
        return self.cnt[:, K.C_SINCE_ALARM]

    @property
    def estimator(self) -> tuple:
        """The fields the estimator's kernel reads and writes (all but ``obs``), in order."""
        return tuple(self)[:-1]


class OnlineInfo(NamedTuple):
    """What one step did, per trial: ``alarm (n,)`` bool, prior errors ``eps (n, 2)``, ``lam (n,)``."""

    alarm: NDArray[np.bool_]
    eps: Array
    lam: Array


def online_init(cfg: TwoLinkOnlineConfig, n_trials: int, theta0: ArrayLike) -> OnlineState:
    """Initial state: the estimate ``theta0 (7,) or (n, 7)``, the shaped start-up covariance.

    Parameters
    ----------
    cfg : TwoLinkOnlineConfig
        The estimator's settings.
    n_trials : int
        Trials estimated at once (the leading axis).
    theta0 : array_like, shape (7,) or (n_trials, 7)
        The start estimate (the paper's J1 J2 r b1 b2 d1 d2).

    Returns
    -------
    OnlineState
        The estimator's state, trial axis first.

    Examples
    --------
    >>> from adaptive_dd.identification.two_link_online import online_init
    >>> from adaptive_dd.identification.two_link_online_config import TwoLinkOnlineConfig
    >>> from adaptive_dd.plant import ClosedFormTwoLink
    >>> sigma = ClosedFormTwoLink.sice().sigma  # Table 1 of the paper
    >>> state = online_init(TwoLinkOnlineConfig(sample_period=1e-3), n_trials=4, theta0=sigma)
    >>> state.theta.shape  # trial axis first, the paper's seven base parameters
    (4, 7)
    """
    from adaptive_dd.closed_loop.laws import OBS_ROWS  # here: the closed-loop package imports this one

    if not isinstance(n_trials, int | np.integer) or n_trials < 1:
        raise ParameterError(f"n_trials must be an integer >= 1, got {n_trials!r}")
    th = np.broadcast_to(np.asarray(theta0, dtype=float), (n_trials, 7)).copy()
    if not np.all(np.isfinite(th)):
        raise ParameterError(f"theta0 must be finite, got {theta0}")
    cnt = np.zeros((n_trials, K.N_CNT), dtype=np.int64)
    cnt[:, K.C_SINCE_ALARM] = K.BIG
    cnt[:, K.C_REOPEN_AT] = -1
    model = th.copy() if cfg.project == "none" else project_sigma(th, PROJECTION_J_MIN, PROJECTION_MARGIN)
    if cfg.project == "state":
        th = model.copy()
    short = np.zeros((n_trials, K.N_SHORT))
    d = np.asarray(cfg.payload_direction, dtype=float)
    if d @ d > 0.0:  # the mass origin of the removal gate: the start estimate carries no payload
        short[:, K.S_M0] = th @ d / (d @ d)
    return OnlineState(
        xf=np.zeros((n_trials, 9, cfg.bank.order)),
        u_last=np.zeros((n_trials, 9)),
        cnt=cnt,
        tau_prev=np.zeros((n_trials, 2)),
        theta=th,
        P=np.broadcast_to(cfg.initial_covariance(), (n_trials, 7, 7)).copy(),
        lam=np.full((n_trials, 2), cfg.rls.lam0),
        short=short,
        long=np.zeros((n_trials, 2)),
        sigma_model=model,
        obs=np.zeros((n_trials, OBS_ROWS, 2)),
    )


def _as_sample(x: ArrayLike, n: int, name: str) -> Array:
    a = np.asarray(x, dtype=float)
    if a.shape != (n, 2):
        raise SignalError(f"{name} must have shape ({n}, 2), got {a.shape}")
    return np.ascontiguousarray(a)


def _step_in_place(state: OnlineState, q, qd, tau, cfg: TwoLinkOnlineConfig) -> OnlineInfo:
    n = state.theta.shape[0]
    q, qd, tau = (_as_sample(x, n, name) for x, name in ((q, "q"), (qd, "qd"), (tau, "tau")))
    eps = np.empty((n, 2))
    alarm = np.zeros(n, dtype=np.int64)
    K.online_step_batch(*state.estimator, q, qd, tau, *cfg.packed, eps, alarm)
    return OnlineInfo(alarm.astype(bool), eps, state.lam[:, 0].copy())


def online_step(
    state: OnlineState, q: ArrayLike, qd: ArrayLike, tau: ArrayLike, cfg: TwoLinkOnlineConfig
) -> tuple[OnlineState, OnlineInfo]:
    """Advance the estimator by one sample (pure function: ``state`` is not changed).

    Parameters
    ----------
    state : OnlineState
    q, qd : array_like, shape (n_trials, 2)
        Measured joint angles [rad] and velocities [rad/s] at this sample; a non-finite
        value (sensor dropout) is held, its equations skipped and counted.
    tau : array_like, shape (n_trials, 2)
        Torque applied over this sample [N m].
    cfg : TwoLinkOnlineConfig

    Returns
    -------
    state : OnlineState
    info : OnlineInfo
        Alarm, prior errors and forgetting factor of this sample.

    Examples
    --------
    >>> import numpy as np
    >>> from adaptive_dd.identification.two_link_online import online_init, online_step
    >>> from adaptive_dd.identification.two_link_online_config import TwoLinkOnlineConfig
    >>> from adaptive_dd.plant import ClosedFormTwoLink
    >>> cfg = TwoLinkOnlineConfig(sample_period=1e-3)
    >>> state = online_init(cfg, n_trials=3, theta0=ClosedFormTwoLink.sice().sigma)
    >>> q = qd = tau = np.zeros((3, 2))  # one sample of three trials (compiles on a cold cache)
    >>> new, info = online_step(state, q, qd, tau, cfg)
    >>> info.alarm, info.eps.shape, info.lam.shape
    (array([False, False, False]), (3, 2), (3,))
    >>> new is state  # a new state: the one given is not changed
    False
    """
    new = state.copy()
    return new, _step_in_place(new, q, qd, tau, cfg)


class OnlineEstimator:
    """Stateful wrapper of :func:`online_step` (updates its state in place).

    Attributes
    ----------
    state : OnlineState
    alarm_times : list of list of float
        Per trial, the times [s] of the alarms.
    """

    def __init__(self, cfg: TwoLinkOnlineConfig, n_trials: int, theta0: ArrayLike) -> None:
        self.cfg = cfg
        self.state = online_init(cfg, n_trials, theta0)
        self.alarm_times: list[list[float]] = [[] for _ in range(n_trials)]
        self.last_info: OnlineInfo | None = None

    @property
    def theta(self) -> Array:
        """The estimator's estimate ``(n, 7)``."""
        return self.state.theta

    @property
    def sigma_model(self) -> Array:
        """The model for control ``(n, 7)`` (projected unless ``project="none"``)."""
        return self.state.sigma_model

    def update(self, q: ArrayLike, qd: ArrayLike, tau: ArrayLike) -> OnlineInfo:
        """Feed one sample (see :func:`online_step`); return what happened."""
        t = self.state.cnt[0, K.C_K] * self.cfg.sample_period
        info = _step_in_place(self.state, q, qd, tau, self.cfg)
        if info.alarm.any():
            for b in np.flatnonzero(info.alarm):
                self.alarm_times[b].append(float(t))
        self.last_info = info
        return info


@dataclass(frozen=True)
class TwoLinkOnlineRecord:
    """The online estimator run over records; arrays are ``(n_trials, n_samples, ...)``.

    Attributes
    ----------
    t : (n_samples,) sample times [s]
    theta : estimator's estimate after each sample
    sigma_model : model for control after each sample
    alarm : bool, a change alarm at that sample
    eps : (…, 2) prior errors (NaN where an equation was not used)
    lam : forgetting factor
    n_skipped : (n_trials,) samples with a non-finite equation
    """

    t: Array
    theta: Array
    sigma_model: Array
    alarm: NDArray[np.bool_]
    eps: Array
    lam: Array
    n_skipped: NDArray[np.int64]

    def alarm_times(self) -> list[list[float]]:
        """Per trial, the times [s] of the alarms."""
        return [list(self.t[np.flatnonzero(a)]) for a in self.alarm]


def run_two_link_online(
    q: ArrayLike, qd: ArrayLike, tau: ArrayLike, cfg: TwoLinkOnlineConfig, theta0: ArrayLike
) -> TwoLinkOnlineRecord:
    """Run the online estimator over whole records ``q, qd, tau (n_trials, n_samples, 2)``.

    Equals :func:`online_step` sample by sample (one compiled loop per trial).

    Parameters
    ----------
    q, qd, tau : array_like, shape (n_trials, n_samples, 2)
        Measured positions [rad], velocities [rad/s] and applied torques [N m].
    cfg : TwoLinkOnlineConfig
        The estimator's settings.
    theta0 : array_like, shape (7,)
        The start estimate.

    Returns
    -------
    TwoLinkOnlineRecord
        The estimates, forgetting factors, prior errors and alarms over time.

    Examples
    --------
    The estimator over 0.5 s of the paper's arm driven by two sines (the plant and the estimator
    compile on a cold cache):

    >>> import numpy as np
    >>> from adaptive_dd.identification.two_link_online import run_two_link_online
    >>> from adaptive_dd.identification.two_link_online_config import TwoLinkOnlineConfig
    >>> from adaptive_dd.plant import ClosedFormTwoLink
    >>> from adaptive_dd.plant.simulator import simulate_open_loop
    >>> t = np.arange(500) * 1e-3
    >>> drive = np.stack([2 * np.sin(4 * np.pi * t), np.cos(6 * np.pi * t)], axis=-1)[None]  # [N m]
    >>> sim = simulate_open_loop(drive, np.random.default_rng(0))
    >>> cfg = TwoLinkOnlineConfig(sample_period=1e-3)
    >>> rec = run_two_link_online(sim.q_meas, sim.qd_meas, sim.tau, cfg, ClosedFormTwoLink.sice().sigma)
    >>> rec.theta.shape, rec.alarm_times()  # trials x samples x the seven parameters; no alarm
    ((1, 500, 7), [[]])
    """
    q, qd, tau = (np.ascontiguousarray(np.asarray(x, dtype=float)) for x in (q, qd, tau))
    if q.ndim == 2:
        q, qd, tau = q[None], qd[None], tau[None]
    if q.ndim != 3 or q.shape[-1] != 2 or qd.shape != q.shape or tau.shape != q.shape:
        raise SignalError(
            f"q, qd and tau must share a shape (n_trials, n_samples, 2), got "
            f"{q.shape}, {qd.shape}, {tau.shape}"
        )
    n, N, _ = q.shape
    state = online_init(cfg, n, theta0)
    theta = np.empty((n, N, 7))
    model = np.empty((n, N, 7))
    eps = np.empty((n, N, 2))
    alarm = np.zeros((n, N), dtype=np.int64)
    lam = np.empty((n, N))
    for i in range(n):
        K.online_run_trial(
            i, *state.estimator, q[i], qd[i], tau[i], *cfg.packed, theta[i], model[i], eps[i], alarm[i],
            lam[i],
        )  # fmt: skip
    t = np.arange(N) * cfg.sample_period
    return TwoLinkOnlineRecord(t, theta, model, alarm.astype(bool), eps, lam, state.n_skipped.copy())
