"""The model control uses, from the compiled online estimator's state.

The payload an estimate implies (:func:`_payload_raw`), with the centred prior on its first moments
(:func:`centred_prior`) and the compact-payload prior on its inertia (:func:`compact_prior`),
projected and scaled by the presence weight (:func:`presence_weight`), the starting payload kept
until the payload changes (:func:`_keep_start`), and the standard parameters control uses
(:func:`est_model_trial`, :func:`est_model_trial_in`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.identification.online_slots import (
    C_FOLLOWS,
    C_K,
    MODE_PAYLOAD,
    est_work,
)
from adaptive_dd.identification.pseudo_inertia import project_payload_in


@njit(cache=True, inline="always")
def _keeps_start(c, s, i):  # pragma: no cover - compiled
    """Whether the model control uses still holds the starting payload (``s.start_pay[i]``)."""
    return c.keep_start and s.cnt[i, C_FOLLOWS] == 0


@njit(cache=True, inline="always")
def _keep_start(c, s, i):  # pragma: no cover - compiled
    """Let the model control uses follow the estimate once the payload has changed: at the first
    alarm (:func:`_alarm`), or once the estimated mass has moved from its start by more than the
    detector's threshold times its standard deviation ``sqrt(P_mm)`` after the detector's warm-up.

    Before that the model keeps the starting payload: with the arm exact nothing is left to learn,
    and the estimate's wander on the unloaded arm (the regression's noise and the filters'
    start-up) only moved the model away from the exact one (drawn arms, exact URDF: the first
    segment's adaptive_ct / ct_oracle up to 3.5x; docs/changelog.md). A payload carried from the
    start, or one the detector misses, still moves the mass beyond the bound."""
    cnt = s.cnt[i]
    if not c.keep_start or cnt[C_FOLLOWS] == 1 or cnt[C_K] < c.warmup:
        return
    a = s.theta.shape[1] - 10  # the payload's mass (the payload block's first parameter)
    var = s.P[i, a, a]
    dm = s.theta[i, a] - s.start_mass[i]
    if not (dm * dm <= c.threshold2 * var):  # (a non-finite estimate follows too)
        cnt[C_FOLLOWS] = 1


@njit(cache=True, inline="always")
def _payload_raw(c, th, raw):  # pragma: no cover - compiled
    """The payload (10,) implied by an estimate theta, unprojected (mode "arm": least squares on pbasis)."""
    p = th.shape[0]
    if c.mode == MODE_PAYLOAD:
        for k in range(10):
            raw[k] = th[k]
        return
    for k in range(10):
        acc = 0.0
        for a in range(p):
            acc += c.pbasis_pinv[k, a] * (th[a] - c.sigma0[a])
        raw[k] = acc


@njit(cache=True, inline="always")
def _inertia_cov(c, P, out, tmp):  # pragma: no cover - compiled
    """The inertia block ``out[4:, 4:]`` of the payload parameters' covariance (the part
    :func:`compact_prior` reads; the rest of ``out (10, 10)`` is left as it is): P's own block in
    payload mode, else that block of ``pbasis_pinv P pbasis_pinv^T``."""
    if c.mode == MODE_PAYLOAD:
        for a in range(4, 10):
            for b in range(4, 10):
                out[a, b] = P[a, b]
        return
    p = P.shape[0]  # tmp (10, p) scratch: rows 4-9 written before they are read
    for a in range(4, 10):
        for b in range(p):
            acc = 0.0
            for k in range(p):
                acc += c.pbasis_pinv[a, k] * P[k, b]
            tmp[a, b] = acc
    for a in range(4, 10):
        for b in range(4, 10):
            acc = 0.0
            for k in range(p):
                acc += tmp[a, k] * c.pbasis_pinv[b, k]
            out[a, b] = acc


@njit(cache=True, inline="always")
def _pseudo_measure(raw, Pc, r, value, R, lo, hi, g, row):  # pragma: no cover - compiled
    """One scalar Kalman update of ``raw[lo:hi]`` (covariance ``Pc[lo:hi, lo:hi]``, overwritten)
    with the pseudo-measurement ``raw[r] = value`` of variance ``R``; ``g``, ``row`` scratch.
    False (nothing changed) when the innovation's variance is not finite and positive."""
    S = Pc[r, r] + R
    if not (np.isfinite(S) and S > 0.0):
        return False
    innov = value - raw[r]
    for a in range(lo, hi):
        g[a] = Pc[a, r] / S
        row[a] = Pc[r, a]
    for a in range(lo, hi):
        raw[a] += g[a] * innov
        for b in range(lo, hi):
            Pc[a, b] -= g[a] * row[b]
    return True


