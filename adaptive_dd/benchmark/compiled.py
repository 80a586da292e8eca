"""The compiled closed loop: plant, sensors, estimator and control law of a trial in one numba call.

For the built-in controllers (``pd``, ``ct_nominal``, ``ct_oracle``, ``ct_oracle_textbook``,
``adaptive_ct``, ``adaptive_ct_paper``, ``slotine_li``, ``slotine_li_oracle``)
:func:`closed_loop_block` runs a block of samples of every trial, trials in parallel
across cores (``numba.prange``), calling the same compiled pieces as the Python path:
the actuator and sensor models
(:mod:`adaptive_dd.plant.sampling`), the plant integrator, the control laws
(:mod:`adaptive_dd.controllers.laws`), the online estimator
(:mod:`adaptive_dd.identification.online_kernel`) and the streamed metrics
(:func:`~adaptive_dd.benchmark.streaming.accumulate_trial`). A controller spec says which
law, with which gains and model (each built-in's ``compiled_spec`` method:
:func:`~adaptive_dd.controllers.compiled_form.compiled_spec`); plug-in controllers have none and
run on the Python path.

What travels into the kernel is named: the run constants, actuator and sensor, streamed
sums, recordings and alarms are the N-joint loop's records
(:mod:`adaptive_dd.closed_loop.types`, :class:`~adaptive_dd.closed_loop.glue.Alarms`); the
two-link plant (:class:`TwoLinkPlant`), trial state (:class:`TwoLinkTrialState`) and
estimator configuration (:class:`OnlineKernelConfig`) are
defined here; the law is the controller's
:class:`~adaptive_dd.controllers.compiled_form.TwoLinkGains`; the estimator state is
:class:`~adaptive_dd.identification.online.OnlineState`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from adaptive_dd.benchmark.streaming import accumulate_trial
from adaptive_dd.controllers.compiled_form import (
    LAW_ADAPTIVE,
    LAW_CT,
    LAW_CT_ORACLE,
    LAW_PD,
    LAW_SLOTINE,
    LAW_SLOTINE_ORACLE,
    CompiledSpec,
    TwoLinkGains,
    compiled_spec,
)
from adaptive_dd.controllers.laws import boost_trial, ct_trial, pd_trial, slotine_li_trial
from adaptive_dd.identification.online_kernel import C_SINCE_ALARM, online_step_trial
from adaptive_dd.plant.integrator import step_one
from adaptive_dd.plant.sampling import actuate_trial, measure_trial

__all__ = [
    "LAW_ADAPTIVE",
    "LAW_CT",
    "LAW_CT_ORACLE",
    "LAW_PD",
    "LAW_SLOTINE",
    "LAW_SLOTINE_ORACLE",
    "CompiledSpec",
    "OnlineKernelConfig",
    "TwoLinkGains",
    "TwoLinkPlant",
    "TwoLinkTrialState",
    "apply_batch",
    "apply_sample",
    "closed_loop_block",
    "compiled_spec",
    "estimate_batch",
    "measure_batch",
    "measure_sample",
    "record_estimate",
    "segment_of",
    "trial_block",
]

Array = NDArray[np.float64]


class OnlineKernelConfig(NamedTuple):
    """:attr:`OnlineConfig.packed <adaptive_dd.identification.online.OnlineConfig.packed>` by
    name: ``ci, cf`` integer and float settings, ``A, B, C, D`` the derivative filters'
    state space, ``d`` payload direction, ``group`` parameter groups, ``split_rows (2,)``."""

    ci: NDArray[np.int64]
    cf: Array
    A: Array
    B: Array
    C: Array
    D: Array
    d: Array
    group: NDArray[np.int64]
    split_rows: NDArray[np.int64]


class TwoLinkPlant(NamedTuple):
    """The two-link plant of a run (:func:`adaptive_dd.plant.integrator.step_one`).

    ``sigma_seg (G, 7)`` true base parameters before the first swap and after each;
    ``swap_k (G - 1,)`` sample of each swap; ``substeps`` RK4 substeps per sample;
    ``friction_code`` (:attr:`Arm.friction_code <adaptive_dd.plant.arm.Arm.friction_code>`);
    ``fparams`` :func:`~adaptive_dd.plant.integrator.friction_vector` of the arm (friction
    velocity, Stribeck ratio and velocity, LuGre sigma0 (2), sigma1 (2)).
    """

    sigma_seg: Array
    swap_k: NDArray[np.int64]
    substeps: int
    friction_code: int
    fparams: Array


class TwoLinkTrialState(NamedTuple):
    """Per-trial state of the two-link loop, trial axis first: ``q, qd (S, 2)``, ``stuck (S, 2)``
    joints held by Coulomb friction, ``slip (S, 2)`` stick-slip state, ``z (S, 2)`` LuGre bristle
    state, ``failed (S,)``, ``failed_at (S,)`` sample of the failure (-1), ``held_q, held_qd (S, 2)``
    the last good measurement, ``n_dropped (S,)`` measurements lost."""

    q: Array
    qd: Array
    stuck: NDArray[np.bool_]
    slip: Array
    z: Array
    failed: NDArray[np.bool_]
    failed_at: NDArray[np.int64]
    held_q: Array
    held_qd: Array
    n_dropped: NDArray[np.int64]


@njit(cache=True, inline="always")
def _command(g, T, sg_true, sg_model, since_alarm, q, qd, q_d, qd_d, qdd_d, out):  # pragma: no cover
    """The command of law ``g.law`` into ``out (2,)``; ``sg_model`` the trial's estimate."""
    law = g.law
    if law == LAW_SLOTINE:
        slotine_li_trial(
            q, qd, q_d, qd_d, qdd_d, sg_model, g.sigma, g.lam, g.kd, T, g.gamma, g.lo, g.hi, g.projection, out
        )  # fmt: skip
    elif law == LAW_SLOTINE_ORACLE:
        th = sg_true.copy()
        slotine_li_trial(
            q, qd, q_d, qd_d, qdd_d, th, g.sigma, g.lam, g.kd, T, g.gamma[0:0], g.lo, g.hi, g.projection, out
        )  # fmt: skip
    elif law == LAW_PD:
        pd_trial(q, qd, q_d, qd_d, g.pd_kp, g.pd_kd, out)
    elif law == LAW_CT:
        ct_trial(q, qd, q_d, qd_d, qdd_d, g.sigma, g.kp, g.kd, g.lam, out)
    elif law == LAW_CT_ORACLE:
        ct_trial(q, qd, q_d, qd_d, qdd_d, sg_true, g.kp, g.kd, g.lam, out)
    else:
        ct_trial(q, qd, q_d, qd_d, qdd_d, sg_model, g.kp, g.kd, g.lam, out)
        if g.boost_samples > 0 and since_alarm < g.boost_samples:
            boost_trial(q, qd, q_d, qd_d, g.sigma, g.boost_kp, g.boost_kd, out)


