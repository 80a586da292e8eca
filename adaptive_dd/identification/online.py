"""Online identification for any serial arm (N joints): a compiled pure step.

The N-joint generalisation of :mod:`~adaptive_dd.identification.two_link_online`::

    c, s = est_init(cfg, arm, n_trials)               # EstCfg (read-only), EstState (in place)
    alarm = est_step_trial(c, s, i, q, qd, tau)       # compiled: one sample of trial i
    est_model_trial(c, s, i, pi_out)                  # compiled: the model control uses (13 n,)
    w = est_work(n, p)                                # scratch of a trial, reused from sample to sample:
    est_step_trial_in(c, s, i, q, qd, tau, w); est_model_trial_in(c, s, i, pi_out, w)  # (no allocation)
    info = est_step(c, s, q, qd, tau)                 # Python: every trial, the same kernel
    rec = run_online(arm, cfg, q, qd, tau)     # a whole record; equals stepping

Two modes (:class:`OnlineConfig`):

``"payload"`` (default)
    The arm is known (its standard parameters ``arm.pi``); the ten parameters of the
    payload about its frame are estimated, as industrial payload identification does.
    Equation: ``y = G0 tau - (G1 p + G0 wv) = phi theta`` with ``phi = (G1 py + G0 wy) @
    payload_map`` (n x 10): the known arm's momentum form and the payload link's columns.
``"arm"``
    The arm's base parameters (prior covariance from the URDF's stated uncertainty,
    :mod:`~adaptive_dd.identification.arm_prior`; never re-opened) and the payload's ten
    parameters apart (columns: the payload link's through ``payload_map``; re-opened alone at
    an alarm). Equation: the momentum form of every link plus friction and armature columns
    (``docs/learning_the_arm.md``).

In payload mode the equation is the momentum form of the known arm and the payload's link,
filtered by the M2 bank (eq. 20, Tustin): ``G0 tau = G1 p + G0 wv`` (no acceleration, exact for
any filter; :mod:`~adaptive_dd.identification.online_kernel`). The estimator is RLS with the
variable forgetting factor of eq. (14), one scalar update per joint equation (the paper's
splits generalised: each row is a split; the forgetting factor advances once per sample).
The change detector, the re-opening along the payload subspace, the start-up covariance
shaped along the payload subspace and the projection of the control model (not of the
estimator's state) follow the lessons of ``payload-swap-adaptation.md`` (see
:func:`~adaptive_dd.identification.online_detector._detect`).

**Re-arm bound.** After any alarm, the next alarm is possible as soon as
``since_alarm > holdoff`` and one used row has been seen ``min_learned`` times from
``resume`` samples after the alarm on: at most ``max(holdoff, resume + min_learned)``
samples in which that row is in use; the level established before the alarm serves no longer
than ``resume + min_learned`` samples after it (``OnlineConfig.rearm_samples``). The level
does not learn from a sample whose squared error exceeds ``gate^2`` times it, so a
change that happens while the detector re-learns is still detected at re-arm.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import SignalError
from adaptive_dd.identification import online_kernel as K
from adaptive_dd.identification.online_config import (  # noqa: F401 (re-exported)
    DEFAULT_PRIOR_RADIUS,
    MODES,
    REOPEN_CAPACITY,
    REOPEN_GENERIC,
    WARMUP,
    WARMUP_ARM,
    Array,
    Detector,
    OnlineConfig,
    _bank,
    _bool,
    _int,
    _num,
    derived_row_weights,
    payload_prior,
    reopen_mass_std,
)
from adaptive_dd.identification.online_init import (  # noqa: F401 (re-exported)
    _channels,
    _detector_velocity_variance,
    _pack,
    est_init,
)
from adaptive_dd.identification.online_kernel import (
    EstCfg,
    EstState,
    compact_prior,
    est_detect_trial,
    est_force_alarm_trial,
    est_model_trial,
    est_model_trial_in,
    est_payload_trial,
    est_step_trial,
    est_step_trial_in,
    est_work,
)
from adaptive_dd.identification.pseudo_inertia import project_payload
from adaptive_dd.plant.arm import Arm

__all__ = [
    "Detector",
    "EstCfg",
    "EstInfo",
    "EstState",
    "OnlineConfig",
    "OnlineRecord",
    "compact_prior",
    "derived_row_weights",
    "est_detect_trial",
    "est_force_alarm_trial",
    "est_init",
    "est_model",
    "est_model_trial",
    "est_model_trial_in",
    "est_payload_trial",
    "est_step",
    "est_step_trial",
    "est_step_trial_in",
    "est_work",
    "payload_prior",
    "project_payload",
    "reopen_mass_std",
    "run_online",
    "state_alarms",
    "state_skipped",
]


class EstInfo(NamedTuple):
    """What one :func:`est_step` did, per trial: ``alarm (m,)`` bool, weighted prior errors
    ``eps (m, n)`` (NaN where a row was not used), forgetting factor ``lam (m,)``."""

    alarm: NDArray[np.bool_]
    eps: Array
    lam: Array


def _sample(x: ArrayLike, shape: tuple, name: str) -> Array:
    a = np.asarray(x, dtype=float)
    if a.shape != shape:
        raise SignalError(f"{name} must have shape {shape}, got {a.shape}")
    return np.ascontiguousarray(a)


def est_step(c: EstCfg, s: EstState, q: ArrayLike, qd: ArrayLike, tau: ArrayLike) -> EstInfo:
    """One sample of every trial (``q, qd, tau (m, n)``), updating ``s`` in place.

    The same compiled :func:`est_step_trial` as the closed loop. Non-finite values are
    skipped and counted (``state_skipped(s)``).
    """
    shape = s.eps.shape
    q, qd, tau = (_sample(x, shape, nm) for x, nm in ((q, "q"), (qd, "qd"), (tau, "tau")))
    alarm = np.zeros((shape[0], 1), dtype=np.int64)
    none = np.empty((0, 1, 0))  # no record (no trial): alarms alone
    K.est_run(c, s, 0, q[:, None], qd[:, None], tau[:, None], none, none, none, alarm, np.empty((0, 1)))
    return EstInfo(alarm[:, 0].astype(bool), s.eps.copy(), s.lam.copy())


def est_model(c: EstCfg, s: EstState) -> Array:
    """The model control uses, standard parameters ``(m, 13 n)`` (see :func:`est_model_trial`)."""
    out = np.empty((s.theta.shape[0], c.pi0.shape[0]))
    for i in range(out.shape[0]):
        est_model_trial(c, s, i, out[i])
    return out


def state_alarms(s: EstState) -> NDArray[np.int64]:
    """Alarms raised so far, per trial."""
    return s.cnt[:, K.C_ALARMS].copy()


def state_skipped(s: EstState) -> NDArray[np.int64]:
    """Samples skipped as non-finite, per trial."""
    return s.cnt[:, K.C_SKIPPED].copy()


@dataclass(frozen=True)
class OnlineRecord:
    """The estimator run over records; arrays ``(n_trials, n_samples, ...)``.

    Attributes
    ----------
    t : (n_samples,) sample times [s]
    theta : (..., p) the estimator's estimate after each sample
    payload : (..., 10) the payload it implies (projected if ``cfg.project``), about the payload frame
    alarm : bool (...) a change alarm at that sample
    eps : (..., n) weighted prior errors (NaN where a row was not used)
    lam : (...) forgetting factor
    n_skipped : (n_trials,) samples skipped as non-finite
    """

    t: Array
    theta: Array
    payload: Array
    alarm: NDArray[np.bool_]
    eps: Array
    lam: Array
    n_skipped: NDArray[np.int64]

    @property
    def mass(self) -> Array:
        """Payload mass [kg], ``(n_trials, n_samples)``."""
        return self.payload[..., 0]

    @property
    def com(self) -> Array:
        """Payload centre of mass [m] in its frame, ``(n_trials, n_samples, 3)`` (NaN at zero mass)."""
        m = self.payload[..., :1]
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(m > 0, self.payload[..., 1:4] / m, np.nan)

    def alarm_times(self) -> list[list[float]]:
        """Per trial, the times [s] of the alarms."""
        return [list(self.t[np.flatnonzero(a)]) for a in self.alarm]


def run_online(
    arm: Arm,
    cfg: OnlineConfig,
    q: ArrayLike,
    qd: ArrayLike,
    tau: ArrayLike,
    sigma_nominal: ArrayLike | None = None,
) -> OnlineRecord:
    """Run the estimator over whole records ``q, qd, tau (n_samples, n)`` or ``(n_trials, n_samples, n)``.

    Equals :func:`est_step` sample by sample, bit for bit (one compiled loop per trial
    over the same :func:`est_step_trial`).
    """
    q, qd, tau = (np.ascontiguousarray(np.asarray(x, dtype=float)) for x in (q, qd, tau))
    if q.ndim == 2:
        q, qd, tau = q[None], qd[None], tau[None]
    n = arm.n_joints
    if q.ndim != 3 or q.shape[-1] != n or qd.shape != q.shape or tau.shape != q.shape:
        raise SignalError(
            f"q, qd and tau must share a shape (n_trials, n_samples, {n}), "
            f"got {q.shape}, {qd.shape}, {tau.shape}"
        )
    m, N, _ = q.shape
    c, s = est_init(cfg, arm, m, sigma_nominal)
    p = s.theta.shape[1]
    theta = np.empty((m, N, p))
    payload = np.empty((m, N, 10))
    eps = np.empty((m, N, n))
    alarm = np.zeros((m, N), dtype=np.int64)
    lam = np.empty((m, N))
    K.est_run(c, s, 0, q, qd, tau, theta, payload, eps, alarm, lam)
    t = np.arange(N) * cfg.sample_period
    return OnlineRecord(t, theta, payload, alarm.astype(bool), eps, lam, state_skipped(s))