@njit(cache=True)
def compact_prior(raw, Pc, rho):  # pragma: no cover - compiled
    """Combine ``raw (10,)`` (covariance ``Pc (10, 10)``, of which only the inertia block
    ``Pc[4:, 4:]`` is read, and overwritten) with a prior that the
    payload is compact: its inertia about the frame ``I = m S(c)^T S(c) + 0.4 m rho^2 1``
    (a solid sphere of radius ``rho`` [m] at the estimated centre of mass ``c`` with the
    estimated mass ``m``), each of the six inertia components with standard deviation
    ``m rho^2 + 1e-6`` [kg m^2]. Six scalar Kalman updates (pseudo-measurements of the
    inertia) on the inertia block of ``Pc``, given the mass and first moments: those are left
    as they are (they are the well-determined part; moving them through their correlation
    with the inertia corrupted the unloaded arm's model, where the prior pins the inertia).

    Right after a swap the data determine the payload's mass and first moments within
    tens of milliseconds but its inertia only over a second (the inertia's columns are
    weakly excited); the prior keeps the model control uses at a plausible inertia
    meanwhile, and the data override it as P shrinks (no effect once the inertia is known).
    """
    compact_prior_in(raw, Pc, rho, np.empty(6), np.empty(10), np.empty(10))


@njit(cache=True)
def compact_prior_in(raw, Pc, rho, mean, g, row):  # pragma: no cover - compiled
    """:func:`compact_prior` with its scratch given: ``mean (6,)``, ``g, row (10,)``."""
    m = max(raw[0], 0.0)
    hx, hy, hz = raw[1], raw[2], raw[3]
    for t in range(6):
        mean[t] = 0.0
    if m > 1e-9:
        h2 = hx * hx + hy * hy + hz * hz
        sph = 0.4 * m * rho * rho
        # (|h|^2 1 - h h^T) / m + sphere; order Ixx, Ixy, Iyy, Ixz, Iyz, Izz
        mean[0] = (h2 - hx * hx) / m + sph
        mean[1] = -hx * hy / m
        mean[2] = (h2 - hy * hy) / m + sph
        mean[3] = -hx * hz / m
        mean[4] = -hy * hz / m
        mean[5] = (h2 - hz * hz) / m + sph
    std = m * rho * rho + 1e-6
    R = std * std
    for t in range(6):
        if not _pseudo_measure(raw, Pc, 4 + t, mean[t], R, 4, 10, g, row):
            return


@njit(cache=True, inline="always")
def _noise_level(c, s, i):  # pragma: no cover - compiled
    """The mean over rows of the detector's noise level (the squared weighted prior error it has
    learned since the last alarm, bias-corrected, once ``min_learned`` samples; before that the
    level established before the alarm, ``ref``): what one weighted equation's error variance is
    in fact, where the recursive least squares take it as 1. 1 where no row has a level."""
    a_l = c.alpha_long
    acc, cnt = 0.0, 0
    for j in range(s.learned.shape[1]):
        nl = s.learned[i, j]
        if nl >= c.min_learned and a_l > 0.0:
            acc += s.long[i, j] / (1.0 - (1.0 - a_l) ** nl)
            cnt += 1
        elif s.ref[i, j] > 0.0:
            acc += s.ref[i, j]
            cnt += 1
    if cnt == 0 or not (acc > 0.0 and np.isfinite(acc)):
        return 1.0
    return acc / cnt


