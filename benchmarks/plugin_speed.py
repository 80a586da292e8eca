"""Per-sample time of a compiled plug-in against the built-in law it reproduces, in one run.

Runs ``examples/plugins/pd_gravity.toml`` (the three-joint vertical arm, a 1 kg payload from
2 s) with each of

* the built-in ``pd_gravity`` (the compiled loop of every built-in),
* ``pd_gravity_plugin:PDGravityPlugin`` (the same law as a compiled plug-in, its own
  specialisation of the loop),
* ``pd_gravity_python:PDGravityPython`` (the same law as a plain-Python plug-in, the Python path),

or, with ``--law slotine_li``, ``examples/plugins/slotine_li.toml`` (the same arm and payload)
with the built-in ``slotine_li`` and ``slotine_li_plugin:SlotineLiPlugin`` (the adaptive law as a
compiled plug-in over the arm's regressor, :mod:`adaptive_dd.controllers.kernels`),

or, with ``--law paper``, the default scenario (the paper's arm on its closed forms, payload swaps
at 5, 10 and 15 s) with the built-in ``pd`` and the same two plug-ins (PD plus gravity is ``pd``
there: the arm moves in a horizontal plane), the compiled one in the two-link compiled loop,

alone, one after the other, ``--repeat`` times each in rotation, and prints for each the best
CPU time per trial-sample [us] over the calls (process CPU time, one numba thread: less
sensitive to other work on the machine than wall time) and its ratio to the built-in: of the
whole ``run_closed_loop`` call (set-up, noise, records included) and, for the two compiled ones,
of the compiled loop's calls alone. The first call of each (compilation, or loading the cache)
is run before and not counted; its wall time and the CPU time numba spent compiling in it are
printed apart. The target: the compiled plug-in
within 1.5x of the built-in.

Usage::

    python benchmarks/plugin_speed.py [--law pd_gravity|slotine_li|paper] [--seeds N]
                                       [--duration S] [--repeat N]

Asserts nothing; speed is never asserted in tests.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
import time
import tomllib
from pathlib import Path

from numba.core import event

ROOT = Path(__file__).resolve().parent.parent
LAWS = {
    "pd_gravity": {
        "built-in pd_gravity": "pd_gravity",
        "compiled plug-in": "pd_gravity_plugin:PDGravityPlugin",
        "plain-Python plug-in": "pd_gravity_python:PDGravityPython",
    },
    "slotine_li": {
        "built-in slotine_li": "slotine_li",
        "compiled plug-in": "slotine_li_plugin:SlotineLiPlugin",
    },
    "paper": {
        "built-in pd": "pd",
        "compiled plug-in": "pd_gravity_plugin:PDGravityPlugin",
        "plain-Python plug-in": "pd_gravity_python:PDGravityPython",
    },
}
"""Per law: the controllers timed (the built-in first), by the name the table prints."""


def _scenario(law: str, spec: str, seeds: int, duration: float):
    from adaptive_dd.benchmark.scenario import parse_scenario

    if law == "paper":  # the default scenario; the plug-ins found on the Python path
        scenario = ROOT / "adaptive_dd" / "scenarios" / "payload_swap.toml"
        if str(ROOT / "examples" / "plugins") not in sys.path:
            sys.path.insert(0, str(ROOT / "examples" / "plugins"))
    else:
        scenario = ROOT / "examples" / "plugins" / f"{law}.toml"
    data = tomllib.loads(scenario.read_text())
    data["run"].update(controllers=[spec], seeds=seeds, duration=duration)
    data["payload"] = [p for p in data.get("payload", []) if p["at"] < duration]  # swaps within the run
    data.pop("controllers", None)  # the plug-in's label table: not needed here
    return parse_scenario(data, str(scenario), name="plugin_speed")


class _Compilations(event.Listener):
    """CPU seconds inside numba's outermost compilations (``numba:compile`` events; a cache hit
    raises none)."""

    def __init__(self) -> None:
        self.depth, self.t0, self.cpu = 0, 0.0, 0.0

    def on_start(self, ev) -> None:
        if self.depth == 0:
            self.t0 = time.process_time()
        self.depth += 1

    def on_end(self, ev) -> None:
        self.depth -= 1
        if self.depth == 0:
            self.cpu += time.process_time() - self.t0


_IN_LOOP = [0.0]  # CPU seconds inside the compiled loop's calls (runner.in_threads)


def _timed_in_threads():
    """The runner's :func:`in_threads`, counting the CPU time of its calls into :data:`_IN_LOOP`."""
    from adaptive_dd.benchmark import drivers
    from adaptive_dd.closed_loop import runner

    inner = runner.in_threads

    def timed(kernel, S, args):
        c0 = time.process_time()
        inner(kernel, S, args)
        _IN_LOOP[0] += time.process_time() - c0

    runner.in_threads = drivers.in_threads = timed


