"""Metrics of a benchmark run, per controller and per payload segment.

Errors are on the *true* joint angles: ``e = q_d - q``, ``|e|`` its Euclidean norm
over both joints [rad]. Per trial, then averaged over the seeds that did not fail:

rms_error
    ``sqrt(mean |e|^2)`` over the segment (``rms_error_joint``: per joint).
rms_error_settled
    ``sqrt(mean |e|^2)`` over the segment less its first ``SETTLE`` (0.5 s): the
    tracking once a swap's transient is over.
max_error
    ``max |e|`` over the segment.
detection_delay
    Controllers with a change detector: time from the segment start to the first
    alarm in the segment (mean over the seeds that raised one), None otherwise or
    for the first segment.
recovery_time
    After a swap at ``t_s``: the time until the 50 ms moving RMS of ``|e|`` enters
    a band and stays inside it for ``RECOVERY_DWELL`` (0.5 s). The band is ``RECOVERY_BAND`` times
    the peak of that moving RMS over the second before the swap or over the last
    second of the segment, whichever is larger (the settled level can differ with
    the payload; friction at reversals makes the steady error spiky, so the band
    is set by its peaks), with a floor ``RECOVERY_FLOOR``. ``None`` for the first segment, and for a trial
    that never does so within the segment.
rms_torque
    ``sqrt(mean |tau|^2)`` of the applied torque [N m].
saturation_fraction
    Fraction of samples with a joint's command beyond its limit.
mass_estimate
    Payload mass implied by the estimates at the end of the segment
    (:func:`~adaptive_dd.plant.payload_mass_from_sigma`); None for fixed models.

Per seed (trial i uses the noise of seed ``(scenario.seed, i)`` for every controller,
so ratios are taken seed by seed: common random numbers):

rms_error_per_seed
    The segment's RMS error of each trial (None for a failed trial).
ratio_to_floor
    Statistics of ``rms_error / rms_error of the floor`` per seed, where the floor is the
    same law with the true model (``Controller.floor``; e.g. ``ct_oracle`` for
    ``adaptive_ct``): ``mean``, ``median``, ``p90``, ``max``, ``ci95`` (t-interval of the
    mean), ``worst_seed``, ``n``. None when the floor is not in the run.
detection_delay_per_seed
    Segments after a swap: the first alarm within ``FALSE_ALARM_WINDOW`` after the swap,
    per seed (None: missed or failed).
false_alarms_per_seed
    Per controller with a detector: alarms that follow no swap by ``FALSE_ALARM_WINDOW``.
"""

from __future__ import annotations

import numpy as np

from adaptive_dd.benchmark.runner import SETTLE, BenchmarkResult
from adaptive_dd.benchmark.streaming import segment_bounds

__all__ = ["RECOVERY_BAND", "RECOVERY_DWELL", "RECOVERY_FLOOR", "compute_metrics", "moving_rms"]

RECOVERY_BAND = 1.5
RECOVERY_FLOOR = 5e-5  # rad
RECOVERY_DWELL = 0.5  # s
WINDOW = 0.05  # s
FALSE_ALARM_WINDOW = 0.3  # s: an alarm later than this after every swap is a false alarm


def moving_rms(x: np.ndarray, n: int, axis: int = -1) -> np.ndarray:
    """Causal moving RMS over n samples along an axis."""
    x2 = np.moveaxis(np.asarray(x, float) ** 2, axis, -1)
    c = np.cumsum(x2, axis=-1)
    c = np.concatenate((np.zeros((*c.shape[:-1], 1)), c), axis=-1)
    k = np.arange(x2.shape[-1])
    lo = np.maximum(k + 1 - n, 0)
    out = np.sqrt((c[..., k + 1] - c[..., lo]) / (k + 1 - lo))
    return np.moveaxis(out, -1, axis)


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


def _mean(x: np.ndarray, ok: np.ndarray):
    v = x[ok]
    v = v[np.isfinite(v)] if v.dtype.kind == "f" else v
    return float(np.mean(v)) if v.size else None


