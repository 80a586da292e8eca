"""Wall and CPU time of ``adaptive-dd leaderboard``, compilation included and apart, and per part.

Runs the command in this process with the arguments given (``--no-progress`` added) and prints
its wall time, the CPU time of this process and of its workers (numba's compiling included; on a
shared machine the wall time exceeds the CPU time by what others took), and the seconds the
benchmark runs spent compiling (numba's cache cold) apart from those spent running, as the
command counts them. The target of issue 43: the whole leaderboard within 30 minutes on 2 cores,
compilation included.

``--parts`` (before the leaderboard's arguments; run it with ``--workers 1``, the workers' time is
not profiled) profiles the run with a CPU-time clock and prints the CPU seconds of each part:
the drawn arms' set-up (each arm's URDF and scenario), the excitation's design, the excitation's
closed loop, each seed's identification, the identified model's arm (its URDF), the
controllers' construction (settings derived from the arm), the task's closed loops, numba's
compiling, the metrics, the recovery times, the rows (bootstraps), the figure and the rest
(imports, the command line, glue). The profiler slows Python-heavy parts (the compiled loops
and BLAS not): the parts' total exceeds the unprofiled run's.

Usage::

    python benchmarks/leaderboard_time.py [--parts] [LEADERBOARD ARGS ...]
    python benchmarks/leaderboard_time.py --arms 3 --seeds 2 \\
        --template benchmarks/scenarios/population_drawn.toml --out docs/leaderboard

Asserts nothing; speed is never asserted in tests.
"""

from __future__ import annotations

import os
import resource
import sys
import time

PARTS = (  # (part, function names (file suffix, name) whose cumulative CPU time it is, minus those below)
    ("drawn arms' set-up (URDF, scenario)", [("benchmark/population.py", "population_scenario")]),
    ("excitation design", [("identification/excitation.py", "design_excitation")]),
    ("identification (per seed)", [("closed_loop/excitation_phase.py", "identify_record")]),
    ("controllers' construction", [("controllers/registry.py", "scenario_controller")]),
    ("closed loops (excitation and task)", [("closed_loop/runner.py", "_run_compiled")]),
    ("numba compiling", [("adaptive_dd/_numba_cache.py", "locked_compile")]),
    ("metrics per seed", [("arena/leaderboard.py", "_per_seed")]),
    ("recovery times", [("arena/leaderboard.py", "_recovery")]),
    ("rows (bootstraps)", [("arena/leaderboard.py", "_row")]),
    ("figure", [("arena/plot.py", "plot_leaderboard"), ("matplotlib/figure.py", "savefig")]),
)


def _cumulative(stats, where: str, name: str) -> float:
    """Cumulative time of the functions ``name`` in a file ending ``where`` (recursion counted once)."""
    return sum(v[3] for (f, _, fn), v in stats.stats.items() if fn == name and f.endswith(where))


def print_parts(stats, total: float) -> None:
    """The CPU seconds of each part of :data:`PARTS`; parts nest (compiling happens inside the
    closed loops' first calls, the controllers' construction inside the run), so each part is
    printed with what it holds, and the rest is the total minus the outermost ones."""
    seen = 0.0
    print("part                                   CPU s   (profiled)")
    for part, funcs in PARTS:
        s = sum(_cumulative(stats, w, n) for w, n in funcs)
        print(f"{part:38s} {s:7.1f}")
        if part not in ("numba compiling",):
            seen += s
    print(f"{'rest (imports, command line, glue)':38s} {total - seen:7.1f}")
    print(f"{'total':38s} {total:7.1f}")
    print("(numba compiling happens inside the closed loops and the identification: not added to the rest)")


def main(argv: list[str]) -> int:
    """Run the leaderboard with ``argv`` and print its times."""
    parts = argv[:1] == ["--parts"]
    argv = argv[1:] if parts else argv
    from adaptive_dd.cli import main as cli

    def cpu() -> float:
        own = resource.getrusage(resource.RUSAGE_SELF)
        kids = resource.getrusage(resource.RUSAGE_CHILDREN)
        return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime

    w0, c0 = time.perf_counter(), cpu()
    if parts:
        import cProfile
        import pstats

        prof = cProfile.Profile(time.process_time)
        p0 = time.process_time()
        code = prof.runcall(cli, ["leaderboard", *argv, "--no-progress"])
        profiled = time.process_time() - p0
    else:
        code = cli(["leaderboard", *argv, "--no-progress"])
    wall, used = time.perf_counter() - w0, cpu() - c0
    print(f"leaderboard {' '.join(argv)}")
    print(f"wall time {wall:.1f} s ({wall / 60:.1f} min), CPU time {used:.1f} s on {os.cpu_count()} cores")
    if parts:
        print_parts(pstats.Stats(prof), profiled)
    return code


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
