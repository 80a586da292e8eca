"""The per-sample glue of the N-joint closed loop, written once.

One sample of one trial is:

1. :func:`measure_trial_sample`: encoder and noise (drawn in blocks by the runner), a lost
   measurement replaced by the last good one for the law and by NaN for the estimator;
2. the command: the compiled law (:func:`~adaptive_dd.closed_loop.laws.law_trial_in`) or a
   Python controller's ``command`` for the whole batch;
3. :func:`apply_trial_sample`: the divergence rule (a non-finite command or an error beyond
   ``max_error`` zeroes the command and fails the trial), saturation and D/A, the plant
   step, the runaway rule (non-finite state or ``|qd| > max_speed``), the failure freeze
   (a failed trial stays at its last finite position, at rest, with zero torque), the
   streamed metrics and the recorded trajectories;
4. the estimator: compiled (:func:`estimator_trial_sample`) or the controller's ``observe``;
   then :func:`record_estimate_trial` keeps the estimate at each segment's end.

The compiled path runs all four inside :func:`closed_loop_block` (a range of trials, the
GIL released so that threads run ranges in parallel);
the Python path calls the batch wrappers (``*_batch``) around the Python controller, so
both paths do the same arithmetic in the same order.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit, types
from numba.extending import overload
from numpy.typing import NDArray

from adaptive_dd.closed_loop.laws import law_trial_in, law_work
from adaptive_dd.closed_loop.plant import plant_scratch, plant_step
from adaptive_dd.identification.online_kernel import est_model_trial_in, est_step_trial_in, est_work
from adaptive_dd.plant.sampling import actuate_trial, measure_trial

__all__ = [
    "Alarms",
    "alarm_lists",
    "apply_batch",
    "apply_trial_sample",
    "closed_loop_block",
    "estimator_batch",
    "estimator_model",
    "estimator_step",
    "estimator_trial_sample",
    "measure_batch",
    "measure_trial_sample",
    "record_estimate_trial",
    "sample_work",
    "segment_of",
    "sigma_batch",
]


class Alarms(NamedTuple):
    """Change-detector alarms: ``times (S, capacity)`` [s], ``count (S,)`` (may exceed capacity)."""

    times: NDArray[np.float64]
    count: NDArray[np.int64]


def alarm_lists(alarms: Alarms) -> list[list[float]]:
    """Per trial, the alarm times [s] that were kept (at most the capacity)."""
    cap = alarms.times.shape[1]
    return [list(alarms.times[i, : min(c, cap)]) for i, c in enumerate(alarms.count)]


@njit(cache=True)
def segment_of(rc, k):  # pragma: no cover - compiled
    """Payload segment of sample ``k``."""
    s = 0
    while s + 1 < rc.seg_start.shape[0] and k >= rc.seg_start[s + 1]:
        s += 1
    return s


@njit(cache=True, inline="always")
def measure_trial_sample(io, ts, i, noise, lost, qm, qdm, qm_obs, qdm_obs):  # pragma: no cover
    """Measured ``qm, qdm (n,)`` for the law and ``qm_obs, qdm_obs`` for the estimator (NaN if lost)."""
    n = qm.shape[0]
    measure_trial(ts.q[i], ts.qd[i], noise, io.res, io.std, io.quantize_encoder, qm, qdm)
    if lost:
        ts.n_dropped[i] += 1
        for j in range(n):
            qm_obs[j], qdm_obs[j] = np.nan, np.nan
            qm[j], qdm[j] = ts.held_q[i, j], ts.held_qd[i, j]
    else:
        for j in range(n):
            qm_obs[j], qdm_obs[j] = qm[j], qdm[j]
            ts.held_q[i, j], ts.held_qd[i, j] = qm[j], qdm[j]


@njit(cache=True)
def _accumulate(rc, acc, i, s, k, e, tau, mask):  # pragma: no cover - compiled
    en2 = 0.0
    t2 = 0.0
    for j in range(e.shape[0]):
        en2 += e[j] * e[j]
        t2 += tau[j] * tau[j]
        acc.sum_e2_joint[i, s, j] += e[j] * e[j]
    en = np.sqrt(en2)
    acc.sum_e2[i, s] += en2
    if en > acc.max_e[i, s]:
        acc.max_e[i, s] = en
    acc.sum_tau2[i, s] += t2
    if mask != 0:
        acc.n_saturated[i, s] += 1.0
    if k >= rc.seg_settled[s]:
        acc.sum_e2_settled[i, s] += en2
    acc.e_norm[i, k] = en


@njit(cache=True)
def sample_work(n):  # pragma: no cover - compiled
    """Work arrays of one trial's :func:`apply_trial_sample`: plant scratch, error, previous q."""
    return plant_scratch(n), np.empty(n), np.empty(n)


