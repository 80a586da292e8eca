"""The compiled online estimator's change detector and what an alarm does.

Per row, short and long averages of the weighted prior errors against a learned level plus the
variance the estimate's covariance predicts for them (:func:`_detect`, :func:`_prior_variance`;
the level's rise at an alarm :func:`_ref_rise`); an alarm re-opens the covariance along the
payload subspace (:func:`_reopen`) and restarts the levels (:func:`_alarm`).
``docs/change_detection.md`` states the rules.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.identification.online_control_model import (
    _control_payload_in,
    _keeps_start,
    _payload_raw,
)
from adaptive_dd.identification.online_slots import (
    BIG,
    C_ALARMS,
    C_FOLLOWS,
    C_K,
    C_LAST_ALARM,
    C_REOPEN_AT,
    C_RESTART,
    C_SINCE_ALARM,
    est_work,
)
from adaptive_dd.plant.chain import (
    mass_matrix_in,
)
from adaptive_dd.plant.chain_dynamics import _composite_mass


@njit(cache=True)
def _reopen(c, P):  # pragma: no cover - compiled
    """``P <- (I - U U^T) P (I - U U^T) + P_reopen``: forget what was known along the payload
    subspace (:func:`_reopen_in` with its scratch made for this call)."""
    p, r = c.U.shape
    _reopen_in(c, P, np.zeros((p, r)), np.zeros((r, r)))


@njit(cache=True)
def _reopen_in(c, P, Q, S):  # pragma: no cover - compiled
    """:func:`_reopen` with its scratch given, ``Q`` (at least p x r) and ``S`` (at least r x r),
    ``r`` the payload subspace's columns: no allocation (the estimator's step calls it)."""
    U = c.U
    p, r = U.shape
    # Q = P U (p x r), S = U^T P U (r x r)
    for a in range(p):
        for k in range(r):
            acc = 0.0
            for b in range(p):
                acc += P[a, b] * U[b, k]
            Q[a, k] = acc
    for k in range(r):
        for m in range(r):
            acc = 0.0
            for a in range(p):
                acc += U[a, k] * Q[a, m]
            S[k, m] = acc
    # (I-UU^T)P(I-UU^T) = P - U Q^T - Q U^T + U S U^T
    for a in range(p):
        for b in range(p):
            acc = P[a, b]
            for k in range(r):
                acc -= U[a, k] * Q[b, k] + Q[a, k] * U[b, k]
                for m in range(r):
                    acc += U[a, k] * S[k, m] * U[b, m]
            P[a, b] = acc + c.P_reopen[a, b]


@njit(cache=True, inline="always")
def _ref_rise(c, s, i, q, w):  # pragma: no cover - compiled
    """``s.ref_rise[i]`` (:func:`_ref_rise_window`): 1 outside the re-learning window after an
    alarm, at every sample; the inertias inside it. Inlined where it is called, so that the
    samples outside the window cost no call: a compiled call handing over the estimator's
    records, about a hundred arrays, costs more than the loop it makes."""
    k = s.cnt[i, C_SINCE_ALARM]
    if c.holdoff <= k < c.resume + c.min_learned:
        _ref_rise_window(c, s, i, q, w)
    else:
        for j in range(q.shape[0]):
            s.ref_rise[i, j] = 1.0


@njit(cache=True)
def _ref_rise_window(c, s, i, q, w):  # pragma: no cover - compiled
    """``s.ref_rise[i]``: per row, how much the payload the estimate now holds raises the row's
    noise variance over the payload it held at the last alarm (``s.ref_pay[i]``), at least 1;
    1 outside the window in which a row is judged against its level of before that alarm.

    The rows' noise is the measured velocity's through the inertia (``G1 (M qd)`` in momentum
    form, ``M qdd`` at the filtered signals): row j's variance ``(M diag(vn^2) M^T)_jj``, ``M``
    the model's inertia (armature included) at the measured q with the payload folded into its
    link, ``vn^2`` the sensor's velocity noise (``c.vdet``). A payload picked up raises it, and
    the level kept from before the pick-up (``ref``) is then too low for the re-learning window:
    the Kinova Gen3 with 2 kg, the wrist rows' noise 5x, a second alarm 0.3-0.45 s after the
    pick-up in 5 of 50 trials (``docs/change_detection.md``, "The level kept over a pick-up").
    Called only in that window (two inertia matrices a sample).
    """
    n = q.shape[0]
    live = False
    for j in range(n):
        live = live or s.ref[i, j] > 0.0
    for j in range(n):
        s.ref_rise[i, j] = 1.0
    if not live:
        return
    raw, pay, pi = w.raw, w.pay, w.pir
    _payload_raw(c, s.theta[i], raw)
    _control_payload_in(c, s, i, raw, pay, w.Pc, w.pphi, w.row, w.d, w.cov)  # (the RLS's scratch is free)
    for t in range(2):
        M = w.Mr if t == 0 else w.Mr0
        src = pay if t == 0 else s.ref_pay[i]
        for a in range(10 * n):
            pi[a] = c.pi0[a]
        base = 10 * c.jp
        for a in range(10):
            acc = 0.0
            for b in range(10):
                acc += c.pmap[a, b] * src[b]
            pi[base + a] += acc
        mass_matrix_in(c.ch, pi, q, w.chain, M)
        for j in range(n):
            M[j, j] += c.pi0[12 * n + j]
    for j in range(n):
        v1, v0 = 0.0, 0.0
        for k2 in range(n):
            v1 += w.Mr[j, k2] * w.Mr[j, k2] * c.vdet[k2]
            v0 += w.Mr0[j, k2] * w.Mr0[j, k2] * c.vdet[k2]
        if v0 > 0.0 and v1 > v0 and np.isfinite(v1):
            s.ref_rise[i, j] = v1 / v0


@njit(cache=True, inline="always")
def _posture_noise(c, s, i, w):  # pragma: no cover - compiled
    """``s.nvar[i]``: per row, the variance the measured velocity's noise gives the weighted row's
    error at the sample's posture, ``vrow_j (M diag(vdet) M^T)_jj``, ``M`` the known arm's inertia
    (armature included), ``vrow_j`` the filter's noise gain over the row's weight squared.

    ``M`` is built from the joint axes and world inertias that this sample's momentum form left in
    ``w.chain`` (:func:`~adaptive_dd.plant.chain_regressor.momentum_form_in` of the known arm at the
    held ``q``): call it after the filters and before anything else writes ``w.chain``
    (:func:`_ref_rise`'s inertia with a payload).

    The rows' noise is the measured velocity's through the inertia (``G1 (M qd)``), and the inertia
    a row carries changes with the posture: a base joint's with the arm's reach, squared. A level
    learnt over the last second is too low where the arm reaches further than it did then; the
    detector adds to it what the posture adds to the row's noise over the postures it was learnt
    at (:func:`_detect`). On drawn arms the base row's posture noise had risen 3.1-3.5x over its
    level's mean within 20 ms at each of the population's five false alarms (random:4, 27, 32;
    ``docs/change_detection.md``, "The level follows the posture").
    Inlined where it is called, as :func:`_ref_rise` is (a call costs more than it computes).
    """
    n = s.nvar.shape[1]
    M, ch = w.Mr, w.chain
    _composite_mass(ch[2], ch[4], M, ch[9][n : n + 10], ch[8][0])
    for j in range(n):
        M[j, j] += c.pi0[12 * n + j]
    for j in range(n):
        v = 0.0
        for k in range(n):
            v += M[j, k] * M[j, k] * c.vdet[k]
        v *= c.vrow[j]
        s.nvar[i, j] = v if np.isfinite(v) else 0.0


@njit(cache=True, inline="always")
def _excess(now, mean):  # pragma: no cover - compiled
    """``max(now - mean, 0)``, 0 without a mean (``mean`` 0: nothing learnt)."""
    return max(now - mean, 0.0) if mean > 0.0 else 0.0


@njit(cache=True, inline="always")
def _prior_variance(phi, g, lam):  # pragma: no cover - compiled
    """``phi^T P phi`` of the covariance ``P`` before :func:`_rls_row`'s update, from what that
    update leaves in its scratch, ``g = P phi / sqrt(lam + phi^T P phi)``: with
    ``x = phi . g = v / sqrt(lam + v)``, ``v`` is the positive root of ``v^2 - x^2 v - x^2 lam``,
    ``(x^2 + x sqrt(x^2 + 4 lam)) / 2`` (O(p), where ``phi^T P phi`` itself costs O(p^2)).

    The prior error of the row is ``eps = e + phi^T (theta* - theta)``, noise ``e`` and the
    estimate's error: its variance is the noise's plus ``phi^T P phi`` in the recursive least
    squares' own scaling (each weighted equation's noise taken as of variance 1), the innovation's
    predicted variance of a Kalman filter on a constant parameter (Gustafsson, "Adaptive Filtering
    and Change Detection", 2000, ch. 5).
    """
    x = 0.0
    for a in range(phi.shape[0]):
        x += phi[a] * g[a]
    if not (x > 0.0 and np.isfinite(x)):
        return 0.0
    x2 = x * x
    return 0.5 * (x2 + x * np.sqrt(x2 + 4.0 * lam))


@njit(cache=True, inline="always")
def _detect(c, s, i, eps, act):  # pragma: no cover - compiled
    """Update the detector of trial i with the rows' prior errors; return True on an alarm.

    Per row j: a short average of ``eps_j^2`` against a long-run level, the
    bias-corrected average ``long / (1 - (1 - a)^learned)`` of what it learned. The
    level learns from ``resume`` samples after the last alarm on, and not from a
    sample whose ``eps^2`` exceeds ``gate^2`` times the level (once ``gate_after``
    samples are learned), so that a change during the learning is not absorbed.
    A row may alarm once it has been *seen* ``min_learned`` times since the last alarm
    (seen, not learned: gated samples count, so the re-arm time is bounded), outside
    the warm-up and the hold-off. Until then, and for at most ``resume + min_learned``
    samples after the alarm (the re-arm bound of a row in use throughout), a row that had
    established its level
    before the last alarm is compared with that level (``ref``, raised by the noise the
    estimate's new payload adds to the row, :func:`_ref_rise`, with the threshold times
    ``relearn``, as the estimate may still be converging): a change that
    follows a false alarm within the re-learning time is detected after the hold-off.
    Past that bound such a row, not yet seen ``min_learned`` times (it was out of use), is
    compared with what it has learned since, once that is ``gate_after`` samples (the count
    after which the level is trusted to gate its own learning), with the same stricter
    threshold (a level learnt over few samples is uncertain; without it, random:14 alarmed
    again 0.43 s after a put-down).
    ``ref`` is set only from an established level, so this adds at most one alarm
    (a swap that raises the noise level cannot chain alarms through it). Its time is bounded
    because a swap changes the noise level itself (the measured velocity's noise enters the
    regression times the inertia each row carries): a row out of use after a swap's alarm
    (slow, reversing) saw nothing of the new noise, and kept comparing it with the stale
    level for as long as it stayed out of use (iiwa 14, 3 kg picked up: joint 6's prior error
    0.09 -> 0.5 RMS, 0.03 of it without sensor noise; 17 of 50 trials with a false alarm 0.5-0.8 s
    after the swap before the bound, 1 of 50 after it, ``docs/learning_the_arm.md``). The level is at
    least ``floor^2``: a row that is nearly noise-free (a wrist joint) would otherwise
    alarm on the regression's own modelling error, which varies with the motion. The threshold
    is the same whether or not another row is out of use: a joint's friction enters its own
    equation only, so a slow or reversing joint does not disturb the others' (a threshold 1.5
    times higher while another row was out of use delayed the alarms: ``docs/changelog.md``).

    The averages are also judged against the level plus what the posture adds to the row's noise
    over the postures the level was learnt at (:func:`_posture_noise`: ``nshort``, for the single
    sample ``nvar``, over the mean of ``nlong``; for the level kept as ``ref``, over ``nref``; only
    a rise counts): a base joint's noise grows with the arm's reach.

    The averages are judged against the level plus what the same average of the variance the
    estimate's covariance predicts for the row's prior error (``s.pvar``, ``phi_j^T P phi_j``:
    ``s.pshort``, ``s.pfast``) exceeds the share of it the level learnt (``s.plong``, kept with
    ``ref`` as ``s.pref``; the level is a mean of ``eps^2``, which holds it): a row whose
    regressor the estimate has not yet learnt along (the payload re-opened at an alarm and learnt
    from the other rows while this one was out of use) carries that uncertainty in its prior
    error, which its noise level does not (random:108:
    ``phi_j^T P phi_j`` 90-254 at a row's first sample back in use 0.3 s after the swap's alarm,
    against its level of 0.6; about 0.003 in steady state).

    A row out of use because its joint is slow (``s.eout[i, j]`` finite: its prior error at the
    estimate it does not update, :func:`~adaptive_dd.identification.online_kernel._slow_rows`)
    feeds its short and fast averages but not its level, and alarms only against a level it learnt
    itself since the last alarm, its RMS bound plus ``(2 + creep_margin) fc_j / w_j`` (the bound's
    square is ``(sqrt(threshold^2 level) + flip)^2``): the model's Coulomb friction turned over
    by the measured speed's sign near a reversal, and friction the model lacks near rest. A
    payload swapped while the joints carrying it reverse shows first in their rows (random:111's
    swap to 30 % at 8 s: 57 ms to the alarm while they were not read, 17 ms).
    """
    n = eps.shape[0]
    a_s, a_l = c.alpha_short, c.alpha_long
    cnt = s.cnt[i]
    learn = cnt[C_SINCE_ALARM] >= c.resume
    rise2 = c.hold_above2 * c.threshold2
    for j in range(n):
        if s.hold[i, j] > 0.0:  # a hold runs out I_HOLD samples after the rise, in use or not
            s.held[i, j] += 1
            if s.held[i, j] > c.hold:
                s.hold[i, j] = -1.0
        e = eps[j]
        if not act[j] and np.isfinite(s.eout[i, j]):
            if s.learned[i, j] > 0:
                # out of use (slow): its averages only, at the estimate it leaves; only with a
                # level learnt since the last alarm (back in use, such a row's averages restart
                # at its level; one without would carry the reversal's errors into use)
                e = s.eout[i, j]
                s.short[i, j] += a_s * (e * e - s.short[i, j])
                s.fast[i, j] += c.alpha_fast * (e * e - s.fast[i, j])
                s.nshort[i, j] += a_s * (s.nvar[i, j] - s.nshort[i, j])
                s.pshort[i, j] += a_s * (s.pvar[i, j] - s.pshort[i, j])
                s.pfast[i, j] += c.alpha_fast * (s.pvar[i, j] - s.pfast[i, j])
            continue
        if not (act[j] and np.isfinite(e)):
            continue
        e2 = e * e
        s.short[i, j] += a_s * (e2 - s.short[i, j])
        s.fast[i, j] += c.alpha_fast * (e2 - s.fast[i, j])
        s.nshort[i, j] += a_s * (s.nvar[i, j] - s.nshort[i, j])
        s.pshort[i, j] += a_s * (s.pvar[i, j] - s.pshort[i, j])
        s.pfast[i, j] += c.alpha_fast * (s.pvar[i, j] - s.pfast[i, j])
        if learn:
            s.seen[i, j] += 1
            nl = s.learned[i, j]
            # a level learned over min_learned samples since the last alarm is established
            est = nl >= c.min_learned
            level = c.floor2
            nmean = 0.0
            if nl >= 1:
                den = 1.0 - (1.0 - a_l) ** nl
                level = max(s.long[i, j] / den, c.floor2)
                nmean = s.nlong[i, j] / den
            ok = True
            if nl >= c.gate_after:
                ok = e2 <= c.gate2 * level
            if c.hold > 0 and est:
                # a row whose short average rises is judged against the level it had then, for
                # I_HOLD samples (a change's rise); the level itself learns on
                if s.hold[i, j] == 0.0:
                    if s.short[i, j] > rise2 * (level + _excess(s.nshort[i, j], nmean)):
                        s.hold[i, j] = level
                        s.held[i, j] = 0
                elif s.short[i, j] <= rise2 * (s.hold[i, j] if s.hold[i, j] > 0.0 else level):
                    s.hold[i, j] = 0.0  # back below: the next rise holds again
            if ok:
                s.long[i, j] += a_l * (e2 - s.long[i, j])
                s.plong[i, j] += a_l * (s.pvar[i, j] - s.plong[i, j])
                s.nlong[i, j] += a_l * (s.nvar[i, j] - s.nlong[i, j])
                s.learned[i, j] = nl + 1
    if cnt[C_K] < c.warmup or cnt[C_SINCE_ALARM] <= c.holdoff:
        return False
    alarm = False
    fast = False
    for j in range(n):
        slow = not act[j] and np.isfinite(s.eout[i, j])
        if not (act[j] or slow):
            continue
        nl = s.learned[i, j]
        thr = c.threshold2
        own = s.seen[i, j] >= c.min_learned and nl >= 1
        den = 1.0 - (1.0 - a_l) ** nl  # the long averages' bias correction after nl samples
        # the share of the level that is the estimate's uncertainty (learnt with it)
        plev = s.plong[i, j] / den if nl >= 1 else 0.0
        # the posture's rise of the row's noise over the postures its level was learnt at
        nmean = s.nlong[i, j] / den if nl >= 1 else 0.0
        rise = _excess(s.nshort[i, j], nmean)
        rise_fast = _excess(s.nvar[i, j], nmean)
        if own:
            level = max(s.long[i, j] / den, c.floor2)
            if s.hold[i, j] > 0.0:  # risen within the hold: the level it had before
                level = s.hold[i, j]
        elif slow:  # out of use: only against a level it learnt itself since the last alarm
            continue
        elif s.ref[i, j] > 0.0 and cnt[C_SINCE_ALARM] < c.resume + c.min_learned:
            # still re-learning, within the re-arm bound: the level established before the last
            # alarm, raised by what the new payload adds to the row's noise (_ref_rise), with the
            # stricter threshold (the estimate may still converge)
            level = max(s.ref[i, j] * s.ref_rise[i, j], c.floor2)
            plev = s.pref[i, j]
            rise = _excess(s.nshort[i, j], s.nref[i, j])
            rise_fast = _excess(s.nvar[i, j], s.nref[i, j])
            thr = c.threshold2 * c.relearn2
        elif s.ref[i, j] > 0.0 and nl >= c.gate_after:
            # past the bound, not yet seen enough: what it learned since (trusted as for the gate),
            # with the stricter threshold (a level learnt over few samples)
            level = max(s.long[i, j] / den, c.floor2)
            thr = c.threshold2 * c.relearn2
        else:
            continue
        # a joint at most the detector's speed within the selection memory creeps: friction the
        # model lacks errs there (Stribeck, soft friction), by less than the joint's Coulomb
        # friction; its row raises an alarm only beyond that (in the weighted equation's units)
        creep2 = 0.0
        if c.select and s.since_crawl[i, j] <= c.sel_memory:
            creep2 = (c.creep_margin * c.pi0[11 * n + j] / c.w[j]) ** 2
        # the level plus what the estimate's uncertainty along the row (the innovation's predicted
        # variance, averaged as the squared errors are) exceeds the share the level learnt of it;
        # a row out of use errs, besides that, by the model's Coulomb friction turned over (the
        # measured speed's sign near zero: 2 fc) and what the model lacks near rest: a bound on
        # the error's RMS, added to the noise's RMS bound (the triangle inequality: the two are
        # not independent, so their mean squares do not add)
        flip = 0.0
        if slow:
            flip = (2.0 + c.creep_margin) * c.pi0[11 * n + j] / c.w[j]
        more = max(s.pshort[i, j] - plev, 0.0)
        bound = (np.sqrt(thr * (level + rise + more)) + flip) ** 2
        if s.short[i, j] > bound + 1e-300 and s.short[i, j] > creep2:
            alarm = True
        if c.fast and own and nl >= c.fast_learned:
            # only against a level the row has learned itself over the long window: not the
            # level of before an alarm, nor one still learning a new payload or the arm
            more = max(s.pfast[i, j] - plev, 0.0)
            bound = (np.sqrt(c.fast2 * (level + rise_fast + more)) + flip) ** 2
            if s.fast[i, j] > bound + 1e-300 and s.fast[i, j] > creep2:
                fast = True
    return alarm or fast


@njit(cache=True)
def _alarm(c, s, i, k):  # pragma: no cover - compiled
    """What an alarm at sample k does (:func:`_alarm_in` with its scratch made for this call)."""
    _alarm_in(c, s, i, k, est_work(c.w.shape[0], s.theta.shape[1]))


@njit(cache=True)
def _alarm_in(c, s, i, k, w):  # pragma: no cover - compiled
    """What an alarm at sample k does: re-open P, count, restart the level (keeping it as ``ref``);
    ``w`` (:class:`~adaptive_dd.identification.online_slots.EstWork`) scratch, its model's part
    free at this point of a sample (the model is made after the step)."""
    cnt = s.cnt[i]
    # the payload the model holds now, with which the levels kept as ref were learnt
    raw = w.raw
    _payload_raw(c, s.theta[i], raw)
    _control_payload_in(c, s, i, raw, s.ref_pay[i], w.Pc, w.pphi, w.row, w.d, w.cov)
    if _keeps_start(c, s, i):
        for a in range(10):
            s.ref_pay[i, a] = s.start_pay[i, a]
    cnt[C_FOLLOWS] = 1
    _reopen_in(c, s.P[i], w.rq, w.rs)
    cnt[C_ALARMS] += 1
    cnt[C_SINCE_ALARM] = 0
    cnt[C_LAST_ALARM] = k
    a_l = c.alpha_long
    for j in range(s.seen.shape[1]):
        nl = s.learned[i, j]
        # the level this row had established (0: none) serves until it re-learns; kept without
        # the floor (applied where it serves), so that a noise rise scales what was learnt
        s.ref[i, j] = 0.0
        s.pref[i, j] = 0.0
        if s.seen[i, j] >= c.min_learned and nl >= 1:
            den = 1.0 - (1.0 - a_l) ** nl  # the long averages' bias correction
            s.ref[i, j] = max(s.long[i, j] / den, 1e-300)
            s.pref[i, j] = s.plong[i, j] / den
        s.nref[i, j] = s.nlong[i, j] / (1.0 - (1.0 - a_l) ** nl) if nl >= 1 else 0.0
        s.seen[i, j] = 0
        s.learned[i, j] = 0
        s.long[i, j] = 0.0
        s.plong[i, j] = 0.0
        s.nlong[i, j] = 0.0
        s.hold[i, j] = 0.0
        s.held[i, j] = 0
    if c.reopen_again:
        cnt[C_REOPEN_AT] = k + c.freeze
    cnt[C_RESTART] = 1


@njit(cache=True, inline="always")
def _detect_step(c, s, i, eps, act):  # pragma: no cover - compiled
    """The detector's part of a sample: :func:`_detect`; 1 on an alarm, which the caller then
    raises (:func:`_alarm_in` with the step's scratch, or :func:`_alarm`), else the count since
    the last one and 0."""
    cnt = s.cnt[i]
    if _detect(c, s, i, eps, act):
        return 1
    cnt[C_SINCE_ALARM] = min(cnt[C_SINCE_ALARM] + 1, BIG)
    return 0


@njit(cache=True)
def est_detect_trial(c, s, i, eps, act):  # pragma: no cover - compiled
    """One sample of trial i's detector alone on given weighted prior errors ``eps (n,)`` of the
    rows in use ``act (n,)`` (bool): 1 on an alarm, else 0. The estimate is not stepped (an alarm
    still re-opens its covariance). For tests and replays of the detector on synthetic errors."""
    alarm = _detect_step(c, s, i, eps, act)
    if alarm:  # its scratch made at an alarm only: a replay calls this every sample
        _alarm(c, s, i, s.cnt[i, C_K])
    s.cnt[i, C_K] += 1
    return alarm


@njit(cache=True)
def est_force_alarm_trial(c, s, i):  # pragma: no cover - compiled
    """Raise an alarm on trial i at its last stepped sample, as if the detector had.

    For a caller that knows of a change (a tool changer's signal) and for tests of what
    follows an alarm. Does nothing before the first sample.
    """
    if s.cnt[i, C_K] > 0:
        _alarm(c, s, i, s.cnt[i, C_K] - 1)
