"""Command-line interface: ``adaptive-dd {check,simulate,reproduce,identify,benchmark}``."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

__all__ = ["main"]


def _cmd_check(args: argparse.Namespace) -> int:
    from adaptive_dd.plant.parameters import TABLE1_PHYSICAL, Payload
    from adaptive_dd.plant.pinocchio_model import cross_check

    payload = Payload(args.payload, args.radius) if args.payload else None
    label = f"payload {args.payload} kg" if payload else "no payload"
    print(f"Cross-check of adaptive_dd.plant against Pinocchio ({label}, {args.states} random states)")
    results = cross_check(
        TABLE1_PHYSICAL, payload, n_states=args.states, rng=np.random.default_rng(args.seed)
    )
    for r in results:
        print("  " + str(r))
    failed = [r for r in results if not r.passed]
    print(f"{len(results) - len(failed)} passed, {len(failed)} failed")
    return 1 if failed else 0


def _cmd_simulate(args: argparse.Namespace) -> int:
    from adaptive_dd.experiments import TABLE2, table2_torque, trial_rngs
    from adaptive_dd.io import write_recording
    from adaptive_dd.plant.simulator import (
        ActuatorConfig,
        PayloadSchedule,
        SensorConfig,
        simulate_open_loop,
    )
    from adaptive_dd.plotting import plot_trajectory

    n = round(args.duration / args.sample_period)
    tau = table2_torque(args.seeds, n, args.sample_period)
    sensor = SensorConfig(
        quantize=not args.no_quantize,
        position_variance=(0.0, 0.0) if args.no_noise else TABLE2["position_variance"],
        velocity_variance=(0.0, 0.0) if args.no_noise else TABLE2["velocity_variance"],
    )
    actuator = ActuatorConfig(saturate=not args.no_saturate, quantize=not args.no_quantize)
    payload = PayloadSchedule(initial_mass=args.payload, radius=args.radius)
    res = simulate_open_loop(
        tau,
        trial_rngs(args.seed, args.seeds),
        sample_period=args.sample_period,
        substeps=args.substeps,
        payload=payload,
        sensor=sensor,
        actuator=actuator,
    )
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    res.save(str(out / "trajectory.npz"))
    write_recording(out / "trajectory.csv", res.t, res.q_meas[0], res.qd_meas[0], res.tau[0])
    plot_trajectory(res, out / "trajectory.png")
    print(
        f"Table 2 experiment: 1 Hz sine torques {TABLE2['amplitude']} N m, {args.duration} s at "
        f"T = {args.sample_period} s, payload {args.payload} kg, {args.seeds} trial(s)"
    )
    print(f"  max |q|   [rad]    : {np.abs(res.q).max(axis=(0, 1)).round(4)}")
    print(f"  max |qd|  [rad/s]  : {np.abs(res.qd).max(axis=(0, 1)).round(4)}")
    print(f"  rms tau   [N m]    : {np.sqrt((res.tau**2).mean(axis=(0, 1))).round(4)}")
    print(f"  stuck fraction     : {(res.qd == 0).mean(axis=(0, 1)).round(4)}")
    print(f"  saturated fraction : {res.saturated.mean(axis=(0, 1)).round(4)}")
    print(f"  failed trials      : {int(res.failed.sum())}")
    print(
        f"wrote {out / 'trajectory.npz'} (all trials), {out / 'trajectory.csv'} (trial 0, "
        f"measured), {out / 'trajectory.png'}"
    )
    return 0


def _cmd_reproduce(args: argparse.Namespace) -> int:
    from adaptive_dd.identification.reproduce import (
        TAU_F_GRID,
        format_bounds,
        format_summary,
        format_table,
        run_reproduce,
    )

    tau_f = tuple(args.tau_f) if args.tau_f else TAU_F_GRID
    res = run_reproduce(
        seeds=args.seeds,
        seed=args.seed,
        tau_f=tau_f,
        estimators=tuple(args.estimators),
        progress=not args.no_progress,
        keep_theta=(_FIG5, _OURS),
        noise=not args.no_noise,
        extra_estimators=tuple(args.extra_estimators),
    )
    if args.no_noise:
        print("\nNOISE-FREE sensors (--no-noise): the errors below are modelling errors only")
    print(
        f"\nEstimation error [%] after 10 000 samples, mean±std over {args.seeds} seeds "
        "(paper's value in parentheses)\n"
    )
    for method, table in (("M1", "Table 3"), ("M2", "Table 5")):
        if (method, "15", "paper") in res.errors:
            print(f"{table} ({method}, estimator 'paper', split (15)):")
            print(format_table(res, method, "15", "paper", with_paper=True) + "\n")
    for method in ("M1", "M2"):
        if (method, "full", "exact") in res.errors:
            print(
                f"Ours ({method}, estimator 'exact': exact filtered regressor, aligned torque, "
                "data selection, full RLS):"
            )
            print(format_table(res, method, "full", "exact", with_paper=False) + "\n")
    print("Worst mean error over the seven parameters [%], every configuration:")
    print(format_summary(res) + "\n")
    if res.crb is not None:
        print(
            "Against the information limit (Cramér-Rao bound of this experiment: Table 2 torques, "
            "Table 2 + 4 noise, q and qd measured, torque known):"
        )
        print(format_bounds(res) + "\n")
    written = _reproduce_figures(res, tau_f, Path(args.out))
    if args.json:
        written.append(res.write_json(args.json))
    if written:
        print("wrote " + ", ".join(str(w) for w in written))
    return 0


_FIG5 = ("M2", "15", "paper")
_OURS = ("M2", "full", "exact")


def _reproduce_figures(res, tau_f: tuple, out: Path) -> list:
    """Fig. 5-like estimate histories and the Fig. 7 model responses; prints Fig. 7's rms."""
    from adaptive_dd.identification.reproduce import model_responses
    from adaptive_dd.plant.parameters import TABLE1_SIGMA
    from adaptive_dd.plotting import plot_estimates, plot_model_response

    written = []
    t = res.sim.t
    i5 = tau_f.index(0.006) if 0.006 in tau_f else 0
    i_best = tau_f.index(0.02) if 0.02 in tau_f else len(tau_f) - 1
    figures = (
        (_FIG5, i5, "fig5_paper_M2.png", "paper's M2 estimator, split (15)", "paper M2"),
        (_OURS, i_best, "fig5_exact_M2.png", "estimator 'exact' (M2)", "exact M2"),
    )
    models = {}
    for key, i, name, label, short in figures:
        if key in res.theta:
            title = f"Estimates, {label}, tau_f = {tau_f[i]}"
            written.append(plot_estimates(t, res.theta[key][i], TABLE1_SIGMA, out / name, title))
            models[f"{short}, tau_f = {tau_f[i]}"] = res.theta[key][i][:, -1].mean(axis=0)
    if models:
        arm_q, qs = model_responses(models, res.sim.t.size)
        written.append(
            plot_model_response(
                t,
                arm_q,
                qs,
                out / "fig7_model_response.png",
                "Arm and identified models, same torque (Table 2)",
            )
        )
        for k, q in qs.items():
            rms = np.sqrt(((q - arm_q) ** 2).mean(axis=0))
            print(f"Fig. 7: rms difference arm - model ({k}): {rms.round(4)} rad")
    return written


