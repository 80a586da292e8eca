"""``adaptive-dd reproduce``: Tables 3 and 5 of the paper, and ours beside.

Genuinely the paper's arm: the experiment is the paper's (the SICE arm, Table 2 torques), so
the command takes no ``--arm``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from adaptive_dd.cli._common import NO_PROGRESS_HELP, SEED, add_command, number, show_progress

__all__ = ["add_parser", "run"]

_FIG5 = ("M2", "15", "paper")
_OURS = ("M2", "full", "exact")


def add_parser(sub) -> None:
    """The options of ``reproduce``."""
    from adaptive_dd.identification.estimators import ESTIMATORS
    from adaptive_dd.identification.reproduce import DEFAULT_ESTIMATORS, EXTRA_ESTIMATORS

    r = add_command(sub, "reproduce", help="reproduce Tables 3 and 5 of the paper (and ours beside)")
    r.add_argument(
        "--seeds",
        type=number(int, 2, 10_000),
        default=10,
        help="Monte-Carlo seeds, at least 2: the tables give the std over them (default 10)",
    )
    r.add_argument("--seed", type=SEED, default=0, help="base seed")
    r.add_argument(
        "--tau-f",
        type=number(float, 0.0, 1.0, lo_open=True),
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
    r.add_argument("--no-progress", action="store_true", help=NO_PROGRESS_HELP)
    r.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the Monte-Carlo, print the tables, write the figures (and the JSON)."""
    from adaptive_dd.identification.reproduce import TAU_F_GRID, run_reproduce
    from adaptive_dd.outputs import OutputSet

    tau_f = tuple(args.tau_f) if args.tau_f else TAU_F_GRID
    outputs = OutputSet(args.out, extras=(args.json,) if args.json else ())
    with outputs:
        res = run_reproduce(
            seeds=args.seeds,
            seed=args.seed,
            tau_f=tau_f,
            estimators=tuple(args.estimators),
            progress=show_progress(args),
            keep_theta=(_FIG5, _OURS),
            noise=not args.no_noise,
            extra_estimators=tuple(args.extra_estimators),
        )
        _print_tables(args, res)
        written = _figures(res, tau_f, outputs)
        if args.json:
            res.write_json(outputs.extra(args.json))
            written.append(Path(args.json))
    if written:
        print("wrote " + ", ".join(str(w) for w in written))
    return 0


def _print_tables(args: argparse.Namespace, res) -> None:
    from adaptive_dd.identification.reproduce import (
        format_bounds,
        format_comparison,
        format_summary,
        format_table,
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
            print(
                f"{table}: ours / paper = ratio (mean error [%] over {args.seeds} seeds; "
                "why they differ: docs/results.md, 'Tables 3 and 5 against the paper')"
            )
            print(format_comparison(res, method) + "\n")
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


def _figures(res, tau_f: tuple, outputs) -> list:
    """Fig. 5-like estimate histories and the Fig. 7 model responses; prints Fig. 7's rms."""
    from adaptive_dd.plant.two_link import ClosedFormTwoLink
    from adaptive_dd.plotting import plot_estimates

    out = outputs.folder
    written = []
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
            plot_estimates(
                res.sim.t, res.theta[key][i], ClosedFormTwoLink.sice().sigma, outputs.path(name), title
            )
            written.append(out / name)
            models[f"{short}, tau_f = {tau_f[i]}"] = res.theta[key][i][:, -1].mean(axis=0)
    if models:
        written.append(_fig7(res, models, outputs))
    return written


def _fig7(res, models: dict, outputs) -> Path:
    """The Fig. 7 model responses to the same torque; prints each model's rms difference."""
    from adaptive_dd.identification.reproduce import model_responses
    from adaptive_dd.plotting import plot_model_response

    t = res.sim.t
    arm_q, qs = model_responses(models, t.size)
    plot_model_response(
        t,
        arm_q,
        qs,
        outputs.path("fig7_model_response.png"),
        "ClosedFormTwoLink and identified models, same torque (Table 2)",
    )
    for k, q in qs.items():
        rms = np.sqrt(((q - arm_q) ** 2).mean(axis=0))
        print(f"Fig. 7: rms difference arm - model ({k}): {rms.round(4)} rad")
    return outputs.folder / "fig7_model_response.png"
