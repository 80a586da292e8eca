"""The per-sample glue of the closed loop, written once for every arm.

One sample of one trial is:

1. :func:`measure_sample`: encoder and noise (drawn in blocks by the runner), a lost
   measurement replaced by the last good one for the law and by NaN for the estimator;
2. the command: the compiled law (:func:`law_command`) or a Python controller's ``command``
   for the whole batch; an oracle is given the true model of the sample's payload segment, or of
   the segment :func:`law_delay` samples back (``ct_oracle_late``, told of each swap late);
3. :func:`apply_sample` and :func:`accumulate_sample`: the divergence rule (a non-finite
   command or an error beyond ``max_error`` zeroes the command and fails the trial),
   saturation and D/A, the plant step (:func:`plant_advance`), the runaway rule (non-finite
   state or ``|qd| >= max_speed``), the failure freeze (a failed trial stays at its last
   finite position, at rest, with zero torque), the recorded trajectories and the streamed
   metrics (the tool frame's error among them: :func:`~adaptive_dd.closed_loop.tool_frame.accumulate_tool`);
4. the estimator: compiled (:func:`estimator_sample`) or the controller's ``observe``, its
   alarms counted; then :func:`record_estimate` keeps the estimate (:func:`law_estimate`) at
   each segment's end and for the recorded trials.

The plant, the law and the estimator are compile-time choices: :func:`plant_advance`,
:func:`law_command`, :func:`law_estimate` and :func:`estimator_sample` are chosen by the
type of their record (:mod:`adaptive_dd.closed_loop.choices`). The choices of an N-joint arm
(:class:`~adaptive_dd.closed_loop.types.Plant`, :class:`ChainLaw`, no estimator or
:class:`~adaptive_dd.identification.online_kernel.EstCfg`) are in
:mod:`adaptive_dd.closed_loop.chain_choices`; :mod:`adaptive_dd.benchmark.compiled` adds the
paper's two-link arm (its closed-form plant, its laws and its estimator). The public names of
``choices`` and ``chain_choices`` are importable from here. The compiled path runs all four inside
:func:`closed_loop_block` (a range of trials, the GIL released so that threads run ranges
in parallel: :func:`in_threads`); the Python path calls the batch wrappers
(:mod:`adaptive_dd.closed_loop.batches`) around the Python controller, so both paths do the same
arithmetic in the same order.
"""

from __future__ import annotations

import itertools
import warnings
from types import FunctionType
from typing import NamedTuple

import numpy as np
from numba import njit, prange
from numba.core.errors import NumbaPerformanceWarning
from numpy.typing import NDArray

from adaptive_dd.closed_loop.borrow import borrowed, keep_alive
from adaptive_dd.closed_loop.chain_choices import (
    ChainEstimator,
    ChainLaw,
    _chain_estimator_sample,
    _chain_estimator_work,
    _chain_law_command,
    _chain_law_delay,
    _chain_law_estimate,
    _chain_law_work,
    _chain_plant_advance,
    _chain_plant_joints,
    _chain_plant_work,
    chain_estimator,
    chain_law,
    compile_estimator,
    online_sample,
)
from adaptive_dd.closed_loop.choices import (
    estimator_sample,
    estimator_work,
    law_command,
    law_delay,
    law_estimate,
    law_work_of,
    plant_advance,
    plant_joints,
    plant_work,
)
from adaptive_dd.closed_loop.tool_frame import accumulate_tool
from adaptive_dd.errors import RunWarning
from adaptive_dd.plant.sampling import actuate_trial, measure_trial

__all__ = [
    "COPY_PROPAGATE_ONLY",
    "Alarms",
    "ChainEstimator",
    "ChainLaw",
    "accumulate_sample",
    "alarm_lists",
    "apply_sample",
    "chain_estimator",
    "chain_law",
    "chain_loop_block",
    "closed_loop_block",
    "compile_estimator",
    "estimator_sample",
    "estimator_work",
    "in_threads",
    "law_command",
    "law_delay",
    "law_estimate",
    "law_work_of",
    "measure_sample",
    "online_sample",
    "plant_advance",
    "plant_joints",
    "plant_work",
    "record_estimate",
    "segment_of",
    "trial_samples",
]

Array = NDArray[np.float64]


class Alarms(NamedTuple):
    """Change-detector alarms: ``times (S, capacity)`` [s], ``count (S,)`` (may exceed capacity)."""

    times: NDArray[np.float64]
    count: NDArray[np.int64]


