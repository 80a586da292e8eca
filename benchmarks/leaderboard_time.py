"""Wall and CPU time of ``adaptive-dd leaderboard``, compilation included and apart.

Runs the command in this process with the arguments given (``--no-progress`` added) and prints
its wall time, the process's CPU time (numba's compiling included; on a shared machine the wall
time exceeds the CPU time by what others took), and the seconds the benchmark runs spent
compiling (numba's cache cold) apart from those spent running, as the command counts them. The
target of issue 43: the whole leaderboard within 30 minutes on 2 cores, compilation included.

Usage::

    python benchmarks/leaderboard_time.py [LEADERBOARD ARGS ...]
    python benchmarks/leaderboard_time.py --arms 3 --seeds 2 \\
        --template benchmarks/scenarios/population_drawn.toml --out docs/leaderboard

Asserts nothing; speed is never asserted in tests.
"""

from __future__ import annotations

import os
import resource
import sys
import time


def main(argv: list[str]) -> int:
    """Run the leaderboard with ``argv`` and print its times."""
    from adaptive_dd.cli import main as cli

    def cpu() -> float:
        own = resource.getrusage(resource.RUSAGE_SELF)
        kids = resource.getrusage(resource.RUSAGE_CHILDREN)
        return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime

    w0, c0 = time.perf_counter(), cpu()
    code = cli(["leaderboard", *argv, "--no-progress"])
    wall, used = time.perf_counter() - w0, cpu() - c0
    print(f"leaderboard {' '.join(argv)}")
    print(f"wall time {wall:.1f} s ({wall / 60:.1f} min), CPU time {used:.1f} s on {os.cpu_count()} cores")
    return code


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
