"""Command-line interface: ``adaptive-dd {check,simulate,reproduce,identify,benchmark,validate}``.

Exit codes: 0 success, 1 a check or an estimate failed, 2 a user error (bad option,
scenario, record or output path; one line naming the problem), 3 an internal error
(a short message; the traceback with ``--debug``), 130 interrupted.
"""

from __future__ import annotations

import argparse
import math
import sys
import traceback
from pathlib import Path

import numpy as np

from adaptive_dd.errors import OutputError, ParameterError

__all__ = ["EXIT_INTERNAL", "EXIT_INTERRUPTED", "EXIT_USAGE", "build_parser", "main"]

EXIT_USAGE = 2
EXIT_INTERNAL = 3
EXIT_INTERRUPTED = 130
ISSUE_TRACKER = "the adaptive_dd issue tracker"


def _number(kind: type, lo: float, hi: float, lo_open: bool = False):
    """An argparse ``type`` accepting a finite ``kind`` in ``[lo, hi]`` (``(lo, hi]``)."""

    def parse(text: str):
        try:
            v = kind(text)
        except ValueError:
            what = "an integer" if kind is int else "a number"
            raise argparse.ArgumentTypeError(f"not {what}: {text!r}") from None
        if (kind is float and not math.isfinite(v)) or (v <= lo if lo_open else v < lo) or v > hi:
            raise argparse.ArgumentTypeError(f"{text} is outside {'(' if lo_open else '['}{lo:g}, {hi:g}]")
        return v

    parse.__name__ = kind.__name__
    return parse


_POS = _number(float, 0.0, 1e6, lo_open=True)
_SEED = _number(int, 0, 2**63 - 1)
_SEEDS = _number(int, 1, 10_000)
_MASS = _number(float, 0.0, 50.0)
_RADIUS = _number(float, 0.0, 0.5)
_PERIOD = _number(float, 1e-5, 0.1)
_SUBSTEPS = _number(int, 1, 100)


def _sub(sub, name: str, **kw) -> argparse.ArgumentParser:
    return sub.add_parser(name, allow_abbrev=False, **kw)


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
    from adaptive_dd.benchmark.scenario import LIMITS, run_estimate
    from adaptive_dd.outputs import OutputSet

    if args.duration < 10 * args.sample_period:
        raise ParameterError(
            f"--duration {args.duration} s is shorter than 10 samples of {args.sample_period} s"
        )
    n = round(args.duration / args.sample_period)
    est = run_estimate(n, args.seeds, 1)
    if est.bytes > LIMITS["max_bytes"] or est.seconds > LIMITS["max_seconds"]:
        raise ParameterError(f"run too large: {est}; reduce --duration or --seeds")
    if est.large:
        print(f"estimate: {est}", file=sys.stderr)
    outputs = OutputSet(args.out)
    with outputs:
        return _simulate(args, n, outputs)


def _simulate(args: argparse.Namespace, n: int, outputs) -> int:
    from adaptive_dd.experiments import TABLE2, table2_torque, trial_rngs
    from adaptive_dd.io import write_recording
    from adaptive_dd.plant.simulator import (
        ActuatorConfig,
        PayloadSchedule,
        SensorConfig,
        simulate_open_loop,
    )
    from adaptive_dd.plotting import plot_trajectory

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
    res.save(str(outputs.path("trajectory.npz")))
    write_recording(outputs.path("trajectory.csv"), res.t, res.q_meas[0], res.qd_meas[0], res.tau[0])
    plot_trajectory(res, outputs.path("trajectory.png"))
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
    out = Path(args.out)
    print(
        f"wrote {out / 'trajectory.npz'} (all trials), {out / 'trajectory.csv'} (trial 0, "
        f"measured), {out / 'trajectory.png'}"
    )
    return 0


