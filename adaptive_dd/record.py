"""A real robot's log as identification reads it: the ``[record]`` table of a scenario.

A log from a robot is rarely the ``t, q1..qN, qd1..qdN, tau1..tauN`` file the simulator
writes: several files, the vendor's column names, jittered time stamps, raw motor efforts,
degrees, a gear ratio, channels that carry nothing. The ``[record]`` table of an
identification scenario (the same file as its ``[arm]``) says how to read it::

    [record]
    files = ["tiago_position.csv", "tiago_velocity.csv", "tiago_effort.csv"]  # beside the scenario
    time = "t"                               # the time column of every file [s]
    position = "- {joint}_position"          # {joint}: the URDF's joint name; {i}: 1, 2, ...
    velocity = "- {joint}_velocity"          # optional: measured velocity columns
    torque = "- {joint}_effort"              # torque or raw effort columns
    velocity_source = "derived"              # "measured" or "derived" (from the positions)
    torque_gain = [1, 13.6, 13.6, -8.7, ...] # tau = sign * gain * effort + offset, per joint
    torque_sign = [1, 1, ...]                # optional, default 1
    torque_offset = [0, 0, ...]              # optional [N m], default 0
    position_unit = "rad"                    # or "deg" (prismatic joints in m), or one per joint
                                             # ("rad", "deg", "m", "mm")
    gear_ratio = [1, 1, ...]                 # optional: motor-side positions / velocities
    exclude = ["torso_lift_joint", "arm_5_joint"]   # torque channels left out of the fit
    torque_weight = [1, 1, 0.5, ...]         # optional: multiplies each channel's weight (0: exclude)
    torque_held = true                       # a command held over each sample (default), or false:
                                             # samples of a continuous torque (a torque sensor)
    window = [9.21, 67.9]                    # optional [s] of the log's clock
    sample_period = 0.01                     # optional: the grid to resample to [s]

Column names may also be lists, one per joint. Without a ``[record]`` table a file has the
simulator's columns (``position = "q{i}"``, ``velocity = "qd{i}"``, ``torque = "tau{i}"``).

Sample times
------------
The filters of the identification run at one sample period, so the log is **resampled**
onto a uniform grid (the mean logged step unless ``sample_period`` is given, starting at
the window's first logged time): positions by a cubic spline through the logged samples
(``scipy.interpolate.CubicSpline``, not-a-knot), measured velocities and torques by linear
interpolation (they are held values). Each file is resampled from its own time column.
Derived velocities (and accelerations, for prediction) are Savitzky-Golay derivatives of the
resampled positions (cubic, window about 0.1 s: :func:`derivatives`). A log with gaps (the
logger's flushes, dropped packets) is split at them into continuous pieces, each resampled and
differentiated on its own (:mod:`adaptive_dd.record_pieces`: how a gap is told from jitter, what
is left out beside it).

A row with an empty, non-numeric or non-finite cell in a column the fit reads (the time, a
position, a fitted torque, a velocity) is a sample the logger missed: it is left out, and the
gaps' rules then bridge it or split the log there, as they do a missing row; the notes name the
file, the count and the first lines. More than :data:`MAX_BAD_ROWS` of a file's rows in the window
is not a logger's missed samples but a column of another kind, or a broken export: refused.

What is refused, with the file, line or column and the remedy: a missing column, non-numeric or
non-finite values in more than :data:`MAX_BAD_ROWS` of the rows, a time that does not increase (a
duplicated stamp), a torque channel
stuck at one value on more than half the window (exclude it), a revolute position whose
range does not fit the URDF's limits in radians but does in degrees (set ``position_unit``), a
measured velocity the fit uses whose gain on its position's derivative is outside
:data:`~adaptive_dd.record_checks.VELOCITY_GAIN` (another unit), a fitted torque beyond
:data:`~adaptive_dd.record_checks.TORQUE_LIMIT_FACTOR` times the URDF's effort limit (mN m, a gain
missing): :mod:`adaptive_dd.record_checks`.
"""

from __future__ import annotations

import difflib
import itertools
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.errors import DataError
from adaptive_dd.record_checks import (
    _check_stuck,
    _check_torque_scale,
    _check_units,
    _check_velocity_scale,
    _line,
    _no_time_stamps,
    _too_many_bad_rows,
    stale_notes,
    velocity_gains,
)
from adaptive_dd.record_csv import read_csv
from adaptive_dd.record_derivatives import derivatives
from adaptive_dd.record_pieces import (
    MAX_LOG_STEP,
    MIN_PIECE_SAMPLES,
    check_overlap,
    clock,
    first_clock,
    likely_unit,
    piece_spans,
    resampler,
    trim_gap_edges,
)
from adaptive_dd.record_spec import RecordSpec, record_spec, zero_based_hint

