"""Reading and writing recorded experiments.

A record of an arm of N joints (the paper's arm: N = 2) is a CSV
``t, q1..qN, qd1..qdN, tau1..tauN``, velocities optional (:func:`read_recording`,
:func:`write_recording`).
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.errors import DataError
from adaptive_dd.outputs import atomic_write

__all__ = [
    "MIN_EQUATIONS",
    "Recording",
    "check_identifiable",
    "read_recording",
    "read_text",
    "read_toml",
    "write_recording",
]

MIN_EQUATIONS = 70
"""Fewest usable equations (10 per base parameter) ``identify`` accepts."""
MIN_MOTION = 1e-3
"""rad: a joint whose position range is below this has not moved."""
MAX_FILTER_SAMPLES = 10_000
"""Largest ``tau_f / T``: the filters look back ~10 tau_f, longer ones make identification crawl."""
MAX_RECORD_SAMPLES = 10_000_000
"""Longest record ``identify`` accepts (memory of the filtered regressors)."""


@dataclass(frozen=True)
class Recording:
    """One measured experiment: ``t (n_samples,)`` [s]; ``q`` [rad], ``tau`` [N m] and ``qd``
    [rad/s] (None when the record has no velocities) of shape ``(n_samples, n_joints)``."""

    t: NDArray[np.float64]
    q: NDArray[np.float64]
    tau: NDArray[np.float64]
    qd: NDArray[np.float64] | None
    sample_period: float
    source: str = "<memory>"


def write_recording(path: str | Path, t, q, qd, tau) -> Path:
    """Write a record as CSV ``t, q1..qN, qd1..qdN, tau1..tauN`` (the qd columns left out when
    ``qd`` is None); ``q, qd, tau (n_samples, N)``. Written atomically; the folder is created."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    q = np.asarray(q, float)
    n = q.shape[-1]
    cols = [f"q{j + 1}" for j in range(n)]
    parts = [np.asarray(t, float)[:, None], q]
    if qd is not None:
        cols += [f"qd{j + 1}" for j in range(n)]
        parts.append(np.asarray(qd, float))
    cols += [f"tau{j + 1}" for j in range(n)]
    parts.append(np.asarray(tau, float))
    with atomic_write(path, encoding="utf-8") as fh:
        np.savetxt(
            fh, np.column_stack(parts), delimiter=",", header="t," + ",".join(cols), comments="", fmt="%.10g"
        )
    return path


def read_text(path: Path, error: type[ValueError] = DataError) -> str:
    """A file's text, read as UTF-8 with or without a BOM; other encodings name the byte offset."""
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise error(f"{path}: cannot read: {exc.strerror or exc}") from None
    bom = 3 if raw.startswith(b"\xef\xbb\xbf") else 0
    try:
        return raw[bom:].decode("utf-8")
    except UnicodeDecodeError as exc:
        at = bom + exc.start
        raise error(f"{path}: not UTF-8 text: byte {raw[at]:#04x} at offset {at}; save it as UTF-8") from None


def read_toml(path: str | Path, error: type[ValueError] = DataError) -> dict:
    """A TOML file parsed: the one reader of the package's TOML files (scenarios, arms, sweeps).

    Read as UTF-8 with or without a BOM (:func:`read_text`); a missing file, another encoding or
    invalid TOML raises ``error`` naming the file (and the position).
    """
    import tomllib

    path = Path(path)
    if not path.is_file():
        raise error(f"{path}: no such file")
    text = read_text(path, error)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: not valid TOML: {exc}") from None


MAX_SAMPLE_PERIOD = 0.1
"""[s] a record sampled more slowly than this is another unit's time column (ms read as s)."""
MAX_VALUE = 1e6
"""A position [rad], velocity [rad/s] or torque [N m] beyond this is a corrupt cell, not data."""


def check_identifiable(rec: Recording, tau_f: float) -> None:
    """Refuse, before any work, a record that cannot be identified or would take too long.

    Raises
    ------
    DataError
        Non-positive or too long ``tau_f`` for the sample period, a record too long,
        or a record in which neither joint moves.
    """
    T, n = rec.sample_period, rec.t.size
    if not (np.isfinite(tau_f) and tau_f > 0):
        raise DataError(f"{rec.source}: --tau-f must be a positive number of seconds, got {tau_f}")
    if tau_f < T:  # the filters' bilinear transform is only the derivative filter above a sample
        raise DataError(
            f"{rec.source}: --tau-f {tau_f:g} s is below the sample period T = {T:.6g} s: the derivative "
            f"filters then pass noise at the Nyquist frequency; give --tau-f of at least a few samples "
            "(the default sizes it to T: 0.02 s up to T = 10 ms)"
        )
    if T > MAX_SAMPLE_PERIOD:
        raise DataError(
            f"{rec.source}: samples {T:.6g} s apart (the time column read in s): a robot's record samples "
            f"faster than every {MAX_SAMPLE_PERIOD:g} s; a time column in ms or ns: convert it to s"
        )
    if tau_f / T > MAX_FILTER_SAMPLES:
        raise DataError(
            f"{rec.source}: tau_f / T = {tau_f / T:.3g} samples (tau_f = {tau_f} s, T = {T:.3g} s) "
            f"exceeds {MAX_FILTER_SAMPLES}; use a smaller --tau-f or a slower sampling"
        )
    if 10 * tau_f > n * T:
        raise DataError(
            f"{rec.source}: the record ({n * T:.3g} s) is shorter than 10 tau_f = {10 * tau_f:.3g} s"
        )
    if n > MAX_RECORD_SAMPLES:
        raise DataError(f"{rec.source}: {n} samples; at most {MAX_RECORD_SAMPLES}")
    span = np.ptp(rec.q, axis=0)
    if np.all(span < MIN_MOTION):
        raise DataError(
            f"{rec.source}: the arm does not move (position range {span.round(6)} rad, below "
            f"{MIN_MOTION} rad): nothing to identify"
        )
    tau_span = np.ptp(rec.tau, axis=0)
    if np.any(tau_span == 0.0):
        j = int(np.flatnonzero(tau_span == 0.0)[0])
        raise DataError(
            f"{rec.source}: column tau{j + 1} holds {rec.tau[0, j]:g} on every sample: a channel that "
            "carries no torque; nothing to identify from it"
        )
    big = (
        np.abs(np.concatenate([rec.q, rec.tau] + ([rec.qd] if rec.qd is not None else []), axis=1))
        > MAX_VALUE
    )
    if big.any():
        k, c = (int(x) for x in np.argwhere(big)[0])
        raise DataError(
            f"{rec.source}: a value beyond {MAX_VALUE:g} at row {k + 1} (column {c + 1} of q, tau, qd): "
            "not a position, a velocity or a torque of an arm; a corrupt cell: remove or fix that row"
        )


