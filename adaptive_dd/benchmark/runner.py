"""The closed loop: every controller over every seed, with metrics accumulated as the run streams.

Trial ``(c, i)`` uses the noise of seed ``(scenario.seed, seed_indices[i])`` for every
controller c (common random numbers), so controllers are compared on identical noise.
Built-in controllers run on the compiled path (:mod:`adaptive_dd.benchmark.compiled`: the
whole loop of a trial in one numba call, trials in parallel); any other controller runs on
the Python path (one vectorised batch per controller, a Python call per sample). Both
paths call the same compiled pieces and agree to rounding (a test holds them to 1e-12).

Memory does not grow with seeds x samples beyond the error norm (float32, for recovery
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
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.compiled import compiled_spec
from adaptive_dd.benchmark.compiled_runner import run_compiled
from adaptive_dd.benchmark.scenario import Scenario
from adaptive_dd.benchmark.streaming import accumulate_batch, segment_bounds
from adaptive_dd.benchmark.trials import (
    dropout_block,
    dropout_rngs,
    new_run,
    payload_schedule,
    sensor_of,
    trial_rngs,
    true_sigma,
)
from adaptive_dd.benchmark.types import (
    CHUNK,
    ENGINES,
    MAX_ERROR,
    SETTLE,
    BenchmarkResult,
    ControllerRun,
)
from adaptive_dd.controllers import Controller, Gains, controller_label, make_controller
from adaptive_dd.controllers.base import declared
from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.plant.simulator import ArmSimulator

__all__ = ["ENGINES", "MAX_ERROR", "SETTLE", "BenchmarkResult", "ControllerRun", "run_benchmark"]


def run_benchmark(
    scenario: Scenario,
    progress: bool = True,
    controllers: dict[str, Controller] | None = None,
    *,
    engine: str = "auto",
    keep_trajectories: int = 3,
    seed_indices: Sequence[int] | None = None,
    on_run=None,
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
        ``auto``: built-in controllers compiled, others in Python; ``python``: all in
        Python; ``compiled``: an error if a controller cannot be compiled.
    keep_trajectories : int
        Seeds (the first ones) whose full trajectories are kept.
    seed_indices : sequence of int, optional
        Seed indices of the trials (default ``range(scenario.seeds)``): a block of seeds
        run alone gives the same numbers as inside a full run.
    on_run : callable, optional
        ``on_run(result, run)`` after each controller's trials (the CLI passes
        :func:`~adaptive_dd.benchmark.metrics.release_error_norm`, which derives what needs the
        per-sample error norm and frees it, so memory holds one controller's norm at a time).
    """
    if engine not in ENGINES:
        raise ParameterError(f"engine must be one of {ENGINES}, got {engine!r}")
    t0 = time.perf_counter()
    from adaptive_dd.plant.serial_arm import SerialArm

    if isinstance(scenario.arm, SerialArm):  # any N-joint arm: adaptive_dd.closed_loop
        from adaptive_dd.closed_loop.runner import run_serial

        n = scenario.n_samples * len(controllers or scenario.controllers)
        bar = _progress(progress, n, scenario.name)
        res = run_serial(
            scenario, controllers, seed_indices=seed_indices, keep_trajectories=keep_trajectories,
            engine=engine, bar=bar,
        )  # fmt: skip
        if bar is not None:
            bar.close()
        res.wall_time = time.perf_counter() - t0
        return res
    gains = Gains(scenario.bandwidth, scenario.damping)
    if controllers is None:
        ctrls = {}
        for spec in scenario.controllers:
            opts = scenario.options(controller_label(spec)) or scenario.options(spec)
            src = Path(scenario.source)
            search = (src.parent, Path.cwd()) if src.is_file() else (Path.cwd(),)
            ctrls[controller_label(spec, opts)] = make_controller(
                spec, gains, opts, arm=scenario.arm, search=search
            )
    else:
        ctrls = controllers
    idx = tuple(range(scenario.seeds)) if seed_indices is None else tuple(int(i) for i in seed_indices)
    if not idx or min(idx) < 0:
        raise ParameterError(f"seed_indices must be a non-empty list of indices >= 0, got {seed_indices}")
    N, T = scenario.n_samples, scenario.sample_period
    t = np.arange(N) * T
    q_d, qd_d, qdd_d = scenario.reference.sample(t)
    sigma_true, mass = true_sigma(scenario, t)
    res = BenchmarkResult(scenario, t, q_d, sigma_true, mass, seed_indices=idx)
    specs = {n: (compiled_spec(c, T) if engine != "python" else None) for n, c in ctrls.items()}
    if engine == "compiled" and any(s is None for s in specs.values()):
        names = [n for n, s in specs.items() if s is None]
        raise ParameterError(f"engine='compiled': no compiled path for {names}; use engine='auto'")
    bar = _progress(progress, len(ctrls) * N, scenario.name)
    for name, ctrl in ctrls.items():
        if specs[name] is not None:
            run = run_compiled(
                name, ctrl, specs[name], scenario, idx, (q_d, qd_d, qdd_d), keep_trajectories, bar
            )
        else:
            run = _run_python(name, ctrl, scenario, idx, (q_d, qd_d, qdd_d), keep_trajectories, bar)
        res.runs[name] = run
        if on_run is not None:
            on_run(res, run)
    if bar is not None:
        bar.close()
    res.wall_time = time.perf_counter() - t0
    return res


