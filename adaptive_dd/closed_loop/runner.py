"""Every controller of a scenario over every seed, on an N-joint arm.

Trial i of every controller uses the noise of seed ``(scenario.seed, seed_indices[i])``
(common random numbers), drawn in blocks of :data:`CHUNK` samples
(:class:`~adaptive_dd.closed_loop.noise.NoiseBlocks`: ``(CHUNK, 2 n)`` standard normals per
trial, dropouts from a second generator ``(seed, i, 1)``), once for all the run's controllers
when they fit in :data:`~adaptive_dd.closed_loop.noise.SHARED_BYTES`
(:class:`~adaptive_dd.closed_loop.noise.RunNoise`). Built-in controllers run compiled
(:func:`~adaptive_dd.closed_loop.glue.chain_loop_block`, a block of samples of a range of
trials in one call, ranges in parallel threads); a compiled plug-in (``reset / command /
observe`` as ``numba.njit`` functions: :func:`~adaptive_dd.controllers.plugins.is_compiled`) runs
the same way in its own specialisation of the loop, cached like the built-ins'
(:func:`~adaptive_dd.closed_loop.plugin_loop.plugin_loop`); any other controller object (a
plain-Python plug-in) runs on the Python path
(:func:`~adaptive_dd.closed_loop.python_path.run_python_batch`, shared with the two-link arm),
one ``command`` per sample for the whole batch, and the run says so once. All three call the same
compiled glue.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Sequence
from functools import partial

import numpy as np

from adaptive_dd.benchmark.types import CHUNK, MAX_ALARMS, BenchmarkResult, ControllerRun
from adaptive_dd.closed_loop.batches import apply_batch, measure_batch, sigma_batch
from adaptive_dd.closed_loop.controllers import Law
from adaptive_dd.closed_loop.glue import (
    Alarms,
    alarm_lists,
    chain_estimator,
    chain_law,
    chain_loop_block,
    in_threads,
    segment_of,
)
from adaptive_dd.closed_loop.noise import RunNoise
from adaptive_dd.closed_loop.python_path import PythonGlue, run_python_batch
from adaptive_dd.closed_loop.types import (
    Plant,
    Recording,
    RunConstants,
    StreamedSums,
    TrialState,
    io_of,
    plant_of,
    plant_record,
    reset_plant,
    run_constants,
    true_models,
)
from adaptive_dd.controllers.base import declared
from adaptive_dd.controllers.plugins import (
    BOUNDS_HINT,
    PythonForm,
    compiled_form,
    is_compiled,
    slow_path_note,
)

__all__ = [
    "CHUNK",
    "MAX_ALARMS",
    "make_controller_of",
    "make_controllers",
    "plant_record",
    "run_closed_loop",
    "true_models",
    "true_parameters",
]


def make_controllers(scenario) -> dict:
    """The scenario's controllers by label: built-ins and plug-ins by path
    (:func:`adaptive_dd.controllers.make_controller`)."""
    from adaptive_dd.controllers.registry import scenario_controllers

    return scenario_controllers(scenario)


def make_controller_of(scenario, spec: str) -> tuple[str, object]:
    """``(label, controller)`` of one entry of the scenario's controller list, with its settings
    (:func:`adaptive_dd.controllers.registry.scenario_controller`, the same on every arm)."""
    from adaptive_dd.controllers.registry import scenario_controller

    return scenario_controller(scenario, spec)


def true_parameters(scenario) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per sample: segment index ``(N,)``, true base parameters ``(N, p)``, payload mass ``(N,)``."""
    from adaptive_dd.closed_loop.types import segment_starts

    seg = np.searchsorted(segment_starts(scenario), np.arange(scenario.n_samples), side="right") - 1
    masses = np.array([0.0, *scenario.swap_masses])
    return seg, scenario.segment_sigmas()[seg], masses[seg]


