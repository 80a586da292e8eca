"""The leaderboard: a list of controllers on a list of scenarios, each ranked per seed against
its own floor (the same law given the true robot), as one table.

:func:`leaderboard` runs each scenario once with the controllers asked for and the floor of
each (a floor that cannot run says why in the row), and returns one row per scenario,
controller and payload segment (:data:`COLUMNS` names every column with its unit). The
scenarios are an argument: paths, :class:`~adaptive_dd.benchmark.scenario.Scenario` objects or
anything :func:`~adaptive_dd.benchmark.scenario.load_scenario` reads; the default is the shipped
N-joint ones (:func:`shipped_scenarios`). ``arms = N`` adds a population of drawn arms nobody tuned
for (the template's payload schedule on ``random:FIRST`` .. ``random:FIRST+N-1``,
:mod:`adaptive_dd.benchmark.population`): one row per arm and, pooled over the arms' seeds, the
population's rows (``kind`` says which). ``adaptive-dd leaderboard`` writes the table as CSV and
JSON and draws it (:mod:`adaptive_dd.cli.leaderboard`).

**Recovery time.** Per seed and segment, the time from the segment's start (a swap; ``t = 0`` for
the first segment) after which the causal 0.25 s moving RMS of the tracking error stays within
1.2 times its floor's (the same seed) to the segment's end
(:func:`~adaptive_dd.benchmark.time_to_floor.time_to_floor`); "never" when the segment's last window
is still above.

**End-effector error.** The tool frame's (the arm's payload frame) RMS and peak position error
[mm] and RMS orientation error [deg] against the frame the reference puts it in, per seed and
segment as the benchmark's ``per_seed.csv`` has them (``ee_position_rms_mm``,
``ee_position_max_mm``, ``ee_orientation_rms_deg``; :mod:`~adaptive_dd.benchmark.end_effector`),
aggregated over the seeds whose trial did not fail.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from adaptive_dd.arena.columns import COLUMNS, contenders, told_the_model
from adaptive_dd.arena.entries import _with_floors
from adaptive_dd.benchmark.end_effector import EE_KEYS
from adaptive_dd.benchmark.intervals import mean_interval
from adaptive_dd.benchmark.scenario import packaged_scenarios
from adaptive_dd.errors import ParameterError

__all__ = [
    "COLUMNS",
    "DEFAULT_CONTROLLERS",
    "POPULATION_TEMPLATE",
    "contenders",
    "leaderboard",
    "ratio_columns",
    "rms_rank",
    "run_unit",
    "shipped_scenarios",
    "told_the_model",
    "unit_costs",
    "unit_design",
]

DEFAULT_CONTROLLERS = (
    "pd",
    "pd_gravity",
    "ct_nominal",
    "momentum_observer_ct",
    "sliding_mode",
    "slotine_li",
    "composite",
    "icl",
    "natural_adaptive",
    "craig_hsu_sastry",
    "adaptive_ct",
)
"""The controllers ranked by default (their floors are added: ``ct_oracle``, ``ct_oracle_textbook``,
``pd_gravity_oracle``, ``slotine_li_oracle``)."""

POPULATION_TEMPLATE = "benchmarks/scenarios/population.toml"
"""The default template of ``arms``: a pick-up of 80 % of each arm's capacity, a swap to 30 %, a
put-down (relative to the source tree)."""


def shipped_scenarios() -> list[Path]:
    """The shipped arms' scenarios with a drawn plant: ur5, panda, iiwa14, vertical3
    (``adaptive_dd/scenarios``), and the Kinova Gen3 and the paper's arm from its URDF
    (``benchmarks/scenarios``: ``gen3_drawn``, ``sice_drawn``; when the source tree is at hand)."""
    pkg = packaged_scenarios()
    out = [pkg[n] for n in ("ur5_tool_swap", "panda_payload", "iiwa14_payload", "vertical3_payload")]
    bench = Path(__file__).resolve().parents[2] / "benchmarks" / "scenarios"
    return out + [p for p in (bench / "gen3_drawn.toml", bench / "sice_drawn.toml") if p.is_file()]


def ratio_columns(ratio: np.ndarray, seed: int = 0) -> dict[str, float]:
    """The ratio columns of :data:`COLUMNS` from per-seed ratios ``(n,)`` (NaN: left out); the
    interval is :func:`~adaptive_dd.benchmark.intervals.mean_interval`'s with ``seed`` (the
    report's at 0). All NaN when no ratio is finite."""
    r = np.asarray(ratio, float)
    r = r[np.isfinite(r)]
    keys = ("ratio_mean", "ratio_ci95_low", "ratio_ci95_high", "ratio_p90", "ratio_cvar10", "ratio_max")
    if r.size == 0:
        return dict.fromkeys(keys, np.nan)
    ci = mean_interval(r, seed) or (np.nan, np.nan)  # one seed: no interval
    worst = np.sort(r)[::-1][: max(1, int(np.ceil(0.1 * r.size)))]
    vals = (r.mean(), *ci, np.percentile(r, 90), worst.mean(), r.max())
    return {k: float(v) for k, v in zip(keys, vals, strict=True)}


