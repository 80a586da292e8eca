"""The checks :func:`adaptive_dd.record.read_log` makes of a log's values against its ``[record]``
table and the arm: a torque channel stuck at one value, positions in another unit than the
table says (degrees read as radians), a measured velocity in another unit than its position, a
torque far beyond the URDF's effort limit. Each raises a :class:`~adaptive_dd.errors.DataError`
naming the file, the column, the joint and the remedy."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.errors import DataError
from adaptive_dd.record_spec import UNITS, RecordSpec

__all__ = [
    "STALE_FRACTION",
    "STUCK_FRACTION",
    "TORQUE_LIMIT_FACTOR",
    "VELOCITY_GAIN",
    "stale_notes",
    "velocity_gains",
]

Array = NDArray[np.float64]

STUCK_FRACTION = 0.5
"""A fitted torque channel holding one value on more than this share of the window is refused."""

VELOCITY_GAIN = (0.5, 2.0)
"""The range of a measured velocity's gain on the positions' derivative (least squares over the
longest piece) that is read as the same unit: a filtered or lagging velocity stays within it, a
unit error (rad/s logged beside degrees, rpm, a gear ratio) does not."""

TORQUE_LIMIT_FACTOR = 10.0
"""A fitted torque channel beyond this many times the URDF's effort limit is refused as a unit
error (mN m, a missing ``torque_gain``): a drive's peak torque is a few times its rated one."""


def velocity_gains(logged: Array, derived: Array) -> Array:
    """Per joint, the least-squares gain of the logged velocity on the positions' derivative
    (both ``(N, n)``, their means removed); NaN for a joint that does not move."""
    a, b = derived - derived.mean(axis=0), logged - logged.mean(axis=0)
    aa = np.einsum("kj,kj->j", a, a)
    moves = aa > 1e-12 * a.shape[0]
    return np.where(moves, np.einsum("kj,kj->j", a, b) / np.where(moves, aa, 1.0), np.nan)


def _check_velocity_scale(spec: RecordSpec, where: dict, columns, gains: Array) -> None:
    """A measured velocity used by the fit whose gain on the positions' derivative
    (:func:`velocity_gains`) is outside :data:`VELOCITY_GAIN`, on a joint that moves: a
    :class:`DataError` naming the column (a velocity in another unit than its position, which
    scales both, fits the wrong friction without it)."""
    lo, hi = VELOCITY_GAIN
    for j, gain in enumerate(gains):
        if not np.isfinite(gain) or lo <= gain <= hi:
            continue
        unit = spec.position_scale[j]
        raise DataError(
            f"{where[columns[j]]}: column {columns[j]!r} (joint '{spec.joint_names[j]}') is {gain:.3g}x the "
            f"derivative of its position column {spec.position[j]!r}: not the same unit (the position's "
            f"unit, x {unit:.6g}, scales the velocity too); log both in one unit, or set "
            'velocity_source = "derived" in [record]'
        )


def _check_torque_scale(spec: RecordSpec, where: dict, tau: Array, arm) -> None:
    """A fitted torque channel beyond :data:`TORQUE_LIMIT_FACTOR` times the URDF's effort limit: a
    :class:`DataError` naming the column, its peak and the limit (the fit would hold every
    parameter at the URDF's value and say the record cannot see them)."""
    act = getattr(arm, "actuator", None)
    if act is None:  # an arm without effort limits (a stand-in with position limits only)
        return
    limit = np.asarray(act.torque_limit, dtype=float)
    for j in np.flatnonzero(spec.used):
        peak = float(np.max(np.abs(tau[:, j])))
        if np.isfinite(limit[j]) and limit[j] > 0 and peak > TORQUE_LIMIT_FACTOR * limit[j]:
            raise DataError(
                f"{where[spec.torque[j]]}: column {spec.torque[j]!r} (joint '{spec.joint_names[j]}') "
                f"reaches |tau| = {peak:.4g} N m after torque_gain {spec.torque_gain[j]:g}, "
                f"{peak / limit[j]:.0f}x the URDF's effort limit {limit[j]:.4g} N m: a unit error (mN m?) "
                "or a torque_gain missing in [record]"
            )


