"""CPU seconds of each seed's identification in the excitation phase, on drawn arms.

Runs the template's excitation phase (``[run] excite``) on the drawn arms ``random:FIRST`` ..
``random:FIRST+ARMS-1`` and seeds ``0 .. SEEDS-1``, and times each seed's
:func:`~adaptive_dd.closed_loop.excitation_phase.identify_record` (the filtered regressions, the
weighted least squares with its sandwich covariance, the physically consistent fit, the model
error's alternative fits) in CPU seconds, BLAS on one thread as the leaderboard holds it; the
first call (imports, numba's compiling) is timed apart. ``--profile``: cProfile (CPU clock) of
each seed's identification, its 25 costliest functions.

Usage::

    python benchmarks/identification_time.py [--arms 1] [--first-arm 1] [--seeds 3]
        [--template benchmarks/scenarios/population_drawn.toml] [--profile]

Asserts nothing; speed is never asserted in tests.
"""

from __future__ import annotations

import argparse
import sys
import time
import tomllib


def main(argv: list[str]) -> int:
    """Print each seed's identification CPU time and the mean per arm."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--arms", type=int, default=1)
    ap.add_argument("--first-arm", type=int, default=1)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--template", default="benchmarks/scenarios/population_drawn.toml")
    ap.add_argument("--profile", action="store_true")
    args = ap.parse_args(argv)

    import cProfile
    import pstats

    import numpy as np
    from threadpoolctl import threadpool_limits

    from adaptive_dd.benchmark.population import population_scenario
    from adaptive_dd.closed_loop import excitation_phase as ep
    from adaptive_dd.closed_loop.runner import run_closed_loop

    with open(args.template, "rb") as f:
        data = tomllib.load(f)
    records = []

    def keep(*a, **k):  # the phase's own calls record their inputs; the timing is redone below
        records.append((a, k))
        return identify(*a, **k)

    identify = ep.identify_record
    ep.identify_record = keep
    with threadpool_limits(limits=1, user_api="blas"):
        rows = []
        for arm in range(args.first_arm, args.first_arm + args.arms):
            records.clear()
            c0 = time.process_time()
            ep.identify_excitation(
                population_scenario(data, args.template, arm), list(range(args.seeds)), run_closed_loop
            )
            used = time.process_time() - c0
            print(f"random:{arm}: excitation phase (closed loop, first identification) {used:.1f} CPU s")
            for s, (a, k) in enumerate(records):
                c0 = time.process_time()
                if args.profile:
                    prof = cProfile.Profile(time.process_time)
                    prof.runcall(identify, *a, **k)
                else:
                    identify(*a, **k)
                cpu = time.process_time() - c0
                model = a[0]
                print(f"random:{arm} seed {s}: {model.n} joints, {model.p} base parameters: {cpu:.2f} CPU s")
                rows.append((arm, cpu))
                if args.profile:
                    pstats.Stats(prof).sort_stats("cumulative").print_stats(25)
    ep.identify_record = identify
    cpu = np.array([c for _, c in rows])
    print(f"identification per seed: mean {cpu.mean():.2f} CPU s, max {cpu.max():.2f} ({len(cpu)} seeds)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