def _scenario(spec):
    from adaptive_dd.benchmark.scenario import Scenario, load_scenario

    sc = spec if isinstance(spec, Scenario) else load_scenario(spec)
    if sc.closed_forms is not None:
        raise ParameterError(
            f"leaderboard: {sc.source} runs the paper's two-link arm on its closed-form runtime, where "
            "the arena's laws do not run; use the arm from its URDF (benchmarks/scenarios/sice_drawn.toml)"
        )
    return sc


def _per_seed(res, names) -> dict[str, dict[str, np.ndarray]]:
    """Per controller of ``names``, ``(n_seeds, n_segments)`` arrays: ``rms_error`` [rad],
    ``rms_torque``, ``saturation_fraction``, the tool frame's ``ee_*`` (:data:`_EE`; NaN where the
    trial failed), the time of each segment's first saturated sample (``sat_t``), and its error norm's
    segments (``e_norm``, a list per segment of ``(n_seeds, samples)``) for the recovery times."""
    from adaptive_dd.arena.flags import lost_times
    from adaptive_dd.benchmark.metrics import per_seed_segment_metrics
    from adaptive_dd.closed_loop.types import sample_bounds

    seg_start, seg_end, _ = sample_bounds(res.scenario)
    T = res.scenario.sample_period
    starts = np.array([a for (a, _, _) in res.scenario.segments()], float)
    out = {}
    with np.errstate(invalid="ignore", divide="ignore"):  # failed trials' NaN, estimates of no payload
        for n in names:
            run = res.runs[n]
            m = per_seed_segment_metrics(res, run, settling=False)
            keep = {k: m[k] for k in ("rms_error", "rms_torque", "saturation_fraction", *_EE)}
            e = np.asarray(run.e_norm, float) if run.e_norm is not None else None
            bounds = zip(seg_start, seg_end, strict=True)
            keep["e_norm"] = [None if e is None else e[:, a:b] for a, b in bounds]
            keep["failed"] = ~np.isfinite(m["rms_error"])
            # a trial that raised in compiled code has no failure time (failed_at < 0): NaN, not 0 s
            keep["failed_trial"] = np.asarray(run.failed, bool)
            keep["fail_t"] = np.where(run.failed & (run.failed_at >= 0), run.failed_at * T, np.nan)
            until = np.where(run.failed, np.nan_to_num(keep["fail_t"], nan=0.0), np.inf)
            keep["lost_t"] = lost_times(keep["e_norm"], list(seg_start * T), T, len(run.failed), until)
            keep["sat_t"] = _first_saturated(run, T)
            # the flags' saturation: over the samples each trial ran in the segment, a failed trial's
            # too (its saturation_fraction is blanked, and a trial saturated into its failure read
            # only "failed")
            ran = (
                np.minimum(seg_end[None, :], np.where(run.failed, run.failed_at, np.inf)[:, None]) - seg_start
            )
            n_sat = np.asarray(run.acc.n_saturated, float)
            keep["sat_flag"] = np.where(ran > 0, n_sat / np.maximum(ran, 1), np.nan)
            keep["why"] = [run.failed_why.get(i, run.error or "") for i in range(len(run.failed))]
            keep["fa"], keep["missed"] = _alarms(run, res.scenario, starts)
            out[n] = keep
    return out