def _cmd_identify(args: argparse.Namespace) -> int:
    from adaptive_dd.identification.estimators import estimate
    from adaptive_dd.io import read_recording
    from adaptive_dd.plotting import plot_estimates

    rec = read_recording(args.data)
    if args.method == "M2" and rec.qd is None:
        print(
            f"adaptive-dd identify: {args.data}: method M2 needs columns qd1, qd2 "
            "(use --method M1 for position only)",
            file=sys.stderr,
        )
        return 2
    oe = args.estimator == "output_error"
    res = estimate(
        rec.q,
        rec.tau,
        rec.qd,
        estimator="exact" if oe else args.estimator,
        method=args.method,
        split=args.split,
        tau_f=args.tau_f,
        sample_period=rec.sample_period,
    )
    final, std = res.final, res.std
    if oe:
        final, std = _identify_output_error(rec, res.final, args)
    print(
        f"{rec.source}: {rec.t.size} samples at T = {rec.sample_period:.6g} s; estimator "
        f"{args.estimator}, method {args.method}, split {res.split}, tau_f = {args.tau_f}"
    )
    print(f"equations used: {int(res.n_used)} of {2 * rec.t.size}")
    if not np.all(np.isfinite(final)):
        print(
            "warning: the estimate is not finite: the record does not excite the arm enough", file=sys.stderr
        )
        return 1
    _print_with_bound(final, std, _identify_bound(rec, final, args), rec, args)
    out = Path(args.out)
    ref = np.full(7, np.nan) if args.true is None else np.asarray(args.true, float)
    path = plot_estimates(
        rec.t,
        res.theta[None],
        np.where(np.isfinite(ref), ref, final),
        out / "convergence.png",
        f"{Path(args.data).name}: {args.estimator} ({args.method})",
    )
    print(f"wrote {path}")
    return 0