@njit(cache=True)
def presence_weight(m, var, present_var):  # pragma: no cover - compiled
    """Posterior probability that a payload is carried, given a mass estimate ``m`` [kg] of
    variance ``var`` [kg^2] and the variance ``present_var`` [kg^2] of a carried payload's mass.

    The prior is even odds between no payload (mass exactly 0: the unloaded arm, the state at the
    start and after every put-down) and a payload whose mass is normal about 0 with variance
    ``present_var``. With ``m`` normal about the true mass, the likelihood ratio of the two is
    ``sqrt(1 + present_var / var) exp(-m^2 present_var / (2 var (var + present_var)))``, and the
    weight is ``1 / (1 + ratio)``: about ``sqrt(var / present_var)`` for an estimate that is noise
    about 0, 1 once the mass is a few of its standard deviations away from 0, 0.5 with no data
    (``var >> present_var``). 1 when either variance is not > 0 (no weighting).
    """
    if not (var > 0.0 and present_var > 0.0 and np.isfinite(m) and np.isfinite(var)):
        return 1.0
    a = m * m * present_var / (2.0 * var * (var + present_var))
    if a > 700.0:
        return 1.0
    return 1.0 / (1.0 + np.sqrt(1.0 + present_var / var) * np.exp(-a))


@njit(cache=True)
def centred_prior(raw, Pc, r):  # pragma: no cover - compiled
    """Combine the mass and first moments ``raw[:4]`` (covariance ``Pc[:4, :4]``, overwritten)
    with the prior that the payload's centre of mass lies within about ``r`` [m] of its frame
    given its mass: each first moment ``m c_k`` is 0 with variance ``r^2 E[m^2]``, ``E[m^2] =
    max(m, 0)^2 + Pc[0, 0]``. Three scalar Kalman updates (pseudo-measurements ``m c_k = 0``) on
    the 4 x 4 block; the inertias are left as they are (:func:`compact_prior` takes them from the
    result)."""
    centred_prior_in(raw, Pc, r, np.empty(4), np.empty(4))


@njit(cache=True)
def centred_prior_in(raw, Pc, r, g, row):  # pragma: no cover - compiled
    """:func:`centred_prior` with its scratch given: ``g, row`` (at least 4,)."""
    if not (r > 0.0):
        return
    m = max(raw[0], 0.0)
    R = r * r * (m * m + max(Pc[0, 0], 0.0))
    for t in range(1, 4):
        if not _pseudo_measure(raw, Pc, t, 0.0, R, 0, 4, g, row):
            return


@njit(cache=True, inline="always")
def _control_payload(c, s, i, raw, pay, Pc):  # pragma: no cover - compiled
    """:func:`_control_payload_in` with its scratch allocated for this call."""
    _control_payload_in(
        c, s, i, raw, pay, Pc, np.empty(10), np.empty(10), np.empty(6), np.empty((10, s.P.shape[1]))
    )


