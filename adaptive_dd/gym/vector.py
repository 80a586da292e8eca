"""Many trials of a scenario stepped in one call: a ``gymnasium.vector.VectorEnv`` over the batch plant.

::

    from adaptive_dd.gym.vector import PayloadSwapVectorEnv

    envs = PayloadSwapVectorEnv("adaptive_dd/scenarios/ur5_tool_swap.toml", num_envs=64)
    obs, info = envs.reset(seed=0)         # trials 0 .. 63 of the benchmark
    obs, reward, terminated, truncated, info = envs.step(actions)   # actions (64, n)

Each sub-environment is one trial, as :class:`~adaptive_dd.gym.env.PayloadSwapEnv` (the same
observation, action and reward); the trials are stepped together by the closed loop's batch glue
(:func:`~adaptive_dd.closed_loop.batches.measure_batch`, :func:`~adaptive_dd.closed_loop.batches.apply_batch`:
one compiled call over every trial per sample) on an arm from a URDF, or by the closed-form
plant's batch simulator (:class:`~adaptive_dd.plant.simulator.ArmSimulator`) on the paper's arm.

The trials share one clock: every episode has the scenario's length, all end together
(``truncated``) and the next :meth:`step` starts the next ``num_envs`` trials (next-step
autoreset: its actions are ignored). A trial that fails (the benchmark's rule) is stopped at rest
and stays there, an absorbing state: each of its steps from the failing one on is rewarded
``-failure_cost(n)`` (:func:`~adaptive_dd.gym.env.failure_cost`), so its return is the single
environment's, which ends the episode there with that cost for every sample left; it is never
``terminated`` (a sub-environment cannot restart before the others), ``info["failed"]`` says which
trials failed. ``info`` holds ``q_true``, ``payload_mass``, ``seed_index`` and ``failed`` per trial,
each with Gymnasium's ``_key`` mask (no floor torque).
"""

from __future__ import annotations

from pathlib import Path
from typing import ClassVar

import gymnasium
import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector.utils import batch_space

from adaptive_dd.benchmark.scenario import Scenario
from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.gym.env import MAX_SEED, failure_cost, scenario_of

__all__ = ["PayloadSwapVectorEnv"]


class _ChainBatch:
    """S trials of an N-joint arm on the Python path's batch glue (the benchmark's arithmetic)."""

    def __init__(self, sc: Scenario, idx: tuple) -> None:
        from adaptive_dd.closed_loop.noise import NoiseBlocks
        from adaptive_dd.closed_loop.runner import _records, true_parameters
        from adaptive_dd.closed_loop.types import io_of, plant_of, run_constants

        self.rc, self.io, self.pl = run_constants(sc), io_of(sc), plant_of(sc, idx)
        _, self.ts, self.acc, self.rec = _records(
            "trials", None, sc, self.rc, self.pl, len(idx), 0, False, "python"
        )
        _, _, self.masses = true_parameters(sc)
        self.noise = NoiseBlocks(sc, idx, 2 * sc.n_joints)
        self.k, self._buf, self._at = 0, None, 0
        self.n_samples = sc.n_samples

    def measure(self):
        from adaptive_dd.benchmark.types import CHUNK
        from adaptive_dd.closed_loop.batches import measure_batch

        if self._buf is None or self._at >= self._buf[0].shape[1]:
            self._buf, self._at = self.noise.block(CHUNK), 0
        noise, drop = self._buf
        lost = drop[:, self._at] if drop.shape[1] else np.zeros(noise.shape[0], dtype=np.bool_)
        qm, qdm, _, _ = measure_batch(self.io, self.ts, noise[:, self._at], lost)
        self._at += 1
        return qm, qdm

    def step(self, tau, q_d=None):  # (the N-joint glue applies the error bound itself)
        from adaptive_dd.closed_loop.batches import apply_batch

        apply_batch(self.rc, self.io, self.pl, self.ts, self.acc, self.rec, self.k, tau)
        self.k += 1

    @property
    def q(self):
        return self.ts.q

    @property
    def failed(self):
        return self.ts.failed

    def mass(self) -> float:
        return float(self.masses[min(self.k, self.n_samples - 1)])


class _TwoLinkBatch:
    """S trials of the paper's arm on its closed-form batch simulator."""

    def __init__(self, sc: Scenario, idx: tuple, q0, qd0) -> None:
        from adaptive_dd.benchmark.trials import payload_schedule, sensor_of, trial_rngs
        from adaptive_dd.plant.simulator import ArmSimulator

        self.sim = ArmSimulator(
            len(idx), sc.n_samples + 1, trial_rngs(sc.seed, idx), arm=sc.closed_forms,
            payload=payload_schedule(sc), sample_period=sc.sample_period, substeps=sc.substeps,
            sensor=sensor_of(sc), q0=q0, qd0=qd0,
        )  # fmt: skip

    @property
    def k(self) -> int:
        return self.sim.k

    def measure(self):
        return self.sim.measure()

    def step(self, tau, q_d) -> None:
        from adaptive_dd.simulation import error_bound

        self.sim.step(error_bound(np.asarray(tau, dtype=float), q_d, self.sim.q))

    @property
    def q(self):
        return self.sim.q

    @property
    def failed(self):
        return self.sim.failed

    def mass(self) -> float:
        return float(self.sim.mass[0])


