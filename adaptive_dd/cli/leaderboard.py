"""``adaptive-dd leaderboard``: controllers on scenarios, each ranked per seed against its floor.

Writes ``leaderboard.csv`` (one row per scenario, controller and segment), ``leaderboard.json``
(the rows and every column's unit and meaning), ``leaderboard.png`` (the mean ratio to the
floor per controller and scenario segment; the population pooled, not each arm) and
``leaderboard.tex`` (the table for a paper, :mod:`adaptive_dd.arena.latex`) into ``--out``
(:func:`adaptive_dd.arena.leaderboard`), and prints per scenario segment the controller with the
lowest RMS error (every controller of a seed meets the same robot and noise), and the seconds
its runs spent compiling (numba, cold cache) apart from those spent running.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from adaptive_dd.cli._common import NO_PROGRESS_HELP, SEED, SEEDS, add_command, number, show_progress
from adaptive_dd.errors import ParameterError

__all__ = ["add_parser", "run"]

ARMS = number(int, 0, 10_000)
WORKERS = number(int, 1, 256)


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
        "--controllers",
        nargs="+",
        metavar="NAME",
        help="built-in names, plug-ins' MODULE:CLASS, or variants every given scenario (and with --arms "
        "the template) defines (default: the arena's list)",
    )
    p.add_argument(
        "--plugin",
        action="append",
        default=[],
        metavar="MODULE:CLASS",
        help="a controller of your own to rank with the others (repeatable); its floor runs beside it",
    )
    p.add_argument("--seeds", type=SEEDS, default=3, help="seeds per scenario and per drawn arm (default 3)")
    p.add_argument(
        "--arms",
        type=ARMS,
        default=0,
        metavar="N",
        help="also N drawn arms nobody tuned for (random:FIRST ..), each a row, pooled as the population",
    )
    p.add_argument("--first-arm", type=SEED, default=0, metavar="SEED", help="seed of the first drawn arm")
    p.add_argument(
        "--template",
        default=None,
        metavar="FILE",
        help="the drawn arms' scenario template (default benchmarks/scenarios/population.toml)",
    )
    p.add_argument(
        "--no-scenarios",
        action="store_true",
        help="the drawn arms alone (with --arms), not the shipped scenarios",
    )
    p.add_argument(
        "--workers",
        type=WORKERS,
        default=1,
        metavar="N",
        help="processes that run the scenarios and drawn arms (one per core; the table is the same)",
    )
    p.add_argument("--bootstrap-seed", type=SEED, default=0, help="seed of the bootstrap intervals")
    p.add_argument("--out", default="results/leaderboard", help="folder for the CSV, JSON and figure")
    p.add_argument("--no-progress", action="store_true", help=NO_PROGRESS_HELP)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the leaderboard and write its four files."""
    from adaptive_dd.arena.leaderboard import (
        COLUMNS,
        DEFAULT_CONTROLLERS,
        _template,
        leaderboard,
        shipped_scenarios,
    )
    from adaptive_dd.outputs import check_output_dir

    for opt in ("--template", "--first-arm"):
        if opt in getattr(args, "given", ()) and not args.arms:
            raise ParameterError(f"{opt}: applies to the drawn arms of --arms N; give --arms N too")
    scenarios = [*args.scenarios, *(args.scenario_list or [])] or None
    for given in args.scenarios:  # --plugin a:A b:B reads b:B as a SCENARIO
        if ":" in given and not given.endswith(".toml") and not Path(given).exists():
            raise ParameterError(
                f"SCENARIO {given!r}: no such file, and it reads as a plug-in (MODULE:CLASS): --plugin takes "
                "one value; repeat it for each plug-in (--plugin a:A --plugin b:B)"
            )
    if args.no_scenarios:
        if scenarios or not args.arms:
            raise ParameterError("--no-scenarios: runs the drawn arms alone; give --arms N and no SCENARIO")
        scenarios = []
    from adaptive_dd.controllers import CONTROLLERS

    sources = _variant_sources(scenarios, args)  # the files whose tables the ranked runs read
    variants = _variants(sources)  # {name: files defining it}: a scenario's own law with settings
    for name, files in variants.items():
        if name not in (args.controllers or ()):
            print(
                f"note: {', '.join(files)} define(s) the variant {name!r}, not ranked: the leaderboard "
                f"ranks --controllers and --plugin (add --controllers ... {name} to rank it)",
                file=sys.stderr,
            )
    for name in args.controllers or ():  # named by the option, not by the scenario it would fail on
        everywhere = bool(sources) and len(variants.get(name, ())) == len(sources)
        if ":" not in name and name not in CONTROLLERS and not everywhere:
            lacking = [str(path) for _, path in sources if path not in variants.get(name, ())]
            where = (
                f": {', '.join(lacking)} do(es) not define it"
                + ("; the drawn arms' template is --template FILE" if args.arms else "")
                if name in variants
                else ""
            )
            from adaptive_dd.benchmark.key_hints import did_you_mean

            raise ParameterError(
                f"--controllers: unknown controller {name!r}"
                + ("" if name in variants else did_you_mean(name, [*CONTROLLERS, *variants]))
                + f"{where}; built-ins: {', '.join(CONTROLLERS)}, a plug-in's 'package.module:Class' (or "
                "--plugin), or a variant every given scenario (and with --arms the template) defines "
                '([controllers.NAME] law = "...")'
            )
    for name in args.plugin:
        if ":" not in name:
            raise ParameterError(f"--plugin {name}: expects MODULE:CLASS (e.g. my_laws:MyLaw)")
    controllers = [*(args.controllers or DEFAULT_CONTROLLERS), *args.plugin]
    out = check_output_dir(Path(args.out))
    if args.arms and scenarios:
        _say_tables_not_on_the_arms(scenarios, controllers, args.template)
    df = leaderboard(
        scenarios, controllers, seeds=args.seeds, rng=args.bootstrap_seed,
        progress=show_progress(args), arms=args.arms, template=args.template, first_arm=args.first_arm,
        workers=args.workers,
    )  # fmt: skip
    csv, js, png = out / "leaderboard.csv", out / "leaderboard.json", out / "leaderboard.png"
    df.to_csv(csv, index=False, float_format="%.6g")
    from adaptive_dd.benchmark.preflight import GAINS_APART

    gains = df[df["floor_note"].str.contains(GAINS_APART, na=False) & (df["kind"] != "population")]
    for (sc, c), g in gains.groupby(["scenario", "controller"], sort=False):  # (said in floor_note too)
        print(f"warning: {sc}: {c}: {g['floor_note'].iloc[0]}", file=sys.stderr)
    import shlex

    command = shlex.join(["adaptive-dd", *getattr(args, "argv", ("leaderboard",))])
    from adaptive_dd.benchmark.provenance import code_provenance

    doc = {
        "command": command,  # as typed: run it from the same folder to reproduce the table
        "provenance": code_provenance(),  # version, git commit: the code the table came from
        "scenarios": scenarios if scenarios is not None else [str(p) for p in shipped_scenarios()],
        "controllers": controllers,
        "template": _template(args.template)[1] if args.arms else None,  # the one the arms were drawn on
        "bootstrap_seed": args.bootstrap_seed,
        "columns": {k: {"unit": u, "meaning": m} for k, (u, m) in COLUMNS.items()},
        "seeds": args.seeds,
        "arms": args.arms,
        "first_arm": args.first_arm,
        "rows": json.loads(df.to_json(orient="records")),
        "flags": df.attrs.get("flags", []),
    }
    js.write_text(json.dumps(doc, indent=1), encoding="utf-8")
    from adaptive_dd.arena.plot import plot_leaderboard

    plot_leaderboard(df[df["kind"] != "arm"]).savefig(png, dpi=120)
    from adaptive_dd.arena.latex import write_latex
    from adaptive_dd.arena.page import read_table

    tex = write_latex(read_table(csv), out / "leaderboard.tex", command)  # the CSV's figures, as the docs
    _print(df[df["kind"] != "arm"])
    _print_winners(df[df["kind"] != "arm"])
    _print_alarms(df[df["kind"] != "arm"])
    _print_flags(df.attrs.get("flags", []))
    for p in (csv, js, png, tex):
        print(f"wrote {p}")
    print(
        f"time: {df.attrs['compile_seconds']:.1f} s compiling (numba; the built-ins' cached, 0 when "
        f"warm{'; a compiled plug-in: its loop compiled once, then cached' if args.plugin else ''}), "
        f"{df.attrs['run_seconds']:.1f} s running (each summed over the workers' runs)"
    )
    return 0


