"""The closed loop: every controller over every seed, with metrics accumulated as the run streams.

Trial ``(c, i)`` uses the noise of seed ``(scenario.seed, seed_indices[i])`` for every
controller c (common random numbers), so controllers are compared on identical noise.
Built-in controllers run on the compiled path (:mod:`adaptive_dd.benchmark.compiled`: the
whole loop of a trial in one numba call, trials in parallel); any other controller runs on
the Python path (one vectorised batch per controller, a Python call per sample). Both
paths (:mod:`adaptive_dd.benchmark.drivers`) call the same compiled per-sample glue and agree
to rounding (a test holds them to 1e-12).

Memory does not grow with seeds x samples beyond the error norm (float32, for settling
times): metrics are accumulated per trial and segment as the run goes
(:mod:`~adaptive_dd.benchmark.streaming`), sensor noise is drawn in blocks, and full
trajectories are kept for the first ``keep_trajectories`` seeds only (for the figures).

A trial that diverges (non-finite, runaway speed or tracking error > ``MAX_ERROR``) is
stopped and counted; a controller that raises (at reset, command or observe) or returns
a torque of the wrong shape fails its own trials with the message recorded, and the rest
of the benchmark goes on.
"""

from __future__ import annotations

import time
import warnings
from collections import Counter
from collections.abc import Mapping, Sequence

import numpy as np

from adaptive_dd.benchmark.drivers import run_compiled, run_constants, run_plugin, run_python
from adaptive_dd.benchmark.progress import RunClock
from adaptive_dd.benchmark.scenario import Scenario
from adaptive_dd.benchmark.trials import true_sigma
from adaptive_dd.benchmark.types import (
    ENGINES,
    MAX_ERROR,
    SETTLE,
    BenchmarkResult,
    ControllerRun,
)
from adaptive_dd.controllers import Controller
from adaptive_dd.controllers.compiled_form import compiled_spec
from adaptive_dd.controllers.plugins import check_controller_object
from adaptive_dd.errors import ParameterError, RunWarning

__all__ = [
    "ENGINES",
    "MAX_ERROR",
    "SETTLE",
    "BenchmarkResult",
    "ControllerRun",
    "run_benchmark",
    "scenario_controller",
]