def _alarms(run, sc, t0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(n_seeds, n_segments)`` each, 1.0 or 0.0: a false alarm in the segment (an alarm that
    follows no swap by less than ``FALSE_ALARM_WINDOW``, counted in the segment it falls in; NaN for
    a failed trial, whose alarms the benchmark does not count either) and the segment's swap missed
    (no alarm within that window after it; 0 in the first segment and for a swap the run ends
    within the window of; NaN for a failed trial, as its false alarms). NaN for a law without a detector. The
    benchmark report's rules (:func:`~adaptive_dd.benchmark.metrics.false_alarm_counts`,
    :func:`~adaptive_dd.benchmark.metrics.missed_swap_counts`), segment by segment."""
    from adaptive_dd.benchmark.metrics import false_alarm_counts, missed_swap_counts

    n, n_seg = len(run.failed), len(t0)
    if run.alarm_times is None:
        return np.full((n, n_seg), np.nan), np.full((n, n_seg), np.nan)
    ends = [*t0[1:], np.inf]
    fa = np.array(
        [false_alarm_counts([[x for x in tr if a <= x < b] for tr in run.alarm_times], sc.swap_times)
         for a, b in zip(t0, ends, strict=True)]
    ).T > 0  # fmt: skip
    fa = np.where(np.asarray(run.failed)[:, None], np.nan, fa.astype(float))  # as the benchmark: none
    missed = np.zeros((n, n_seg))
    for i in range(1, n_seg):
        missed[:, i] = missed_swap_counts(run.alarm_times, [t0[i]], np.zeros(n, bool), sc.duration)
    missed = np.where(np.asarray(run.failed)[:, None], np.nan, missed)  # as the false alarms
    return fa, missed


def _first_saturated(run, T: float) -> np.ndarray:
    """``(n_seeds, n_segments)``: the time [s] of each segment's first saturated sample (NaN: none)."""
    first = run.acc.first_saturated
    if first is None:
        return np.full(run.acc.n_saturated.shape, np.nan)
    return np.asarray(first, float) * T


def _recovery(mine: dict, floor: dict, i: int, T: float) -> np.ndarray:
    """Per seed, the recovery time [s] in segment ``i`` (module docstring; inf never, NaN failed)."""
    from adaptive_dd.benchmark.time_to_floor import time_to_floor

    e, f = mine["e_norm"][i], floor["e_norm"][i]
    if e is None or f is None or e.shape[1] == 0:
        return np.full(mine["rms_error"].shape[0], np.nan)
    t = time_to_floor(e, f, T)
    return np.where(mine["failed"][:, i] | floor["failed"][:, i], np.nan, t)


def _cells(name, kind, per, floors, missing, masses, T, seeds, t0) -> list[dict]:
    """One scenario's cells, with the per-seed arrays a row is computed from (``_row``)."""
    cells = []
    for ctrl, floor in floors.items():
        m = per[ctrl]
        fm = per.get(floor) if floor is not None else None
        note = "" if fm is not None else ("an oracle: its own floor" if floor is None else missing[floor])
        for i, mass in enumerate(masses):
            e = m["rms_error"][:, i]
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio = e / fm["rms_error"][:, i] if fm is not None else np.full(e.shape, np.nan)
            cells.append(
                {
                    "scenario": name, "kind": kind, "controller": ctrl, "floor": floor or "",
                    "floor_note": note, "segment": i, "payload_kg": float(mass), "e": e, "ratio": ratio,
                    "fe": fm["rms_error"][:, i] if fm else np.full(e.shape, np.nan),
                    "torque": m["rms_torque"][:, i], "sat": m["saturation_fraction"][:, i],
                    "fsat": fm["saturation_fraction"][:, i] if fm else np.full(e.shape, np.nan),
                    "recovery": _recovery(m, fm, i, T) if fm else np.full(e.shape, np.nan),
                    **{k: m[k][:, i] for k in _EE}, "lost_t": m["lost_t"][:, i], "sat_t": m["sat_t"][:, i],
                    "fail_t": m["fail_t"], "failed_trial": m["failed_trial"], "fa": m["fa"][:, i],
                    "missed": m["missed"][:, i],
                    "sat_flag": m["sat_flag"][:, i],
                    "why": m["why"], "seed": seeds, "t0": float(t0[i]),
                }
            )  # fmt: skip
    return cells


