"""How a log is read: the ``[record]`` table parsed and checked into a :class:`RecordSpec`
(the keys and what they mean: :mod:`adaptive_dd.record`, which reads the log with it).

Every error names the scenario file and the key (``record.KEY``), the value and what to do.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.errors import ScenarioError

__all__ = ["RECORD_KEYS", "UNITS", "RecordSpec", "record_spec", "zero_based_hint"]

Array = NDArray[np.float64]

RECORD_KEYS = (
    "files",
    "time",
    "time_unit",
    "position",
    "velocity",
    "torque",
    "velocity_source",
    "torque_gain",
    "torque_sign",
    "torque_offset",
    "position_unit",
    "gear_ratio",
    "exclude",
    "torque_weight",
    "torque_held",
    "window",
    "sample_period",
)
UNITS = {"rad": 1.0, "mrad": 1e-3, "deg": math.pi / 180.0, "m": 1.0, "mm": 1e-3}
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}
"""``[record] time_unit``: the time column's unit (ROS stamps are often ns); the window and the
sample period are in s of the log's clock either way."""


@dataclass(frozen=True)
class RecordSpec:
    """How to read a log (module docstring); per-joint arrays have the arm's ``n`` entries.

    Attributes
    ----------
    files : tuple of Path
    time : str
    position, torque : tuple of str
        Column names, one per joint.
    velocity : tuple of str or None
        Measured velocity columns (None: none in the files).
    derive_velocity : bool
        Derive the velocity from the positions even if measured.
    position_scale : ndarray (n,)
        Multiplies a logged position or velocity into rad or m (unit and gear ratio).
    torque_gain, torque_offset : ndarray (n,)
        ``tau = torque_gain * logged + torque_offset`` [N m] (the sign folded into the gain).
    used : ndarray of bool (n,)
        Torque channels in the fit (False: excluded).
    weight : ndarray (n,)
        Multiplies each channel's weight in the fit (``torque_weight``; 1 by default).
    torque_held : bool
        The torque is a command held over each sample (else samples of a continuous torque).
    window : tuple of float or None
    sample_period : float or None
    joint_names : tuple of str
    source : str
        Where the description came from (errors name it).
    simulator_format : bool
        No ``[record]`` table: the simulator's columns, velocity columns optional.
    """

    files: tuple[Path, ...]
    time: str
    position: tuple[str, ...]
    torque: tuple[str, ...]
    velocity: tuple[str, ...] | None
    derive_velocity: bool
    position_scale: Array
    torque_gain: Array
    torque_offset: Array
    used: NDArray[np.bool_]
    weight: Array
    torque_held: bool
    window: tuple[float, float] | None
    sample_period: float | None
    joint_names: tuple[str, ...]
    source: str
    simulator_format: bool = False
    time_scale: float = 1.0
    """Multiplies the time column into s (``[record] time_unit``)."""
    patterns: tuple[tuple[str, str], ...] = ()
    """``(key, pattern)`` of the column keys given as a pattern with ``{i}`` (errors name them)."""


def _err(src: str, key: str, why: str) -> ScenarioError:
    return ScenarioError(f"{src}: key 'record.{key}' {why}")


def _columns(src: str, key: str, v, names: tuple[str, ...]) -> tuple[str, ...]:
    n = len(names)
    if isinstance(v, str):
        if "{joint}" not in v and "{i}" not in v:
            raise _err(src, key, f"= {v!r} must contain {{joint}} or {{i}}, or be a list of {n} names")
        return tuple(
            v.replace("{joint}", nm).replace("{i}", str(j + 1)).strip() for j, nm in enumerate(names)
        )
    if isinstance(v, list) and len(v) == n and all(isinstance(x, str) and x.strip() for x in v):
        return tuple(x.strip() for x in v)  # as the files' headers are read: stripped
    raise _err(src, key, f"must be a column-name pattern or a list of {n} names (one per joint), got {v!r}")


def _per_joint(src: str, key: str, v, n: int, default: float, nonzero: bool = False) -> Array:
    if v is None:
        return np.full(n, default)
    if isinstance(v, int | float) and not isinstance(v, bool):
        v = [v] * n
    ok = isinstance(v, list) and len(v) == n
    ok = ok and all(isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x) for x in v)
    if not ok:
        raise _err(src, key, f"must be a number or a list of {n} finite numbers (one per joint), got {v!r}")
    a = np.array(v, dtype=float)
    if nonzero and np.any(a == 0):
        raise _err(src, key, f"must be nonzero, got {v!r}")
    return a


