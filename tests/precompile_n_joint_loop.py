"""Compile the N-joint closed loop into numba's cache: ``python tests/precompile_n_joint_loop.py``.

``conftest.py`` starts it at the start of a parallel run of the whole suite. A kernel is compiled
once per source state by whichever process asks first (``adaptive_dd/_numba_cache.py``'s lock)
and a process that asks meanwhile waits for it. On a cold cache the N-joint closed loop (about
160 CPU s with its callees, in one process) is asked for by a test in every worker within the
first minute or two: the other workers waited while one compiled it, a core idle.
Here it is compiled from the run's start in processes that wait for nothing, in two of them as
the command line compiles it (:class:`~adaptive_dd._numba_cache.Compiling`: the estimator's step
in one, the plant's step, the law's pieces and the report's kernels in the other, then the loop
around them). Whichever process asks for the loop first compiles it: a worker that gets there
before this one compiles the loop alone (about 50 CPU s), its pieces already in the cache.
A short run of the shipped UR5 scenario gives the loop the argument types every run gives it
(one specialisation for every law and arm: ``tests/test_compile_once.py``). Nothing is done when
the cache holds the loop already. The two-link loop (about 60 CPU s) is left to the tests: no
worker waited for it.
"""

from __future__ import annotations

import dataclasses
import os
from importlib import resources


def main() -> None:
    from adaptive_dd._numba_cache import announce_compilation, compile_estimate
    from adaptive_dd.benchmark.runner import run_benchmark
    from adaptive_dd.benchmark.scenario import load_scenario

    source = str(resources.files("adaptive_dd.scenarios").joinpath("ur5_tool_swap.toml"))
    sc = load_scenario(source)
    if not compile_estimate(sc.arm):
        return
    sc = dataclasses.replace(
        sc, seeds=1, duration=1.5, swap_times=(0.5, 1.0), swap_masses=(2.0, 0.0), swap_com=(), swap_inertia=()
    ).with_controllers(("pd", "adaptive_ct", "ct_oracle"))  # a law with the estimator and without
    with (
        open(os.devnull, "w") as quiet,
        announce_compilation(sc.arm, stream=quiet, source=source) as compiling,
    ):
        run_benchmark(sc, progress=False)
        compiling.join()


if __name__ == "__main__":
    main()
