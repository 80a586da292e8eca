"""Compiled change detector of the two-link online estimator (called by
:func:`~adaptive_dd.identification.two_link_online_kernel.online_step_trial`): the short-window
tests along the payload direction, the persistence test and the GLR candidates."""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.identification.two_link_online_slots import (
    C_K,
    C_LEARNED1,
    C_SINCE_ALARM,
    F_ALPHA_DIR,
    F_ALPHA_LONG,
    F_ALPHA_PERSIST,
    F_ALPHA_SHORT,
    F_GLR_THRESHOLD,
    F_HETERO,
    F_MG_THRESHOLD,
    F_MIN_EXPLAINED,
    F_MIN_MASS,
    F_REMOVAL,
    F_THRESHOLD2,
    G_A,
    G_AGE,
    G_E,
    G_OFF,
    G_X,
    GLR_CANDIDATES,
    GLR_CHANNELS,
    GLR_STRIDE,
    I_CONSTRUCTION,
    I_GLR_MIN_AGE,
    I_GLR_SPACING,
    I_HOLDOFF,
    I_MIN_LEARNED,
    I_PERSIST_MIN,
    I_RESUME,
    I_WARMUP,
    S_DIR,
    S_E2,
    S_GLR,
    S_LREF,
    S_M0,
    S_MG_DM,
    S_MG_SCORE,
    S_PER,
    S_PER_N,
)


@njit(cache=True)
def _direction(sh, k, a, b, e, alpha):  # pragma: no cover - compiled
    """EWMA of the three payload-direction sums into columns k, k + 1, k + 2 of ``sh``."""
    sh[k] += alpha * (a - sh[k])
    sh[k + 1] += alpha * (b - sh[k + 1])
    sh[k + 2] += alpha * (e - sh[k + 2])


@njit(cache=True)
def _explained(sh, k, cf):  # pragma: no cover - compiled
    """True when the sums at column k say: a payload change of at least ``min_mass`` explains
    at least ``min_explained`` of the weighted error energy (``A^2 / (B E)``, ``|A / B|``)."""
    a, b, e = sh[k], sh[k + 1], sh[k + 2]
    if not (b > 0.0 and e > 0.0):
        return False
    return abs(a) >= cf[F_MIN_MASS] * b and a * a >= cf[F_MIN_EXPLAINED] * b * e


@njit(cache=True, inline="always")
def _mass_gates(a, b, th, d, sh, cf):  # pragma: no cover - compiled
    """The gates on the mass change ``dm = a / b`` (``b > 0``) a test claims: ``|dm| >= min_mass``,
    and the payload left after it must be able to exist, ``dm >= -(removal m_hat + min_mass)``
    with ``m_hat = d . theta / (d . d)`` over the start estimate's (written as products by ``b``,
    so that ``b = 0`` divides nothing)."""
    if not abs(a) >= cf[F_MIN_MASS] * b:
        return False
    dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    if not dd > 0.0:
        return True
    m_hat = (d[0] * th[0] + d[1] * th[1] + d[2] * th[2]) / dd - sh[S_M0]
    return a >= -(cf[F_REMOVAL] * max(m_hat, 0.0) + cf[F_MIN_MASS]) * b


