"""The compiled closed loop: plant, sensors, estimator and control law of a trial in one numba call.

For the built-in controllers (``pd``, ``ct_nominal``, ``ct_oracle``, ``ct_oracle_textbook``,
``adaptive_ct``, ``adaptive_ct_paper``, ``slotine_li``, ``slotine_li_oracle``)
:func:`closed_loop_block` runs a block of samples of every trial, trials in parallel
across cores (``numba.prange``), calling the same compiled pieces as the Python path:
the actuator and sensor models
(:mod:`adaptive_dd.plant.sampling`), the plant integrator, the control laws
(:mod:`adaptive_dd.controllers.laws`), the online estimator
(:mod:`adaptive_dd.identification.two_link_online_kernel`) and the streamed metrics
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
:class:`~adaptive_dd.identification.two_link_online.OnlineState`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from adaptive_dd.benchmark.streaming import accumulate_trial
from adaptive_dd.controllers.compiled_form import LAW_ADAPTIVE, LAW_SLOTINE, command_trial
from adaptive_dd.identification.two_link_online_kernel import C_SINCE_ALARM, online_step_trial
from adaptive_dd.plant.sampling import actuate_trial, measure_trial
from adaptive_dd.plant.two_link_integrator import step_one

__all__ = [
    "OnlineKernelConfig",
    "TwoLinkPlant",
    "TwoLinkTrialState",
    "apply_batch",
    "apply_sample",
    "closed_loop_block",
    "estimate_batch",
    "measure_batch",
    "measure_sample",
    "record_estimate",
    "segment_of",
    "trial_block",
]

Array = NDArray[np.float64]


class OnlineKernelConfig(NamedTuple):
    """:attr:`TwoLinkOnlineConfig.packed
    <adaptive_dd.identification.two_link_online.TwoLinkOnlineConfig.packed>` by name: ``ci, cf``
    integer and float settings, ``A, B, C, D`` the derivative filters' state space,
    ``d`` payload direction, ``group`` parameter groups, ``split_rows (2,)``."""

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
    """The two-link plant of a run (:func:`adaptive_dd.plant.two_link_integrator.step_one`).

    ``sigma_seg (G, 7)`` true base parameters before the first swap and after each;
    ``swap_k (G - 1,)`` sample of each swap; ``substeps`` RK4 substeps per sample;
    ``friction_code`` (:attr:`TwoLinkArm.friction_code
    <adaptive_dd.plant.two_link.TwoLinkArm.friction_code>`);
    ``fparams`` :func:`~adaptive_dd.plant.two_link_integrator.friction_vector` of the arm (friction
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


COPY_PROPAGATE_ONLY = {
    k: False
    for k in (
        "comprehension",
        "prange",
        "setitem",
        "reduction",
        "numpy",
        "stencil",
        "fusion",
        "inplace_binop",
    )
}
"""numba's ``parallel`` options with every conversion off: what is left is the parallel pipeline's
copy propagation, which removes the argument copies (``param = caller_var``) that inlining
leaves in the sample loop; each copy of an array is a reference-count update that numba does not
prune (pd: 0.55 -> 0.43 us per trial-sample, benchmarks/two_link_speed_ab.py). Nothing
runs in parallel: the function has no ``prange`` and no array expression is converted."""


@njit(cache=True, parallel=True)
def closed_loop_block(k0, k1, noise, drop, rc, io, pl, g, ts, es, ec, acc, rec, alarms):  # pragma: no cover
    """Samples ``k0`` to ``k1 - 1`` of every trial (prange over trials); state updated in place.

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
        # np.int64: the parallel loop's index is uint64 once lowered and int64 when typed; the
        # same type in both compiles trial_block (the sample loop) once, not twice
        trial_block(np.int64(i), k0, k1, noise, drop, rc, io, pl, g, ts, es, ec, acc, rec, alarms)


@njit(cache=True, inline="always")
def segment_of(pl, k):  # pragma: no cover - compiled
    """Payload segment of sample ``k``: the swaps at or before it (indexes ``pl.sigma_seg``)."""
    return _segment(pl.swap_k, k)


@njit(cache=True, inline="always")
def _segment(swap_k, k):  # pragma: no cover - compiled
    """:func:`segment_of` on the plant's ``swap_k``."""
    w = 0
    while w < swap_k.shape[0] and k >= swap_k[w]:
        w += 1
    return w


# The per-sample glue takes plain arrays, unpacked from the records once per trial block (or
# per sample on the Python path): each read of an array out of a NamedTuple inside the sample
# loop costs a reference-count update that numba does not prune (pd: 0.64 -> 0.55 us per
# trial-sample, benchmarks/two_link_speed_ab.py).


@njit(cache=True, inline="always")
def measure_sample(
    q, qd, held_q, held_qd, n_dropped, res, std, quantize, i, noise, lost, qm, qdm
):  # pragma: no cover
    """Trial i's measured ``qm, qdm (2,)`` from ``noise (4,)`` standard normal (``res, std,
    quantize`` of :class:`~adaptive_dd.closed_loop.types.Io`); a ``lost`` measurement is replaced
    by the last good one (``held_q, held_qd (S, 2)``) and counted in ``n_dropped (S,)``. The
    estimator gets NaN for a lost one (the caller's choice)."""
    measure_trial(q[i], qd[i], noise, res, std, quantize, qm, qdm)
    if lost:  # the law gets the last good measurement, the estimator the NaN
        n_dropped[i] += 1
        qm[0], qm[1] = held_q[i, 0], held_q[i, 1]
        qdm[0], qdm[1] = held_qd[i, 0], held_qd[i, 1]
    else:
        held_q[i, 0], held_q[i, 1] = qm[0], qm[1]
        held_qd[i, 0], held_qd[i, 1] = qdm[0], qdm[1]


@njit(cache=True, inline="always")
def apply_sample(
    T, max_error, max_speed, q_d, seg_start, seg_settled, lim, lsb, saturate, quantize_dac,
    sg_true, substeps, friction_code, fparams, q, qd, stuck, slip, z, failed, failed_at,
    acc, q_rec, qd_rec, tau_rec, sat_rec, i, k, cmd, tau,
):  # pragma: no cover - compiled  # fmt: skip
    """Apply trial i's command ``cmd (2,)`` [N m] over sample k; returns its segment.

    The arguments are the fields of :class:`~adaptive_dd.closed_loop.types.RunConstants`,
    :class:`~adaptive_dd.closed_loop.types.Io`, :class:`TwoLinkPlant` and :class:`TwoLinkTrialState`
    of the same names, ``sg_true (7,)`` the true base parameters over sample k, the streamed sums
    ``acc`` and the recording's ``q, qd, tau, saturated`` (``q_rec, qd_rec, tau_rec, sat_rec``).
    The divergence rule (a non-finite command or a tracking error beyond ``max_error``
    zeroes the command and fails the trial), saturation and D/A into ``tau (2,)`` (zero once
    failed), the plant step, the runaway rule (non-finite q or ``|qd| >= max_speed``), the
    failure freeze (the last good q, at rest, stuck), the streamed sums and the recording of
    the first ``q_rec.shape[0]`` trials (q and qd before the step, the applied torque and its
    saturation). ``cmd`` is zeroed in place when the rule applies.
    """
    e1, e2 = q_d[k, 0] - q[i, 0], q_d[k, 1] - q[i, 1]
    bad = not (np.isfinite(cmd[0]) and np.isfinite(cmd[1]))
    if max(abs(e1), abs(e2)) > max_error:
        bad = True
    if bad:
        cmd[0], cmd[1] = 0.0, 0.0
    mask = actuate_trial(cmd, lim, lsb, saturate, quantize_dac, tau)
    if failed[i]:
        tau[0], tau[1] = 0.0, 0.0
    p1, p2 = q[i, 0], q[i, 1]
    keep = i < q_rec.shape[0]
    if keep:
        qd_rec[i, k, 0], qd_rec[i, k, 1] = qd[i, 0], qd[i, 1]
    step_one(q, qd, stuck, slip, z, i, tau, sg_true, T, substeps, friction_code, fparams)
    ok = np.isfinite(q[i, 0]) and np.isfinite(q[i, 1])
    ok = ok and abs(qd[i, 0]) < max_speed and abs(qd[i, 1]) < max_speed
    if bad or not ok or failed[i]:
        if not failed[i]:
            failed_at[i] = k
        failed[i] = True
        q[i, 0] = p1 if np.isfinite(p1) else 0.0
        q[i, 1] = p2 if np.isfinite(p2) else 0.0
        qd[i, 0], qd[i, 1] = 0.0, 0.0
        stuck[i, 0], stuck[i, 1] = True, True
    s = accumulate_trial(acc, i, k, seg_start, seg_settled, e1, e2, tau, mask)
    if keep:
        q_rec[i, k, 0], q_rec[i, k, 1] = q_d[k, 0] - e1, q_d[k, 1] - e2
        tau_rec[i, k, 0], tau_rec[i, k, 1] = tau[0], tau[1]
        sat_rec[i, k, 0], sat_rec[i, k, 1] = (mask & 1) != 0, (mask & 2) != 0
    return s


@njit(cache=True, inline="always")
def record_estimate(seg_end, sigma_end, sigma_rec, i, k, s, theta):  # pragma: no cover - compiled
    """Trial i's estimate ``theta (7,)`` after sample k (segment s): at the segment's last sample
    (``seg_end``) into ``sigma_end (S, G, 7)``, and into ``sigma_rec`` (the recording's ``sigma``)
    for its first ``sigma_rec.shape[0]`` trials."""
    if k == seg_end[s] - 1:
        for j in range(7):  # a loop, not sigma_end[i, s] = theta: numba would compile the
            sigma_end[i, s, j] = theta[j]  # slice assignment's shape-error message (string code)
    if i < sigma_rec.shape[0]:
        for j in range(7):
            sigma_rec[i, k, j] = theta[j]


@njit(cache=True, parallel=COPY_PROPAGATE_ONLY)
def trial_block(i, k0, k1, noise, drop, rc, io, pl, g, ts, es, ec, acc, rec, alarms):  # pragma: no cover
    """Samples ``k0`` to ``k1 - 1`` of trial i (see :func:`closed_loop_block`).

    A function of its own because numba 0.68's parallel loop loses the writes its own body makes
    to arrays reached through a NamedTuple (``a.count[i] += 1`` in a ``prange`` body leaves
    ``a.count`` unchanged); writes made in a function it calls are kept. The records' fields are
    read out once, before the sample loop, and the per-sample pieces, inlined into it
    (``inline="always"``), take them as plain arrays; compiled with :data:`COPY_PROPAGATE_ONLY`
    so that the inlined calls' argument copies cost no reference-count update per sample.
    """
    law = g.law
    adaptive = law == LAW_ADAPTIVE
    estimates = adaptive or law == LAW_SLOTINE
    T, max_error, max_speed, q_d, qd_d, qdd_d = rc.T, rc.max_error, rc.max_speed, rc.q_d, rc.qd_d, rc.qdd_d
    seg_start, seg_end, seg_settled = rc.seg_start, rc.seg_end, rc.seg_settled
    lim, lsb, saturate, quantize_dac = io.lim, io.lsb, io.saturate, io.quantize_dac
    res, std, quantize_encoder = io.res, io.std, io.quantize_encoder
    sigma_seg, swap_k, substeps, friction_code, fparams = (
        pl.sigma_seg,
        pl.swap_k,
        pl.substeps,
        pl.friction_code,
        pl.fparams,
    )
    q, qd, stuck, slip, z, failed, failed_at = ts.q, ts.qd, ts.stuck, ts.slip, ts.z, ts.failed, ts.failed_at
    held_q, held_qd, n_dropped = ts.held_q, ts.held_qd, ts.n_dropped
    q_rec, qd_rec, tau_rec, sat_rec, sigma_rec, sigma_end = (
        rec.q,
        rec.qd,
        rec.tau,
        rec.saturated,
        rec.sigma,
        rec.sigma_end,
    )
    xf, u_last, cnt, tau_prev, theta, P, lam, short, long, sigma_model = es
    ci, cf, A, B, C, D, d, group, split_rows = ec
    alarm_t, n_alarms = alarms.times, alarms.count
    qm = np.empty(2)
    qdm = np.empty(2)
    cmd = np.empty(2)
    tau = np.empty(2)
    eps = np.empty(2)
    lost_q = np.full(2, np.nan)
    has_drop = drop.shape[1] > 0
    for k in range(k0, k1):
        lost = has_drop and drop[i, k - k0]
        measure_sample(
            q, qd, held_q, held_qd, n_dropped, res, std, quantize_encoder, i, noise[i, k - k0], lost, qm, qdm
        )
        model = theta[i] if law == LAW_SLOTINE else sigma_model[i]
        sg_true = sigma_seg[_segment(swap_k, k)]
        command_trial(g, T, sg_true, model, cnt[i, C_SINCE_ALARM], qm, qdm, q_d[k], qd_d[k], qdd_d[k], cmd)
        s = apply_sample(
            T, max_error, max_speed, q_d, seg_start, seg_settled, lim, lsb, saturate, quantize_dac,
            sg_true, substeps, friction_code, fparams, q, qd, stuck, slip, z, failed, failed_at,
            acc, q_rec, qd_rec, tau_rec, sat_rec, i, k, cmd, tau,
        )  # fmt: skip
        if adaptive:
            alarm = online_step_trial(
                i, xf, u_last, cnt, tau_prev, theta, P, lam, short, long,
                sigma_model, lost_q if lost else qm, lost_q if lost else qdm, tau,
                ci, cf, A, B, C, D, d, group, split_rows, eps,
            )  # fmt: skip
            if alarm == 1 and n_alarms[i] < alarm_t.shape[1]:
                alarm_t[i, n_alarms[i]] = k * T
                n_alarms[i] += 1
        if estimates:
            record_estimate(seg_end, sigma_end, sigma_rec, i, k, s, theta[i])


@njit(cache=True)
def _measure_loop(io, ts, noise, lost, qm, qdm, qm_obs, qdm_obs):  # pragma: no cover - compiled
    for i in range(ts.q.shape[0]):
        measure_sample(
            ts.q, ts.qd, ts.held_q, ts.held_qd, ts.n_dropped, io.res, io.std, io.quantize_encoder, i,
            noise[i], lost[i], qm[i], qdm[i],
        )  # fmt: skip
        for j in range(2):
            qm_obs[i, j] = np.nan if lost[i] else qm[i, j]
            qdm_obs[i, j] = np.nan if lost[i] else qdm[i, j]


def measure_batch(io, ts, noise, lost) -> tuple[Array, Array, Array, Array]:
    """:func:`measure_sample` for every trial (the Python path): ``noise (S, 4)``, ``lost (S,)``
    -> the law's ``qm, qdm (S, 2)`` and the estimator's ``qm_obs, qdm_obs`` (NaN if lost)."""
    S = ts.q.shape[0]
    qm, qdm, qm_obs, qdm_obs = (np.empty((S, 2)) for _ in range(4))
    _measure_loop(io, ts, np.ascontiguousarray(noise), np.ascontiguousarray(lost), qm, qdm, qm_obs, qdm_obs)
    return qm, qdm, qm_obs, qdm_obs


@njit(cache=True)
def _apply_loop(rc, io, pl, ts, acc, rec, k, cmd, tau):  # pragma: no cover - compiled
    s = 0
    sg_true = pl.sigma_seg[segment_of(pl, k)]
    for i in range(ts.q.shape[0]):
        s = apply_sample(
            rc.T, rc.max_error, rc.max_speed, rc.q_d, rc.seg_start, rc.seg_settled, io.lim, io.lsb,
            io.saturate, io.quantize_dac, sg_true, pl.substeps, pl.friction_code, pl.fparams, ts.q, ts.qd,
            ts.stuck, ts.slip, ts.z, ts.failed, ts.failed_at, acc, rec.q, rec.qd, rec.tau, rec.saturated,
            i, k, cmd[i], tau[i],
        )  # fmt: skip
    return s


def apply_batch(rc, io, pl, ts, acc, rec, k: int, cmd) -> tuple[Array, int]:
    """:func:`apply_sample` for every trial (the Python path): ``cmd (S, 2)`` the Python
    controller's command (copied); returns the applied torque ``(S, 2)`` and the segment of sample k."""
    cmd = np.array(cmd, dtype=float, order="C")
    tau = np.empty_like(cmd)
    s = _apply_loop(rc, io, pl, ts, acc, rec, k, cmd, tau)
    return tau, int(s)


@njit(cache=True)
def estimate_batch(rc, rec, k, s, theta):  # pragma: no cover - compiled
    """:func:`record_estimate` for every trial (the Python path): ``theta (S, 7)``."""
    for i in range(theta.shape[0]):
        record_estimate(rc.seg_end, rec.sigma_end, rec.sigma, i, k, s, theta[i])
