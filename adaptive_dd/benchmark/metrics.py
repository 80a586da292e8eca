"""Metrics of a benchmark run, per controller and per payload segment: one schema on every arm.

The JSON (:func:`compute_metrics`) has the keys :data:`TOP_KEYS`; each controller the keys
:data:`CONTROLLER_KEYS`, each of its segments the keys :data:`SEGMENT_KEYS`, on the two-link
arm and on an N-joint arm alike. A figure that exists on one kind of arm only is ``None`` on the
other, never absent (``tests/test_result_schema.py`` holds both arms' results to this).

Errors are on the *true* joint angles: ``e = q_d - q``, ``|e|`` its Euclidean norm over the
joints [rad]. Per trial, then averaged over the seeds that did not fail:

start, end [s], mass [kg]
    The segment and the payload on the arm during it.
rms_error [rad]
    ``sqrt(mean |e|^2)`` over the segment (``rms_error_joint``: per joint, a list of n_joints).
rms_error_settled [rad]
    ``sqrt(mean |e|^2)`` over the segment less its first ``SETTLE`` (0.5 s): the
    tracking once a swap's transient is over; None in a segment no longer than ``SETTLE``.
max_error [rad]
    ``max |e|`` over the segment.
detection_delay [s]
    Controllers with a change detector: time from the swap to the first alarm within
    ``FALSE_ALARM_WINDOW`` after it, mean over the seeds that raised one (``detected`` of them;
    ``missed``: kept seeds that raised none, 0 for a swap the run ends within that window of),
    None otherwise or for the first segment.
settling_time [s]
    After a swap at ``t_s``: the time until the 50 ms moving RMS of ``|e|`` enters
    a band about the controller's own error and stays inside it for ``SETTLING_DWELL`` (0.5 s):
    how long its transient lasts, not how close it comes to its floor (a law whose error stays
    far above the floor's settles at once; the time to come within 1.2x the floor is
    ``time_to_floor`` in the first segment and the leaderboard's ``recovery`` after a swap).
    The band is ``SETTLING_BAND`` times the peak of that moving RMS over the second before the
    swap or over the last second of the segment (each at most its segment's second half: in a
    segment shorter than 2 s a swap's own transient would otherwise set the band), whichever is
    larger (the settled level can differ with the payload; friction at reversals makes the steady
    error spiky, so the band is set by its peaks), with a floor ``SETTLING_FLOOR``. ``None`` for
    the first segment, and for a trial that never does so within the segment.
rms_torque [N m]
    ``sqrt(mean |tau|^2)`` of the applied torque.
saturation_fraction
    Fraction of samples with a joint's command beyond its limit.
floor_saturation, floor_saturated
    The floor's saturation fraction in the segment, and whether it exceeds
    ``SATURATION_LIMIT`` (1 %): there the floor is not the law with the true model but a
    saturated loop, its ratio says nothing and the report gives no verdict.
mass_estimate [kg]
    Payload mass implied by the estimates at the end of the segment (the arm's
    ``payload_mass_from_sigma``, or ``payload_from_sigma``); None for fixed models.
com_estimate [m]
    The payload's centre of mass (x, y, z, payload frame) implied by the estimates at the end
    of the segment (None below 0.1 kg); N-joint arms only: None on the two-link arm, whose
    paper's sigma holds the payload at the tip (eq. 9) and no centre of mass.
ee_position_rms, ee_position_max [mm], ee_orientation_rms [deg], ee_seeds
    The tool frame's error (the arm's ``payload_frame``, placed by forward kinematics at the true
    q and at the reference): position RMS and peak, orientation RMS, on every arm
    (:mod:`~adaptive_dd.benchmark.end_effector`), streamed by the loop for every trial
    (:mod:`~adaptive_dd.closed_loop.tool_frame`); the mean over the ``ee_seeds`` seeds that did
    not fail before the segment's end.
com_true [m]
    The centre of mass of the segment's payload in the payload frame; None without payload.
sigma_true
    The arm's true base parameters in the segment: the paper's seven (J1 J2 r b1 b2 d1 d2) on the
    two-link arm, the arm's ``base.count`` on an N-joint arm (the plant's before any draw).

A trial that diverged is left out of the segments that end after its failure (the segments
before it count); a controller that raised is left out everywhere
(:func:`~adaptive_dd.benchmark.segments.segment_failed`, the one rule on every arm).

Per controller: ``rms_error`` [rad] over the whole run, ``failed_trials``, ``error`` (the
controller's exception, or None), ``engine``, ``dropped_samples`` (lost measurements of the kept
trials), ``skipped_samples_per_seed`` (samples the estimator skipped; None without one),
``failures`` (``[{"seed", "t" [s], "why"}]`` of every failed trial; ``[]`` when none failed),
``nonfinite_estimates`` (``[[seed, segment], ...]`` where a kept trial's estimate ends the segment
not finite; None without an estimate).

Per seed (trial i uses the noise of seed ``(scenario.seed, i)`` for every controller,
so ratios are taken seed by seed: common random numbers):

rms_error_per_seed [rad]
    The segment's RMS error of each trial (None for a failed trial).
ratio_to_floor
    Statistics of ``rms_error / rms_error of the floor`` per seed, where the floor (``floor``: its
    name, None without) is the same law with the true model (``Controller.floor``; e.g.
    ``ct_oracle`` for ``adaptive_ct``): ``mean``, ``median``, ``p90``, ``max``, ``ci95``
    (bootstrap interval of the mean), ``worst_seed`` (the seed index of the largest ratio), ``n``. None
    when the floor is not in the run.
detection_delay_per_seed [s]
    Segments after a swap: the first alarm within ``FALSE_ALARM_WINDOW`` after the swap,
    per seed (None: missed or failed). None for a controller without a detector.
missed_swaps_per_seed
    Per controller with a detector: swaps with no alarm within ``FALSE_ALARM_WINDOW`` after
    them, per seed (None: failed); ``missed_swaps``: their sum. None without a detector.
false_alarms_per_seed
    Per controller with a detector: alarms that follow no swap by ``FALSE_ALARM_WINDOW``
    (``trials_with_false_alarms``: the trials with one). None without a detector.
detection_delay_median [s]
    Segments after a swap: the median of ``detection_delay_per_seed`` over the trials that
    detected it (None: none did); the report compares it with ``detection_limit``.
time_to_floor
    First segment, controllers whose floor ran: per seed the time [s] after which the 0.25 s
    moving RMS error stays within 1.2x the floor's to the first swap (``"never"`` if it does not),
    with its median, p90, max and the count of never
    (:mod:`~adaptive_dd.benchmark.time_to_floor`); None elsewhere.
information_time, detection_limit, mass_learning_time, com_learning_time, learning_seeds
    Per swap, the information limit and each controller's time to learn the payload
    (:mod:`~adaptive_dd.closed_loop.information`, its keys and units); None in the first segment.

Top level: ``scenario`` (its file), ``seeds``, ``wall_time_s`` [s] (the runs, numba's compilation left
out), ``provenance``, ``plant``
(the plants the trials met when the plant is not the model; None: the plant is the arm),
``excitation`` (the ``[run] excite`` phase's identification; None without), ``controllers``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from adaptive_dd.benchmark.intervals import mean_interval
from adaptive_dd.benchmark.provenance import provenance
from adaptive_dd.benchmark.segments import moving_rms, nonfinite_estimates, segment_failed
from adaptive_dd.benchmark.streaming import SETTLE, segment_bounds

if TYPE_CHECKING:  # annotations only: types imports this module for BenchmarkResult.metrics()
    from adaptive_dd.benchmark.types import BenchmarkResult

__all__ = [
    "CONTROLLER_KEYS",
    "FALSE_ALARM_WINDOW",
    "MODEL_FRICTION",
    "SATURATION_LIMIT",
    "SEGMENT_KEYS",
    "SETTLING_BAND",
    "SETTLING_DWELL",
    "SETTLING_FLOOR",
    "TOP_KEYS",
    "compute_metrics",
    "detection_delays",
    "error_trace",
    "false_alarm_counts",
    "floor_caveat",
    "missed_swap_counts",
    "moving_rms",
    "per_seed_segment_metrics",
    "ratio_statistics",
    "release_error_norm",
    "segment_failed",
    "segment_rms",
]

SETTLING_BAND = 1.5
SETTLING_FLOOR = 5e-5  # rad
SETTLING_DWELL = 0.5  # s
WINDOW = 0.05  # s
FALSE_ALARM_WINDOW = 0.3  # s: an alarm later than this after every swap is a false alarm
SATURATION_LIMIT = 0.01  # fraction of samples: a floor saturated more than this is no floor
SEED_CHUNK = 64  # seeds per block of the per-sample post-processing (bounds its memory)

TOP_KEYS = (
    "scenario", "seeds", "wall_time_s", "provenance", "plant", "excitation", "floor_caveat", "controllers",
)  # fmt: skip
"""The keys of the metrics (the JSON), on every arm (module docstring)."""
CONTROLLER_KEYS = (
    "rms_error", "failed_trials", "error", "engine", "dropped_samples", "skipped_samples_per_seed",
    "failures", "floor", "false_alarms_per_seed", "trials_with_false_alarms", "missed_swaps_per_seed",
    "missed_swaps", "nonfinite_estimates", "segments",
)  # fmt: skip
"""The keys of each controller's entry, on every arm (module docstring)."""
SEGMENT_KEYS = (
    "start", "end", "mass", "rms_error", "rms_error_settled", "rms_error_joint", "max_error",
    "settling_time", "rms_torque", "saturation_fraction", "mass_estimate", "com_estimate", "com_true",
    "sigma_true", "rms_error_per_seed", "ratio_to_floor", "floor_saturation", "floor_saturated",
    "detection_delay", "detection_delay_per_seed", "detection_delay_median", "detected", "missed",
    "time_to_floor", "information_time", "detection_limit", "mass_learning_time", "com_learning_time",
    "learning_seeds", "ee_position_rms", "ee_position_max", "ee_orientation_rms", "ee_seeds",
)  # fmt: skip
"""The keys of each segment, on every arm (module docstring;
:data:`~adaptive_dd.closed_loop.information.LEARNING_KEYS` among them)."""


