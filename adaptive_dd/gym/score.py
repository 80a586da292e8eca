"""A policy's score on the benchmark's scale: its trials, the floor's, the ratio per seed.

:func:`evaluate` runs a policy (any callable from the observation to the action) through the
environment's episodes, trial ``i`` of the scenario for each seed index ``i`` (the benchmark's
noise, drawn plant and payload schedule), and sets each trial's RMS tracking error per payload
segment beside the floor's on the same seed: the scenario's ``ct_oracle`` (or the ``floor``
given) run by the benchmark (:func:`~adaptive_dd.benchmark.runner.run_benchmark`, compiled). The
error is the benchmark's: ``e = q_d - q`` of the true joint angles at every sample the policy
commanded, so a policy that commands what a built-in law commands has the benchmark's figures
(``tests/test_gym.py`` holds the ``pd`` law written as a policy to the benchmark's ``pd`` trial).
The tool frame's error (:mod:`~adaptive_dd.benchmark.end_effector`) is computed on every trial.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import gymnasium
import numpy as np

from adaptive_dd.benchmark.scenario import Scenario
from adaptive_dd.errors import ParameterError, SignalError

__all__ = ["Evaluation", "evaluate", "run_episode"]

FLOOR = "ct_oracle"


@dataclass
class Evaluation:
    """A policy's trials beside the floor's.

    Attributes
    ----------
    name : str
    seeds : tuple of int
        The seed indices, one trial each.
    segments : list of (start [s], end [s], mass [kg])
    rms_error, floor_rms_error : ndarray (n_seeds, n_segments)
        RMS of ``|q_d - q|`` [rad] per trial and segment (NaN for segments that end after a
        failure: the benchmark's rule).
    ee_position_rms, ee_position_max, ee_orientation_rms : ndarray (n_seeds, n_segments)
        The tool frame's error [mm, mm, deg] of the policy's trials.
    failed : ndarray of bool (n_seeds,)
    floor : str
        The law the ratios divide by (``evaluate``'s ``floor``).
    failed_at : ndarray (n_seeds,)
        [s] When each failed trial was stopped (its state diverged or left the arm's limits), NaN
        for a trial that did not fail.
    max_error, rms_torque, saturation_fraction : ndarray (n_seeds, n_segments) or None
        The benchmark's: ``max |e|`` [rad], ``sqrt(mean |tau|^2)`` of the applied torque [N m] and
        the fraction of samples with a joint's command beyond its limit (NaN as ``rms_error``).
    """

    name: str
    seeds: tuple
    segments: list
    rms_error: np.ndarray
    floor_rms_error: np.ndarray
    ee_position_rms: np.ndarray
    ee_position_max: np.ndarray
    ee_orientation_rms: np.ndarray
    failed: np.ndarray
    floor: str = FLOOR
    failed_at: np.ndarray | None = None
    max_error: np.ndarray | None = None
    rms_torque: np.ndarray | None = None
    saturation_fraction: np.ndarray | None = None

    @property
    def ratio_to_floor(self) -> np.ndarray:
        """``(n_seeds, n_segments)``: the per-seed ratio of RMS errors to the floor's."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return self.rms_error / self.floor_rms_error

    def summary(self) -> list[dict]:
        """Per segment: ``start_s, end_s, mass_kg``, the mean RMS error ``rms_error_rad``, the tool
        frame's mean errors ``ee_position_rms_mm``, ``ee_orientation_rms_deg`` (None where every
        trial failed; the units in the names, as :meth:`to_frame`'s columns) and the ratio's
        statistics ``ratio_to_floor`` (:func:`~adaptive_dd.benchmark.metrics.ratio_statistics`:
        mean, median, p90, max, ci95, worst_seed, n), and ``failed``: per trial stopped by the
        segment's end, its seed and time [s] (``{"seed": 3, "at_s": 1.234}``)."""
        from adaptive_dd.benchmark.metrics import ratio_statistics

        out = []
        r = self.ratio_to_floor
        for s, (a, b, m) in enumerate(self.segments):
            out.append({
                "start_s": a, "end_s": b, "mass_kg": m,
                "rms_error_rad": _mean(self.rms_error[:, s]),
                "ee_position_rms_mm": _mean(self.ee_position_rms[:, s]),
                "ee_orientation_rms_deg": _mean(self.ee_orientation_rms[:, s]),
                "ratio_to_floor": ratio_statistics(r[:, s], self.seeds),
                "failed": [
                    {"seed": int(seed), "at_s": float(t)}
                    for seed, t in zip(self.seeds, self._failed_at(), strict=True)
                    if np.isfinite(t) and t < b
                ],
            })  # fmt: skip
        return out

    def _failed_at(self) -> np.ndarray:
        if self.failed_at is not None:
            return np.asarray(self.failed_at, float)
        return np.full(len(self.failed), np.nan)  # built without the times: not known

    def to_frame(self):
        """One row per seed x segment (pandas DataFrame), the benchmark's column names."""
        import pandas as pd

        rows = []
        r = self.ratio_to_floor
        nan = np.full(r.shape, np.nan)
        extra = {
            "max_error_rad": self.max_error, "rms_torque_Nm": self.rms_torque,
            "saturation_fraction": self.saturation_fraction,
        }  # fmt: skip
        extra = {k: nan if v is None else v for k, v in extra.items()}
        for i, seed in enumerate(self.seeds):
            for s, (a, b, m) in enumerate(self.segments):
                rows.append({
                    "controller": self.name, "seed": seed, "segment": s, "start_s": a, "end_s": b,
                    "mass_kg": m, "rms_error_rad": self.rms_error[i, s], "floor": self.floor,
                    "ratio_to_floor": r[i, s], "failed": bool(self.failed[i]),
                    "failed_at_s": float(self._failed_at()[i]),
                    "ee_position_rms_mm": self.ee_position_rms[i, s],
                    "ee_position_max_mm": self.ee_position_max[i, s],
                    "ee_orientation_rms_deg": self.ee_orientation_rms[i, s],
                    **{k: v[i, s] for k, v in extra.items()},
                })  # fmt: skip
        return pd.DataFrame(rows)


def _mean(x) -> float | None:
    """Mean of the finite entries (None if there is none: every trial failed)."""
    v = np.asarray(x, float)
    v = v[np.isfinite(v)]
    return float(v.mean()) if v.size else None


def run_episode(policy: Callable, env: gymnasium.Env, seed: int) -> tuple[np.ndarray, bool, int]:
    """One episode of ``policy`` on ``env`` from ``reset(seed=seed)``.

    Returns the true joint angles ``(N, n)`` at the samples the policy commanded (the state each
    action was applied to; NaN after a failure), whether the trial failed, and the sample it
    failed at (-1: none). ``policy.reset()`` is called first if the policy has one. An episode the
    environment cuts short (a ``TimeLimit``: ``gymnasium.make(..., max_episode_steps=...)``) is an
    error: the score is over the scenario's whole trial."""
    q, _, _, failed, k = _episode(policy, env, seed)
    return q, failed, k


def _episode(policy: Callable, env: gymnasium.Env, seed: int):
    """:func:`run_episode` with the applied torque ``(N, n)`` and the saturation ``(N, n)`` of each
    sample (NaN / False after a failure): ``q, tau, saturated, failed, k``."""
    sc = env.unwrapped.scenario
    if hasattr(policy, "reset"):
        policy.reset()
    obs, info = env.reset(seed=int(seed))
    N, n = sc.n_samples, sc.n_joints
    q, tau = np.full((N, n), np.nan), np.full((N, n), np.nan)
    sat = np.zeros((N, n), dtype=bool)
    for k in range(N):
        q[k] = info["q_true"]
        action = policy(obs)
        try:
            obs, _, terminated, truncated, info = env.step(action)
        except SignalError as exc:  # the action's shape: say whose, where
            raise SignalError(
                f"the policy's action at seed {seed}, sample {k} (t = {k * sc.sample_period:.6g} s): {exc}"
            ) from None
        tau[k], sat[k] = info["applied_torque"], info["saturated"]
        if terminated:
            return q, tau, sat, True, k
        if truncated:
            if k < N - 1:
                raise ParameterError(
                    f"the environment ended seed {seed}'s episode at sample {k + 1} of the scenario's {N} "
                    "(a TimeLimit wrapper: gymnasium.make(..., max_episode_steps=...)?); the score is over "
                    "the whole trial: give evaluate the scenario, or an environment without the limit"
                )
            break
    return q, tau, sat, False, -1


def evaluate(
    policy: Callable,
    scenario: Scenario | str | Path | gymnasium.Env,
    seeds: Sequence[int] | int = 5,
    name: str = "policy",
    floor: str = FLOOR,
) -> Evaluation:
    """Run ``policy`` on trials ``seeds`` of ``scenario`` and set it beside the floor, seed by seed.

    Parameters
    ----------
    policy : callable
        ``policy(observation (5 n,)) -> torques (n,)`` [N m] (:mod:`adaptive_dd.gym.env`); with a
        ``reset()`` it is called before each episode.
    scenario : Scenario, path, or gymnasium.Env
        The scenario, or an environment over one (e.g. a
        :class:`~adaptive_dd.gym.wrappers.ResidualTorque`: the policy then gives the residual).
    seeds : sequence of int or int
        The trials' seed indices (an int ``m``: ``0 .. m - 1``).
    name : str
        The policy's name in the tables.
    floor : str
        The built-in law told the true model whose trials the policy's are divided by: ``ct_oracle``
        (computed torque), or the floor of the law the policy is closest to (``pd_gravity_oracle`` for
        a PD plus gravity, ``slotine_li_oracle``: the arena's floors).

    Returns
    -------
    Evaluation
        Per seed and segment: the policy's RMS error, the floor's on the same seed, their ratio and
        the tool frame's error (``summary()``, ``to_frame()``).

    Examples
    --------
    A policy that commands no torque, on half a second of the paper's arm (compiles its plant on a
    cold cache):

    >>> import numpy as np
    >>> from adaptive_dd.benchmark.scenario import parse_scenario
    >>> from adaptive_dd.gym.score import evaluate
    >>> sc = parse_scenario({"run": {"duration": 0.5, "seeds": 1}})
    >>> ev = evaluate(lambda obs: np.zeros(2), sc, seeds=1, name="zero")
    >>> ev.rms_error.shape  # seeds x segments
    (1, 1)
    >>> bool(ev.ratio_to_floor[0, 0] > 100)  # far from the oracle's tracking
    True
    """
    from adaptive_dd.benchmark.end_effector import end_effector_errors
    from adaptive_dd.benchmark.metrics import per_seed_segment_metrics
    from adaptive_dd.benchmark.runner import run_benchmark, scenario_controller
    from adaptive_dd.closed_loop.types import run_constants
    from adaptive_dd.gym import scenario_file
    from adaptive_dd.gym.env import PayloadSwapEnv, floor_laws

    if not isinstance(scenario, gymnasium.Env):
        scenario = PayloadSwapEnv(scenario_file(scenario, "evaluate"), floor=None)
    env = scenario
    sc = env.unwrapped.scenario
    told = floor_laws()
    if floor not in told:
        raise ParameterError(f"evaluate: floor {floor!r} is no built-in told the true model: one of {told}")
    ints = (int, np.integer)
    whole = isinstance(seeds, ints) and not isinstance(seeds, bool)
    many = isinstance(seeds, Sequence | np.ndarray) and not isinstance(seeds, str)
    if not (whole or (many and all(isinstance(s, ints) and not isinstance(s, bool) for s in seeds))):
        raise ParameterError(f"evaluate: seeds must be a count >= 1 or seed indices >= 0, got {seeds!r}")
    idx = tuple(range(seeds)) if whole else tuple(int(s) for s in seeds)
    if not idx or min(idx) < 0:
        raise ParameterError(f"evaluate: seeds must be a count >= 1 or seed indices >= 0, got {seeds!r}")
    try:
        floor_law = dict([scenario_controller(sc, floor)])  # before the episodes: it may not run here
    except ParameterError as exc:
        raise ParameterError(f"evaluate: floor {floor!r}: {exc}") from None
    rc = run_constants(sc)
    start, end = rc.seg_start, rc.seg_end
    G = start.size
    rms = np.full((len(idx), G), np.nan)
    max_e, rms_tau, sat_frac = (np.full((len(idx), G), np.nan) for _ in range(3))
    failed = np.zeros(len(idx), dtype=bool)
    failed_at = np.full(len(idx), np.nan)
    qs = np.full((len(idx), sc.n_samples, sc.n_joints), np.nan)
    for i, seed in enumerate(idx):
        q, tau, sat, failed[i], at = _episode(policy, env, seed)
        if failed[i]:
            failed_at[i] = at * sc.sample_period
        qs[i] = q
        e2 = np.sum((rc.q_d - q) ** 2, axis=1)
        t2 = np.sum(tau**2, axis=1)
        for s in range(G):
            if not failed[i] or end[s] <= at:  # the benchmark's rule: segments ending after it
                a, b = start[s], end[s]
                rms[i, s] = np.sqrt(np.sum(e2[a:b]) / (b - a))
                max_e[i, s] = np.sqrt(np.max(e2[a:b]))
                rms_tau[i, s] = np.sqrt(np.sum(t2[a:b]) / (b - a))
                sat_frac[i, s] = np.mean(np.any(sat[a:b], axis=1))
    ee = end_effector_errors(sc.arm, qs, rc.q_d, start, end)
    runs = run_benchmark(
        sc, progress=False, controllers=floor_law, seed_indices=idx,
        keep_trajectories=0,
    )  # fmt: skip
    label = next(iter(runs.runs))
    floor_rms = per_seed_segment_metrics(runs, runs.runs[label], settling=False)["rms_error"]
    return Evaluation(
        name, idx, list(sc.segments()), rms, floor_rms, ee["ee_position_rms"], ee["ee_position_max"],
        ee["ee_orientation_rms"], failed, floor, failed_at, max_e, rms_tau, sat_frac,
    )  # fmt: skip
