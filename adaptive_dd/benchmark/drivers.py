"""The paths of a two-link run, on the same set-up and the closed loop's one per-sample glue.

:func:`run_compiled` drives :func:`~adaptive_dd.closed_loop.glue.closed_loop_block` over a run,
block by block, with the two-link plant, a built-in controller's law and the paper's estimator
as its compile-time choices (:mod:`adaptive_dd.benchmark.compiled`); :func:`run_plugin` drives a
compiled plug-in's two-link loop (:func:`~adaptive_dd.closed_loop.plugin_loop.plugin_loop`, the
same per-sample glue with the plug-in's functions); :func:`run_python` runs
any controller object (``reset / command / observe``) on the closed loop's one Python path
(:func:`~adaptive_dd.closed_loop.python_path.run_python_batch`, shared with the N-joint arm)
around the batch wrappers of the same per-trial functions
(:func:`~adaptive_dd.closed_loop.batches.measure_batch`,
:func:`~adaptive_dd.closed_loop.batches.apply_batch`,
:func:`~adaptive_dd.closed_loop.batches.sigma_batch`): the measurement with its dropouts,
the divergence rule, actuator, plant step, failure freeze, streamed sums and recordings are
written once (:mod:`adaptive_dd.closed_loop.glue`), so the two paths agree to rounding.
"""

from __future__ import annotations

from functools import partial

import numpy as np

from adaptive_dd.benchmark.compiled import OnlineKernelConfig, TwoLinkPlant
from adaptive_dd.benchmark.streaming import segment_bounds
from adaptive_dd.benchmark.trials import new_run, sensor_of, true_sigma
from adaptive_dd.benchmark.types import MAX_ALARMS, MAX_ERROR, SETTLE, ControllerRun
from adaptive_dd.closed_loop.batches import apply_batch, measure_batch, sigma_batch
from adaptive_dd.closed_loop.glue import (
    Alarms,
    alarm_lists,
    closed_loop_block,
    in_threads,
    segment_of,
)
from adaptive_dd.closed_loop.noise import NoiseBlocks
from adaptive_dd.closed_loop.python_path import PythonGlue, run_python_batch
from adaptive_dd.closed_loop.tool_frame import tool_tables
from adaptive_dd.closed_loop.types import Io, Recording, RunConstants, TrialState
from adaptive_dd.controllers.compiled_form import LAW_ADAPTIVE, LAW_SLOTINE, CompiledSpec
from adaptive_dd.identification.two_link_online import TwoLinkOnlineConfig, online_init
from adaptive_dd.plant.sampling import first_sample
from adaptive_dd.plant.simulator import MAX_SPEED
from adaptive_dd.plant.two_link_integrator import friction_vector

__all__ = ["run_compiled", "run_constants", "run_plugin", "run_python"]


def run_constants(scenario, reference) -> tuple[RunConstants, Io, np.ndarray]:
    """``(rc, io, sigma_seg)``: what every trial of every controller shares, made once per run
    (the tool frame's placements along the reference among it); ``reference`` is ``(q_d, qd_d,
    qdd_d)``; ``sigma_seg (G, 7)`` the true base parameters of each segment."""
    N, T = scenario.n_samples, scenario.sample_period
    seg_start, seg_end, seg_settled = segment_bounds(scenario.segments(), T, SETTLE)
    c = np.ascontiguousarray
    q_d, qd_d, qdd_d = (c(x, dtype=float) for x in reference)
    tool = tool_tables(scenario.arm, q_d)
    rc = RunConstants(
        float(T), float(MAX_ERROR), float(MAX_SPEED), q_d, qd_d, qdd_d, seg_start, seg_end, seg_settled,
        *tool,
    )  # fmt: skip
    arm = scenario.closed_forms
    act, sens = arm.actuator, sensor_of(scenario)
    io = Io(
        c(act._lim, dtype=float), c(act._lsb, dtype=float), bool(act.saturate), bool(act.quantize),
        c(sens.resolution, dtype=float), c(sens.noise_std, dtype=float), bool(sens.quantize),
    )  # fmt: skip
    sigma_true, _ = true_sigma(scenario, np.arange(N) * T)
    swap_k = np.array([first_sample(at, T) for at in scenario.swap_times], dtype=np.int64)
    return rc, io, c(sigma_true[np.concatenate(([0], np.minimum(swap_k, N - 1)))])


def _records(
    name, ctrl, scenario, rc: RunConstants, sigma_seg, S: int, keep: int, estimates: bool, engine: str
):
    """``(run, pl, ts, rec)``: an empty run of S trials, their plant and state at the reference's
    start, and the recording over the run's arrays."""
    N = rc.q_d.shape[0]
    run = new_run(name, ctrl, S, len(rc.seg_start), N, keep, estimates, engine)
    q = np.broadcast_to(rc.q_d[0], (S, 2)).copy()
    qd = np.broadcast_to(rc.qd_d[0], (S, 2)).copy()
    run.dropped = np.zeros(S, dtype=np.int64)
    arm = scenario.closed_forms
    pl = TwoLinkPlant(
        sigma_seg, int(scenario.substeps), int(arm.friction_code), friction_vector(arm.friction_params),
        np.ones((S, 2)), np.zeros((S, 2)),
    )  # fmt: skip
    ts = TrialState(
        q, qd, qd == 0.0, run.failed, run.failed_at, q.copy(), qd.copy(), run.dropped, run.failed_cmd
    )
    rec = Recording(
        run.q, run.qd, run.tau, run.saturated, run.sigma_hat if estimates else np.zeros((0, N, 7)),
        run.sigma_end if estimates else np.zeros((S, len(rc.seg_start), 7)),
    )  # fmt: skip
    return run, pl, ts, rec