def run_benchmark(
    scenario: Scenario,
    progress: bool = True,
    controllers: dict[str, Controller] | None = None,
    *,
    engine: str = "auto",
    keep_trajectories: int = 3,
    seed_indices: Sequence[int] | None = None,
    on_run=None,
    scale_check: bool = True,
    warn_missing_floors: bool = True,
) -> BenchmarkResult:
    """Run every controller of the scenario over all seeds.

    Parameters
    ----------
    scenario : Scenario
    progress : bool
        Show a progress bar.
    controllers : dict, optional
        Controller objects by name, in place of ``make_controller(name)`` (for custom
        gains or your own controller classes).
    engine : {"auto", "python", "compiled"}
        ``auto``: built-in controllers and compiled plug-ins (``njit`` ``reset``, ``command``,
        ``observe``) compiled, others in Python; ``python``: all in Python (a compiled
        plug-in's functions called trial by trial); ``compiled``: an error if a controller
        cannot be compiled.
    keep_trajectories : int
        Seeds (the first ones) whose full trajectories are kept.
    seed_indices : sequence of int, optional
        Seed indices of the trials (default ``range(scenario.seeds)``): a block of seeds
        run alone gives the same numbers as inside a full run.
    on_run : callable, optional
        ``on_run(result, run)`` after each controller's trials (the CLI passes
        :func:`~adaptive_dd.benchmark.metrics.release_error_norm`, which derives what needs the
        per-sample error norm and frees it, so memory holds one controller's norm at a time).
    scale_check : bool
        With an excitation phase, compute its report's ``estimator_scale`` (a check, reported and
        not applied; the leaderboard, which reads no report, leaves it out).
    warn_missing_floors : bool
        Warn (:class:`RunWarning`) when a controller's floor is not among the controllers run: its
        ratios are NaN. False for a caller that runs controllers without their floors on purpose
        and says so itself (a sweep's cell, :func:`~adaptive_dd.simulation.run_trial`, the
        leaderboard); a keyword, not a warnings filter, so that it holds in threads.

    Returns
    -------
    BenchmarkResult
        Every controller's trials: ``to_frame()``, ``summary()``, ``metrics()``, and the
        figures of :mod:`adaptive_dd.plotting`.

    Raises
    ------
    ParameterError
        An unknown ``engine``, empty or negative ``seed_indices``, a controller that cannot run
        on the engine asked for.

    Examples
    --------
    Two seeds of a one-second run, the nominal law beside the oracle, 2 kg picked up at 0.5 s (the
    first run compiles the closed loop: minutes on a cold cache, then cached):

    >>> from adaptive_dd import run_benchmark
    >>> from adaptive_dd.benchmark.scenario import parse_scenario
    >>> sc = parse_scenario({"run": {"duration": 1.0, "seeds": 2,
    ...                              "controllers": ["ct_nominal", "ct_oracle"]},
    ...                      "payload": [{"at": 0.5, "mass": 2.0}]})
    >>> res = run_benchmark(sc, progress=False)
    >>> sorted(res.runs)
    ['ct_nominal', 'ct_oracle']
    >>> s = res.summary().set_index(["controller", "segment"])  # the per-seed ratios to the floor
    >>> bool(s.loc[("ct_nominal", 1), "ratio_mean"] > 10)  # the 2 kg it does not know
    True
    """
    if engine not in ENGINES:
        raise ParameterError(f"engine must be one of {ENGINES}, got {engine!r}")
    if not isinstance(scenario, Scenario):
        raise ParameterError(
            f"run_benchmark: scenario must be a Scenario, got {type(scenario).__name__} {scenario!r:.80}; "
            "load a file with adaptive_dd.benchmark.scenario.load_scenario(path)"
        )
    if controllers is not None and not isinstance(controllers, Mapping):
        raise ParameterError(
            f"run_benchmark: controllers must be a dict {{name: controller object}}, got "
            f"{type(controllers).__name__}; to run some of the scenario's by name, pass "
            "scenario.with_controllers([...])"
        )
    for key, obj in (controllers or {}).items():
        check_controller_object("run_benchmark", f"controllers[{key!r}]", obj)
    if not (isinstance(keep_trajectories, int | np.integer) and keep_trajectories >= 0):
        raise ParameterError(f"keep_trajectories must be an integer >= 0, got {keep_trajectories!r}")
    if seed_indices is not None and not (
        isinstance(seed_indices, Sequence | np.ndarray) and not isinstance(seed_indices, str)
    ):
        raise ParameterError(
            f"run_benchmark: seed_indices is a list of seed indices, got {seed_indices!r}: pass "
            f"[{seed_indices!r}] for that one seed, or range(n)"
        )
    if seed_indices is not None:
        bad = [i for i in seed_indices if isinstance(i, bool) or not isinstance(i, int | np.integer) or i < 0]
        twice = [] if bad else sorted(i for i, k in Counter(map(int, seed_indices)).items() if k > 1)
        if bad or twice or not len(seed_indices):
            raise ParameterError(
                "run_benchmark: seed_indices must be distinct integers >= 0 (a seed run twice would "
                "count twice in every mean), got "
                + (f"{bad!r} among them" if bad else f"{twice} twice" if twice else "an empty list")
            )
    t0 = time.perf_counter()
    total = scenario.n_samples * len(controllers or scenario.controllers)
    with RunClock(total, f"benchmark {scenario.name}", show=progress) as clock:
        if scenario.closed_forms is None:  # the general kernels: adaptive_dd.closed_loop
            from adaptive_dd.closed_loop.runner import run_closed_loop

            res = run_closed_loop(
                scenario, controllers, seed_indices=seed_indices, keep_trajectories=keep_trajectories,
                engine=engine, bar=clock, scale_check=scale_check, on_run=on_run,
            )  # fmt: skip
        else:  # the paper's closed forms
            res = _run_two_link(scenario, clock, controllers, engine, keep_trajectories, seed_indices, on_run)
    res.compile_time = clock.compile_seconds
    res.wall_time = time.perf_counter() - t0 - res.compile_time
    from adaptive_dd.controllers import CONTROLLERS
    from adaptive_dd.plant.kind import run_kind

    kind = run_kind(scenario)
    for name, run in res.runs.items():
        if warn_missing_floors and run.floor is not None and run.floor not in res.runs:
            fix = (
                f"add {run.floor!r} to the scenario's controllers"
                if controllers is None
                else f"put a {run.floor!r} controller in controllers= too (its dict is what runs)"
            )
            if run.floor in CONTROLLERS and not CONTROLLERS[run.floor].applies_to(kind):
                fix = f"{run.floor} does not run on this arm: give {name} another floor (its table's floor)"
            warnings.warn(
                f"run_benchmark: {name}'s floor {run.floor} did not run: its ratios to the floor are "
                f"NaN and its limits are judged on another reference; {fix}",
                RunWarning,
                stacklevel=2,
            )
    return res