def per_seed_segment_metrics(res: BenchmarkResult, run) -> dict[str, np.ndarray]:
    """Per seed and segment, ``(n_seeds, n_segments)`` arrays from the streamed sums (NaN: failed)."""
    sc = res.scenario
    T = sc.sample_period
    if hasattr(run.acc, "sum_e2_joint"):  # an N-joint run (adaptive_dd.closed_loop)
        from adaptive_dd.closed_loop.metrics import serial_segment_metrics

        out = serial_segment_metrics(res, run)
        out["recovery_time"] = _recovery_times(run.e_norm, *_serial_bounds(sc), T)
        out["recovery_time"][run.failed] = np.nan
        return out
    start, end, settled = segment_bounds(sc.segments(), T, SETTLE)
    n, n_set = (end - start).astype(float), (end - settled).astype(float)
    acc = run.acc
    out = {
        "rms_error": np.sqrt(acc[..., 0] / n),
        "rms_error_joint1": np.sqrt(acc[..., 1] / n),
        "rms_error_joint2": np.sqrt(acc[..., 2] / n),
        "max_error": acc[..., 3].copy(),
        "rms_torque": np.sqrt(acc[..., 4] / n),
        "saturation_fraction": acc[..., 5] / n,
        "rms_error_settled": np.sqrt(acc[..., 6] / n_set),
        "recovery_time": _recovery_times(run.e_norm, start, end, T),
    }
    if run.sigma_end is not None:
        out["mass_estimate"] = sc.arm.payload_mass_from_sigma(run.sigma_end)
    for v in out.values():
        v[run.failed] = np.nan
    return out


def _serial_bounds(sc):
    from adaptive_dd.closed_loop.types import run_constants

    rc = run_constants(sc)
    return rc.seg_start, rc.seg_end


def _recovery_times(e_norm: np.ndarray, start, end, T: float) -> np.ndarray:
    """Recovery time after each swap (see the module docstring), ``(n_seeds, n_segments)``; NaN if none."""
    smooth = moving_rms(e_norm.astype(float), max(1, round(WINDOW / T)))
    out = np.full((e_norm.shape[0], len(start)), np.nan)
    n1 = round(1.0 / T)
    for s, (a, b) in enumerate(zip(start, end, strict=True)):
        if a == 0:
            continue
        pre = smooth[:, max(0, a - n1) : a].max(axis=1)
        post = smooth[:, max(a, b - n1) : b].max(axis=1)
        band = np.maximum(RECOVERY_BAND * np.maximum(pre, post), RECOVERY_FLOOR)
        out[:, s] = _settling_time(smooth[:, a:b] > band[:, None], round(RECOVERY_DWELL / T)) * T
    return out


def compute_metrics(res: BenchmarkResult) -> dict:
    """Metrics in the JSON layout of the README (``{"controllers": {NAME: {...}}}``)."""
    sc = res.scenario
    out = {}
    per = {name: per_seed_segment_metrics(res, run) for name, run in res.runs.items()}
    seg_sigma = _segment_sigmas(sc)
    for name, run in res.runs.items():
        ok = ~run.failed
        m = per[name]
        segs = []
        for i, (start, end, mass) in enumerate(sc.segments()):
            delay = None
            if run.alarm_times is not None and i > 0:
                first = [min((x for x in tr if start <= x < end), default=np.nan) for tr in run.alarm_times]
                delay = _mean(np.asarray(first) - start, ok)
            segs.append(
                {
                    "start": start,
                    "end": end,
                    "mass": mass,
                    "rms_error": _mean(m["rms_error"][:, i], ok),
                    "rms_error_settled": _mean(m["rms_error_settled"][:, i], ok),
                    "detection_delay": delay,
                    "rms_error_joint": [
                        _mean(m[f"rms_error_joint{j}"][:, i], ok) for j in range(1, sc.n_joints + 1)
                    ],
                    "max_error": _mean(m["max_error"][:, i], ok),
                    "recovery_time": _mean(m["recovery_time"][:, i], ok) if i > 0 else None,
                    "rms_torque": _mean(m["rms_torque"][:, i], ok),
                    "saturation_fraction": _mean(m["saturation_fraction"][:, i], ok),
                    "mass_estimate": _mean(m["mass_estimate"][:, i], ok) if "mass_estimate" in m else None,
                    "sigma_true": [float(x) for x in seg_sigma[i]],
                }
            )
            if "com_estimate_x" in m:
                segs[-1]["com_estimate"] = [_mean(m[f"com_estimate_{a}"][:, i], ok) for a in "xyz"]
                segs[-1]["com_true"] = _com_true(sc, i)
        acc = run.acc
        sums = acc.sum_e2 if hasattr(acc, "sum_e2") else acc[..., 0]
        total = np.sqrt(sums.sum(axis=1) / sc.n_samples)
        out[name] = {
            "rms_error": _mean(total, ok),
            "failed_trials": int(run.failed.sum()),
            "error": run.error or None,
            "engine": run.engine,
            "dropped_samples": None if run.dropped is None else int(run.dropped[ok].sum()),
            "skipped_samples_per_seed": None if run.skipped is None else [int(x) for x in run.skipped],
            "segments": segs,
        }
    _add_seed_statistics(res, out, per)
    _add_information_times(res, out)
    from adaptive_dd.benchmark.results import provenance

    return {
        "scenario": sc.source,
        "seeds": sc.seeds,
        "wall_time_s": res.wall_time,
        "provenance": provenance(res),
        "controllers": out,
    }