def _print_with_bound(final, std, crb, rec, args: argparse.Namespace) -> None:
    from adaptive_dd.plant.parameters import SIGMA_NAMES

    print(f"{'param':>6} {'estimate':>12} {'std':>10} {'CRB std':>10} {'CRB [%]':>9} {'std/CRB':>8}")
    for k, name in enumerate(SIGMA_NAMES):
        print(
            f"{name:>6} {final[k]:12.5g} {std[k]:10.2g} {crb.crb_std[k]:10.2g} "
            f"{crb.crb_std_pct[k]:9.2g} {std[k] / crb.crb_std[k]:8.1f}"
        )
    print(
        f"CRB: the smallest std any unbiased estimator can reach from this record (measured "
        f"torque, noise variances q {args.position_variance}, qd {args.velocity_variance}, "
        f"signals {'q, qd' if rec.qd is not None else 'q'}, initial state unknown), evaluated at the "
        "estimate; "
        f"condition number {crb.condition_number:.3g}"
    )


def _identify_output_error(rec, sigma0, args: argparse.Namespace):
    from adaptive_dd.identification.output_error import output_error_fit

    if rec.qd is None:
        raise ValueError(f"{args.data}: estimator output_error needs columns qd1, qd2")
    fit = output_error_fit(
        rec.q,
        rec.qd,
        rec.tau,
        sigma0,
        rec.sample_period,
        args.position_variance,
        args.velocity_variance,
    )
    print(f"output error: {fit.nfev} evaluations, {fit.message}")
    return fit.sigma, fit.std


def _identify_bound(rec, sigma, args: argparse.Namespace):
    """Cramér-Rao bound at the estimate for the record's torque, the initial state estimated too."""
    from adaptive_dd.identification.fisher import fisher_information
    from adaptive_dd.plant.parameters import project_sigma

    qd0 = np.zeros(2)
    if rec.qd is not None:  # a measured velocity within 3 noise std of zero: at rest (stuck)
        at_rest = np.abs(rec.qd[0]) <= 3 * np.sqrt(np.asarray(args.velocity_variance))
        qd0 = np.where(at_rest, 0.0, rec.qd[0])
    return fisher_information(
        project_sigma(sigma),
        rec.tau,
        rec.sample_period,
        args.position_variance,
        args.velocity_variance,
        measured=("q", "qd") if rec.qd is not None else ("q",),
        q0=rec.q[0],
        qd0=qd0,
        initial_state="unknown",
    )