def _parse_rows(path: Path, reader, header: list[str]) -> NDArray[np.float64]:
    """Rows of numbers under ``header``; a bad cell names its line and column."""
    rows = []
    for lineno, row in enumerate(reader, start=2):
        if not row or all(not c.strip() for c in row):
            continue
        if len(row) != len(header):
            raise DataError(f"{path}: line {lineno}: {len(row)} cells, header has {len(header)}")
        vals = []
        for col, cell in zip(header, row, strict=True):
            try:
                v = float(cell)
            except ValueError:
                raise DataError(f"{path}: line {lineno}, column '{col}': not a number: {cell!r}") from None
            if not np.isfinite(v):
                raise DataError(f"{path}: line {lineno}, column '{col}': non-finite value {cell!r}")
            vals.append(v)
        rows.append(vals)
    if len(rows) < 10:
        raise DataError(f"{path}: {len(rows)} data rows; need at least 10")
    return np.array(rows)


def _sample_period(path: Path, t: NDArray[np.float64], rtol_dt: float) -> float:
    dt = np.diff(t)
    T = float(np.median(dt))
    if T <= 0:
        raise DataError(f"{path}: column 't' is not increasing")
    bad = np.flatnonzero(np.abs(dt - T) > rtol_dt * T)
    if bad.size:
        i = int(bad[0])
        raise DataError(
            f"{path}: line {i + 3}, column 't': non-uniform sampling, step {dt[i]:.6g} s "
            f"where the median step is {T:.6g} s"
        )
    return T


def read_recording(path: str | Path, n_joints: int = 2, rtol_dt: float = 1e-3) -> Recording:
    """Read a CSV record ``t, q1..qN, [qd1..qdN,] tau1..tauN`` of an arm of ``n_joints`` (the
    paper's arm: 2); every problem names the file, line and column.

    Returns a :class:`Recording` with ``q, tau (N, n)`` and ``qd (N, n)`` or None.

    Raises
    ------
    DataError
        Naming the file (and line, column): columns that do not match the arm's joint count
        (which columns are missing or extra), non-numeric or non-finite cells, too few rows,
        non-uniform or non-increasing sampling (``|dt - T| > rtol_dt T``).
    """
    path = Path(path)
    if not path.is_file():
        raise DataError(f"{path}: no such file")
    n = int(n_joints)
    q_cols = [f"q{j + 1}" for j in range(n)]
    qd_cols = [f"qd{j + 1}" for j in range(n)]
    tau_cols = [f"tau{j + 1}" for j in range(n)]
    expected = "t, " + ", ".join(q_cols + qd_cols + tau_cols)
    with io.StringIO(read_text(path), newline="") as fh:
        reader = csv.reader(fh)
        try:
            header = [h.strip() for h in next(reader)]
        except StopIteration:
            raise DataError(f"{path}: empty file, expected a header {expected}") from None
        if len(set(header)) != len(header):
            raise DataError(f"{path}: line 1: duplicate column names in {header}")
        has_qd = any(h.startswith("qd") for h in header)
        want = ["t", *q_cols, *(qd_cols if has_qd else []), *tau_cols]
        missing = [h for h in want if h not in header]
        extra = [h for h in header if h not in want]
        if missing or extra:
            n_file = sum(1 for h in header if h.startswith("tau"))
            what = [f"missing column(s) {missing}"] * bool(missing)
            what += [f"unknown column(s) {extra}"] * bool(extra)
            raise DataError(
                f"{path}: line 1: the columns do not fit an arm of {n} joints: {'; '.join(what)} (the "
                f"file has {len(header)} columns, {n_file} torque column(s)); expected {expected} (the qd "
                "columns all or none)"
            )
        a = _parse_rows(path, reader, header)
    col = {h: a[:, i] for i, h in enumerate(header)}
    T = _sample_period(path, col["t"], rtol_dt)
    return Recording(
        t=col["t"],
        q=np.column_stack([col[c] for c in q_cols]),
        tau=np.column_stack([col[c] for c in tau_cols]),
        qd=np.column_stack([col[c] for c in qd_cols]) if has_qd else None,
        sample_period=T,
        source=str(path),
    )


_RENAMED = {"read_serial_recording": "read_recording", "write_serial_recording": "write_recording"}


def __getattr__(name: str):
    """The old names of :func:`read_recording` and :func:`write_recording` (a FutureWarning)."""
    if name in _RENAMED:
        import warnings

        warnings.warn(
            f"adaptive_dd.io.{name} is now {_RENAMED[name]} (one record format for every arm); the "
            "old name will be removed",
            FutureWarning,
            stacklevel=2,
        )
        return globals()[_RENAMED[name]]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