_KEYS = ("scenario", "kind", "controller", "law", "floor", "floor_note", "segment", "payload_kg")
_EE = EE_KEYS  # the tool frame's per-seed figures [mm], [mm], [deg] (per_seed.csv's ee_* columns)
_ARRAYS = (
    "e",
    "ratio",
    "fe",
    "torque",
    "sat",
    "sat_flag",
    "fsat",
    "recovery",
    "lost_t",
    "fa",
    "missed",
    *_EE,
)


def _row(c: dict, seed: int) -> dict:
    """A table row (:data:`COLUMNS`) from a cell's per-seed arrays."""
    from adaptive_dd.benchmark.metrics import SATURATION_LIMIT
    from adaptive_dd.benchmark.time_to_floor import quantile_never

    e, rec = c["e"], c["recovery"]
    return {
        **{k: c[k] for k in _KEYS},
        "seeds": int(np.sum(np.isfinite(e))), **ratio_columns(c["ratio"], seed),
        "failures": int(np.sum(~np.isfinite(e))),
        "saturated_seeds": int(np.sum(c["sat"] > SATURATION_LIMIT)),
        "lost_seeds": int(np.sum(np.isfinite(c["lost_t"]))), "rms_error_mrad": 1e3 * _mean(e),
        "floor_rms_error_mrad": 1e3 * _mean(c["fe"]), "rms_torque_Nm": _mean(c["torque"]),
        "saturation_pct": 100 * _mean(c["sat"]), "floor_saturation_pct": 100 * _mean(c["fsat"]),
        "false_alarm_seeds": _count(c["fa"]), "missed_swaps": _count(c["missed"]),
        "recovery_median_s": quantile_never(rec, 50.0), "recovery_p90_s": quantile_never(rec, 90.0),
        "recovery_never": int(np.sum(np.isinf(rec))),
        "ee_position_rms_mm": _mean(c["ee_position_rms"]), "ee_position_peak_mm": _mean(c["ee_position_max"]),
        "ee_position_peak_max_mm": _max(c["ee_position_max"]),
        "ee_orientation_rms_deg": _mean(c["ee_orientation_rms"]),
    }  # fmt: skip


def _pooled(cells: list[dict], n_arms: int) -> list[dict]:
    """The population's cells: each controller's and segment's per-seed arrays over every arm."""
    groups: dict = {}
    for c in cells:
        groups.setdefault((c["controller"], c["segment"]), []).append(c)
    out, name = [], f"population({n_arms} arm{'s' if n_arms != 1 else ''})"
    for (_, seg), cs in groups.items():
        first = cs[0]
        pooled = {k: np.concatenate([c[k] for c in cs]) for k in _ARRAYS}
        notes = sorted({c["floor_note"] for c in cs if c["floor_note"]})
        out.append(
            {
                **first, **pooled, "scenario": name, "kind": "population",
                "floor_note": "; ".join(notes[:1]), "segment": seg,
                "payload_kg": float(np.mean([c["payload_kg"] for c in cs])),
            }
        )  # fmt: skip
    return out


def _mean(x) -> float:
    """Mean of the finite entries (NaN if none)."""
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    return float(x.mean()) if x.size else float("nan")


def alarm_totals(rows) -> tuple[int, int, int, int] | None:
    """Over one scenario's (or the population's) rows of one law, every segment: ``(false alarms,
    trials, missed swaps, swaps)``, a trial with false alarms in two segments counted twice (the
    trials with one are at most the first); None for a law without a detector."""
    fa = rows["false_alarm_seeds"].sum(min_count=1)  # NaN when no row has a count
    if not np.isfinite(fa):
        return None
    trials = int(rows["seeds"].iloc[-1])  # those that did not fail (a failed one's alarms are not counted)
    return int(fa), trials, int(rows["missed_swaps"].sum()), trials * (len(rows) - 1)


def _count(x) -> float:
    """Sum of the finite entries (NaN if none: a law without a detector)."""
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    return float(x.sum()) if x.size else float("nan")


def _max(x) -> float:
    """Largest of the finite entries (NaN if none)."""
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    return float(x.max()) if x.size else float("nan")


