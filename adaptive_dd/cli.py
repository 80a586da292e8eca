"""Command-line interface: ``adaptive-dd {check,simulate,reproduce,identify,benchmark,sweep}``."""

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
        format_summary,
        format_table,
        model_responses,
        run_reproduce,
    )
    from adaptive_dd.plant.parameters import TABLE1_SIGMA
    from adaptive_dd.plotting import plot_estimates, plot_model_response

    tau_f = tuple(args.tau_f) if args.tau_f else TAU_F_GRID
    fig5 = ("M2", "15", "paper")
    ours = ("M2", "full", "exact")
    res = run_reproduce(
        seeds=args.seeds,
        seed=args.seed,
        tau_f=tau_f,
        estimators=tuple(args.estimators),
        progress=not args.no_progress,
        keep_theta=(fig5, ours),
        noise=not args.no_noise,
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
    out = Path(args.out)
    written = []
    t = res.sim.t
    i5 = tau_f.index(0.006) if 0.006 in tau_f else 0
    i_best = tau_f.index(0.02) if 0.02 in tau_f else len(tau_f) - 1
    figures = (
        (fig5, i5, "fig5_paper_M2.png", "paper's M2 estimator, split (15)"),
        (ours, i_best, "fig5_exact_M2.png", "estimator 'exact' (M2)"),
    )
    for key, i, name, label in figures:
        if key in res.theta:
            title = f"Estimates, {label}, tau_f = {tau_f[i]}"
            written.append(plot_estimates(t, res.theta[key][i], TABLE1_SIGMA, out / name, title))
    models = {}
    for key, i, label in ((fig5, i5, "paper M2"), (ours, i_best, "exact M2")):
        if key in res.theta:
            models[f"{label}, tau_f = {tau_f[i]}"] = res.theta[key][i][:, -1].mean(axis=0)
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
    if args.json:
        written.append(res.write_json(args.json))
    if written:
        print("wrote " + ", ".join(str(w) for w in written))
    return 0


def _cmd_identify(args: argparse.Namespace) -> int:
    from adaptive_dd.identification.estimators import estimate
    from adaptive_dd.io import read_recording
    from adaptive_dd.plant.parameters import SIGMA_NAMES
    from adaptive_dd.plotting import plot_estimates

    rec = read_recording(args.data)
    if args.method == "M2" and rec.qd is None:
        print(
            f"adaptive-dd identify: {args.data}: method M2 needs columns qd1, qd2 "
            "(use --method M1 for position only)",
            file=sys.stderr,
        )
        return 2
    res = estimate(
        rec.q,
        rec.tau,
        rec.qd,
        estimator=args.estimator,
        method=args.method,
        split=args.split,
        tau_f=args.tau_f,
        sample_period=rec.sample_period,
    )
    print(
        f"{rec.source}: {rec.t.size} samples at T = {rec.sample_period:.6g} s; estimator "
        f"{args.estimator}, method {args.method}, split {res.split}, tau_f = {args.tau_f}"
    )
    print(f"equations used: {int(res.n_used)} of {2 * rec.t.size}")
    print(f"{'param':>6} {'estimate':>12} {'std':>10}")
    for k, name in enumerate(SIGMA_NAMES):
        print(f"{name:>6} {res.final[k]:12.5g} {res.std[k]:10.2g}")
    if not np.all(np.isfinite(res.final)):
        print(
            "warning: the estimate is not finite: the record does not excite the arm enough", file=sys.stderr
        )
        return 1
    out = Path(args.out)
    ref = np.full(7, np.nan) if args.true is None else np.asarray(args.true, float)
    path = plot_estimates(
        rec.t,
        res.theta[None],
        np.where(np.isfinite(ref), ref, res.final),
        out / "convergence.png",
        f"{Path(args.data).name}: {args.estimator} ({args.method})",
    )
    print(f"wrote {path}")
    return 0


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


def _cmd_sweep(args: argparse.Namespace) -> int:
    import dataclasses

    from adaptive_dd.sweep import run_sweep
    from adaptive_dd.sweep_spec import load_sweep

    sweep = load_sweep(args.sweep)
    if args.block is not None:
        if args.block < 1:
            raise ValueError(f"--block must be >= 1, got {args.block}")
        sweep = dataclasses.replace(sweep, block=min(args.block, sweep.seeds))
    if args.workers is not None and args.workers < 1:
        raise ValueError(f"--workers must be >= 1, got {args.workers}")
    if args.scheduler and args.workers:
        print("adaptive-dd sweep: --workers is ignored with --scheduler", file=sys.stderr)
    res = run_sweep(
        sweep, args.out, scheduler=args.scheduler, workers=args.workers, progress=not args.no_progress
    )
    failed = res.table.loc[res.table["failed"], "error"]
    print(
        f"{len(res.table)} rows ({res.failed_rows} failed), {res.ran} tasks run, {res.reused} reused; "
        f"wrote {res.table_path}" + "".join(f", {p}" for p in res.heatmaps)
    )
    for msg, count in failed.value_counts().head(5).items():
        print(f"  failed rows: {count} x {msg}")
    if sweep.heatmap:
        from adaptive_dd.sweep import ratio_medians

        hm = sweep.heatmap
        r = ratio_medians(res.table, hm, [a for a, _ in sweep.axes])
        print(
            f"median over seeds of rms {hm['adaptive']} / rms {hm['floor']}, segment {hm['segment']}"
            f" (rows {hm['y']}, columns {hm['x']}; median over any other axes):"
        )
        print(r.pivot_table(index=hm["y"], columns=hm["x"], values="ratio", aggfunc="median").round(3))
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

    from adaptive_dd.identification.estimators import ESTIMATORS
    from adaptive_dd.identification.reproduce import DEFAULT_ESTIMATORS

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
    r.add_argument("--out", default="results/reproduce", help="folder for figures")
    r.add_argument("--json", metavar="PATH", help="write tidy rows as JSON")
    r.add_argument("--no-noise", action="store_true", help="noise-free sensors (modelling errors only)")
    r.add_argument("--no-progress", action="store_true")
    r.set_defaults(func=_cmd_reproduce)

    i = sub.add_parser("identify", help="estimate sigma from a recorded experiment (CSV)")
    i.add_argument("data", help="CSV with header t,q1,q2,qd1,qd2,tau1,tau2 (qd optional for M1)")
    i.add_argument("--estimator", default="exact", choices=ESTIMATORS)
    i.add_argument("--method", default="M2", choices=("M1", "M2"))
    i.add_argument("--split", default="15", choices=("15", "16", "full"), help="split of 'paper'")
    i.add_argument("--tau-f", type=float, default=0.02, help="filter time constant [s]")
    i.add_argument("--true", type=float, nargs=7, metavar="S", help="true sigma, to mark on the plot")
    i.add_argument("--out", default="results/identify")
    i.set_defaults(func=_cmd_identify)

    b = sub.add_parser("benchmark", help="payload-swap tracking benchmark (the main job)")
    b.add_argument("scenario", nargs="?", help="scenario TOML (default: the shipped payload_swap)")
    b.add_argument("--out", default="results/benchmark", help="folder for CSV, JSON and figures")
    b.add_argument("--json", metavar="PATH", help="where to write the JSON (default OUT/metrics.json)")
    b.add_argument("--seeds", type=int, help="override the scenario's number of seeds")
    b.add_argument("--no-progress", action="store_true")
    b.set_defaults(func=_cmd_benchmark)

    w = sub.add_parser("sweep", help="grid over scenario fields x controllers x seeds, on Dask")
    w.add_argument("sweep", help="sweep TOML (see docs/sweeps.md)")
    w.add_argument("--out", default="results/sweep", help="folder for cells, table and heatmaps")
    w.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler (default: local cluster)")
    w.add_argument("--workers", type=int, help="local cluster worker processes (default: all cores)")
    w.add_argument("--block", type=int, metavar="SEEDS", help="seeds per task (overrides sweep.block)")
    w.add_argument("--no-progress", action="store_true")
    w.set_defaults(func=_cmd_sweep)
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
