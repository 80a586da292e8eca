"""``[run] excite`` with the estimator's mode "arm": the task's report with and without an
excitation phase before it, on one scenario (ct_oracle, ct_nominal and adaptive_ct only).

    python studies/excitation_phase.py SCENARIO.toml [--seeds 20] [--excite 20] [--first-seed 0]
        [--only with|without] [--urdf-prior] [--handoff cov|std|noise] [--prior-scale S]
        [--region task|arm] [--reach on|off] [--targets] [--coverage-only]

Prints, for ``excite = 0`` and ``excite = SECONDS``, adaptive_ct / ct_oracle per segment (mean,
p90, max over seeds), the first segment's time to come within 1.2x of the floor
(:mod:`adaptive_dd.benchmark.time_to_floor`), trials with a false alarm, missed swaps, the median
detection delay, ct_nominal / ct_oracle per segment, and the identification's errors.
``--urdf-prior``: adaptive_ct's arm prior after the phase is the scenario's stated uncertainty
(``[plant.uncertainty]``) about the identified model, not what the identification knows (the
default, :func:`adaptive_dd.closed_loop.excitation_phase.identified_prior`). ``--handoff std``:
that prior's standard deviations only (the hand-off before the correlations were passed on).
``--handoff noise``: the covariance divided by the rows' white-noise variance (about 35x wider on
the iiwa); ``--prior-scale S``: the covariance handed on times ``S`` (ablations; ``S = 35``, about
what ``noise`` does, measured
worse, docs/learning_the_arm.md). With the phase it also prints the consistency check
``estimator_scale`` per seed (:func:`adaptive_dd.closed_loop.model_prior.estimator_scale`) and
the excitation's coverage of the task's region (:class:`adaptive_dd.identification.excitation.Coverage`).
``--region task``: the excitation designed on the task's region (the arm's limits narrowed to the
reference's positions +- ``TASK_MARGIN``), not over the arm's whole limits (the default,
:func:`adaptive_dd.closed_loop.excitation_phase.excitation_reference`; measured worse).
``--reach on``: the design's acceleration limit raised per joint to the largest the task's
reference reaches (:data:`adaptive_dd.closed_loop.excitation_phase.REACH_TASK`, an option: round
31, docs/learning_the_arm.md); ``off`` (the default) keeps the arm's one 5 rad/s^2.
``--targets``: also the benchmark report's "Targets" section of each run (what ``adaptive-dd
benchmark`` prints for the scenario with ``[run] excite`` set). ``--coverage-only``: the designed
excitation's coverage of the task's region alone (no run).
"""

from __future__ import annotations

import argparse
import copy
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.metrics import compute_metrics
from adaptive_dd.benchmark.report import time_to_floor_line
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import parse_scenario, read_toml