def _settling_time(above: np.ndarray, dwell: int) -> np.ndarray:
    """Per row: first index i with ``above[i : i + dwell]`` all False (NaN if none)."""
    n = above.shape[-1]
    idx = np.arange(n)
    # index of the next True at or after i (n if none)
    nxt = np.where(above, idx, n)
    nxt = np.minimum.accumulate(nxt[..., ::-1], axis=-1)[..., ::-1]
    good = (nxt - idx >= dwell) & (idx + dwell <= n)
    first = np.argmax(good, axis=-1)
    return np.where(good.any(axis=-1), first, np.nan).astype(float)


def _mean(x: np.ndarray):
    """Mean of the finite entries (None if there is none)."""
    v = np.asarray(x, float)
    v = v[np.isfinite(v)]
    return float(np.mean(v)) if v.size else None


def segment_rms(sums: np.ndarray, n) -> np.ndarray:
    """RMS from streamed sums of squares over ``n`` samples: the one per-seed RMS of the package."""
    return np.sqrt(np.asarray(sums, float) / n)


def _no_settled_window(out: dict, sc) -> dict:
    """``rms_error_settled`` NaN in a segment no longer than ``SETTLE`` (it has no sample after its
    first ``SETTLE``: the bounds' clamp to one sample printed that sample's error as the RMS)."""
    short = [b - a <= SETTLE + 1e-9 for a, b, _ in sc.segments()]
    if any(short):
        out["rms_error_settled"] = np.where(np.asarray(short)[None, :], np.nan, out["rms_error_settled"])
    return out


