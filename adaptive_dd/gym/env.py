"""A Gymnasium environment over one trial of a scenario (:class:`~adaptive_dd.simulation.Simulation`).

::

    import gymnasium as gym
    import adaptive_dd.gym  # registers adaptive_dd/PayloadSwap-UR5-v0, ...

    env = gym.make("adaptive_dd/PayloadSwap-UR5-v0")
    obs, info = env.reset(seed=3)          # trial 3 of the benchmark: its noise, plant, payloads
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())

Action: the joint torques ``(n,)`` [N m], a ``Box`` within the arm's effort limits (a command
beyond them is saturated by the actuator, as in the benchmark). Observation ``(5 n,)``: what the
benchmark's controllers see, never the truth: the measured ``q`` [rad] and ``qd`` [rad/s] (sensor
noise, quantisation, dropouts as the scenario says) and the reference ``q_d, qd_d, qdd_d`` at the
same sample. ``info`` carries the truth, for evaluation only: the true ``q_true, qd_true``, the
payload's ``payload_mass`` [kg] and ``segment``, ``swap`` (a payload change takes effect at this
sample), the torque ``applied_torque`` [N m] and ``saturated`` of the last step, ``failure`` (why
the trial failed, "" while it has not), the tracking error
``error`` (``q_d - q_true`` of the sample the last action was applied on, the benchmark's ``e``) and
``floor_torque``: what the scenario's floor (``ct_oracle``, the law with the true model) would
command on this observation (NaN on the last sample, where nothing is commanded).

Reward: ``-|q_d - q_true|^2`` [rad^2] of the state the action leads to. ``terminated``: the trial
failed (the benchmark's rule: a non-finite command or state, a runaway speed or a joint's error
beyond ``max_error``, 3 rad); the failing step's reward is :func:`failure_cost` per sample the
episode had left, that one included: as if every joint stayed at the largest error the benchmark
lets a trial survive until the end, so that no failure returns more than tracking on would.
``truncated``: the scenario's samples are done.
"""

from __future__ import annotations

from pathlib import Path
from typing import ClassVar

import gymnasium
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from adaptive_dd.benchmark.scenario import Scenario, load_scenario
from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.simulation import Measurement, Simulation

__all__ = ["PayloadSwapEnv", "failure_cost", "floor_command", "floor_laws", "observation_of", "scenario_of"]

Array = NDArray[np.float64]

MAX_SEED = 2**31 - 1


def failure_cost(n_joints: int) -> float:
    """[rad^2] What a failed trial's reward charges per sample it had left: ``n max_error^2``, every
    joint at the error beyond which the benchmark fails a trial
    (:data:`~adaptive_dd.closed_loop.types.MAX_ERROR`, 3 rad), so more than any sample of a trial
    that goes on."""
    from adaptive_dd.closed_loop.types import MAX_ERROR

    return float(n_joints) * MAX_ERROR**2


def floor_laws() -> list[str]:
    """The built-in laws a score may divide by: those told the true model at once (``ct_oracle``,
    ``slotine_li_oracle``, ...; ``ct_oracle_late``, told late, is measured against one)."""
    from adaptive_dd.controllers.builtins import CONTROLLERS

    return [
        n for n, e in CONTROLLERS.items() if e.knows.startswith("true model") and "delay" not in e.settings
    ]


def scenario_of(scenario: Scenario | str | Path | None) -> Scenario:
    """A :class:`Scenario` from itself, a scenario file, a registered id
    (``adaptive_dd/PayloadSwap-UR5-v0``), or None (the shipped payload swap)."""
    from adaptive_dd.gym import scenario_file

    scenario = scenario_file(scenario, "PayloadSwapEnv")
    if scenario is None or isinstance(scenario, (str, Path)):
        return load_scenario(scenario)
    if isinstance(scenario, Scenario):
        return scenario
    raise ParameterError(
        f"scenario must be a Scenario, a path to a scenario file or None, got {type(scenario).__name__}"
    )


def observation_of(m: Measurement) -> Array:
    """The observation ``(5 n,)``: measured ``q, qd`` and the reference ``q_d, qd_d, qdd_d``."""
    return np.concatenate((m.q, m.qd, m.q_d, m.qd_d, m.qdd_d))