def _segment_sigmas(sc) -> np.ndarray:
    """True base parameters per segment ``(G, p)``."""
    from adaptive_dd.plant.serial_arm import SerialArm

    if isinstance(sc.arm, SerialArm):
        return sc.segment_sigmas()
    return np.array([sc.arm.sigma_with_payload(m, sc.payload_radius) for _, _, m in sc.segments()])


def _com_true(sc, i: int):
    """Centre of mass [m] of segment i's payload in the payload frame (None without payload)."""
    if i == 0 or sc.swap_masses[i - 1] == 0:
        return None
    com = sc.payload_of(i - 1).get("com")
    return [float(x) for x in com] if com is not None else [0.0, 0.0, 0.0]


def _seed_list(x: np.ndarray, ok: np.ndarray) -> list:
    return [float(v) if (good and np.isfinite(v)) else None for v, good in zip(x, ok, strict=True)]


def ratio_statistics(ratio: np.ndarray) -> dict | None:
    """Mean, median, p90, max, 95 % t-interval of the mean and worst seed of per-seed ratios.

    NaN entries (failed trials) are left out."""
    from scipy import stats

    idx = np.flatnonzero(np.isfinite(ratio))
    if idx.size == 0:
        return None
    r = ratio[idx]
    mean = float(r.mean())
    half = float(stats.t.ppf(0.975, r.size - 1) * r.std(ddof=1) / np.sqrt(r.size)) if r.size > 1 else np.nan
    return {
        "mean": mean,
        "median": float(np.median(r)),
        "p90": float(np.percentile(r, 90)),
        "max": float(r.max()),
        "ci95": [mean - half, mean + half] if np.isfinite(half) else None,
        "worst_seed": int(idx[np.argmax(r)]),
        "n": int(r.size),
    }


def _add_seed_statistics(res: BenchmarkResult, out: dict, per: dict) -> None:
    """Per-seed lists, ratios to each controller's floor, false alarms and detection delays."""
    sc = res.scenario
    per_seed = {}
    for name, run in res.runs.items():
        rms = per[name]["rms_error"].T  # (n_segments, n_seeds)
        per_seed[name] = rms
        for seg, r in zip(out[name]["segments"], rms, strict=True):
            seg["rms_error_per_seed"] = _seed_list(r, ~run.failed)
    for name, run in res.runs.items():
        floor = run.floor if run.floor in per_seed else None
        out[name]["floor"] = floor
        for i, seg in enumerate(out[name]["segments"]):
            seg["ratio_to_floor"] = None
            if floor is not None:
                with np.errstate(divide="ignore", invalid="ignore"):
                    ratio = per_seed[name][i] / per_seed[floor][i]
                seg["ratio_to_floor"] = ratio_statistics(np.where(np.isfinite(ratio), ratio, np.nan))
        if run.alarm_times is None:
            continue
        swaps = sc.swap_times
        false = [
            sum(1 for x in tr if not any(0 <= x - s < FALSE_ALARM_WINDOW for s in swaps))
            for tr in run.alarm_times
        ]
        out[name]["false_alarms_per_seed"] = [
            None if f else n for n, f in zip(false, run.failed, strict=True)
        ]
        ok = ~run.failed
        out[name]["trials_with_false_alarms"] = int(sum(1 for n, g in zip(false, ok, strict=True) if g and n))
        for seg, s in zip(out[name]["segments"][1:], swaps, strict=True):
            first = [
                min((x - s for x in tr if 0 <= x - s < FALSE_ALARM_WINDOW), default=None)
                for tr in run.alarm_times
            ]
            seg["detection_delay_per_seed"] = [d if g else None for d, g in zip(first, ok, strict=True)]