@njit(cache=True, inline="always")
def apply_trial_sample(ch, rc, io, pl, ts, acc, rec, i, k, s, cmd, tau, work):  # pragma: no cover
    """Steps 3 of the module docstring for trial i at sample k (segment s); ``tau (n,)`` applied;
    ``work``: :func:`sample_work` (allocated once per trial, not per sample)."""
    n = cmd.shape[0]
    sc, e, prev = work
    bad = False
    for j in range(n):
        e[j] = rc.q_d[k, j] - ts.q[i, j]
        if not np.isfinite(cmd[j]) or abs(e[j]) > rc.max_error:
            bad = True
    if bad:
        cmd[:] = 0.0
    mask = actuate_trial(cmd, io.lim, io.lsb, io.saturate, io.quantize_dac, tau)
    if ts.failed[i]:
        tau[:] = 0.0
    keep = i < rec.q.shape[0]
    for j in range(n):
        prev[j] = ts.q[i, j]
    if keep:
        for j in range(n):
            rec.q[i, k, j], rec.qd[i, k, j] = ts.q[i, j], ts.qd[i, j]
    plant_step(ch, pl, i, s, ts.q[i], ts.qd[i], tau, rc.T, ts.stuck[i], sc)
    ok = True
    for j in range(n):
        if not (np.isfinite(ts.q[i, j]) and abs(ts.qd[i, j]) < rc.max_speed):
            ok = False
    if bad or not ok or ts.failed[i]:
        if not ts.failed[i]:
            ts.failed_at[i] = k
        ts.failed[i] = True
        for j in range(n):
            ts.q[i, j] = prev[j] if np.isfinite(prev[j]) else 0.0
            ts.qd[i, j] = 0.0
            ts.stuck[i, j] = True
    _accumulate(rc, acc, i, s, k, e, tau, mask)
    if keep:
        for j in range(n):
            rec.tau[i, k, j] = tau[j]
            rec.saturated[i, k, j] = (mask >> j) & 1 == 1


@njit(cache=True)
def record_estimate_trial(rc, rec, i, k, s, sigma):  # pragma: no cover - compiled
    """Keep the estimate ``sigma (p,)`` at the segment's last sample, and for recorded trials."""
    if k == rc.seg_end[s] - 1:
        for c in range(sigma.shape[0]):
            rec.sigma_end[i, s, c] = sigma[c]
    if i < rec.sigma.shape[0]:
        for c in range(sigma.shape[0]):
            rec.sigma[i, k, c] = sigma[c]


def estimator_work(ec, es):  # pragma: no cover - replaced by the overload
    """Scratch of one trial's estimator, reused from sample to sample (an empty array without one)."""
    raise NotImplementedError("compiled only")


def estimator_step(ec, es, i, q, qd, tau, ew):  # pragma: no cover - replaced by the overload
    """One sample of trial i's estimator: 1 on an alarm. Chosen at compile time by the type of
    ``ec``: an array means no estimator (never an alarm), an ``EstCfg`` the N-joint online
    estimator (:func:`~adaptive_dd.identification.online.est_step_trial_in`)."""
    raise NotImplementedError("compiled only")


def estimator_model(ec, es, i, pi_out, ew):  # pragma: no cover - replaced by the overload
    """The model control uses ``pi_out (13 n,)`` (left as it is without an estimator)."""
    raise NotImplementedError("compiled only")


@overload(estimator_work)
def _estimator_work(ec, es):
    if isinstance(ec, types.Array):
        return lambda ec, es: np.empty(0)
    return lambda ec, es: est_work(ec.w.shape[0], es.theta.shape[1])


