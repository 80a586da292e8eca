"""Speed and memory of the closed loop, against the targets of issue 11.

Prints, in one run:

* for each built-in controller, simulated seconds per wall second for one trial and
  for a batch of trials, on the Python path of :func:`adaptive_dd.benchmark.run_benchmark`
  and, when ``run_benchmark`` accepts ``engine=`` (detected, never required), on
  ``engine="compiled"`` (its first call, compile included, is timed apart);
* the anchor: a per-sample Python loop of ``pinocchio.aba`` (RK4, 2 substeps per
  sample, viscous + smooth Coulomb friction as torque) with a numpy computed-torque
  law on the SICE arm (:func:`adaptive_dd.plant.pinocchio_model.build_model`);
* peak RSS and wall time of the user's command ``adaptive-dd benchmark --seeds N`` (all
  controllers, every output), measured from outside the process (``/usr/bin/time -v``);
* the default benchmark (all controllers) at 10 seeds, wall time.

Each line is marked against the issue's targets (``met`` / ``NOT met``; ``-`` where
the issue sets none). The trials are the default scenario's reference and noise,
shortened to ``--duration`` s with one 3 kg swap at mid-run.

Usage::

    python benchmarks/speed.py [--duration S] [--single-duration S] [--repeat N] [--batch N]
                               [--pin-duration S]
                               [--seeds-memory N] [--default-seeds N]
                               [--controllers NAME ...] [--engines python compiled]

Options
-------
--duration S           simulated seconds per trial of the batch lines (default 2)
--single-duration S    simulated seconds of the 1-trial lines (default 20, the default scenario's
                       length: a 2-s trial is dominated by the fixed cost of a run_benchmark call)
--repeat N             calls per line, the best one counted (default 3)
--batch N              trials in a batch (default 64)
--pin-duration S       simulated seconds of the Pinocchio loop (default 1)
--seeds-memory N       seeds of the CLI run measured from outside; 0 skips it (default 1000)
--default-seeds N      seeds of the full default benchmark timing; 0 skips it (default 10)
--controllers ...      controllers of the speed lines (default: all built-in)
--engines ...          engines to try (default: python compiled)

Asserts nothing; speed is never asserted in tests.
"""

from __future__ import annotations

import argparse
import dataclasses
import inspect
import os
import subprocess
import sys
import time

import numpy as np

TARGETS = {
    "single": 1000.0,  # one trial of adaptive_ct, simulated s per wall s
    "vs_pinocchio": 100.0,  # ... and x the Pinocchio loop
    "batch": 3000.0,  # batch of adaptive_ct on 2 cores
    "memory_gib": 1.0,  # default scenario at 1000 seeds
    "memory_wall": 60.0,  # s, default benchmark at 1000 seeds
    "default10_wall": 5.0,  # s, default benchmark at 10 seeds after the first compile
}


def _mark(ok: bool | None) -> str:
    return "-" if ok is None else "met" if ok else "NOT met"


def _engine_kwargs(engine: str) -> dict | None:
    """Keyword arguments selecting an engine, or None if run_benchmark has no such engine."""
    from adaptive_dd.benchmark.runner import run_benchmark

    if "engine" not in inspect.signature(run_benchmark).parameters:
        return {} if engine == "python" else None
    return {"engine": engine}


def _scenario(n_trials: int, duration: float):
    from adaptive_dd.benchmark.scenario import load_scenario

    return dataclasses.replace(
        load_scenario(), seeds=n_trials, duration=duration, swap_times=(duration / 2,), swap_masses=(3.0,)
    )


def sim_rate(controller: str, n_trials: int, duration: float, engine: str, repeat: int = 1) -> float:
    """Simulated seconds (summed over trials) per wall second of one run_benchmark call (the best
    of ``repeat`` calls: other processes on the machine only ever slow a call down)."""
    import numba

    from adaptive_dd.benchmark.runner import run_benchmark

    sc = dataclasses.replace(_scenario(n_trials, duration), controllers=(controller,))
    threads = numba.get_num_threads()
    if n_trials == 1:  # one trial runs on one thread; a second only waits at each block's barrier
        numba.set_num_threads(1)
    best = float("inf")
    try:
        for _ in range(repeat):
            t0 = time.perf_counter()
            run_benchmark(sc, progress=False, **_engine_kwargs(engine))
            best = min(best, time.perf_counter() - t0)
    finally:
        numba.set_num_threads(threads)
    return n_trials * duration / best