def _progress(show: bool, total: int, name: str):
    if not show:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=f"benchmark {name}", unit="sample", mininterval=0.5, unit_scale=True)


def _run_python(name, ctrl, scenario, idx, reference, keep, bar) -> ControllerRun:
    """One controller's trials on the Python path (a vectorised batch, one call per sample)."""
    S, N, T = len(idx), scenario.n_samples, scenario.sample_period
    q_d, qd_d, qdd_d = reference
    sim = ArmSimulator(
        S,
        N,
        trial_rngs(scenario.seed, idx),
        arm=scenario.arm,
        payload=payload_schedule(scenario),
        sample_period=T,
        substeps=scenario.substeps,
        sensor=sensor_of(scenario),
        q0=q_d[0],
        qd0=qd_d[0],
    )
    error = ""
    try:
        ctrl.reset(S, T)
        adaptive = declared(ctrl, "adaptive")
    except Exception as exc:  # contain any controller failure to its own trials
        error, adaptive = f"{type(exc).__name__} in reset: {exc}", False
    seg_start, seg_end, seg_settled = segment_bounds(scenario.segments(), T, SETTLE)
    run = new_run(name, ctrl, S, len(seg_start), N, keep, adaptive, "python")
    K = run.q.shape[0]
    seg = 0
    drop_rngs = dropout_rngs(scenario, idx)
    held_q, held_qd = np.broadcast_to(q_d[0], (S, 2)).copy(), np.broadcast_to(qd_d[0], (S, 2)).copy()
    run.dropped = np.zeros(S, dtype=int)
    for k in range(N):
        qm, qdm = sim.measure()
        qm_obs, qdm_obs = qm, qdm
        if drop_rngs is not None:
            if k % CHUNK == 0:
                drops = dropout_block(drop_rngs, scenario.dropout, min(CHUNK, N - k))
            lost = drops[:, k % CHUNK]
            run.dropped += lost
            held_q, held_qd = np.where(lost[:, None], held_q, qm), np.where(lost[:, None], held_qd, qdm)
            qm_obs = np.where(lost[:, None], np.nan, qm)
            qdm_obs = np.where(lost[:, None], np.nan, qdm)
            qm, qdm = held_q, held_qd
        err = q_d[k] - sim.q
        if K:
            run.q[:, k], run.qd[:, k] = sim.q[:K], sim.qd[:K]
        tau = np.full((S, 2), np.nan)
        if not error:
            try:
                truth = {"sigma_true": sim.sigma} if declared(ctrl, "needs_true_model") else {}
                cmd = np.asarray(ctrl.command(qm, qdm, q_d[k], qd_d[k], qdd_d[k], **truth), dtype=float)
                if cmd.shape != (S, 2):
                    raise SignalError(f"command returned shape {cmd.shape}, expected ({S}, 2)")
                tau = cmd
            except Exception as exc:
                error = f"{type(exc).__name__} in command at t = {k * T:.3f} s: {exc}"
        tau = np.where((np.abs(err).max(axis=-1) > MAX_ERROR)[:, None], np.nan, tau)
        applied, sat = sim.step(tau)
        accumulate_batch(run.acc, k, seg_start, seg_settled, err, applied, sat)
        if K:
            run.tau[:, k], run.saturated[:, k] = applied[:K], sat[:K]
        if not error:
            try:
                ctrl.observe(qm_obs, qdm_obs, applied)
                if adaptive:
                    est = np.asarray(declared(ctrl, "sigma_hat"))
                    if K:
                        run.sigma_hat[:, k] = est[:K]
                    while seg + 1 < len(seg_end) and k >= seg_end[seg]:
                        seg += 1
                    if k == seg_end[seg] - 1:
                        run.sigma_end[:, seg] = est
            except Exception as exc:
                error = f"{type(exc).__name__} in observe at t = {k * T:.3f} s: {exc}"
        if bar is not None and k % 1000 == 999:
            bar.update(1000)
    if bar is not None:
        bar.update(N % 1000)
    run.failed, run.failed_at, run.error = sim.failed.copy(), sim.failed_at.copy(), error
    if error:
        run.failed[:] = True
    run.alarm_times = None if error else declared(ctrl, "alarm_times")
    run.skipped = None if error else declared(ctrl, "skipped_samples")
    return run