def _variant_sources(scenarios, args) -> list:
    """The scenario files a ranked run reads its tables from: the given scenarios (none: the shipped
    ones, which define no variant), and with ``--arms`` the drawn arms' template."""
    from adaptive_dd.arena.leaderboard import _template, shipped_scenarios

    out = [(None, str(p)) for p in (shipped_scenarios() if scenarios is None else scenarios)]
    if args.arms:
        out.append(_template(args.template))
    return out


def _variants(sources) -> dict[str, list[str]]:
    """The variants (entries whose table names a ``law``) of the given ``(data or None, path)``
    scenario files, by name: the files that define each."""
    from adaptive_dd.benchmark.scenario import read_toml, scenario_file

    out: dict[str, list[str]] = {}
    for data, path in sources:
        data = read_toml(scenario_file(path)) if data is None else data
        run = data.get("run") if isinstance(data.get("run"), dict) else {}
        listed = run.get("controllers") if isinstance(run.get("controllers"), list) else []
        tables = data.get("controllers") if isinstance(data.get("controllers"), dict) else {}
        for c in listed:  # (a malformed file: none here; its own check names it when it is loaded)
            if isinstance(c, str) and isinstance(tables.get(c), dict) and "law" in tables[c]:
                out.setdefault(c, []).append(path)
    return out


