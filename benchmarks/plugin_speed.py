"""Per-sample time of a compiled plug-in against the built-in law it reproduces, in one run.

Runs ``examples/plugins/pd_gravity.toml`` (the three-joint vertical arm, a 1 kg payload from
2 s) with each of

* the built-in ``pd_gravity`` (the compiled loop of every built-in),
* ``pd_gravity_plugin:PDGravityPlugin`` (the same law as a compiled plug-in, its own
  specialisation of the loop),
* ``pd_gravity_python:PDGravityPython`` (the same law as a plain-Python plug-in, the Python path),

alone, one after the other, ``--repeat`` times each in rotation, and prints for each the best
CPU time per trial-sample [us] over the calls (process CPU time, one numba thread: less
sensitive to other work on the machine than wall time) and its ratio to the built-in. The first
call of each (compilation, or loading the cache) is run before and not counted; its wall time is
printed apart. The issue's target: the compiled plug-in within 1.5x of the built-in.

Usage::

    python benchmarks/plugin_speed.py [--seeds N] [--duration S] [--python-duration S] [--repeat N]

Asserts nothing; speed is never asserted in tests.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENARIO = ROOT / "examples" / "plugins" / "pd_gravity.toml"
LAWS = {
    "built-in pd_gravity": "pd_gravity",
    "compiled plug-in": "pd_gravity_plugin:PDGravityPlugin",
    "plain-Python plug-in": "pd_gravity_python:PDGravityPython",
}


def _scenario(spec: str, seeds: int, duration: float):
    from adaptive_dd.benchmark.scenario import parse_scenario

    data = tomllib.loads(SCENARIO.read_text())
    data["run"].update(controllers=[spec], seeds=seeds, duration=duration)
    data.pop("controllers", None)  # the plug-in's label table: not needed here
    return parse_scenario(data, str(SCENARIO), name="plugin_speed")


def _cpu_per_sample(sc) -> tuple[float, float]:
    """``(cpu_us, wall_s)``: CPU time per trial-sample of one run of ``sc`` and its wall time."""
    from adaptive_dd.closed_loop.runner import run_closed_loop

    w0, c0 = time.perf_counter(), time.process_time()
    with contextlib.redirect_stdout(io.StringIO()):  # the slow-path note, once per run
        run_closed_loop(sc, keep_trajectories=0)
    c1, w1 = time.process_time(), time.perf_counter()
    return (c1 - c0) / (sc.seeds * sc.n_samples) * 1e6, w1 - w0


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=4, help="trials per run (default 4)")
    ap.add_argument("--duration", type=float, default=4.0, help="simulated s per trial (default 4)")
    ap.add_argument(
        "--python-duration", type=float, default=1.0, help="simulated s of the Python path's runs (default 1)"
    )
    ap.add_argument("--repeat", type=int, default=3, help="timed runs of each, the best counted (default 3)")
    a = ap.parse_args(argv)
    import numba

    numba.set_num_threads(1)
    import sys

    sys.path.insert(0, str(SCENARIO.parent))
    scs = {
        k: _scenario(v, a.seeds, a.python_duration if "Python" in k else a.duration) for k, v in LAWS.items()
    }
    for k, sc in scs.items():
        t0 = time.perf_counter()
        _cpu_per_sample(sc)
        print(f"{k}: first run (compilation or cache load included) {time.perf_counter() - t0:.1f} s wall")
    best = {k: float("inf") for k in scs}
    for _ in range(a.repeat):
        for k, sc in scs.items():
            best[k] = min(best[k], _cpu_per_sample(sc)[0])
    ref = best["built-in pd_gravity"]
    print(f"\n{a.seeds} trials, one numba thread, best of {a.repeat}; CPU time per trial-sample")
    print(f"{'controller':<24}{'us/sample':>12}{'x built-in':>12}")
    for k, v in best.items():
        print(f"{k:<24}{v:>12.3f}{v / ref:>12.2f}")
    r = best["compiled plug-in"] / ref
    print(f"\ncompiled plug-in / built-in = {r:.2f} (target <= 1.5: {'met' if r <= 1.5 else 'NOT met'})")


if __name__ == "__main__":
    main()
