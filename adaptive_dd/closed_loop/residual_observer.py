"""adaptive_ct's residual observer and its momentum test, compiled: one sample per call.

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

The momentum test (``obs_mtest``; :func:`_momentum_test`) and the trip (``obs_trip``;
:func:`_trip`) start the law's boost as an alarm would. The settings are the fields ``obs_*`` of
:class:`~adaptive_dd.closed_loop.laws.LawConfig`, the state the rows ``O_*`` of
``LawState.obs (S, OBS_ROWS, n)``; the law (:func:`~adaptive_dd.closed_loop.laws.law_trial_in`)
calls the observer, and the closed loop :func:`observe_applied` after each sample. The two-link
arm compiles :func:`_observe` itself with its closed-form momentum
(:mod:`adaptive_dd.controllers.two_link_observer`): ``_momentum``, ``_mass`` and ``_coulomb``
are looked up by name.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.plant.chain import mass_matrix_in, momentum_form_in

__all__ = [
    "M_WINDOWS",
    "OBS_ROWS",
    "O_COUNT",
    "O_LEVEL",
    "O_MC",
    "O_R",
    "O_TRIP",
    "observe_applied",
]

# rows of the observer's per-trial state LawState.obs (S, OBS_ROWS, n)
O_R = 0  # the observed residual torque r [N m] (the last stage's output)
O_LEVEL = 1  # its learnt mean square (winsorised, not bias-corrected) [N^2 m^2]
O_Q, O_QD = 2, 3  # the last fresh measurement
O_TAU = 4  # the applied torques summed since that measurement [N m] (written by the closed loop)
O_COUNT = 5  # [0]: observer updates so far, [1]: samples summed in O_TAU
O_R1 = 6  # the first stage's output (two stages)
O_TRIP = 7  # [0]: samples since the observer's residual last tripped the boost (obs_trip)
# the momentum test (obs_mtest; :func:`_momentum_test`)
M_WINDOWS = (1, 2, 3, 4, 6, 8, 12, 16, 24, 32)  # its windows [fresh measurements]
M_RING = 33  # the integrated error's ring: the longest window plus one
M_ARM = 2.0  # level windows of free learning before the test is armed (the first may be a ramp-up)
O_MV = 8  # rows O_MV + w: the learnt mean square of window w's whitened sum [(rad/s)^2]
O_MB = O_MV + len(M_WINDOWS)  # the learnt drift of rho (the model's own error) [N m]
O_ME = O_MB + 1  # rows O_ME + i: the integrated error E, less the drift [N m s], a ring
O_MA = O_ME + M_RING  # rows O_MA + i: the integrated Coulomb allowance [N m s], a ring
O_MC = O_MA + M_RING  # [0]: updates of the test so far, [1]: 1 if it crossed at the last one (2: and
# started the boost asking the estimator to re-open: obs_mreopen)
OBS_ROWS = O_MC + 1


@njit(cache=True)
def _momentum(ch, pi, q, qd, work, p, wv):  # pragma: no cover - compiled
    """``p = M(q) qd + Ia qd`` and ``wv = g - C^T qd + fv qd + fc sgn(qd)`` of ``pi (13 n,)``."""
    n = q.shape[0]
    pyw = work[8]
    # link np.int64(0), not 0: the literal 0 is a type of its own, which compiled momentum_form_in
    # once more (4.5 CPU s) beside the estimator's int64 one
    momentum_form_in(ch, pi[: 10 * n], np.int64(0), q, qd, work[0], work[6], p, wv, pyw[0], pyw[1])
    for j in range(n):
        p[j] += pi[12 * n + j] * qd[j]
        wv[j] += pi[10 * n + j] * qd[j] + pi[11 * n + j] * np.sign(qd[j])


@njit(cache=True)
def _mass(ch, pi, q, work, m):  # pragma: no cover - compiled
    """``m = M(q) + diag(Ia)`` of ``pi (13 n,)`` (the momentum test's metric)."""
    n = q.shape[0]
    mass_matrix_in(ch, pi[: 10 * n], q, work[0], m)
    for j in range(n):
        m[j, j] += pi[12 * n + j]


@njit(cache=True, inline="always")
def _coulomb(pi, n, j):  # pragma: no cover - compiled
    """The model's Coulomb friction of joint ``j`` [N m]."""
    return abs(pi[11 * n + j])


@njit(cache=True)
def _spd_inverse(a, out):  # pragma: no cover - compiled
    """``out = a^-1`` of a symmetric positive definite ``a (n, n)`` (Gauss-Jordan, no pivoting;
    ``a`` destroyed). A non-positive pivot leaves ``out`` the identity."""
    n = a.shape[0]
    for r in range(n):
        for c in range(n):
            out[r, c] = 1.0 if r == c else 0.0
    for k in range(n):
        piv = a[k, k]
        if not piv > 0.0:
            for r in range(n):
                for c in range(n):
                    out[r, c] = 1.0 if r == c else 0.0
            return
        for c in range(n):
            a[k, c] /= piv
            out[k, c] /= piv
        for r in range(n):
            if r != k:
                f = a[r, k]
                if f != 0.0:
                    for c in range(n):
                        a[r, c] -= f * a[k, c]
                        out[r, c] -= f * out[k, c]


@njit(cache=True, inline="always")
def _sign_unknown(cfg, qd_last, qd_now):  # pragma: no cover - compiled
    """Whether the true speed's sign over a sample is not known from its two measured ends: one at
    most ``obs_mslow`` fast, or the two of opposite signs."""
    return min(abs(qd_last), abs(qd_now)) <= cfg.obs_mslow or qd_last * qd_now <= 0.0


@njit(cache=True, inline="always")
def _friction_allowance(cfg, qd_last, qd_now, fc):  # pragma: no cover - compiled
    """[N m] How far the model's Coulomb torque over one sample (the trapezoid of ``fc sgn(qd)`` at
    its two measured ends) may be from the plant's, for a joint measured ``qd_last``, ``qd_now``:
    ``2 fc`` where the sign of the true speed is not known over the sample (an end within
    ``obs_mslow``, the stated velocity noise's quantile, or the two ends of opposite signs: the
    joint may reverse or stick within it, its friction then anything within ``+-fc``); else
    ``obs_mcreep_margin fc`` where the slower end is just above ``obs_mslow``, falling linearly to
    none at ``obs_mcreep`` (friction the model lacks, a Stribeck bump or a soft law, errs near
    rest by a fraction of the Coulomb level: the detector's creeping rule; a flat allowance up to
    ``obs_mcreep`` cost vertical3 its gain); else none."""
    if _sign_unknown(cfg, qd_last, qd_now):
        return 2.0 * fc
    slow = min(abs(qd_last), abs(qd_now))
    if slow <= cfg.obs_mcreep:
        return cfg.obs_mcreep_margin * fc * (cfg.obs_mcreep - slow) / (cfg.obs_mcreep - cfg.obs_mslow)
    return 0.0


@njit(cache=True, inline="always")
def _remove_friction(obs, mt, u, v, bias, pos, back):  # pragma: no cover - compiled
    """Remove from a window's unexplained velocity change ``u (n,)`` the friction torques within
    its allowances that explain it best (:func:`_momentum_test`): three passes of coordinate
    descent over the joints with an allowance ``al`` (ring slots ``pos``, ``back``), metric
    ``bias / v`` (``v (n,)`` the window's learnt levels), each torque ``c_j`` within ``+-al`` and
    its effect ``M^-1 e_j c_j`` (``mt[:n]`` is ``M^-1``) taken from ``u``."""
    n = u.shape[0]
    for _ in range(3):
        for j in range(n):
            al = obs[O_MA + pos, j] - obs[O_MA + back, j]
            if al <= 0.0:
                continue
            num, den = 0.0, 0.0
            for r in range(n):
                wr = bias / v[r]
                num += mt[r, j] * wr * u[r]
                den += mt[r, j] * mt[r, j] * wr
            cj = min(max(num / den, -al), al) if den > 0.0 else 0.0
            for r in range(n):
                u[r] -= mt[r, j] * cj


@njit(cache=True)
def _momentum_test(cfg, obs, mt, qd, m):  # pragma: no cover - compiled
    """One fresh update of the momentum test; ``obs[O_MC, 1]`` set to 1 if it crossed.

    ``mt (n + 4, n)``: ``M^-1`` of this measurement (rows ``0..n-1``), the mean residual ``rho``
    over the ``m`` samples since the last measurement (row ``n``), the model's Coulomb friction
    (row ``n + 1``); rows ``n + 2, n + 3`` scratch. The integrated momentum error ``E_k = sum (rho
    - b) m T`` (``b`` the row's drift, learnt over the level's window) telescopes: over a window
    of ``w`` updates its sum ``S = E_k - E_(k-w)`` is the missing torque's integral plus the two
    end momenta's noise, whatever ``w``; a step ``d`` of missing torque is a ramp ``d w T`` in it.
    ``u = M^-1 S`` (the unexplained velocity change: the velocity noise, independent per joint,
    whitens it) per window of :data:`M_WINDOWS`; a joint whose friction over a sample is not
    known (:func:`_friction_allowance`: near rest or reversing, ``2 fc``; creeping, a fraction of
    ``fc``) has that allowance, summed over the window: once the test is armed, the friction
    torques within it that explain ``u`` best are removed from it first (three passes of
    coordinate descent, metric ``1 / V``). Statistic: the largest over windows of ``sqrt(sum_j
    u_j^2 / V_j)``, ``V`` each window's and row's learnt mean square of ``u``, learnt only on
    windows without allowance (elsewhere it keeps its bias-corrected value; a window whose level
    has learnt nothing is not tested): freely for :data:`M_ARM` level windows, then winsorised at
    the threshold. Learnt on every window before it armed, the first seconds' reversals raised
    the levels and the test was blind for a second or more after it armed. Armed
    after those: learnt over the first second alone, on a reference that ramps up over it, the
    levels were too low for the full motion (vertical3 drawn: starts at 1.18-1.19 s in 2 of 10
    trials, none from 2 s on)."""
    n = qd.shape[0]
    rho, fc, sm, u = mt[n], mt[n + 1], mt[n + 2], mt[n + 3]
    c = obs[O_MC, 0]
    pos = int(c) % M_RING
    prev = (int(c) + M_RING - 1) % M_RING
    dt = m * cfg.T
    for j in range(n):
        obs[O_ME + pos, j] = obs[O_ME + prev, j] + (rho[j] - obs[O_MB, j]) * dt
        obs[O_MA + pos, j] = obs[O_MA + prev, j] + _friction_allowance(cfg, obs[O_QD, j], qd[j], fc[j]) * dt
    c += 1.0
    obs[O_MC, 0] = c
    alpha = cfg.obs_alpha
    armed = c * alpha > M_ARM
    bias = 1.0 - (1.0 - alpha) ** c
    bias0 = 1.0 - (1.0 - alpha) ** (c - 1.0)
    z2 = cfg.obs_mtest * cfg.obs_mtest
    best = 0.0
    for w in range(len(M_WINDOWS)):
        mw = M_WINDOWS[w]
        if c <= mw:
            continue
        back = (pos + M_RING - mw) % M_RING
        clean = True
        for j in range(n):
            sm[j] = obs[O_ME + pos, j] - obs[O_ME + back, j]
            clean = clean and obs[O_MA + pos, j] == obs[O_MA + back, j]
        for r in range(n):
            acc = 0.0
            for j in range(n):
                acc += mt[r, j] * sm[j]
            u[r] = acc
        v = obs[O_MV + w]
        learnt = True
        for r in range(n):
            sm[r] = u[r] * u[r]  # before the allowance (the levels learn it where there is none)
            learnt = learnt and v[r] > 0.0
        if armed and learnt and not clean:
            _remove_friction(obs, mt, u, v, bias, pos, back)
        tot = 0.0
        for r in range(n):
            if armed and learnt:
                tot += u[r] * u[r] * bias / v[r]
            if clean:
                x = min(sm[r], z2 * v[r] / bias) if armed and learnt else sm[r]
            else:  # the level's own estimate: its bias-corrected value unchanged
                x = v[r] / bias0 if bias0 > 0.0 else 0.0
            v[r] += alpha * (x - v[r])
        if tot > best:
            best = tot
    if c > M_RING:
        for j in range(n):
            obs[O_MB, j] += alpha * (rho[j] - obs[O_MB, j])
    obs[O_MC, 1] = 1.0 if armed and np.isfinite(best) and best > z2 else 0.0


@njit(cache=True, inline="always")
def observe_applied(obs, tau):  # pragma: no cover - compiled
    """Add the torque ``tau (n,)`` applied over one sample to the residual observer's state
    ``obs (OBS_ROWS, n)`` (the closed loop calls it after each sample's actuation)."""
    for j in range(tau.shape[0]):
        obs[O_TAU, j] += tau[j]
    obs[O_COUNT, 1] += 1.0


@njit(cache=True)
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
        finite = True
        for j in range(n):
            rho = obs[O_TAU, j] / m - 0.5 * (pw[1, j] + pw[3, j]) - (pw[2, j] - pw[0, j]) / (m * cfg.T)
            if cfg.obs_mtest > 0.0:
                work[9][n, j] = rho
            if not np.isfinite(rho):
                finite = False
                continue
            if cfg.obs_stages == 2:
                obs[O_R1, j] = am * obs[O_R1, j] + (1.0 - am) * rho
                rho = obs[O_R1, j]
            obs[O_R, j] = am * obs[O_R, j] + (1.0 - am) * rho
        if cfg.obs_mtest > 0.0:
            obs[O_MC, 1] = 0.0
            if finite:
                mt = work[9]
                _mass(ch, pi, q, work, work[2])
                _spd_inverse(work[2], mt[:n])
                fc = mt[n + 1]
                for j in range(n):
                    fc[j] = _coulomb(pi, n, j)
                _momentum_test(cfg, obs, mt, qd, m)
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


@njit(cache=True)
def _trip(cfg, pi, qd, obs):  # pragma: no cover - compiled
    """A row of the observer's output beyond ``obs_trip`` times its learnt level (plus twice its
    Coulomb friction when its joint is at most ``obs_trip_speed``) sets ``O_TRIP`` to 0."""
    n = qd.shape[0]
    c = obs[O_COUNT, 0]
    if c <= cfg.obs_warmup:
        return
    bias = 1.0 - (1.0 - cfg.obs_alpha) ** c
    for j in range(n):
        rms = np.sqrt(obs[O_LEVEL, j] / bias)
        flip = 0.0 if abs(qd[j]) > cfg.obs_trip_speed else 2.0 * abs(pi[11 * n + j])
        if abs(obs[O_R, j]) > cfg.obs_trip * rms + flip:
            obs[O_TRIP, 0] = 0.0
