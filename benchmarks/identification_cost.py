"""What the identification costs adaptive_ct on robots drawn around their URDFs.

Usage::

    python benchmarks/identification_cost.py [--template benchmarks/scenarios/population_drawn.toml]
        [--arms 10] [--first-arm 0] [--seeds 2] [--only LABEL ...] [--cache DIR] [--csv FILE]
    python benchmarks/identification_cost.py --scenario FILE [--seeds 2] [--only LABEL ...]

(``--scenario``: one scenario with ``[run] excite`` in place of the drawn arms).

Per drawn arm and seed, the excitation phase and its identification run once
(:func:`~adaptive_dd.closed_loop.excitation_phase.identify_excitation`; ``--cache DIR`` keeps them
in ``DIR`` between runs), then the task runs once per variant of what adaptive_ct is given, every
variant on the same plants, noise and swaps (``ct_oracle``, the floor, once):

``identified``
    What ``[run] excite`` gives today: the identified model, the estimator in mode ``"arm"`` with
    the identification's covariance as its prior on the arm
    (:func:`~adaptive_dd.closed_loop.model_prior.identified_prior`).
``identified, p0_arm``, ``true, arm, p0_arm``
    ``identified`` and ``true, arm`` with ``OnlineConfig.p0_arm`` (1e-6 on every base parameter)
    added to the prior, as before the hand-off set it to 0.
``identified, scaled``
    The same with the prior divided by the report's ``estimator_scale`` (the identification's
    covariance in the units of the estimator's own rows:
    :func:`~adaptive_dd.closed_loop.model_prior.estimator_scale`).
``identified, payload``
    The identified model held fixed: the estimator in mode ``"payload"`` (the arm not learnt).
``identified, physical``
    ``identified`` with payload mode's treatment of the payload block in the model control uses:
    projected onto physical payloads, with the compact-payload prior weighed by the rows' noise
    (``OnlineConfig.project``, ``prior_radius``, ``prior_noise`` as payload mode's defaults).
``identified, arm held``
    ``identified`` with the arm block's prior 1e-12 times the identification's (the arm not
    learnt; the payload block started as in ``identified``).
``true, arm``
    The seed's true robot as the model, the estimator as in ``identified`` (the identification's
    prior): what the model's error costs, the estimator's mode the same.
``true, payload``
    The seed's true robot as the model, mode ``"payload"``: what a URDF exact to the plant gives
    (``population.toml``'s estimator on these plants).

Prints per arm and seed what the identification states against what it got wrong (the share of
base parameters whose identified variance is below ``OnlineConfig.p0_arm``'s 1e-6; the identified
model's base parameters' errors against the plant's in the standard deviations it states: rms,
max; ``--prior-only``: these lines alone), then per variant and segment the mean / p90 / max of
the per-seed ``adaptive_ct / ct_oracle`` RMS ratio (the worst arm and seed), and the same over
each segment less its first 0.5 s (``rms_error_settled``: the swap's transient left out).
Asserts nothing.
"""

from __future__ import annotations

import argparse
import dataclasses
import pickle
import sys
import tomllib
from pathlib import Path

import numpy as np

VARIANTS = (
    "identified", "identified, p0_arm", "identified, scaled", "identified, payload",
    "identified, physical", "identified, arm held", "true, arm", "true, arm, p0_arm", "true, payload",
)  # fmt: skip


def _identified(sc, idx, cache: Path | None):
    from adaptive_dd.closed_loop.excitation_phase import identify_excitation
    from adaptive_dd.closed_loop.runner import run_closed_loop

    path = None if cache is None else cache / f"{sc.name}_s{len(idx)}_kappa.pkl"
    if path is not None and path.exists():
        return pickle.loads(path.read_bytes())
    old = None if cache is None else cache / f"{sc.name}_s{len(idx)}.pkl"
    if old is not None and old.exists():  # an earlier run's, without the scale
        return (*pickle.loads(old.read_bytes()), np.full(len(idx), np.nan))
    pis, report = identify_excitation(sc, idx, run_closed_loop, scale_check=True)
    out = (pis, report.sigma_cov, report.estimator_scale)
    if path is not None:
        path.write_bytes(pickle.dumps(out))
    return out