def record_spec(table: dict | None, joint_names, kinds, src: str, files=None) -> RecordSpec:
    """The :class:`RecordSpec` of a ``[record]`` table (None: the simulator's columns).

    Parameters
    ----------
    table : dict or None
    joint_names, kinds : sequence of str
        The arm's joints and their URDF types (``revolute``, ``continuous``, ``prismatic``).
    src : str
        The scenario file (relative file names are beside it).
    files : sequence of str, optional
        Files given on the command line: they replace ``files``.


    Returns
    -------
    RecordSpec
        Files, columns, conversions, excluded channels and window, checked.


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
    >>> spec.position, spec.torque, spec.derive_velocity
    (('q1', 'q2'), ('tau1', 'tau2'), True)

    Raises
    ------
    ScenarioError
        Naming the key and the reason.
    """
    t = {} if table is None else dict(table)
    unknown = [k for k in t if k not in RECORD_KEYS]
    if unknown:
        raise _err(src, unknown[0], f"is unknown; allowed: {', '.join(RECORD_KEYS)}")
    names = tuple(joint_names)
    n = len(names)
    paths = _log_files(src, t, files)
    default = table is None
    time, position, torque, velocity, source = _signal_columns(src, t, names, default)
    scale = _position_scale(src, t, names, tuple(kinds))
    gain, offset = _torque_conversion(src, t, n)
    used, weight = _channels(src, t, names)
    window, T = _window_period(src, t)
    unit = t.get("time_unit", "s")
    if not isinstance(unit, str) or unit not in TIME_UNITS:
        raise _err(
            src,
            "time_unit",
            f"must be one of {', '.join(map(repr, TIME_UNITS))} (the time column's unit), got {unit!r}",
        )
    held = t.get("torque_held", True)
    if not isinstance(held, bool):
        raise _err(src, "torque_held", f"must be true or false, got {held!r}")
    return RecordSpec(
        files=paths,
        time=time,
        position=position,
        torque=torque,
        velocity=velocity,
        derive_velocity=source == "derived",
        position_scale=scale,
        torque_gain=gain,
        torque_offset=offset,
        used=used,
        weight=weight,
        torque_held=held,
        window=window,
        sample_period=T,
        joint_names=names,
        source=src,
        simulator_format=default,
        time_scale=TIME_UNITS[unit],
        patterns=tuple(
            (k, v)
            for k in ("position", "torque", "velocity")
            if isinstance(v := t.get(k), str) and "{i}" in v
        ),
    )


def zero_based_hint(spec: RecordSpec, col: str, columns) -> str:
    """Where the missing column ``col`` comes from a pattern with ``{i}`` (which counts the joints
    from 1) and the files hold its columns counted from 0 (a ROS export's ``field.position0``): the
    lists of names to give instead (every such key's at once); else ''."""
    import json

    hit, keys, lists = False, [], []
    for key, v in spec.patterns:
        names = [v.replace("{joint}", nm).strip() for nm in spec.joint_names]
        zeros = [nm.replace("{i}", str(j)) for j, nm in enumerate(names)]
        if set(zeros) <= set(columns):
            hit = hit or col in [nm.replace("{i}", str(j + 1)) for j, nm in enumerate(names)]
            keys.append(f"record.{key} = {v!r}")
            lists.append(f"{key} = {json.dumps(zeros)}")
    if not hit:
        return ""
    return (
        f"; {{i}} counts the joints from 1 ({', '.join(keys)}) and the files number them from 0: list the "
        f"names instead, {'; '.join(lists)}"
    )


def _log_files(src: str, t: dict, files) -> tuple[Path, ...]:
    """The log's files: the command line's as given, else the table's (beside the scenario file)."""
    base = Path(src).parent if Path(src).is_file() else Path.cwd()
    raw = files if files else t.get("files")
    if isinstance(raw, str):
        raw = [raw]
    if not raw or not isinstance(raw, list | tuple) or not all(isinstance(f, str) and f for f in raw):
        raise _err(src, "files", "is missing: give the log's file(s) on the command line or in [record]")
    return tuple(Path(f) if (files or Path(f).is_absolute()) else base / f for f in raw)


