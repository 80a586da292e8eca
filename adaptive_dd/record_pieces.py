"""A log as it comes: its gaps, its continuous pieces, several records fitted together.

Gaps
----
A logger that flushes or drops packets leaves steps in the time column far longer than the
others. A step is a **gap** when it lies beyond the log's own spread of steps: above Tukey's
far-out fence of the steps inside the window, ``Q3 + 3 IQR`` (Tukey, *Exploratory Data
Analysis*, 1977: the fence of a "far out" value; on a jittered clock such as the TIAGo's,
7.7-12.3 ms, it sits above the jitter), and at least 1.5 median steps (on a clock without
jitter the IQR is zero; one missing sample makes a step of two, so 1.5 is halfway between a
step and a missed sample). The threshold is derived from the record, not tuned: a log whose
steps are all alike has no gap.

A gap of **one missed sample** (a step of at most 2.5 median steps, halfway between one and two
missed) is bridged, not split: the positions' cubic spline and the torques' linear interpolation
run across it, as they run between any two samples of a jittered clock, and the line says how
many were bridged. Splitting there would cost more than the sample: each piece restarts the
derivative's window and the filters' settling (at 1 % single drops on a 200 Hz log with derived
velocities, a fifth of the samples). The interpolated torque of a missed sample is not the one
applied where the torque changes from sample to sample (a closed loop's feedback noise): there the
estimate moves by a few tenths of its std (``benchmarks/log_drops.py``, ``docs/real_log.md``).

The log is split at its other gaps (those of every file of the record) into its continuous pieces;
each is resampled onto its own uniform grid (the same period for all), and its velocities and
accelerations derived on their own, so that no spline, filter or derivative runs across a gap.
Left out: beside each gap, half the derivative's window (the Savitzky-Golay fit there is
one-sided); the identification then cuts each piece's first 10 ``tau_f`` (where its filters
have not settled, :func:`adaptive_dd.identification.regression.filter_pieces`). A piece too
short to leave any sample once those are cut is left out and named (:func:`drop_short`).

Several records
---------------
Records of one arm (several trajectories, or the pieces of one log) are fitted together as the
pieces of one :class:`~adaptive_dd.record.LogRecord` (:func:`merge_records`), as FIGAROH and
MATLAB's System Identification Toolbox (``merge`` of ``iddata`` experiments) do: one set of
parameters, one weighting of the channels, the covariance's autocovariances summed within each
piece only.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.errors import DataError

if TYPE_CHECKING:
    from adaptive_dd.record_spec import RecordSpec

__all__ = [
    "MAX_LOG_STEP",
    "check_overlap",
    "clock",
    "drop_short",
    "find_gaps",
    "first_clock",
    "gap_threshold",
    "likely_unit",
    "merge_records",
    "piece_spans",
    "resampler",
    "trim_gap_edges",
]

Array = NDArray[np.float64]
FAR_OUT = 3.0
"""Tukey's far-out fence: ``Q3 + 3 IQR``."""
MIN_GAP_STEPS = 1.5
"""A gap is at least this many median steps (halfway between one step and one missed sample)."""
BRIDGE_STEPS = 2.5
"""A gap of at most this many median steps (one missed sample: a step of two, halfway to two missed)
is bridged by the interpolation, not split."""
MIN_PIECE_SAMPLES = 7
"""Fewest samples a piece needs on its grid (the shortest Savitzky-Golay window)."""


def clock(t: float) -> str:
    """A time stamp [s] as messages print it: 6 significant digits below 1000 s, to the microsecond
    beyond (an uptime or an epoch clock: seconds since 1970 read 1.7e+09 at every stamp of a log)."""
    t = float(t)
    return f"{t:.6g}" if abs(t) < 1e3 else f"{t:.6f}".rstrip("0").rstrip(".")


def gap_threshold(steps: Array) -> float:
    """[s] The longest step that is not a gap: ``max(Q3 + 3 IQR, 1.5 median)`` of ``steps``."""
    q1, med, q3 = np.percentile(steps, [25, 50, 75])
    return float(max(q3 + FAR_OUT * (q3 - q1), MIN_GAP_STEPS * med))