def _model(arm, pi, tmp: Path, tag: str):
    from adaptive_dd.plant.urdf_write import write_urdf_links

    n = arm.n_joints
    path = write_urdf_links(arm, pi[: 10 * n], tmp / f"{tag}.urdf", tag)
    model = arm.with_(
        urdf=path, viscous=pi[10 * n : 11 * n], coulomb=pi[11 * n : 12 * n], armature=pi[12 * n :]
    )
    _ = model.pi_links, model.chain, model.base
    return model


def _options(sc, variant: str, prior):
    from adaptive_dd.identification.online_config import DEFAULT_PRIOR_RADIUS, OnlineConfig

    memory = OnlineConfig().tau_f / OnlineConfig().sample_period  # payload mode's "auto"
    from adaptive_dd.benchmark.scenario_settings import with_settings
    from adaptive_dd.closed_loop.model_prior import identified_prior, known_payload_mass_std

    if variant.endswith("payload"):
        return with_settings(sc, "adaptive_ct", {"estimator": {"mode": "payload"}}).controller_options
    if "p0_arm" in variant:  # the isotropic start-up variance added to the prior as before
        sc = with_settings(sc, "adaptive_ct", {"estimator": {"p0_arm": 1e-6}})
    if "held" in variant:  # the arm block held; the payload block's start from the prior as it is
        est = {"payload_mass_std": known_payload_mass_std(sc.arm, prior)}
        sc = with_settings(sc, "adaptive_ct", {"estimator": est})
        prior = np.asarray(prior) * 1e-12
    if "physical" in variant:  # payload mode's projection and compact prior on the payload block
        est = {"project": True, "prior_radius": DEFAULT_PRIOR_RADIUS, "prior_noise": memory}
        sc = with_settings(sc, "adaptive_ct", {"estimator": est})
    return identified_prior(sc, prior)


def prior_line(sc, pis, covs, truth) -> str:
    """Per seed: the share of base parameters whose identified variance is below ``p0_arm``'s
    1e-6, and the identified model's errors against the plant in its stated standard deviations
    (rms, max and where)."""
    B = sc.arm.base.B
    parts = []
    for k, (pi, C, tr) in enumerate(zip(pis, covs, truth, strict=True)):
        var = np.diag(C)
        z = B @ (pi - tr) / np.sqrt(np.maximum(var, 1e-300))
        j = int(np.argmax(np.abs(z)))
        parts.append(
            f"seed {k}: {100 * np.mean(var < 1e-6):.0f} % of {var.size} below 1e-6, error / std rms "
            f"{np.sqrt(np.mean(z**2)):.2f} max {abs(z[j]):.1f} ({sc.arm.base.names[j]})"
        )
    return f"{sc.name}: the identification's variance; " + "; ".join(parts)


def run_arm(sc, idx, variants, cache, tmp: Path) -> dict:
    """Per variant the frame rows of adaptive_ct (and ct_oracle once, as ``floor``)."""
    from adaptive_dd.closed_loop.excitation_phase import join_results
    from adaptive_dd.closed_loop.runner import run_closed_loop
    from adaptive_dd.closed_loop.types import plant_of, true_models
    from adaptive_dd.plant.uncertainty import exact_plant

    pis, covs, kappa = _identified(sc, idx, cache)
    print(f"{sc.name}: estimator_scale per seed {np.round(kappa, 3).tolist()}", flush=True)
    plant = sc.plant if sc.plant is not None else exact_plant(sc.arm)
    truth = true_models(plant_of(sc, idx))[:, 0]  # (S, 13 n): each seed's robot, no payload
    print(prior_line(sc, pis, covs, truth), flush=True)
    out = {}
    if not variants:
        return out
    for v in ("floor", *variants):
        parts = []
        for k, i in enumerate(idx):
            pi = truth[k] if v.startswith("true") else pis[k]
            model = _model(sc.arm, pi, tmp, f"{sc.name}_{k}_{v[:4]}")
            base = dataclasses.replace(sc, arm=model, plant=plant, excite=0.0)
            names = ("ct_oracle",) if v == "floor" else ("adaptive_ct",)
            base = base.with_controllers(names)
            prior = covs[k] / kappa[k] if "scaled" in v else covs[k]
            one = dataclasses.replace(base, controller_options=_options(base, v, prior))
            parts.append(run_closed_loop(one, seed_indices=(i,), keep_trajectories=0))
        res = join_results(parts, dataclasses.replace(sc, controllers=names), idx)
        out[v] = res.to_frame()
    return out


