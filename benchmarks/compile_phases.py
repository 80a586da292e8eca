"""The critical path of a cold-cache N-joint benchmark's compilation, phase by phase, in CPU seconds.

Usage (from the repository's root; a fresh numba cache folder, removed afterwards)::

    PYTHONPATH=. python benchmarks/compile_phases.py [SCENARIO]   # default: the UR5 tool swap

On a cold cache ``adaptive-dd benchmark`` on an N-joint arm compiles in two processes
(:class:`adaptive_dd._numba_cache.Compiling`). This script times each phase in CPU seconds
(robust on a shared machine, unlike wall time; read them beside the load it prints):

* ``P2``: the second process (:func:`adaptive_dd.closed_loop.precompile.second_process`) run as
  a child, CPU s of that process when it is ready (the plant's integrator and the law's pieces in
  the cache, ``P2READY``; its imports and its loading of the scenario included, which here
  compiles the scenario's kernels too: the benchmark's own second process finds them cached,
  its first process having loaded the scenario before starting it) and at its end (``P2END``);
* ``P1a``: the first process's estimator step
  (:func:`~adaptive_dd.closed_loop.chain_choices.compile_estimator`), run meanwhile;
* ``P1b``: after both, the benchmark itself in this process (``--seeds 2``): the closed loop's
  compilation and any kernel it compiled that the phases before did not leave in the cache
  (nested compilations over 0.3 CPU s listed), then numba's pass times (wall s) of the loop.

The benchmark's critical path on 2 idle cores is about ``max(P1a, P2READY - scenario kernels) +
P1b``; the figure it prints (``compiled the kernels in N s``: time inside compilations in the
first process) about ``P1a + P1b``. Asserts nothing: a measurement.
"""

from __future__ import annotations

import contextlib
import io
import os
import shutil
import subprocess
import sys
import tempfile
import time

CACHE = tempfile.mkdtemp(prefix="adaptive_dd_phases_")
os.environ["NUMBA_CACHE_DIR"] = CACHE
os.environ["ADAPTIVE_DD_COMPILE_HELPER"] = "0"  # the phases are run here, one after the other

CHILD = r"""
import sys, time
from adaptive_dd.closed_loop import precompile
import builtins
def told(*a, **k):
    if a and a[0] == precompile.READY:
        sys.stderr.write(f"P2READY {time.process_time():.1f}\n")
    builtins.print(*a, **k)
precompile.print = told
precompile.second_process(sys.argv[1])
sys.stderr.write(f"P2END {time.process_time():.1f}\n")
"""


def main() -> None:
    from numba.core import event

    src = sys.argv[1] if len(sys.argv) > 1 else "adaptive_dd/scenarios/ur5_tool_swap.toml"
    path = os.pathsep.join(filter(None, (os.getcwd(), os.environ.get("PYTHONPATH"))))
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, src], env={**os.environ, "PYTHONPATH": path},
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.closed_loop.glue import chain_loop_block, compile_estimator

    sc = load_scenario(src)
    c0 = time.process_time()
    compile_estimator(sc.arm)
    p1a = time.process_time() - c0
    err = child.communicate()[1]
    told = " ".join(line for line in err.splitlines() if line.startswith("P2"))
    print(f"P2: {told} (exit {child.returncode})")
    print(f"P1a compile_estimator CPU {p1a:.1f}")

    class Listener(event.Listener):
        def __init__(self) -> None:
            self.stack, self.rows, self.nested = [], [], []

        def on_start(self, ev) -> None:
            self.stack.append([time.process_time(), 0.0])

        def on_end(self, ev) -> None:
            t0, nested = self.stack.pop()
            incl = time.process_time() - t0
            if self.stack:
                self.stack[-1][1] += incl
            name = ev.data["dispatcher"].py_func.__qualname__
            if not self.stack:
                self.rows.append((name, round(incl, 1)))
            elif incl - nested > 0.3:
                self.nested.append((name, round(incl - nested, 1)))

    from adaptive_dd.cli import main as cli_main

    out, listener = tempfile.mkdtemp(), Listener()
    with event.install_listener("numba:compile", listener), contextlib.redirect_stdout(io.StringIO()):
        cli_main(["benchmark", src, "--seeds", "2", "--no-progress", "--out", out])
    shutil.rmtree(out, ignore_errors=True)
    print("P1b compilations (CPU s):", [r for r in listener.rows if r[1] > 0.3])
    print("P1b nested, self > 0.3:", listener.nested)
    for cres in chain_loop_block.overloads.values():
        for pipe, passes in (cres.metadata or {}).get("pipeline_times", {}).items():
            big = [(k.split("_", 1)[1], round(v.init + v.run + v.finalize, 1)) for k, v in passes.items()]
            print(f"chain_loop_block {pipe} pass wall s:", [b for b in big if b[1] > 0.3])
    print(f"load {os.getloadavg()[0]:.1f}")
    shutil.rmtree(CACHE, ignore_errors=True)


if __name__ == "__main__":
    main()
