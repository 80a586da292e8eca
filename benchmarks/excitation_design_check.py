"""The excitation design with exact derivatives against the design on scipy's finite differences.

For each drawn arm ``random:A`` of the template (its first start, as the excitation phase's
:func:`~adaptive_dd.closed_loop.excitation_phase.excitation_reference` draws it), designs the
excitation four ways: SLSQP on finite differences (the design before) and with the exact
gradient and Jacobian (:mod:`adaptive_dd.identification.excitation_gradient`), each from the start
and from the start times ``1 + 1e-12`` (how far round-off moves each optimum). Prints per arm each
design's CPU seconds (this process, BLAS as configured: run with ``OPENBLAS_NUM_THREADS=1`` as the
leaderboard holds it), SLSQP's iterations and status and the objective (``-log det`` per base
parameter of the scaled information: lower is better), then the summary: the CPU seconds in all
and the exact design's objective minus the finite differences' (mean, median, min, max) beside
the finite differences' own change under the 1e-12 move of the start.

Usage::

    OPENBLAS_NUM_THREADS=1 python benchmarks/excitation_design_check.py [--arms 0,1,2]
        [--template benchmarks/scenarios/population_drawn.toml]

Asserts nothing; ``tests/test_excitation_design.py`` holds the derivatives and two arms' optima.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path


def main(argv: list[str]) -> int:
    """Print each arm's four designs and the summary."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--arms", default="0,1,2")
    ap.add_argument("--template", default="benchmarks/scenarios/population_drawn.toml")
    args = ap.parse_args(argv)

    import numpy as np

    import adaptive_dd.identification.excitation as ex
    from adaptive_dd.benchmark.population import population_scenario
    from adaptive_dd.benchmark.scenario import read_toml

    data = read_toml(Path(args.template))
    optimise = ex._optimise
    ways = (
        ("fd", False, 0.0),
        ("fd moved", False, 1e-12),
        ("exact", True, 0.0),
        ("exact moved", True, 1e-12),
    )
    cpu = {w[0]: 0.0 for w in ways}
    costs: dict[str, list[float]] = {w[0]: [] for w in ways}
    for a in (int(s) for s in args.arms.split(",")):
        sc = population_scenario(data, args.template, a)
        lim = ex.ExcitationLimits.of_arm(sc.arm)
        for label, exact, move in ways:

            def run(problem, x0, *rest, exact=exact, move=move, **kw):
                return optimise(problem, x0 * (1 + move), *rest, exact=exact, **kw)

            ex._optimise = run
            t0 = time.process_time()
            _, res = ex.design_excitation(sc.arm, lim, rng=np.random.default_rng([int(sc.seed), 4, 0]))
            used = time.process_time() - t0
            ex._optimise = optimise
            cpu[label] += used
            costs[label].append(float(res.fun))
            print(
                f"random:{a} ({sc.arm.n_joints} joints) {label:11s} {used:6.2f} CPU s, {res.nit:3d} "
                f"iterations, status {res.status}, objective {res.fun:.4f}",
                flush=True,
            )
    c = {k: np.array(v) for k, v in costs.items()}
    d, spread = c["exact"] - c["fd"], np.abs(c["fd moved"] - c["fd"])
    print("CPU s in all: " + ", ".join(f"{k} {v:.1f}" for k, v in cpu.items()))
    print(
        f"exact minus finite differences' objective: mean {d.mean():+.4f}, median {np.median(d):+.4f}, "
        f"min {d.min():+.4f}, max {d.max():+.4f}; the finite differences' own change with the start "
        f"moved by 1e-12: mean {spread.mean():.4f}, max {spread.max():.4f}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