def leaderboard(
    scenarios: Sequence | None = None,
    controllers: Sequence[str] = DEFAULT_CONTROLLERS,
    seeds: int | None = 3,
    rng: np.random.Generator | None = None,
    progress: bool = False,
    arms: int = 0,
    template=None,
    first_arm: int = 0,
    workers: int = 1,
):
    """Rank ``controllers`` on ``scenarios`` (and ``arms`` drawn arms) against each one's floor, seed by seed.

    Parameters
    ----------
    scenarios : sequence, optional
        Scenario files, :class:`~adaptive_dd.benchmark.scenario.Scenario` objects, or any other
        source :func:`~adaptive_dd.benchmark.scenario.load_scenario` takes (default
        :func:`shipped_scenarios`; an empty list: none, the arms alone). N-joint arms only.
    controllers : sequence of str
        Built-in names or plug-ins ``"package.module:Class"``; each one's floor (its ``floor``
        attribute) runs beside it and is ranked too.
    seeds : int or None
        Seeds per scenario and per arm (None: each scenario's own).
    rng : numpy.random.Generator or int, optional
        The bootstrap intervals' seed (default 0; a generator: one seed drawn from it), every row's
        interval drawn from it alone (:func:`~adaptive_dd.benchmark.intervals.mean_interval`: at 0
        the report's interval of the same ratios); the trials' noise
        and plants come from each scenario's own seeds (common random numbers: every controller of
        a seed meets the same robot and noise).
    progress : bool
        Show the benchmark's progress bars.
    arms : int
        Drawn arms ``random:first_arm`` .. (0: none): ``template``'s payload schedule on each
        (:func:`~adaptive_dd.benchmark.population.population_scenario`), a row per arm and the
        population's rows pooled over their seeds.
    template : path, optional
        The population's template (default :data:`POPULATION_TEMPLATE` in the source tree).
    first_arm : int
        Seed of the first drawn arm.
    workers : int
        Processes that run the scenarios and arms (:mod:`adaptive_dd.arena.pool`; 1: this one);
        the table is the same for any number.

    Returns
    -------
    pandas.DataFrame
        One row per scenario (or arm, or the population), controller and segment; the columns of
        :data:`COLUMNS`. ``attrs["flags"]``: every trial that saturated, lost tracking or failed,
        from when and why (:func:`~adaptive_dd.arena.flags.trial_flags`).
        ``attrs["compile_seconds"]``: numba's compile time of the runs [s];
        ``attrs["run_seconds"]``: the rest of their wall time [s] (both summed over the workers).

    Raises
    ------
    ParameterError
        No controller, fewer than one seed, a negative ``arms``, fewer than one worker, a missing
        template, a two-link closed-form scenario, an unknown controller.

    Examples
    --------
    One controller and its floor on a one-second run of the three-joint arm (compiles the N-joint
    closed loop on a cold cache):

    >>> from adaptive_dd.arena.leaderboard import leaderboard
    >>> from adaptive_dd.benchmark.scenario import parse_scenario
    >>> ref = {"joint1": {"offset": 0.3, "amplitude": [0.4], "frequency": [0.3]},
    ...        "joint2": {"offset": -0.6, "amplitude": [0.5], "frequency": [0.4]},
    ...        "joint3": {"offset": 0.4, "amplitude": [0.6], "frequency": [0.5]}}
    >>> sc = parse_scenario({"arm": {"robot": "vertical3"}, "reference": ref,
    ...                      "payload": [{"at": 0.5, "mass": 1.0}], "run": {"duration": 1.0}})
    >>> table = leaderboard([sc], controllers=["ct_nominal"], seeds=2)
    >>> sorted(set(table["controller"]))
    ['ct_nominal', 'ct_oracle']
    """
    import pandas as pd

    for name, value in (("controllers", controllers), ("scenarios", scenarios)):
        if isinstance(value, str | Path):  # a string would be iterated letter by letter
            raise ParameterError(f"leaderboard: {name} is a list, got the one {value!r}: pass [{value!r}]")
    controllers = list(dict.fromkeys(controllers))
    if not controllers:
        raise ParameterError("leaderboard: controllers: name at least one controller")
    if seeds is not None and (isinstance(seeds, bool) or not isinstance(seeds, int) or seeds < 1):
        raise ParameterError(f"leaderboard: seeds must be an integer >= 1, got {seeds!r}")
    if isinstance(arms, bool) or not isinstance(arms, int) or arms < 0:
        raise ParameterError(f"leaderboard: arms must be an integer >= 0, got {arms!r}")
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ParameterError(f"leaderboard: workers must be an integer >= 1, got {workers!r}")
    seed_ok = isinstance(rng, int | np.integer) and not isinstance(rng, bool) and rng >= 0
    if not (rng is None or isinstance(rng, np.random.Generator) or seed_ok):
        raise ParameterError(
            f"leaderboard: rng must be a numpy.random.Generator or a seed (int >= 0), got {rng!r}"
        )
    # every row's interval from the one seed: a seed given, or one drawn from the generator given
    seed = int(rng.integers(2**63)) if isinstance(rng, np.random.Generator) else int(rng or 0)
    specs = shipped_scenarios() if scenarios is None else scenarios
    units = [("scenario", _scenario(spec)) for spec in specs]
    if arms:
        data, src = _template(template)
        units += [("arm", (data, src, k)) for k in range(first_arm, first_arm + arms)]
    from threadpoolctl import threadpool_limits

    from adaptive_dd.arena.flags import trial_flags
    from adaptive_dd.arena.pool import run_units

    # BLAS on one thread: the identification's and the design's small products otherwise spin
    # OpenBLAS's worker threads for a core (CPU s per call 4-30x on a shared 2-core machine)
    with threadpool_limits(limits=1, user_api="blas"):
        costs = unit_costs(units) if workers > 1 else None
        done = run_units(run_unit, units, controllers, seeds, progress, workers, costs, unit_design)
    rows: list[dict] = []
    arm_cells: list[dict] = []
    flags: list[dict] = []
    for (kind, _), (cells, _, _) in zip(units, done, strict=True):
        rows += [_row(c, seed) for c in cells]
        flags += trial_flags(cells)
        if kind == "arm":
            arm_cells += cells
    if arms:
        rows += [_row(c, seed) for c in _pooled(arm_cells, arms)]
    df = pd.DataFrame(rows, columns=list(COLUMNS))
    df["rms_rank"] = rms_rank(df)
    df.attrs["flags"] = flags
    df.attrs["compile_seconds"] = sum(d[1] for d in done)
    df.attrs["run_seconds"] = sum(d[2] for d in done)
    return df


