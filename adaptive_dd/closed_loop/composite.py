"""The prediction-error terms of composite adaptation and of integral concurrent learning,
compiled: one sample per call.

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

Integral concurrent learning (Parikh, Kamalapurkar and Dixon, "Integral concurrent learning:
Adaptive control with parameter convergence using finite excitation", Int. J. Adapt. Control
Signal Process. 33(12), 2019) uses the same measurements integrated over
windows instead of filtered: ``U_i = int tau_r dt`` and ``Y_i = int Phi_p dt`` over a window of
``cfg.icl_window`` seconds (in momentum form the integral of the acceleration term is the
momentum's change: exact, no acceleration), kept in a history stack of :data:`ICL_SLOTS` windows,
and adds ``(1 / N) sum_i Ybar_i^T R (Ubar_i - Ybar_i theta)`` (``Ybar = Y / window``,
``Ubar = U / window``, the window means; ``N`` the windows stored) to Slotine-Li's step. The
data-selection rule is recency: a closed window replaces the oldest one, so that after a payload
swap the stack holds the new payload's data within ``ICL_SLOTS * icl_window`` seconds (the
rank-maximising rule of Chowdhary and Johnson, which the paper uses for constant parameters,
would keep the old payload's windows as long as they are the most exciting). Rows ``I_*``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.closed_loop.adaptation import ADAPT_ICL
from adaptive_dd.closed_loop.residual_observer import O_COUNT, O_Q, O_QD, O_TAU
from adaptive_dd.plant.chain import momentum_form_in

__all__ = [
    "C_P", "C_PY", "C_ROWS", "C_TF", "C_W", "C_WV", "C_WY", "ICL_ROWS", "ICL_SLOTS", "composite_term",
]  # fmt: skip

C_TF = 0  # the filtered torque less the nominal arm's [N m]
C_P = 1  # the nominal arm's momentum at the last fresh measurement [N m s]
C_WV = 6  # its wv there [N m]
C_PY = 8  # rows C_PY + c: column c of the payload link's momentum regressor there
C_WY = C_PY + 10  # rows C_WY + c: the same of wv
C_W = C_WY + 10  # rows C_W + k: column k of the filtered payload regressor W
C_ROWS = C_W + 10  # rows used (the observer's state has more)
I_U = C_ROWS  # the open window's integrated residual torque [N m s]
I_Y = I_U + 1  # rows I_Y + k: its integrated payload regressor, column k
I_T = I_Y + 10  # [0]: the open window's length so far [s]
I_N = I_T + 1  # [0]: windows in the stack
I_NEXT = I_N + 1  # [0]: the stack's slot the next window goes to
I_S = I_NEXT + 1  # slot i: row I_S + 11 i the mean residual Ubar, rows I_S + 11 i + 1 + k Ybar's column k
ICL_SLOTS = 10
"""Windows in integral concurrent learning's history stack."""
ICL_ROWS = I_S + 11 * ICL_SLOTS


@njit(cache=True)
def composite_term(ch, cfg, q, qd, theta, obs, work, gx):  # pragma: no cover - compiled
    """``gx (10,) = W^T R eps`` at a fresh measurement ``q, qd`` (zero at a held one, and until
    two fresh measurements were seen), the filters and the stored measurement updated. With
    ``cfg.adapt_kind == ADAPT_ICL``, integral concurrent learning's term instead, ``gx = (1 / N)
    sum_i Ybar_i^T R (Ubar_i - Ybar_i theta)`` over the history stack (zero while it is empty),
    the open window and the stack updated (module docstring).

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
    if obs[O_COUNT, 0] >= 1.0 and m >= 1.0 and cfg.adapt_kind == ADAPT_ICL:
        _icl_step(cfg, n, m, obs, p, wv, py, wy)
        _icl_gradient(cfg, n, obs, theta, gx)
    elif obs[O_COUNT, 0] >= 1.0 and m >= 1.0:
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
def _increment(cfg, n, m, obs, p, wv, py, wy, r, k):  # pragma: no cover - compiled
    """Joint ``r``'s mean residual torque over the ``m`` samples since the last fresh measurement
    (``k < 0``), or column ``k`` of its payload regressor (momentum form, as the module says)."""
    dt = m * cfg.T
    if k < 0:
        return obs[O_TAU, r] / m - (p[r] - obs[C_P, r]) / dt - 0.5 * (wv[r] + obs[C_WV, r])
    phi = 0.0
    for c in range(10):
        d = (py[r, c] - obs[C_PY + c, r]) / dt + 0.5 * (wy[r, c] + obs[C_WY + c, r])
        phi += d * cfg.payload_map[c, k]
    return phi


@njit(cache=True)
def _icl_step(cfg, n, m, obs, p, wv, py, wy):  # pragma: no cover - compiled
    """Integrate ``m`` samples into the open window; a window of ``cfg.icl_window`` s or longer goes
    to the stack's oldest slot as its means, and a new window opens."""
    dt = m * cfg.T
    u = np.empty(n)
    ok = True
    for r in range(n):
        u[r] = _increment(cfg, n, m, obs, p, wv, py, wy, r, -1)
        ok = ok and np.isfinite(u[r])
    if not ok:  # a non-finite sample: this window is lost
        for r in range(n):
            for row in range(I_U, I_T + 1):
                obs[row, r] = 0.0
        return
    for r in range(n):
        obs[I_U, r] += u[r] * dt
        for k in range(10):
            obs[I_Y + k, r] += _increment(cfg, n, m, obs, p, wv, py, wy, r, k) * dt
    obs[I_T, 0] += dt
    if obs[I_T, 0] < cfg.icl_window:
        return
    slot = int(obs[I_NEXT, 0])
    base = I_S + 11 * slot
    span = obs[I_T, 0]
    for r in range(n):
        for row in range(11):
            obs[base + row, r] = obs[I_U + row, r] / span
            obs[I_U + row, r] = 0.0
    obs[I_T, 0] = 0.0
    obs[I_N, 0] = min(obs[I_N, 0] + 1.0, float(ICL_SLOTS))
    obs[I_NEXT, 0] = float((slot + 1) % ICL_SLOTS)


@njit(cache=True)
def _icl_gradient(cfg, n, obs, theta, gx):  # pragma: no cover - compiled
    """``gx = (1 / N) sum_i Ybar_i^T R (Ubar_i - Ybar_i theta)`` over the stored windows."""
    count = int(obs[I_N, 0])
    for i in range(count):
        base = I_S + 11 * i
        for r in range(n):
            eps = obs[base, r]
            for k in range(10):
                eps -= obs[base + 1 + k, r] * theta[k]
            w = cfg.comp_weight[r] * eps / count
            for k in range(10):
                gx[k] += obs[base + 1 + k, r] * w


@njit(cache=True)
def _filter_step(cfg, n, m, obs, p, wv, py, wy):  # pragma: no cover - compiled
    """One step of ``F`` on the residual torque and on the payload's regressor over ``m`` samples."""
    dt = m * cfg.T
    a = np.exp(-cfg.comp_rate * dt)
    for r in range(n):
        res = _increment(cfg, n, m, obs, p, wv, py, wy, r, -1)
        if np.isfinite(res):
            obs[C_TF, r] = a * obs[C_TF, r] + (1.0 - a) * res
        for k in range(10):
            phi = _increment(cfg, n, m, obs, p, wv, py, wy, r, k)
            if np.isfinite(phi):
                obs[C_W + k, r] = a * obs[C_W + k, r] + (1.0 - a) * phi
