"""Benchmark results as data: one row per controller x seed x segment, summaries, provenance."""

from __future__ import annotations

import numpy as np

from adaptive_dd.benchmark.metrics import detection_delays, false_alarm_counts, per_seed_segment_metrics
from adaptive_dd.benchmark.provenance import provenance, scenario_dict
from adaptive_dd.benchmark.time_to_floor import per_seed_time_to_floor

__all__ = ["plant_frame", "provenance", "scenario_dict", "summary_frame", "to_frame"]


def to_frame(res):
    """Long table (pandas DataFrame): one row per controller x seed x segment.

    Columns: ``controller, seed, segment, start, end, mass, rms_error, rms_error_settled,
    rms_error_joint1, rms_error_joint2, max_error, rms_torque, saturation_fraction,
    recovery_time, mass_estimate, floor, ratio_to_floor, time_to_floor, detection_delay,
    false_alarms, failed, engine``; errors in rad, torques in N m, times in s. ``time_to_floor``:
    first segment only (NaN elsewhere, and without a floor or for a failed trial), ``inf``
    when never (:mod:`~adaptive_dd.benchmark.time_to_floor`). ``seed`` is the seed index
    i of trial i (noise seeded by ``(scenario.seed, i)``, the same for every controller).
    """
    import pandas as pd

    sc = res.scenario
    segs = sc.segments()
    per = {name: per_seed_segment_metrics(res, run) for name, run in res.runs.items()}
    rows = []
    for name, run in res.runs.items():
        m = per[name]
        floor = run.floor if run.floor in per else None
        ttf = per_seed_time_to_floor(res, run)
        ttf = np.full(len(res.seed_indices), np.nan) if ttf is None else ttf
        false, delays = None, {}
        if run.alarm_times is not None:
            false = false_alarm_counts(run.alarm_times, sc.swap_times)
            delays = {s: detection_delays(run.alarm_times, a) for s, (a, _, _) in enumerate(segs) if s > 0}
        for i, seed in enumerate(res.seed_indices):
            for s, (a, b, mass) in enumerate(segs):
                delay = delays[s][i] if s in delays and delays[s][i] is not None else np.nan
                row = {"controller": name, "seed": seed, "segment": s, "start": a, "end": b, "mass": mass}
                row.update({k: float(v[i, s]) for k, v in m.items()})
                row["floor"] = floor
                row["ratio_to_floor"] = (
                    float(m["rms_error"][i, s] / per[floor]["rms_error"][i, s]) if floor else np.nan
                )
                row["time_to_floor"] = ttf[i] if s == 0 else np.nan
                row["detection_delay"] = delay
                row["false_alarms"] = np.nan if false is None else false[i]
                row["failed"] = bool(run.failed[i])
                row["engine"] = run.engine
                rows.append(row)
    return pd.DataFrame(rows)


def summary_frame(res):
    """Per controller and segment: mean, median, p90 and max of the per-seed RMS error and
    ratio to the floor, and the worst seed (failed trials left out)."""
    df = to_frame(res)
    df = df[~df["failed"]]

    def p90(x):
        return float(np.nanpercentile(x, 90)) if x.notna().any() else np.nan

    g = df.groupby(["controller", "segment", "mass"], sort=False)
    out = g.agg(
        rms_error_mean=("rms_error", "mean"),
        rms_error_median=("rms_error", "median"),
        ratio_mean=("ratio_to_floor", "mean"),
        ratio_median=("ratio_to_floor", "median"),
        ratio_p90=("ratio_to_floor", p90),
        ratio_max=("ratio_to_floor", "max"),
        n=("seed", "size"),
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