def run_closed_loop(
    scenario,
    controllers: dict | None = None,
    *,
    seed_indices: Sequence[int] | None = None,
    keep_trajectories: int = 3,
    engine: str = "auto",
    bar=None,
    scale_check: bool = True,
    on_run=None,
) -> BenchmarkResult:
    """Run every controller of ``scenario`` (an N-joint arm) over its seeds.

    Parameters
    ----------
    scenario : Scenario
        With ``scenario.arm`` an :class:`~adaptive_dd.plant.arm.Arm`.
    controllers : dict, optional
        Controller objects by name (default: the scenario's, :func:`make_controllers`).
    seed_indices : sequence of int, optional
        Default ``range(scenario.seeds)``.
    keep_trajectories : int
        First seeds whose trajectories are kept.
    engine : {"auto", "python", "compiled"}
        ``python`` runs the built-ins through their Python form too.
    bar : tqdm-like or None
        Progress (samples).
    scale_check : bool
        With an excitation phase (``[run] excite``), compute its report's ``estimator_scale`` (a
        check, reported and not applied:
        :func:`~adaptive_dd.closed_loop.excitation_phase.identify_excitation`).
    on_run : callable, optional
        ``on_run(result, run)`` after each controller's trials
        (:func:`~adaptive_dd.benchmark.runner.run_benchmark`'s).
    """
    from adaptive_dd.errors import ParameterError

    idx = tuple(range(scenario.seeds)) if seed_indices is None else tuple(int(i) for i in seed_indices)
    if not idx or min(idx) < 0:
        raise ParameterError(f"seed_indices must be a non-empty list of indices >= 0, got {seed_indices}")
    if scenario.excite > 0:  # identification first, then each seed's identified model
        if controllers is not None:
            raise ParameterError(
                "run.excite: the controllers are built per seed from the identified model; "
                "give no controller objects (or set [run] excite = 0)"
            )
        from adaptive_dd.closed_loop.excitation_phase import run_with_excitation

        res = run_with_excitation(
            scenario, idx, run_closed_loop, keep_trajectories, engine, bar=bar, scale_check=scale_check
        )
        for run in res.runs.values() if on_run is not None else ():  # the seeds' runs joined
            on_run(res, run)
        return res
    ctrls = make_controllers(scenario) if controllers is None else controllers
    rc, io, pl = run_constants(scenario), io_of(scenario), plant_of(scenario, idx)
    _, sigma_true, mass = true_parameters(scenario)
    t = np.arange(scenario.n_samples) * rc.T
    res = BenchmarkResult(scenario, t, rc.q_d, sigma_true, mass, seed_indices=idx)
    if scenario.plant is not None:
        res.plant = plant_record(scenario, idx)
    noise = RunNoise(scenario, idx, 2 * scenario.n_joints, scenario.n_samples)  # one draw for all
    for name, ctrl in ctrls.items():
        builtin = isinstance(ctrl, Law)
        plugin = not builtin and is_compiled(ctrl)
        if plugin and engine == "python":  # its njit functions trial by trial, as asked
            ctrl, plugin = PythonForm(name, ctrl, scenario.arm, "engine='python'"), False
        if engine == "compiled" and not (builtin or plugin):
            raise ParameterError(f"engine='compiled': no compiled path for {name!r}; use engine='auto'")
        if builtin and engine != "python":
            runner = _run_compiled
        elif plugin:
            runner = _run_plugin
        else:
            runner = _run_python
            if not (builtin or isinstance(ctrl, PythonForm)):  # a plain-Python one: say once why it is slow
                _say(bar, slow_path_note(name, ctrl))
        res.runs[name] = runner(name, ctrl, scenario, idx, rc, io, pl, keep_trajectories, bar, noise)
        if on_run is not None:
            on_run(res, res.runs[name])
    return res


def _say(bar, line: str) -> None:
    """Print ``line`` on stderr on a line of its own, the progress bar (if any) cleared first."""
    if bar is not None:
        bar.clear()
    print(line, file=sys.stderr, flush=True)
    if bar is not None:
        bar.refresh()


# ------------------------------------------------------------------------ shared set-up
def _records(
    name, ctrl, scenario, rc: RunConstants, pl: Plant, S: int, keep: int, estimates: bool, engine: str
):
    """``(run, ts, acc, rec)``: an empty run of S trials over the arrays its paths fill in place
    (trial state at the reference's start, streamed sums, the recording of the first ``keep``)."""
    N, n = rc.q_d.shape
    G, p = pl.pi_seg.shape[1], scenario.arm.base.B.shape[0]
    reset_plant(pl)
    K = min(keep, S)
    q = np.broadcast_to(rc.q_d[0], (S, n)).copy()
    qd = np.broadcast_to(rc.qd_d[0], (S, n)).copy()
    z = np.zeros(S, dtype=np.int64)
    ts = TrialState(q, qd, qd == 0.0, np.zeros(S, np.bool_), z - 1, q.copy(), qd.copy(), z.copy(), z - 1)
    acc = StreamedSums.zeros(S, G, n, N)
    rec = Recording(
        np.zeros((K, N, n)), np.zeros((K, N, n)), np.zeros((K, N, n)), np.zeros((K, N, n), np.bool_),
        np.full((K if estimates else 0, N, p), np.nan), np.full((S, G, p), np.nan),
    )  # fmt: skip
    run = ControllerRun(
        name=name, acc=acc, e_norm=acc.e_norm, sigma_end=rec.sigma_end if estimates else None,
        failed=ts.failed, failed_at=ts.failed_at, failed_cmd=ts.failed_cmd, floor=declared(ctrl, "floor"),
        q=rec.q, qd=rec.qd, tau=rec.tau, saturated=rec.saturated,
        sigma_hat=rec.sigma if estimates and K else None, engine=engine, dropped=ts.n_dropped,
    )  # fmt: skip
    return run, ts, acc, rec