def _run_two_link(
    scenario: Scenario, bar: RunClock, controllers, engine: str, keep: int, seed_indices, on_run
) -> BenchmarkResult:
    """:func:`run_benchmark` on the closed forms (``scenario.closed_forms``): each controller
    compiled (:func:`~adaptive_dd.benchmark.drivers.run_compiled`) or in Python
    (:func:`~adaptive_dd.benchmark.drivers.run_python`), as ``engine`` says."""
    if controllers is None:
        from adaptive_dd.controllers.registry import scenario_controllers

        ctrls = scenario_controllers(scenario)
    else:
        ctrls = controllers
    idx = tuple(range(scenario.seeds)) if seed_indices is None else tuple(int(i) for i in seed_indices)
    if not idx or min(idx) < 0:
        raise ParameterError(f"seed_indices must be a non-empty list of indices >= 0, got {seed_indices}")
    N, T = scenario.n_samples, scenario.sample_period
    t = np.arange(N) * T
    ref = scenario.reference.sample(t)
    sigma_true, mass = true_sigma(scenario, t)
    res = BenchmarkResult(scenario, t, ref[0], sigma_true, mass, seed_indices=idx)
    specs = {n: (compiled_spec(c, T) if engine != "python" else None) for n, c in ctrls.items()}
    plugins = {n: _two_link_plugin(n, c, scenario, engine) for n, c in ctrls.items()}
    names = [n for n, s in specs.items() if s is None and plugins[n][0] is None]
    if engine == "compiled" and names:
        raise ParameterError(f"engine='compiled': no compiled path for {names}; use engine='auto'")
    bar.total = len(ctrls) * N
    constants = run_constants(scenario, ref)
    for name, ctrl in ctrls.items():
        if specs[name] is not None:
            run = run_compiled(name, ctrl, specs[name], scenario, idx, constants, keep, bar)
        elif plugins[name][0] is not None:
            run = run_plugin(name, plugins[name][0], scenario, idx, constants, keep, bar)
        else:
            py = plugins[name][1]
            if not type(py).__module__.startswith("adaptive_dd."):  # a user's plain-Python law: say why slow
                from adaptive_dd.closed_loop.runner import _say
                from adaptive_dd.controllers.plugins import slow_path_note

                _say(bar, slow_path_note(name, py))
            run = run_python(name, py, scenario, idx, constants, keep, bar)
        res.runs[name] = run
        if on_run is not None:
            on_run(res, run)
    return res


def _two_link_plugin(name: str, ctrl, scenario, engine: str):
    """``(plugin, ctrl)``: the compiled plug-in that the paper's arm runs in its compiled loop (or
    None), and ``ctrl`` as the Python path takes it. A compiled plug-in comes bare (``controllers=``)
    or wrapped in a :class:`~adaptive_dd.controllers.plugins.PythonForm` for the closed forms'
    other users (:data:`~adaptive_dd.controllers.plugins.CLOSED_FORMS`); with ``engine="python"``
    it runs wrapped, saying so. One that needs the arm's kernels, which the closed forms do not
    have, is refused before the run."""
    from adaptive_dd.controllers.plugins import (
        CLOSED_FORMS,
        PythonForm,
        declared_needs,
        is_compiled,
        no_kernels,
    )

    if isinstance(ctrl, PythonForm):
        inner = ctrl.ctrl if ctrl.why == CLOSED_FORMS else None
    else:
        inner = ctrl if is_compiled(ctrl) else None
    if inner is None:
        return None, ctrl
    if "regressor" in declared_needs(inner):
        raise no_kernels(name, CLOSED_FORMS)
    if engine == "python":
        return None, PythonForm(name, inner, scenario.closed_forms, "engine='python'")
    return inner, ctrl


def scenario_controller(scenario: Scenario, spec: str) -> tuple[str, Controller]:
    """``(label, controller)`` of one entry of the scenario's controller list, built as the run
    builds it (on either arm: :func:`adaptive_dd.controllers.registry.scenario_controller`)."""
    from adaptive_dd.controllers.registry import scenario_controller as build

    return build(scenario, spec)