__all__ = ["LogRecord", "RecordSpec", "derivatives", "read_log", "record_spec"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class LogRecord:
    """A log on a uniform grid, in rad (m) and N m.

    Attributes
    ----------
    t : ndarray (N,)
        [s], the log's clock.
    q, qd, tau : ndarray (N, n)
    qd_measured : bool
        ``qd`` is the measured velocity (else derived from ``q``).
    used : ndarray of bool (n,)
        Torque channels in the fit.
    weight : ndarray (n,)
        Their weight multipliers (``torque_weight``).
    sample_period : float
    source : str
        The file(s).
    notes : tuple of str
        How it was read (resampling, jitter), for the report.
    simulator_format : bool
        Read as the simulator writes records (no ``[record]`` table).
    pieces : tuple of (int, int)
        The continuous pieces ``[a, b)`` of the arrays, each on its own uniform grid (a log split at
        its gaps, several records end to end: :mod:`adaptive_dd.record_pieces`); empty: one piece.
    piece_record : tuple of int
        The record each piece comes from (an index into ``record_names``); empty: one record.
    record_names : tuple of str
        The records' names (their files), when several.
    """

    t: Array
    q: Array
    qd: Array
    tau: Array
    qd_measured: bool
    used: NDArray[np.bool_]
    weight: Array
    sample_period: float
    source: str
    notes: tuple[str, ...] = ()
    simulator_format: bool = False
    pieces: tuple[tuple[int, int], ...] = ()
    piece_record: tuple[int, ...] = ()
    record_names: tuple[str, ...] = ()

    @property
    def spans(self) -> tuple[tuple[int, int], ...]:
        """The continuous pieces ``[a, b)`` (one, the whole record, when it has no gap)."""
        return self.pieces or ((0, self.t.size),)

    def piece_label(self, i: int) -> str:
        """The record piece ``i`` comes from (its files)."""
        return self.record_names[self.piece_record[i]] if self.piece_record else self.source


def _locate(frames: dict, spec: RecordSpec, wanted: list[str]) -> dict:
    """``{column: file}`` for every wanted column; a missing one is named with near matches."""
    where = {}
    for col in wanted:
        hits = [p for p, f in frames.items() if col.strip() in f.columns]
        if not hits:
            every = [c for f in frames.values() for c in f.columns]
            named = {c.strip() for c in wanted}  # columns the description gives another use: no match
            near = difflib.get_close_matches(col.strip(), [c for c in every if c not in named], n=3)
            n = len(spec.position)
            whence = (
                f"the simulator's format of the {n}-joint arm of {spec.source} (t, q1..q{n}, qd1..qd{n}, "
                f"tau1..tau{n}; a log of another shape is described by a [record] table)"
                if spec.simulator_format
                else f"from [record] of {spec.source}"
            )
            listed = ", ".join(map(repr, every[:12])) + (
                f", ... ({len(every)} in all)" if len(every) > 12 else ""
            )
            raise DataError(
                f"{', '.join(str(p) for p in frames)}: no column {col!r} ({whence})"
                + (f"; near matches: {near}" if near else f"; columns: {listed}")
                + zero_based_hint(spec, col.strip(), every)
            )
        where[col] = hits[0]
    return where


def _coerced(frame, col: str) -> Array:
    """A column as floats, NaN where a cell is not a number."""
    import pandas as pd

    return pd.to_numeric(frame[col], errors="coerce").to_numpy(dtype=float)


def _numeric(path: Path, frame, col: str, rows: slice) -> Array:
    v = _coerced(frame, col)
    raw = frame[col].to_numpy()
    bad = np.flatnonzero(~np.isfinite(v[rows])) + (rows.start or 0)
    if bad.size:
        i = int(bad[0])
        breaks = np.flatnonzero(np.diff(bad) != 1)
        run = bad[breaks[0]] if breaks.size else bad[-1]
        kind = "not a number" if isinstance(raw[i], str) else "non-finite value"
        cell = raw[i].item() if isinstance(raw[i], np.generic) else raw[i]  # nan, not np.float64(nan)
        first, last = _line(frame, i), _line(frame, int(run))
        lines = f"line {first}" if run == i else f"lines {first}-{last}"
        raise DataError(
            f"{path}: {lines}, column {col!r}: {kind} ({cell!r}; {bad.size} such row(s) in the window, "
            f"more than the {MAX_BAD_ROWS:.0%} of its rows left out as missed samples): is the column the "
            "one meant? Else cut the window to avoid them ([record] window or --window) or repair the file"
        )
    return v


def _leave_out_bad_rows(frames: dict, where: dict, spec: RecordSpec, fitted: list[str], window):
    """``frames`` without the rows whose time or fitted column (``fitted``, in ``where``'s file) is not
    a finite number, where those are at most :data:`MAX_BAD_ROWS` of a file's rows in the window
    (rows outside it are left out only for a bad time, which places them nowhere); and the notes.
    A file with more is returned whole: :func:`_numeric` then refuses it, naming the first cell."""
    out, notes = {}, []
    for p, f in frames.items():
        if spec.time not in f.columns:
            out[p] = f  # _times names it
            continue
        t = _coerced(f, spec.time) * spec.time_scale
        finite_t = np.isfinite(t)
        if not finite_t.any():  # nothing to place in time: say why, not an empty record later
            raise _no_time_stamps(p, f, spec.time)
        bad = ~finite_t
        bad_of = {spec.time: ~finite_t}  # per column read of this file: its bad rows (the time's first)
        for c in fitted:
            if where[c] == p:
                bad_of[c] = ~np.isfinite(_coerced(f, c))
                bad |= bad_of[c]
        lo, hi = (-np.inf, np.inf) if window is None else window
        inside = np.flatnonzero(finite_t & (t >= lo) & (t <= hi))
        in_window = np.zeros(len(f), dtype=bool)
        if inside.size:
            in_window[inside[0] : inside[-1] + 1] = True  # a row of no time between two in the window too
        drop = bad & in_window | ~finite_t
        n_in = int(np.sum(bad & in_window))
        if n_in > MAX_BAD_ROWS * max(int(in_window.sum()), 1):
            raise _too_many_bad_rows(
                p, f, {c: b & in_window for c, b in bad_of.items()}, n_in, in_window, MAX_BAD_ROWS, spec
            )
        if not drop.any():
            out[p] = f
            continue
        lines = [_line(f, int(i)) for i in np.flatnonzero(drop)[:5]]
        more = ", ..." if drop.sum() > 5 else ""
        out[p] = f[~drop]  # each row keeps its index: its line in the file (_line)
        out[p].attrs.update(f.attrs)
        cols = [repr(c) for c, b in bad_of.items() if (b & drop).any()]
        notes.append(
            f"{p}: {int(drop.sum())} row(s) with an empty, non-numeric or non-finite cell in a column the "
            f"fit reads ({', '.join(cols)}) left out as samples the logger missed (line(s) "
            f"{', '.join(map(str, lines))}{more})"
        )
    return out, notes


def _times(path: Path, frame, col: str) -> Array:
    if col not in frame.columns:
        raise DataError(
            f"{path}: no time column {col!r} (set [record] time); columns: {list(frame.columns)[:12]}"
        )
    t = _numeric(path, frame, col, slice(0, len(frame)))
    dt = np.diff(t)
    bad = np.flatnonzero(dt <= 0)
    if bad.size:
        i = int(bad[0])
        what = "repeats" if dt[i] == 0 else "goes back from"
        raise DataError(
            f"{path}: line {_line(frame, i + 1)}, column {col!r}: time {float(t[i + 1])!r} {what} line "
            f"{_line(frame, i)}'s {float(t[i])!r} "
            f"({bad.size} such step(s)): a duplicated or reordered sample; remove or reorder those rows"
        )
    return t


def _window_rows(path: Path, t: Array, window, time_scale: float = 1.0) -> slice:
    lo, hi = (t[0], t[-1]) if window is None else window
    if window is not None and not lo < hi:
        raise DataError(f"{path}: the window [{clock(lo)}, {clock(hi)}] s: its start must be before its end")
    i0, i1 = int(np.searchsorted(t, lo)), int(np.searchsorted(t, hi, side="right"))
    if i1 - i0 < 20:
        step = float(np.median(np.diff(t))) if t.size > 1 else 0.0
        likely = likely_unit(step / time_scale)  # from the column's own numbers
        unit = (
            f"; its stamps step by {step:.6g} s per sample (median): if they are in {likely}, say so "
            f'([record] time_unit = "{likely}"; the window stays in s)'
            if step > MAX_LOG_STEP
            else ""
        )
        if window is not None and t.size and hi < t[0] and abs(t[0]) >= 1e3:  # a window from the log's start
            unit += (
                f"; the window is in the log's own clock, which starts at {clock(t[0])} s: the same window "
                f"from its start is --window {clock(t[0] + lo)} {clock(t[0] + hi)}"
            )
        raise DataError(
            f"{path}: the window [{clock(lo)}, {clock(hi)}] s holds {max(i1 - i0, 0)} samples (the log spans "
            f"{clock(t[0])}-{clock(t[-1])} s): need at least 20{unit}"
        )
    return slice(i0, i1)


def read_log(spec: RecordSpec, window: tuple[float, float] | None = None, arm=None) -> LogRecord:
    """Read, check, convert and resample a log (module docstring).

    Parameters
    ----------
    spec : RecordSpec
    window : (float, float), optional
        Replaces ``spec.window`` [s].
    arm : Arm, optional
        For the unit check against the URDF's position limits.


    Returns
    -------
    LogRecord
        The log on a uniform grid of the spec's period: positions, velocities, torques and what
        was done to them (``notes``).


    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> import numpy as np
    >>> from adaptive_dd.record import read_log, record_spec
    >>> folder = Path(tempfile.mkdtemp())
    >>> t = np.arange(0.0, 2.0, 0.01)
    >>> np.savetxt(folder / "log.csv", np.column_stack([t, np.sin(t), np.cos(t), 3 * np.sin(t), np.cos(t)]),
    ...            delimiter=",", header="t,q1,q2,tau1,tau2", comments="")
    >>> spec = record_spec({"files": [str(folder / "log.csv")], "time": "t", "position": "q{i}",
    ...                     "torque": "tau{i}", "velocity_source": "derived"},
    ...                    joint_names=["joint1", "joint2"], kinds=["revolute", "revolute"],
    ...                    src="arm.toml")
    >>> log = read_log(spec)
    >>> log.q.shape, log.qd.shape, log.sample_period  # velocities derived from the positions
    ((200, 2), (200, 2), 0.01)

    Raises
    ------
    DataError
        Naming the file, line or column and the remedy.
    """
    window = window if window is not None else spec.window
    frames = {p: read_csv(p) for p in spec.files}
    velocity = spec.velocity

    def present(c: str) -> bool:
        return any(c in f.columns for f in frames.values())

    skipped = []  # columns named but not needed and absent: said, not an error
    if spec.simulator_format and velocity and not present(velocity[0]):
        velocity = None  # the simulator's format: velocity columns optional
    elif velocity and spec.derive_velocity and not all(map(present, velocity)):
        skipped.append(  # derived from the positions: the logged ones only compared, when all there
            f"velocity columns {[c for c in velocity if not present(c)]} are not in the files: the "
            "velocities are derived from the positions (velocity_source = 'derived'), with no logged ones to "
            "compare"
        )
        velocity = None
    absent = {
        spec.torque[j] for j in range(len(spec.torque)) if not spec.used[j] and not present(spec.torque[j])
    }
    if absent:
        skipped.append(
            f"torque column(s) {sorted(absent)} of excluded joint(s) are not in the files: those channels "
            "are read as 0 (not fitted)"
        )
    cols = [
        *spec.position,
        *(c for c in spec.torque if c not in absent),
        *([] if velocity is None else velocity),
    ]
    if spec.simulator_format:  # t, q1.., qd1.., tau1..: a joint beyond the arm's is another arm's record
        n = len(spec.position)
        extra = [
            c for f in frames.values() for c in f.columns
            if (m := re.fullmatch(r"(?:q|qd|tau)(\d+)", str(c))) and int(m.group(1)) > n
        ]  # fmt: skip
        if extra:
            raise DataError(
                f"{', '.join(str(p) for p in frames)}: columns {extra[:6]} do not fit the {n}-joint arm of "
                f"{spec.source}: a record of another arm (identify the arm it was recorded on)"
            )
    where = _locate(frames, spec, cols)
    excluded = {spec.torque[j] for j in range(len(spec.torque)) if not spec.used[j]}
    for p, f in frames.items():  # a repeat in what is read (a cell elsewhere differs): the same sample
        read = [c for c in (spec.time, *(c for c in cols if where[c] == p and c not in excluded)) if c in f]
        again = f.duplicated(subset=read, keep="first")
        if again.any():
            frames[p] = f[~again]  # each row keeps its index: its line in the file (_line)
            frames[p].attrs.update(f.attrs, repeats=f.attrs.get("repeats", 0) + int(again.sum()))
    frames, missed = _leave_out_bad_rows(frames, where, spec, [c for c in cols if c not in excluded], window)
    clocks = {p: _times(p, f, spec.time) * spec.time_scale for p, f in frames.items()}
    rows = {p: _window_rows(p, clocks[p], window, spec.time_scale) for p in frames}
    t0, T = first_clock(spec, clocks, rows)
    lo = max(clocks[p][rows[p]][0] for p in frames)
    hi = min(clocks[p][rows[p]][-1] for p in frames)
    check_overlap({p: clocks[p][rows[p]] for p in frames}, lo, hi, T)
    spans, gap_lines = piece_spans({p: clocks[p][rows[p]] for p in frames}, lo, hi)
    grids = [a + T * np.arange(int(np.floor((b - a) / T + 1e-9)) + 1) for a, b in spans]
    short = [(a, b) for (a, b), g in zip(spans, grids, strict=True) if g.size < MIN_PIECE_SAMPLES]
    grids = [g for g in grids if g.size >= MIN_PIECE_SAMPLES]
    if not grids:
        raise DataError(f"{spec.files[0]}: no piece between the log's gaps holds {MIN_PIECE_SAMPLES} samples")
    lenient: list[str] = []

    # an excluded torque channel is not fitted: its bad cells are read as 0 and said, not errors
    def numeric(path, frame, col, r):
        if col not in excluded:
            return _numeric(path, frame, col, r)
        v = _coerced(frame, col)
        bad = int(np.sum(~np.isfinite(v[r])))
        if bad:
            lenient.append(
                f"{path}: column {col!r} (excluded, not fitted): {bad} non-finite cell(s) read as 0"
            )
        return np.where(np.isfinite(v), v, 0.0)

    column = resampler(frames, where, clocks, rows, grids, numeric)
    q = np.column_stack([column(c, True) for c in spec.position])
    n_grid = sum(g.size for g in grids)
    raw_tau = np.column_stack([np.zeros(n_grid) if c in absent else column(c, False) for c in spec.torque])
    _check_stuck(spec, where, raw_tau)
    if arm is not None:
        _check_units(spec, where, q, arm)
    q = q * spec.position_scale
    tau = spec.torque_gain * raw_tau + spec.torque_offset
    if arm is not None:
        _check_torque_scale(spec, where, tau, arm)
    qd_measured = velocity is not None and not spec.derive_velocity
    bounds = np.cumsum([0] + [g.size for g in grids])
    pieces = list(itertools.pairwise(bounds.tolist()))
    qd = np.concatenate([derivatives(q[a:b], T)[0] for a, b in pieces])
    lag_note = ()
    if velocity is not None:
        logged = np.column_stack([column(c, False) for c in velocity]) * spec.position_scale
        a, b = max(pieces, key=lambda ab: ab[1] - ab[0])
        gains = velocity_gains(logged[a:b], qd[a:b])
        lag_note = (_velocity_lag(logged[a:b], qd[a:b], gains, T, spec.joint_names, qd_measured),)
        if qd_measured:
            _check_velocity_scale(spec, where, velocity, gains)
            qd = logged
    grid = np.concatenate(grids)
    notes = (
        *skipped,
        _resampling_note(t0, T, qd_measured),
        *_cut_notes({p: clocks[p][rows[p]] for p in frames}, lo, hi, T, window),
        *lag_note,
        *stale_notes(spec, where, q),
        *missed,
        *gap_lines,
        *lenient,
        *_rate_notes(clocks, rows, T),
        *(
            f"{p}: {f.attrs['repeats']} row(s) repeated (a logger's repeats: the same values in every "
            "column read) read once"
            for p, f in frames.items()
            if f.attrs.get("repeats")
        ),
        *(n for f in frames.values() for n in f.attrs.get("notes", ())),
    )
    if len(pieces) > 1 or short:
        keep, pieces, more = trim_gap_edges(pieces, qd_measured, T, short)
        grid, q, qd, tau = grid[keep], q[keep], qd[keep], tau[keep]
        notes += more
    names = ", ".join(str(p) for p in spec.files)
    return LogRecord(
        grid,
        q,
        qd,
        tau,
        qd_measured,
        spec.used.copy(),
        spec.weight.copy(),
        T,
        names,
        notes,
        spec.simulator_format,
        pieces=tuple(pieces) if len(pieces) > 1 else (),
    )


def _rate_notes(clocks: dict, rows: dict, T: float) -> list[str]:
    """A file logged at another rate than the grid's: said (the grid follows the first file or
    ``sample_period``; a finer file is decimated by interpolation, with no anti-alias filter)."""
    out = []
    for p, t in clocks.items():
        steps = np.diff(t[rows[p]])
        if steps.size == 0:
            continue
        m = float(np.median(steps))
        if m < T / 1.2:
            out.append(
                f"{p}: logged every {m * 1e3:.4g} ms (median), read at T = {T:.6g} s by interpolation: "
                "decimated, with no anti-alias filter (content above the grid's Nyquist frequency folds in)"
            )
        elif m > 1.2 * T:
            out.append(f"{p}: logged every {m * 1e3:.4g} ms (median), interpolated onto T = {T:.6g} s")
    return out


MAX_BAD_ROWS = 0.05
"""The largest share of a file's rows in the window with a bad cell (empty, non-numeric or
non-finite) in a column the fit reads that is left out as samples the logger missed: a logger
misses a few; a column that is mostly or wholly not numbers is another column than the table
meant (a mistyped name matched, an export's broken column), and is refused."""


def _cut_notes(clocks: dict, lo: float, hi: float, T: float, window=None) -> list[str]:
    """A note for a file that starts later or ends earlier than another by more than two samples:
    the record holds only the span every file covers (``lo``-``hi``), the rest of the others lost;
    and for a ``window`` reaching beyond it."""
    a, b = window or (lo, hi)
    out = []
    if a < lo - 2 * T or b > hi + 2 * T:
        out.append(f"the window {a:g}-{b:g} s reaches beyond the log: read {clock(lo)}-{clock(hi)} s")
    for k, word, edge in ((0, "starts", lo), (-1, "ends", hi)):
        by, far = (min(clocks, key=lambda p, s=s: s * abs(clocks[p][k] - edge)) for s in (1, -1))
        if abs(clocks[far][k] - edge) > 2 * T:
            out.append(
                f"{by} {word} at {clock(edge)} s, {far} at {clock(clocks[far][k])} s: the record holds only"
                f" what every file covers, {clock(lo)}-{clock(hi)} s ({abs(clocks[far][k] - edge):.4g} s of "
                f"{far} left out)"
            )
    return out


def _resampling_note(t0: Array, T: float, qd_measured: bool) -> str:
    steps = np.diff(t0)
    return (
        f"{t0.size} logged samples over {clock(t0[0])}-{clock(t0[-1])} s, steps {steps.min() * 1e3:.3g}-"
        f"{steps.max() * 1e3:.3g} ms (median {np.median(steps) * 1e3:.4g} ms); resampled to T = {T:.6g} s: "
        "positions by cubic spline, torques"
        + (" and velocities" if qd_measured else "")
        + " by linear interpolation"
        + ("" if qd_measured else "; velocities derived (Savitzky-Golay, cubic, ~0.1 s)")
    )


def _velocity_lag(logged: Array, derived: Array, gains: Array, T: float, names, used: bool) -> str:
    """How far the logged velocity lags the positions' derivative (cross-correlation, the joint that
    moves most) and its gain (``gains``: :func:`~adaptive_dd.record_checks.velocity_gains`), as a note."""
    j = int(np.argmax(np.std(derived, axis=0)))
    a, b = derived[:, j] - derived[:, j].mean(), logged[:, j] - logged[:, j].mean()
    m = min(a.size // 4, round(1.0 / T))
    lags = np.arange(-m, m + 1)
    c = [np.dot(a[max(0, -k) : a.size - max(0, k)], b[max(0, k) : b.size - max(0, -k)]) for k in lags]
    k = int(lags[int(np.argmax(c))])
    gain = gains[j]
    text = (
        f"the logged velocity lags the positions' derivative by {k * T * 1e3:.0f} ms (joint "
        f"'{names[j]}', gain {gain:.2f})"
    )
    if used and k > 2:
        text += (
            ': it is filtered, or its file stamped late (a clock offset); velocity_source = "derived" '
            "avoids the lag"
        )
    return text
