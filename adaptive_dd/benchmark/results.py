"""Benchmark results as data: one row per controller x seed x segment, summaries, provenance."""

from __future__ import annotations

import numpy as np

from adaptive_dd.benchmark.metrics import detection_delays, false_alarm_counts, per_seed_segment_metrics
from adaptive_dd.benchmark.provenance import provenance, scenario_dict
from adaptive_dd.benchmark.time_to_floor import per_seed_time_to_floor

__all__ = [
    "UNITS",
    "column",
    "frame_columns",
    "plant_frame",
    "provenance",
    "scenario_dict",
    "summary_frame",
    "to_frame",
]


UNITS = {
    "start": "s", "end": "s", "mass": "kg", "rms_error": "rad", "rms_error_settled": "rad",
    "max_error": "rad", "rms_torque": "Nm", "saturation_fraction": "", "settling_time": "s",
    "mass_estimate": "kg", "com_estimate_x": "m", "com_estimate_y": "m", "com_estimate_z": "m",
    "time_to_floor": "s", "detection_delay": "s", "failed_at": "s", "ee_position_rms": "mm",
    "ee_position_max": "mm", "ee_orientation_rms": "deg",
}  # fmt: skip
"""The unit of each quantity of :func:`to_frame` (its column is ``NAME_UNIT``; ``""``: none)."""

_ESTIMATES = ("mass_estimate", "com_estimate_x", "com_estimate_y", "com_estimate_z")


def column(name: str) -> str:
    """The :func:`to_frame` column of a quantity: its name with its unit (``rms_error_rad``)."""
    unit = "rad" if name.startswith("rms_error_joint") else UNITS.get(name, "")
    return f"{name}_{unit}" if unit else name


def frame_columns(n_joints: int) -> list[str]:
    """The columns of :func:`to_frame` and ``per_seed.csv``, in order, each unit in its name.

    The same on every arm but the per-joint RMS errors.

    Parameters
    ----------
    n_joints : int
        The arm's joints.

    Returns
    -------
    list of str
        The column names.

    Examples
    --------
    >>> from adaptive_dd.benchmark.results import frame_columns
    >>> cols = frame_columns(2)
    >>> cols[:7]
    ['controller', 'seed', 'segment', 'start_s', 'end_s', 'mass_kg', 'rms_error_rad']
    >>> [c for c in cols if c.startswith("rms_error_joint")]
    ['rms_error_joint1_rad', 'rms_error_joint2_rad']
    >>> "ratio_to_floor" in cols
    True
    """
    names = [
        "controller", "seed", "segment", "start", "end", "mass", "rms_error",
        *(f"rms_error_joint{j}" for j in range(1, n_joints + 1)),
        "max_error", "rms_torque", "saturation_fraction", "rms_error_settled", "settling_time",
        *_ESTIMATES, "floor", "ratio_to_floor", "time_to_floor", "detection_delay", "false_alarms",
        "failed", "failed_at", "failure", "engine", "ee_position_rms", "ee_position_max",
        "ee_orientation_rms",
    ]  # fmt: skip
    return [column(n) for n in names]


def to_frame(res):
    """Long table (pandas DataFrame): one row per controller x seed x segment, the same columns on
    every arm (:func:`frame_columns`), each quantity's unit in its column's name.

    Columns: ``controller, seed, segment, start_s, end_s, mass_kg, rms_error_rad,
    rms_error_joint1_rad .. rms_error_jointN_rad, max_error_rad, rms_torque_Nm,
    saturation_fraction, rms_error_settled_rad, settling_time_s, mass_estimate_kg,
    com_estimate_x_m, com_estimate_y_m, com_estimate_z_m, floor, ratio_to_floor,
    time_to_floor_s, detection_delay_s, false_alarms (the segment's alarms no swap explains), failed,
    failed_at_s, failure, engine,
    ee_position_rms_mm, ee_position_max_mm, ee_orientation_rms_deg`` (the tool frame's error,
    :mod:`~adaptive_dd.benchmark.end_effector`, streamed for every seed; metrics:
    :mod:`~adaptive_dd.benchmark.metrics`). NaN where a figure does not apply: the
    estimates for a fixed model (the centre of mass on the two-link arm, whose paper's sigma holds
    none), ``time_to_floor_s`` outside the first segment, without a floor or for a failed trial
    (``inf`` when never, :mod:`~adaptive_dd.benchmark.time_to_floor`), the metrics of a failed
    trial in the segments that end after its failure (``failed``, ``failed_at_s`` [s] and
    ``failure``: why, on every row of the trial; NaN and ``""`` for a trial that did not fail).
    ``seed`` is the seed index i of trial i (noise seeded by ``(scenario.seed, i)``, the same
    for every controller).
    """
    import pandas as pd

    return pd.DataFrame(_rows(res), columns=frame_columns(res.scenario.n_joints))