def find_gaps(t: Array) -> tuple[NDArray[np.int64], float]:
    """The indices ``i`` of the gaps ``t[i] -> t[i + 1]`` of an increasing clock and the threshold."""
    steps = np.diff(t)
    limit = gap_threshold(steps)
    return np.flatnonzero(steps > limit), limit


def check_overlap(clocks: dict, lo: float, hi: float, T: float) -> None:
    """A :class:`~adaptive_dd.errors.DataError` when the files' clocks (``{file: times}``, the
    rows read) share less than :data:`MIN_PIECE_SAMPLES` samples: two clocks, or two units (one
    relative, one an epoch; one in s, one in ms), named with each file's span."""
    if len(clocks) > 1 and hi - lo < MIN_PIECE_SAMPLES * T:
        each = "; ".join(f"{p} {clock(t[0])}-{clock(t[-1])} s" for p, t in clocks.items())
        raise DataError(
            f"the files' time spans do not overlap ({each}): are their clocks the same one, in the same "
            "unit (one relative, one an epoch; one in s, one in ms)? Shift or convert one file's time column"
        )


def piece_spans(clocks: dict, lo: float, hi: float) -> tuple[list[tuple[float, float]], list[str]]:
    """The continuous time spans ``[(a, b), ...]`` of ``[lo, hi]`` between the gaps of every file's
    clock (``{path: t}``, each the window's logged times), and the report's lines: one per gap split
    at, one for the gaps of one missed sample bridged (:data:`BRIDGE_STEPS`)."""
    found: dict = {}  # (start, end) -> (files, limit, median step)
    for path, t in clocks.items():
        idx, limit = find_gaps(t)
        med = float(np.median(np.diff(t)))
        for i in idx:
            key = (float(t[i]), float(t[i + 1]))
            found.setdefault(key, ([], limit, med))[0].append(str(path))
    gaps, lines, bridged = [], [], []
    for a, b in sorted(found):
        files, limit, med = found[(a, b)]
        if b - a <= BRIDGE_STEPS * med:
            bridged.append(files)
            continue
        gaps.append((a, b))
        lines.append(
            f"a gap of {b - a:.4g} s at {clock(a)}-{clock(b)} s ({(b - a) / med:.3g} median steps) in "
            f"{', '.join(files)} (a gap: a step above {limit:.4g} s, max(Q3 + 3 IQR, 1.5 median) of the "
            "log's steps)"
        )
    if bridged:
        where = sorted({f for files in bridged for f in files})
        lines.append(
            f"bridged {len(bridged)} gap(s) of one missed sample (a step of at most {BRIDGE_STEPS:g} median "
            f"steps) in {', '.join(where)}: interpolated across, not split"
        )
    spans, start = [], lo
    for a, b in gaps:
        if a > start:
            spans.append((start, a))
        start = max(start, b)
    if hi > start:
        spans.append((start, hi))
    return spans, lines