# ------------------------------------------------------------------------ the two paths
def _run_compiled(name, ctrl: Law, scenario, idx, rc, io, pl, keep, bar, noise=None) -> ControllerRun:
    """One built-in controller's trials on the compiled loop; ``noise``: the run's
    :class:`~adaptive_dd.closed_loop.noise.RunNoise` (default: drawn for this controller)."""
    S, N, n = len(idx), scenario.n_samples, scenario.n_joints
    form = ctrl.compiled_form(S, rc.T)
    run, ts, acc, rec = _records(name, ctrl, scenario, rc, pl, S, keep, form.estimates, "compiled")
    alarms = Alarms(np.zeros((S, MAX_ALARMS)), np.zeros(S, dtype=np.int64))
    law = chain_law(form.cfg, true_models(pl), scenario.arm.base.B)
    # every law carries an estimator (inactive but for adaptive_ct): one compiled loop for all
    ec, es = chain_estimator(form.ec, form.es, scenario.arm, rc.T)
    noise = RunNoise(scenario, idx, 2 * n, N) if noise is None else noise
    for k0, k1, block, drop in noise.blocks():
        args = (
            k0,
            k1,
            block,
            drop,
            rc,
            io,
            pl,
            ts,
            acc,
            rec,
            alarms,
            law,
            form.state,
            ec,
            es,
            form.estimates,
        )
        in_threads(chain_loop_block, S, args)
        if bar is not None:
            bar.update(k1 - k0)
    run.skipped = ctrl.skipped(form)
    if ctrl.has_detector:
        run.alarm_times = alarm_lists(alarms)
    run.explain_failures(rc.max_error, rc.max_speed)
    return run


def _run_plugin(name, ctrl, scenario, idx, rc, io, pl, keep, bar, noise=None) -> ControllerRun:
    """A compiled plug-in's trials in its specialisation of the compiled loop
    (:func:`~adaptive_dd.closed_loop.plugin_loop.plugin_loop`, driven by :func:`drive_plugin`),
    blocks and threads as :func:`_run_compiled`; ``noise`` as :func:`_run_compiled`'s."""
    S, N, n = len(idx), scenario.n_samples, scenario.n_joints
    form = compiled_form(name, ctrl, S, rc.T)
    run, ts, acc, rec = _records(name, ctrl, scenario, rc, pl, S, keep, form.estimates, "compiled")
    alarms = Alarms(np.zeros((S, MAX_ALARMS)), np.zeros(S, dtype=np.int64))
    pis = (
        true_models(pl) if form.true_model else np.ascontiguousarray(scenario.arm.pi, dtype=float)[None, None]
    )
    arm = scenario.arm
    kin = (int(arm.payload_joint), np.ascontiguousarray(arm.payload_map, dtype=float))
    tail = (pl.chain, pis, *kin, form.need, form.params, form.state, form.estimates)

    def blocks():
        draws = RunNoise(scenario, idx, 2 * n, N) if noise is None else noise
        for k0, k1, block, drop in draws.blocks():
            yield k0, k1, (k0, k1, block, drop, rc, io, pl, ts, acc, rec, alarms, *tail)

    return drive_plugin(name, ctrl, form, "chain", run, blocks, alarms, rc, bar)


