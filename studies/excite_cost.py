"""What the excitation phase (``[run] excite``) costs, piece by piece, on one seed: the design of
the excitation (once per run), its closed loop (warm: the kernels compiled by a first run) and
the identification of the record; the per-sample-per-joint^2 figure of the identification is
``_IDENTIFY_SECONDS_PER_SAMPLE_JOINT2`` in ``adaptive_dd/benchmark/scenario_base.py``.

    python studies/excite_cost.py benchmarks/scenarios/gen3_excite.toml
"""

from __future__ import annotations

import dataclasses
import sys
import time

from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.closed_loop import excitation_phase as ep
from adaptive_dd.closed_loop.runner import run_closed_loop


def main(path: str) -> None:
    sc = dataclasses.replace(load_scenario(path), seeds=1)
    t = time.perf_counter()
    reference = ep.excitation_reference(sc)
    design = time.perf_counter() - t
    exc = ep._excitation_scenario(sc, reference)
    run_closed_loop(exc, seed_indices=(0,), keep_trajectories=1)  # compiles on a cold cache
    t = time.perf_counter()
    run_closed_loop(exc, seed_indices=(0,), keep_trajectories=1)
    loop = time.perf_counter() - t
    timed = {"identify": 0.0}
    identify_record = ep.identify_record

    def timed_identify(*a, **k):
        t0 = time.perf_counter()
        out = identify_record(*a, **k)
        timed["identify"] += time.perf_counter() - t0
        return out

    ep.identify_record = timed_identify
    ep.identify_excitation(sc, (0,), run_closed_loop)
    n, N = sc.n_joints, exc.n_samples
    print(f"{path}: {n} joints, excite {sc.excite:g} s = {N} samples, one seed")
    print(f"  design (once)            : {design:.1f} s")
    print(f"  closed loop (warm)       : {loop:.2f} s")
    print(
        f"  identification (a seed)  : {timed['identify']:.1f} s = "
        f"{timed['identify'] / (N * n * n):.2e} s per sample per joint^2"
    )


if __name__ == "__main__":
    main(sys.argv[1])
