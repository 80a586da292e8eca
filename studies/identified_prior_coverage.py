"""Does the prior an excitation phase hands to adaptive_ct cover what the identification got wrong?

    python studies/identified_prior_coverage.py SCENARIO.toml [--seeds 10] [--excite 20]

Runs the scenario's excitation phase (:mod:`adaptive_dd.closed_loop.excitation_phase`: the designed
excitation tracked by ct_nominal on each seed's drawn plant, sensor noise at the scenario's levels)
and identifies each record (:func:`~adaptive_dd.closed_loop.excitation_phase.identify_record`).
Prints, for three rules of the prior's standard deviations, the errors of the identified base
parameters against each seed's plant in units of those standard deviations, ``z``: rms, the
fraction beyond 3, the largest, the Mahalanobis norm per parameter (median over seeds) and the
worst parameters (draws of a right prior: rms 1, 0.3 % beyond 3):

* ``white``: the white-residual least squares formula plus the consistent fit's step (the rule
  before this one);
* ``sandwich``: the Newey-West sandwich of ``adaptive-dd identify`` plus the step;
* ``sandwich + model error``: the rule in use
  (:func:`~adaptive_dd.identification.arm_prior.identified_prior_std` with
  :func:`~adaptive_dd.identification.model_error.model_error_variance`).
"""

from __future__ import annotations

import argparse
import copy
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop import excitation_phase as ep
from adaptive_dd.closed_loop.runner import run_closed_loop
from adaptive_dd.closed_loop.types import io_of, plant_of, true_models
from adaptive_dd.identification.friction_width import identification_model
from adaptive_dd.identification.regression import filtered_regression, weighted_least_squares


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--excite", type=float, default=20.0)
    a = ap.parse_args()
    d = copy.deepcopy(read_toml(Path(a.scenario)))
    d["run"]["excite"] = a.excite
    sc = parse_scenario(d, a.scenario, Path(a.scenario).stem)
    idx = tuple(range(a.seeds))
    exc = ep._excitation_scenario(sc, ep.excitation_reference(sc))
    run = run_closed_loop(exc, seed_indices=idx, keep_trajectories=len(idx)).runs[ep.EXCITATION_CONTROLLER]
    n, T, std = sc.n_joints, sc.sample_period, io_of(sc).std
    plant = true_models(plant_of(exc, idx))[:, 0] @ sc.arm.base.B.T
    rules: dict[str, list] = {"white": [], "sandwich": [], "sandwich + model error": []}
    for k, i in enumerate(idx):  # the noise of identify_excitation: generator (seed, i, 3)
        rng = np.random.default_rng([int(sc.seed), int(i), 3])
        qm = run.q[k] + std[:n] * rng.standard_normal(run.q[k].shape)
        qdm = run.qd[k] + std[n:] * rng.standard_normal(run.qd[k].shape)
        model = identification_model(sc.arm, qdm)  # the phase's model: its Coulomb law's width
        one = ep.identify_record(model, qm, qdm, run.tau[k], T)
        white = weighted_least_squares(
            filtered_regression(model, qm, qdm, run.tau[k], tau_f=ep.TAU_F, sample_period=T)
        )
        step2 = (one.fit - one.hat) ** 2
        e = one.fit - plant[k]
        for name, s in (
            ("white", np.sqrt(white.std**2 + step2)),
            ("sandwich", np.sqrt(np.diag(one.cov) + step2)),
            ("sandwich + model error", one.std),
        ):
            rules[name].append(e / s)
        print(f"seed {i}: identified", flush=True)
    print(f"{a.scenario}: {a.seeds} seeds, excite {a.excite:g} s, {model.p} base parameters")
    for name, zs in rules.items():
        Z = np.array(zs)
        worst = np.argsort(-np.sqrt(np.mean(Z**2, axis=0)))[:4]
        print(
            f"  {name:24s} z rms {np.sqrt(np.mean(Z**2)):.2f}, "
            f"beyond 3: {100 * np.mean(np.abs(Z) > 3):.1f} %, "
            f"max {np.abs(Z).max():.1f}, |z|^2 per parameter (median over seeds) "
            f"{np.median(np.mean(Z**2, axis=1)):.2f}; worst {', '.join(model.names[j][:12] for j in worst)}"
        )


if __name__ == "__main__":
    main()
