"""``adaptive-dd benchmark [SCENARIO]``: the payload-swap tracking benchmark, on any arm.

Writes the metrics (CSV and JSON), the per-seed table, the tracking-error and estimate
figures, one panel per joint for an arm of more than two joints, and each seed's drawn plant
where the scenario's plant is not its model.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import threading
from pathlib import Path

from adaptive_dd.cli._common import NO_PROGRESS_HELP, SEED, SEEDS, add_command, number, show_progress

__all__ = ["add_parser", "run"]


def add_parser(sub) -> None:
    """The options of ``benchmark``."""
    b = add_command(sub, "benchmark", help="payload-swap tracking benchmark (the main job)")
    b.add_argument("scenario", nargs="?", help="scenario TOML (default: the shipped payload_swap)")
    b.add_argument("--out", default="results/benchmark", help="folder for CSV, JSON and figures")
    b.add_argument("--json", metavar="PATH", help="where to write the JSON (default OUT/metrics.json)")
    b.add_argument("--seeds", type=SEEDS, help="override the scenario's number of seeds")
    b.add_argument(
        "--seed",
        type=SEED,
        help="override the scenario's base seed (run.seed): trial i's noise is seeded by (seed, i); "
        "per_seed.csv's seed column is the index i, metrics.json's provenance.seed the base "
        "(population.json's seed with --arms)",
    )
    b.add_argument(
        "--controllers",
        nargs="+",
        metavar="NAME",
        help="run only these of the scenario's controllers, as run.controllers or the results name them "
        "(a plug-in by its label); each one's floor is added: ratios need it",
    )
    b.add_argument(
        "--figure-formats",
        nargs="+",
        default=["png"],
        choices=("png", "pdf", "svg"),
        help="formats of the figures (default png)",
    )
    b.add_argument(
        "--arms",
        type=number(int, 1, 10_000),
        metavar="N",
        help="run the scenario's payload schedule over N drawn arms (random:SEED, SEED from --first-arm; "
        "masses scaled to each arm's capacity): per arm and pooled",
    )
    b.add_argument(
        "--first-arm", type=number(int, 0, 2**62), default=0, metavar="SEED", help="seed of the first arm"
    )
    b.add_argument("--draw-swaps", action="store_true", help="with --arms: draw each arm's swap times too")
    b.add_argument("--no-progress", action="store_true", help=NO_PROGRESS_HELP)
    b.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Load the scenario, run it, print the report, write the outputs."""
    import dataclasses

    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.errors import ParameterError
    from adaptive_dd.outputs import OutputSet

    if args.arms is not None:
        from adaptive_dd.cli._population import run_arms

        return run_arms(args, only_controllers, with_floors)
    for opt in ("--draw-swaps", "--first-arm"):
        if opt in getattr(args, "given", ()):
            raise ParameterError(f"{opt}: applies to the drawn arms of --arms N; give --arms N too")
    sc = load_scenario(args.scenario)
    if args.seeds is not None:
        sc = dataclasses.replace(sc, seeds=args.seeds)
    if args.seed is not None:
        sc = dataclasses.replace(sc, seed=args.seed)
    if args.controllers:
        sc = sc.with_controllers(only_controllers(sc, args.controllers))
    sc = with_floors(sc)
    estimate = sc.estimate()
    if estimate.large:
        print(f"estimate: {estimate}", file=sys.stderr)
    for line in limit_warnings(sc):
        print(line, file=sys.stderr)
    outputs = OutputSet(args.out, extras=(args.json,) if args.json else ())
    with outputs:
        written, res = _benchmark(args, sc, outputs)
    print("wrote " + ", ".join(str(w) for w in written))
    if res.runs and all(run.error or all(run.failed) for run in res.runs.values()):
        print(
            "adaptive-dd benchmark: every trial of every controller failed (the report's failed trials "
            "say why and when): no result to compare",
            file=sys.stderr,
        )
        return 1
    return 0


def _benchmark(args: argparse.Namespace, sc, outputs) -> tuple[list[Path], object]:
    from adaptive_dd._numba_cache import announce_compilation
    from adaptive_dd.benchmark.metrics import compute_metrics, release_error_norm
    from adaptive_dd.benchmark.report import format_report, write_csv, write_json
    from adaptive_dd.benchmark.runner import run_benchmark

    if args.figure_formats:  # matplotlib's import (about 0.4 s) overlaps the trials, which free the GIL
        threading.Thread(target=importlib.import_module, args=("matplotlib.pyplot",), daemon=True).start()
    # a cold cache compiles first (the kernels of the path the run takes: the closed forms' or the general)
    with announce_compilation(sc.closed_forms or sc.arm, source=sc.source) as compiling:
        res = run_benchmark(sc, progress=show_progress(args), on_run=release_error_norm)
        compiling.join()  # the report's kernels, compiled meanwhile by a second process
        metrics = compute_metrics(res)
    print(format_report(metrics, res))
    if "excitation_report" in res.cache:  # [run] excite: what the identification found
        print(res.cache["excitation_report"].summary())
    out = Path(args.out)
    write_csv(metrics, outputs.path("metrics.csv"))
    write_json(metrics, outputs.extra(args.json) if args.json else outputs.path("metrics.json"))
    written = [out / "metrics.csv", Path(args.json or out / "metrics.json")]
    written += _figures(res, sc, outputs, out, tuple(args.figure_formats))
    from adaptive_dd.benchmark.results import write_per_seed_csv

    write_per_seed_csv(res, outputs.path("per_seed.csv"))
    written.append(out / "per_seed.csv")
    if res.plant is not None:  # the plant is not the model: each seed's drawn plant
        from adaptive_dd.benchmark.results import plant_frame

        plant_frame(res).to_csv(outputs.path("plant.csv"), index=False)
        written.append(out / "plant.csv")
    return written, res