INFO_WINDOW = 1.0
"""[s] after a swap searched for the information-limited time."""


def mass_learning_time(m_hat: np.ndarray, mass: float, removed: float, T: float, rel: float = 0.05):
    """First time after which the estimated mass stays within ``rel`` of the truth (per row), NaN if never.

    ``rel`` is taken of the payload that changed (``max(mass, removed)``), so a removal is judged
    on the mass that left.
    """
    tol = rel * max(mass, removed)
    outside = np.abs(m_hat - mass) > tol  # (n, N)
    n = outside.shape[-1]
    last = np.where(outside.any(axis=-1), n - 1 - np.argmax(outside[..., ::-1], axis=-1), -1)
    return np.where(last < n - 1, (last + 1) * T, np.nan)


def _add_information_times(res: BenchmarkResult, out: dict) -> None:
    """Per swap: the time the information limit needs to know the payload mass within 5 %
    (first kept seed of a controller with recorded trajectories, the oracle's if present),
    beside the time each controller with an estimate took (median over the kept seeds)."""
    from adaptive_dd.identification.fisher import mass_information_time

    sc = res.scenario
    if not sc.swap_times:
        return
    from adaptive_dd.plant.serial_arm import SerialArm

    if isinstance(sc.arm, SerialArm):  # N joints: adaptive_dd.closed_loop.information
        from adaptive_dd.closed_loop.information import add_information_times

        add_information_times(res, out)
        return
    T = sc.sample_period
    ref = next(
        (
            r
            for n, r in sorted(res.runs.items(), key=lambda x: x[0] != "ct_oracle")
            if r.q is not None and r.q.shape[0]
        ),
        None,
    )
    segs = sc.segments()
    w = round(INFO_WINDOW / T)
    d = sc.arm.payload_direction(sc.payload_radius)
    for i in range(1, len(segs)):
        a, b, mass = segs[i]
        removed = segs[i - 1][2]
        k0 = int(np.ceil(a / T - 1e-9))
        k1 = min(round(b / T), k0 + w)
        info = {"known": None, "unknown": None}
        if ref is not None and not ref.failed[0] and max(mass, removed) > 0:
            for others in info:
                info[others] = mass_information_time(
                    ref.q[0, k0 - 1 : k1],
                    ref.qd[0, k0 - 1 : k1],
                    ref.tau[0, k0 - 1 : k1],
                    1,
                    T,
                    sc.arm.sigma_with_payload(mass, sc.payload_radius),
                    d,
                    sc.position_variance,
                    sc.velocity_variance,
                    mass=max(mass, removed),
                    others=others,
                )
        for name, run in res.runs.items():
            seg = out[name]["segments"][i]
            seg["information_time"] = info
            seg["mass_learning_time"] = None
            if run.sigma_hat is not None and run.sigma_hat.shape[0]:
                kept = ~run.failed[: run.sigma_hat.shape[0]]
                m_hat = sc.arm.payload_mass_from_sigma(run.sigma_hat[kept, k0 : round(b / T)])
                tl = mass_learning_time(m_hat, mass, removed, T)
                seg["mass_learning_time"] = None if np.all(np.isnan(tl)) else float(np.nanmedian(tl))