def write_per_seed_csv(res, path) -> None:
    """Write :func:`to_frame`'s table as ``per_seed.csv`` without importing pandas (a quarter of
    a second of a short run): the same text as ``to_frame(res).to_csv(path, index=False)``.

    A column that holds whole numbers and a missing value is written as floats (``3.0``), as
    pandas writes it; a missing value (NaN, None) is an empty field.
    """
    import csv
    import math
    from numbers import Integral

    columns = frame_columns(res.scenario.n_joints)
    rows = _rows(res)

    def missing(v) -> bool:
        return v is None or (isinstance(v, float) and math.isnan(v))

    def whole(v) -> bool:
        return isinstance(v, Integral) and not isinstance(v, (bool, np.bool_))

    as_float = {
        c
        for c in columns
        if any(missing(r.get(c)) for r in rows)
        and any(whole(r.get(c)) for r in rows)
        and all(missing(r.get(c)) or whole(r.get(c)) or isinstance(r.get(c), float) for r in rows)
    }

    def text(c: str, v) -> str:
        if missing(v):
            return ""
        if c in as_float or isinstance(v, (float, np.floating)):
            return repr(float(v))
        if isinstance(v, (bool, np.bool_)):
            return str(bool(v))
        return str(v)

    with open(path, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(columns)
        for r in rows:
            w.writerow([text(c, r.get(c)) for c in columns])


def _rows(res) -> list[dict]:
    """Every controller's rows of :func:`to_frame`, keyed by column."""
    per = {name: per_seed_segment_metrics(res, run) for name, run in res.runs.items()}
    rows = []
    for name, run in res.runs.items():
        rows += _controller_rows(res, name, run, per)
    return rows


def _controller_rows(res, name: str, run, per: dict) -> list[dict]:
    """One controller's rows of :func:`to_frame`."""
    sc = res.scenario
    segs = sc.segments()
    m = per[name]
    floor = run.floor if run.floor in per else None
    ttf = per_seed_time_to_floor(res, run)
    ttf = np.full(len(res.seed_indices), np.nan) if ttf is None else ttf
    false, delays = None, {}
    if run.alarm_times is not None:  # per segment: the alarms in it that no swap explains
        false = np.array(
            [false_alarm_counts([[x for x in tr if a <= x < b] for tr in run.alarm_times], sc.swap_times)
             for a, b, _ in segs]
        ).T  # fmt: skip
        delays = {s: detection_delays(run.alarm_times, a) for s, (a, _, _) in enumerate(segs) if s > 0}
    why = {f["seed"]: f for f in run.failures(sc.sample_period, res.seed_indices or None)}
    rows = []
    for i, seed in enumerate(res.seed_indices):
        fail = why.get(int(seed))
        failed = bool(run.failed[i]) or bool(run.error)  # the detector's figures blank, as metrics()'s
        for s, (a, b, mass) in enumerate(segs):
            delay = delays[s][i] if s in delays and delays[s][i] is not None and not failed else np.nan
            row = {"controller": name, "seed": seed, "segment": s, "start": a, "end": b, "mass": mass}
            row.update(dict.fromkeys(_ESTIMATES, np.nan))
            row.update({k: float(v[i, s]) for k, v in m.items()})
            row["floor"] = floor
            row["ratio_to_floor"] = (
                float(m["rms_error"][i, s] / per[floor]["rms_error"][i, s]) if floor else np.nan
            )
            row["time_to_floor"] = ttf[i] if s == 0 else np.nan
            row["detection_delay"] = delay
            row["false_alarms"] = np.nan if false is None or failed else false[i, s]
            row["failed"] = bool(run.failed[i])
            row["failed_at"] = np.nan if fail is None or fail["t"] is None else fail["t"]
            row["failure"] = "" if fail is None else fail["why"]
            row["engine"] = run.engine
            rows.append({column(k): v for k, v in row.items()})
    return rows


def summary_frame(res):
    """Per controller and segment: mean, median, p90 and max of the per-seed RMS error and
    ratio to the floor, and the worst seed. Columns ``controller, segment, mass_kg,
    rms_error_mean_rad, rms_error_median_rad, ratio_mean, ratio_median, ratio_p90, ratio_max, n,
    ratio_n, worst_seed``. A failed trial counts in the segments that ended before its failure, as in
    :meth:`~adaptive_dd.benchmark.types.BenchmarkResult.metrics` and the report (``n``: the trials
    counted; ``ratio_n``: the seeds the ratio statistics are over, those whose floor finished the
    segment too, the JSON's ``ratio_to_floor.n``); a controller whose every trial failed at once
    keeps its rows, ``n`` 0."""
    df = to_frame(res)  # a failed trial's metrics are NaN in the segments that end after its failure

    def p90(x):
        return float(np.nanpercentile(x, 90)) if x.notna().any() else np.nan

    g = df.groupby(["controller", "segment", "mass_kg"], sort=False)
    out = g.agg(
        rms_error_mean_rad=("rms_error_rad", "mean"),
        rms_error_median_rad=("rms_error_rad", "median"),
        ratio_mean=("ratio_to_floor", "mean"),
        ratio_median=("ratio_to_floor", "median"),
        ratio_p90=("ratio_to_floor", p90),
        ratio_max=("ratio_to_floor", "max"),
        n=("rms_error_rad", "count"),
        ratio_n=("ratio_to_floor", "count"),
    )

    def worst(x):
        r = x["ratio_to_floor"]
        return int(x["seed"].iloc[int(np.nanargmax(r))]) if r.notna().any() else -1

    out["worst_seed"] = g.apply(worst, include_groups=False)
    return out.reset_index()


def plant_frame(res):
    """The plant each seed met (pandas DataFrame), or None when the plant is the arm itself.

    One row per seed x joint: ``seed, joint, mass`` [kg], ``com_x, com_y, com_z`` [m] (link
    frame), ``ixx, iyy, izz, ixy, ixz, iyz`` [kg m^2] about the centre of mass, ``viscous``
    [N m s], ``coulomb`` [N m], ``armature`` [kg m^2], and the same of the nominal plant with the
    prefix ``nominal_``.
    """
    import pandas as pd

    if res.plant is None:
        return None

    def rows(d: dict) -> list[dict]:
        out = []
        for j, link in enumerate(d["links"]):
            r = {"mass": link["mass"], **dict(zip(("com_x", "com_y", "com_z"), link["com"], strict=True))}
            r.update(zip(("ixx", "iyy", "izz", "ixy", "ixz", "iyz"), link["inertia"], strict=True))
            r.update(viscous=d["viscous"][j], coulomb=d["coulomb"][j], armature=d["armature"][j])
            out.append(r)
        return out

    nominal = rows(res.plant["nominal"])
    table = []
    for seed, d in res.plant["seeds"].items():
        for j, r in enumerate(rows(d)):
            table.append(
                {"seed": int(seed), "joint": j + 1, **r, **{f"nominal_{k}": v for k, v in nominal[j].items()}}
            )
    return pd.DataFrame(table)
