"""Compiled per-trial step of the N-joint online estimator (:mod:`~adaptive_dd.identification.online`).

:func:`est_step_trial` advances trial ``i`` of an :class:`EstState` by one sample, in
place; :func:`est_model_trial` writes the model that control uses (standard
parameters, projected). The Python path and any compiled closed loop call these
same functions. Configuration travels as one :class:`EstCfg` NamedTuple of arrays
and scalars (built by :func:`~adaptive_dd.identification.online.est_init`).

One sample, per trial:

1. non-finite input: the last finite channels are held, the sample is counted as
   skipped, and the filtered equations are not used for ``taint`` samples (the
   filters' memory);
2. M2 filter bank (eq. 20, Tustin; the same matrices as
   :func:`~adaptive_dd.identification.filters.design_filter_bank`) on the momentum form
   ``tau = d/dt p + wv``: ``G0 tau``, ``G1 p + G0 wv`` and ``G1 py + G0 wy`` (the payload
   link's columns; every link's in mode "arm"), each sum as one state of the bank's
   transposed realisation (:func:`~adaptive_dd.identification.filters.summing_realisation`),
   restarted after an alarm;
3. data selection: equation j is used once joint j has been faster than the
   threshold for the filters' memory;
4. RLS of eq. (14), one scalar update per used joint equation (row weights ``w``);
   the forgetting factor advances once per sample, at the first used row;
5. the change detector on the rows' prior errors and the variances the covariance predicts for
   them (:func:`_prior_variance`, :func:`_detect`); on an alarm the
   covariance is re-opened along the payload subspace (and once more when the
   filters' memory has passed the alarm).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.identification.online_control_model import (  # noqa: F401 (re-exported)
    _control_payload,
    _inertia_cov,
    _keep_start,
    _keeps_start,
    _payload_raw,
    compact_prior,
    est_model_trial,
    est_model_trial_in,
    est_payload_trial,
    presence_weight,
)
from adaptive_dd.identification.online_detector import (  # noqa: F401 (re-exported)
    _alarm,
    _alarm_in,
    _detect,
    _detect_step,
    _posture_noise,
    _prior_variance,
    _ref_rise,
    _reopen,
    _reopen_in,
    est_detect_trial,
    est_force_alarm_trial,
)
from adaptive_dd.identification.online_regression import (  # noqa: F401 (re-exported)
    _arm_momentum_channels,
    _filtered_signals,
    _momentum_channels,
    _payload_rows,
    _regression,
    _rls_row,
    _summed_channels,
    arm_momentum_channels,
)
from adaptive_dd.identification.online_slots import (  # noqa: F401 (re-exported)
    BIG,
    C_ALARMS,
    C_FOLLOWS,
    C_K,
    C_LAST_ALARM,
    C_REOPEN_AT,
    C_RESTART,
    C_SINCE_ALARM,
    C_SINCE_BAD,
    C_SKIPPED,
    C_STARTED,
    MODE_ARM,
    MODE_PAYLOAD,
    MOMENTUM_CHANNELS,
    N_CNT,
    EstCfg,
    EstState,
    EstWork,
    est_work,
)


@njit(cache=True)
def est_step_trial(c, s, i, q, qd, tau):  # pragma: no cover - compiled
    """Advance trial i by one sample in place; return 1 on a change alarm at this sample, else 0.

    :func:`est_step_trial_in` with its scratch allocated for this call.
    """
    return est_step_trial_w(c, s, i, q, qd, tau, est_work(q.shape[0], s.theta.shape[1]))


@njit(cache=True, inline="always")
def est_step_trial_w(c, s, i, q, qd, tau, w):  # pragma: no cover - compiled
    """:func:`est_step_trial_in` through the one compiled copy of the step (:func:`est_step_model`,
    the model left alone), inlined where it is called: :func:`est_step_trial`,
    :func:`est_run` (the estimator run alone) and the closed loop's estimator all call that copy
    (each inlining the step cost a full compilation of it: about 25 CPU s on the UR5)."""
    return est_step_model(c, s, i, q, qd, tau, w, s.lam[:0])


@njit(cache=True, _nrt=False)
def est_step_model(c, s, i, q, qd, tau, w, pi_model):  # pragma: no cover - compiled
    """:func:`est_step_trial_in`, then the model control uses into ``pi_model (13 n,)``
    (:func:`est_model_trial_in`) unless ``pi_model`` is empty: the estimator's step compiled once,
    a function of its own, for the closed loop and for the estimator run alone (an empty
    ``pi_model``, :func:`est_step_trial_w`; a flag would be typed by its literal value: two
    copies). One call per sample: the closed loop passes its records once, as to the compiled
    sample that inlined the step before (a compiled sample calling a compiled step, two calls,
    ran the UR5's ``adaptive_ct`` about 4 % slower per sample)."""
    alarm = est_step_trial_in(c, s, i, q, qd, tau, w)
    if pi_model.shape[0] > 0:
        est_model_trial_in(c, s, i, pi_model, w)
    return alarm


@njit(cache=True, inline="always")
def _back_in_use(c, s, i, j):  # pragma: no cover - compiled
    """Row j of trial i back in use after a slow phase: its short and fast averages restart at the
    level it is judged against, the one learnt since the last alarm or, without one, the one kept
    from before it (``ref``). Its averages stopped while it was out of use, so a row out of use
    since before an alarm held the errors of the swap itself: random:81's second alarm 0.35 s
    after a put-down's, in every seed (``docs/change_detection.md``)."""
    nl = s.learned[i, j]
    if nl > 0:
        den = 1.0 - (1.0 - c.alpha_long) ** nl
        s.short[i, j] = s.long[i, j] / den
        s.nshort[i, j] = s.nlong[i, j] / den
    else:
        s.short[i, j] = s.ref[i, j]
        s.nshort[i, j] = s.nref[i, j]
    s.fast[i, j] = s.short[i, j]
    s.pshort[i, j] = 0.0  # the level holds what the estimate's uncertainty adds in use
    s.pfast[i, j] = 0.0


@njit(cache=True, inline="always")
def est_step_trial_in(c, s, i, q, qd, tau, w):  # pragma: no cover - compiled
    """Advance trial i by one sample in place; return 1 on a change alarm at this sample, else 0.

    Parameters
    ----------
    c : EstCfg
    s : EstState
    i : int
        Trial index.
    q, qd : (n,)
        Measured joint positions [rad] and velocities [rad/s] at this sample.
    tau : (n,)
        Torque applied over this sample [N m]. A non-finite q, qd or tau skips the
        sample (counted in ``cnt[i, C_SKIPPED]``).
    w : EstWork
        Scratch (:func:`est_work`), reused from sample to sample (one per thread).
    """
    n = q.shape[0]
    p = s.theta.shape[1]
    cnt = s.cnt[i]
    usable = _filtered_signals(c, s, i, q, qd, tau, w)
    act = w.act
    n_rows = c.n_rows
    for j in range(n):
        if c.select:
            if np.isfinite(qd[j]) and abs(qd[j]) <= c.sel_threshold:
                s.since_slow[i, j] = 0
            else:
                s.since_slow[i, j] = min(s.since_slow[i, j] + 1, BIG)
            act[j] = s.since_slow[i, j] > c.sel_memory
            if np.isfinite(qd[j]) and abs(qd[j]) <= c.det_speed:
                s.since_crawl[i, j] = 0
            else:
                s.since_crawl[i, j] = min(s.since_crawl[i, j] + 1, BIG)
            if s.since_slow[i, j] == c.sel_memory + 1:
                _back_in_use(c, s, i, j)
        else:
            act[j] = True
        act[j] = act[j] and usable and j < n_rows
    for j in range(n):
        s.eps[i, j] = np.nan
        s.eout[i, j] = np.nan
        s.pvar[i, j] = 0.0
    th, Pi = s.theta[i], s.P[i]
    if usable:
        phi, y = w.phi, w.y
        _regression(c, w.tf, w.ym, w.phim, phi, y)
        pphi, row, nz = w.pphi, w.row, w.nz
        first = True
        for j in range(n_rows):
            if not act[j]:
                continue
            if first:
                s.lam[i] = (1.0 - c.mu) * s.lam[i] + c.mu
            lam_eff = s.lam[i] if first else 1.0
            first = False
            wj = c.w[j]
            for k in range(p):
                row[k] = phi[j, k] / wj
            s.eps[i, j] = _rls_row(th, Pi, row, y[j] / wj, lam_eff, pphi, nz)
            s.pvar[i, j] = _prior_variance(row, pphi, lam_eff) if np.isfinite(s.eps[i, j]) else 0.0
        if not first and c.max_trace > 0.0:
            tr = 0.0
            for k in range(p):
                tr += Pi[k, k]
            if tr > c.max_trace:
                scale = c.max_trace / tr
                for a in range(p):
                    for b in range(p):
                        Pi[a, b] *= scale
        if c.select and c.detect:
            _slow_rows(c, s, i, act, th, Pi, phi, y, row)
    alarm = 0
    if c.detect:
        if cnt[C_REOPEN_AT] == cnt[C_K]:
            _reopen_in(c, Pi, w.rq, w.rs)
        _posture_noise(c, s, i, w)  # reads what the filters' momentum form left in w.chain
        _ref_rise(c, s, i, q, w)
        alarm = _detect_step(c, s, i, s.eps[i], act)
        if alarm:
            _alarm_in(c, s, i, cnt[C_K], w)
        _keep_start(c, s, i)
    cnt[C_K] += 1
    return alarm


@njit(cache=True, inline="always")
def _slow_rows(c, s, i, act, th, P, phi, y, row):  # pragma: no cover - compiled
    """The rows out of use because their joint is slow (a reversal; the data selection): each one's
    prior error at the estimate, which it does not update, into ``s.eout[i]``, and the variance
    the covariance predicts for it, ``phi_j^T P phi_j``, into ``s.pvar[i]``, for the detector
    (:func:`_detect`: a payload swapped while the joints carrying it reverse shows first in
    their rows)."""
    p = th.shape[0]
    for j in range(c.n_rows):
        if act[j] or s.since_slow[i, j] > c.sel_memory:
            continue
        wj = c.w[j]
        e = y[j] / wj
        for a in range(p):
            row[a] = phi[j, a] / wj
            e -= row[a] * th[a]
        v = 0.0
        for a in range(p):
            if row[a] == 0.0:
                continue
            acc = 0.0
            for b in range(p):
                acc += P[a, b] * row[b]
            v += row[a] * acc
        if np.isfinite(e) and np.isfinite(v):
            s.eout[i, j] = e
            s.pvar[i, j] = max(v, 0.0)


@njit(cache=True)
def est_run(
    c, s, i0, q, qd, tau, theta_rec, payload_rec, eps_rec, alarm_rec, lam_rec
):  # pragma: no cover - compiled
    """Step trials ``i0 .. i0 + m - 1`` of ``s`` through records ``q, qd, tau (m, N, n)``, alarms
    into ``alarm_rec (m, N)``; after every sample the estimate, the payload it implies, the prior
    errors and the forgetting factor into ``theta_rec (m, N, p)``, ``payload_rec (m, N, 10)``,
    ``eps_rec (m, N, n)`` and ``lam_rec (m, N)``, unless ``theta_rec`` has no trial (then
    alarms alone). The one compiled driver of the estimator run alone (:func:`est_run_trial`,
    ``online.est_step``, ``online.run_online``): each compiled caller of the step links and
    optimises it again (about 8 CPU s on the UR5), so its callers share this one, with one
    specialisation (the same argument types from every caller)."""
    record = theta_rec.shape[0] > 0
    pay = np.empty(10)
    w = est_work(q.shape[2], s.theta.shape[1])
    for t in range(q.shape[0]):
        i = i0 + t
        for k in range(q.shape[1]):
            alarm_rec[t, k] = est_step_trial_w(c, s, i, q[t, k], qd[t, k], tau[t, k], w)
            if not record:
                continue
            # loops, not slice assignments: numba would compile the slice assignment's shape-error
            # message (string code, about 2 CPU s)
            for a in range(s.theta.shape[1]):
                theta_rec[t, k, a] = s.theta[i, a]
            est_payload_trial(c, s, i, pay)
            for a in range(10):
                payload_rec[t, k, a] = pay[a]
            for a in range(s.eps.shape[1]):
                eps_rec[t, k, a] = s.eps[i, a]
            lam_rec[t, k] = s.lam[i]


def est_run_trial(c, s, i, q, qd, tau, theta_rec, payload_rec, eps_rec, alarm_rec, lam_rec) -> None:
    """Step trial i through a record ``q, qd, tau (N, n)``, recording after every sample into
    ``theta_rec (N, p)``, ``payload_rec (N, 10)``, ``eps_rec (N, n)``, ``alarm_rec (N,)`` (int64)
    and ``lam_rec (N,)``: :func:`est_run` on one trial."""
    q, qd, tau = (np.ascontiguousarray(x, dtype=np.float64)[None] for x in (q, qd, tau))
    recs = (theta_rec, payload_rec, eps_rec, alarm_rec, lam_rec)
    est_run(c, s, i, q, qd, tau, *(r[None] for r in recs))
