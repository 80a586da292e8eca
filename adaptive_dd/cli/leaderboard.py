"""``adaptive-dd leaderboard``: controllers on scenarios, each ranked per seed against its floor.

Writes ``leaderboard.csv`` (one row per scenario, controller and segment), ``leaderboard.json``
(the rows and every column's unit and meaning) and ``leaderboard.png`` (the mean ratio to the
floor per controller and scenario segment) into ``--out``
(:func:`adaptive_dd.arena.leaderboard`).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from adaptive_dd.cli._common import SEED, SEEDS, add_command

__all__ = ["add_parser", "run"]


def add_parser(sub) -> None:
    """The options of ``leaderboard``."""
    p = add_command(sub, "leaderboard", help="rank controllers on scenarios against each one's floor")
    p.add_argument(
        "scenarios", nargs="*", metavar="SCENARIO", help="scenario TOMLs (default: the shipped N-joint ones)"
    )
    p.add_argument(
        "--scenarios", dest="scenario_list", nargs="+", metavar="SCENARIO", help="the same, as an option"
    )
    p.add_argument(
        "--controllers", nargs="+", metavar="NAME", help="built-in names (default: the arena's list)"
    )
    p.add_argument(
        "--plugin",
        action="append",
        default=[],
        metavar="MODULE:CLASS",
        help="a controller of your own to rank with the others (repeatable); its floor runs beside it",
    )
    p.add_argument("--seeds", type=SEEDS, default=3, help="seeds per scenario (default 3)")
    p.add_argument("--bootstrap-seed", type=SEED, default=0, help="seed of the bootstrap intervals")
    p.add_argument("--out", default="results/leaderboard", help="folder for the CSV, JSON and figure")
    p.add_argument("--no-progress", action="store_true")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the leaderboard and write its three files."""
    import numpy as np

    from adaptive_dd.arena.leaderboard import COLUMNS, DEFAULT_CONTROLLERS, leaderboard
    from adaptive_dd.outputs import check_output_dir

    scenarios = [*args.scenarios, *(args.scenario_list or [])] or None
    controllers = [*(args.controllers or DEFAULT_CONTROLLERS), *args.plugin]
    out = check_output_dir(Path(args.out))
    df = leaderboard(
        scenarios, controllers, seeds=args.seeds, rng=np.random.default_rng(args.bootstrap_seed),
        progress=not args.no_progress,
    )  # fmt: skip
    csv, js, png = out / "leaderboard.csv", out / "leaderboard.json", out / "leaderboard.png"
    df.to_csv(csv, index=False, float_format="%.6g")
    doc = {
        "columns": {k: {"unit": u, "meaning": m} for k, (u, m) in COLUMNS.items()},
        "seeds": args.seeds,
        "rows": json.loads(df.to_json(orient="records")),
    }
    js.write_text(json.dumps(doc, indent=1), encoding="utf-8")
    from adaptive_dd.arena.plot import plot_leaderboard

    plot_leaderboard(df).savefig(png, dpi=120)
    _print(df)
    for p in (csv, js, png):
        print(f"wrote {p}")
    return 0


def _print(df) -> None:
    """The ratio columns per scenario, controller and segment, as a plain table."""
    cols = ["scenario", "controller", "floor", "segment", "payload_kg", "ratio_mean", "ratio_ci95_low",
            "ratio_ci95_high", "ratio_p90", "ratio_max", "failures", "saturation_pct"]  # fmt: skip
    with __import__("pandas").option_context("display.width", 200, "display.max_rows", 1000):
        print(df[cols].to_string(index=False, float_format=lambda x: f"{x:.3f}"))
