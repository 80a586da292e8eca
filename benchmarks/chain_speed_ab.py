"""Per-sample speed of the N-joint closed loop in two source trees, trials interleaved in one run.

    python benchmarks/chain_speed_ab.py TREE_A TREE_B [--trials 12] [--controller adaptive_ct]

Starts one worker process per tree (``PYTHONPATH`` the tree, ``NUMBA_NUM_THREADS=1``, each its own
numba cache folder under ``$NUMBA_CACHE_DIR`` or ``~/.cache``, keyed by the tree's source as
usual), which loads the shipped UR5 tool-swap scenario (1 seed, one controller) and compiles or
loads the closed loop on a 0.2-s warm-up run; then asks the workers for one 20-s trial at a
time, alternating which tree goes first, and prints each trial's CPU seconds (of the thread that
ran it) per simulated second, then the mean, median and best of each tree and B / A. CPU seconds,
not wall: read them beside the load printed. Asserts nothing: a measurement.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys


def worker(name: str) -> None:
    """One trial of controller ``name`` per line on stdin; prints CPU s per simulated s."""
    import dataclasses
    import time
    from importlib import resources

    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.closed_loop.runner import run_closed_loop

    sc = load_scenario(str(resources.files("adaptive_dd.scenarios").joinpath("ur5_tool_swap.toml")))
    opts = tuple(o for o in sc.controller_options if o[0] == name)
    one = dataclasses.replace(sc, seeds=1, controllers=(name,), controller_options=opts)
    run_closed_loop(dataclasses.replace(one, duration=0.2, swap_times=(0.05, 0.1, 0.15)))
    print("ready", flush=True)
    for _ in sys.stdin:
        c0 = time.thread_time()
        res = run_closed_loop(one)
        cpu = time.thread_time() - c0
        assert not res.runs[name].failed.any(), f"{name} failed"
        print(f"{cpu / sc.duration:.6f}", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("trees", nargs=2, help="the two source trees (folders holding adaptive_dd/)")
    ap.add_argument("--trials", type=int, default=12)
    ap.add_argument("--controller", default="adaptive_ct")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    a = ap.parse_args()
    procs = []
    for tree in a.trees:
        env = {**os.environ, "PYTHONPATH": os.path.abspath(tree), "NUMBA_NUM_THREADS": "1"}
        cmd = [sys.executable, os.path.abspath(__file__), *a.trees, "--worker", a.controller]
        procs.append(
            subprocess.Popen(cmd, env=env, cwd=tree, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        )
    for p in procs:
        if p.stdout.readline().strip() != "ready":
            sys.exit("a worker failed before its first trial")
    res: list[list[float]] = [[], []]
    for r in range(a.trials):
        for j in (0, 1) if r % 2 == 0 else (1, 0):
            procs[j].stdin.write("go\n")
            procs[j].stdin.flush()
            res[j].append(float(procs[j].stdout.readline()))
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


if __name__ == "__main__":
    if "--worker" in sys.argv:
        worker(sys.argv[sys.argv.index("--worker") + 1])
    else:
        main()