def _cmd_reproduce(args: argparse.Namespace) -> int:
    from adaptive_dd.identification.reproduce import TAU_F_GRID
    from adaptive_dd.outputs import OutputSet

    tau_f = tuple(args.tau_f) if args.tau_f else TAU_F_GRID
    outputs = OutputSet(args.out, extras=(args.json,) if args.json else ())
    with outputs:
        written = _reproduce(args, tau_f, outputs)
    if written:
        print("wrote " + ", ".join(str(w) for w in written))
    return 0


def _reproduce(args: argparse.Namespace, tau_f: tuple, outputs) -> list[Path]:
    from adaptive_dd.identification.reproduce import (
        format_summary,
        format_table,
        model_responses,
        run_reproduce,
    )
    from adaptive_dd.plant.parameters import TABLE1_SIGMA
    from adaptive_dd.plotting import plot_estimates, plot_model_response

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
            plot_estimates(t, res.theta[key][i], TABLE1_SIGMA, outputs.path(name), title)
            written.append(out / name)
    models = {}
    for key, i, label in ((fig5, i5, "paper M2"), (ours, i_best, "exact M2")):
        if key in res.theta:
            models[f"{label}, tau_f = {tau_f[i]}"] = res.theta[key][i][:, -1].mean(axis=0)
    if models:
        arm_q, qs = model_responses(models, res.sim.t.size)
        plot_model_response(
            t,
            arm_q,
            qs,
            outputs.path("fig7_model_response.png"),
            "Arm and identified models, same torque (Table 2)",
        )
        written.append(out / "fig7_model_response.png")
        for k, q in qs.items():
            rms = np.sqrt(((q - arm_q) ** 2).mean(axis=0))
            print(f"Fig. 7: rms difference arm - model ({k}): {rms.round(4)} rad")
    if args.json:
        res.write_json(outputs.extra(args.json))
        written.append(Path(args.json))
    return written


def _cmd_identify(args: argparse.Namespace) -> int:
    from adaptive_dd.errors import DataError
    from adaptive_dd.identification.estimators import estimate
    from adaptive_dd.io import MIN_EQUATIONS, check_identifiable, read_recording
    from adaptive_dd.outputs import OutputSet

    rec = read_recording(args.data)
    if args.method == "M2" and rec.qd is None:
        raise DataError(f"{args.data}: method M2 needs columns qd1, qd2 (use --method M1 for position only)")
    check_identifiable(rec, args.tau_f)
    outputs = OutputSet(args.out)
    with outputs:
        return _identify(args, rec, outputs, estimate, MIN_EQUATIONS)


def _identify(args, rec, outputs, estimate, min_equations: int) -> int:
    from adaptive_dd.errors import DataError
    from adaptive_dd.plant.parameters import SIGMA_NAMES
    from adaptive_dd.plotting import plot_estimates

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
    if int(res.n_used) < min_equations:
        raise DataError(
            f"{rec.source}: only {int(res.n_used)} usable equations (the arm barely moves or the "
            f"record is short); identify needs at least {min_equations}"
        )
    print(f"{'param':>6} {'estimate':>12} {'std':>10}")
    for k, name in enumerate(SIGMA_NAMES):
        print(f"{name:>6} {res.final[k]:12.5g} {res.std[k]:10.2g}")
    if not np.all(np.isfinite(res.final)):
        print(
            "warning: the estimate is not finite: the record does not excite the arm enough", file=sys.stderr
        )
        return 1
    ref = np.full(7, np.nan) if args.true is None else np.asarray(args.true, float)
    plot_estimates(
        rec.t,
        res.theta[None],
        np.where(np.isfinite(ref), ref, res.final),
        outputs.path("convergence.png"),
        f"{Path(args.data).name}: {args.estimator} ({args.method})",
    )
    print(f"wrote {Path(args.out) / 'convergence.png'}")
    return 0