STALE_FRACTION = 0.05
"""The share of a log's moving samples that may repeat the previous sample's positions in every
joint before :func:`stale_notes` says so."""


def stale_notes(spec: RecordSpec, where: dict, q: Array) -> list[str]:
    """A note when more than :data:`STALE_FRACTION` of the samples at which the arm moves repeat the
    previous sample's positions in every joint (``q (N, n)`` on the grid): a stale sensor, or a
    logger that writes before the next reading. Their derivatives are wrong, and the estimates
    biased beyond their bounds (a helper's walk-through: every second row repeated put a viscous
    friction outside its 95 % bound on 6 seeds of 6)."""
    if q.shape[0] < 3:
        return []
    same = np.all(q[1:-1] == q[:-2], axis=1)  # sample k repeats k - 1
    moving = ~np.all(q[2:] == q[:-2], axis=1)  # the arm moves across k - 1 .. k + 1
    n_moving = int(moving.sum())
    stale = int(np.sum(same & moving))
    if n_moving == 0 or stale <= STALE_FRACTION * n_moving:
        return []
    return [
        f"{where[spec.position[0]]}: {stale} of {n_moving} samples while the arm moves repeat the previous "
        "sample's positions in every joint (a stale sensor, or a logger writing before the next reading): "
        "the derived velocities and accelerations, and the estimates, are biased beyond their bounds; "
        "log the positions fresh, or leave the repeated rows out"
    ]


def _check_stuck(spec: RecordSpec, where: dict, raw: Array) -> None:
    for j in np.flatnonzero(spec.used):
        col = raw[:, j]
        vals, counts = np.unique(col, return_counts=True)
        frac = counts.max() / col.size
        if frac > STUCK_FRACTION:
            raise DataError(
                f"{where[spec.torque[j]]}: column {spec.torque[j]!r} (joint '{spec.joint_names[j]}') holds "
                f"{vals[np.argmax(counts)]:g} on {100 * frac:.0f}% of the window: a channel that carries no "
                f'torque; leave it out of the fit (exclude = ["{spec.joint_names[j]}"] in [record])'
            )


def _check_units(spec: RecordSpec, where: dict, q_raw: Array, arm) -> None:
    lim = arm.position_limits
    kinds = getattr(arm, "joint_kinds", None)

    def fits(j: int, q: Array) -> bool | None:  # None: the joint has no finite limits
        lo, hi = lim[j]
        if not (np.isfinite(lo) and np.isfinite(hi)):
            return None
        slack = 0.1 * (hi - lo) + 0.05
        return bool(q.min() >= lo - slack and q.max() <= hi + slack)

    scaled = [q_raw[:, j] * spec.position_scale[j] for j in range(q_raw.shape[1])]
    outside = [j for j, q in enumerate(scaled) if fits(j, q) is False]
    in_degrees = [j for j in outside if fits(j, scaled[j] * math.pi / 180.0)]  # every such joint at once
    for j in outside:
        lo, hi = lim[j]
        qj = scaled[j]
        hint = (
            f"; in degrees it would fit: set {_degrees_hint(spec, in_degrees, kinds)} in [record]"
            if j in in_degrees
            else ""
        )
        raise DataError(
            f"{where[spec.position[j]]}: column {spec.position[j]!r} (joint '{spec.joint_names[j]}') spans "
            f"[{qj.min():.4g}, {qj.max():.4g}], outside the URDF's limits [{lo:.4g}, {hi:.4g}]{hint}"
            + ("" if hint else ": check the unit, gear ratio and column of this joint")
        )


