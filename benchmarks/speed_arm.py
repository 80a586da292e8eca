"""Speed of the N-joint closed loop on the UR5 tool-swap scenario, beside a Pinocchio anchor.

    python benchmarks/speed_arm.py            # one trial of adaptive_ct and ct_oracle, the anchor
    python benchmarks/speed_arm.py --full     # also 200 seeds x all controllers, timed from outside

Prints, in one run:

* the anchor: a per-sample Python loop on the same arm (computed torque through
  ``pin.rnea``, RK4 with 2 substeps over ``pin.aba``, 1 kHz), simulated s per wall s;
* one trial of ``adaptive_ct`` and of ``ct_oracle`` over the whole 20 s scenario on the
  compiled path (compilation excluded: a short warm-up run first; the first call of the full
  trial, so with the per-arm set-up a user's single run pays), simulated s per wall s,
  against the targets (>= 100x and >= 150x real time), and against the same targets in
  units of the anchor measured in this run (the issue set them beside an anchor of about
  23x real time: 100 / 23 = 4.35x anchor for adaptive_ct, 150 / 23 = 6.52x for ct_oracle),
  which factors out the machine;
* the same trial through ``run_benchmark``, warm: the best of 3 calls after one, per CPU s (the
  loop's rate with what every call adds, the per-arm set-up cached);
* with ``--full``: ``adaptive-dd benchmark ur5_tool_swap_exact.toml --seeds 200`` (every
  controller) under ``/usr/bin/time -v``: wall time and peak resident memory measured from
  outside the process, against the targets (<= 5 min on 2 cores, < 1 GiB).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import re
import subprocess
import sys
import tempfile
import time
from importlib import resources

import numpy as np

TARGET_ADAPTIVE_X = 100.0
TARGET_ORACLE_X = 150.0
ISSUE_ANCHOR_X = 23.0  # issue 17 (Targets): the anchor ran at about 23 simulated s per wall s on its machine
TARGET_FULL_S = 300.0
TARGET_FULL_GIB = 1.0


def _scenario():
    from adaptive_dd.benchmark.scenario import load_scenario

    return load_scenario(str(resources.files("adaptive_dd.scenarios").joinpath("ur5_tool_swap_exact.toml")))


def anchor(sc, seconds: float = 2.0) -> tuple[float, float]:
    """Simulated s per wall s and per CPU s of a per-sample Python loop of Pinocchio (rnea law,
    RK4 over aba)."""
    import pinocchio as pin

    arm = sc.arm
    model = arm.model.copy()
    model.armature = np.array(arm.armature, dtype=float)
    data = model.createData()
    T, sub = sc.sample_period, 2
    h = T / sub
    N = round(seconds / T)
    q_d, qd_d, qdd_d = sc.reference.sample(np.arange(N) * T)
    q, qd = q_d[0].copy(), qd_d[0].copy()
    kp, kd = 40.0**2, 80.0
    fv, fc = arm.viscous, arm.coulomb

    def acc(q, v, tau):
        return pin.aba(model, data, q, v, tau - fv * v - fc * np.tanh(v / 0.02))

    t0, c0 = time.perf_counter(), time.thread_time()
    for k in range(N):
        a = qdd_d[k] + kd * (qd_d[k] - qd) + kp * (q_d[k] - q)
        tau = pin.rnea(model, data, q, qd, a) + model.armature * a + fv * qd + fc * np.sign(qd_d[k])
        for _ in range(sub):
            k1q, k1v = qd, acc(q, qd, tau)
            k2q, k2v = qd + 0.5 * h * k1v, acc(q + 0.5 * h * k1q, qd + 0.5 * h * k1v, tau)
            k3q, k3v = qd + 0.5 * h * k2v, acc(q + 0.5 * h * k2q, qd + 0.5 * h * k2v, tau)
            k4q, k4v = qd + h * k3v, acc(q + h * k3q, qd + h * k3v, tau)
            q = q + h / 6 * (k1q + 2 * k2q + 2 * k3q + k4q)
            qd = qd + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
    return seconds / (time.perf_counter() - t0), seconds / (time.thread_time() - c0)


def one_trial(sc, name: str) -> tuple[float, float]:
    """Simulated s per wall s and per CPU s (of this thread: one trial runs in it) of one trial of
    ``name`` on the compiled path (compile excluded)."""
    from adaptive_dd.closed_loop.runner import run_closed_loop

    opts = tuple(o for o in sc.controller_options if o[0] == name)
    one = dataclasses.replace(sc, seeds=1, controllers=(name,), controller_options=opts)
    run_closed_loop(dataclasses.replace(one, duration=0.2, swap_times=(0.05, 0.1, 0.15)))  # compile
    t0, c0 = time.perf_counter(), time.thread_time()
    res = run_closed_loop(one)
    wall, cpu = time.perf_counter() - t0, time.thread_time() - c0
    assert not res.runs[name].failed.any(), f"{name} failed"
    return sc.duration / wall, sc.duration / cpu


def warm_benchmark(sc, name: str, repeat: int = 3) -> float:
    """Simulated s per CPU s (of this thread) of one trial of ``name`` through ``run_benchmark``,
    the best of ``repeat`` calls after one (the run's per-arm set-up cached, as in a study that
    runs the arm again): the loop's own rate with what each call adds."""
    import warnings

    from adaptive_dd.benchmark.runner import run_benchmark

    opts = tuple(o for o in sc.controller_options if o[0] == name)
    one = dataclasses.replace(sc, seeds=1, controllers=(name,), controller_options=opts)
    best = np.inf
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # its floor does not run: the ratios are not wanted here
        run_benchmark(one, progress=False)
        for _ in range(repeat):
            c0 = time.thread_time()
            run_benchmark(one, progress=False)
            best = min(best, time.thread_time() - c0)
    return sc.duration / best


