"""Slotine and Li's composite adaptation's prediction-error term, compiled: one sample per call.

Composite adaptive control (Slotine and Li, "Composite Adaptive Control of Robot Manipulators",
Automatica 25(4), 1989) drives the payload's parameters by the tracking error and by the error
of the filtered torque predicted by the estimate: ``theta' = Gamma (Y_p^T s + W^T R eps)``, with
``W = F Phi_p`` the filtered payload regressor, ``eps = F tau_r - W theta`` and ``tau_r`` the
applied torque less the nominal arm's. The filter ``F = rate / (s + rate)`` is applied to the
dynamics in momentum form, ``tau = d/dt p + wv`` (:func:`~adaptive_dd.plant.chain.momentum_form_in`),
so that no acceleration is needed and the regressor is filtered exactly: over the ``m`` samples
between two fresh measurements ``tau_mean = (p_now - p_last) / (m T) + (wv_last + wv_now) / 2``,
the same discrete form as the residual observer's (:mod:`adaptive_dd.closed_loop.residual_observer`).

State: rows of the law's per-trial ``obs (OBS_ROWS, n)`` (the residual observer is off for this
law): the last fresh measurement (``O_Q``, ``O_QD``), the applied torques summed since and their
count (``O_TAU``, ``O_COUNT``: written by the closed loop), and the rows ``C_*`` below.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.closed_loop.residual_observer import O_COUNT, O_Q, O_QD, O_TAU
from adaptive_dd.plant.chain import momentum_form_in

__all__ = ["C_P", "C_PY", "C_TF", "C_W", "C_WV", "C_WY", "composite_term"]

C_TF = 0  # the filtered torque less the nominal arm's [N m]
C_P = 1  # the nominal arm's momentum at the last fresh measurement [N m s]
C_WV = 6  # its wv there [N m]
C_PY = 8  # rows C_PY + c: column c of the payload link's momentum regressor there
C_WY = C_PY + 10  # rows C_WY + c: the same of wv
C_W = C_WY + 10  # rows C_W + k: column k of the filtered payload regressor W
C_ROWS = C_W + 10  # rows used (the observer's state has more)


@njit(cache=True)
def composite_term(ch, cfg, q, qd, theta, obs, work, gx):  # pragma: no cover - compiled
    """``gx (10,) = W^T R eps`` at a fresh measurement ``q, qd`` (zero at a held one, and until
    two fresh measurements were seen), the filters and the stored measurement updated.

    ``cfg.comp_rate`` is the filter's rate [rad/s], ``cfg.comp_weight (n,)`` R's diagonal
    [1/(N m s)], ``cfg.pi_fixed`` the nominal arm, ``cfg.payload_joint`` / ``payload_map`` the
    payload's link and map (as Slotine-Li's adaptation). Scratch: ``work`` of
    :func:`~adaptive_dd.closed_loop.laws.law_work`."""
    n = q.shape[0]
    for k in range(10):
        gx[k] = 0.0
    held = obs[O_COUNT, 0] >= 1.0
    for r in range(n):
        held = held and q[r] == obs[O_Q, r] and qd[r] == obs[O_QD, r]
    if held:
        return
    p, wv, py, wy = work[7][0], work[7][1], work[8][0], work[8][1]
    pi = cfg.pi_fixed
    momentum_form_in(ch, pi[: 10 * n], np.int64(cfg.payload_joint), q, qd, work[0], work[6], p, wv, py, wy)
    for r in range(n):
        p[r] += pi[12 * n + r] * qd[r]
        wv[r] += pi[10 * n + r] * qd[r] + pi[11 * n + r] * np.sign(qd[r])
    m = obs[O_COUNT, 1]
    if obs[O_COUNT, 0] >= 1.0 and m >= 1.0:
        _filter_step(cfg, n, m, obs, p, wv, py, wy)
        for r in range(n):
            eps = obs[C_TF, r]
            for k in range(10):
                eps -= obs[C_W + k, r] * theta[k]
            if np.isfinite(eps):
                for k in range(10):
                    gx[k] += obs[C_W + k, r] * cfg.comp_weight[r] * eps
    for r in range(n):
        obs[C_P, r], obs[C_WV, r] = p[r], wv[r]
        for c in range(10):
            obs[C_PY + c, r], obs[C_WY + c, r] = py[r, c], wy[r, c]
        obs[O_Q, r], obs[O_QD, r], obs[O_TAU, r] = q[r], qd[r], 0.0
    obs[O_COUNT, 0] += 1.0
    obs[O_COUNT, 1] = 0.0


@njit(cache=True)
def _filter_step(cfg, n, m, obs, p, wv, py, wy):  # pragma: no cover - compiled
    """One step of ``F`` on the residual torque and on the payload's regressor over ``m`` samples."""
    dt = m * cfg.T
    a = np.exp(-cfg.comp_rate * dt)
    for r in range(n):
        res = obs[O_TAU, r] / m - (p[r] - obs[C_P, r]) / dt - 0.5 * (wv[r] + obs[C_WV, r])
        if np.isfinite(res):
            obs[C_TF, r] = a * obs[C_TF, r] + (1.0 - a) * res
        for k in range(10):
            phi = 0.0
            for c in range(10):
                d = (py[r, c] - obs[C_PY + c, r]) / dt + 0.5 * (wy[r, c] + obs[C_WY + c, r])
                phi += d * cfg.payload_map[c, k]
            if np.isfinite(phi):
                obs[C_W + k, r] = a * obs[C_W + k, r] + (1.0 - a) * phi