def rms_rank(df):
    """The ``rms_rank`` column of ``df`` (:data:`COLUMNS`): per scenario and segment, the rank of
    the mean RMS error among the :func:`contenders`' rows, those with a failed trial after the
    others; NaN for an oracle's row and a law told the true model. Every controller of a
    scenario's seed meets the same robot, noise and swaps, so the RMS errors of one segment compare
    where the ratios (different floors) do not."""
    import pandas as pd

    out = pd.Series(np.nan, index=df.index, dtype=float)
    ranked = df[contenders(df)]
    for _, g in ranked.groupby(["scenario", "segment"], sort=False):
        key = g["rms_error_mrad"].where(np.isfinite(g["rms_error_mrad"]), np.inf)
        order = sorted(g.index, key=lambda i: (g.at[i, "failures"] > 0, key[i]))
        out[order] = np.arange(1, len(order) + 1, dtype=float)
    return out


def unit_costs(units: list) -> list[float]:
    """Each unit's expected CPU time, in any unit, for the order the workers take them in
    (:func:`~adaptive_dd.arena.pool.largest_first`): the joints squared (the closed loops' and the
    identification's cost per sample grows about so), times 3 with an excitation phase (its
    design, its closed loop and each seed's identification: about twice the task's closed loops)."""
    out = []
    for kind, what in units:
        if kind == "arm":  # the arm's joints without drawing the arm (its URDF: 70 ms each)
            from adaptive_dd.robots.random_arm import random_arm_joints

            data, _, seed = what
            n, excite = random_arm_joints(int(seed)), float(data.get("run", {}).get("excite", 0.0))
        else:
            n, excite = what.n_joints, float(what.excite)
        out.append(float(n * n * (3.0 if excite > 0 else 1.0)))
    return out


def unit_design(unit):
    """A drawn arm's excitation (:func:`~adaptive_dd.closed_loop.excitation_phase.excitation_reference`,
    the design every seed of the arm tracks), made apart from its unit so that a worker can make it
    while another compiles the closed loop (:func:`~adaptive_dd.arena.pool.run_units`); None for a
    unit with no excitation phase."""
    kind, what = unit
    if kind != "arm" or not float(what[0].get("run", {}).get("excite", 0.0)) > 0:
        return None
    from adaptive_dd.benchmark.population import population_scenario
    from adaptive_dd.closed_loop.excitation_phase import excitation_reference

    return excitation_reference(population_scenario(*what))


