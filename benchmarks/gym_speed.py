"""Environment steps per second beside the compiled benchmark's samples per second, in one run.

    python benchmarks/gym_speed.py [--scenario FILE] [--num-envs 64] [--steps 2000] [--seeds 8]

Three rates on the same scenario (default the UR5 tool swap), each with the ``pd`` law's gains
(a numpy PD on the observation for the environments, so that the arm tracks and no trial is
stopped; the compiled benchmark runs the built-in ``pd``):

- the single environment (:class:`adaptive_dd.gym.PayloadSwapEnv`, no floor torque), steps/s;
- the vector environment (:class:`adaptive_dd.gym.vector.PayloadSwapVectorEnv`), environment
  steps/s (``num_envs`` per call);
- the compiled benchmark (:func:`adaptive_dd.benchmark.runner.run_benchmark`), trial-samples/s.

Wall-clock rates: they depend on the machine and on what else runs on it. Each is timed after a
warm-up that loads (or compiles) its kernels.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.runner import run_benchmark, scenario_controller
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.gym import make_env
from adaptive_dd.gym.vector import PayloadSwapVectorEnv

ROOT = Path(__file__).resolve().parent.parent


def pd_gains(sc):
    """The built-in ``pd`` law's joint gains ``kp, kd (n,)``."""
    law = scenario_controller(sc, "pd")[1]
    cfg = law.law_config(sc.sample_period)
    return np.asarray(cfg.kp), np.asarray(cfg.kd)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default=str(ROOT / "adaptive_dd" / "scenarios" / "ur5_tool_swap.toml"))
    ap.add_argument("--num-envs", type=int, default=64)
    ap.add_argument("--steps", type=int, default=2000, help="steps timed per environment")
    ap.add_argument("--seeds", type=int, default=8, help="trials of the compiled benchmark")
    args = ap.parse_args()
    sc = load_scenario(args.scenario)
    n = sc.n_joints
    kp, kd = pd_gains(sc)

    def policy(obs):
        return kp * (obs[..., 2 * n : 3 * n] - obs[..., :n]) + kd * (
            obs[..., 3 * n : 4 * n] - obs[..., n : 2 * n]
        )

    env = make_env(sc, floor=None)
    rates = {}
    for label, e, per in (
        ("single environment", env, 1),
        (f"vector environment ({args.num_envs} trials)", None, args.num_envs),
    ):
        e = e or PayloadSwapVectorEnv(sc, num_envs=args.num_envs)
        obs, _ = e.reset(seed=0)
        for _ in range(20):  # warm-up: the kernels load
            obs = e.step(policy(obs))[0]
        t0 = time.perf_counter()
        for _ in range(args.steps):
            obs = e.step(policy(obs))[0]
        rates[label] = per * args.steps / (time.perf_counter() - t0)
    pd = dict([scenario_controller(sc, "pd")])
    import warnings

    from adaptive_dd.errors import RunWarning

    warnings.simplefilter("ignore", RunWarning)  # pd's floor is not run: a speed, no ratio
    run_benchmark(sc, progress=False, controllers=pd, seed_indices=[0], keep_trajectories=0)  # warm-up
    t0 = time.perf_counter()
    run_benchmark(sc, progress=False, controllers=pd, seed_indices=range(args.seeds), keep_trajectories=0)
    rates[f"compiled benchmark (pd, {args.seeds} trials)"] = (
        args.seeds * sc.n_samples / (time.perf_counter() - t0)
    )
    print(f"{sc.source}: {n} joints, T = {sc.sample_period} s")
    for label, r in rates.items():
        unit = "trial-samples/s" if label.startswith("compiled") else "env steps/s"
        print(f"  {label:40s} {r:12,.0f} {unit}")


if __name__ == "__main__":
    main()