def floor_command(floor, sim: Simulation, m: Measurement) -> Array:
    """What ``floor`` (a controller object given the true model) commands on measurement ``m``
    of ``sim``'s trial, ``(n,)`` [N m]."""
    kw = {"sigma_true": sim.sigma_true[None]}
    pi = sim.pi_true
    if pi is not None and getattr(floor, "takes_pi_true", False):
        kw["pi_true"] = pi[None]
    tau = floor.command(m.q[None], m.qd[None], m.q_d, m.qd_d, m.qdd_d, **kw)
    return np.asarray(tau, dtype=float)[0]


def _say_if_cold(sc) -> None:
    """A ``RunWarning`` when the first ``reset`` and ``step`` will compile the arm's step (numba's
    cache lacks it): up to about a minute on 2 cores, silent otherwise, it looked like a hang."""
    import os
    import warnings

    from adaptive_dd._numba_cache import cache_index
    from adaptive_dd.errors import RunWarning

    if sc.closed_forms is not None:  # the closed forms' plant step
        from adaptive_dd.plant.two_link_integrator import step_trials as step
    else:  # the N-joint glue's step over the trials
        from adaptive_dd.closed_loop.batches import _chain_apply_loop as step
    index = cache_index(step)
    if index is not None and not os.path.exists(index):
        warnings.warn(
            "adaptive_dd.gym: numba's cache lacks this arm's step: the first reset() and step() compile it "
            "(from seconds to about a minute on 2 cores, by what the cache holds; once: later processes "
            "load it)",
            RunWarning,
            stacklevel=3,
        )