@njit(cache=True, parallel=True)
def closed_loop_block(k0, k1, noise, drop, rc, io, pl, g, ts, es, ec, acc, rec, alarms):  # pragma: no cover
    """Samples ``k0 .. k1 - 1`` of every trial (prange over trials); state updated in place.

    Parameters
    ----------
    k0, k1 : int
        The block of samples.
    noise : ndarray (S, k1 - k0, 4)
        Standard normal sensor noise (q1, q2, qd1, qd2).
    drop : ndarray of bool (S, k1 - k0) or (S, 0)
        Lost measurements (none: ``(S, 0)``).
    rc : RunConstants
        Sample period, divergence limits, reference ``q_d, qd_d, qdd_d (N, 2)``, segments.
    io : Io
        Actuator and sensor.
    pl : TwoLinkPlant
    g : TwoLinkGains
        The law.
    ts : TwoLinkTrialState
    es : OnlineState
        The estimator's state (``adaptive_ct``; its ``theta`` is also Slotine-Li's estimate).
    ec : OnlineKernelConfig
        The estimator's configuration.
    acc : StreamedSums
        Per trial and segment (:func:`~adaptive_dd.benchmark.streaming.accumulate_trial`).
    rec : Recording
        Trajectories of the first ``rec.q.shape[0]`` trials, the estimate at each segment's end.
    alarms : Alarms
        Change-detector alarm times [s] (the count stops at the capacity).
    """
    for i in prange(ts.q.shape[0]):
        trial_block(i, k0, k1, noise, drop, rc, io, pl, g, ts, es, ec, acc, rec, alarms)


@njit(cache=True, inline="always")
def segment_of(pl, k):  # pragma: no cover - compiled
    """Payload segment of sample ``k``: the swaps at or before it (indexes ``pl.sigma_seg``)."""
    w = 0
    while w < pl.swap_k.shape[0] and k >= pl.swap_k[w]:
        w += 1
    return w