def main(argv=None) -> int:
    import tempfile

    import pandas as pd

    from adaptive_dd import load_scenario
    from adaptive_dd.benchmark.population import population_scenario
    from adaptive_dd.robots.random_arm import random_arm

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--template", default="benchmarks/scenarios/population_drawn.toml")
    ap.add_argument("--arms", type=int, default=10)
    ap.add_argument("--first-arm", type=int, default=0)
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--arm-list", type=int, nargs="+", default=None, help="these arm seeds instead")
    ap.add_argument("--only", nargs="+", default=None, choices=VARIANTS)
    ap.add_argument("--cache", type=Path, default=None)
    ap.add_argument("--prior-only", action="store_true", help="the identification's lines alone, no task")
    ap.add_argument("--csv", type=Path, default=None, help="write the per-seed rows here")
    ap.add_argument(
        "--scenario", default=None, help="this scenario (with [run] excite) instead of drawn arms"
    )
    a = ap.parse_args(argv)
    variants = () if a.prior_only else tuple(a.only or VARIANTS)
    data = tomllib.loads(Path(a.template).read_text())
    if a.cache is not None:
        a.cache.mkdir(parents=True, exist_ok=True)
    idx = tuple(range(a.seeds))
    rows = []
    from threadpoolctl import threadpool_limits

    with tempfile.TemporaryDirectory() as tmp, threadpool_limits(1):
        arms = [None] if a.scenario else a.arm_list or range(a.first_arm, a.first_arm + a.arms)
        for arm_seed in arms:
            if arm_seed is None:
                sc = load_scenario(a.scenario)
                cap = sc.arm.payload_capacity
            else:
                sc = population_scenario(data, a.template, arm_seed)
                cap = random_arm(arm_seed).payload_capacity
            sc = dataclasses.replace(sc, seeds=a.seeds).with_controllers(("ct_oracle", "adaptive_ct"))
            frames = run_arm(sc, idx, variants, a.cache, Path(tmp))
            if not frames:
                continue
            fl = frames["floor"].set_index(["seed", "segment"])
            for v in variants:
                f = frames[v]
                f = f[f["controller"] == "adaptive_ct"].copy()
                at = fl.loc[list(zip(f["seed"], f["segment"], strict=True))]
                f["ratio"] = f["rms_error_rad"].to_numpy() / at["rms_error_rad"].to_numpy()
                f["ratio_settled"] = (
                    f["rms_error_settled_rad"].to_numpy() / at["rms_error_settled_rad"].to_numpy()
                )
                f["variant"] = v
                f["arm_seed"] = -1 if arm_seed is None else arm_seed
                f["capacity_kg"] = cap
                rows.append(f)
                line = " / ".join(f"{g['ratio'].mean():.3f}" for _, g in f.groupby("segment"))
                print(f"{sc.name if arm_seed is None else f'random:{arm_seed}'} {v:20s} {line}", flush=True)
    if not rows:
        return 0
    df = pd.concat(rows, ignore_index=True)
    if a.csv is not None:
        df.to_csv(a.csv, index=False)
    print(summary(df, variants))
    return 0


def _where(arm_seed, seed) -> str:
    return f"seed {seed}" if arm_seed < 0 else f"random:{arm_seed}:{seed}"


def summary(df, variants) -> str:
    lines = ["adaptive_ct / ct_oracle per seed, per segment: mean / p90 / max (worst arm:seed)"]
    for v in variants:
        lines.append(f"{v}:")
        for s, g in df[df["variant"] == v].groupby("segment"):
            r = g["ratio"].to_numpy(float)
            k = int(np.nanargmax(r))
            rs = g["ratio_settled"].to_numpy(float)
            lines.append(
                f"  segment {s + 1}: {np.nanmean(r):.3f} / {np.nanquantile(r, 0.9):.3f} / {r[k]:.3f} "
                f"({_where(g['arm_seed'].iloc[k], g['seed'].iloc[k])}); after its first 0.5 s "
                f"{np.nanmean(rs):.3f} / {np.nanquantile(rs, 0.9):.3f} / {np.nanmax(rs):.3f}"
            )
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