def per_seed_segment_metrics(res: BenchmarkResult, run, settling: bool = True) -> dict[str, np.ndarray]:
    """Per seed and segment, ``(n_seeds, n_segments)`` arrays from the streamed sums.

    NaN where the trial failed before the segment's end (:func:`segment_failed`). Computed once
    per run and kept in ``res.cache`` (the JSON, the report and the per-seed table share it);
    ``settling=False`` leaves out the settling times (they need the per-sample error norm).
    """
    key = ("per_seed", run.name, settling)
    if key in res.cache:
        return res.cache[key]
    sc = res.scenario
    T = sc.sample_period

    if sc.closed_forms is None:  # the general kernels' run (adaptive_dd.closed_loop)
        from adaptive_dd.closed_loop.metrics import segment_metrics

        out = _no_settled_window(segment_metrics(res, run), sc)
        start, end = _bounds(sc)
        out.update(_end_effector(res, run, start, end))
        if settling:
            out["settling_time"] = _settling_times(run.e_norm, start, end, T)
        return _blank_failed(res, run, out, end, key)
    start, end, settled = segment_bounds(sc.segments(), T, SETTLE)
    n, n_set = (end - start).astype(float), (end - settled).astype(float)
    acc = run.acc
    out = {
        "rms_error": segment_rms(acc.sum_e2, n),
        "rms_error_joint1": segment_rms(acc.sum_e2_joint[..., 0], n),
        "rms_error_joint2": segment_rms(acc.sum_e2_joint[..., 1], n),
        "max_error": acc.max_e.copy(),
        "rms_torque": segment_rms(acc.sum_tau2, n),
        "saturation_fraction": acc.n_saturated / n,
        "rms_error_settled": segment_rms(acc.sum_e2_settled, n_set),
    }
    out = _no_settled_window(out, sc)
    out.update(_end_effector(res, run, start, end))
    if settling:
        out["settling_time"] = _settling_times(run.e_norm, start, end, T)
    if run.sigma_end is not None:
        out["mass_estimate"] = sc.closed_forms.payload_mass_from_sigma(run.sigma_end)
    return _blank_failed(res, run, out, end, key)