@njit(cache=True)
def _glr_update(sh, u, k, eps, act, w, ci, cf, A, B, C, D, d):  # pragma: no cover - compiled
    """Advance every GLR candidate by one sample; return ``(best A^2 / B, its A, B, E)``.

    Candidate c models a payload change at its onset ``k_c``: the prior errors it predicts are
    ``dm psi_c(k)``, with ``psi_c`` the regressor along the payload direction d of the motion
    *after* the onset only. By linearity of the filters, ``psi_c`` is the exact construction's
    J1, J2, r columns computed by a filter bank started from rest at ``k_c`` on the channels
    ``u - u(k_c)`` (those the derivative filter G1 reads: a jump of the parameters at ``k_c``
    leaves ``G0 (M qdd)`` = ``G1 (qd - qd(k_c))`` on the post-swap part) and ``u`` (the one G0
    reads). A new candidate starts every ``glr_spacing`` samples, replacing the oldest, so the
    onsets of the last ``GLR_CANDIDATES * spacing`` samples are covered.
    """
    spacing = ci[I_GLR_SPACING]
    if k % spacing == 0:  # restart the oldest candidate at this sample
        c0 = S_GLR + ((k // spacing) % GLR_CANDIDATES) * GLR_STRIDE
        for m in range(GLR_STRIDE):
            sh[c0 + m] = 0.0
        for ch in range(4):
            sh[c0 + G_OFF + ch] = u[ch]
    best, ba, bb, be = 0.0, 0.0, 0.0, 0.0
    f = np.empty((GLR_CHANNELS, 2))
    for c in range(GLR_CANDIDATES):
        c0 = S_GLR + c * GLR_STRIDE
        if k - c * spacing < 0 and k < GLR_CANDIDATES * spacing:
            continue  # not started yet
        for ch in range(GLR_CHANNELS):
            x = c0 + G_X + 2 * ch
            v = u[ch] - sh[c0 + G_OFF + ch] if ch < 4 else u[ch]
            for o in range(2):
                f[ch, o] = D[o] * v + C[o, 0] * sh[x] + C[o, 1] * sh[x + 1]
            x0 = A[0, 0] * sh[x] + A[0, 1] * sh[x + 1] + B[0] * v
            x1 = A[1, 0] * sh[x] + A[1, 1] * sh[x + 1] + B[1] * v
            sh[x], sh[x + 1] = x0, x1
        psi0 = d[0] * f[0, 1] + d[1] * (f[0, 1] + f[1, 1]) + d[2] * f[2, 1]
        psi1 = d[1] * (f[0, 1] + f[1, 1]) + d[2] * (f[3, 1] + f[4, 0])
        for j in range(2):
            e = eps[j]
            if act[j] and np.isfinite(e) and w[j] > 0.0:
                psi = psi0 if j == 0 else psi1
                sh[c0 + G_A + j] += w[j] * psi * e
                sh[c0 + G_A + 2 + j] += w[j] * psi * psi
                sh[c0 + G_E] += w[j] * e * e
        sh[c0 + G_AGE] += 1.0
        a0, a1, b0, b1 = sh[c0 + G_A], sh[c0 + G_A + 1], sh[c0 + G_A + 2], sh[c0 + G_A + 3]
        a, b = a0 + a1, b0 + b1
        if sh[c0 + G_AGE] < ci[I_GLR_MIN_AGE] or not b > 0.0:
            continue
        glr = a * a / b
        # heterogeneity: what one payload change per equation explains beyond a common one;
        # friction at one joint's reversal is explained by one equation, a payload by both
        het = (a0 * a0 / b0 if b0 > 0.0 else 0.0) + (a1 * a1 / b1 if b1 > 0.0 else 0.0) - glr
        score = glr - het / cf[F_HETERO]
        if score > best:
            best, ba, bb, be = score, a, b, sh[c0 + G_E]
    return best, ba, bb, be


@njit(cache=True)
def _detect(i, eps, act, phi_d, u, th, short, long, cnt, ci, cf, A, B, C, D, d):  # pragma: no cover
    """Update the detector statistics of trial i; return True on an alarm.

    Every test asks that a change of the tip mass explain the prior errors: a change ``dm``
    makes ``e_j = psi_j dm`` in both equations at once, ``psi`` the regressor along the payload
    direction d; friction the model lacks makes errors of another shape, at low speed. Errors
    are weighted by ``w_j = 1 / level_j`` (the long-run level of equation j: learned only
    while both joints are faster than ``speed``, from ``resume`` samples after the last alarm
    on, bias-corrected; the weight keeps the last level learned in full and may only fall
    while a new one is learned), and an equation feeds the tests only while its joint has
    been faster than ``speed`` for the selection memory.

    1. **GLR** (exact construction): the generalized likelihood ratio ``A^2 / B`` of a mass
       change at each of the last ``GLR_CANDIDATES`` onsets (:func:`_glr_update`), less the
       heterogeneity over the two equations / ``hetero``, above ``glr_threshold``, with
       ``|A / B| >= min_mass`` [kg] and ``A^2 / (B E) >= min_explained``; and the change
       must leave a payload that can exist: ``dm_hat >= -(removal m_hat + min_mass)``,
       ``m_hat = d . (theta - theta0) / (d . d)`` the mass the estimate carries over the start
       estimate (the arm without payload). A stick event of one joint disturbs the other
       joint's equation like a payload change of either sign; at no payload only the sign
       that adds mass can be a swap (the false alarms of ``alternating.toml`` at 1.85 s claimed
       -0.7 to -1.3 kg at 0 kg).
    2. **Persistence** (cannot lock up): over the persistence window (restarted at each alarm,
       filled from ``resume`` samples after it) the same ``|dm_hat| >= min_mass`` and
       explained fraction, with ``psi = phi d`` (long after a change the post-onset regressor
       is the whole one), after ``persist_min`` samples. A model left wrong along d (a swap
       masked by an alarm, levels learned on a wrong model) raises an alarm within
       :func:`~adaptive_dd.identification.two_link_online_config.rearm_time` of motion.
    3. The paper's construction (no GLR): the short average of ``e_j^2`` above ``threshold^2``
       times the level, after
       ``min_learned`` learned samples, gated as 2. over the direction window.
    """
    a_s, a_l = cf[F_ALPHA_SHORT], cf[F_ALPHA_LONG]
    sh = short[i]
    learn = cnt[i, C_SINCE_ALARM] >= ci[I_RESUME]
    a_sum, b_sum, e_sum = 0.0, 0.0, 0.0
    w = np.zeros(2)
    for j in range(2):
        e = eps[j]
        if not (act[j] and np.isfinite(e)):
            continue
        e2 = e * e
        sh[S_E2 + j] += a_s * (e2 - sh[S_E2 + j])
        if learn and act[1 - j]:
            long[i, j] += a_l * (e2 - long[i, j])
            cnt[i, C_LEARNED1 + j] += 1
        n_l = cnt[i, C_LEARNED1 + j]
        if n_l >= ci[I_MIN_LEARNED]:
            sh[S_LREF + j] = long[i, j] / (1.0 - (1.0 - a_l) ** n_l)
        elif n_l >= max(1, ci[I_MIN_LEARNED] // 8):  # relearning: the weight may only fall meanwhile
            sh[S_LREF + j] = max(sh[S_LREF + j], long[i, j] / (1.0 - (1.0 - a_l) ** n_l))
        w[j] = 1.0 / sh[S_LREF + j] if sh[S_LREF + j] > 0.0 else 0.0
        if np.isfinite(phi_d[j]):
            a_sum += w[j] * phi_d[j] * e
            b_sum += w[j] * phi_d[j] * phi_d[j]
            e_sum += w[j] * e2
    _direction(sh, S_DIR, a_sum, b_sum, e_sum, cf[F_ALPHA_DIR])
    if learn:
        _direction(sh, S_PER, a_sum, b_sum, e_sum, cf[F_ALPHA_PERSIST])
        sh[S_PER_N] += 1.0
    glr, ga, gb, ge = 0.0, 0.0, 0.0, 0.0
    if ci[I_CONSTRUCTION] == 1:
        glr, ga, gb, ge = _glr_update(sh, u, cnt[i, C_K], eps, act, w, ci, cf, A, B, C, D, d)
    if cnt[i, C_K] < ci[I_WARMUP] or cnt[i, C_SINCE_ALARM] <= ci[I_HOLDOFF]:
        return False
    if sh[S_PER_N] >= ci[I_PERSIST_MIN] and _explained(sh, S_PER, cf):
        return True
    settled = cnt[i, C_SINCE_ALARM] * a_l >= 1.0  # a long window since the last alarm
    if settled and cf[F_MG_THRESHOLD] > 0.0 and sh[S_MG_SCORE] >= cf[F_MG_THRESHOLD]:
        # the momentum test (two_link_momentum_test), under the GLR's gates on the mass it claims;
        # not while the estimate learns the last change: its residual holds what is left to learn
        if _mass_gates(sh[S_MG_DM], 1.0, th, d, sh, cf):
            return True
    if ci[I_CONSTRUCTION] == 1:  # the GLR on the payload direction
        gate = ga * ga >= cf[F_MIN_EXPLAINED] * gb * ge and _mass_gates(ga, gb, th, d, sh, cf)
        return glr >= cf[F_GLR_THRESHOLD] and gate
    # the paper's construction has no GLR: the energy test, gated over the direction window
    energy = False
    for j in range(2):
        n_l = cnt[i, C_LEARNED1 + j]
        if n_l < ci[I_MIN_LEARNED] or not act[j]:  # only an equation in use may alarm
            continue
        level = long[i, j] / (1.0 - (1.0 - a_l) ** n_l)
        if sh[S_E2 + j] > cf[F_THRESHOLD2] * level + 1e-300:
            energy = True
    return energy and _explained(sh, S_DIR, cf)