@njit(cache=True, inline="always")
def measure_sample(io, ts, i, noise, lost, qm, qdm):  # pragma: no cover - compiled
    """Trial i's measured ``qm, qdm (2,)`` from ``noise (4,)`` standard normal; a ``lost``
    measurement is replaced by the last good one (``ts.held_q, ts.held_qd``) and counted.
    The estimator gets NaN for a lost one (the caller's choice)."""
    measure_trial(ts.q[i], ts.qd[i], noise, io.res, io.std, io.quantize_encoder, qm, qdm)
    if lost:  # the law gets the last good measurement, the estimator the NaN
        ts.n_dropped[i] += 1
        qm[0], qm[1] = ts.held_q[i, 0], ts.held_q[i, 1]
        qdm[0], qdm[1] = ts.held_qd[i, 0], ts.held_qd[i, 1]
    else:
        ts.held_q[i, 0], ts.held_q[i, 1] = qm[0], qm[1]
        ts.held_qd[i, 0], ts.held_qd[i, 1] = qdm[0], qdm[1]


@njit(cache=True, inline="always")
def apply_sample(rc, io, pl, ts, acc, rec, i, k, cmd, tau):  # pragma: no cover - compiled
    """Apply trial i's command ``cmd (2,)`` [N m] over sample k; returns its segment.

    The divergence rule (a non-finite command or a tracking error beyond ``rc.max_error``
    zeroes the command and fails the trial), saturation and D/A into ``tau (2,)`` (zero once
    failed), the plant step, the runaway rule (non-finite q or ``|qd| >= rc.max_speed``), the
    failure freeze (the last good q, at rest, stuck), the streamed sums and the recording of
    the first ``rec.q.shape[0]`` trials (q and qd before the step, the applied torque and its
    saturation). ``cmd`` is zeroed in place when the rule applies.
    """
    e1, e2 = rc.q_d[k, 0] - ts.q[i, 0], rc.q_d[k, 1] - ts.q[i, 1]
    bad = not (np.isfinite(cmd[0]) and np.isfinite(cmd[1]))
    if max(abs(e1), abs(e2)) > rc.max_error:
        bad = True
    if bad:
        cmd[0], cmd[1] = 0.0, 0.0
    mask = actuate_trial(cmd, io.lim, io.lsb, io.saturate, io.quantize_dac, tau)
    if ts.failed[i]:
        tau[0], tau[1] = 0.0, 0.0
    p1, p2 = ts.q[i, 0], ts.q[i, 1]
    keep = i < rec.q.shape[0]
    if keep:
        rec.qd[i, k, 0], rec.qd[i, k, 1] = ts.qd[i, 0], ts.qd[i, 1]
    step_one(
        ts.q, ts.qd, ts.stuck, ts.slip, ts.z, i, tau, pl.sigma_seg[segment_of(pl, k)], rc.T, pl.substeps,
        pl.friction_code, pl.fparams,
    )  # fmt: skip
    ok = np.isfinite(ts.q[i, 0]) and np.isfinite(ts.q[i, 1])
    ok = ok and abs(ts.qd[i, 0]) < rc.max_speed and abs(ts.qd[i, 1]) < rc.max_speed
    if bad or not ok or ts.failed[i]:
        if not ts.failed[i]:
            ts.failed_at[i] = k
        ts.failed[i] = True
        ts.q[i, 0] = p1 if np.isfinite(p1) else 0.0
        ts.q[i, 1] = p2 if np.isfinite(p2) else 0.0
        ts.qd[i, 0], ts.qd[i, 1] = 0.0, 0.0
        ts.stuck[i, 0], ts.stuck[i, 1] = True, True
    s = accumulate_trial(acc, i, k, rc.seg_start, rc.seg_settled, e1, e2, tau, mask)
    if keep:
        rec.q[i, k, 0], rec.q[i, k, 1] = rc.q_d[k, 0] - e1, rc.q_d[k, 1] - e2
        rec.tau[i, k, 0], rec.tau[i, k, 1] = tau[0], tau[1]
        rec.saturated[i, k, 0], rec.saturated[i, k, 1] = (mask & 1) != 0, (mask & 2) != 0
    return s


