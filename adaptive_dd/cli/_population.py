"""``adaptive-dd benchmark FILE --arms N``: one scenario's payload schedule over N drawn arms
(:mod:`adaptive_dd.benchmark.population`), BLAS held to one thread as the leaderboard holds it
(the excitation's design and each seed's identification make many small products, whose BLAS
threads otherwise spin waiting for a core on a shared machine)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

__all__ = ["run_arms"]


def run_arms(args: argparse.Namespace, only_controllers, with_floors) -> int:
    """Run the population, print per arm and pooled, write ``per_seed.csv`` (an ``arm_seed``
    column first), ``arms.csv`` and ``population.json``. ``only_controllers(scenario, names)`` and
    ``with_floors(scenario)``: ``benchmark``'s ``--controllers`` rule and its floors added."""
    import json

    from adaptive_dd._numba_cache import announce_compilation
    from adaptive_dd.benchmark.population import (
        arms_frame,
        format_population,
        judged_rows,
        pooled,
        population_scenario,
        run_population,
    )
    from adaptive_dd.benchmark.scenario import read_toml
    from adaptive_dd.cli._common import show_progress
    from adaptive_dd.errors import ScenarioError
    from adaptive_dd.outputs import OutputSet

    if args.scenario is None:
        raise ScenarioError(
            "--arms needs a template scenario FILE (its payload schedule, run and controllers), e.g. "
            "benchmarks/scenarios/population.toml"
        )
    from adaptive_dd.benchmark.scenario import scenario_file

    path = scenario_file(args.scenario)  # a shipped scenario's name too
    data, src = read_toml(path), str(path)
    if getattr(args, "seed", None) is not None:  # every arm's trials from this base seed
        data = {
            **data,
            "run": {**(data.get("run") if isinstance(data.get("run"), dict) else {}), "seed": args.seed},
        }
    seeds = range(args.first_arm, args.first_arm + args.arms)
    first = population_scenario(data, src, seeds[0], draw_swaps=args.draw_swaps)  # checks the template
    names = only_controllers(first, args.controllers) if args.controllers else first.controllers
    names = with_floors(first.with_controllers(names)).controllers  # each missing floor added, and said
    arm = data.get("arm", {}) if isinstance(data.get("arm"), dict) else {}
    own = arm.get("robot") or arm.get("urdf")
    if own:
        print(
            f"population: {src}'s own arm ({own!r}) is replaced by the drawn arms; run it without "
            "--arms for its own figures",
            file=sys.stderr,
        )
    n_seeds = args.seeds if args.seeds is not None else first.seeds
    print(
        f"population: {args.arms} arms (random:{seeds[0]} .. random:{seeds[-1]}) x {n_seeds} seeds of {src}",
        file=sys.stderr,
    )
    from adaptive_dd.benchmark.controller_entries import variants_line

    if variants_line(first.with_controllers(names)):
        print(f"population: {variants_line(first.with_controllers(names))}", file=sys.stderr)

    def controllers(sc):
        return names

    def on_arm(a: dict) -> None:
        means = " / ".join(f"{s['mean']:.3f}" for s in a["segments"])
        print(
            f"  random:{a['arm_seed']} ({a['joints']} joints): {a['controller']} {means}",
            file=sys.stderr,
            flush=True,
        )

    from threadpoolctl import threadpool_limits

    with (
        announce_compilation(first.arm, source=src) as compiling,
        threadpool_limits(limits=1, user_api="blas"),
    ):
        pop = run_population(
            data,
            src,
            seeds,
            seeds=args.seeds,
            controllers=controllers,
            progress=show_progress(args),
            draw_swaps=args.draw_swaps,
            on_arm=on_arm,
        )
        compiling.join()
    print(format_population(pop))
    out = Path(args.out)
    outputs = OutputSet(args.out, extras=(args.json,) if args.json else ())
    with outputs:
        pop.frame.to_csv(outputs.path("per_seed.csv"), index=False)
        arms_frame(pop).to_csv(outputs.path("arms.csv"), index=False)
        summary = {
            "template": src, "seed": first.seed, "floor_caveat": pop.floor_caveat, "lead": pop.lead,
            "arms": pop.arms,
            "pooled": pooled(pop), "laws": {n: pooled(pop, n) for n in pop.laws},
        }  # fmt: skip
        target = outputs.extra(args.json) if args.json else outputs.path("population.json")
        target.write_text(json.dumps(summary, indent=1, default=float))
        fmts = tuple(args.figure_formats or ())
        if fmts:  # each law's ratio to its floor per segment, every arm and seed pooled
            from adaptive_dd.plotting import plot_ratios

            staged = [outputs.path(f"ratios.{f}") for f in fmts]
            plot_ratios(judged_rows(pop), staged[0], formats=fmts)  # as the pooled lines: no saturated floor
    written = [out / "per_seed.csv", out / "arms.csv", Path(args.json or out / "population.json")]
    written += [out / f"ratios.{f}" for f in fmts]
    print("wrote " + ", ".join(str(w) for w in written))
    frame = pop.frame
    if frame is not None and len(frame) and frame["failed"].astype(bool).all():
        print(
            "adaptive-dd benchmark: every trial of every controller on every arm failed (per_seed.csv's "
            "failure column says why): no result to compare",
            file=sys.stderr,
        )
        return 1
    return 0
