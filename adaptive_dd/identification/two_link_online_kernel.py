"""Compiled per-trial kernel of the online estimator (see :mod:`adaptive_dd.identification.two_link_online`).

One call of :func:`online_step_trial` advances trial ``i`` of a batch of estimator
states by one sample, in place: the M2 derivative filter bank (eq. 19/20, Tustin),
the filtered regression (the paper's construction or the exact one), data
selection, recursive least squares (eq. 14) on the chosen split, the change
detector, covariance re-opening along the payload direction and projection of the
model used for control. The Python path (:func:`~adaptive_dd.identification.two_link_online.online_step`)
and the compiled closed loop call this same function; nothing here is duplicated.

Configuration travels as two flat arrays (``cf`` floats, ``ci`` integers) whose
slots are the constants of :mod:`adaptive_dd.identification.two_link_online_slots` (read
here as this module's too), plus the filter matrices, the payload
direction and the parameter groups of the split. This keeps the kernel a plain
numba function of arrays (cacheable, callable from other compiled code).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.identification.two_link_detector_kernel import _detect
from adaptive_dd.identification.two_link_momentum_test import momentum_test
from adaptive_dd.identification.two_link_online_slots import (  # noqa: F401 (read as K.NAME by the estimator)
    BIG,
    C_ALARMS,
    C_K,
    C_LEARNED1,
    C_LEARNED2,
    C_REOPEN_AT,
    C_SINCE_ALARM,
    C_SINCE_BAD,
    C_SINCE_SLOW1,
    C_SINCE_SLOW2,
    C_SINCE_SLOW_DET1,
    C_SKIPPED,
    C_STARTED,
    F_ALPHA_DIR,
    F_ALPHA_LONG,
    F_ALPHA_PERSIST,
    F_ALPHA_SHORT,
    F_CAP0,
    F_CAP1,
    F_DET_SPEED,
    F_GLR_THRESHOLD,
    F_HETERO,
    F_J_MIN,
    F_LAM0,
    F_MARGIN,
    F_MG_THRESHOLD,
    F_MIN_EXPLAINED,
    F_MIN_MASS,
    F_MU,
    F_P_J2,
    F_P_MASS,
    F_R_MIN,
    F_REMOVAL,
    F_SEL_THRESHOLD,
    F_T,
    F_THRESHOLD2,
    F_XS0,
    G_A,
    G_AGE,
    G_E,
    G_OFF,
    G_X,
    GLR_CANDIDATES,
    GLR_CHANNELS,
    GLR_STRIDE,
    I_ALIGN,
    I_CONSTRUCTION,
    I_DETECT,
    I_FREEZE,
    I_GLR_MIN_AGE,
    I_GLR_SPACING,
    I_HOLDOFF,
    I_MIN_LEARNED,
    I_PERSIST_MIN,
    I_PROJECT,
    I_REOPEN_AGAIN,
    I_RESUME,
    I_SEL_MEMORY,
    I_SELECT,
    I_SPEED_MEMORY,
    I_SPLIT,
    I_TAINT,
    I_WARMUP,
    N_CF,
    N_CI,
    N_CNT,
    N_SHORT,
    S_DIR,
    S_E2,
    S_GLR,
    S_LREF,
    S_M0,
    S_PER,
    S_PER_N,
)
from adaptive_dd.plant.sampling import project_trial


@njit(cache=True)
def _channels(cons, q, qd, tau, u):  # pragma: no cover - compiled
    """Raw channels of one sample into ``u``; returns their number."""
    if cons == 1:
        c2, s2 = np.cos(q[1]), np.sin(q[1])
        u[0], u[1] = qd[0], qd[1]
        u[2] = c2 * (2.0 * qd[0] + qd[1])
        u[3] = c2 * qd[0]
        u[4] = s2 * qd[0] * (qd[0] + qd[1])
        u[5], u[6] = np.sign(qd[0]), np.sign(qd[1])
        u[7], u[8] = tau[0], tau[1]
        return 9
    u[0], u[1], u[2], u[3] = q[0], q[1], qd[0], qd[1]
    u[4], u[5] = np.sign(qd[0]), np.sign(qd[1])
    u[6], u[7] = tau[0], tau[1]
    return 8


@njit(cache=True)
def _assemble(cons, f, phi, y):  # pragma: no cover - compiled
    """Regression ``y = phi sigma`` (2 x 7) from filtered channels ``f (n_ch, 2)`` = [G0, G1]."""
    for r in range(2):
        for j in range(7):
            phi[r, j] = 0.0
    if cons == 1:
        phi[0, 0] = f[0, 1]
        phi[0, 1] = f[0, 1] + f[1, 1]
        phi[1, 1] = phi[0, 1]
        phi[0, 2] = f[2, 1]
        phi[1, 2] = f[3, 1] + f[4, 0]
        phi[0, 3] = f[0, 0]
        phi[1, 4] = f[1, 0]
        phi[0, 5] = f[5, 0]
        phi[1, 6] = f[6, 0]
        y[0], y[1] = f[7, 0], f[8, 0]
        return
    q2 = f[1, 0]
    v1, v2 = f[2, 0], f[3, 0]
    a1, a2 = f[2, 1], f[3, 1]
    c2, s2 = np.cos(q2), np.sin(q2)
    phi[0, 0] = a1
    phi[0, 1] = a1 + a2
    phi[1, 1] = a1 + a2
    phi[0, 2] = c2 * (2.0 * a1 + a2) - s2 * (2.0 * v1 * v2 + v2 * v2)
    phi[1, 2] = c2 * a1 + s2 * v1 * v1
    phi[0, 3] = v1
    phi[1, 4] = v2
    phi[0, 5] = f[4, 0]
    phi[1, 6] = f[5, 0]
    y[0], y[1] = f[6, 0], f[7, 0]


@njit(cache=True)
def _filter(xf, u, n_ch, A, B, C, D, f):  # pragma: no cover - compiled
    """One sample of the filter bank on n_ch channels; outputs into f (n_ch, n_out)."""
    order = A.shape[0]
    n_out = C.shape[0]
    tmp = np.empty(order)
    for c in range(n_ch):
        for o in range(n_out):
            acc = D[o] * u[c]
            for m in range(order):
                acc += C[o, m] * xf[c, m]
            f[c, o] = acc
        for m in range(order):
            acc = B[m] * u[c]
            for n in range(order):
                acc += A[m, n] * xf[c, n]
            tmp[m] = acc
        for m in range(order):
            xf[c, m] = tmp[m]


@njit(cache=True)
def _rls_update(theta, P, lam, stage, phi, y, group, g, cf, forget):  # pragma: no cover
    """Eq. (14) for one scalar equation on parameter group g; returns the prior error.

    The same arithmetic as :func:`~adaptive_dd.identification.rls.rls_step`; P is kept
    block diagonal over the groups, so the update touches group g's block only: the
    group's indices are gathered once (ascending, so every sum runs in the order of the
    full loops) and the loops run over the block alone.
    A non-finite equation or a non-positive denominator leaves everything unchanged
    and returns NaN.
    """
    n = theta.shape[0]
    lam_prev = lam[stage]
    lam_new = (1.0 - cf[F_MU]) * lam_prev + cf[F_MU] if forget else lam_prev
    lam_eff = lam_new if forget else 1.0
    buf = np.empty(2 * n)  # pphi, then the block's indices (as floats: one allocation)
    m = 0
    for i in range(n):
        if group[i] == g:
            buf[n + m] = i
            m += 1
    eps = y
    for a in range(m):
        i = int(buf[n + a])
        eps -= phi[i] * theta[i]
        acc = 0.0
        for b in range(m):
            j = int(buf[n + b])
            acc += P[i, j] * phi[j]
        buf[a] = acc
    den = lam_eff
    for a in range(m):
        den += phi[int(buf[n + a])] * buf[a]
    if not (np.isfinite(eps) and np.isfinite(den) and den > 0.0):
        return np.nan
    tr = 0.0
    for a in range(m):
        i = int(buf[n + a])
        gain = buf[a] / den
        theta[i] += gain * eps
        for b in range(m):
            j = int(buf[n + b])
            P[i, j] = (P[i, j] - gain * buf[b]) / lam_eff
        tr += P[i, i]
    for a in range(m):  # keep P symmetric
        i = int(buf[n + a])
        for b in range(a + 1, m):
            j = int(buf[n + b])
            s = 0.5 * (P[i, j] + P[j, i])
            P[i, j] = s
            P[j, i] = s
    cap = cf[F_CAP1] if g == 1 else cf[F_CAP0]
    if cap > 0.0 and tr > cap:
        scale = cap / tr
        for a in range(m):
            i = int(buf[n + a])
            for b in range(m):
                P[i, int(buf[n + b])] *= scale
    lam[stage] = lam_new
    return eps


@njit(cache=True)
def _reopen(P, group, d, cf):  # pragma: no cover - compiled
    """Clear the inertial covariance (J1, J2, r) and open it along the payload direction d.

    Per parameter group, so a split's covariance stays block diagonal.
    """
    n = P.shape[0]
    for i in range(3):
        for j in range(n):
            P[i, j] = 0.0
            P[j, i] = 0.0
    for i in range(3):
        for j in range(3):
            if group[i] == group[j]:
                P[i, j] += cf[F_P_MASS] * d[i] * d[j]
    P[1, 1] += cf[F_P_J2]


@njit(cache=True)
def _project(src, dst, cf):  # pragma: no cover - compiled
    """Nearest physically consistent sigma (as :func:`adaptive_dd.plant.project_sigma`)."""
    project_trial(src, dst, cf[F_J_MIN], cf[F_MARGIN], cf[F_R_MIN])


@njit(cache=True)
def _regress(i, xf, u_last, cnt, tau_prev, q, qd, tau, ci, cf, A, B, C, D, phi, y):  # pragma: no cover
    """Filtered regression of trial i's sample into (phi, y); NaN while a bad input taints it."""
    cons = ci[I_CONSTRUCTION]
    u = np.empty(9)
    t_used = np.empty(2)
    for j in range(2):
        if ci[I_ALIGN] == 1:
            prev = tau[j] if cnt[i, C_STARTED] == 0 else tau_prev[i, j]
            t_used[j] = 0.5 * (tau[j] + prev)
            tau_prev[i, j] = tau[j]
        else:
            t_used[j] = tau[j]
    n_ch = _channels(cons, q, qd, t_used, u)
    bad = False
    for c in range(n_ch):
        if not np.isfinite(u[c]):
            bad = True
    if cnt[i, C_STARTED] == 0:  # filters start in the steady state of the first sample
        xs0 = cf[F_XS0 : F_XS0 + A.shape[0]]
        for c in range(n_ch):
            u_last[i, c] = u[c] if np.isfinite(u[c]) else 0.0
            for m in range(A.shape[0]):
                xf[i, c, m] = u_last[i, c] * xs0[m]
        cnt[i, C_SINCE_BAD] = BIG
        cnt[i, C_STARTED] = 1
    if bad:  # hold the last finite sample
        for c in range(n_ch):
            u[c] = u_last[i, c]
        cnt[i, C_SINCE_BAD] = 0
    else:
        for c in range(n_ch):
            u_last[i, c] = u[c]
        cnt[i, C_SINCE_BAD] = min(cnt[i, C_SINCE_BAD] + 1, BIG)
    f = np.empty((n_ch, C.shape[0]))
    _filter(xf[i], u, n_ch, A, B, C, D, f)
    _assemble(cons, f, phi, y)
    if cnt[i, C_SINCE_BAD] <= ci[I_TAINT]:
        phi[:, :] = np.nan
        y[:] = np.nan


