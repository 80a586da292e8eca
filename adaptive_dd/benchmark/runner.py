"""The closed loop: every controller over every seed, as one vectorised batch.

All ``n_controllers x n_seeds`` trials share one :class:`~adaptive_dd.plant.ArmSimulator`
(the integrator is one compiled loop over the batch); trial ``(c, i)`` uses the
noise of seed ``(seed, i)`` for every controller c (common random numbers), so
controllers are compared on identical noise. A trial that diverges (non-finite,
runaway speed or tracking error > ``MAX_ERROR``), or whose controller raises, is
stopped and counted; the rest of the benchmark goes on.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.benchmark.scenario import Scenario
from adaptive_dd.controllers import Controller, Gains, make_controller
from adaptive_dd.plant.parameters import TABLE1_SIGMA
from adaptive_dd.plant.simulator import ArmSimulator, PayloadSchedule, SensorConfig

__all__ = ["MAX_ERROR", "BenchmarkResult", "ControllerRun", "run_benchmark"]

Array = NDArray[np.float64]
MAX_ERROR = 3.0
"""Tracking error [rad] beyond which a trial counts as diverged."""


@dataclass
class ControllerRun:
    """One controller's trials; arrays are ``(n_seeds, n_samples, ...)``.

    Attributes
    ----------
    q : true joint angles [rad]
    tau : applied torque [N m]
    saturated : bool, a joint's command beyond its limit
    sigma_hat : estimates (adaptive controllers) or None
    failed : bool (n_seeds,); failed_at : sample index or -1
    error : message if the controller raised, else ""
    alarm_times : per trial, the times [s] a change detector fired (or None)
    """

    name: str
    q: Array
    tau: Array
    saturated: NDArray[np.bool_]
    sigma_hat: Array | None
    failed: NDArray[np.bool_]
    failed_at: NDArray[np.int_]
    error: str = ""
    alarm_times: list | None = None


@dataclass
class BenchmarkResult:
    """Everything a benchmark run produced; see :mod:`adaptive_dd.benchmark.metrics`."""

    scenario: Scenario
    t: Array
    q_d: Array
    sigma_true: Array  # (n_samples, 7)
    mass: Array  # (n_samples,)
    runs: dict = field(default_factory=dict)
    wall_time: float = 0.0


def run_benchmark(
    scenario: Scenario,
    progress: bool = True,
    controllers: dict[str, Controller] | None = None,
    seed_indices: Sequence[int] | None = None,
) -> BenchmarkResult:
    """Run every controller of the scenario over all seeds.

    Parameters
    ----------
    scenario : Scenario
    progress : bool
        Show a progress bar.
    controllers : dict, optional
        Controller objects by name, in place of ``make_controller(name)`` (for
        custom gains or your own controller classes).
    seed_indices : sequence of int, optional
        Which trials to run (default ``range(scenario.seeds)``): trial i of every
        controller uses ``numpy.random.default_rng([scenario.seed, seed_indices[i]])``,
        so a block of seeds run alone gives the same numbers as inside a full run.
    """
    from tqdm.auto import tqdm

    t0 = time.perf_counter()
    gains = Gains(scenario.bandwidth, scenario.damping)
    ctrls = controllers or {name: make_controller(name, gains) for name in scenario.controllers}
    names = list(ctrls)
    idx = range(scenario.seeds) if seed_indices is None else [int(i) for i in seed_indices]
    S, N, T = len(idx), scenario.n_samples, scenario.sample_period
    B = len(names) * S
    t = np.arange(N) * T
    q_d, qd_d, qdd_d = scenario.reference.sample(t)
    rngs = [np.random.default_rng([int(scenario.seed), i]) for _ in names for i in idx]
    sim = ArmSimulator(
        B,
        N,
        rngs,
        sigma0=TABLE1_SIGMA,
        payload=PayloadSchedule(scenario.swap_times, scenario.swap_masses, radius=scenario.payload_radius),
        sample_period=T,
        substeps=scenario.substeps,
        sensor=SensorConfig(
            position_variance=scenario.position_variance, velocity_variance=scenario.velocity_variance
        ),
        q0=q_d[0],
        qd0=qd_d[0],
    )
    slices = {n: slice(i * S, (i + 1) * S) for i, n in enumerate(names)}
    for c in ctrls.values():
        c.reset(S, T)
    q_rec = np.zeros((B, N, 2))
    tau_rec = np.zeros((B, N, 2))
    sat_rec = np.zeros((B, N, 2), dtype=bool)
    sig_rec = {n: np.full((S, N, 7), np.nan) for n in names if ctrls[n].adaptive}
    sigma_true = np.zeros((N, 7))
    mass = np.zeros(N)
    errors = dict.fromkeys(names, "")
    tau = np.zeros((B, 2))
    for k in tqdm(
        range(N),
        desc=f"benchmark {scenario.name}",
        unit="sample",
        disable=not progress,
        mininterval=0.5,
        unit_scale=True,
    ):
        qm, qdm = sim.measure()
        q_rec[:, k] = sim.q
        sigma_true[k], mass[k] = sim.sigma[0], sim.mass[0]
        for n in names:
            sl = slices[n]
            if errors[n]:
                tau[sl] = np.nan  # stopped: the simulator marks the trials failed
                continue
            try:
                tau[sl] = ctrls[n].command(
                    qm[sl], qdm[sl], q_d[k], qd_d[k], qdd_d[k], sigma_true=sim.sigma[sl]
                )
            except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
                errors[n] = f"{type(exc).__name__} at t = {t[k]:.3f} s: {exc}"
                tau[sl] = np.nan
        runaway = np.abs(sim.q - q_d[k]).max(axis=-1) > MAX_ERROR
        tau[runaway] = np.nan
        applied, sat = sim.step(tau)
        tau_rec[:, k], sat_rec[:, k] = applied, sat
        for n in names:
            if errors[n]:
                continue
            sl = slices[n]
            try:
                ctrls[n].observe(qm[sl], qdm[sl], applied[sl])
            except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
                errors[n] = f"{type(exc).__name__} at t = {t[k]:.3f} s: {exc}"
            if n in sig_rec:
                sig_rec[n][:, k] = ctrls[n].sigma_hat
    res = BenchmarkResult(scenario, t, q_d, sigma_true, mass)
    for n in names:
        sl = slices[n]
        est = getattr(ctrls[n], "estimator", None)
        alarms = est.alarm_times if getattr(est, "detector", None) is not None else None
        res.runs[n] = ControllerRun(
            n,
            q_rec[sl],
            tau_rec[sl],
            sat_rec[sl],
            sig_rec.get(n),
            sim.failed[sl].copy(),
            sim.failed_at[sl].copy(),
            errors[n],
            alarms,
        )
    res.wall_time = time.perf_counter() - t0
    return res
