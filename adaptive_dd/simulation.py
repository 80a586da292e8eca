"""One trial in your own loop: step the arm of a scenario with your own torques.

::

    from adaptive_dd import Simulation, load_scenario

    sim = Simulation(load_scenario(), seed_index=0)
    meas = sim.reset()
    while not sim.done:
        tau = my_law(meas.q, meas.qd, meas.q_d, meas.qd_d, meas.qdd_d)
        meas = sim.step(tau)
    sim.q_true, sim.sigma_true, sim.payload_mass   # the truth, for analysis

It is the same simulator, noise and payload schedule as trial ``seed_index`` of
``adaptive-dd benchmark`` on that scenario; :func:`run_trial` runs a controller object
over it and returns a result of the benchmark's kind.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import Scenario, load_scenario
from adaptive_dd.benchmark.trials import payload_schedule, sensor_of, trial_rngs
from adaptive_dd.errors import SignalError
from adaptive_dd.plant.simulator import ArmSimulator

__all__ = ["Measurement", "Simulation", "run_trial"]

Array = NDArray[np.float64]


class Measurement(NamedTuple):
    """What a controller sees at sample k: time [s], measured ``q, qd (2,)`` and the reference."""

    k: int
    t: float
    q: Array
    qd: Array
    q_d: Array
    qd_d: Array
    qdd_d: Array


class Simulation:
    """One arm of a scenario, stepped by the caller at the sample rate.

    Parameters
    ----------
    scenario : Scenario, optional
        Default: the shipped payload-swap scenario.
    seed_index : int
        Noise of seed ``(scenario.seed, seed_index)``, as in the benchmark.
    """

    def __init__(self, scenario: Scenario | None = None, seed_index: int = 0) -> None:
        self.scenario = scenario or load_scenario()
        self.seed_index = int(seed_index)
        sc = self.scenario
        t = np.arange(sc.n_samples) * sc.sample_period
        self._ref = sc.reference.sample(t)
        self._sim: ArmSimulator | None = None
        self.applied_torque = np.zeros(2)
        self.saturated = np.zeros(2, dtype=bool)

    def reset(self) -> Measurement:
        """Start (again) at t = 0, on the reference, at rest if it is; return the first measurement."""
        sc = self.scenario
        q_d, qd_d, _ = self._ref
        self._sim = ArmSimulator(
            1,
            sc.n_samples,
            trial_rngs(sc.seed, [self.seed_index]),
            arm=sc.arm,
            payload=payload_schedule(sc),
            sample_period=sc.sample_period,
            substeps=sc.substeps,
            sensor=sensor_of(sc),
            q0=q_d[0],
            qd0=qd_d[0],
        )
        return self._measure()

    def _measure(self) -> Measurement:
        sim = self._sim
        if sim.k >= sim.n_samples:
            return Measurement(sim.k, sim.t, *(np.full(2, np.nan) for _ in range(5)))
        qm, qdm = sim.measure()
        k = sim.k
        return Measurement(k, sim.t, qm[0], qdm[0], self._ref[0][k], self._ref[1][k], self._ref[2][k])

    def step(self, tau: ArrayLike) -> Measurement:
        """Apply the torque command ``tau (2,)`` [N m] for one sample; return the next measurement."""
        if self._sim is None:
            raise SignalError("call reset() before step()")
        if self.done:
            raise SignalError(f"the scenario's {self.scenario.n_samples} samples are done; call reset()")
        tau = np.asarray(tau, dtype=float)
        if tau.shape != (2,):
            raise SignalError(f"tau must have shape (2,), got {tau.shape}")
        applied, sat = self._sim.step(tau[None])
        self.applied_torque, self.saturated = applied[0], sat[0]
        return self._measure()

    @property
    def done(self) -> bool:
        return self._sim is not None and self._sim.k >= self._sim.n_samples

    @property
    def failed(self) -> bool:
        """The arm diverged (non-finite or runaway) and was stopped."""
        return bool(self._sim.failed[0])

    @property
    def q_true(self) -> Array:
        return self._sim.q[0].copy()

    @property
    def qd_true(self) -> Array:
        return self._sim.qd[0].copy()

    @property
    def sigma_true(self) -> Array:
        """The true base parameters now, payload included (7,)."""
        return self._sim.sigma[0].copy()

    @property
    def payload_mass(self) -> float:
        return float(self._sim.mass[0])


def run_trial(controller, scenario: Scenario | None = None, seed_index: int = 0, name: str | None = None):
    """Run one controller object on trial ``seed_index`` of a scenario; a benchmark result."""
    sc = scenario or load_scenario()
    label = name or getattr(controller, "name", type(controller).__name__)
    return run_benchmark(sc, progress=False, controllers={label: controller}, seed_indices=[seed_index])