def pinocchio_rate(duration: float, substeps: int = 2, seed: int = 0) -> float:
    """The anchor: per-sample Python loop of ``pin.aba`` + RK4 + numpy computed torque."""
    import pinocchio as pin

    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.controllers.feedback import computed_torque_law
    from adaptive_dd.plant import TABLE1_PHYSICAL, TABLE1_SIGMA
    from adaptive_dd.plant.pinocchio_model import build_model

    model = build_model(TABLE1_PHYSICAL)
    data = model.createData()
    T = 1e-3
    n = round(duration / T)
    q_d, qd_d, qdd_d = load_scenario().reference.sample(np.arange(n) * T)
    b, d = TABLE1_SIGMA[3:5], TABLE1_SIGMA[5:7]
    rng = np.random.default_rng(seed)

    def accel(q, v, tau):
        return pin.aba(model, data, q, v, tau - b * v - d * np.tanh(v / 1e-3))

    t0 = time.perf_counter()
    q, v = q_d[0].copy(), qd_d[0].copy()
    h = T / substeps
    for k in range(n):
        qm = q + 1e-4 * rng.standard_normal(2)
        vm = v + 7e-3 * rng.standard_normal(2)
        tau = computed_torque_law(qm, vm, q_d[k], qd_d[k], qdd_d[k], TABLE1_SIGMA, 1600.0, 80.0)
        for _ in range(substeps):  # RK4 on (q, v); torque held over the sample
            a1 = accel(q, v, tau)
            a2 = accel(q + 0.5 * h * v, v + 0.5 * h * a1, tau)
            a3 = accel(q + 0.5 * h * (v + 0.5 * h * a1), v + 0.5 * h * a2, tau)
            a4 = accel(q + h * (v + 0.5 * h * a2), v + h * a3, tau)
            q = q + h * v + h * h / 6 * (a1 + a2 + a3)
            v = v + h / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
    return duration / (time.perf_counter() - t0)


def cli_run(seeds: int) -> dict:
    """The user's command ``adaptive-dd benchmark --seeds N`` (default scenario, all controllers,
    report, CSV, JSON, per-seed table and figures), measured from outside the process.

    Peak RSS from ``/usr/bin/time -v`` ("Maximum resident set size") when it is installed, else
    from the kernel's resource usage of the child (``os.wait4``); wall time around the whole
    command (start-up, compile cache load and outputs included); ``run`` is the wall time the
    report prints for the runs alone.
    """
    import re
    import shutil
    import tempfile

    with tempfile.TemporaryDirectory() as out:
        cmd = [sys.executable, "-m", "adaptive_dd.cli", "benchmark", "--seeds", str(seeds)]
        cmd += ["--out", out, "--no-progress"]
        timev = shutil.which("time") or ("/usr/bin/time" if os.path.exists("/usr/bin/time") else None)
        t0 = time.perf_counter()
        if timev:
            p = subprocess.run([timev, "-v", *cmd], capture_output=True, text=True, check=False)
            wall = time.perf_counter() - t0
            m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr)
            rss_kib, how = (int(m.group(1)) if m else float("nan")), "/usr/bin/time -v"
            stdout, code = p.stdout, p.returncode
        else:
            child = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
            stdout = child.stdout.read()
            _, status, usage = os.wait4(child.pid, 0)
            wall = time.perf_counter() - t0
            rss_kib, how, code = usage.ru_maxrss, "os.wait4 rusage", os.waitstatus_to_exitcode(status)
    m = re.search(r"wall time: ([\d.]+) s", stdout)
    return {
        "wall": wall,
        "run": float(m.group(1)) if m else float("nan"),
        "rss_gib": rss_kib / 2**20,
        "how": how,
        "error": "" if code == 0 else f"exit {code}",
    }


def default_benchmark_wall(seeds: int, engine: str) -> float:
    """Wall time [s] of the full default benchmark (all controllers) at ``seeds`` seeds."""
    from adaptive_dd.benchmark.runner import run_benchmark
    from adaptive_dd.benchmark.scenario import load_scenario

    sc = dataclasses.replace(load_scenario(), seeds=seeds)
    t0 = time.perf_counter()
    run_benchmark(sc, progress=False, **_engine_kwargs(engine))
    return time.perf_counter() - t0


def _line(name: str, value: str, target: str, ok: bool | None) -> None:
    print(f"{name:52s} {value:>16s}  {target:>22s}  {_mark(ok)}")