def merge_records(records: list, names: list[str] | None = None):
    """Several :class:`~adaptive_dd.record.LogRecord` of one arm as one, their pieces end to end.

    The records must share the sample period (within 0.1 %: read them with one ``sample_period``),
    the velocity's source and the torque channels' treatment; a channel is fitted when it is in
    every record (the others named in a note). ``names`` label each record in the notes.

    Raises
    ------
    DataError
        Naming the record whose sample period or velocity source differs.
    """
    first = records[0]
    if len(records) == 1:
        return first
    names = names or [r.source for r in records]
    for r, nm in zip(records[1:], names[1:], strict=True):
        if abs(r.sample_period - first.sample_period) > 1e-3 * first.sample_period:
            raise DataError(
                f"{nm}: sample period {r.sample_period:.6g} s, the first record's "
                f"{first.sample_period:.6g} s: records fitted together share one period (set [record] "
                "sample_period in each)"
            )
        if r.qd_measured != first.qd_measured:
            raise DataError(
                f"{nm}: velocities {'measured' if r.qd_measured else 'derived'}, the first record's "
                f"{'measured' if first.qd_measured else 'derived'}: give every record the same "
                "velocity_source"
            )
    used = np.logical_and.reduce([r.used for r in records])
    if not used.any():
        raise DataError(f"{', '.join(names)}: no torque channel is fitted in every record")
    notes = []
    for r, nm in zip(records, names, strict=True):
        notes += [f"[{nm}] {x}" for x in r.notes]
        if (r.used & ~used).any():
            notes.append(
                f"[{nm}] its channels {np.flatnonzero(r.used & ~used).tolist()} not fitted: not in every "
                "record"
            )
    pieces, owner, offset = [], [], 0
    for i, r in enumerate(records):
        for a, b in r.spans:
            pieces.append((a + offset, b + offset))
            owner.append(i)
        offset += r.t.size
    return dataclasses.replace(  # a LogRecord like the first (no import of adaptive_dd.record: a circle)
        first,
        t=np.concatenate([r.t for r in records]),
        q=np.concatenate([r.q for r in records]),
        qd=np.concatenate([r.qd for r in records]),
        tau=np.concatenate([r.tau for r in records]),
        used=used,
        weight=first.weight.copy(),
        source="; ".join(names),
        notes=tuple(notes),
        simulator_format=all(r.simulator_format for r in records),
        pieces=tuple(pieces),
        piece_record=tuple(owner),
        record_names=tuple(names),
    )


def drop_short(rec, settle: int):
    """``rec`` without the pieces too short to use, and one line per piece left out.

    A piece is too short when it holds no sample once its first ``settle`` samples (the
    filters' settling, ``ceil(10 tau_f / T)``) are cut.

    Raises
    ------
    DataError
        Every piece is too short (each named with its start, end and why).
    """
    keep, lines = [], []
    for i, (a, b) in enumerate(rec.spans):
        if b - a > settle:
            keep.append(i)
            continue
        lines.append(
            f"{rec.piece_label(i)}: the piece {clock(rec.t[a])}-{clock(rec.t[b - 1])} s ({b - a} samples) "
            f"is too short to use: the filters settle over its first {settle} samples "
            f"({settle * rec.sample_period:.3g} s = 10 tau_f): left out"
        )
    if not keep:
        raise DataError("no piece of the record is long enough to use: " + "; ".join(lines))
    if len(keep) == len(rec.spans):
        return rec, lines
    rows = np.concatenate([np.arange(*rec.spans[i]) for i in keep])
    pieces, at = [], 0
    for i in keep:
        a, b = rec.spans[i]
        pieces.append((at, at + b - a))
        at += b - a
    owner = tuple(rec.piece_record[i] for i in keep) if rec.piece_record else ()
    out = dataclasses.replace(
        rec,
        t=rec.t[rows],
        q=rec.q[rows],
        qd=rec.qd[rows],
        tau=rec.tau[rows],
        pieces=tuple(pieces),
        piece_record=owner,
    )
    return out, lines


def trim_gap_edges(pieces, qd_measured: bool, T: float, short, derivative_window: float = 0.1) -> tuple:
    """The samples kept (``(N',)`` indices), the pieces after the cut and notes: beside each gap, half
    the derivative's window left out when the velocities are derived (its fit is one-sided there)."""
    h = 0 if qd_measured else max(7, 2 * round(derivative_window / T / 2) + 1) // 2
    keep, out, at = [], [], 0
    for i, (a, b) in enumerate(pieces):
        lo = a + (h if i > 0 else 0)
        hi = b - (h if i < len(pieces) - 1 else 0)
        keep.append(np.arange(lo, max(lo, hi)))
        out.append((at, at + max(0, hi - lo)))
        at += max(0, hi - lo)
    each = (
        f"resampled and differentiated on its own; left out: {h} samples ({h * T:.3g} s, half the "
        "derivative's window) beside each gap"
        if h
        else "resampled on its own"  # velocities measured: nothing differentiated, nothing left out
    )
    notes = [
        f"split at the gaps into {len(pieces)} continuous piece{'s' if len(pieces) > 1 else ''}, each {each}"
    ]
    notes += [
        f"the piece {clock(a)}-{clock(b)} s is too short to use (under {MIN_PIECE_SAMPLES} samples): left out"
        for a, b in short
    ]
    return np.concatenate(keep), tuple((a, b) for a, b in out if b > a), tuple(notes)


