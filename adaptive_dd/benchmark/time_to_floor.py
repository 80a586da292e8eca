"""How long a controller takes to come within a factor of its floor in the first segment.

Before the first swap an adaptive controller learns what its model lacks (the arm's own error
on a plant that is not its URDF); the ratio of its RMS error to the floor's over that whole
segment mixes the learning transient with the settled tracking. The benchmark also prints how
long the transient lasts.

**Definition.** Per seed (common random numbers: the controller and its floor meet the same
noise and plant), with ``|e|`` the norm of the tracking error on the true joint angles:

* ``r(k) = rms_c(k) / rms_f(k)``, the ratio of the *causal moving RMS* of ``|e|`` over
  :data:`WINDOW` (0.25 s; over the samples so far during the segment's first window) of the
  controller (``c``) and of its floor (``f``), at every sample ``k`` of the segment;
* the time to the floor is ``(k* + 1) T`` measured from the segment's start, where ``k*`` is the
  last sample with ``rms_c(k) > LEVEL rms_f(k)`` (:data:`LEVEL` = 1.2): the earliest time from
  which the windowed ratio stays within 1.2 to the segment's end; 0 when it never exceeds 1.2;
* **never** (``inf``) when the last window of the segment still exceeds it: the controller was
  not within 1.2x of its floor by the first swap.

Over the seeds: the median, p90 and max (linear interpolation between order statistics, as
:func:`numpy.percentile`; a "never" seed counts as later than every time, so a statistic that
reaches one is "never"), and the number of "never" seeds.
"""

from __future__ import annotations

import math

import numpy as np

from adaptive_dd.benchmark.segments import moving_rms, segment_failed

__all__ = [
    "LEVEL",
    "WINDOW",
    "add_time_to_floor",
    "first_segment_norm",
    "per_seed_time_to_floor",
    "quantile_never",
    "time_to_floor",
    "time_to_floor_stats",
]

WINDOW = 0.25
"""[s] Length of the moving RMS windows compared with the floor's."""
LEVEL = 1.2
"""The factor of the floor the windowed RMS error must stay within."""


def time_to_floor(
    e: np.ndarray, e_floor: np.ndarray, T: float, window: float = WINDOW, level: float = LEVEL
) -> np.ndarray:
    """Per seed: the time [s] from the segment's start after which the moving RMS of ``|e|``
    stays within ``level`` times the floor's to the segment's end (module docstring).

    Parameters
    ----------
    e, e_floor : ndarray (n_seeds, n_samples)
        ``|e|`` [rad] over the segment, of the controller and of its floor, seed by seed.
    T : float
        Sample period [s].

    Returns
    -------
    ndarray (n_seeds,)
        Seconds; ``inf``: never (the segment's last window is above); NaN where either input
        has a non-finite sample (a failed trial).
    """
    e, e_floor = np.asarray(e, float), np.asarray(e_floor, float)
    if e.shape != e_floor.shape or e.ndim != 2:
        raise ValueError(
            f"time_to_floor: e {e.shape} and e_floor {e_floor.shape} must be equal (seeds, samples)"
        )
    n = max(1, round(window / T))
    above = moving_rms(e, n) > level * moving_rms(e_floor, n)  # 0 > 0 at the start: not above
    N = e.shape[1]
    last = np.where(above.any(axis=1), N - 1 - np.argmax(above[:, ::-1], axis=1), -1)
    out = np.where(last == N - 1, np.inf, (last + 1) * T)
    bad = ~(np.isfinite(e).all(axis=1) & np.isfinite(e_floor).all(axis=1))
    return np.where(bad, np.nan, out)


def quantile_never(x: np.ndarray, q: float) -> float:
    """The ``q``-th percentile of ``x`` (finite values and ``inf`` for never; NaN left out) by
    linear interpolation between order statistics; ``inf`` when it reaches a never."""
    v = np.sort(np.asarray(x, float)[~np.isnan(x)])
    if v.size == 0:
        return math.nan
    h = (v.size - 1) * q / 100.0
    lo, hi = math.floor(h), math.ceil(h)
    w = h - lo
    if w == 0.0 or v[lo] == v[hi]:
        return float(v[lo])
    if np.isinf(v[hi]):
        return math.inf
    return float(v[lo] + w * (v[hi] - v[lo]))


