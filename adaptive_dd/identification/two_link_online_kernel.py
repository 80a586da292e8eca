"""Compiled per-trial kernel of the online estimator (see :mod:`adaptive_dd.identification.two_link_online`).

One call of :func:`online_step_trial` advances trial ``i`` of a batch of estimator
states by one sample, in place: the M2 derivative filter bank (eq. 19/20, Tustin),
the filtered regression (the paper's construction or the exact one), data
selection, recursive least squares (eq. 14) on the chosen split, the change
detector, covariance re-opening along the payload direction and projection of the
model used for control. The Python path (:func:`~adaptive_dd.identification.two_link_online.online_step`)
and the compiled closed loop call this same function; nothing here is duplicated.

Configuration travels as two flat arrays (``cf`` floats, ``ci`` integers) whose
slots are the module constants below, plus the filter matrices, the payload
direction and the parameter groups of the split. This keeps the kernel a plain
numba function of arrays (cacheable, callable from other compiled code).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.plant.sampling import project_trial

# integer slots of ci
I_CONSTRUCTION = 0  # 0 paper, 1 exact
I_SPLIT = 1  # 0 full, 1 "15", 2 "16"
I_ALIGN = 2
I_SELECT = 3  # data selection on/off
I_SEL_MEMORY = 4  # samples
I_TAINT = 5  # samples a non-finite input taints the filtered equations
I_DETECT = 6
I_WARMUP = 7  # samples
I_MIN_LEARNED = 8
I_HOLDOFF = 9
I_RESUME = 10
I_FREEZE = 11
I_REOPEN_AGAIN = 12
I_PROJECT = 13  # 0 none, 1 the control model only, 2 the estimator state too
I_PERSIST_MIN = 14  # samples the persistence test needs since it restarted
I_GLR_SPACING = 15  # samples between the onsets of two GLR candidates
I_GLR_MIN_AGE = 16  # samples a candidate must have run before it may alarm
I_SPEED_MEMORY = 17  # samples a joint must have been faster than F_DET_SPEED
N_CI = 18

# float slots of cf
F_LAM0 = 0
F_MU = 1
F_CAP0 = 2  # trace cap of the covariance block of group 0 (F_CAP1: group 1); <= 0: none
F_SEL_THRESHOLD = 3
F_ALPHA_SHORT = 4
F_ALPHA_LONG = 5
F_THRESHOLD2 = 6
F_P_MASS = 7
F_P_J2 = 8
F_J_MIN = 9
F_MARGIN = 10
F_R_MIN = 11
F_CAP1 = 12
F_SLOW_FACTOR = 13  # threshold2 multiplier while the other joint is slow
F_ALPHA_DIR = 14  # EWMA weight of the payload-direction test (short window)
F_ALPHA_PERSIST = 15  # EWMA weight of the persistence test
F_MIN_MASS = 16  # [kg] smallest payload change an alarm may claim
F_MIN_EXPLAINED = 17  # fraction of the weighted error energy the payload direction must explain
F_GLR_THRESHOLD = 18  # threshold on A^2 / B of a GLR candidate
F_HETERO = 19  # a candidate's score is A^2 / B - heterogeneity / F_HETERO
F_DET_SPEED = 20  # [rad/s] an equation feeds the payload tests only while its joint is faster
F_REMOVAL = 21  # a GLR alarm may claim removing at most this many times the mass carried (+ min_mass)
N_CF = 22
F_XS0 = N_CF  # cf[F_XS0:]: the filters' state under a unit constant input, (I - A)^-1 B (order,)

# columns of the detector statistics `short` (n, N_SHORT)
S_E2 = 0  # 0, 1: short average of the squared prior error per equation
S_DIR = 2  # 2, 3, 4: short averages of sum_j w_j phi_d,j e_j, w_j phi_d,j^2, w_j e_j^2
S_PER = 5  # 5, 6, 7: the same over the persistence window (restarted at each alarm)
S_PER_N = 8  # samples in the persistence window
S_LREF = 9  # 9, 10: last long-run level per equation that was learned in full (the weights w_j)
S_M0 = 11  # d . theta0 / (d . d) of the start estimate (the arm without payload): the mass origin
S_GLR = 12  # GLR candidates, GLR_STRIDE columns each (see _glr_update)
GLR_CANDIDATES = 16
GLR_CHANNELS = 5  # exact-construction channels of the inertial columns (J1, J2, r)
G_X = 0  # filter state, GLR_CHANNELS x 2
G_OFF = 10  # channel values at the onset (channels 0..3, those filtered by G1)
G_A = 14  # per equation j: sum of w_j psi_j e_j (G_A + j), w_j psi_j^2 (G_A + 2 + j)
G_E = 18  # sum of w_j e_j^2 over both equations
G_AGE = 19
GLR_STRIDE = 20
N_SHORT = S_GLR + GLR_CANDIDATES * GLR_STRIDE

# columns of the per-trial integer state `cnt`
C_STARTED = 0
C_SINCE_BAD = 1
C_SINCE_SLOW1 = 2
C_SINCE_SLOW2 = 3
C_SKIPPED = 4
C_LEARNED1 = 5
C_LEARNED2 = 6
C_SINCE_ALARM = 7
C_REOPEN_AT = 8
C_ALARMS = 9
C_K = 10
C_SINCE_SLOW_DET1 = 11  # samples since joint 1 was slower than the detector's speed (12: joint 2)
N_CNT = 13

BIG = 1 << 40


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
def _detect(i, eps, act, rest, phi_d, u, th, short, long, cnt, ci, cf, A, B, C, D, d):  # pragma: no cover
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
       ``|A / B| >= min_mass`` [kg] and ``A^2 / (B E) >= min_explained``; the threshold is
       ``slow_factor`` times higher while a joint was at rest within the selection memory; and
       the change must leave a payload that can exist: ``dm_hat >= -(removal m_hat + min_mass)``,
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
       times the level (``slow_factor`` more while the other joint is slow), after
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
        elif n_l >= ci[I_MIN_LEARNED] // 8:  # relearning: the weight may only fall meanwhile
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
    if ci[I_CONSTRUCTION] == 1:  # the GLR on the payload direction
        gate = abs(ga) >= cf[F_MIN_MASS] * gb and ga * ga >= cf[F_MIN_EXPLAINED] * gb * ge
        dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
        if gate and dd > 0.0:  # the payload left after the change must be able to exist
            m_hat = (d[0] * th[0] + d[1] * th[1] + d[2] * th[2]) / dd - sh[S_M0]
            gate = ga >= -(cf[F_REMOVAL] * max(m_hat, 0.0) + cf[F_MIN_MASS]) * gb
        # a joint that stops or sticks disturbs the other joint's equation for the filters'
        # memory (the sampled filters meet an acceleration jump): while a joint has been at
        # rest within the selection memory (rest False), ask slow_factor (RMS) times more
        thr = cf[F_GLR_THRESHOLD] if rest[0] and rest[1] else cf[F_GLR_THRESHOLD] * np.sqrt(cf[F_SLOW_FACTOR])
        return glr >= thr and gate
    # the paper's construction has no GLR: the energy test, gated over the direction window
    energy = False
    for j in range(2):
        n_l = cnt[i, C_LEARNED1 + j]
        if n_l < ci[I_MIN_LEARNED] or not act[j]:  # only an equation in use may alarm
            continue
        level = long[i, j] / (1.0 - (1.0 - a_l) ** n_l)
        # a joint that stops or reverses (stick-slip) disturbs the other joint's equation
        # through the coupling for about the filters' memory: ask more of the evidence then
        thr = cf[F_THRESHOLD2] if act[1 - j] else cf[F_THRESHOLD2] * cf[F_SLOW_FACTOR]
        if sh[S_E2 + j] > thr * level + 1e-300:
            energy = True
    return energy and _explained(sh, S_DIR, cf)


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
            if cnt[i, C_SINCE_SLOW1 + j] == ci[I_SEL_MEMORY] + 1:
                # back in use after a slow phase: the short average must not carry the
                # errors of the approach to it (it restarts at the long-run level)
                n_l = cnt[i, C_LEARNED1 + j]
                a_l = cf[F_ALPHA_LONG]
                short[i, S_E2 + j] = long[i, j] / (1.0 - (1.0 - a_l) ** n_l) if n_l > 0 else 0.0
    det_act = act.copy()
    sel_act = act.copy()  # False while a joint was at rest within the selection memory
    if ci[I_DETECT] == 1:
        for j in range(2):  # friction the model lacks lives at low speed: the tests skip it
            c = C_SINCE_SLOW_DET1 + j
            cnt[i, c] = 0 if abs(qd[j]) <= cf[F_DET_SPEED] else min(cnt[i, c] + 1, BIG)
            det_act[j] = det_act[j] and cnt[i, c] > ci[I_SPEED_MEMORY]
    if ci[I_DETECT] == 1 and ci[I_REOPEN_AGAIN] == 0 and cnt[i, C_SINCE_ALARM] < ci[I_FREEZE]:
        act[:] = False  # frozen after an alarm
    th, Pi, li = theta[i], P[i], lam[i]
    eps_out[:] = np.nan
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
        if not act[r]:
            continue
        ph = np.zeros(7)
        for j in range(7):
            if group[j] == g:
                ph[j] = phi[r, j]
        forget = split != 0 or stage == 0
        e = _rls_update(th, Pi, li, stage if split != 0 else 0, ph, yr, group, g, cf, forget)
        eps_out[r] = e
        if not np.isfinite(e):
            skipped = True
    if skipped:
        cnt[i, C_SKIPPED] += 1
    alarm = 0
    if ci[I_DETECT] == 1:
        if cnt[i, C_REOPEN_AT] == cnt[i, C_K]:
            _reopen(Pi, group, d, cf)
        phi_d = np.zeros(2)
        for r in range(2):
            for j in range(7):
                phi_d[r] += phi[r, j] * d[j]
        if _detect(
            i, eps_out, det_act, sel_act, phi_d, u_last[i], th, short, long, cnt, ci, cf, A, B, C, D, d
        ):
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
