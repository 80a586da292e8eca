"""The two-link change detector's momentum test: a GLR of a tip-mass change on the generalised
momentum, compiled (called by
:func:`~adaptive_dd.identification.two_link_online_kernel.online_step_trial`).

Over one sample the model's momentum ``p = M(q) qd`` changes by what the torque leaves beside
``wv = -dT/dq + B qd + D sgn(qd)`` (:func:`momentum_two_link`); the increment's residual

    g_k = T tau_(k-1) - T (wv_k + wv_(k-1)) / 2 - (p_k - p_(k-1)),

both momenta with one model (as the residual observer forms it, De Luca and Mattone, ICRA 2003),
is zero on the model but for the sensors' noise. It is linear in sigma, ``T tau - Y_k sigma``;
each candidate forms it with the estimate held from its onset, so that the RLS, which starts
to follow a swap before any alarm, does not take the change out of the test's residual. A tip
mass ``dm`` added at sample ``k0`` adds ``dm h_k`` to it, ``h = Y_k d`` the same increment of the
payload direction ``d``'s momentum and ``wv`` (a disk of mass m at the tip moves sigma by
``m d``). Summed from the onset, the residual ``R_m = dm S_m + e_m`` has the noise of the two momenta alone,
``e_m = -(M_m n_m - M_0 n_0)`` with ``n`` the velocity noise: its covariance is
``blockdiag(Q_m) + 1 1^T (x) Q_0``, ``Q = M Sigma_v M^T``, which Woodbury's identity inverts
recursively. The GLR of ``dm`` at each of ``MG_CANDIDATES`` onsets (one every ``glr_spacing``)
is ``A^2 / B``, its estimate ``dm_hat = A / B``, with

    A = sum S_m^T Q_m^-1 R_m - (sum Q_m^-1 S_m)^T (Q_0^-1 + sum Q_m^-1)^-1 (sum Q_m^-1 R_m)

and B the same with S for R. Unlike the filtered equations' GLR
(:func:`~adaptive_dd.identification.two_link_detector_kernel._glr_update`), whose errors are
coloured by the derivative filters, this statistic is whitened: chi-square with one degree of
freedom on the model, so the whole information of the first samples after a swap counts
(Willsky and Jones, IEEE TAC 21(1), 1976, on GLR tests of jumps).

* ``Sigma_v`` (2 x 2) is learnt from the residuals themselves, ``v = M^-1 g ~ -(n_k - n_(k-1))``,
  over the detector's long window (winsorised at 9 times its level): the test reads no
  sensor setting, so none can be misstated to it. The viscous term's share of the noise,
  which the sum accumulates, is added (``T^2 b_j^2 Sigma_v,jj`` over the candidates' span):
  it bounds Q along the inertia matrix's near-null direction (the SICE arm's M is close to
  singular).
* Friction the model lacks lives at low speed (Coulomb's sign, Stribeck, LuGre's bristles): a
  joint slower than the detector's ``speed`` at any sample of a candidate's span leaves that
  candidate's statistic (its row weighs nothing from then on).
* A non-finite input leaves every running candidate and the next sample's increment.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.identification.two_link_online_slots import (
    C_K,
    F_ALPHA_LONG,
    F_DET_SPEED,
    F_T,
    I_GLR_SPACING,
    MG_A,
    MG_ACTIVE,
    MG_B,
    MG_CANDIDATES,
    MG_K,
    MG_MIN_AGE,
    MG_Q0,
    MG_R,
    MG_S,
    MG_STRIDE,
    MG_TAINT,
    MG_TH,
    MG_W,
    MG_WR,
    MG_WS,
    S_MG_DM,
    S_MG_N,
    S_MG_PREV,
    S_MG_SCORE,
    S_MG_SV,
    S_MGC,
)

__all__ = ["momentum_test", "momentum_two_link"]


@njit(cache=True, inline="always")
def momentum_two_link(ch, sg, q, qd, work, p, wv):  # pragma: no cover - compiled
    """``p = M(q) qd`` and ``wv = -dT/dq + B qd + D sgn(qd)`` of the paper's sigma ``sg (7,)``
    (``J1 J2 r b1 b2 d1 d2``; ``M = [[J1 + J2 + 2 r c2, J2 + r c2], [J2 + r c2, J2]]``, no
    gravity: the arm is horizontal), into ``p, wv (2,)``: ``dp/dt = tau - wv`` on the model.

    The chain's ``_momentum`` signature (``ch`` and ``work`` unused): the kinetic energy
    ``T = qd^T M qd / 2`` depends on ``q2`` only, ``dT/dq2 = -r s2 qd1 (qd1 + qd2)``.
    """
    c2, s2 = np.cos(q[1]), np.sin(q[1])
    j2, r = sg[1], sg[2]
    rc = r * c2
    p[0] = (sg[0] + j2 + 2.0 * rc) * qd[0] + (j2 + rc) * qd[1]
    p[1] = (j2 + rc) * qd[0] + j2 * qd[1]
    wv[0] = sg[3] * qd[0] + sg[5] * np.sign(qd[0])
    wv[1] = r * s2 * qd[0] * (qd[0] + qd[1]) + sg[4] * qd[1] + sg[6] * np.sign(qd[1])


@njit(cache=True, inline="always")
def _regressor(qa, qda, qb, qdb, T):  # pragma: no cover - compiled
    """The increment's regressor ``Y`` from the sample ``a`` to ``b``: ``T tau_a - Y sigma`` is the
    residual of :func:`momentum_two_link`'s identity on the model sigma (linear in sigma). Its
    nine entries that are not zero, row 0 at J1, J2, r, b1, d1 and row 1 at J2, r, b2, d2:
    ``p_b - p_a`` (J1, J2, r) and ``T (wv_b + wv_a) / 2`` (r, b, d)."""
    c2a, c2b = np.cos(qa[1]), np.cos(qb[1])
    s2a, s2b = np.sin(qa[1]), np.sin(qb[1])
    y00 = qdb[0] - qda[0]
    y01 = qdb[0] + qdb[1] - qda[0] - qda[1]
    y02 = c2b * (2.0 * qdb[0] + qdb[1]) - c2a * (2.0 * qda[0] + qda[1])
    y03 = 0.5 * T * (qdb[0] + qda[0])
    y05 = 0.5 * T * (np.sign(qdb[0]) + np.sign(qda[0]))
    y12 = c2b * qdb[0] - c2a * qda[0]
    y12 += 0.5 * T * (s2b * qdb[0] * (qdb[0] + qdb[1]) + s2a * qda[0] * (qda[0] + qda[1]))
    y14 = 0.5 * T * (qdb[1] + qda[1])
    y16 = 0.5 * T * (np.sign(qdb[1]) + np.sign(qda[1]))
    return y00, y01, y02, y03, y05, y12, y14, y16


@njit(cache=True, inline="always")
def _times(y, p, o):  # pragma: no cover - compiled
    """``Y sigma`` (2,) of :func:`_regressor`'s ``y`` and the sigma ``p[o : o + 7]``."""
    y00, y01, y02, y03, y05, y12, y14, y16 = y
    r0 = y00 * p[o] + y01 * p[o + 1] + y02 * p[o + 2] + y03 * p[o + 3] + y05 * p[o + 5]
    r1 = y01 * p[o + 1] + y12 * p[o + 2] + y14 * p[o + 4] + y16 * p[o + 6]
    return r0, r1