def resampler(frames: dict, where: dict, clocks: dict, rows: dict, grids: list, numeric):
    """``column(name, spline)``: a logged column in the window, checked, on each piece's grid (spline or
    linear through that file's samples of the piece, and one step either side), the pieces end to end;
    ``numeric(path, frame, column, rows)`` reads a column, checked."""
    from scipy.interpolate import CubicSpline

    def column(col: str, spline: bool) -> Array:
        p = where[col]
        r = rows[p]
        v = numeric(p, frames[p], col, r)[r]
        tt = clocks[p][r]
        step = float(np.median(np.diff(tt)))
        out = []
        for g in grids:
            m = (tt >= g[0] - step) & (tt <= g[-1] + step)
            out.append(CubicSpline(tt[m], v[m])(g) if spline else np.interp(g, tt[m], v[m]))
        return np.concatenate(out)

    return column


MAX_LOG_STEP = 0.1
"""[s] The largest median time step a log is read with (10 Hz: coarser, the derivatives' 7-sample
window spans most of a second); a coarser one is a time column in another unit (``[record]
time_unit``): a 1 kHz log stamped in ms steps by exactly 1."""


def likely_unit(step: float, as_period: bool = False) -> str:
    """The time unit (ms, us or ns) that makes a median stamp step of ``step`` (in the column's own
    numbers) a robot's sample period: of those within :data:`MAX_LOG_STEP`, the nearest 1 ms (ns
    when none is); ``as_period``: that period in s, as text."""
    from adaptive_dd.record_spec import TIME_UNITS

    fit = [u for u in ("ms", "us", "ns") if step * TIME_UNITS[u] <= MAX_LOG_STEP]
    unit = min(fit, key=lambda u: abs(np.log10(max(step * TIME_UNITS[u], 1e-300) / 1e-3)), default="ns")
    return f"{step * TIME_UNITS[unit]:.4g} s" if as_period else unit


def first_clock(spec: RecordSpec, clocks: dict, rows: dict) -> tuple[Array, float]:
    """The first file's times in the window and the sample period: given, else the mean step
    between its gaps (:func:`~adaptive_dd.record_pieces.find_gaps`; jitter averages out)."""
    first = spec.files[0]
    t0 = clocks[first][rows[first]]
    steps = np.diff(t0)
    gaps, _ = find_gaps(t0)
    ok = np.ones(steps.size, dtype=bool)
    ok[gaps] = False
    for p in (first, *(f for f in clocks if f != first)):  # every file: one may be stamped in ms
        d = np.diff(clocks[p][rows[p]])
        median = float(np.median(d)) if d.size else 0.0
        if median > MAX_LOG_STEP:
            break
    raw = median / spec.time_scale  # the step in the column's own numbers (time_unit undone)
    if median > MAX_LOG_STEP:  # with sample_period given too: the grid is in s, the stamps are not
        unit = (
            f'say so: [record] time_unit = "{likely_unit(raw)}"'
            if p == first
            else ("convert its time column to the first file's unit ([record] time_unit is every file's)")
        )
        raise DataError(
            f"{p}: the time column {spec.time!r} steps by {median:.6g} per sample (median), read as "
            f"s: a robot's log samples faster than every {MAX_LOG_STEP:g} s. If its time is in "
            f"{likely_unit(raw)} (a step of {likely_unit(raw, True)}), {unit}; a log truly slower "
            f"than {1 / MAX_LOG_STEP:g} Hz is too coarse for the accelerations this identification derives"
        )
    return t0, spec.sample_period or float(np.mean(steps[ok]))