def _figures(res, sc, outputs, out: Path, fmts: tuple) -> list[Path]:
    from adaptive_dd.plotting import plot_benchmark_estimates, plot_tracking_errors

    written: list[Path] = []

    def announce(stem: str) -> Path:
        """Every format's file announced to ``outputs``; the path the plot is given (its suffix is
        replaced per format)."""
        staged = [outputs.path(f"{stem}.{f}") for f in fmts]
        written.extend(out / f"{stem}.{f}" for f in fmts)
        return staged[0]

    plot_tracking_errors(res, announce("tracking_error"), formats=fmts)
    if any(r.sigma_hat is not None for r in res.runs.values()):
        plot_benchmark_estimates(res, announce("estimates"), formats=fmts)
    if sc.n_joints != 2:  # N-joint arms: one panel per joint as well
        from adaptive_dd.plotting import plot_joint_errors

        plot_joint_errors(res, announce("joint_errors"), formats=fmts)
    return written


def limit_warnings(sc) -> list[str]:
    """One ``warning:`` line per place the reference leaves a joint's position or velocity limits
    (``adaptive-dd validate`` reports them as problems, exit 1; the benchmark runs them, as the
    simulated arm has no stops, but says so first rather than leave a user to find it later)."""
    from adaptive_dd.benchmark.preflight import (
        duration_problems,
        floor_problems,
        inertia_problems,
        reference_problems,
    )

    found = reference_problems(sc) + inertia_problems(sc) + floor_problems(sc) + duration_problems(sc)
    return [f"warning: {sc.source or 'scenario'}: {p}" for p in found]


def with_floors(sc):
    """``sc`` with the floor of each of its controllers that lacks its own (``adaptive_ct``'s
    ``ct_oracle``) added, and said (:func:`~adaptive_dd.benchmark.preflight.missing_floors`): without
    it a controller has no ratio to its floor, and the information and detection limits are judged
    on another reference. A floor that cannot run on the arm is said, not added."""
    import dataclasses

    from adaptive_dd.benchmark.preflight import missing_floors
    from adaptive_dd.controllers.plugins import table_name

    add, cannot = missing_floors(sc)
    where = sc.source or "scenario"
    for floor, of in cannot.items():
        tables = ", ".join(f"[controllers.{table_name(n)}]" for n in of)
        print(
            f"{where}: {floor}, the floor of {', '.join(of)}, does not run on this arm (N-joint arms "
            f"only): reported with no ratio to a floor; set the floor of {tables} to one of the run's "
            "controllers to measure against that one",
            file=sys.stderr,
        )
    for floor, of in add.items():
        print(
            f"{where}: run.controllers: {floor} added (the floor of {', '.join(of)}; list it to keep "
            "this quiet)",
            file=sys.stderr,
        )
    return dataclasses.replace(sc, controllers=(*sc.controllers, *add)) if add else sc


def only_controllers(sc, names: list[str]) -> tuple[str, ...]:
    """The scenario's controllers among ``names``, with the floor of each (``adaptive_ct`` brings
    ``ct_oracle``), in the scenario's order; a plug-in may be named by its label, as its results
    are; a name the scenario does not list is an error naming the scenario's list."""
    from adaptive_dd.benchmark.preflight import scenario_floors
    from adaptive_dd.benchmark.scenario_settings import result_names
    from adaptive_dd.errors import ParameterError

    carried = result_names(
        sc.controllers, {n: sc.options(n) for n, _ in sc.controller_options}, sc.source, sc.origin
    )
    spec_of = {name: spec for spec, name in carried.items()}  # a result's name (a label): its entry
    names = [spec_of.get(n, n) for n in names]
    unknown = [n for n in names if n not in sc.controllers]
    if unknown:
        from adaptive_dd.benchmark.key_hints import did_you_mean

        known = dict.fromkeys([*sc.controllers, *spec_of])
        said = ", ".join(n + did_you_mean(n, known) for n in unknown)
        raise ParameterError(
            f"--controllers: {said} not among {sc.source}'s controllers "
            f"{list(sc.controllers)}; name some of those (--controllers picks from the scenario's "
            "run.controllers; add another law there)"
        )
    keep, floors = set(names), scenario_floors(sc)
    for n in names:
        floor = spec_of.get(floors.get(n), floors.get(n))
        if floor is not None and floor not in keep and floor in sc.controllers:
            keep.add(floor)
            print(f"--controllers: {floor} added (the floor of {n})", file=sys.stderr)
    return tuple(c for c in sc.controllers if c in keep)