def _end_effector(res: BenchmarkResult, run, start, end) -> dict[str, np.ndarray]:
    """The tool frame's error per seed and segment (:mod:`~adaptive_dd.benchmark.end_effector`)
    from the sums the loop streamed for every trial (:mod:`~adaptive_dd.closed_loop.tool_frame`):
    position RMS and peak [mm], orientation RMS [deg]; NaN where no sums were streamed."""
    from adaptive_dd.benchmark.end_effector import EE_KEYS

    acc = run.acc
    S = run.failed.shape[0]
    if acc is None or acc.ee_sum_p2 is None:
        return {k: np.full((S, len(start)), np.nan) for k in EE_KEYS}
    n = (np.asarray(end) - np.asarray(start)).astype(float)
    return {
        "ee_position_rms": 1e3 * segment_rms(acc.ee_sum_p2, n),
        "ee_position_max": 1e3 * acc.ee_max_p,
        "ee_orientation_rms": np.degrees(segment_rms(acc.ee_sum_th2, n)),
    }


def _blank_failed(res: BenchmarkResult, run, out: dict, end: np.ndarray, key) -> dict:
    """NaN where the trial failed (:func:`segment_failed`, every arm's one rule); cached."""
    bad = segment_failed(run.failed, run.failed_at, end)
    if run.error:
        bad[:] = True
    for v in out.values():
        v[bad] = np.nan
    res.cache[key] = out
    return out


def _bounds(sc):
    from adaptive_dd.closed_loop.types import sample_bounds

    return sample_bounds(sc)[:2]