def full_run(seeds: int, out: str | None = None) -> tuple[float, float, str]:
    """``adaptive-dd benchmark`` of the UR5 scenario under /usr/bin/time -v: wall s, peak GiB, report.

    The outputs go to ``out`` (kept), else to a temporary folder."""
    path = str(resources.files("adaptive_dd.scenarios").joinpath("ur5_tool_swap_exact.toml"))
    with tempfile.TemporaryDirectory() as tmp:
        cmd = ["/usr/bin/time", "-v", sys.executable, "-m", "adaptive_dd.cli", "benchmark", path]
        cmd += ["--seeds", str(seeds), "--out", out or tmp, "--no-progress"]
        p = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if p.returncode != 0:
        raise RuntimeError(f"benchmark failed ({p.returncode}):\n{p.stderr[-3000:]}")
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", p.stderr).group(1)
    parts = [float(x) for x in wall.split(":")]
    secs = sum(x * 60**i for i, x in enumerate(reversed(parts)))
    kb = float(re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr).group(1))
    return secs, kb / 2**20, p.stdout


def _verdict(ok: bool) -> str:
    return "met" if ok else "NOT met"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--full", action="store_true", help="also the 200-seed run under /usr/bin/time -v")
    ap.add_argument("--seeds", type=int, default=200)
    ap.add_argument(
        "--out", default=None, help="keep the full run's outputs (report.txt, metrics, figures) here"
    )
    args = ap.parse_args()
    sc = _scenario()
    print(f"UR5 tool swap: {sc.duration} s at T = {sc.sample_period} s, {sc.n_joints} joints")
    print(f"NUMBA_NUM_THREADS = {os.environ.get('NUMBA_NUM_THREADS', '(unset)')}, cores = {os.cpu_count()}")
    print(f"plant: plant_step, {sc.arm.friction} friction, {sc.substeps} RK4 substeps")
    print("simulated s per wall s, and per CPU s of the thread (robust on a shared machine):")
    xa, ca = anchor(sc)
    print(f"anchor (Python loop: pin.rnea law, RK4 x2 over pin.aba): wall {xa:8.1f}   CPU {ca:8.1f}")
    for name, target in (("adaptive_ct", TARGET_ADAPTIVE_X), ("ct_oracle", TARGET_ORACLE_X)):
        x, c = one_trial(sc, name)
        rel = target / ISSUE_ANCHOR_X
        print(
            f"{name:12s} one trial, compiled: wall {x:8.1f}   CPU {c:8.1f} ({c / ca:5.2f}x anchor, CPU) "
            f"(target >= {target:g}x real time: wall {_verdict(x >= target)}, CPU {_verdict(c >= target)})"
        )
        print(
            f"{'':12s} in anchor units: wall {x / xa:5.2f}x   CPU {c / ca:5.2f}x anchor "
            f"(target >= {target:g} / {ISSUE_ANCHOR_X:g} = {rel:.2f}x anchor, the issue's anchor figure: "
            f"wall {_verdict(x / xa >= rel)}, CPU {_verdict(c / ca >= rel)})"
        )
    for name in ("adaptive_ct", "ct_oracle"):
        c = warm_benchmark(sc, name)
        print(
            f"{name:12s} through run_benchmark, warm (best of 3 calls after one): CPU {c:8.1f} "
            f"({c / ca:5.2f}x anchor, CPU)"
        )
    if args.full:
        secs, gib, report = full_run(args.seeds, args.out)
        if args.out:
            with open(os.path.join(args.out, "report.txt"), "w", encoding="utf-8") as fh:
                fh.write(report)
        print(
            f"adaptive-dd benchmark ur5_tool_swap_exact.toml --seeds {args.seeds} "
            f"({len(sc.controllers)} controllers), /usr/bin/time -v: wall {secs:.1f} s "
            f"(target <= {TARGET_FULL_S:g} s: {_verdict(secs <= TARGET_FULL_S)}), "
            f"peak RSS {gib:.2f} GiB (target < {TARGET_FULL_GIB:g} GiB: {_verdict(gib < TARGET_FULL_GIB)})"
        )


if __name__ == "__main__":
    main()
