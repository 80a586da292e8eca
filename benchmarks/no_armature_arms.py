"""Drawn arms stripped of their armature: ``adaptive_ct`` against ``ct_oracle`` where a joint's
Coulomb friction dwarfs its inertia (the case ``adaptive-dd validate`` warns of).

Usage (from the repository's root)::

    python benchmarks/no_armature_arms.py [--arms 50] [--seeds 5]

Of the first ``--arms`` drawn arms (``random:0 ..``), those that become friction-dominated with
their armature set to zero (Coulomb friction over the smallest inertia about a joint's axis along
the task beyond ``preflight.FRICTION_ACCELERATION``) run ``benchmarks/scenarios/population.toml``'s
payload schedule, exact model, ``--seeds`` seeds each. Prints each arm's per-segment mean and max
of ``adaptive_ct / ct_oracle``, its false-alarm trials, and the mean over those arms. Asserts
nothing: a measurement (the changelog quotes it).
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.population import population_scenario
from adaptive_dd.benchmark.preflight import FRICTION_ACCELERATION
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.closed_loop.boost import task_room
from adaptive_dd.io import read_toml

TEMPLATE = Path(__file__).resolve().parent / "scenarios" / "population.toml"


def stripped(data: dict, seed: int, seeds: int):
    """The template's scenario on ``random:seed`` with no armature, or None when no joint is then
    friction-dominated."""
    sc = population_scenario(data, str(TEMPLATE), seed)
    arm = sc.arm.with_(armature=np.zeros(sc.arm.n_joints))
    sc = dataclasses.replace(
        sc, arm=arm, seeds=seeds, controllers=("ct_oracle", "adaptive_ct"), controller_options=()
    )
    inertia = np.diagonal(arm.mass_matrix(task_room(sc)[0]), axis1=-2, axis2=-1).min(axis=0)
    ratio = np.asarray(arm.coulomb, dtype=float) / inertia
    return (sc, float(ratio.max())) if ratio.max() > FRICTION_ACCELERATION else None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--arms", type=int, default=50)
    ap.add_argument("--seeds", type=int, default=5)
    args = ap.parse_args()
    data = read_toml(TEMPLATE)
    means, maxes = [], []
    for seed in range(args.arms):
        got = stripped(data, seed, args.seeds)
        if got is None:
            continue
        sc, ratio = got
        f = run_benchmark(sc, progress=False).to_frame()
        a = f[f.controller == "adaptive_ct"]
        by = a.groupby("segment")["ratio_to_floor"]
        means.append(by.mean().to_numpy())
        maxes.append(by.max().to_numpy())
        fa = int((a.groupby("seed")["false_alarms"].max() > 0).sum())
        print(
            f"random:{seed} ({sc.n_joints} joints, friction / inertia {ratio:.0f} rad/s^2): mean "
            f"{' / '.join(f'{x:.3f}' for x in means[-1])}, max {' / '.join(f'{x:.2f}' for x in maxes[-1])}, "
            f"false-alarm trials {fa} of {args.seeds}",
            flush=True,
        )
    if means:
        print(
            f"{len(means)} of {args.arms} arms friction-dominated without armature; mean over them per "
            f"segment {' / '.join(f'{x:.3f}' for x in np.mean(means, axis=0))}, max "
            f"{' / '.join(f'{x:.2f}' for x in np.max(maxes, axis=0))}"
        )


if __name__ == "__main__":
    main()