def _cmd_benchmark(args: argparse.Namespace) -> int:
    import dataclasses

    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.outputs import OutputSet

    sc = load_scenario(args.scenario)
    if args.seeds is not None:
        sc = dataclasses.replace(sc, seeds=args.seeds)
    if sc.estimate().large:
        print(f"estimate: {sc.estimate()}", file=sys.stderr)
    outputs = OutputSet(args.out, extras=(args.json,) if args.json else ())
    with outputs:
        written = _benchmark(args, sc, outputs)
    print("wrote " + ", ".join(str(w) for w in written))
    return 0


def _benchmark(args: argparse.Namespace, sc, outputs) -> list[Path]:
    from adaptive_dd.benchmark.metrics import compute_metrics
    from adaptive_dd.benchmark.report import format_report, write_csv, write_json
    from adaptive_dd.benchmark.runner import run_benchmark
    from adaptive_dd.plotting import plot_benchmark_estimates, plot_tracking_errors

    res = run_benchmark(sc, progress=not args.no_progress)
    metrics = compute_metrics(res)
    print(format_report(metrics, res))
    out = Path(args.out)
    write_csv(metrics, outputs.path("metrics.csv"))
    write_json(metrics, outputs.extra(args.json) if args.json else outputs.path("metrics.json"))
    plot_tracking_errors(res, outputs.path("tracking_error.png"))
    written = [out / "metrics.csv", Path(args.json or out / "metrics.json"), out / "tracking_error.png"]
    if any(r.sigma_hat is not None for r in res.runs.values()):
        plot_benchmark_estimates(res, outputs.path("estimates.png"))
        written.append(out / "estimates.png")
    return written