@njit(cache=True, inline="always")
def _control_payload_in(c, s, i, raw, pay, Pc, g, row, mean, cov):  # pragma: no cover - compiled
    """The payload the model control uses: ``raw`` with the centred prior (:func:`centred_prior`,
    if ``F_COM_SIZE`` is set: :attr:`~adaptive_dd.identification.online_config.OnlineConfig.payload_priors`,
    the payload block's own covariance) and the compact prior (if set); projected
    (if set) and then, in payload mode, scaled by :func:`presence_weight` of the mass (its
    variance ``P[0, 0]``, both after the centred prior, a carried payload's ``F_PRESENT2``): the
    posterior mean of a payload that may be absent. A scaled consistent body stays consistent
    (its pseudo-inertia scaled by a factor in [0, 1], within the same ball). ``Pc (10, 10)``
    scratch.

    The centred prior is weighed against ``P`` as the recursive least squares state it, the
    compact prior against ``P`` in the units of the equations' learned noise (``F_PRIOR_NOISE``):
    scaled, the centred prior overrode first moments the data know on an arm whose rows are far
    noisier than 1 (random:19's 30 % segment, docs/changelog.md), and gained less on the paper's
    arm."""
    m_raw = raw[0]
    var_m = s.P[i][0, 0]
    if c.com_size > 0.0:
        P = s.P[i]
        o = P.shape[0] - 10  # the payload block (mode "arm": after the arm's base parameters)
        for a in range(4):
            for b in range(4):
                Pc[a, b] = P[o + a, o + b]
        centred_prior_in(raw, Pc, c.com_size, g, row)
        m_raw = raw[0]
        var_m = Pc[0, 0]
    rho = c.prior_radius
    if rho > 0.0:
        _inertia_cov(c, s.P[i], Pc, cov)
        if c.prior_noise > 0.0:  # P in the units of the equations' actual noise
            kappa = c.prior_noise * _noise_level(c, s, i)
            for a in range(4, 10):
                for b in range(4, 10):
                    Pc[a, b] *= kappa
        compact_prior_in(raw, Pc, rho, mean, g, row)
    if c.project:
        project_payload_in(raw, pay, c.eig_min, c.bound_radius, Pc)  # Pc read no more
        if c.mode == MODE_PAYLOAD and c.present2 > 0.0:
            wp = presence_weight(m_raw, var_m, c.present2)
            for k in range(10):
                pay[k] *= wp
    else:
        for k in range(10):
            pay[k] = raw[k]


@njit(cache=True)
def est_payload_trial(c, s, i, out):  # pragma: no cover - compiled
    """The payload (10,) about its frame implied by trial i's estimate, projected if set to."""
    raw = np.empty(10)
    _payload_raw(c, s.theta[i], raw)
    _control_payload(c, s, i, raw, out, np.empty((10, 10)))


@njit(cache=True)
def est_model_trial(c, s, i, pi_out):  # pragma: no cover - compiled
    """The model control uses for trial i, as standard parameters ``pi_out (13 n,)``
    (:func:`est_model_trial_in` with its scratch allocated for this call)."""
    est_model_trial_in(c, s, i, pi_out, est_work(c.w.shape[0], s.theta.shape[1]))


@njit(cache=True, inline="always")
def est_model_trial_in(c, s, i, pi_out, w):  # pragma: no cover - compiled
    """The model control uses for trial i, as standard parameters ``pi_out (13 n,)``; ``w``
    (:class:`EstWork`) scratch.

    Payload mode: the arm's ``pi0`` with the (projected) payload folded into link ``jp``
    through ``pmap``. Full mode: ``pi0 + Bpinv (theta_p - B pi0)``, where ``theta_p`` is
    theta with its payload part replaced by the projected one
    (``theta_p = theta + pbasis (payload_projected - payload_raw)``), so that
    ``B pi_out == theta_p``.
    """
    m = pi_out.shape[0]
    for k in range(m):
        pi_out[k] = c.pi0[k]
    th = s.theta[i]
    p = th.shape[0]
    raw, pay = w.raw, w.pay
    _payload_raw(c, th, raw)
    raw_est = raw
    if c.mode != MODE_PAYLOAD:  # mode "arm": theta's own payload
        raw_est = w.raw_est
        for k in range(10):
            raw_est[k] = raw[k]
    if _keeps_start(c, s, i):  # (the priors and the projection would be thrown away)
        for k in range(10):
            pay[k] = s.start_pay[i, k]
    else:
        _control_payload_in(c, s, i, raw, pay, w.Pc, w.pphi, w.row, w.d, w.cov)  # (the RLS's scratch is free)
    if c.mode == MODE_PAYLOAD:
        base = 10 * c.jp
        for a in range(10):
            acc = 0.0
            for b in range(10):
                acc += c.pmap[a, b] * pay[b]
            pi_out[base + a] += acc
        return
    d = w.d
    for a in range(p):
        acc = th[a] - c.sigma0[a]
        for k in range(10):
            acc += c.pbasis[a, k] * (pay[k] - raw_est[k])
        d[a] = acc
    for k in range(m):
        acc = 0.0
        for a in range(p):
            acc += c.Bpinv[k, a] * d[a]
        pi_out[k] += acc