@njit(cache=True)
def on_alarm(i, P, cnt, long, short, group, d, ci, cf):  # pragma: no cover - compiled
    """What an alarm does to trial i: re-open the covariance along the payload direction
    (again after ``freeze`` with ``reopen_again``), restart the long-run levels and the
    persistence window, count it. The weights ``S_LREF`` and the GLR candidates are kept."""
    _reopen(P[i], group, d, cf)
    cnt[i, C_ALARMS] += 1
    cnt[i, C_SINCE_ALARM] = 0
    cnt[i, C_LEARNED1] = 0
    cnt[i, C_LEARNED2] = 0
    long[i, 0] = 0.0
    long[i, 1] = 0.0
    for c in range(S_PER, S_PER_N + 1):  # the persistence window starts anew
        short[i, c] = 0.0
    if ci[I_REOPEN_AGAIN] == 1:
        cnt[i, C_REOPEN_AT] = cnt[i, C_K] + ci[I_FREEZE]


@njit(cache=True)
def online_step_trial(
    i, xf, u_last, cnt, tau_prev, theta, P, lam, short, long, sigma_model,
    q, qd, tau, ci, cf, A, B, C, D, d, group, split_rows, eps_out,
):  # pragma: no cover - compiled  # fmt: skip
    """Advance trial i by one sample in place; return 1 on a change alarm, else 0.

    ``q, qd (2,)`` measured at this sample, ``tau (2,)`` the torque applied over it.
    ``split_rows (2,)``: the regressor row of the first and second stage (full: 0, 1).
    The prior errors of the two equations go to ``eps_out (2,)`` (NaN when unused).
    """
    phi = np.empty((2, 7))
    y = np.empty(2)
    _regress(i, xf, u_last, cnt, tau_prev, q, qd, tau, ci, cf, A, B, C, D, phi, y)
    act = np.ones(2, dtype=np.bool_)
    if ci[I_SELECT] == 1:
        for j in range(2):
            if abs(qd[j]) <= cf[F_SEL_THRESHOLD]:
                cnt[i, C_SINCE_SLOW1 + j] = 0
            else:
                cnt[i, C_SINCE_SLOW1 + j] = min(cnt[i, C_SINCE_SLOW1 + j] + 1, BIG)
            act[j] = cnt[i, C_SINCE_SLOW1 + j] > ci[I_SEL_MEMORY]
    # the detector's own gate, read apart from the selection: friction the model lacks lives at
    # low speed, so the tests skip an equation while its joint is slower than ``speed`` and for
    # ``speed_memory`` after; an equation the RLS does not use gives the tests its prior error
    det_act = np.zeros(2, dtype=np.bool_)
    if ci[I_DETECT] == 1:
        for j in range(2):
            c = C_SINCE_SLOW_DET1 + j
            cnt[i, c] = 0 if abs(qd[j]) <= cf[F_DET_SPEED] else min(cnt[i, c] + 1, BIG)
            det_act[j] = cnt[i, c] > ci[I_SPEED_MEMORY]
            if cnt[i, c] == ci[I_SPEED_MEMORY] + 1:
                # back in use after a slow phase: the short average must not carry the
                # errors of the approach to it (it restarts at the long-run level)
                n_l = cnt[i, C_LEARNED1 + j]
                a_l = cf[F_ALPHA_LONG]
                short[i, S_E2 + j] = long[i, j] / (1.0 - (1.0 - a_l) ** n_l) if n_l > 0 else 0.0
    frozen = ci[I_DETECT] == 1 and ci[I_REOPEN_AGAIN] == 0 and cnt[i, C_SINCE_ALARM] < ci[I_FREEZE]
    if frozen:
        act[:] = False  # frozen after an alarm (the tests too)
    th, Pi, li = theta[i], P[i], lam[i]
    eps_out[:] = np.nan
    det_eps = np.full(2, np.nan)
    skipped = False
    split = ci[I_SPLIT]
    for stage in range(2):
        r = split_rows[stage]
        g = 0 if split == 0 else stage
        yr = y[r]
        if split != 0 and stage == 1:  # cascade: remove the first stage's part
            for j in range(7):
                if group[j] != g:
                    yr -= phi[r, j] * th[j]
        ph = np.zeros(7)
        for j in range(7):
            if group[j] == g:
                ph[j] = phi[r, j]
        if not act[r]:
            if det_act[r] and not frozen:  # the detector's prior error of an equation the RLS skips
                e = yr
                for j in range(7):
                    e -= ph[j] * th[j]
                det_eps[r] = e
            continue
        forget = split != 0 or stage == 0
        e = _rls_update(th, Pi, li, stage if split != 0 else 0, ph, yr, group, g, cf, forget)
        eps_out[r] = e
        det_eps[r] = e
        if not np.isfinite(e):
            skipped = True
    if skipped:
        cnt[i, C_SKIPPED] += 1
    alarm = 0
    if ci[I_DETECT] == 1:
        if cnt[i, C_REOPEN_AT] == cnt[i, C_K]:
            _reopen(Pi, group, d, cf)
        if cf[F_MG_THRESHOLD] > 0.0:
            momentum_test(short[i], cnt, i, th, d, q, qd, tau, ci, cf)
        phi_d = np.zeros(2)
        for r in range(2):
            for j in range(7):
                phi_d[r] += phi[r, j] * d[j]
        if _detect(i, det_eps, det_act, phi_d, u_last[i], th, short, long, cnt, ci, cf, A, B, C, D, d):
            alarm = 1
            on_alarm(i, P, cnt, long, short, group, d, ci, cf)
        else:
            cnt[i, C_SINCE_ALARM] = min(cnt[i, C_SINCE_ALARM] + 1, BIG)
    if ci[I_PROJECT] == 2:
        _project(th, th, cf)
    if ci[I_PROJECT] >= 1:
        _project(th, sigma_model[i], cf)
    else:
        for j in range(7):
            sigma_model[i, j] = th[j]
    cnt[i, C_K] += 1
    return alarm


