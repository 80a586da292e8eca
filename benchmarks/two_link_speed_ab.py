"""Wall time per simulated sample of the two-link compiled closed loop, for comparing source trees.

Usage (one line per tree; alternate the trees a few times, the machine's load moves every figure)::

    NUMBA_NUM_THREADS=1 PYTHONPATH=/path/to/tree python benchmarks/two_link_speed_ab.py

Prints, for ``pd``, ``ct_nominal``, ``slotine_li`` and ``adaptive_ct`` on the default scenario
(20 s), the best of three ``run_benchmark(engine="compiled")`` calls in microseconds per
trial-sample, for 1 and 16 seeds (compilation excluded: a short warm-up run first): wall time, and
in brackets CPU time of the process (all its threads; steadier than wall time on a loaded
machine). Asserts nothing.
"""

from __future__ import annotations

import dataclasses
import time
import warnings

import adaptive_dd
from adaptive_dd.benchmark import load_scenario, run_benchmark
from adaptive_dd.benchmark.scenario import default_scenario_path


def main() -> None:
    # each controller alone, its floor not run: the run's warning about its missing ratios, once per
    # run, is not news here
    warnings.filterwarnings("ignore", message=r".*floor \w+ did not run")
    sc = load_scenario(default_scenario_path())
    out = []
    for name in ("pd", "ct_nominal", "slotine_li", "adaptive_ct"):
        for seeds in (1, 16):
            s = dataclasses.replace(sc, seeds=seeds, controllers=(name,))
            warm = dataclasses.replace(s, duration=0.5, swap_times=(), swap_masses=())
            run_benchmark(warm, progress=False, engine="compiled")
            best, best_cpu = float("inf"), float("inf")
            for _ in range(3):
                t0, c0 = time.perf_counter(), time.process_time()
                run_benchmark(s, progress=False, engine="compiled")
                best = min(best, time.perf_counter() - t0)
                best_cpu = min(best_cpu, time.process_time() - c0)
            per = 1e6 / (s.n_samples * seeds)
            out.append(f"{name}/{seeds}: {best * per:.2f} [{best_cpu * per:.2f}]")
    print(adaptive_dd.__file__, "us per trial-sample:", " ".join(out), flush=True)


if __name__ == "__main__":
    main()