def _cmd_benchmark(args: argparse.Namespace) -> int:
    import dataclasses

    from adaptive_dd.benchmark.metrics import compute_metrics
    from adaptive_dd.benchmark.report import format_report, write_csv, write_json
    from adaptive_dd.benchmark.runner import run_benchmark
    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.plotting import plot_benchmark_estimates, plot_tracking_errors

    sc = load_scenario(args.scenario)
    if args.seeds is not None:
        if args.seeds < 1:
            raise ValueError(f"--seeds must be >= 1, got {args.seeds}")
        sc = dataclasses.replace(sc, seeds=args.seeds)
    res = run_benchmark(sc, progress=not args.no_progress)
    metrics = compute_metrics(res)
    print(format_report(metrics, res))
    out = Path(args.out)
    written = [
        write_csv(metrics, out / "metrics.csv"),
        write_json(metrics, args.json or out / "metrics.json"),
        plot_tracking_errors(res, out / "tracking_error.png"),
    ]
    if any(r.sigma_hat is not None for r in res.runs.values()):
        written.append(plot_benchmark_estimates(res, out / "estimates.png"))
    print("wrote " + ", ".join(str(w) for w in written))
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="adaptive-dd", description=__doc__)
    sub = p.add_subparsers(dest="command", required=True)

    c = sub.add_parser("check", help="cross-check the dynamics against Pinocchio")
    c.add_argument("--payload", type=float, default=0.0, metavar="KG", help="tip disk mass [kg]")
    c.add_argument("--radius", type=float, default=0.05, help="tip disk radius [m]")
    c.add_argument("--states", type=int, default=200, help="number of random states")
    c.add_argument("--seed", type=int, default=0)
    c.set_defaults(func=_cmd_check)

    s = sub.add_parser("simulate", help="simulate the paper's open-loop Table 2 experiment")
    s.add_argument("--duration", type=float, default=10.0, help="[s] (default 10)")
    s.add_argument("--sample-period", type=float, default=1e-3, help="T [s] (default 0.001)")
    s.add_argument("--substeps", type=int, default=2, help="RK4 steps per sample")
    s.add_argument("--seeds", type=int, default=1, help="number of trials (noise seeds)")
    s.add_argument("--seed", type=int, default=0, help="base seed")
    s.add_argument("--payload", type=float, default=0.0, metavar="KG")
    s.add_argument("--radius", type=float, default=0.05)
    s.add_argument("--no-noise", action="store_true", help="noise-free sensors")
    s.add_argument("--no-quantize", action="store_true", help="no encoder or D/A quantization")
    s.add_argument("--no-saturate", action="store_true", help="no torque saturation")
    s.add_argument("--out", default="results/simulate", help="output folder")
    s.set_defaults(func=_cmd_simulate)

    from adaptive_dd.experiments import TABLE2
    from adaptive_dd.identification.estimators import ESTIMATORS
    from adaptive_dd.identification.reproduce import DEFAULT_ESTIMATORS, EXTRA_ESTIMATORS

    r = sub.add_parser("reproduce", help="reproduce Tables 3 and 5 of the paper (and ours beside)")
    r.add_argument("--seeds", type=int, default=10, help="Monte-Carlo seeds (default 10)")
    r.add_argument("--seed", type=int, default=0, help="base seed")
    r.add_argument("--tau-f", type=float, nargs="+", help="filter time constants (default: the paper's)")
    r.add_argument(
        "--estimators",
        nargs="+",
        default=list(DEFAULT_ESTIMATORS),
        choices=ESTIMATORS,
        help="estimators to run (kalman equals batch_ls here and costs ~1 min more)",
    )
    r.add_argument(
        "--extra-estimators",
        nargs="+",
        default=[],
        choices=EXTRA_ESTIMATORS,
        help="also run output error (~6 s per seed) and/or the augmented EKF (~1 min per 10 seeds)",
    )
    r.add_argument("--out", default="results/reproduce", help="folder for figures")
    r.add_argument("--json", metavar="PATH", help="write tidy rows as JSON")
    r.add_argument("--no-noise", action="store_true", help="noise-free sensors (modelling errors only)")
    r.add_argument("--no-progress", action="store_true")
    r.set_defaults(func=_cmd_reproduce)

    i = sub.add_parser("identify", help="estimate sigma from a recorded experiment (CSV)")
    i.add_argument("data", help="CSV with header t,q1,q2,qd1,qd2,tau1,tau2 (qd optional for M1)")
    i.add_argument(
        "--estimator",
        default="exact",
        choices=(*ESTIMATORS, "output_error"),
        help="output_error: maximum likelihood started from 'exact' (needs qd)",
    )
    i.add_argument("--method", default="M2", choices=("M1", "M2"))
    i.add_argument("--split", default="15", choices=("15", "16", "full"), help="split of 'paper'")
    i.add_argument("--tau-f", type=float, default=0.02, help="filter time constant [s]")
    i.add_argument("--true", type=float, nargs=7, metavar="S", help="true sigma, to mark on the plot")
    i.add_argument(
        "--position-variance",
        type=float,
        nargs=2,
        default=list(TABLE2["position_variance"]),
        metavar="V",
        help="noise variance of q1, q2 [rad^2] for the bound (default: Table 2)",
    )
    i.add_argument(
        "--velocity-variance",
        type=float,
        nargs=2,
        default=list(TABLE2["velocity_variance"]),
        metavar="V",
        help="noise variance of qd1, qd2 [(rad/s)^2] for the bound (default: Table 4)",
    )
    i.add_argument("--out", default="results/identify")
    i.set_defaults(func=_cmd_identify)

    b = sub.add_parser("benchmark", help="payload-swap tracking benchmark (the main job)")
    b.add_argument("scenario", nargs="?", help="scenario TOML (default: the shipped payload_swap)")
    b.add_argument("--out", default="results/benchmark", help="folder for CSV, JSON and figures")
    b.add_argument("--json", metavar="PATH", help="where to write the JSON (default OUT/metrics.json)")
    b.add_argument("--seeds", type=int, help="override the scenario's number of seeds")
    b.add_argument("--no-progress", action="store_true")
    b.set_defaults(func=_cmd_benchmark)
    return p


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except ValueError as exc:  # our errors subclass ValueError and name what was wrong
        print(f"adaptive-dd {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