def alarm_lists(alarms: Alarms) -> list[list[float]]:
    """Per trial, the alarm times [s] that were kept (at most the capacity); a trial that raised more
    is warned of (its false alarms, missed swaps and delays are counted on the first ones only)."""
    cap = alarms.times.shape[1]
    over = np.flatnonzero(np.asarray(alarms.count) > cap)
    if over.size:
        warnings.warn(
            f"trial(s) {over[:8].tolist()} raised up to {int(np.max(alarms.count))} change alarms; the "
            f"first {cap} of each are kept, so their false alarms, missed swaps and detection delays "
            "count those only (a detector that alarms this often is not detecting changes)",
            RunWarning,
            stacklevel=2,
        )
    return [AlarmTimes(alarms.times[i, : min(c, cap)], c > cap) for i, c in enumerate(alarms.count)]


class AlarmTimes(list):
    """One trial's kept alarm times [s], a list; ``truncated``: the trial raised more than were kept
    (the compiled path keeps the first ``MAX_ALARMS``), so a swap after the last kept one is not known
    to have been detected or missed."""

    def __init__(self, times=(), truncated: bool = False) -> None:
        super().__init__(float(t) for t in times)
        self.truncated = bool(truncated)


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
prune (two-link pd: 0.55 -> 0.43 us per trial-sample, benchmarks/two_link_speed_ab.py). Nothing
runs in parallel: :func:`trial_samples` has no ``prange`` and no array expression is converted."""


@njit(cache=True, inline="always")
def segment_of(rc, k):  # pragma: no cover - compiled
    """Payload segment of sample ``k`` (:class:`~adaptive_dd.closed_loop.types.RunConstants`)."""
    return _segment(rc.seg_start, k)


@njit(cache=True, inline="always")
def _segment(seg_start, k):  # pragma: no cover - compiled
    s = 0
    while s + 1 < seg_start.shape[0] and k >= seg_start[s + 1]:
        s += 1
    return s


# ------------------------------------------------------------------ the per-sample algorithm
# The per-sample pieces take plain arrays, read out of the records once per trial block (or per
# sample on the Python path): each read of an array out of a NamedTuple inside the sample loop
# costs a reference-count update that numba does not prune (two-link pd: 0.64 -> 0.55 us per
# trial-sample, benchmarks/two_link_speed_ab.py).


@njit(cache=True, inline="always")
def measure_sample(
    q, qd, held_q, held_qd, n_dropped, res, std, quantize, i, noise, lost, qm, qdm, qm_obs, qdm_obs
):  # pragma: no cover - compiled
    """Trial i's measured ``qm, qdm (n,)`` for the law and ``qm_obs, qdm_obs`` for the estimator
    from ``noise (2 n,)`` standard normal (``res, std, quantize`` of
    :class:`~adaptive_dd.closed_loop.types.Io`); a ``lost`` measurement is the last good one
    (``held_q, held_qd (S, n)``) for the law, NaN for the estimator, and counted in ``n_dropped``."""
    measure_trial(q[i], qd[i], noise, res, std, quantize, qm, qdm)
    if lost:
        n_dropped[i] += 1
        for j in range(qm.shape[0]):
            qm_obs[j], qdm_obs[j] = np.nan, np.nan
            qm[j], qdm[j] = held_q[i, j], held_qd[i, j]
    else:
        for j in range(qm.shape[0]):
            qm_obs[j], qdm_obs[j] = qm[j], qdm[j]
            held_q[i, j], held_qd[i, j] = qm[j], qdm[j]


@njit(cache=True, inline="always")
def accumulate_sample(
    sum_e2, sum_e2_joint, max_e, sum_tau2, n_saturated, first_saturated, sum_e2_settled, e_norm,
    seg_settled, i, s, k, e, tau, mask,
):  # pragma: no cover - compiled  # fmt: skip
    """Add sample k (segment s) of trial i, error ``e (n,)`` [rad] and applied ``tau (n,)``, to the
    streamed sums (the fields of :class:`~adaptive_dd.closed_loop.types.StreamedSums`), ``mask``
    the saturation mask of :func:`apply_sample`."""
    en2 = 0.0
    t2 = 0.0
    for j in range(e.shape[0]):
        en2 += e[j] * e[j]
        t2 += tau[j] * tau[j]
        sum_e2_joint[i, s, j] += e[j] * e[j]
    en = np.sqrt(en2)
    sum_e2[i, s] += en2
    if en > max_e[i, s]:
        max_e[i, s] = en
    sum_tau2[i, s] += t2
    if mask != 0:
        if n_saturated[i, s] == 0.0:
            first_saturated[i, s] = k
        n_saturated[i, s] += 1.0
    if k >= seg_settled[s]:
        sum_e2_settled[i, s] += en2
    e_norm[i, k] = en


@njit(cache=True, inline="always")
def apply_sample(
    T, max_error, max_speed, q_d, lim, lsb, saturate, quantize_dac, pl, pw,
    q, qd, stuck, failed, failed_at, failed_cmd, q_rec, qd_rec, tau_rec, sat_rec, i, k, cmd, tau, e, prev, s,
):  # pragma: no cover - compiled  # fmt: skip
    """Step 3 of the module docstring for trial i at sample k (segment s): ``cmd (n,)`` [N m]
    (zeroed in place when the divergence rule applies), the applied torque into ``tau (n,)``.

    Returns the saturation mask (bit j: joint j's command beyond its limit); the caller adds the
    sample to the streamed sums next (:func:`accumulate_sample`, with the error ``e`` this
    leaves). Not one function with it: a call of more than 30 arguments is compiled as a call
    with ``*args``, which numba does not inline.

    The arguments are the fields of :class:`~adaptive_dd.closed_loop.types.RunConstants`,
    :class:`~adaptive_dd.closed_loop.types.Io` and :class:`~adaptive_dd.closed_loop.types.TrialState`
    of the same names, the plant ``pl`` and its scratch ``pw`` (:func:`plant_advance`), and the
    recording's ``q, qd, tau, saturated``
    (``q_rec, qd_rec, tau_rec, sat_rec``: the first ``q_rec.shape[0]`` trials, the state before the step, the
    applied torque and its saturation); ``e, prev (n,)`` scratch.
    """
    n = cmd.shape[0]
    bad = False
    non_finite = -1  # the first joint whose command is not finite
    for j in range(n):
        e[j] = q_d[k, j] - q[i, j]
        if not np.isfinite(cmd[j]):
            bad = True
            if non_finite < 0:
                non_finite = j
        elif abs(e[j]) > max_error:
            bad = True
    if bad:
        for j in range(n):
            cmd[j] = 0.0
    mask = actuate_trial(cmd, lim, lsb, saturate, quantize_dac, tau)
    if failed[i]:  # stopped at rest: nothing applied, nothing saturated (the flags' fractions)
        mask = 0
        for j in range(n):
            tau[j] = 0.0
    keep = i < q_rec.shape[0]
    for j in range(n):
        prev[j] = q[i, j]
    if keep:
        for j in range(n):
            q_rec[i, k, j], qd_rec[i, k, j] = q[i, j], qd[i, j]
    plant_advance(pl, i, s, q, qd, stuck, tau, T, pw)
    ok = True
    for j in range(n):
        if not (np.isfinite(q[i, j]) and abs(qd[i, j]) < max_speed):
            ok = False
    if bad or not ok or failed[i]:
        if not failed[i]:
            failed_at[i] = k
            failed_cmd[i] = non_finite
        failed[i] = True
        for j in range(n):
            q[i, j] = prev[j] if np.isfinite(prev[j]) else 0.0
            qd[i, j] = 0.0
            stuck[i, j] = True
    if keep:
        for j in range(n):
            tau_rec[i, k, j] = tau[j]
            sat_rec[i, k, j] = (mask >> j) & 1 == 1
    return mask


@njit(cache=True, inline="always")
def record_estimate(seg_end, sigma_end, sigma_rec, i, k, s, sigma):  # pragma: no cover - compiled
    """Trial i's estimate ``sigma (p,)`` after sample k (segment s): at the segment's last sample
    (``seg_end``) into ``sigma_end (S, G, p)``, and into ``sigma_rec`` (the recording's ``sigma``)
    for its first ``sigma_rec.shape[0]`` trials."""
    if k == seg_end[s] - 1:
        for c in range(sigma.shape[0]):  # a loop, not a slice assignment: numba would compile
            sigma_end[i, s, c] = sigma[c]  # the slice assignment's shape-error message (string code)
    if i < sigma_rec.shape[0]:
        for c in range(sigma.shape[0]):
            sigma_rec[i, k, c] = sigma[c]


@njit(cache=True, inline="always")
def _as_is(x):  # pragma: no cover - compiled
    """``x`` itself: the two-link loop's :func:`borrowed` (its ``prange`` hands it arrays without
    reference counts already)."""
    return x


@njit(cache=True, inline="always")
def _nothing(x):  # pragma: no cover - compiled
    """The two-link loop's :func:`keep_alive`: nothing to keep."""
    return None


@njit(cache=True, parallel=COPY_PROPAGATE_ONLY)
def trial_samples(
    i, k0, k1, noise, drop, rc, io, pl, ts, acc, rec, alarms, law, ls, ec, es, estimates
):  # pragma: no cover - compiled
    """Samples ``k0`` to ``k1 - 1`` of trial i, state updated in place: the loop of the module
    docstring's four steps, the one writing of the closed loop's per-sample algorithm.

    ``noise (S, k1 - k0, 2 n)`` standard normal; ``drop (S, k1 - k0)`` lost measurements (or
    ``(S, 0)``: none); ``rc, io, ts, acc, rec, alarms`` the run's records
    (:mod:`adaptive_dd.closed_loop.types`, :class:`Alarms`); ``pl`` the plant, ``law, ls`` the
    law and its per-trial state, ``ec, es`` the estimator (each chosen by its type);
    ``estimates``: record the law's estimate (:func:`law_estimate`).

    The records' fields are read out once, before the sample loop, and the per-sample pieces,
    inlined into it (``inline="always"``), take them as plain arrays; compiled with
    :data:`COPY_PROPAGATE_ONLY` so that the inlined calls' argument copies cost no
    reference-count update per sample (the two-link arm's; the N-joint loop's records and scratch
    are borrowed instead: :data:`_chain_trial_samples`). A compiled kernel longer than 60 lines
    would be split here only at a cost in speed; this one is not.
    """
    # one value a call: numba's array analysis (the two-link loop's copy propagation) misreads the
    # shapes of records unpacked from one tuple of them
    rc = records_view(rc)
    io = records_view(io)
    pl = records_view(pl)
    ts = records_view(ts)
    acc = records_view(acc)
    rec = records_view(rec)
    alarms = records_view(alarms)
    law = records_view(law)
    ls = records_view(ls)
    ec = records_view(ec)
    es = records_view(es)
    noise = records_view(noise)
    drop = records_view(drop)
    T, max_error, max_speed, q_d, qd_d, qdd_d = rc.T, rc.max_error, rc.max_speed, rc.q_d, rc.qd_d, rc.qdd_d
    seg_start, seg_end, seg_settled = rc.seg_start, rc.seg_end, rc.seg_settled
    lim, lsb, saturate, quantize_dac = io.lim, io.lsb, io.saturate, io.quantize_dac
    res, std, quantize_encoder = io.res, io.std, io.quantize_encoder
    q, qd, stuck, failed, failed_at = ts.q, ts.qd, ts.stuck, ts.failed, ts.failed_at
    held_q, held_qd, n_dropped, failed_cmd = ts.held_q, ts.held_qd, ts.n_dropped, ts.failed_cmd
    sum_e2, sum_e2_joint, max_e, sum_tau2 = acc.sum_e2, acc.sum_e2_joint, acc.max_e, acc.sum_tau2
    n_saturated, sum_e2_settled, e_norm = acc.n_saturated, acc.sum_e2_settled, acc.e_norm
    first_saturated = acc.first_saturated
    ee_sum_p2, ee_max_p, ee_sum_th2 = acc.ee_sum_p2, acc.ee_max_p, acc.ee_sum_th2
    ee_index, ee_links, ee_ref = rc.ee_index, rc.ee_links, rc.ee_ref
    q_rec, qd_rec, tau_rec, sat_rec = rec.q, rec.qd, rec.tau, rec.saturated
    sigma_rec, sigma_end = rec.sigma, rec.sigma_end
    alarm_t, n_alarms = alarms.times, alarms.count
    n = plant_joints(pl, q)
    rows_own, sig_own = np.empty((8, n)), np.empty(sigma_end.shape[2])
    tw_own, tr_own = np.zeros((max(ee_index.shape[0], 1), 12)), np.zeros(9)
    pw_own, lw_own, ew_own = plant_work(pl, n), law_work_of(law, n), estimator_work(ec, es)
    rows = records_view(rows_own)
    sig = records_view(sig_own)
    tw = records_view(tw_own)
    tr = records_view(tr_own)
    pw = records_view(pw_own)
    lw = records_view(lw_own)
    ew = records_view(ew_own)
    qm, qdm, qm_obs, qdm_obs = rows[0], rows[1], rows[2], rows[3]
    cmd, tau, e, prev = rows[4], rows[5], rows[6], rows[7]
    has_drop = drop.shape[1] > 0
    late = law_delay(law)  # an oracle told of each swap late: its true model's segment lags
    for k in range(k0, k1):
        s = _segment(seg_start, k)
        s_law = s if late == 0 else _segment(seg_start, max(k - late, 0))
        lost = has_drop and drop[i, k - k0]
        measure_sample(
            q, qd, held_q, held_qd, n_dropped, res, std, quantize_encoder, i, noise[i, k - k0], lost,
            qm, qdm, qm_obs, qdm_obs,
        )  # fmt: skip
        law_command(law, ls, pl, i, s_law, T, qm, qdm, q_d[k], qd_d[k], qdd_d[k], lw, cmd)
        mask = apply_sample(
            T, max_error, max_speed, q_d, lim, lsb, saturate, quantize_dac, pl, pw,
            q, qd, stuck, failed, failed_at, failed_cmd, q_rec, qd_rec, tau_rec, sat_rec, i, k, cmd, tau, e,
            prev, s,
        )  # fmt: skip
        accumulate_sample(
            sum_e2, sum_e2_joint, max_e, sum_tau2, n_saturated, first_saturated, sum_e2_settled, e_norm,
            seg_settled, i, s, k, e, tau, mask,
        )  # fmt: skip
        accumulate_tool(ee_index, ee_links, ee_ref, ee_sum_p2, ee_max_p, ee_sum_th2, i, s, k, prev, tw, tr)
        if estimator_sample(ec, es, ls, i, qm_obs, qdm_obs, tau, ew) == 1:
            if n_alarms[i] < alarm_t.shape[1]:
                alarm_t[i, n_alarms[i]] = k * T
            n_alarms[i] += 1
        if estimates and (k == seg_end[s] - 1 or i < sigma_rec.shape[0]):
            record_estimate(seg_end, sigma_end, sigma_rec, i, k, s, law_estimate(law, ls, i, lw, sig))
    kept_to_here(rows_own)
    kept_to_here(sig_own)
    kept_to_here(tw_own)
    kept_to_here(tr_own)
    kept_to_here(pw_own)
    kept_to_here(lw_own)
    kept_to_here(ew_own)


records_view, kept_to_here = _as_is, _nothing
"""What :func:`trial_samples` calls to view its records and scratch, and to keep the scratch alive
to the end of its loop: on the two-link arm the values as they are (:func:`_as_is`); the N-joint
loop binds :func:`~adaptive_dd.closed_loop.borrow.borrowed` and
:func:`~adaptive_dd.closed_loop.borrow.keep_alive` (:data:`_chain_trial_samples`)."""


def _bound(f, **names):
    """Python function ``f`` with the global ``names`` bound to other functions (its code and its
    module's other globals the same)."""
    g = {**f.__globals__, **names}
    bound = FunctionType(f.__code__, g, f.__name__, f.__defaults__, f.__closure__)
    bound.__kwdefaults__, bound.__doc__ = f.__kwdefaults__, f.__doc__
    return bound


def _named(f, name: str):
    """Python function ``f`` renamed ``name`` (numba's cache files and messages go by the name)."""
    f.__name__ = f.__qualname__ = name
    return f


_chain_apply_sample = njit(inline="always")(
    _named(_bound(apply_sample.py_func, plant_advance=_chain_plant_advance), "_chain_apply_sample")
)
""":func:`apply_sample` of an N-joint arm, its plant's step called by name (:data:`_chain_trial_samples`)."""

_chain_trial_samples = njit(inline="always")(
    _bound(
        trial_samples.py_func,
        apply_sample=_chain_apply_sample,
        plant_joints=_chain_plant_joints,
        plant_work=_chain_plant_work,
        law_work_of=_chain_law_work,
        estimator_work=_chain_estimator_work,
        law_command=_chain_law_command,
        law_delay=_chain_law_delay,
        estimator_sample=_chain_estimator_sample,
        law_estimate=_chain_law_estimate,
        records_view=borrowed,
        kept_to_here=keep_alive,
    )
)
""":func:`trial_samples` for N-joint arms: the same code, its choices (:func:`plant_advance`,
:func:`law_command`, ...) the N-joint arm's functions called by name (``_chain_*``), inlined into
:func:`chain_loop_block` (numba optimises each compiled function again with everything it
calls: one compiled function less). Its records and scratch are
:func:`~adaptive_dd.closed_loop.borrow.borrowed` (``records_view``, kept alive by
``kept_to_here``): without it each array passed along (each call's arguments, each view such as
``q[i]``) costs an atomic reference-count update. The two-link loop gets its arrays without
reference counts from its ``prange`` (:func:`closed_loop_block`) and keeps its scratch as it is:
borrowed, it ran slower (the changelog has the measurements).

By name, not by type: numba compiles an ``@overload``'s implementation in full (with everything
it calls) to type it, even one inlined where it is called, and then throws that compiled form
away; a function compiled with ``inline="always"`` is inlined before typing, compiled only as
part of its caller. On the UR5 the overloads cost the loop's compilation about 15 CPU s (the
estimator's choice 4.8 with the estimator's step, the plant's 3.6, the law's 2.6, the plant's
friction family once more, the scratch allocations)."""


@njit(cache=True, nogil=True, parallel=True)
def closed_loop_block(
    i0, i1, k0, k1, noise, drop, rc, io, pl, ts, acc, rec, alarms, law, ls, ec, es, estimates
):  # pragma: no cover - compiled
    """Samples ``k0`` to ``k1 - 1`` of trials ``i0`` to ``i1 - 1`` (:func:`trial_samples`) of the
    two-link arm, a ``prange`` over the trials (:func:`in_threads` calls it once for all of them).

    A ``prange`` for speed, not only for threads: numba hands the arrays to the parallel loop's
    body without their reference counts (null meminfos), so that the count updates of every
    array that the sample loop and its callees pass along (about 35 per sample: each call's
    arguments, each view such as ``q[i]``) cost a null test, not an atomic update. Without it the
    two-link loop ran 8-19 % slower per sample (benchmarks/two_link_speed_ab.py). The N-joint loop
    cannot use it: its estimator's configuration, a NamedTuple holding a NamedTuple, does not
    pass into a ``prange`` (:func:`chain_loop_block`).
    """
    for t in prange(i1 - i0):
        # np.int64: the parallel loop's index is uint64 once lowered and int64 when typed; the
        # same type in both compiles trial_samples once, not twice
        trial_samples(
            np.int64(i0 + t), k0, k1, noise, drop, rc, io, pl, ts, acc, rec, alarms, law, ls, ec, es,
            estimates,
        )  # fmt: skip


@njit(cache=True, nogil=True)
def chain_loop_block(
    i0, i1, k0, k1, noise, drop, rc, io, pl, ts, acc, rec, alarms, law, ls, ec, es, estimates
):  # pragma: no cover - compiled
    """:func:`closed_loop_block` of an N-joint arm (:data:`_chain_trial_samples`), compiled once
    for every law (the estimator a :class:`ChainEstimator`, active or not)."""
    for i in range(i0, i1):
        _chain_trial_samples(
            i, k0, k1, noise, drop, rc, io, pl, ts, acc, rec, alarms, law, ls, ec, es, estimates
        )


def in_threads(kernel, S: int, args: tuple) -> None:
    """``kernel(i0, i1, *args)`` over disjoint ranges of the S trials, one per numba thread (a
    kernel with a ``prange`` over them, :func:`closed_loop_block`, once for all)."""
    import numba

    m = 1 if kernel.targetoptions.get("parallel") is True else max(1, min(S, numba.config.NUMBA_NUM_THREADS))
    with warnings.catch_warnings():  # trial_samples asks for numba's parallel pipeline on purpose
        warnings.filterwarnings(  # (COPY_PROPAGATE_ONLY); its compilation warns that nothing ran parallel
            "ignore", message=r"\s*The keyword argument 'parallel=True' was specified",
            category=NumbaPerformanceWarning,
        )  # fmt: skip
        # compile (or load) in this thread: numba's dispatch is not thread-safe
        kernel(0, S if m == 1 else 0, *args)
    if m == 1:
        return
    from concurrent.futures import ThreadPoolExecutor

    edges = np.linspace(0, S, m + 1).astype(int)
    with ThreadPoolExecutor(m) as pool:
        for f in [pool.submit(kernel, int(a), int(b), *args) for a, b in itertools.pairwise(edges)]:
            f.result()