def _degrees_hint(spec: RecordSpec, joints, kinds=None) -> str:
    """``position_unit = "deg"`` when every joint is revolute and in ``joints`` (the joints whose
    logged range fits their limits in degrees, all named at once), else the per-joint list with
    those in degrees and the others as they are read (a global "deg" would turn the joints logged
    in radians into degrees too)."""
    n = len(spec.position)
    joints = [joints] if isinstance(joints, int | np.integer) else list(joints)
    kinds = tuple(kinds) if kinds is not None else ("revolute",) * n
    if len(joints) == n and all(k != "prismatic" for k in kinds):
        return 'position_unit = "deg"'
    angles = {UNITS["rad"]: "rad", UNITS["mrad"]: "mrad", UNITS["deg"]: "deg"}  # a revolute joint's
    lengths = {UNITS["m"]: "m", UNITS["mm"]: "mm"}  # a prismatic joint's (its scale read back)
    units = [
        (lengths if k == "prismatic" else angles).get(float(s), "rad" if k != "prismatic" else "m")
        for s, k in zip(spec.position_scale, kinds, strict=True)
    ]
    for j in joints:
        units[j] = "deg"
    listed = ", ".join(f'"{u}"' for u in units)
    return f'position_unit = [{listed}] (one per joint; a prismatic one\'s "m" or "mm")'


def _line(frame, row: int) -> int:
    """The file's line number of ``frame``'s row ``row`` (the header is line 1; repeated rows that
    were dropped counted)."""
    return int(frame.index[row]) + 2


def _too_many_bad_rows(
    path, frame, bad_of: dict, n_in: int, in_window, limit: float, spec: RecordSpec | None = None
) -> DataError:
    """The error for a file whose rows in the window with a bad cell in a fitted column are more
    than ``limit`` of them (:data:`adaptive_dd.record.MAX_BAD_ROWS`): each such column, most first,
    with its count and its first bad cell (line, and the cell as written); where they are all
    ``spec``'s velocity columns, the remedy of deriving the velocities from the positions."""

    def first(c: str) -> str:
        i = int(np.flatnonzero(bad_of[c])[0])
        raw = frame[c].to_numpy()[i]
        kind = "not a number" if isinstance(raw, str) else "non-finite value"
        cell = raw.item() if isinstance(raw, np.generic) else raw  # nan, not np.float64(nan)
        return f"line {_line(frame, i)}: {kind} ({cell!r})"

    counts = sorted(((int(b.sum()), c) for c, b in bad_of.items() if b.any()), reverse=True)
    cols = "; ".join(f"column {c!r}: {k}, the first at {first(c)}" for k, c in counts[:4])
    cols += f"; {len(counts) - 4} more column(s)" if len(counts) > 4 else ""
    velocity = set(spec.velocity or ()) if spec is not None else set()
    derive = ""
    if velocity and all(c in velocity for _, c in counts):  # the positions are whole: derive from them
        src = spec.source
        derive = (
            f"drop the velocity key of [record] in {src} (the velocities are derived from the positions "
            "already; without it the logged ones, only compared, are not read)"
            if spec.derive_velocity
            else f'add [record] with velocity_source = "derived" to {src} (the velocities derived from the '
            "positions, the logged ones not read)"
            if spec.simulator_format
            else f'set velocity_source = "derived" in [record] of {src} and drop its velocity key (the '
            "velocities derived from the positions, the logged ones not read)"
        )
        derive = f"only velocity columns, which the fit can do without: {derive}; or "
    return DataError(
        f"{path}: {n_in} of the window's {int(in_window.sum())} rows have an empty, non-numeric or "
        f"non-finite cell in a column the fit reads, more than the {limit:.0%} left out as missed "
        f"samples ({cols}): {derive or 'is each column the one meant? Else '}cut the window to avoid "
        "them ([record] window or --window) or repair the file"
    )


def _no_time_stamps(path, frame, col: str) -> DataError:
    """The error of a file none of whose rows has a numeric time stamp (or that has no rows)."""
    if len(frame) == 0:
        return DataError(f"{path}: no data rows (a header alone): is it the file meant?")
    cell = frame[col].to_numpy()[0]
    return DataError(
        f"{path}: column {col!r}: no numeric time stamp in {'any of its' if len(frame) > 1 else 'its'} "
        f"{len(frame)} row{'s' if len(frame) > 1 else ''} (line "
        f"{_line(frame, 0)}: {cell!r}): the time column must be numbers, seconds or [record] time_unit's "
        "unit (convert a date-time text to seconds first, e.g. pandas.to_datetime(...).astype('int64') "
        'with time_unit = "ns")'
    )