class PayloadSwapEnv(gymnasium.Env):
    """One trial of a scenario as a ``gymnasium.Env`` (module docstring).

    Parameters
    ----------
    scenario : Scenario, str, Path or None
        The scenario (any arm: the shipped ones, or a user's URDF scenario); None: the shipped
        payload swap of the paper's arm.
    floor : str or None
        The law told the true model whose command on each observation ``info["floor_torque"]``
        holds (default ``ct_oracle``, the floor of ``adaptive_ct``; one of :func:`floor_laws`);
        None leaves it out (faster steps).
    render_mode : None
        Gymnasium's keyword; the environment draws nothing (plot ``info["q_true"]`` against the
        reference, or run the benchmark for its figures).

    Examples
    --------
    >>> import numpy as np
    >>> from adaptive_dd.gym.env import PayloadSwapEnv
    >>> env = PayloadSwapEnv()  # the paper's arm (the first step compiles its plant on a cold cache)
    >>> obs, info = env.reset(seed=0)  # the benchmark's trial 0
    >>> obs.shape  # measured q, qd and the reference q_d, qd_d, qdd_d
    (10,)
    >>> obs, reward, terminated, truncated, info = env.step(np.zeros(2))
    >>> terminated, truncated, info["k"]
    (False, False, 1)
    """

    metadata: ClassVar[dict] = {"render_modes": []}

    def __init__(
        self,
        scenario: Scenario | str | Path | None = None,
        floor: str | None = "ct_oracle",
        render_mode: str | None = None,
    ) -> None:
        from adaptive_dd.closed_loop.types import io_of

        if render_mode is not None:
            raise ParameterError(
                f"PayloadSwapEnv: render_mode {render_mode!r}: the environment draws nothing (render_mode "
                "None); plot info['q_true'] against the reference, or run `adaptive-dd benchmark` for figures"
            )
        self.render_mode = None
        if floor is not None and floor not in floor_laws():
            raise ParameterError(
                f"PayloadSwapEnv: floor {floor!r} is no built-in told the true model (its command would "
                f"not be a floor: a law that adapts is never shown its torques here); one of {floor_laws()}, "
                "or None"
            )
        self.scenario = sc = scenario_of(scenario)
        _say_if_cold(sc)
        n = sc.n_joints
        lim = np.asarray(io_of(sc).lim, dtype=np.float64)
        self.action_space = spaces.Box(-lim, lim, dtype=np.float64)
        self.observation_space = spaces.Box(-np.inf, np.inf, shape=(5 * n,), dtype=np.float64)
        self._floor_name = floor
        self._floor = None
        if floor is not None:
            from adaptive_dd.controllers.registry import scenario_controller

            self._floor = scenario_controller(sc, floor)[1]
        from adaptive_dd.closed_loop.types import segment_starts

        self._starts = segment_starts(sc)
        self.sim: Simulation | None = None
        self.seed_index: int | None = None
        self._m: Measurement | None = None

    # ------------------------------------------------------------------ gymnasium API
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start trial ``seed`` of the benchmark (its sensor noise, drawn plant and payload
        schedule: the scenario's ``seed`` with this seed index); without a seed, a seed index
        drawn from the environment's generator. ``options={"seed_index": i}`` is the same as
        ``seed=i`` without reseeding the generator."""
        super().reset(seed=seed)
        opts = dict(options or {})
        bad = sorted(set(opts) - {"seed_index"})
        if bad:
            raise ParameterError(f"PayloadSwapEnv.reset: unknown option(s) {bad}; allowed: ['seed_index']")
        idx = opts.get("seed_index", seed)
        if idx is None:
            idx = int(self.np_random.integers(0, MAX_SEED))
        if isinstance(idx, bool) or not isinstance(idx, (int, np.integer)) or not 0 <= idx < 2**63:
            raise ParameterError(
                "PayloadSwapEnv.reset: the seed (a trial's seed index) must be an int in [0, 2**63), "
                f"got {idx!r}"
            )
        self.seed_index = int(idx)
        self.sim = Simulation(self.scenario, self.seed_index)
        self._m = self.sim.reset()
        if self._floor is not None:
            self._floor.reset(1, self.scenario.sample_period)
        self._segment = 0
        return observation_of(self._m), self._info(None)

    def step(self, action):
        """Apply ``action`` (the torques ``(n,)`` [N m]) for one sample."""
        if self.sim is None:
            raise SignalError("PayloadSwapEnv: call reset() before step()")
        if self.sim.failed:  # Gymnasium leaves a step after termination undefined: say so
            raise SignalError(
                f"PayloadSwapEnv: the episode terminated (trial {self.seed_index} failed); call reset() "
                "before step()"
            )
        sim, m = self.sim, self._m
        error = m.q_d - sim.q_true  # the benchmark's e at this sample (the state before the step)
        left = self.scenario.n_samples - m.k  # samples the episode has left, this one included
        self._m = m = sim.step(np.asarray(action, dtype=np.float64))
        e_next = m.q_d - sim.q_true
        failed = bool(sim.failed)
        reward = -failure_cost(self.scenario.n_joints) * left if failed else -float(e_next @ e_next)
        return observation_of(m), reward, failed, bool(sim.done), self._info(error)

    def render(self):
        """No rendering (``render_mode`` None): raises, saying what to do instead."""
        raise NotImplementedError(
            "PayloadSwapEnv draws nothing: plot info['q_true'] against the reference (observation "
            "[2n:3n]), or run `adaptive-dd benchmark` for the figures"
        )

    # --------------------------------------------------------------------- the truth
    def _info(self, error: Array | None) -> dict:
        sim, m, sc = self.sim, self._m, self.scenario
        k = min(m.k, sc.n_samples - 1)
        seg = int(np.searchsorted(self._starts, k, side="right")) - 1
        info = {
            "k": m.k,
            "t": m.t,
            "seed_index": self.seed_index,
            "q_true": sim.q_true,
            "qd_true": sim.qd_true,
            "payload_mass": sim.payload_mass,
            "segment": seg,
            "swap": seg != self._segment,
            "applied_torque": sim.applied_torque.copy(),
            "saturated": np.asarray(sim.saturated, dtype=bool).copy(),
            "error": np.full(sc.n_joints, np.nan) if error is None else error,
            "failure": sim.failure or "",  # why the trial failed, in the benchmark's words ("" if not)
        }
        self._segment = seg
        if self._floor is not None:  # NaN at the last sample: nothing is commanded there
            done = sim.done
            info["floor_torque"] = (
                np.full(sc.n_joints, np.nan) if done else floor_command(self._floor, sim, m)
            )
        return info
