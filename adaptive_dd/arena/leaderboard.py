"""The leaderboard: a list of controllers on a list of scenarios, each ranked per seed against
its own floor (the same law given the true robot), as one table.

:func:`leaderboard` runs each scenario once with the controllers asked for and the floor of
each (a floor that cannot run says why in the row), and returns one row per scenario,
controller and payload segment (:data:`COLUMNS` names every column with its unit). The
scenarios are an argument: paths, :class:`~adaptive_dd.benchmark.scenario.Scenario` objects or
anything :func:`~adaptive_dd.benchmark.scenario.load_scenario` reads; the default is the shipped
N-joint ones (:func:`shipped_scenarios`). ``adaptive-dd leaderboard`` writes the table as CSV and
JSON and draws it (:mod:`adaptive_dd.cli.leaderboard`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from importlib import resources
from pathlib import Path

import numpy as np

from adaptive_dd.errors import ParameterError

__all__ = [
    "BOOTSTRAP_RESAMPLES",
    "COLUMNS",
    "DEFAULT_CONTROLLERS",
    "leaderboard",
    "ratio_columns",
    "shipped_scenarios",
]

DEFAULT_CONTROLLERS = (
    "pd",
    "pd_gravity",
    "ct_nominal",
    "momentum_observer_ct",
    "sliding_mode",
    "slotine_li",
    "composite",
    "adaptive_ct",
)
"""The controllers ranked by default (their floors are added: ``ct_oracle``,
``pd_gravity_oracle``, ``slotine_li_oracle``)."""

BOOTSTRAP_RESAMPLES = 2000
"""Resamples of the seeds for the 95 % interval of the mean ratio (percentile bootstrap)."""

COLUMNS: dict[str, tuple[str, str]] = {
    "scenario": ("-", "the scenario's name"),
    "controller": ("-", "the controller ranked"),
    "floor": ("-", "the controller it is divided by, seed by seed (the same law with the true robot)"),
    "floor_note": ("-", "empty, or why the row has no ratio"),
    "segment": ("-", "payload segment, 0-based"),
    "payload_kg": ("kg", "the payload carried in the segment"),
    "seeds": ("-", "seeds whose trial did not fail before the segment's end"),
    "ratio_mean": ("-", "mean over seeds of RMS error / the floor's RMS error (same seed, same segment)"),
    "ratio_ci95_low": ("-", "percentile-bootstrap 95 % interval of ratio_mean, low end"),
    "ratio_ci95_high": ("-", "percentile-bootstrap 95 % interval of ratio_mean, high end"),
    "ratio_p90": ("-", "90th percentile of the per-seed ratio (linear interpolation)"),
    "ratio_cvar10": ("-", "CVaR of the worst 10 %: mean of the ceil(0.1 n) largest per-seed ratios"),
    "ratio_max": ("-", "largest per-seed ratio"),
    "failures": ("-", "trials that failed (diverged, ran away or raised) before the segment's end"),
    "rms_error_mrad": ("mrad", "mean over seeds of the joint-space RMS tracking error |q_d - q|"),
    "floor_rms_error_mrad": ("mrad", "the same of the floor"),
    "rms_torque_Nm": ("N m", "mean over seeds of the RMS applied torque (norm over joints)"),
    "saturation_pct": ("%", "mean over seeds of the samples with a joint's command beyond its limit"),
    "floor_saturation_pct": ("%", "the same of the floor (a saturated floor makes the ratio optimistic)"),
}
"""Every column of the table: ``name -> (unit, meaning)``."""


def shipped_scenarios() -> list[Path]:
    """The shipped N-joint scenarios with a drawn plant: ur5, panda, iiwa14, vertical3
    (``adaptive_dd/scenarios``) and the Kinova Gen3 (``benchmarks/scenarios``, when the source
    tree is at hand)."""
    pkg = resources.files("adaptive_dd.scenarios")
    names = ("ur5_tool_swap", "panda_payload", "iiwa14_payload", "vertical3_payload")
    out = [Path(str(pkg.joinpath(f"{n}.toml"))) for n in names]
    gen3 = Path(__file__).resolve().parents[2] / "benchmarks" / "scenarios" / "gen3_drawn.toml"
    return out + ([gen3] if gen3.is_file() else [])


def ratio_columns(ratio: np.ndarray, rng: np.random.Generator) -> dict[str, float]:
    """The ratio columns of :data:`COLUMNS` from per-seed ratios ``(n,)`` (NaN: left out); the
    bootstrap draws from ``rng``. All NaN when no ratio is finite."""
    r = np.asarray(ratio, float)
    r = r[np.isfinite(r)]
    keys = ("ratio_mean", "ratio_ci95_low", "ratio_ci95_high", "ratio_p90", "ratio_cvar10", "ratio_max")
    if r.size == 0:
        return dict.fromkeys(keys, np.nan)
    boot = r[rng.integers(0, r.size, (BOOTSTRAP_RESAMPLES, r.size))].mean(axis=1)
    worst = np.sort(r)[::-1][: max(1, int(np.ceil(0.1 * r.size)))]
    vals = (r.mean(), *np.percentile(boot, [2.5, 97.5]), np.percentile(r, 90), worst.mean(), r.max())
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


def _with_floors(sc, names: Sequence[str]) -> tuple[tuple[str, ...], dict, dict]:
    """The names to run (each asked-for one and its floor), each one's floor by the label its
    results carry, and why a floor that does not build is missing (its row then has no ratio and
    says so)."""
    from adaptive_dd.controllers.registry import scenario_controller

    floors: dict[str, str | None] = {}
    missing: dict[str, str] = {}
    run: list[str] = []
    for name in names:
        try:
            label, ctrl = scenario_controller(sc, name)  # results carry the label (a plug-in's class)
        except ParameterError as exc:
            raise ParameterError(f"leaderboard: {sc.source}: {exc}") from None
        floor = floors[label] = getattr(ctrl, "floor", "ct_oracle")
        if floor is not None and floor not in run and floor not in missing:
            try:
                scenario_controller(sc, floor)
            except ParameterError as exc:
                missing[floor] = f"its floor {floor} cannot run here: {exc}"
        for n in (name, floor):
            if n is not None and n not in run and n not in missing:
                run.append(n)
    return tuple(run), floors, missing


def _rows(res, floors: dict, missing: dict, rng: np.random.Generator) -> list[dict]:
    from adaptive_dd.benchmark.metrics import per_seed_segment_metrics

    sc = res.scenario
    masses = [m for (_, _, m) in sc.segments()]
    with np.errstate(invalid="ignore", divide="ignore"):  # failed trials' NaN, estimates of no payload
        per = {n: per_seed_segment_metrics(res, r, recovery=False) for n, r in res.runs.items()}
    rows = []
    for name, floor in floors.items():
        m = per[name]
        fm = per.get(floor) if floor is not None else None
        note = "" if fm is not None else ("an oracle: its own floor" if floor is None else missing[floor])
        for i, mass in enumerate(masses):
            e = m["rms_error"][:, i]  # NaN: the trial failed before the segment's end
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio = e / fm["rms_error"][:, i] if fm is not None else np.full(1, np.nan)
            rows.append(
                {
                    "scenario": sc.name, "controller": name, "floor": floor or "", "floor_note": note,
                    "segment": i, "payload_kg": float(mass), "seeds": int(np.sum(np.isfinite(e))),
                    **ratio_columns(ratio, rng), "failures": int(np.sum(~np.isfinite(e))),
                    "rms_error_mrad": 1e3 * _mean(e),
                    "floor_rms_error_mrad": 1e3 * _mean(fm["rms_error"][:, i]) if fm else np.nan,
                    "rms_torque_Nm": _mean(m["rms_torque"][:, i]),
                    "saturation_pct": 100 * _mean(m["saturation_fraction"][:, i]),
                    "floor_saturation_pct": 100 * _mean(fm["saturation_fraction"][:, i]) if fm else np.nan,
                }
            )  # fmt: skip
    return rows


def _mean(x) -> float:
    """Mean of the finite entries (NaN if none)."""
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    return float(x.mean()) if x.size else float("nan")


def leaderboard(
    scenarios: Sequence | None = None,
    controllers: Sequence[str] = DEFAULT_CONTROLLERS,
    seeds: int | None = 3,
    rng: np.random.Generator | None = None,
    progress: bool = False,
):
    """Rank ``controllers`` on ``scenarios`` against each one's floor, seed by seed.

    Parameters
    ----------
    scenarios : sequence, optional
        Scenario files, :class:`~adaptive_dd.benchmark.scenario.Scenario` objects, or any other
        source :func:`~adaptive_dd.benchmark.scenario.load_scenario` takes (default
        :func:`shipped_scenarios`). N-joint arms only.
    controllers : sequence of str
        Built-in names or plug-ins ``"package.module:Class"``; each one's floor (its ``floor``
        attribute) runs beside it and is ranked too.
    seeds : int or None
        Seeds per scenario (None: each scenario's own).
    rng : numpy.random.Generator, optional
        For the bootstrap intervals (default ``numpy.random.default_rng(0)``); the trials' noise
        and plants come from each scenario's own seeds (common random numbers: every controller of
        a seed meets the same robot and noise).
    progress : bool
        Show the benchmark's progress bars.

    Returns
    -------
    pandas.DataFrame
        One row per scenario, controller and segment; the columns of :data:`COLUMNS`.

    Raises
    ------
    ParameterError
        No controller, fewer than one seed, a two-link closed-form scenario, an unknown controller.
    """
    import pandas as pd

    from adaptive_dd.benchmark.runner import run_benchmark

    controllers = list(dict.fromkeys(controllers))
    if not controllers:
        raise ParameterError("leaderboard: controllers: name at least one controller")
    if seeds is not None and (isinstance(seeds, bool) or not isinstance(seeds, int) or seeds < 1):
        raise ParameterError(f"leaderboard: seeds must be an integer >= 1, got {seeds!r}")
    rng = np.random.default_rng(0) if rng is None else rng
    rows: list[dict] = []
    for spec in shipped_scenarios() if scenarios is None else scenarios:
        sc = _scenario(spec)
        if seeds is not None:
            sc = dataclasses.replace(sc, seeds=seeds)
        names, floors, missing = _with_floors(sc, controllers)
        res = run_benchmark(dataclasses.replace(sc, controllers=names), progress=progress)
        rows += _rows(res, {n: floors.get(n, r.floor) for n, r in res.runs.items()}, missing, rng)
    return pd.DataFrame(rows, columns=list(COLUMNS))