def _settling_times(e_norm: np.ndarray, start, end, T: float) -> np.ndarray:
    """Settling time after each swap (see the module docstring), ``(n_seeds, n_segments)``; NaN if none.

    Computed ``SEED_CHUNK`` seeds at a time, so the float64 work arrays stay small at 1000 seeds."""
    out = np.full((e_norm.shape[0], len(start)), np.nan)
    n1 = round(1.0 / T)
    for c in range(0, e_norm.shape[0], SEED_CHUNK):
        smooth = moving_rms(e_norm[c : c + SEED_CHUNK].astype(float), max(1, round(WINDOW / T)))
        for s, (a, b) in enumerate(zip(start, end, strict=True)):
            if a == 0:
                continue
            a0 = start[s - 1]  # the segment before (a > 0: not the first): at most its second half too
            pre = smooth[:, max(a0 + (a - a0) // 2, a - n1) : a].max(axis=1)
            post = smooth[:, max(a + (b - a) // 2, b - n1) : b].max(axis=1)  # the settled tail
            band = np.maximum(SETTLING_BAND * np.maximum(pre, post), SETTLING_FLOOR)
            settle = _settling_time(smooth[:, a:b] > band[:, None], round(SETTLING_DWELL / T))
            out[c : c + SEED_CHUNK, s] = settle * T
    return out


def error_trace(res: BenchmarkResult, run, window: float = WINDOW) -> np.ndarray | None:
    """``(n_samples,)``: the ``window`` moving RMS of ``|e|`` [rad], mean over the seeds that did not
    fail (None if all failed); computed ``SEED_CHUNK`` seeds at a time and kept in ``res.cache``."""
    key = ("trace", run.name, window)
    if key not in res.cache:
        ok = np.flatnonzero(~run.failed)
        n = max(1, round(window / res.scenario.sample_period))
        total = np.zeros(run.e_norm.shape[1])
        for c in range(0, ok.size, SEED_CHUNK):
            total += moving_rms(run.e_norm[ok[c : c + SEED_CHUNK]].astype(float), n).sum(axis=0)
        res.cache[key] = total / ok.size if ok.size else None
    return res.cache[key]


def release_error_norm(res: BenchmarkResult, run, keep: int = 0) -> None:
    """Derive everything that needs a run's per-sample error norm (per-seed metrics with settling
    times, the figure's error trace), then keep only its first ``keep`` seeds' norm.

    Passed as ``run_benchmark(..., on_run=release_error_norm)`` by the CLI: memory then holds one
    controller's ``(n_seeds, n_samples)`` float32 norm at a time (80 MB at 1000 seeds of 20 s),
    and each controller's norm over the first segment only (the time to come within 1.2x of the
    floor, :mod:`~adaptive_dd.benchmark.time_to_floor`).
    """
    per_seed_segment_metrics(res, run)
    error_trace(res, run)
    from adaptive_dd.benchmark.time_to_floor import first_segment_norm

    first = first_segment_norm(res, run)  # the first segment's norm, for the time to the floor
    if first is not None:
        res.cache[("first_segment_norm", run.name)] = first.copy()
    run.e_norm = run.e_norm[:keep].copy()
    run.acc = run.acc._replace(e_norm=run.e_norm)  # the streamed sums held the same array


_TIE = 1e-9
"""[s] Alarm and swap times are sample times in float seconds: an alarm ``FALSE_ALARM_WINDOW``
after a swap to the sample is outside the window whatever the rounding of the two times."""


def _after(x: float, s: float) -> bool:
    """Alarm ``x`` [s] within ``FALSE_ALARM_WINDOW`` after swap ``s`` [s], ties decided as above."""
    return -_TIE <= x - s < FALSE_ALARM_WINDOW - _TIE


def judged(swap: float, duration: float) -> bool:
    """A swap the run lasts ``FALSE_ALARM_WINDOW`` beyond: only then can it be called missed."""
    return swap + FALSE_ALARM_WINDOW <= duration + _TIE


def false_alarm_counts(alarm_times, swaps) -> list[int]:
    """Per trial: alarms [s] that follow no swap [s] by less than ``FALSE_ALARM_WINDOW``."""
    return [sum(1 for x in tr if not any(_after(x, s) for s in swaps)) for tr in alarm_times]


def missed_swap_counts(alarm_times, swaps, failed, duration: float = np.inf) -> np.ndarray:
    """Per trial, the swaps [s] with no alarm within ``FALSE_ALARM_WINDOW`` after them (0 for a
    failed trial; a swap the run ends within that window of is not judged: :func:`judged`, nor one
    after the last alarm a truncated record kept: :func:`seen_swap`)."""

    def missed(tr, s) -> bool:
        return judged(s, duration) and seen_swap(tr, s) and not any(_after(x, s) for x in tr)

    return np.array(
        [0 if f else sum(missed(tr, s) for s in swaps) for tr, f in zip(alarm_times, failed, strict=True)]
    )


def seen_swap(times, swap: float) -> bool:
    """Whether one trial's alarm record can tell if ``swap`` [s] was detected: not when the record
    was truncated (``AlarmTimes.truncated``: more alarms than kept) before the swap (a kept alarm at
    or after it is either the detection or beyond its window)."""
    return not getattr(times, "truncated", False) or (len(times) > 0 and times[-1] >= swap)


def detection_delays(alarm_times, swap: float) -> list[float | None]:
    """Per trial: the first alarm within ``FALSE_ALARM_WINDOW`` after ``swap``, less the swap [s]
    (None: missed)."""
    return [min((x - swap for x in tr if _after(x, swap)), default=None) for tr in alarm_times]


MODEL_FRICTION = "stick-slip"
"""The plant friction law the controllers' and the estimator's model describes: viscous plus Coulomb
friction, the Coulomb torque's sign the velocity's (stuck at rest below breakaway)."""


def floor_caveat(sc) -> str | None:
    """Why the floor (the same law given the true model) is no floor in ``sc``, or None.

    On a plant whose friction law is not the model's (:data:`MODEL_FRICTION`: tanh, Stribeck,
    LuGre), the floor knows the plant's rigid body and its viscous and Coulomb coefficients but not
    its friction law, so it is not the best the law can do: an estimator that absorbs part of the
    unmodelled friction into its parameters can beat it (a ratio below 1)."""
    law = getattr(sc.arm, "friction", MODEL_FRICTION)
    if law == MODEL_FRICTION:
        return None
    return (
        f"the plant's friction law ({law}) is not the controllers' model's (viscous plus Coulomb): "
        "each floor is its law given the plant's rigid body and friction coefficients, not the "
        "plant's friction law, so it is a reference rather than a floor (a ratio below 1 is possible)"
    )


def compute_metrics(res: BenchmarkResult) -> dict:
    """Metrics in the JSON layout of the README (``{"controllers": {NAME: {...}}}``): the keys of
    :data:`TOP_KEYS`, each controller's :data:`CONTROLLER_KEYS` and each segment's
    :data:`SEGMENT_KEYS`, on every arm (a figure one kind of arm lacks is None, never absent)."""
    from adaptive_dd.benchmark.time_to_floor import add_time_to_floor
    from adaptive_dd.closed_loop.information import add_information_times

    sc = res.scenario
    per = {name: per_seed_segment_metrics(res, run) for name, run in res.runs.items()}
    seg_sigma = _segment_sigmas(sc)
    out = {name: _controller_entry(res, run, per[name], seg_sigma) for name, run in res.runs.items()}
    _add_floor_ratios(res, out, per)
    _add_detector_statistics(res, out)
    add_information_times(res, out)
    add_time_to_floor(res, out)
    return {
        "scenario": sc.source,
        "seeds": len(res.seed_indices) or sc.seeds,  # the trials run (seed_indices: some of the scenario's)
        "wall_time_s": res.wall_time,
        "provenance": provenance(res),
        "plant": res.plant,  # the plant is not the model: what each seed's plant was (None: the arm)
        "excitation": res.excitation,  # [run] excite: the identification before the task (None: none)
        "floor_caveat": floor_caveat(sc),
        "controllers": out,
    }


def _controller_entry(res: BenchmarkResult, run, m: dict, seg_sigma: np.ndarray) -> dict:
    """One controller's :data:`CONTROLLER_KEYS`, its segments' figures from the per-seed ``m``
    (the floor ratios, detector, information and time-to-floor keys are filled after, None here)."""
    sc = res.scenario
    ok = ~run.failed if not run.error else np.zeros_like(run.failed)
    total = segment_rms(run.acc.sum_e2.sum(axis=1), sc.n_samples)
    return {
        "rms_error": _mean(np.where(ok, total, np.nan)),
        "failed_trials": int(run.failed.sum()),
        "error": run.error or None,
        "engine": run.engine,
        "dropped_samples": None if run.dropped is None else int(run.dropped[ok].sum()),
        "skipped_samples_per_seed": None if run.skipped is None else [int(x) for x in run.skipped],
        "failures": run.failures(sc.sample_period, res.seed_indices or None),  # seed, time, why
        "floor": None,
        "false_alarms_per_seed": None,
        "trials_with_false_alarms": None,
        "missed_swaps_per_seed": None,
        "missed_swaps": None,
        "nonfinite_estimates": nonfinite_estimates(
            run.sigma_end, run.failed, bool(run.error), res.seed_indices or range(sc.seeds)
        ),
        "segments": [_segment_entry(sc, m, i, seg_sigma[i]) for i in range(len(sc.segments()))],
    }


def _segment_entry(sc, m: dict, i: int, sigma_true: np.ndarray) -> dict:
    """Segment i's :data:`SEGMENT_KEYS`: its means over the kept seeds of ``m``, the rest None."""
    start, end, mass = sc.segments()[i]
    seg = dict.fromkeys(SEGMENT_KEYS)
    seg.update(
        start=start,
        end=end,
        mass=mass,
        rms_error=_mean(m["rms_error"][:, i]),
        rms_error_settled=_mean(m["rms_error_settled"][:, i]),
        rms_error_joint=[_mean(m[f"rms_error_joint{j}"][:, i]) for j in range(1, sc.n_joints + 1)],
        max_error=_mean(m["max_error"][:, i]),
        settling_time=_mean(m["settling_time"][:, i]) if i > 0 else None,
        rms_torque=_mean(m["rms_torque"][:, i]),
        saturation_fraction=_mean(m["saturation_fraction"][:, i]),
        mass_estimate=_mean(m["mass_estimate"][:, i]) if "mass_estimate" in m else None,
        sigma_true=[float(x) for x in sigma_true],
        rms_error_per_seed=_seed_list(m["rms_error"][:, i]),
        com_true=_com_true(sc, i),
        floor_saturated=False,
        detected=None,
        missed=None,
    )
    ee = m["ee_position_rms"][:, i]
    seg["ee_seeds"] = int(np.isfinite(ee).sum())
    for k in ("ee_position_rms", "ee_position_max", "ee_orientation_rms"):
        seg[k] = _mean(m[k][:, i])
    if "com_estimate_x" in m:
        seg["com_estimate"] = [_mean(m[f"com_estimate_{a}"][:, i]) for a in "xyz"]
    return seg


def _segment_sigmas(sc) -> np.ndarray:
    """True base parameters per segment ``(G, p)``."""

    if sc.closed_forms is None:
        return sc.segment_sigmas()
    return np.array([sc.closed_forms.sigma_with_payload(m, sc.payload_radius) for _, _, m in sc.segments()])


def _com_true(sc, i: int):
    """Centre of mass [m] of segment i's payload in the payload frame (None without payload)."""
    if i == 0 or sc.swap_masses[i - 1] == 0:
        return None
    com = sc.payload_of(i - 1).get("com")
    return [float(x) for x in com] if com is not None else [0.0, 0.0, 0.0]


def _seed_list(x: np.ndarray) -> list:
    return [float(v) if np.isfinite(v) else None for v in x]


def ratio_statistics(ratio: np.ndarray, seeds=None) -> dict | None:
    """Mean, median, p90, max, 95 % interval of the mean and worst seed of per-seed ratios.

    Parameters
    ----------
    ratio : ndarray (n_seeds,)
        Per-seed ratios; NaN entries (failed trials) are left out.
    seeds : sequence of int, optional
        The seed index of each entry (default ``0 .. n_seeds - 1``); ``worst_seed`` is one of them.

    Returns
    -------
    dict or None
        ``mean``, ``median``, ``p90`` (linear interpolation between order statistics, numpy's
        default), ``max``, ``ci95`` (percentile-bootstrap interval of the mean,
        :func:`~adaptive_dd.benchmark.intervals.mean_interval`; None for one seed),
        ``worst_seed`` and ``n`` (seeds counted); None when no entry is finite.
    """
    ratio = np.asarray(ratio, float)
    seeds = np.arange(ratio.size) if seeds is None else np.asarray(seeds)
    idx = np.flatnonzero(np.isfinite(ratio))
    if idx.size == 0:
        return None
    r = ratio[idx]
    mean = float(r.mean())
    ci = mean_interval(r)
    return {
        "mean": mean,
        "median": float(np.median(r)),
        "p90": float(np.percentile(r, 90)),
        "max": float(r.max()),
        "ci95": list(ci) if ci is not None else None,
        "worst_seed": int(seeds[idx[np.argmax(r)]]),
        "n": int(r.size),
    }


def _add_floor_ratios(res: BenchmarkResult, out: dict, per: dict) -> None:
    """Each controller's floor, and per segment the per-seed ratio to it and the floor's saturation."""
    seeds = res.seed_indices or tuple(range(res.scenario.seeds))
    floors = {r.floor for r in res.runs.values() if r.floor in res.runs}
    for name, run in res.runs.items():
        floor = run.floor if run.floor in per else None
        out[name]["floor"] = floor
        for i, seg in enumerate(out[name]["segments"]):
            ref = floor or (name if name in floors else None)
            seg["floor_saturation"] = out[ref]["segments"][i]["saturation_fraction"] if ref else None
            fs = seg["floor_saturation"]
            seg["floor_saturated"] = bool(fs is not None and fs > SATURATION_LIMIT)
            if floor is not None:
                with np.errstate(divide="ignore", invalid="ignore"):
                    ratio = per[name]["rms_error"][:, i] / per[floor]["rms_error"][:, i]
                seg["ratio_to_floor"] = ratio_statistics(np.where(np.isfinite(ratio), ratio, np.nan), seeds)


def _add_detector_statistics(res: BenchmarkResult, out: dict) -> None:
    """Controllers with a change detector: false alarms, missed swaps and detection delays per
    seed (None for a failed trial), and per swap their mean, median and counts."""
    sc = res.scenario
    for name, run in res.runs.items():
        if run.alarm_times is None:
            continue
        ok = ~run.failed if not run.error else np.zeros_like(run.failed)
        false = false_alarm_counts(run.alarm_times, sc.swap_times)
        out[name]["false_alarms_per_seed"] = [n if g else None for n, g in zip(false, ok, strict=True)]
        out[name]["trials_with_false_alarms"] = int(sum(1 for n, g in zip(false, ok, strict=True) if g and n))
        missed = np.zeros(len(ok), dtype=int)
        for seg, s in zip(out[name]["segments"][1:], sc.swap_times, strict=True):
            first = detection_delays(run.alarm_times, s)
            seg["detection_delay_per_seed"] = [d if g else None for d, g in zip(first, ok, strict=True)]
            hit = [d for d, g in zip(first, ok, strict=True) if g and d is not None]
            seg["detection_delay"] = float(np.mean(hit)) if hit else None
            seg["detection_delay_median"] = float(np.median(hit)) if hit else None
            seg["detected"] = len(hit)
            # the leaderboard's rule: judged swaps only, none after a truncated record's last alarm
            lost = missed_swap_counts(run.alarm_times, (s,), ~ok, sc.duration)
            seg["missed"] = int(lost.sum())
            missed += lost
        out[name]["missed_swaps_per_seed"] = [int(n) if g else None for n, g in zip(missed, ok, strict=True)]
        out[name]["missed_swaps"] = int(missed[ok].sum())
