"""Compile one closed loop into numba's cache: ``python tests/precompile_loops.py two-link|n-joint``.

``conftest.py`` starts both at the start of a parallel run of the whole suite. Each closed loop is
compiled once per source state by whichever process asks first (``adaptive_dd/_numba_cache.py``'s
lock), and a worker that asks meanwhile waits: on a cold cache the N-joint loop (about 160 CPU s)
held two of the three workers idle while the third compiled it. Started here, at once, in
processes that wait for nothing (the N-joint one in two, as the command line compiles it:
:class:`~adaptive_dd._numba_cache.Compiling`), the workers find them in the cache or wait less.
A short run of a shipped scenario compiles the loop with the argument types every run gives it
(one specialisation for every law and arm: ``tests/test_compile_once.py``). Nothing is done when
the cache holds the loop already.
"""

from __future__ import annotations

import dataclasses
import os
import sys
from importlib import resources


def main(kind: str) -> None:
    from adaptive_dd._numba_cache import announce_compilation, compile_estimate
    from adaptive_dd.benchmark.runner import run_benchmark
    from adaptive_dd.benchmark.scenario import load_scenario

    if kind == "n-joint":
        source = str(resources.files("adaptive_dd.scenarios").joinpath("ur5_tool_swap.toml"))
        sc = load_scenario(source)
        short = {"duration": 1.5, "swap_times": (0.5, 1.0), "swap_masses": (2.0, 0.0)}
        short.update(swap_com=(), swap_inertia=())
    else:
        source, sc = None, load_scenario()
        short = {"duration": 0.5, "swap_times": (0.25,), "swap_masses": (1.0,)}
    arm = sc.closed_forms or sc.arm
    if not compile_estimate(arm):
        return
    # two laws, one with the estimator: the loop is one specialisation for every law
    sc = dataclasses.replace(sc, seeds=1, **short).with_controllers(("pd", "adaptive_ct", "ct_oracle"))
    with open(os.devnull, "w") as quiet, announce_compilation(arm, stream=quiet, source=source) as compiling:
        run_benchmark(sc, progress=False)
        compiling.join()


if __name__ == "__main__":
    main(sys.argv[1])
