"""Per-sample speed of the N-joint closed loop in two source trees, trials interleaved in one run.

    python benchmarks/chain_speed_ab.py TREE_A TREE_B [--trials 12] [--controller adaptive_ct]
        [--robot random:K] [--seeds 1] [--scenario ur5_tool_swap_exact.toml]

Starts one worker process per tree (``PYTHONPATH`` the tree, ``NUMBA_NUM_THREADS=1``, each its own
numba cache folder under ``$NUMBA_CACHE_DIR`` or ``~/.cache``, keyed by the tree's source as
usual), which loads the shipped UR5 tool-swap scenario (``--scenario``: another shipped one, such
as ``ur5_tool_swap_exact.toml``) (or, with ``--robot random:K``, the drawn arm K on
``benchmarks/scenarios/population_drawn.toml`` without its excitation phase: each seed's robot
drawn around the arm's URDF) with one controller and compiles or loads the closed loop on a
0.2-s warm-up run; then asks the workers for one whole run (``--seeds`` trials) at a time,
alternating which tree goes first, and prints each run's CPU seconds (of the thread that ran it)
per simulated second of one trial, then the mean, median and best of each tree and B / A. CPU
seconds, not wall: read them beside the load printed. Then compares the two trees' results: the
largest relative difference over every per-seed, per-segment sum of the run (the squared joint
error, per joint, its peak, the squared torque, the tool frame's sums) and the estimate at the end
of each segment (a controller with one), 0 when bit-identical; and whether every sample's tracking
error norm and the detector's alarm times are equal (one digest of each run).
Asserts nothing: a measurement.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys

SUMS = (
    "sum_e2",
    "sum_e2_joint",
    "max_e",
    "sum_tau2",
    "sum_e2_settled",
    "ee_sum_p2",
    "ee_max_p",
    "ee_sum_th2",
)
"""The run's streamed sums compared between the trees."""


def _scenario(robot: str | None, name: str = "ur5_tool_swap.toml"):
    from importlib import resources

    from adaptive_dd.benchmark.scenario import load_scenario

    if robot is None:
        return load_scenario(str(resources.files("adaptive_dd.scenarios").joinpath(name)))
    import tomllib

    from adaptive_dd.benchmark.population import population_scenario

    src = "benchmarks/scenarios/population_drawn.toml"
    with open(src, "rb") as f:
        data = tomllib.load(f)
    del data["run"]["excite"]
    return population_scenario(data, src, int(robot.split(":")[1]))


def worker(name: str, robot: str | None, seeds: int, scenario: str) -> None:
    """One run of controller ``name`` per line on stdin; prints CPU s per simulated s of one trial,
    then the run's sums (``float.hex``, one line)."""
    import dataclasses
    import hashlib
    import time

    import numpy as np

    from adaptive_dd.closed_loop.runner import run_closed_loop

    sc = _scenario(robot, scenario)
    opts = tuple(o for o in sc.controller_options if o[0] == name)
    one = dataclasses.replace(sc, seeds=seeds, controllers=(name,), controller_options=opts)
    run_closed_loop(dataclasses.replace(one, seeds=1, duration=0.2, swap_times=(0.05, 0.1, 0.15)))
    print("ready", flush=True)
    for _ in sys.stdin:
        c0 = time.thread_time()
        res = run_closed_loop(one, keep_trajectories=0)
        cpu = time.thread_time() - c0
        run = res.runs[name]
        assert not run.failed.any(), f"{name} failed"
        sums = [np.ravel(getattr(run.acc, k)) for k in SUMS]
        if run.sigma_end is not None:  # the estimate at the end of each segment
            sums.append(np.ravel(run.sigma_end))
        sums = np.concatenate(sums)
        # every sample's tracking error and the alarm times, as one digest
        h = hashlib.sha256(np.ascontiguousarray(run.e_norm).tobytes())
        h.update(repr(run.alarm_times).encode())
        hexes = ",".join(float(x).hex() for x in sums)
        print(f"{cpu / sc.duration / seeds:.6f} {hexes} {h.hexdigest()}", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("trees", nargs=2, help="the two source trees (folders holding adaptive_dd/)")
    ap.add_argument("--trials", type=int, default=12)
    ap.add_argument("--controller", default="adaptive_ct")
    ap.add_argument("--robot", help="a drawn arm, random:K (default: the shipped UR5 tool swap)")
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument(
        "--scenario",
        default="ur5_tool_swap.toml",
        help="a shipped scenario (without --robot), e.g. ur5_tool_swap_exact.toml",
    )
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    a = ap.parse_args()
    procs = []
    for tree in a.trees:
        env = {**os.environ, "PYTHONPATH": os.path.abspath(tree), "NUMBA_NUM_THREADS": "1"}
        cmd = [sys.executable, os.path.abspath(__file__), *a.trees, "--worker", a.controller]
        cmd += ["--seeds", str(a.seeds), "--scenario", a.scenario] + (["--robot", a.robot] if a.robot else [])
        procs.append(
            subprocess.Popen(cmd, env=env, cwd=tree, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        )
    for p in procs:
        if p.stdout.readline().strip() != "ready":
            sys.exit("a worker failed before its first trial")
    res: list[list[float]] = [[], []]
    sums: list[list[float]] = [[], []]
    digests: list[str] = ["", ""]
    for r in range(a.trials):
        for j in (0, 1) if r % 2 == 0 else (1, 0):
            procs[j].stdin.write("go\n")
            procs[j].stdin.flush()
            cpu, hexes, digests[j] = procs[j].stdout.readline().split()
            res[j].append(float(cpu))
            sums[j] = [float.fromhex(x) for x in hexes.split(",")]
        print(
            f"trial {r}: A {res[0][-1]:.5f}  B {res[1][-1]:.5f}  (load {os.getloadavg()[0]:.1f})", flush=True
        )
    for p in procs:
        p.stdin.close()
        p.wait()
    for tag, tree, x in zip("AB", a.trees, res, strict=True):
        m, md, b = statistics.mean(x), statistics.median(x), min(x)
        print(
            f"{tag} {tree}: mean {m:.5f} median {md:.5f} best {b:.5f} CPU s per simulated s ({len(x)} trials)"
        )
    ratio = [
        statistics.mean(res[1]) / statistics.mean(res[0]),
        statistics.median(res[1]) / statistics.median(res[0]),
    ]
    print(f"B / A: mean {ratio[0]:.4f} median {ratio[1]:.4f} best {min(res[1]) / min(res[0]):.4f}")
    rel = max(abs(x - y) / max(abs(x), abs(y)) if x != y else 0.0 for x, y in zip(*sums, strict=True))
    print(
        f"results: {sum(x == y for x, y in zip(*sums, strict=True))} of {len(sums[0])} sums equal, "
        f"largest relative difference {rel:.3g}; every sample's tracking error and the alarm times "
        + ("equal" if digests[0] == digests[1] else "DIFFER")
    )


if __name__ == "__main__":
    if "--worker" in sys.argv:
        argv = sys.argv
        robot = argv[argv.index("--robot") + 1] if "--robot" in argv else None
        worker(
            argv[argv.index("--worker") + 1],
            robot,
            int(argv[argv.index("--seeds") + 1]),
            argv[argv.index("--scenario") + 1],
        )
    else:
        main()