def run_unit(
    unit, controllers, seeds, progress: bool = False, design=None
) -> tuple[list[dict], float, float]:
    """One unit of the leaderboard (:mod:`adaptive_dd.arena.pool`): ``("scenario", Scenario)`` or
    ``("arm", (template data, template path, arm seed))``; returns its cells (:func:`_cells`) and
    the seconds its runs spent compiling and running. ``design``: the arm's excitation made
    beforehand (:func:`unit_design`; None: designed here)."""
    from contextlib import nullcontext

    from adaptive_dd.closed_loop.excitation_phase import designed_excitation

    kind, what = unit
    if kind == "arm":
        from adaptive_dd.benchmark.population import population_scenario

        what = population_scenario(*what)
    times = {"compile": 0.0, "run": 0.0}
    with nullcontext() if design is None else designed_excitation(what.name, design):
        cells = _run_cells(what, kind, controllers, seeds, progress, times)
    return cells, times["compile"], times["run"]


def _run_cells(sc, kind: str, controllers, seeds, progress, times=None) -> list[dict]:
    """Run one scenario's controllers and floors; its cells (:func:`_cells`). ``times``: a dict
    whose ``compile`` and ``run`` [s] the run's compile and other wall time are added to."""
    from adaptive_dd.benchmark.runner import run_benchmark

    if seeds is not None:
        sc = dataclasses.replace(sc, seeds=seeds)
    names, floors, missing, laws = _with_floors(sc, controllers)
    # no trajectories kept and no excitation report's scale check: the table reads neither; a floor
    # that cannot run is the row's floor_note (missing), said once
    res = run_benchmark(
        sc.with_controllers(names), progress=progress, keep_trajectories=0, scale_check=False,
        warn_missing_floors=False,
    )  # fmt: skip
    if times is not None:
        times["compile"] += float(res.compile_time or 0.0)
        times["run"] += float(res.wall_time or 0.0)
    floors = {n: floors.get(n, r.floor) for n, r in res.runs.items()}
    per = _per_seed(res, list(res.runs))
    segs = sc.segments()
    masses, t0 = [m for (_, _, m) in segs], [a for (a, _, _) in segs]
    from adaptive_dd.benchmark.metrics import floor_caveat

    cells = _cells(sc.name, kind, per, floors, missing, masses, sc.sample_period, res.seed_indices, t0)
    caveat, gains = floor_caveat(sc), _gains_apart(sc.with_controllers(names))
    for c in cells:
        c["law"] = laws.get(c["controller"], c["controller"])
        if caveat and c["floor"] and not c["floor_note"]:
            c["floor_note"] = caveat
        if c["controller"] in gains and c["floor"]:
            c["floor_note"] = "; ".join(filter(None, (c["floor_note"], gains[c["controller"]])))
    return cells


def _gains_apart(sc) -> dict[str, str]:
    """``{name results carry: what of its gains differs from its floor's}`` in ``sc`` (a scenario's
    table set another bandwidth or damping for the law than for its floor,
    :func:`~adaptive_dd.benchmark.preflight.floor_mismatches`): the row's ratio measures the gains
    as well as the law, which its ``floor_note`` says (ranked before without a word)."""
    from adaptive_dd.benchmark.preflight import floor_mismatches
    from adaptive_dd.benchmark.scenario_settings import result_names

    differ = floor_mismatches(sc)
    if not differ:
        return {}
    named = result_names(
        sc.controllers, {n: sc.options(n) for n, _ in sc.controller_options}, sc.source, sc.origin
    )
    return {named[k]: "; ".join(v) for k, v in differ.items()}


def _template(template) -> tuple[dict, str]:
    """The population's template, parsed, and its path."""
    from adaptive_dd.benchmark.scenario import read_toml

    root = Path(__file__).resolve().parents[2]
    path = Path(template) if template is not None else root / POPULATION_TEMPLATE
    if not path.is_file():
        raise ParameterError(
            f"leaderboard: --template {path}: no such file; give a template scenario with a [[payload]] "
            f"schedule (the source tree's {POPULATION_TEMPLATE})"
        )
    return read_toml(path), str(path)