@njit(cache=True)
def momentum_test(sh, cnt, i, th, d, q, qd, tau, ci, cf):  # pragma: no cover - compiled
    """Advance trial i's momentum test by the sample ``q, qd`` (the torque applied over the last
    sample is in the state; ``tau``, applied over this one, is kept for the next); the best
    candidate's ``A^2 / B`` and ``A / B`` into ``sh[S_MG_SCORE]``, ``sh[S_MG_DM]`` (0 while none
    may alarm). ``sh`` is the trial's row of the detector statistics, ``th`` the estimate both
    momenta are formed with."""
    T = cf[F_T]
    k = cnt[i, C_K]
    sh[S_MG_SCORE] = 0.0
    sh[S_MG_DM] = 0.0
    finite = np.isfinite(q[0]) and np.isfinite(q[1]) and np.isfinite(qd[0]) and np.isfinite(qd[1])
    fresh = finite and sh[S_MG_PREV + 6] == 1.0
    g0 = g1 = h0 = h1 = tt0 = tt1 = 0.0
    y = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    q00 = q01 = q11 = 0.0  # Q_k
    if fresh:
        y = _regressor(sh[S_MG_PREV : S_MG_PREV + 2], sh[S_MG_PREV + 2 : S_MG_PREV + 4], q, qd, T)
        tt0, tt1 = T * sh[S_MG_PREV + 4], T * sh[S_MG_PREV + 5]
        r0, r1 = _times(y, th, 0)
        g0, g1 = tt0 - r0, tt1 - r1
        h0, h1 = _times(y, d, 0)  # dm d added to the plant: + dm h in the residual
        fresh = np.isfinite(g0) and np.isfinite(g1)
    m00 = m01 = m11 = 0.0
    if fresh:
        c2 = np.cos(q[1])
        m00 = th[0] + th[1] + 2.0 * th[2] * c2
        m01 = th[1] + th[2] * c2
        m11 = th[1]
        fresh = m11 > 0.0 and m00 * m11 > m01 * m01  # the estimate's inertia positive definite
    if fresh:
        det = m00 * m11 - m01 * m01
        v0 = (m11 * g0 - m01 * g1) / det
        v1 = (m00 * g1 - m01 * g0) / det
        # Sigma_v learnt from v v^T / 2, winsorised at 9 times its level once it has one
        n = sh[S_MG_N]
        a = cf[F_ALPHA_LONG]
        e00, e01, e11 = 0.5 * v0 * v0, 0.5 * v0 * v1, 0.5 * v1 * v1
        if n > 100.0:
            bias = 1.0 - (1.0 - a) ** n
            l00, l11 = 9.0 * sh[S_MG_SV] / bias, 9.0 * sh[S_MG_SV + 2] / bias
            s = 1.0
            if e00 > l00:
                s = min(s, l00 / e00)
            if e11 > l11:
                s = min(s, l11 / e11)
            e00, e01, e11 = s * e00, s * e01, s * e11
        sh[S_MG_SV] += a * (e00 - sh[S_MG_SV])
        sh[S_MG_SV + 1] += a * (e01 - sh[S_MG_SV + 1])
        sh[S_MG_SV + 2] += a * (e11 - sh[S_MG_SV + 2])
        n += 1.0
        sh[S_MG_N] = n
        bias = 1.0 - (1.0 - a) ** n
        s00, s01, s11 = sh[S_MG_SV] / bias, sh[S_MG_SV + 1] / bias, sh[S_MG_SV + 2] / bias
        # Q = M Sigma_v M^T, and the viscous term's share over the candidates' span
        span = MG_CANDIDATES * ci[I_GLR_SPACING]
        t00 = m00 * s00 + m01 * s01
        t01 = m00 * s01 + m01 * s11
        t10 = m01 * s00 + m11 * s01
        t11 = m01 * s01 + m11 * s11
        q00 = t00 * m00 + t01 * m01 + T * T * th[3] * th[3] * s00 * span
        q01 = t00 * m01 + t01 * m11
        q11 = t10 * m01 + t11 * m11 + T * T * th[4] * th[4] * s11 * span
        fresh = n > 100.0 and q00 > 0.0 and q11 > 0.0 and q00 * q11 > q01 * q01
    spacing = ci[I_GLR_SPACING]
    if k % spacing == 0:  # restart the oldest candidate, its onset at this sample
        c0 = S_MGC + ((k // spacing) % MG_CANDIDATES) * MG_STRIDE
        for m in range(MG_STRIDE):
            sh[c0 + m] = 0.0
        sh[c0 + MG_Q0], sh[c0 + MG_Q0 + 1], sh[c0 + MG_Q0 + 2] = q00, q01, q11
        sh[c0 + MG_ACTIVE] = 1.0
        for a in range(7):  # the model the candidate's residual is formed with, held from its onset
            sh[c0 + MG_TH + a] = th[a]
        if not fresh:
            sh[c0 + MG_TAINT] = sh[c0 + MG_TAINT + 1] = 1.0
    else:
        c0 = -1
    if fresh:
        det_q = q00 * q11 - q01 * q01
        i00, i01, i11 = q11 / det_q, -q01 / det_q, q00 / det_q  # Q_k^-1
        best, best_dm = 0.0, 0.0
        slow0, slow1 = abs(qd[0]) <= cf[F_DET_SPEED], abs(qd[1]) <= cf[F_DET_SPEED]
        for c in range(MG_CANDIDATES):
            b0 = S_MGC + c * MG_STRIDE
            if sh[b0 + MG_ACTIVE] != 1.0 or b0 == c0:
                continue
            r0, r1 = _times(y, sh, b0 + MG_TH)  # the residual with the onset's estimate
            sh[b0 + MG_R] += tt0 - r0
            sh[b0 + MG_R + 1] += tt1 - r1
            sh[b0 + MG_S] += h0
            sh[b0 + MG_S + 1] += h1
            if slow0:
                sh[b0 + MG_TAINT] = 1.0
            if slow1:
                sh[b0 + MG_TAINT + 1] = 1.0
            sh[b0 + MG_K] += 1.0
            keep0, keep1 = sh[b0 + MG_TAINT] == 0.0, sh[b0 + MG_TAINT + 1] == 0.0
            if keep0 and keep1:
                w00, w01, w11 = i00, i01, i11
            else:  # the kept joint's marginal: 1 / Q_jj
                w00 = 1.0 / q00 if keep0 else 0.0
                w11 = 1.0 / q11 if keep1 else 0.0
                w01 = 0.0
            r0, r1 = sh[b0 + MG_R], sh[b0 + MG_R + 1]
            s0, s1 = sh[b0 + MG_S], sh[b0 + MG_S + 1]
            ws0, ws1 = w00 * s0 + w01 * s1, w01 * s0 + w11 * s1
            wr0, wr1 = w00 * r0 + w01 * r1, w01 * r0 + w11 * r1
            sh[b0 + MG_A] += s0 * wr0 + s1 * wr1
            sh[b0 + MG_B] += s0 * ws0 + s1 * ws1
            sh[b0 + MG_W] += w00
            sh[b0 + MG_W + 1] += w01
            sh[b0 + MG_W + 2] += w11
            sh[b0 + MG_WS] += ws0
            sh[b0 + MG_WS + 1] += ws1
            sh[b0 + MG_WR] += wr0
            sh[b0 + MG_WR + 1] += wr1
            if sh[b0 + MG_K] < MG_MIN_AGE or not (keep0 or keep1):
                continue
            # (Q_0^-1 + sum Q_m^-1)^-1 on the kept joints
            p00, p01, p11 = sh[b0 + MG_Q0], sh[b0 + MG_Q0 + 1], sh[b0 + MG_Q0 + 2]
            if keep0 and keep1:
                dp = p00 * p11 - p01 * p01
                o00, o01, o11 = p11 / dp, -p01 / dp, p00 / dp
            else:
                o00 = 1.0 / p00 if keep0 else 1.0
                o11 = 1.0 / p11 if keep1 else 1.0
                o01 = 0.0
            g00, g01, g11 = o00 + sh[b0 + MG_W], o01 + sh[b0 + MG_W + 1], o11 + sh[b0 + MG_W + 2]
            dg = g00 * g11 - g01 * g01
            h00, h01, h11 = g11 / dg, -g01 / dg, g00 / dg
            zs0, zs1 = sh[b0 + MG_WS], sh[b0 + MG_WS + 1]
            zr0, zr1 = sh[b0 + MG_WR], sh[b0 + MG_WR + 1]
            a_ = sh[b0 + MG_A] - (zs0 * (h00 * zr0 + h01 * zr1) + zs1 * (h01 * zr0 + h11 * zr1))
            b_ = sh[b0 + MG_B] - (zs0 * (h00 * zs0 + h01 * zs1) + zs1 * (h01 * zs0 + h11 * zs1))
            if b_ > 0.0 and a_ * a_ / b_ > best:
                best, best_dm = a_ * a_ / b_, a_ / b_
        sh[S_MG_SCORE] = best
        sh[S_MG_DM] = best_dm
    else:  # no increment (a lost sample, the first, the noise not learnt): the candidates stop
        for c in range(MG_CANDIDATES):
            b0 = S_MGC + c * MG_STRIDE
            sh[b0 + MG_TAINT] = sh[b0 + MG_TAINT + 1] = 1.0
    if finite:
        for j in range(2):
            sh[S_MG_PREV + j] = q[j]
            sh[S_MG_PREV + 2 + j] = qd[j]
    for j in range(2):  # the torque applied over this sample, for the next sample's increment
        sh[S_MG_PREV + 4 + j] = tau[j]
    sh[S_MG_PREV + 6] = 1.0 if finite and np.isfinite(tau[0]) and np.isfinite(tau[1]) else 0.0