def _say_tables_not_on_the_arms(scenarios, controllers, template) -> None:
    """A note per given scenario whose ``[controllers.NAME]`` table of a ranked controller is not the
    template's: the drawn arms run the template's tables, so the law runs there with other settings
    (and under another name, with a ``label``): two rows, not one."""
    from adaptive_dd.arena.leaderboard import _template
    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.controllers.plugins import table_name

    data, src = _template(template)
    theirs = data.get("controllers") or {}
    for path in scenarios:
        sc = load_scenario(path)
        for c in controllers:
            mine = sc.options(table_name(c))
            if mine and mine != theirs.get(table_name(c), {}):
                print(
                    f"note: {sc.source}'s [controllers.{table_name(c)}] ({', '.join(sorted(mine))}) sets "
                    f"{c} for that scenario only; the drawn arms run {src}'s tables: two rows (for one, "
                    f"copy the template, add the same table and {c!r} to its run.controllers, and pass "
                    "the copy as --template)",
                    file=sys.stderr,
                )


def _print(df) -> None:
    """The ratio columns per scenario, controller and segment, as a plain table."""
    cols = ["scenario", "controller", "floor", "segment", "payload_kg", "ratio_mean", "ratio_ci95_low",
            "ratio_ci95_high", "ratio_p90", "ratio_max", "failures", "saturated_seeds", "lost_seeds",
            "saturation_pct", "rms_error_mrad", "false_alarm_seeds", "missed_swaps",
            "recovery_median_s", "recovery_never", "ee_position_rms_mm"]  # fmt: skip
    with __import__("pandas").option_context("display.width", 200, "display.max_rows", 1000):
        print(df[cols].to_string(index=False, float_format=lambda x: f"{x:.3f}"))


def _print_winners(df) -> None:
    """Per scenario segment, the law with the lowest mean RMS error among the contenders (the
    oracles and laws told the true model left out), and the runner-up."""
    from adaptive_dd.arena.leaderboard import contenders

    ranked = df[contenders(df) & (df["failures"] == 0)]
    if ranked.empty:  # only oracles asked for, or every law failed a trial: nothing to list
        print("lowest RMS error per segment: no law to rank (oracles and laws with a failed trial left out)")
        return
    print("lowest RMS error per segment (oracles left out; laws with a failed trial left out):")
    for (sc, seg), g in ranked.groupby(["scenario", "segment"], sort=False):
        g = g.sort_values("rms_error_mrad")
        best = [f"{r.controller} {r.rms_error_mrad:.3g} mrad" for r in g.head(2).itertuples()]
        print(f"  {sc}:{seg} ({g['payload_kg'].iloc[0]:.3g} kg): " + ", then ".join(best))


def _print_alarms(df) -> None:
    """Per scenario and law with a change detector: its false alarms and missed swaps over the
    segments (a trial with false alarms in two segments counts in both, so the trials with one
    are at most the sum)."""
    from adaptive_dd.arena.leaderboard import alarm_totals

    det = df[df["false_alarm_seeds"].notna()]
    if det.empty:
        return
    print(
        "change detectors (an alarm with no swap in the 0.3 s before is false; a swap with no alarm "
        "in the 0.3 s after, missed):"
    )
    for (sc, ctrl), g in det.groupby(["scenario", "controller"], sort=False):
        fa, trials, missed, swaps = alarm_totals(g)
        print(
            f"  {sc} {ctrl}: false alarms in {fa} of {trials * len(g)} seed-segments (trials with one: at "
            f"most {fa} of {trials}, {100 * fa / max(trials, 1):.1f} %); missed swaps {missed} of {swaps}"
        )


def _print_flags(flags: list[dict], shown: int = 10) -> None:
    """How many trials were flagged, by first flag, and the first ``shown`` of them with their
    reasons (every one in leaderboard.json's ``flags``)."""
    if not flags:
        print(
            "flagged trials: none (no saturation beyond 1 % of a segment, no error beyond 0.2 rad, "
            "no failure)"
        )
        return
    from collections import Counter

    count = Counter(f["flag"] for f in flags)
    print(f"flagged trials: {len(flags)} (" + ", ".join(f"{k}: {v}" for k, v in sorted(count.items()))
          + "; every one with its reasons in leaderboard.json's flags)")  # fmt: skip
    for f in flags[:shown]:
        print(f"  {f['scenario']} {f['controller']} seed {f['seed']}: " + "; ".join(f["reasons"]))
