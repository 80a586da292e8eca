"""adaptive_ct's residual observer, compiled: one sample per call.

The residual observer (``observer``, adaptive_ct's; :func:`_observe`): De Luca's
generalised-momentum observer of the torque the trial's model leaves unexplained,
``r = beta / (s + beta) (tau - d/dt p - wv)`` with ``p = M(q) qd`` and ``wv = g - C^T qd +
friction`` of ``pi_model``, discrete and consistent under a changing model (the momentum at the
last and at this measurement both with this sample's model), here low-passed once more
(``obs_stages = 2``: ``(beta / (s + beta))^2``, whose response to the measured velocity's white
noise rolls off instead of passing it at the gain beta up to the Nyquist frequency); ``r``
soft-thresholded at ``obs_kappa`` times its own learnt RMS level is added to the command. Noise
stays below the threshold; a payload's torque passes from the samples after the swap, before the
change is detected, and fades as the estimate learns it (``r`` is the residual of the current
model).

The settings are the fields ``obs_*`` of
:class:`~adaptive_dd.closed_loop.laws.LawConfig`, the state the rows ``O_*`` of
``LawState.obs (S, OBS_ROWS, n)``; the law (:func:`~adaptive_dd.closed_loop.laws.law_trial_in`)
calls the observer, and the closed loop :func:`observe_applied` after each sample. The two-link
arm compiles :func:`_observe` itself with its closed-form momentum
(:mod:`adaptive_dd.controllers.two_link_observer`): ``_momentum`` is looked up by name.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.plant.chain import momentum_in

__all__ = [
    "OBS_ROWS",
    "O_COUNT",
    "O_LEVEL",
    "O_R",
    "observe_applied",
]

# rows of the observer's per-trial state LawState.obs (S, OBS_ROWS, n)
O_R = 0  # the observed residual torque r [N m] (the last stage's output)
O_LEVEL = 1  # its learnt mean square (winsorised, not bias-corrected) [N^2 m^2]
O_Q, O_QD = 2, 3  # the last fresh measurement
O_TAU = 4  # the applied torques summed since that measurement [N m] (written by the closed loop)
O_COUNT = 5  # [0]: observer updates so far, [1]: samples summed in O_TAU
O_R1 = 6  # the first stage's output (two stages)
OBS_ROWS = O_R1 + 1


@njit(cache=True, _nrt=False)
def _momentum(ch, pi, q, qd, work, p, wv):  # pragma: no cover - compiled
    """``p = M(q) qd + Ia qd`` and ``wv = g - C^T qd + fv qd + fc sgn(qd)`` of ``pi (13 n,)``."""
    n = q.shape[0]
    momentum_in(ch, pi[: 10 * n], q, qd, work[0], p, wv)
    for j in range(n):
        p[j] += pi[12 * n + j] * qd[j]
        wv[j] += pi[10 * n + j] * qd[j] + pi[11 * n + j] * np.sign(qd[j])


@njit(cache=True, inline="always")
def observe_applied(obs, tau):  # pragma: no cover - compiled
    """Add the torque ``tau (n,)`` applied over one sample to the residual observer's state
    ``obs (OBS_ROWS, n)`` (the closed loop calls it after each sample's actuation)."""
    for j in range(tau.shape[0]):
        obs[O_TAU, j] += tau[j]
    obs[O_COUNT, 1] += 1.0


@njit(cache=True, _nrt=False)
def _observe(ch, cfg, pi, q, qd, obs, work, out):  # pragma: no cover - compiled
    """One sample of the residual observer (module docstring) at a fresh measurement ``q, qd``;
    its soft-thresholded output added to ``out``.

    ``obs`` holds the last fresh measurement and the applied torques summed since (``O_TAU``,
    ``O_COUNT[1]`` samples: the closed loop adds each sample's). Over those ``m`` samples the
    mean residual is ``rho = sum tau / m - (wv_last + wv_now) / 2 - (p_now - p_last) / (m T)``,
    both momenta with ``pi`` (consistent when the model changes), and ``r <- a^m r + (1 - a^m)
    rho``. A measurement equal to the last one (a lost sample held) is not fresh: ``r`` is
    kept and the torques go on being summed. The level learns ``min(r^2, kappa^2 level)``
    (winsorised: a payload's residual raises it slowly, a higher noise still gets learnt).
    """
    n = q.shape[0]
    held = obs[O_COUNT, 0] >= 1.0
    for j in range(n):
        held = held and q[j] == obs[O_Q, j] and qd[j] == obs[O_QD, j]
    m = obs[O_COUNT, 1]
    if obs[O_COUNT, 0] >= 1.0 and m >= 1.0 and not held:
        pw = work[7]
        _momentum(ch, pi, obs[O_Q], obs[O_QD], work, pw[0], pw[1])
        _momentum(ch, pi, q, qd, work, pw[2], pw[3])
        am = cfg.obs_a**m
        for j in range(n):
            rho = obs[O_TAU, j] / m - 0.5 * (pw[1, j] + pw[3, j]) - (pw[2, j] - pw[0, j]) / (m * cfg.T)
            if not np.isfinite(rho):
                continue
            if cfg.obs_stages == 2:
                obs[O_R1, j] = am * obs[O_R1, j] + (1.0 - am) * rho
                rho = obs[O_R1, j]
            obs[O_R, j] = am * obs[O_R, j] + (1.0 - am) * rho
    if not held:
        c = obs[O_COUNT, 0] + 1.0
        bias = 1.0 - (1.0 - cfg.obs_alpha) ** c
        for j in range(n):
            r2 = obs[O_R, j] * obs[O_R, j]
            if c > cfg.obs_warmup:
                r2 = min(r2, cfg.obs_kappa**2 * obs[O_LEVEL, j] / bias)
            obs[O_LEVEL, j] += cfg.obs_alpha * (r2 - obs[O_LEVEL, j])
            obs[O_Q, j], obs[O_QD, j], obs[O_TAU, j] = q[j], qd[j], 0.0
        obs[O_COUNT, 0] = c
        obs[O_COUNT, 1] = 0.0
    c = obs[O_COUNT, 0]
    if c <= cfg.obs_warmup:
        return
    bias = 1.0 - (1.0 - cfg.obs_alpha) ** c
    for j in range(n):
        thr = cfg.obs_kappa * np.sqrt(obs[O_LEVEL, j] / bias)
        r = obs[O_R, j]
        if r > thr:
            out[j] += r - thr
        elif r < -thr:
            out[j] += r + thr