def _cmd_validate(args: argparse.Namespace) -> int:
    from adaptive_dd.benchmark.scenario import format_scenario, load_scenario

    print(format_scenario(load_scenario(args.scenario)))
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The ``adaptive-dd`` parser (no abbreviations of options; checked numeric options)."""
    from adaptive_dd import __version__

    p = argparse.ArgumentParser(prog="adaptive-dd", description=__doc__, allow_abbrev=False)
    p.add_argument("--version", action="version", version=f"adaptive-dd {__version__}")
    p.add_argument("--debug", action="store_true", help="show the traceback of an internal error")
    sub = p.add_subparsers(dest="command", required=True)

    c = _sub(sub, "check", help="cross-check the dynamics against Pinocchio")
    c.add_argument("--payload", type=_MASS, default=0.0, metavar="KG", help="tip disk mass [kg]")
    c.add_argument("--radius", type=_RADIUS, default=0.05, help="tip disk radius [m]")
    c.add_argument("--states", type=_number(int, 1, 100_000), default=200, help="number of random states")
    c.add_argument("--seed", type=_SEED, default=0)
    c.set_defaults(func=_cmd_check)

    s = _sub(sub, "simulate", help="simulate the paper's open-loop Table 2 experiment")
    s.add_argument(
        "--duration", type=_number(float, 0.0, math.inf, lo_open=True), default=10.0, help="[s] (default 10)"
    )
    s.add_argument("--sample-period", type=_PERIOD, default=1e-3, help="T [s] (default 0.001)")
    s.add_argument("--substeps", type=_SUBSTEPS, default=2, help="RK4 steps per sample")
    s.add_argument("--seeds", type=_SEEDS, default=1, help="number of trials (noise seeds)")
    s.add_argument("--seed", type=_SEED, default=0, help="base seed")
    s.add_argument("--payload", type=_MASS, default=0.0, metavar="KG")
    s.add_argument("--radius", type=_RADIUS, default=0.05)
    s.add_argument("--no-noise", action="store_true", help="noise-free sensors")
    s.add_argument("--no-quantize", action="store_true", help="no encoder or D/A quantization")
    s.add_argument("--no-saturate", action="store_true", help="no torque saturation")
    s.add_argument("--out", default="results/simulate", help="output folder")
    s.set_defaults(func=_cmd_simulate)

    from adaptive_dd.identification.estimators import ESTIMATORS
    from adaptive_dd.identification.reproduce import DEFAULT_ESTIMATORS

    r = _sub(sub, "reproduce", help="reproduce Tables 3 and 5 of the paper (and ours beside)")
    r.add_argument("--seeds", type=_SEEDS, default=10, help="Monte-Carlo seeds (default 10)")
    r.add_argument("--seed", type=_SEED, default=0, help="base seed")
    r.add_argument(
        "--tau-f",
        type=_number(float, 0.0, 1.0, lo_open=True),
        nargs="+",
        help="filter time constants [s] (default: the paper's)",
    )
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

    i = _sub(sub, "identify", help="estimate sigma from a recorded experiment (CSV)")
    i.add_argument("data", help="CSV with header t,q1,q2,qd1,qd2,tau1,tau2 (qd optional for M1)")
    i.add_argument("--estimator", default="exact", choices=ESTIMATORS)
    i.add_argument("--method", default="M2", choices=("M1", "M2"))
    i.add_argument("--split", default="15", choices=("15", "16", "full"), help="split of 'paper'")
    i.add_argument("--tau-f", type=_POS, default=0.02, help="filter time constant [s]")
    i.add_argument(
        "--true", type=_number(float, -1e6, 1e6), nargs=7, metavar="S", help="true sigma, to mark on the plot"
    )
    i.add_argument("--out", default="results/identify")
    i.set_defaults(func=_cmd_identify)

    b = _sub(sub, "benchmark", help="payload-swap tracking benchmark (the main job)")
    b.add_argument("scenario", nargs="?", help="scenario TOML (default: the shipped payload_swap)")
    b.add_argument("--out", default="results/benchmark", help="folder for CSV, JSON and figures")
    b.add_argument("--json", metavar="PATH", help="where to write the JSON (default OUT/metrics.json)")
    b.add_argument("--seeds", type=_SEEDS, help="override the scenario's number of seeds")
    b.add_argument("--no-progress", action="store_true")
    b.set_defaults(func=_cmd_benchmark)

    v = _sub(sub, "validate", help="check a scenario and print it resolved (defaults marked)")
    v.add_argument("scenario", nargs="?", help="scenario TOML (default: the shipped payload_swap)")
    v.set_defaults(func=_cmd_validate)
    return p


def _is_user_error(exc: BaseException) -> bool:
    """Our errors, file-system errors, and plain ValueErrors raised by adaptive_dd's own code."""
    from adaptive_dd.errors import DataError, ScenarioError, SignalError

    if isinstance(exc, ParameterError | ScenarioError | DataError | SignalError | OutputError | OSError):
        return True
    if type(exc) is ValueError and exc.__traceback__ is not None:
        last = traceback.extract_tb(exc.__traceback__)[-1].filename
        return Path(last).resolve().is_relative_to(Path(__file__).resolve().parent)
    return False


def _user_message(exc: BaseException) -> str:
    if isinstance(exc, OSError):
        where = f"{exc.filename}: " if exc.filename else ""
        return f"{where}{exc.strerror or exc}"
    return str(exc)


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the exit code (0 ok, 1 failed check, 2 user error, 3 internal error)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except KeyboardInterrupt:
        print(f"adaptive-dd {args.command}: interrupted; outputs left as before", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as exc:
        if _is_user_error(exc):  # our errors name what was wrong and where
            print(f"adaptive-dd {args.command}: error: {_user_message(exc)}", file=sys.stderr)
            return EXIT_USAGE
        if args.debug:
            traceback.print_exc()
        print(
            f"adaptive-dd {args.command}: internal error: {type(exc).__name__}: {exc}; please report it "
            f"at {ISSUE_TRACKER}, rerun with --debug for the traceback",
            file=sys.stderr,
        )
        return EXIT_INTERNAL


if __name__ == "__main__":
    sys.exit(main())
