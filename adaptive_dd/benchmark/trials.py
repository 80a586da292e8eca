"""The set-up every two-link trial shares, whichever path runs it: its sensor-noise generators
(:func:`~adaptive_dd.closed_loop.noise.trial_rngs`, common random numbers across controllers;
the run draws them, and its dropouts, through :class:`~adaptive_dd.closed_loop.noise.NoiseBlocks`),
its sensors, the true parameters at every sample, and an empty
:class:`~adaptive_dd.benchmark.types.ControllerRun`."""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.benchmark.scenario import Scenario
from adaptive_dd.benchmark.types import ControllerRun
from adaptive_dd.closed_loop.noise import trial_rngs
from adaptive_dd.closed_loop.types import StreamedSums
from adaptive_dd.controllers.base import declared
from adaptive_dd.plant.sampling import first_sample
from adaptive_dd.plant.simulator import PayloadSchedule

__all__ = [
    "new_run",
    "payload_schedule",
    "sensor_of",
    "trial_rngs",
    "true_sigma",
]

Array = NDArray[np.float64]


def payload_schedule(scenario: Scenario) -> PayloadSchedule:
    return PayloadSchedule(scenario.swap_times, scenario.swap_masses, radius=scenario.payload_radius)


def sensor_of(scenario: Scenario):
    """The arm's sensors with the scenario's noise."""
    return dataclasses.replace(
        scenario.arm.sensor,
        position_variance=scenario.position_variance,
        velocity_variance=scenario.velocity_variance,
    )


def true_sigma(scenario: Scenario, t: Array) -> tuple[Array, Array]:
    """True sigma and payload mass at every sample, as the simulator applies them."""
    T = scenario.sample_period
    k_sw = [first_sample(at, T) for at in scenario.swap_times]
    masses = np.array([0.0, *scenario.swap_masses])
    w = np.searchsorted(np.array(k_sw, dtype=np.int64), np.arange(t.size), side="right")
    mass = masses[w]
    return scenario.closed_forms.sigma_with_payload(mass, scenario.payload_radius), mass


def new_run(
    name: str, ctrl, S: int, n_seg: int, N: int, keep: int, adaptive: bool, engine: str
) -> ControllerRun:
    """An empty run of ``S`` trials: zero streamed sums
    (:class:`~adaptive_dd.closed_loop.types.StreamedSums`; ``run.e_norm`` is ``run.acc.e_norm``),
    trajectories of the first ``keep`` trials, the estimates if ``adaptive``."""
    K = min(keep, S)
    acc = StreamedSums.zeros(S, n_seg, 2, N)
    return ControllerRun(
        name=name,
        acc=acc,
        e_norm=acc.e_norm,
        sigma_end=np.full((S, n_seg, 7), np.nan) if adaptive else None,
        failed=np.zeros(S, dtype=bool),
        failed_at=np.full(S, -1),
        failed_cmd=np.full(S, -1),
        floor=declared(ctrl, "floor"),
        q=np.zeros((K, N, 2)),
        qd=np.zeros((K, N, 2)),
        tau=np.zeros((K, N, 2)),
        saturated=np.zeros((K, N, 2), dtype=bool),
        sigma_hat=np.full((K, N, 7), np.nan) if adaptive else None,
        engine=engine,
    )