def summary(d: dict, source: str, seeds: list[int], targets: bool = False) -> list[str]:
    """The figures of one run of the scenario ``d`` over ``seeds`` (``targets``: and the report's
    "Targets" section)."""
    sc = parse_scenario(d, source, Path(source).stem)
    res = run_benchmark(sc, progress=False, seed_indices=seeds)
    m = compute_metrics(res)
    c = m["controllers"]
    a = c["adaptive_ct"]
    lines = []
    for name in ("adaptive_ct", "ct_nominal"):
        cells = [
            f"{s['ratio_to_floor']['mean']:.3f}/{s['ratio_to_floor']['p90']:.3f}/{s['ratio_to_floor']['max']:.2f}"
            for s in c[name]["segments"]
        ]
        lines.append(f"  {name} / ct_oracle mean/p90/max per segment: " + "  ".join(cells))
    lines.append("  " + time_to_floor_line("adaptive_ct", a))
    o = c["ct_oracle"]["segments"]
    per_seed = [
        "/".join(f"{x / y:.3f}" for x, y in zip(
            (s["rms_error_per_seed"][k] for s in a["segments"]), (s["rms_error_per_seed"][k] for s in o),
            strict=True))
        for k in range(len(seeds))
    ]  # fmt: skip
    lines.append("  adaptive_ct / ct_oracle per seed: " + " ".join(per_seed))
    delays = [s.get("detection_delay_median") for s in a["segments"][1:]]
    limits = [s.get("detection_limit") for s in a["segments"][1:]]
    lines.append(
        f"  trials with a false alarm {a['trials_with_false_alarms']} of {len(seeds)}, missed swaps "
        f"{a['missed_swaps']}, median detection delay ms "
        + " / ".join("-" if x is None else f"{1e3 * x:.0f}" for x in delays)
        + " (limit "
        + " / ".join("-" if x is None else f"{1e3 * x:.0f}" for x in limits)
        + ")"
    )
    if res.excitation is not None:
        rep = res.cache["excitation_report"]
        err = rep.errors()
        lines.append(
            "  identification: base parameters' error against the plant's, median (worst) over "
            f"parameters and seeds: model {np.median(err['model']):.3g} ({err['model'].max():.3g}), "
            f"identified {np.median(err['fit']):.3g} ({err['fit'].max():.3g})"
        )
        if rep.coverage is not None:
            lines.append("  " + rep.coverage.line())
        lines.append(
            "  Coulomb law's width per seed [rad/s] (the record's velocity noise): "
            + " ".join(f"{x:.4g}" for x in rep.coulomb_width)
        )
        if rep.estimator_scale is not None:
            lines.append(
                "  the identification's covariance against the online estimator's information from the "
                "same record (estimator_scale, median generalised eigenvalue) per seed: "
                + " ".join(f"{x:.3g}" for x in rep.estimator_scale)
            )
    if targets:
        from adaptive_dd.benchmark.report import format_report

        text = format_report(m, res)
        lines += ["  " + x for x in text[text.index("Targets") :].splitlines()]
    lines.append(f"  wall time {res.wall_time:.0f} s")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario")
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--excite", type=float, default=20.0)
    ap.add_argument("--only", choices=("with", "without"), default=None)
    ap.add_argument("--urdf-prior", action="store_true")
    ap.add_argument("--handoff", choices=("cov", "std", "noise"), default="cov")
    ap.add_argument("--prior-scale", type=float, default=None, help="the handed-on covariance times S")
    ap.add_argument(
        "--region", choices=("arm", "task"), default="arm", help="where the excitation is designed"
    )
    ap.add_argument(
        "--reach", choices=("on", "off"), default="off", help="the design's accelerations up to the task's"
    )
    ap.add_argument("--targets", action="store_true", help="also print the report's Targets section")
    ap.add_argument("--coverage-only", action="store_true", help="the excitation's coverage alone, no run")
    a = ap.parse_args()
    if a.reach == "on":  # the acceleration limits raised to the task's (an option, round 31)
        from adaptive_dd.closed_loop import excitation_phase

        excitation_phase.REACH_TASK = True
    if a.coverage_only:
        from adaptive_dd.closed_loop.excitation_phase import excitation_coverage, excitation_reference

        sc = parse_scenario(read_toml(Path(a.scenario)), a.scenario, Path(a.scenario).stem)
        ref = excitation_reference(sc, a.region)
        cov = excitation_coverage(sc, ref, a.excite)
        print(f"{a.scenario}, {a.region} design, {a.excite:g} s: {cov.line()}")
        return
    if a.region != "arm":  # the design on the task's region (an ablation: measured worse)
        from adaptive_dd.closed_loop import excitation_phase

        design = excitation_phase.excitation_reference
        excitation_phase.excitation_reference = lambda sc: design(sc, a.region)
    if a.prior_scale is not None:  # an ablation: the hand-off's covariance scaled by a constant
        from adaptive_dd.closed_loop import excitation_phase, model_prior

        excitation_phase.identified_prior = lambda sc, P: model_prior.identified_prior(sc, a.prior_scale * P)
    if a.handoff == "noise":  # the covariance in the units of the estimator's rows (unit noise)
        from adaptive_dd.closed_loop import excitation_phase
        from adaptive_dd.identification.online import derived_row_weights

        ident = excitation_phase.identify_excitation

        def scaled(scenario, idx, run):
            pis, rep = ident(scenario, idx, run)
            w = derived_row_weights(scenario.arm)
            s2 = np.mean((rep.rstd / w) ** 2, axis=1)  # (S,) the rows' noise variance
            print(f"  handoff noise: rows' residual variance per seed {np.round(s2, 5).tolist()}", flush=True)
            rep.sigma_cov = rep.sigma_cov / s2[:, None, None]
            return pis, rep

        excitation_phase.identify_excitation = scaled
    if a.handoff == "std":  # the diagonal only: what the phase handed on before the correlations
        from adaptive_dd.closed_loop import excitation_phase, model_prior

        excitation_phase.identified_prior = lambda sc, P: model_prior.identified_prior(
            sc, np.sqrt(np.diag(P))
        )
    base = copy.deepcopy(read_toml(Path(a.scenario)))
    base["run"]["controllers"] = ["ct_oracle", "ct_nominal", "adaptive_ct"]
    if a.urdf_prior:
        levels = {k: v for k, v in base["plant"]["uncertainty"].items() if k != "distribution"}
        ac = base.setdefault("controllers", {}).setdefault("adaptive_ct", {})
        ac.setdefault("estimator", {})["arm_uncertainty"] = levels
    seeds = list(range(a.first_seed, a.first_seed + a.seeds))
    runs = {"without": 0.0, "with": a.excite}
    for label, excite in runs.items():
        if a.only and label != a.only:
            continue
        d = copy.deepcopy(base)
        d["run"]["excite"] = excite
        print(f"{a.scenario}, seeds {seeds[0]}..{seeds[-1]}, excite = {excite:g} s:", flush=True)
        print("\n".join(summary(d, a.scenario, seeds, a.targets)), flush=True)


if __name__ == "__main__":
    main()