def _json_time(t: float) -> float | str | None:
    """A time for JSON: seconds, ``"never"`` (inf) or None (NaN: failed)."""
    if np.isnan(t):
        return None
    return "never" if np.isinf(t) else float(t)


def time_to_floor_stats(times: np.ndarray, seeds, segment_length: float) -> dict:
    """The JSON block of one controller: ``window``, ``level``, ``segment_length`` [s],
    ``per_seed`` (seconds, ``"never"``, or None for a failed trial), ``median``, ``p90``, ``max``
    (seconds or ``"never"``; None without a kept seed), ``never`` (count), ``n`` (seeds counted)
    and ``seeds`` (the seed index of each entry of ``per_seed``)."""
    t = np.asarray(times, float)
    ok = ~np.isnan(t)
    stat = {k: _json_time(quantile_never(t, q)) for k, q in (("median", 50.0), ("p90", 90.0), ("max", 100.0))}
    return {
        "window": WINDOW,
        "level": LEVEL,
        "segment_length": float(segment_length),
        "per_seed": [_json_time(x) for x in t],
        "seeds": [int(s) for s in seeds],
        **stat,
        "never": int(np.isinf(t[ok]).sum()),
        "n": int(ok.sum()),
    }


def first_segment_norm(res, run) -> np.ndarray | None:
    """``(n_seeds, n_samples)`` of ``|e|`` over the first segment: from the run, or from
    ``res.cache`` where :func:`~adaptive_dd.benchmark.metrics.release_error_norm` kept it."""
    key = ("first_segment_norm", run.name)
    if key in res.cache:
        return res.cache[key]
    end = _first_end(res)
    if run.e_norm is None or run.e_norm.shape[0] != run.failed.shape[0] or run.e_norm.shape[1] < end:
        return None
    return run.e_norm[:, :end]


def _first_end(res) -> int:
    """The first segment's end sample (exclusive)."""
    sc = res.scenario
    if sc.closed_forms is None:
        from adaptive_dd.closed_loop.types import run_constants

        return int(run_constants(sc).seg_end[0])
    from adaptive_dd.benchmark.streaming import SETTLE, segment_bounds

    return int(segment_bounds(sc.segments(), sc.sample_period, SETTLE)[1][0])


def per_seed_time_to_floor(res, run) -> np.ndarray | None:
    """``(n_seeds,)`` the first segment's time to the floor of ``run`` (:func:`time_to_floor`; NaN
    for a trial that failed within the first segment, either controller's, by the benchmark's one
    rule :func:`~adaptive_dd.benchmark.metrics.segment_failed`); None without a floor that ran,
    or without the error norms."""
    floor = res.runs.get(run.floor) if run.floor != run.name else None
    if floor is None or run.error or floor.error:
        return None
    e, ef = first_segment_norm(res, run), first_segment_norm(res, floor)
    if e is None or ef is None:
        return None
    t = time_to_floor(e, ef, res.scenario.sample_period)
    for r in (run, floor):
        t[segment_failed(r.failed, r.failed_at, [e.shape[1]])[:, 0]] = np.nan
    return t


def add_time_to_floor(res, out: dict) -> None:
    """``out[name]["segments"][0]["time_to_floor"]`` (:func:`time_to_floor_stats`) for every
    controller whose floor ran."""
    sc = res.scenario
    seeds = res.seed_indices or tuple(range(sc.seeds))
    for name, run in res.runs.items():
        t = per_seed_time_to_floor(res, run)
        if t is not None:
            length = _first_end(res) * sc.sample_period
            out[name]["segments"][0]["time_to_floor"] = time_to_floor_stats(t, seeds, length)
