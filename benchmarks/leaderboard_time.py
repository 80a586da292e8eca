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

``--timers`` (the same place; ``--workers 1``) times the parts unprofiled instead: the CPU seconds
(this process's) spent in each of :data:`TIMED` and in each controller's closed loops, with the
number of calls, a clock read around each call and nothing else.

Usage::

    python benchmarks/leaderboard_time.py [--parts | --timers] [LEADERBOARD ARGS ...]
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


TIMED = (  # (module, function) timed by --timers; a name imported elsewhere is replaced there too
    ("adaptive_dd.benchmark.population", "population_scenario"),
    ("adaptive_dd.identification.excitation", "design_excitation"),
    ("adaptive_dd.closed_loop.excitation_phase", "identify_record"),
    ("adaptive_dd.identification.log_fit", "fit_log"),
    ("adaptive_dd.identification.consistency", "consistent_arm_fit"),
    ("adaptive_dd.identification.model_error", "model_error_variance"),
    ("adaptive_dd.closed_loop.model_prior", "estimator_scale"),
    ("adaptive_dd.closed_loop.types", "run_constants"),
    ("adaptive_dd.closed_loop.excitation_phase", "join_results"),
    ("adaptive_dd.arena.leaderboard", "_per_seed"),
    ("adaptive_dd.closed_loop.runner", "_run_compiled"),
)


def install_timers(seconds: dict, calls: dict) -> None:
    """Wrap each function of :data:`TIMED` (and each controller's closed loops, ``loop NAME``) so
    that its CPU seconds and calls add to ``seconds`` and ``calls``."""
    import functools
    import importlib

    def timed(f, label):
        @functools.wraps(f)
        def g(*args, **kw):
            key = f"loop {args[0]}" if label == "_run_compiled" else label
            t = time.process_time()
            try:
                return f(*args, **kw)
            finally:
                seconds[key] = seconds.get(key, 0.0) + time.process_time() - t
                calls[key] = calls.get(key, 0) + 1

        return g

    for mod, name in TIMED:
        f = getattr(importlib.import_module(mod), name)
        g = timed(f, name)
        for m in list(sys.modules.values()):  # the module and every one that imported the name
            if getattr(m, "__name__", "").startswith("adaptive_dd") and getattr(m, name, None) is f:
                setattr(m, name, g)


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
    parts, timers = argv[:1] == ["--parts"], argv[:1] == ["--timers"]
    argv = argv[1:] if parts or timers else argv
    from adaptive_dd.cli import main as cli

    seconds: dict = {}
    calls: dict = {}
    if timers:
        import adaptive_dd.arena.leaderboard  # the modules whose names the timers replace
        import adaptive_dd.closed_loop.excitation_phase
        import adaptive_dd.closed_loop.runner  # noqa: F401

        install_timers(seconds, calls)

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
    for key, s in seconds.items():
        print(f"{key:38s} {s:8.2f} CPU s  {calls[key]:5d} calls")
    return code


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