@overload(estimator_step)
def _estimator_step(ec, es, i, q, qd, tau, ew):
    if isinstance(ec, types.Array):
        return lambda ec, es, i, q, qd, tau, ew: 0
    return lambda ec, es, i, q, qd, tau, ew: est_step_trial_in(ec, es, i, q, qd, tau, ew)


@overload(estimator_model)
def _estimator_model(ec, es, i, pi_out, ew):
    if isinstance(ec, types.Array):
        return lambda ec, es, i, pi_out, ew: None
    return lambda ec, es, i, pi_out, ew: est_model_trial_in(ec, es, i, pi_out, ew)


@njit(cache=True, inline="always")
def estimator_trial_sample(ec, es, ls, i, qm_obs, qdm_obs, tau, ew):  # pragma: no cover - compiled
    """The estimator's step on the applied torque, the alarm counter, the model for the next command;
    ``ew`` the estimator's scratch (:func:`estimator_work`)."""
    alarm = estimator_step(ec, es, i, qm_obs, qdm_obs, tau, ew)
    if alarm == 1:
        ls.since_alarm[i] = 0
    else:
        ls.since_alarm[i] += 1
    estimator_model(ec, es, i, ls.pi_model[i], ew)
    return alarm


@njit(cache=True)
def _nonzero_columns(B):  # pragma: no cover - compiled
    """Per row of ``B (p, m)``: its nonzero columns in order, ``cols (p, m)`` and their count ``(p,)``."""
    p, m = B.shape
    cols = np.empty((p, m), dtype=np.int64)
    count = np.zeros(p, dtype=np.int64)
    for r in range(p):
        for c in range(m):
            if B[r, c] != 0.0:
                cols[r, count[r]] = c
                count[r] += 1
    return cols, count


@njit(cache=True)
def _sigma_of(B, cols, count, pi, out):  # pragma: no cover - compiled
    """``out = B pi`` over B's nonzero entries (the same sums in the same order as the dense
    product: a skipped term ``0 * pi_c`` adds exactly zero for a finite ``pi``); a non-finite
    ``pi`` falls back to the dense product so that NaN spreads as it would."""
    finite = True
    for c in range(pi.shape[0]):
        if not np.isfinite(pi[c]):
            finite = False
    for r in range(B.shape[0]):
        acc = 0.0
        if finite:
            for t in range(count[r]):
                c = cols[r, t]
                acc += B[r, c] * pi[c]
        else:
            for c in range(B.shape[1]):
                acc += B[r, c] * pi[c]
        out[r] = acc


@njit(cache=True, nogil=True)
def closed_loop_block(
    i0, i1, k0, k1, ch, rc, io, pl, ts, acc, rec, alarms, noise, drop, cfg, ls, pi_true, B, ec, es, estimates,
):  # pragma: no cover - compiled  # fmt: skip
    """Samples ``k0`` to ``k1 - 1`` of trials ``i0`` to ``i1 - 1``, state updated in place.

    ``noise (S, k1 - k0, 2 n)`` standard normal; ``drop (S, k1 - k0)`` lost measurements
    (or ``(S, 0)``: none); ``cfg, ls`` the law; ``pi_true (S, G, 13 n)`` trial i's true model
    per segment (its plant); ``B (p, 13 n)`` standard -> base parameters; ``ec, es`` the estimator's records
    (arrays: none; see :func:`estimator_step`); ``estimates``: record ``B pi_model``.
    The GIL is released: the runner runs disjoint ranges of trials in threads (numba's
    ``prange`` cannot take the estimator's configuration, a NamedTuple holding a NamedTuple).
    """
    n = ts.q.shape[1]
    cols, count = _nonzero_columns(B)
    for i in range(i0, i1):
        qm, qdm, qm_obs, qdm_obs = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
        cmd, tau = np.empty(n), np.empty(n)
        sig = np.empty(B.shape[0])
        work = sample_work(n)
        lw = law_work(n)
        ew = estimator_work(ec, es)
        for k in range(k0, k1):
            s = segment_of(rc, k)
            lost = drop.shape[1] > 0 and drop[i, k - k0]
            measure_trial_sample(io, ts, i, noise[i, k - k0], lost, qm, qdm, qm_obs, qdm_obs)
            law_trial_in(
                ch, cfg, pi_true[i, s], ls.pi_model[i], ls.theta[i], ls.since_alarm[i],
                qm, qdm, rc.q_d[k], rc.qd_d[k], rc.qdd_d[k], lw, cmd,
            )  # fmt: skip
            apply_trial_sample(ch, rc, io, pl, ts, acc, rec, i, k, s, cmd, tau, work)
            if estimator_trial_sample(ec, es, ls, i, qm_obs, qdm_obs, tau, ew) == 1:
                if alarms.count[i] < alarms.times.shape[1]:
                    alarms.times[i, alarms.count[i]] = k * rc.T
                alarms.count[i] += 1
            if estimates and (k == rc.seg_end[s] - 1 or i < rec.sigma.shape[0]):
                _sigma_of(B, cols, count, ls.pi_model[i], sig)
                record_estimate_trial(rc, rec, i, k, s, sig)