class PayloadSwapVectorEnv(gymnasium.vector.VectorEnv):
    """``num_envs`` trials of a scenario stepped together (module docstring).

    Parameters
    ----------
    scenario : Scenario, str, Path or None
    num_envs : int
        Trials per batch.
    """

    metadata: ClassVar[dict] = {"autoreset_mode": gymnasium.vector.AutoresetMode.NEXT_STEP}

    def __init__(self, scenario: Scenario | str | Path | None = None, num_envs: int = 16) -> None:
        from adaptive_dd.closed_loop.types import io_of

        if not isinstance(num_envs, (int, np.integer)) or num_envs < 1:
            raise ParameterError(f"PayloadSwapVectorEnv: num_envs must be an int >= 1, got {num_envs!r}")
        self.scenario = sc = scenario_of(scenario)
        self.num_envs = int(num_envs)
        n = sc.n_joints
        lim = np.asarray(io_of(sc).lim, dtype=np.float64)
        self.single_action_space = spaces.Box(-lim, lim, dtype=np.float64)
        self.single_observation_space = spaces.Box(-np.inf, np.inf, shape=(5 * n,), dtype=np.float64)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        t = np.arange(sc.n_samples + 1) * sc.sample_period
        self._ref = sc.reference.sample(t)
        self._batch = None
        self._next = 0
        self._done = False

    def _start(self, first: int | tuple):
        sc = self.scenario
        idx = first if isinstance(first, tuple) else tuple(range(first, first + self.num_envs))
        self.seed_indices = idx
        if sc.closed_forms is not None:
            self._batch = _TwoLinkBatch(sc, idx, self._ref[0][0], self._ref[1][0])
        else:
            self._batch = _ChainBatch(sc, idx)
        self._next = max(idx) + 1
        self._done = False
        return self._observe(), self._info()

    def reset(self, *, seed: int | list[int] | None = None, options: dict | None = None):
        """Start trials ``seed .. seed + num_envs - 1`` of the benchmark, or the trials of a list of
        ``num_envs`` seed indices (without a seed: from a seed index drawn from the generator); the
        next batch goes on after the largest."""
        if options:
            raise ParameterError(f"PayloadSwapVectorEnv.reset: no options are taken, got {sorted(options)}")
        ints = (int, np.integer)
        if isinstance(seed, list | tuple | np.ndarray):
            ok = len(seed) == self.num_envs and all(
                isinstance(x, ints) and not isinstance(x, bool) and 0 <= x < 2**63 for x in seed
            )
            if not ok:
                raise ParameterError(
                    f"PayloadSwapVectorEnv.reset: a list of seeds must hold num_envs = {self.num_envs} ints "
                    f"in [0, 2**63) (one trial's seed index each), got {list(seed)!r}"
                )
            self._np_random, self._np_random_seed = seeding.np_random(int(seed[0]))
            first = tuple(int(x) for x in seed)
        elif seed is not None:
            if isinstance(seed, bool) or not isinstance(seed, ints) or not 0 <= seed < 2**63 - self.num_envs:
                raise ParameterError(
                    "PayloadSwapVectorEnv.reset: seed must be an int >= 0 (the first trial's seed index) or "
                    f"a list of num_envs of them, got {seed!r}"
                )
            self._np_random, self._np_random_seed = seeding.np_random(int(seed))
            first = int(seed)
        else:
            first = int(self.np_random.integers(0, MAX_SEED - self.num_envs))
        return self._start(first)

    def _observe(self):
        b = self._batch
        qm, qdm = b.measure()
        k = b.k
        q_d, qd_d, qdd_d = (np.broadcast_to(r[k], qm.shape) for r in self._ref)
        return np.concatenate((qm, qdm, q_d, qd_d, qdd_d), axis=1)

    def _info(self) -> dict:
        b = self._batch
        info = {
            "q_true": b.q.copy(),
            "payload_mass": np.full(self.num_envs, b.mass()),
            "seed_index": np.asarray(self.seed_indices),
            "failed": np.asarray(b.failed, dtype=bool).copy(),
        }
        every = np.ones(self.num_envs, dtype=bool)
        return {**info, **{f"_{k}": every.copy() for k in info}}

    def step(self, actions):
        """Apply ``actions (num_envs, n)`` [N m] for one sample of every trial."""
        if self._batch is None:
            raise SignalError("PayloadSwapVectorEnv: call reset() before step()")
        S = self.num_envs
        if self._done:  # next-step autoreset: the next trials
            obs, info = self._start(self._next)
            z = np.zeros(S, dtype=bool)
            return obs, np.zeros(S), z, z.copy(), info
        a = np.asarray(actions, dtype=np.float64)
        if a.shape != self.action_space.shape:
            raise SignalError(
                f"PayloadSwapVectorEnv.step: actions must be {self.action_space.shape}, got {a.shape}"
            )
        b = self._batch
        b.step(a, self._ref[0][b.k])
        obs = self._observe()
        e = self._ref[0][b.k] - b.q
        failed = np.asarray(b.failed, dtype=bool)
        with np.errstate(invalid="ignore", over="ignore"):
            reward = np.where(failed, -failure_cost(self.scenario.n_joints), -np.sum(e * e, axis=1))
        self._done = b.k >= self.scenario.n_samples
        truncated = np.full(S, self._done)
        return obs, reward, np.zeros(S, dtype=bool), truncated, self._info()