@njit(cache=True)
def online_step_batch(
    xf, u_last, cnt, tau_prev, theta, P, lam, short, long, sigma_model,
    q, qd, tau, ci, cf, A, B, C, D, d, group, split_rows, eps, alarm,
):  # pragma: no cover - compiled  # fmt: skip
    """:func:`online_step_trial` over every trial of the batch (``q, qd, tau (n, 2)``)."""
    for i in range(q.shape[0]):
        alarm[i] = online_step_trial(
            i, xf, u_last, cnt, tau_prev, theta, P, lam, short, long, sigma_model,
            q[i], qd[i], tau[i], ci, cf, A, B, C, D, d, group, split_rows, eps[i],
        )  # fmt: skip


@njit(cache=True)
def online_run_trial(
    i, xf, u_last, cnt, tau_prev, theta, P, lam, short, long, sigma_model,
    q, qd, tau, ci, cf, A, B, C, D, d, group, split_rows,
    theta_rec, model_rec, eps_rec, alarm_rec, lam_rec,
):  # pragma: no cover - compiled  # fmt: skip
    """Step trial i through a record ``q, qd, tau (N, 2)``, recording after every sample."""
    for k in range(q.shape[0]):
        alarm_rec[k] = online_step_trial(
            i, xf, u_last, cnt, tau_prev, theta, P, lam, short, long, sigma_model,
            q[k], qd[k], tau[k], ci, cf, A, B, C, D, d, group, split_rows, eps_rec[k],
        )  # fmt: skip
        theta_rec[k] = theta[i]
        model_rec[k] = sigma_model[i]
        lam_rec[k] = lam[i, 0]