def _speed_lines(args, engines: list[str], pin: float) -> None:
    for engine in engines:
        ones = {}
        if engine != "python":  # the first call compiles; time it apart
            t0 = time.perf_counter()
            sim_rate(args.controllers[0], 1, 0.05, engine)
            print(f"[{engine}] first call (compile, {args.controllers[0]}): {time.perf_counter() - t0:.1f} s")
        for c in args.controllers:
            sim_rate(c, 1, 0.02, engine)  # warm (imports, caches)
            one = sim_rate(c, 1, args.single_duration, engine, repeat=args.repeat)
            many = sim_rate(c, args.batch, args.duration, engine, repeat=args.repeat)
            ones[c] = one
            main = c == "adaptive_ct"
            _line(
                f"{c}, 1 trial of {args.single_duration:g} s [{engine}]",
                f"{one:.1f}",
                f">= {TARGETS['single']:g}" if main else "",
                one >= TARGETS["single"] if main else None,
            )
            if main:
                _line(
                    f"{c}, 1 trial / Pinocchio loop [{engine}]",
                    f"{one / pin:.2f}x",
                    f">= {TARGETS['vs_pinocchio']:g}x",
                    one / pin >= TARGETS["vs_pinocchio"],
                )
            _line(
                f"{c}, batch of {args.batch} [{engine}]",
                f"{many:.1f}",
                f">= {TARGETS['batch']:g}" if main else "",
                many >= TARGETS["batch"] if main else None,
            )
        _cost_lines(ones, engine)


def _cost_lines(ones: dict, engine: str) -> None:
    """Wall time per simulated sample (T = 1 ms) of the 1-trial lines, and the online estimator's
    share: ``adaptive_ct`` less ``ct_oracle`` (the same plant and law without the estimator)."""
    us = {c: 1e3 / r for c, r in ones.items()}  # µs per sample = 1 ms / (sim s per wall s)
    for c, v in us.items():
        _line(f"{c}, 1 trial [{engine}]: µs per sample", f"{v:.2f} µs", "", None)
    if "adaptive_ct" in us and "ct_oracle" in us:
        _line(
            f"online estimator (adaptive_ct - ct_oracle) [{engine}]",
            f"{us['adaptive_ct'] - us['ct_oracle']:.2f} µs",
            "",
            None,
        )


def _memory_lines(args) -> None:
    n = args.seeds_memory
    r = cli_run(n)
    at1000 = n == 1000
    label = f"adaptive-dd benchmark --seeds {n} (from outside, {r['how']})"
    note = "" if at1000 else " (target at 1000)"
    if r["error"]:
        print(f"{label}: {r['error']}")
    _line(
        f"{label}: peak RSS",
        f"{r['rss_gib']:.2f} GiB",
        f"<= {TARGETS['memory_gib']:g} GiB{note}",
        (not r["error"] and r["rss_gib"] <= TARGETS["memory_gib"]) if at1000 else None,
    )
    _line(
        f"{label}: wall",
        f"{r['wall']:.1f} s",
        f"<= {TARGETS['memory_wall']:g} s{note}",
        (not r["error"] and r["wall"] <= TARGETS["memory_wall"]) if at1000 else None,
    )
    _line(f"{label}: the runs alone (the report's wall time)", f"{r['run']:.1f} s", "", None)


def main(argv: list[str] | None = None) -> None:
    from adaptive_dd.controllers import CONTROLLERS

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--duration", type=float, default=2.0)
    p.add_argument("--single-duration", type=float, default=20.0)
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--batch", type=int, default=64)
    p.add_argument("--pin-duration", type=float, default=1.0)
    p.add_argument("--seeds-memory", type=int, default=1000)
    p.add_argument("--default-seeds", type=int, default=10)
    p.add_argument("--controllers", nargs="+", default=list(CONTROLLERS), choices=CONTROLLERS)
    p.add_argument("--engines", nargs="+", default=["python", "compiled"])
    args = p.parse_args(argv)
    engines = [e for e in args.engines if _engine_kwargs(e) is not None]
    skipped = [e for e in args.engines if e not in engines]
    print(f"closed loop, T = 1 ms, 2 RK4 substeps; {args.duration} s per trial; engines: {engines}")
    print(f"cores: {os.cpu_count()}, load average (1, 5, 15 min) at start: {os.getloadavg()}")
    if skipped:
        print(f"engines not offered by run_benchmark (no 'engine' keyword): {skipped}")
    print(f"{'configuration':52s} {'sim s / wall s':>16s}  {'target':>22s}  status")
    pin = pinocchio_rate(args.pin_duration)
    _line("Pinocchio aba + RK4 (2 substeps) + numpy CT, 1 trial", f"{pin:.1f}", "anchor", None)
    _speed_lines(args, engines, pin)
    best = engines[-1]
    if args.default_seeds > 0:
        default_benchmark_wall(1, best)  # first compile / imports
        w = default_benchmark_wall(args.default_seeds, best)
        at10 = args.default_seeds == 10
        _line(
            f"default benchmark, {args.default_seeds} seeds, all controllers [{best}]",
            f"{w:.1f} s",
            f"<= {TARGETS['default10_wall']:g} s" + ("" if at10 else " (target at 10)"),
            w <= TARGETS["default10_wall"] if at10 else None,
        )
    if args.seeds_memory > 0:
        _memory_lines(args)
    print(f"load average at end: {os.getloadavg()} (other processes slow every figure above)")


if __name__ == "__main__":
    main()
