"""``validate``'s time estimate against the run it estimates: one line per scenario and size.

Usage::

    PYTHONPATH=. python benchmarks/estimate_check.py [--repeat 3] [--seeds 1 10] [--duration 2 20]
        [SCENARIO ...]

With ``--cli`` each size is ``adaptive-dd benchmark SCENARIO --seeds N`` in a new process (the
scenario's duration), as a user runs it. For each scenario (default: the shipped
``payload_swap`` and ``ur5_tool_swap``), each seed count and each duration, it prints what
:meth:`~adaptive_dd.benchmark.scenario.Scenario.estimate` says (the run and, on a cold cache,
the one-time compilation) beside the wall time
:func:`~adaptive_dd.benchmark.runner.run_benchmark` takes in this process, with the compilation
it measured (``res.compile_time``), the ratio measured / estimated and the CPU seconds of the
process and its children (on a busy machine the wall time stretches, the CPU time much less);
``--repeat`` runs each size that many times (the first run of a scenario compiles when the cache
is cold: give a fresh ``NUMBA_CACHE_DIR`` to measure the compilation). The load average is
printed with each line: the figures are of a shared machine when it is not near 0.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from adaptive_dd.benchmark import load_scenario, run_benchmark

SHIPPED = Path(__file__).resolve().parents[1] / "adaptive_dd" / "scenarios"


def _cpu() -> float:
    """CPU seconds of this process and its waited-for children (the second compiling process)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def check(path: Path, seeds: int, duration: float) -> tuple[float, float, float, float, float]:
    """``(estimated s, of which compiling, measured s, of which compiling, CPU s)`` of one run."""
    sc = load_scenario(path)
    keep = [(t, m) for t, m in zip(sc.swap_times, sc.swap_masses, strict=True) if t < duration - 0.25]
    sc = dataclasses.replace(
        sc,
        seeds=seeds,
        duration=duration,
        swap_times=tuple(t for t, _ in keep),
        swap_masses=tuple(m for _, m in keep),
        swap_com=sc.swap_com[: len(keep)],
        swap_inertia=sc.swap_inertia[: len(keep)],
    )
    est = sc.estimate()
    t, cpu = time.perf_counter(), _cpu()
    res = run_benchmark(sc, progress=False)
    wall = time.perf_counter() - t
    return est.seconds, est.compile_seconds, wall, res.compile_time, _cpu() - cpu


def check_cli(path: Path, seeds: int) -> tuple[float, float, float, float, float]:
    """As :func:`check`, of ``adaptive-dd benchmark PATH --seeds SEEDS`` in a new process (the
    scenario's own duration): imports, the run, the report and the figures, as a user runs it;
    its compilation is the ``compiled the kernels in N s`` it prints (0 when it prints none)."""
    est = dataclasses.replace(load_scenario(path), seeds=seeds).estimate()
    with tempfile.TemporaryDirectory() as out:
        cmd = [sys.executable, "-m", "adaptive_dd.cli", "benchmark", str(path), "--seeds", str(seeds)]
        t, cpu = time.perf_counter(), _cpu()
        done = subprocess.run(
            [*cmd, "--out", out, "--no-progress"], capture_output=True, text=True, check=True
        )
        wall, cpu = time.perf_counter() - t, _cpu() - cpu
    said = [ln for ln in done.stderr.splitlines() if ln.startswith("compiled the kernels in ")]
    compiled = float(said[-1].split()[4]) if said else 0.0
    return est.seconds, est.compile_seconds, wall, compiled, cpu


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], allow_abbrev=False)
    ap.add_argument("scenarios", nargs="*", type=Path)
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 10])
    ap.add_argument("--duration", type=float, nargs="+", default=[2.0, 20.0])
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--cli", action="store_true", help="run `adaptive-dd benchmark` (full duration)")
    args = ap.parse_args()
    if args.cli:
        args.duration = [None]
    paths = args.scenarios or [SHIPPED / "payload_swap.toml", SHIPPED / "ur5_tool_swap.toml"]
    print("scenario | seeds | duration [s] | estimated [s] (compiling) | measured [s] (compiling) | "
          "measured / estimated | CPU [s] | load")  # fmt: skip
    ratios = []
    for path in paths:
        for seeds in args.seeds:
            for duration in args.duration:
                for _ in range(args.repeat):
                    if args.cli:
                        est, est_c, wall, wall_c, cpu = check_cli(path, seeds)
                        duration = load_scenario(path).duration
                    else:
                        est, est_c, wall, wall_c, cpu = check(path, seeds, duration)
                    ratios.append(wall / est)
                    print(
                        f"{path.stem} | {seeds} | {duration:g} | {est:.1f} ({est_c:.0f}) | "
                        f"{wall:.1f} ({wall_c:.0f}) | {wall / est:.2f} | {cpu:.1f} | "
                        f"{os.getloadavg()[0]:.1f}",
                        flush=True,
                    )
    print(f"measured / estimated: min {min(ratios):.2f}, max {max(ratios):.2f} over {len(ratios)} runs")


if __name__ == "__main__":
    main()
