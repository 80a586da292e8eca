"""Gymnasium environments over the benchmark's scenarios (``pip install -e ".[gym]"``).

Importing this package registers one environment id per shipped scenario (:data:`SCENARIO_IDS`):

- ``adaptive_dd/PayloadSwap-SICE-v0``: ``payload_swap.toml`` (the paper's two-link arm);
- ``adaptive_dd/PayloadSwap-UR5-v0``, ``-UR5Exact-v0``: ``ur5_tool_swap.toml``,
  ``ur5_tool_swap_exact.toml``;
- ``adaptive_dd/PayloadSwap-Panda-v0``, ``-PandaExact-v0``: ``panda_payload.toml``,
  ``panda_payload_exact.toml``;
- ``adaptive_dd/PayloadSwap-iiwa14-v0``, ``-iiwa14Exact-v0``: ``iiwa14_payload.toml``,
  ``iiwa14_payload_exact.toml``;
- ``adaptive_dd/PayloadSwap-Vertical3-v0``, ``-Vertical3Exact-v0``: ``vertical3_payload.toml``,
  ``vertical3_payload_exact.toml``.

:func:`make_env` builds the environment of any scenario (a user's URDF arm too);
:class:`~adaptive_dd.gym.wrappers.ResidualTorque` makes the action a residual on a base
controller; :func:`~adaptive_dd.gym.score.evaluate` scores a policy against the floor, seed by
seed, on the benchmark's scale.
"""

from __future__ import annotations

from pathlib import Path

try:
    import gymnasium
except ImportError as exc:  # pragma: no cover - the optional extra is missing
    raise ImportError(
        'adaptive_dd.gym needs gymnasium: pip install -e ".[gym]" (or pip install gymnasium)'
    ) from exc

from adaptive_dd.gym.env import PayloadSwapEnv, observation_of
from adaptive_dd.gym.score import Evaluation, evaluate, run_episode
from adaptive_dd.gym.wrappers import ResidualTorque

__all__ = [
    "SCENARIO_IDS",
    "Evaluation",
    "PayloadSwapEnv",
    "ResidualTorque",
    "evaluate",
    "make_env",
    "observation_of",
    "run_episode",
]

_SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"

SCENARIO_IDS = {
    "adaptive_dd/PayloadSwap-SICE-v0": "payload_swap.toml",
    "adaptive_dd/PayloadSwap-UR5-v0": "ur5_tool_swap.toml",
    "adaptive_dd/PayloadSwap-UR5Exact-v0": "ur5_tool_swap_exact.toml",
    "adaptive_dd/PayloadSwap-Panda-v0": "panda_payload.toml",
    "adaptive_dd/PayloadSwap-PandaExact-v0": "panda_payload_exact.toml",
    "adaptive_dd/PayloadSwap-iiwa14-v0": "iiwa14_payload.toml",
    "adaptive_dd/PayloadSwap-iiwa14Exact-v0": "iiwa14_payload_exact.toml",
    "adaptive_dd/PayloadSwap-Vertical3-v0": "vertical3_payload.toml",
    "adaptive_dd/PayloadSwap-Vertical3Exact-v0": "vertical3_payload_exact.toml",
}
"""Registered id -> the shipped scenario file (``adaptive_dd/scenarios/``)."""


def make_env(scenario=None, floor: str | None = "ct_oracle") -> PayloadSwapEnv:
    """The environment of a scenario: a :class:`~adaptive_dd.benchmark.scenario.Scenario`, a
    scenario file (any arm, a user's URDF too), a registered id, or None (the paper's arm).

    Parameters
    ----------
    scenario : Scenario, str, Path or None
        The scenario, its file, a registered id (:data:`SCENARIO_IDS`), or None.
    floor : str or None
        The law told the true model whose command ``info["floor_torque"]`` holds (default
        ``ct_oracle``; one of :func:`~adaptive_dd.gym.env.floor_laws`); None leaves it out.

    Returns
    -------
    PayloadSwapEnv
        One trial of the scenario per episode; ``reset(seed=i)`` is the benchmark's trial ``i``.

    Examples
    --------
    >>> import numpy as np
    >>> from adaptive_dd.gym import make_env
    >>> env = make_env()  # the paper's arm (the first step compiles its plant on a cold cache)
    >>> obs, info = env.reset(seed=0)  # the benchmark's trial 0
    >>> obs.shape  # measured q, qd and the reference q_d, qd_d, qdd_d
    (10,)
    >>> obs, reward, terminated, truncated, info = env.step(np.zeros(2))
    >>> terminated, truncated, info["k"]
    (False, False, 1)
    """
    return PayloadSwapEnv(scenario_file(scenario, "make_env"), floor=floor)


def scenario_file(scenario, who: str = "make_env"):
    """A registered id's scenario file (:data:`SCENARIO_IDS`); anything else as given. A string of
    an id's shape (``adaptive_dd/Name-v0``) that is not registered is an error naming ``who``."""
    if isinstance(scenario, str) and scenario in SCENARIO_IDS:
        return _SCENARIOS / SCENARIO_IDS[scenario]
    if isinstance(scenario, str) and scenario.startswith("adaptive_dd/") and not scenario.endswith(".toml"):
        # an id's shape (adaptive_dd/Name-v0), not a file's (the README's adaptive_dd/scenarios/*.toml)
        from adaptive_dd.errors import ScenarioError

        raise ScenarioError(
            f"{who}: {scenario!r} is not a registered id; registered: {', '.join(SCENARIO_IDS)} "
            "(or give a scenario file or a Scenario)"
        )
    return scenario


def _register() -> None:
    for env_id, file in SCENARIO_IDS.items():
        if env_id not in gymnasium.registry:
            gymnasium.register(
                id=env_id,
                entry_point="adaptive_dd.gym.env:PayloadSwapEnv",
                vector_entry_point="adaptive_dd.gym.vector:PayloadSwapVectorEnv",
                kwargs={"scenario": str(_SCENARIOS / file)},
                disable_env_checker=False,
            )


_register()