@njit(cache=True, inline="always")
def record_estimate(rc, rec, i, k, s, theta):  # pragma: no cover - compiled
    """Trial i's estimate ``theta (7,)`` after sample k (segment s): at the segment's last sample
    into ``rec.sigma_end``, and into ``rec.sigma`` for the first ``rec.sigma.shape[0]`` trials."""
    if k == rc.seg_end[s] - 1:
        rec.sigma_end[i, s] = theta
    if i < rec.sigma.shape[0]:
        for j in range(7):
            rec.sigma[i, k, j] = theta[j]


@njit(cache=True)
def trial_block(i, k0, k1, noise, drop, rc, io, pl, g, ts, es, ec, acc, rec, alarms):  # pragma: no cover
    """Samples ``k0 .. k1 - 1`` of trial i (see :func:`closed_loop_block`).

    A function of its own because numba 0.68's parallel loop loses the writes its own body makes
    to arrays reached through a NamedTuple (``a.count[i] += 1`` in a ``prange`` body leaves
    ``a.count`` unchanged); writes made in a function it calls are kept. The per-sample pieces
    are inlined into it (``inline="always"``): a call passing the records' arrays costs a
    reference-count update per array.
    """
    law = g.law
    adaptive = law == LAW_ADAPTIVE
    estimates = adaptive or law == LAW_SLOTINE
    qm = np.empty(2)
    qdm = np.empty(2)
    cmd = np.empty(2)
    tau = np.empty(2)
    eps = np.empty(2)
    lost_q = np.full(2, np.nan)
    has_drop = drop.shape[1] > 0
    for k in range(k0, k1):
        lost = has_drop and drop[i, k - k0]
        measure_sample(io, ts, i, noise[i, k - k0], lost, qm, qdm)
        model = es.theta[i] if law == LAW_SLOTINE else es.sigma_model[i]
        _command(
            g, rc.T, pl.sigma_seg[segment_of(pl, k)], model, es.cnt[i, C_SINCE_ALARM], qm, qdm, rc.q_d[k],
            rc.qd_d[k], rc.qdd_d[k], cmd,
        )  # fmt: skip
        s = apply_sample(rc, io, pl, ts, acc, rec, i, k, cmd, tau)
        if adaptive:
            alarm = online_step_trial(
                i, es.xf, es.u_last, es.cnt, es.tau_prev, es.theta, es.P, es.lam, es.short, es.long,
                es.sigma_model, lost_q if lost else qm, lost_q if lost else qdm, tau,
                ec.ci, ec.cf, ec.A, ec.B, ec.C, ec.D, ec.d, ec.group, ec.split_rows, eps,
            )  # fmt: skip
            if alarm == 1 and alarms.count[i] < alarms.times.shape[1]:
                alarms.times[i, alarms.count[i]] = k * rc.T
                alarms.count[i] += 1
        if estimates:
            record_estimate(rc, rec, i, k, s, es.theta[i])


@njit(cache=True)
def measure_batch(io, ts, noise, drop, qm, qdm, qm_obs, qdm_obs):  # pragma: no cover - compiled
    """:func:`measure_sample` for every trial (the Python path): ``noise (S, 4)``, ``drop (S,)``
    or ``(0,)``; the law's ``qm, qdm (S, 2)``, the estimator's ``qm_obs, qdm_obs`` (NaN if lost)."""
    for i in range(ts.q.shape[0]):
        lost = drop.shape[0] > 0 and drop[i]
        measure_sample(io, ts, i, noise[i], lost, qm[i], qdm[i])
        for j in range(2):
            qm_obs[i, j] = np.nan if lost else qm[i, j]
            qdm_obs[i, j] = np.nan if lost else qdm[i, j]


@njit(cache=True)
def apply_batch(rc, io, pl, ts, acc, rec, k, cmd, tau):  # pragma: no cover - compiled
    """:func:`apply_sample` for every trial (the Python path): ``cmd (S, 2)`` the Python
    controller's command (zeroed where the rule applies), ``tau (S, 2)`` the applied torque;
    returns the segment of sample k."""
    s = 0
    for i in range(ts.q.shape[0]):
        s = apply_sample(rc, io, pl, ts, acc, rec, i, k, cmd[i], tau[i])
    return s


@njit(cache=True)
def estimate_batch(rc, rec, k, s, theta):  # pragma: no cover - compiled
    """:func:`record_estimate` for every trial (the Python path): ``theta (S, 7)``."""
    for i in range(theta.shape[0]):
        record_estimate(rc, rec, i, k, s, theta[i])
