"""Time per simulated sample of the paper's arm's closed loop: its closed forms and the general kernels.

Usage::

    NUMBA_NUM_THREADS=1 python benchmarks/two_link_speed_ab.py
    NUMBA_NUM_THREADS=1 PYTHONPATH=/path/to/tree python benchmarks/two_link_speed_ab.py --runtimes closed

Runs ``pd``, ``ct_oracle``, ``slotine_li`` and ``adaptive_ct`` each alone on the default scenario
(the paper's arm on its closed forms, 20 s) and on ``benchmarks/scenarios/sice_general.toml`` (the
same arm, reference, payloads and noise on the general N-joint kernels), for 1 and 16 seeds, and
prints the best of three ``run_benchmark`` calls in microseconds per trial-sample (compilation
excluded: a short warm-up run first): wall time, and in brackets the process's CPU time (all its
threads; steadier than wall time on a loaded machine, but with more than one numba thread it
counts the closed forms' idle worker waiting: set ``NUMBA_NUM_THREADS=1``), and the general
kernels' time over the closed forms'. For comparing source trees, alternate them a few times: the
machine's load moves every figure. Asserts nothing.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time
import warnings

import adaptive_dd
from adaptive_dd.benchmark import load_scenario, run_benchmark
from adaptive_dd.benchmark.scenario import default_scenario_path

GENERAL = os.path.join(os.path.dirname(os.path.abspath(__file__)), "scenarios", "sice_general.toml")
CONTROLLERS = ("pd", "ct_oracle", "slotine_li", "adaptive_ct")


def per_sample(sc, name: str, seeds: int) -> tuple[float, float]:
    """Best of three (wall, CPU) microseconds per trial-sample of ``name`` alone over ``seeds``."""
    s = dataclasses.replace(sc, seeds=seeds, controllers=(name,))
    warm = dataclasses.replace(s, duration=0.5, swap_times=(), swap_masses=())
    run_benchmark(warm, progress=False)
    best, best_cpu = float("inf"), float("inf")
    for _ in range(3):
        t0, c0 = time.perf_counter(), time.process_time()
        run_benchmark(s, progress=False)
        best = min(best, time.perf_counter() - t0)
        best_cpu = min(best_cpu, time.process_time() - c0)
    per = 1e6 / (s.n_samples * seeds)
    return best * per, best_cpu * per


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runtimes", default="closed,general", help="closed, general or both (default)")
    ap.add_argument("--controllers", default=",".join(CONTROLLERS))
    args = ap.parse_args()
    runtimes = args.runtimes.split(",")
    bad = sorted(set(runtimes) - {"closed", "general"})
    if bad:
        ap.error(f"--runtimes: {', '.join(bad)} is not closed or general")
    # each controller alone, its floor not run: the run's warning about its missing ratios is not news
    warnings.filterwarnings("ignore", message=r".*floor \w+ did not run")
    paths = {"closed": default_scenario_path(), "general": GENERAL}
    scenarios = {r: load_scenario(paths[r]) for r in runtimes}
    print(adaptive_dd.__file__, f"NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS', '(unset)')}")
    print("us per trial-sample, best of 3: wall [process CPU]")
    head = f"{'controller':12s} {'seeds':>5s}" + "".join(f"  {r:>18s}" for r in runtimes)
    print(head + ("  general / closed (wall)" if len(runtimes) == 2 else ""), flush=True)
    for name in args.controllers.split(","):
        for seeds in (1, 16):
            got = {r: per_sample(sc, name, seeds) for r, sc in scenarios.items()}
            line = f"{name:12s} {seeds:5d}" + "".join(f"  {w:8.2f} [{c:7.2f}]" for w, c in got.values())
            if len(got) == 2:
                line += f"  {got['general'][0] / got['closed'][0]:6.2f}x"
            print(line, flush=True)


if __name__ == "__main__":
    main()
