"""Seconds to compile the two-link compiled loop from an empty numba cache (one tiny run).

Usage::

    NUMBA_NUM_THREADS=1 PYTHONPATH=. python benchmarks/two_link_compile_time.py

Runs ``pd`` (compiles ``closed_loop_block`` and everything it inlines), then ``adaptive_ct``
(the same kernel: the law is a runtime code, :func:`~adaptive_dd.controllers.compiled_form.command_trial`),
each on one seed for 0.05 s, in a fresh temporary cache folder, and prints the wall time of each.
The second figure near zero is what a per-law kernel (numba specialising the sample loop on a
function or a gains type per law) would give up: each law would pay the first figure again.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import time

os.environ["NUMBA_CACHE_DIR"] = tempfile.mkdtemp(prefix="adaptive_dd_numba_")

import dataclasses

from adaptive_dd.benchmark import load_scenario, run_benchmark


def main() -> None:
    sc = dataclasses.replace(load_scenario(), seeds=1, duration=0.05, swap_times=(), swap_masses=())
    for name in ("pd", "adaptive_ct"):
        t = time.perf_counter()
        run_benchmark(dataclasses.replace(sc, controllers=(name,)), progress=False, engine="compiled")
        print(f"{name}: {time.perf_counter() - t:.1f} s (compile + run, from an empty cache)")
    shutil.rmtree(os.environ["NUMBA_CACHE_DIR"], ignore_errors=True)


if __name__ == "__main__":
    main()