# ----------------------------------------------------------------------- Python path
@njit(cache=True)
def _measure_loop(io, ts, noise, lost, qm, qdm, qm_obs, qdm_obs):  # pragma: no cover - compiled
    for i in range(qm.shape[0]):
        measure_trial_sample(io, ts, i, noise[i], lost[i], qm[i], qdm[i], qm_obs[i], qdm_obs[i])


def measure_batch(io, ts, noise, lost) -> tuple:
    """Step 1 for every trial: ``noise (S, 2 n)``, ``lost (S,)`` -> ``qm, qdm, qm_obs, qdm_obs (S, n)``."""
    S, n = ts.q.shape
    qm, qdm, qm_obs, qdm_obs = (np.empty((S, n)) for _ in range(4))
    _measure_loop(io, ts, np.ascontiguousarray(noise), np.ascontiguousarray(lost), qm, qdm, qm_obs, qdm_obs)
    return qm, qdm, qm_obs, qdm_obs


@njit(cache=True)
def _apply_loop(ch, rc, io, pl, ts, acc, rec, k, cmd, tau):  # pragma: no cover - compiled
    s = segment_of(rc, k)
    work = sample_work(cmd.shape[1])  # one per call: trials run one after the other here
    for i in range(cmd.shape[0]):
        apply_trial_sample(ch, rc, io, pl, ts, acc, rec, i, k, s, cmd[i], tau[i], work)
    return s


def apply_batch(ch, rc, io, pl, ts, acc, rec, k: int, cmd) -> tuple[NDArray[np.float64], int]:
    """Step 3 for every trial; ``cmd (S, n)`` (copied); returns the applied torque ``(S, n)`` and
    the segment of sample k."""
    cmd = np.array(cmd, dtype=float, order="C")
    tau = np.empty_like(cmd)
    s = _apply_loop(ch, rc, io, pl, ts, acc, rec, k, cmd, tau)
    return tau, int(s)


@njit(cache=True)
def _sigma_loop(rc, rec, k, s, sigma):  # pragma: no cover - compiled
    for i in range(sigma.shape[0]):
        record_estimate_trial(rc, rec, i, k, s, sigma[i])


def sigma_batch(rc, rec, k: int, s: int, sigma) -> None:
    """Record every trial's estimate ``sigma (S, p)`` (see :func:`record_estimate_trial`)."""
    _sigma_loop(rc, rec, k, s, np.ascontiguousarray(sigma, dtype=float))


@njit(cache=True)
def _estimator_loop(ec, es, ls, qm_obs, qdm_obs, tau, alarm):  # pragma: no cover - compiled
    ew = estimator_work(ec, es)  # one per call: trials run one after the other here
    for i in range(tau.shape[0]):
        alarm[i] = estimator_trial_sample(ec, es, ls, i, qm_obs[i], qdm_obs[i], tau[i], ew)


def estimator_batch(ec, es, ls, qm_obs, qdm_obs, tau) -> NDArray[np.int64]:
    """:func:`estimator_trial_sample` for every trial ``(S, n)``; returns the alarms ``(S,)`` (1: alarm)."""
    alarm = np.zeros(tau.shape[0], dtype=np.int64)
    c = np.ascontiguousarray
    _estimator_loop(ec, es, ls, c(qm_obs), c(qdm_obs), c(tau), alarm)
    return alarm