def drive_plugin(name, ctrl, form, runtime: str, run, blocks, alarms, rc, bar) -> ControllerRun:
    """Run a compiled plug-in's loop (:func:`~adaptive_dd.closed_loop.plugin_loop.plugin_loop` of
    ``form``'s functions and ``runtime``) over ``blocks()``, which yields ``(k0, k1, args)`` per
    block of samples, into ``run``. The loop is compiled (or loaded) on its first call, with no
    trial, timed and printed apart from the run; an exception raised inside it fails the
    plug-in's trials with the message in ``run.error``, as on the Python path; then the alarms
    (``alarms``, a plug-in with ``has_detector``) and the failures' reasons, a non-finite command
    naming the terms it did not declare (NaN)."""
    from adaptive_dd.closed_loop.plugin_loop import NEEDS, plugin_loop

    S = run.failed.shape[0]
    try:
        loop = plugin_loop((form.reset, form.command, form.observe, form.estimate), runtime)
        for k0, k1, args in blocks():
            if k0 == 0:  # compile (or find) this plug-in's loop first: no trial, timed apart
                _first_call(name, loop, args, bar)
            in_threads(loop, S, args)
            if bar is not None:
                bar.update(k1 - k0)
    except Exception as exc:  # contain any plug-in failure to its own trials
        hint = f" ({BOUNDS_HINT})" if isinstance(exc, IndexError) else ""
        run.error = f"{type(exc).__name__} in the compiled plug-in: {exc}{hint}"
        run.failed[:] = True
    if getattr(ctrl, "has_detector", False):
        run.alarm_times = alarm_lists(alarms)
    run.explain_failures(rc.max_error, rc.max_speed)
    undeclared = [k for k in ("gravity", "mass_matrix", "bias") if not form.need & NEEDS[k]]  # NaN terms
    if undeclared:  # a term it reads without declaring it is NaN: the likeliest cause of a NaN command
        hint = (
            f" (if it reads {', '.join(undeclared)}, which it does not declare in needs: those terms are "
            "NaN in its loop; declare what it reads)"
        )
        for i, why in run.failed_why.items():
            if why.startswith("non-finite torque command"):
                run.failed_why[i] = why + hint
    return run


_SAID: set = set()
"""(name, loop) of the plug-ins whose loop :func:`_first_call` has said it runs in."""


def _first_call(name, loop, args, bar) -> None:
    """The loop's first call, with no trial: compiled when the cache does not hold it, and then
    said with the time it took; loaded, the process's first run of it says it is in the compiled
    loop (as a run says of a plain-Python controller that it is on the slow path). Printed before
    the progress bar comes back, not inside it."""
    t0, missed = time.perf_counter(), sum(loop.stats.cache_misses.values())
    known = len(loop.overloads)
    if bar is not None:  # no progress bar (nor its estimate) while it compiles
        bar.clear()
    in_threads(loop, 0, args)
    why = getattr(loop, "adaptive_dd_uncached", None)
    if len(loop.overloads) > known and (sum(loop.stats.cache_misses.values()) > missed or why):
        again = "later runs load it" if not why else f"compiled again by every run: {why}"
        spent = time.perf_counter() - t0
        said = f"{name}: compiled the plug-in into the closed loop in {spent:.1f} s ({again})"
    elif (name, loop) not in _SAID:
        said = f"{name}: a compiled plug-in, in the compiled closed loop (compiled before)"
    else:
        said = None  # said once per process: a study of many arms runs the same loop again
    _SAID.add((name, loop))
    if said:
        print(said, file=sys.stderr, flush=True)
    if bar is not None:
        bar.refresh()


def _run_python(name, ctrl, scenario, idx, rc, io, pl, keep, bar, noise=None) -> ControllerRun:
    """One controller's trials on the Python path
    (:func:`~adaptive_dd.closed_loop.python_path.run_python_batch`); ``noise`` a
    :class:`~adaptive_dd.closed_loop.noise.RunNoise` (default: drawn for this controller), which
    the path only reads (each sample's column is copied before it is measured)."""
    pi_true = true_models(pl)
    sig_true = pi_true @ scenario.arm.base.B.T  # (S, G, p)

    def records(estimates: bool):
        run, ts, acc, rec = _records(name, ctrl, scenario, rc, pl, len(idx), keep, estimates, "python")
        glue = PythonGlue(
            measure=partial(measure_batch, io, ts),
            sigma_true=lambda k: sig_true[:, segment_of(rc, k)],
            pi_true=lambda k: pi_true[:, segment_of(rc, k)],
            apply=partial(apply_batch, rc, io, pl, ts, acc, rec),
            record_estimate=partial(sigma_batch, rc, rec),
        )
        return run, glue

    draws = RunNoise(scenario, idx, 2 * scenario.n_joints, scenario.n_samples) if noise is None else noise
    return run_python_batch(ctrl, rc, draws, records, bar)