def run_compiled(name, ctrl, spec: CompiledSpec, scenario, idx, constants, keep: int, bar) -> ControllerRun:
    """One built-in controller's trials on the compiled path; the same result as :func:`run_python`.

    ``spec`` its :func:`~adaptive_dd.controllers.compiled_form.compiled_spec`; ``idx`` the seed indices;
    ``constants`` the run's :func:`run_constants`; ``keep`` trials recorded; ``bar`` a progress
    bar (samples) or None."""
    S, N, T = len(idx), scenario.n_samples, scenario.sample_period
    adaptive = spec.law == LAW_ADAPTIVE
    estimates = adaptive or spec.law == LAW_SLOTINE
    rc, io, sigma_seg = constants
    run, pl, ts, rec = _records(name, ctrl, scenario, rc, sigma_seg, S, keep, estimates, "compiled")
    cfg = spec.online if adaptive else TwoLinkOnlineConfig(sample_period=T, tau_f=max(0.01, T))  # unused
    es = online_init(cfg, S, spec.sigma)
    ec = OnlineKernelConfig(*cfg.packed, adaptive)
    alarms = Alarms(np.zeros((S, MAX_ALARMS)), np.zeros(S, dtype=np.int64))
    for k0, k1, noise, drop in NoiseBlocks(scenario, idx, 4).blocks(N):
        args = (k0, k1, noise, drop, rc, io, pl, ts, run.acc, rec, alarms, spec.gains, es, ec, es, estimates)
        in_threads(closed_loop_block, S, args)
        if bar is not None:
            bar.update(k1 - k0)
    if adaptive:
        run.skipped = es.n_skipped.copy()
    if adaptive and cfg.detector is not None:
        run.alarm_times = alarm_lists(alarms)
    run.explain_failures(rc.max_error, rc.max_speed)
    return run


def run_plugin(name, ctrl, scenario, idx, constants, keep: int, bar) -> ControllerRun:
    """A compiled plug-in's trials in its two-link compiled loop
    (:func:`~adaptive_dd.closed_loop.plugin_loop.plugin_loop` with ``"two-link"``, driven as on
    any arm: :func:`~adaptive_dd.closed_loop.runner.drive_plugin`); its model terms of the closed
    forms' sigma (each segment's true one for a plug-in with ``needs_true_model``). Arguments as
    :func:`run_compiled`'s."""
    from adaptive_dd.closed_loop.runner import drive_plugin
    from adaptive_dd.controllers.plugins import compiled_form

    S, N, T = len(idx), scenario.n_samples, scenario.sample_period
    rc, io, sigma_seg = constants
    form = compiled_form(name, ctrl, S, T)
    run, pl, ts, rec = _records(name, ctrl, scenario, rc, sigma_seg, S, keep, form.estimates, "compiled")
    alarms = Alarms(np.zeros((S, MAX_ALARMS)), np.zeros(S, dtype=np.int64))
    sigma = scenario.closed_forms.sigma  # read-only: copied, so that the model and the true ones
    pis = np.array(sigma_seg[None] if form.true_model else sigma[None, None], dtype=float)  # share a type
    tail = (None, pis, 0, np.zeros((0, 0)), form.need, form.params, form.state, form.estimates)

    def blocks():
        for k0, k1, noise, drop in NoiseBlocks(scenario, idx, 4).blocks(N):
            yield k0, k1, (k0, k1, noise, drop, rc, io, pl, ts, run.acc, rec, alarms, *tail)

    return drive_plugin(name, ctrl, form, "two-link", run, blocks, alarms, rc, bar)


def run_python(name, ctrl, scenario, idx, constants, keep: int, bar) -> ControllerRun:
    """One controller object's trials on the Python path
    (:func:`~adaptive_dd.closed_loop.python_path.run_python_batch`): a vectorised batch, one
    ``command`` and one ``observe`` per sample; a controller that raises fails its own trials
    (``run.error``). Arguments as :func:`run_compiled`'s."""
    rc, io, sigma_seg = constants

    def records(estimates: bool):
        run, pl, ts, rec = _records(name, ctrl, scenario, rc, sigma_seg, len(idx), keep, estimates, "python")
        glue = PythonGlue(
            measure=partial(measure_batch, io, ts),
            sigma_true=lambda k: sigma_seg[segment_of(rc, k)],
            apply=partial(apply_batch, rc, io, pl, ts, run.acc, rec),
            record_estimate=partial(sigma_batch, rc, rec),
        )
        return run, glue

    return run_python_batch(ctrl, rc, NoiseBlocks(scenario, idx, 4), records, bar)
