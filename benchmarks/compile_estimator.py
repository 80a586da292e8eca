"""Cold compilation of the N-joint closed loop and the estimator run alone, in one process.

    NUMBA_CACHE_DIR=$(mktemp -d) PYTHONPATH=TREE python benchmarks/compile_estimator.py

Runs a 0.01-s UR5 ``adaptive_ct`` closed loop (1 seed, no payload change), then the estimator
alone on the same arm (``run_online`` over 4 samples, one ``est_step``), on whatever numba's cache
holds (give it a fresh ``NUMBA_CACHE_DIR`` for a cold figure; ``PYTHONPATH`` picks the source tree,
so one copy of this file measures any tree). Prints the CPU seconds of each part, of all the
top-level compilations (callees included) and, per compiled function, the CPU seconds of its
own compilation (callees excluded; above 0.5 s), from numba's ``numba:compile`` events. CPU
seconds, not wall: read them beside the machine's load. Asserts nothing: a measurement.
"""

import time
import tomllib
from collections import defaultdict
from importlib import resources

import numpy as np
from numba.core import event

rows, stack = defaultdict(float), []


class R(event.Listener):
    """Each compilation's CPU seconds, with and without its callees."""

    def on_start(self, ev):
        d = ev.data["dispatcher"]
        stack.append((d.py_func.__qualname__, time.process_time(), [0.0]))

    def on_end(self, ev):
        name, t0, nested = stack.pop()
        incl = time.process_time() - t0
        if stack:
            stack[-1][2][0] += incl
        rows[("self", name)] += incl - nested[0]
        if not stack:
            rows[("top", name)] += incl


event.register("numba:compile", R())
import adaptive_dd  # noqa: E402 (after the listener)
from adaptive_dd.benchmark.scenario import parse_scenario  # noqa: E402 (after the listener)
from adaptive_dd.closed_loop.runner import run_closed_loop  # noqa: E402 (after the listener)
from adaptive_dd.identification import online  # noqa: E402 (after the listener)

print(adaptive_dd.__file__)
path = str(resources.files("adaptive_dd.scenarios").joinpath("ur5_tool_swap.toml"))
data = tomllib.loads(open(path, encoding="utf-8").read())
data["run"] = {**data["run"], "duration": 0.01, "seeds": 1, "controllers": ["adaptive_ct"]}
data["payload"], data["reference"]["ramp"] = [], 0.2
data["controllers"] = {k: v for k, v in data.get("controllers", {}).items() if k in ("adaptive_ct",)}
sc = parse_scenario(data, "test.toml", name="ur5_tool_swap")
c0 = time.process_time()
run_closed_loop(sc)
c1 = time.process_time()
z = np.zeros((4, sc.n_joints))
cfg = online.OnlineConfig(sample_period=sc.sample_period)
online.run_online(sc.arm, cfg, z, z, z)
c, s = online.est_init(cfg, sc.arm, 2)
online.est_step(c, s, z[:2], z[:2], z[:2])
c2 = time.process_time()
print(f"closed loop CPU {c1 - c0:.1f} s; estimator alone after it {c2 - c1:.1f} s", end="; ")
print(f"process {time.process_time():.1f} s")
top = sum(v for (k, _), v in rows.items() if k == "top")
print(f"compiling (top level, callees included) {top:.1f} CPU s")
for (k, n), v in sorted(rows.items(), key=lambda kv: -kv[1]):
    if k == "self" and v > 0.5:
        print(f"  self {v:6.1f}  {n}")
