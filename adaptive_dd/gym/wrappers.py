"""Learned residual control: the action a torque added to a chosen base controller's command.

::

    env = ResidualTorque(make_env("adaptive_dd/scenarios/ur5_tool_swap.toml"), base="ct_nominal")
    obs, info = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(np.zeros(6))  # the base controller alone

The base is a built-in controller or a plug-in of the scenario (``adaptive_ct``, ``pd``,
``ct_nominal``, ...), built with the scenario's settings as the benchmark builds it, and run on
the environment's observations exactly as the benchmark's Python path runs it: ``command`` on the
measurement of the sample, then ``observe`` of that measurement and the torque the actuator
applied (its estimator, if any, learns from it). A controller given the true model (an oracle)
cannot be a base: the observation holds no truth.
"""

from __future__ import annotations

import gymnasium
import numpy as np
from gymnasium import spaces

from adaptive_dd.errors import ParameterError, SignalError

__all__ = ["ResidualTorque"]


class ResidualTorque(gymnasium.Wrapper):
    """Action: a residual torque ``(n,)`` [N m] (a ``Box`` within the effort limits) added to
    ``base``'s command on the same observation; ``info["base_torque"]`` holds that command.

    Parameters
    ----------
    env : PayloadSwapEnv (or a wrapper of one)
    base : str
        A controller of the scenario's registry or a plug-in (``module:Class``), not an oracle.
    """

    def __init__(self, env: gymnasium.Env, base: str = "adaptive_ct") -> None:
        super().__init__(env)
        from adaptive_dd.controllers.base import declared
        from adaptive_dd.controllers.plugins import PythonForm, is_compiled
        from adaptive_dd.controllers.registry import scenario_controller

        sc = env.unwrapped.scenario
        self.base_name, self.base = scenario_controller(sc, base)
        if is_compiled(self.base):  # its njit functions called per sample, as engine="python" runs it
            self.base = PythonForm(self.base_name, self.base, sc.arm, "the base of a ResidualTorque wrapper")
        if declared(self.base, "needs_true_model"):
            raise ParameterError(
                f"ResidualTorque: base {base!r} is given the true model (an oracle); the observation "
                "holds no truth: choose a controller that is not (adaptive_ct, ct_nominal, pd, ...)"
            )
        lim = env.action_space.high
        self.action_space = spaces.Box(-lim, lim, dtype=np.float64)
        self._n = sc.n_joints
        self._obs = None
        self._base_tau = None

    def _command(self, obs) -> np.ndarray:
        n = self._n
        q, qd, q_d, qd_d, qdd_d = (obs[i * n : (i + 1) * n] for i in range(5))
        return np.asarray(self.base.command(q[None], qd[None], q_d, qd_d, qdd_d), dtype=float)[0]

    def reset(self, *, seed=None, options=None):
        obs, info = self.env.reset(seed=seed, options=options)
        self.base.reset(1, self.env.unwrapped.scenario.sample_period)
        self._obs = obs
        self._base_tau = self._command(obs)
        info["base_torque"] = self._base_tau.copy()
        return obs, info

    def step(self, action):
        if self._obs is None:
            raise ParameterError("ResidualTorque: call reset() before step()")
        n = self._n
        action = np.asarray(action, dtype=float)
        if action.shape != (n,):
            raise SignalError(
                f"ResidualTorque: the residual must have shape ({n},) (per joint), got {action.shape}"
            )
        tau = self._base_tau + action
        obs, reward, terminated, truncated, info = self.env.step(tau)
        q, qd = self._obs[:n], self._obs[n : 2 * n]
        self.base.observe(q[None], qd[None], info["applied_torque"][None])
        self._obs = obs
        if not (terminated or truncated):
            self._base_tau = self._command(obs)
        info["base_torque"] = self._base_tau.copy()
        return obs, reward, terminated, truncated, info