def _cpu_per_sample(sc) -> tuple[float, float, float]:
    """``(run_us, loop_us, wall_s)``: CPU time per trial-sample of one run of ``sc``, of its
    compiled loop's calls alone (0 on the Python path), and the run's wall time."""
    from adaptive_dd.benchmark.runner import run_benchmark

    _IN_LOOP[0] = 0.0
    w0, c0 = time.perf_counter(), time.process_time()
    with contextlib.redirect_stderr(io.StringIO()):  # the slow-path note; each runs alone, without its floor
        run_benchmark(sc, progress=False, keep_trajectories=0, warn_missing_floors=False)
    c1, w1 = time.process_time(), time.perf_counter()
    per = 1e6 / (sc.seeds * sc.n_samples)
    return (c1 - c0) * per, _IN_LOOP[0] * per, w1 - w0


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--law", choices=sorted(LAWS), default="pd_gravity", help="the law (default pd_gravity)")
    ap.add_argument("--seeds", type=int, default=8, help="trials per run (default 8)")
    ap.add_argument("--duration", type=float, default=4.0, help="simulated s per trial, > 2 (default 4)")
    ap.add_argument("--repeat", type=int, default=3, help="timed runs of each, the best counted (default 3)")
    a = ap.parse_args(argv)
    import numba

    numba.set_num_threads(1)
    _timed_in_threads()
    scs = {k: _scenario(a.law, v, a.seeds, a.duration) for k, v in LAWS[a.law].items()}
    for k, sc in scs.items():
        t0, listener = time.perf_counter(), _Compilations()
        with event.install_listener("numba:compile", listener):
            _cpu_per_sample(sc)
        print(
            f"{k}: first run {time.perf_counter() - t0:.1f} s wall, of which numba compiled for "
            f"{listener.cpu:.1f} CPU s (cached kernels are loaded, not counted)"
        )
    best = {k: [float("inf"), float("inf")] for k in scs}
    for _ in range(a.repeat):
        for k, sc in scs.items():
            run_us, loop_us, _ = _cpu_per_sample(sc)
            best[k] = [min(best[k][0], run_us), min(best[k][1], loop_us if loop_us > 0 else float("inf"))]
    ref = best[next(iter(scs))]
    print(f"\n{a.seeds} trials of {a.duration} s, one numba thread, best of {a.repeat}; CPU us per sample")
    print(f"{'controller':<24}{'whole run':>11}{'x built-in':>11}{'in the loop':>13}{'x built-in':>11}")
    for k, (run_us, loop_us) in best.items():
        loop = f"{'-':>13}{'-':>11}"
        if loop_us < float("inf"):
            loop = f"{loop_us:>13.3f}{loop_us / ref[1]:>11.2f}"
        print(f"{k:<24}{run_us:>11.3f}{run_us / ref[0]:>11.2f}{loop}")
    r = best["compiled plug-in"][0] / ref[0]
    verdict = "met" if r <= 1.5 else "NOT met"
    print(f"\ncompiled plug-in / built-in (whole run) = {r:.2f} (target <= 1.5: {verdict})")


if __name__ == "__main__":
    main()