def _signal_columns(src: str, t: dict, names: tuple[str, ...], default: bool):
    """The time column, the position, torque and velocity (or None) column names per joint, and
    the velocity's source (``measured`` or ``derived``); the simulator's names by default."""
    time = t.get("time", "t")
    if not isinstance(time, str) or not time.strip():
        raise _err(src, "time", f"must be a column name, got {time!r}")
    time = time.strip()  # as the files' headers are read (" stamp" in "t, stamp": a header with spaces)
    position = _columns(src, "position", t.get("position", "q{i}"), names)
    torque = _columns(src, "torque", t.get("torque", "tau{i}"), names)
    vel = t.get("velocity", "qd{i}" if default else None)
    velocity = None if vel is None else _columns(src, "velocity", vel, names)
    source = t.get("velocity_source", "measured" if velocity else "derived")
    if source not in ("measured", "derived"):
        raise _err(src, "velocity_source", f"must be 'measured' or 'derived', got {source!r}")
    if source == "measured" and velocity is None:
        raise _err(src, "velocity_source", "is 'measured' but no 'velocity' columns are given")
    return time, position, torque, velocity, source


def _position_scale(src: str, t: dict, names: tuple[str, ...], kinds: tuple[str, ...]) -> Array:
    """Logged position or velocity -> rad or m, per joint (``position_unit``, ``gear_ratio``)."""
    n = len(names)
    unit = t.get("position_unit", "rad")
    if isinstance(unit, str):  # one unit: for the revolute joints ("rad", "deg") or the prismatic ones
        length = unit in ("m", "mm")
        units = [unit if (k == "prismatic") == length else ("rad" if length else "m") for k in kinds]
    else:
        units = unit
    if not (isinstance(units, list) and len(units) == n and all(u in UNITS for u in units)):
        raise _err(
            src, "position_unit", f"must be one of {sorted(UNITS)} or a list of {n} of them, got {unit!r}"
        )
    for j, (u, k) in enumerate(zip(units, kinds, strict=True)):
        if (u in ("m", "mm")) != (k == "prismatic"):
            raise _err(src, "position_unit", f"{u!r} does not fit joint '{names[j]}' ({k})")
    gear = _per_joint(src, "gear_ratio", t.get("gear_ratio"), n, 1.0, nonzero=True)
    return np.array([UNITS[u] for u in units]) / gear


def _torque_conversion(src: str, t: dict, n: int) -> tuple[Array, Array]:
    """``(sign * gain, offset)`` per joint."""
    gain = _per_joint(src, "torque_gain", t.get("torque_gain"), n, 1.0, nonzero=True)
    sign = _per_joint(src, "torque_sign", t.get("torque_sign"), n, 1.0)
    if np.any(np.abs(sign) != 1):
        raise _err(src, "torque_sign", f"must be +1 or -1 per joint, got {t.get('torque_sign')!r}")
    return sign * gain, _per_joint(src, "torque_offset", t.get("torque_offset"), n, 0.0)


def _channels(src: str, t: dict, names: tuple[str, ...]) -> tuple[NDArray[np.bool_], Array]:
    """Fitted torque channels and their weight multipliers (``exclude``, ``torque_weight``)."""
    exclude = t.get("exclude", [])
    if not isinstance(exclude, list) or any(x not in names for x in exclude):
        raise _err(src, "exclude", f"must list joint names of the arm ({', '.join(names)}), got {exclude!r}")
    weight = _per_joint(src, "torque_weight", t.get("torque_weight"), len(names), 1.0)
    if np.any(weight < 0):
        raise _err(src, "torque_weight", f"must be >= 0 per joint, got {t.get('torque_weight')!r}")
    used = np.array([nm not in exclude for nm in names]) & (weight > 0)
    if not used.any():
        raise _err(src, "exclude", "leaves no torque channel to fit")
    return used, weight


def _window_period(src: str, t: dict) -> tuple[tuple[float, float] | None, float | None]:
    window = t.get("window")
    if window is not None:
        ok = isinstance(window, list) and len(window) == 2
        ok = ok and all(isinstance(x, int | float) and not isinstance(x, bool) for x in window)
        if not ok or not window[0] < window[1]:
            raise _err(src, "window", f"must be [start, end] in s with start < end, got {window!r}")
        window = (float(window[0]), float(window[1]))
    T = t.get("sample_period")
    if T is not None and not (isinstance(T, int | float) and not isinstance(T, bool) and 0 < T < 10):
        raise _err(src, "sample_period", f"must be in (0, 10) s, got {T!r}")
    return window, None if T is None else float(T)
