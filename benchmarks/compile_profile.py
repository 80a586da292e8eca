"""Which numba kernels a cold-cache benchmark compiles, how often, and for how long.

Usage::

    PYTHONPATH=. python benchmarks/compile_profile.py                         # the two-link default, 2 seeds
    PYTHONPATH=. python benchmarks/compile_profile.py adaptive_dd/scenarios/ur5_tool_swap.toml --seeds 2
    PYTHONPATH=. python benchmarks/compile_profile.py SCENARIO --top 40 --why

Runs ``adaptive-dd benchmark SCENARIO --seeds N`` in this process with ``NUMBA_CACHE_DIR`` set to
a fresh temporary folder (a cold cache; removed afterwards) and a listener on numba's
``numba:compile`` events. Prints, per compiled function: the number of specialisations compiled,
the CPU seconds inside its compilations (``incl``: nested compilations of the functions it calls
included) and the CPU seconds of its own (``self``: nested ones subtracted), largest ``self``
first; then the wall time of the whole command, the CPU time inside at least one compilation, and
this process's CPU time (user + sys). CPU time (``time.process_time``), not wall time: other work
on a shared machine slows the wall clock, not the CPU seconds compilation needs (it runs in one
thread, before the trials start). ``--keep-cache`` keeps the filled folder (printed) for a timed
run of the same kernels after (``NUMBA_CACHE_DIR=FOLDER python benchmarks/speed_arm.py``).
With ``--why``, every function compiled more than once is listed
with the argument types that differ between its specialisations (int vs float, readonly vs
writable, C vs A layout, ...). Asserts nothing: a measurement, to be read beside ``uptime``.

On an N-joint arm the benchmark compiles in two processes on a cold cache
(``adaptive_dd._numba_cache.Compiling``): the table is this process's (the critical path: the
estimator's step and the closed loop); ``ADAPTIVE_DD_COMPILE_HELPER=0`` compiles everything here
(the total CPU cost, each kernel in the table).
"""

from __future__ import annotations

import os
import sys
import tempfile

os.environ["NUMBA_CACHE_DIR"] = tempfile.mkdtemp(prefix="adaptive_dd_numba_")

import argparse
import contextlib
import io
import shutil
import time
from collections import defaultdict

from numba.core import event


class _Listener(event.Listener):
    """Per compile event: name, argument types, start and end; nested events form a stack."""

    def __init__(self) -> None:
        self.stack: list[list] = []
        self.done: list[tuple] = []  # name, args, incl, self, depth, caller

    def on_start(self, ev) -> None:
        d = ev.data["dispatcher"]
        name = f"{d.py_func.__module__}.{d.py_func.__qualname__}"
        caller = self.stack[-1][0] if self.stack else "(Python)"
        self.stack.append([name, tuple(ev.data["args"]), time.process_time(), 0.0, caller])

    def on_end(self, ev) -> None:
        name, args, t0, nested, caller = self.stack.pop()
        incl = time.process_time() - t0
        if self.stack:
            self.stack[-1][3] += incl
        self.done.append((name, args, incl, incl - nested, len(self.stack), caller))


def _differences(sigs: list[tuple]) -> list[str]:
    """Per argument position whose type differs between the specialisations: 'arg k: a | b'."""
    out = []
    if len({len(s) for s in sigs}) > 1:
        return ["different numbers of arguments: " + " | ".join(str(len(s)) for s in sigs)]
    for k in range(len(sigs[0])):
        kinds = [str(s[k]) for s in sigs]
        if len(set(kinds)) > 1:
            shown = " | ".join(x if len(x) < 90 else x[:87] + "..." for x in kinds)
            out.append(f"arg {k}: {shown}")
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scenario", nargs="?", default=None, help="scenario TOML (default: two-link payload_swap)")
    p.add_argument("--seeds", type=int, default=2)
    p.add_argument("--top", type=int, default=25, help="rows of the table (largest self time first)")
    p.add_argument("--why", action="store_true", help="list the differing argument types of repeated kernels")
    p.add_argument(
        "--keep-cache",
        action="store_true",
        help="keep the filled cache folder (printed)",
    )
    a = p.parse_args()

    from adaptive_dd.cli import main as cli_main

    argv = ["benchmark", *([a.scenario] if a.scenario else []), "--seeds", str(a.seeds), "--no-progress"]
    out = tempfile.mkdtemp(prefix="adaptive_dd_out_")
    argv += ["--out", out]
    listener = _Listener()
    cpu0, t0 = os.times(), time.perf_counter()
    with event.install_listener("numba:compile", listener), contextlib.redirect_stdout(io.StringIO()):
        rc = cli_main(argv)
    wall, cpu1 = time.perf_counter() - t0, os.times()
    shutil.rmtree(out, ignore_errors=True)
    if not a.keep_cache:
        shutil.rmtree(os.environ["NUMBA_CACHE_DIR"], ignore_errors=True)

    rows: dict[str, list] = defaultdict(lambda: [0, 0.0, 0.0, [], []])
    for name, args, incl, own, _depth, caller in listener.done:
        r = rows[name]
        r[0], r[1], r[2] = r[0] + 1, r[1] + incl, r[2] + own
        r[3].append(args)
        r[4].append(caller.rsplit(".", 1)[-1])
    top_level = sum(ev[2] for ev in listener.done if ev[4] == 0)
    import adaptive_dd

    load = os.getloadavg()[0]
    cmd = " ".join(argv[:-2])
    import numba

    opt = f"LLVM -O{int(numba.config.OPT)}"
    helper = os.environ.get("ADAPTIVE_DD_COMPILE_HELPER", "1") != "0"
    procs = "two processes on an N-joint arm (this one's table)" if helper else "one process"
    print(f"adaptive-dd {cmd} (exit {rc}); {adaptive_dd.__file__}; cold cache; {opt}; load {load:.2f}")
    print(f"compiled in {procs}")
    if a.keep_cache:
        print(f"cache kept: NUMBA_CACHE_DIR={os.environ['NUMBA_CACHE_DIR']}")
    print(f"{'count':>5} {'incl':>6} {'self':>6}  function (CPU seconds)")
    for name, (n, incl, own, *_) in sorted(rows.items(), key=lambda kv: -kv[1][2])[: a.top]:
        print(f"{n:5d} {incl:6.1f} {own:6.1f}  {name}")
    repeated = {k: v for k, v in rows.items() if v[0] > 1}
    print(
        f"{len(rows)} functions, {len(listener.done)} compilations "
        f"({len(repeated)} functions compiled more than once, "
        f"{sum(v[0] - 1 for v in repeated.values())} extra compilations)"
    )
    cpu = (cpu1.user - cpu0.user) + (cpu1.system - cpu0.system)
    print(f"wall {wall:.1f} s; CPU (user+sys) {cpu:.1f} s, of which compiling {top_level:.1f} s")
    if a.why:
        for name, (n, _incl, own, sigs, callers) in sorted(repeated.items(), key=lambda kv: -kv[1][2]):
            print(f"\n{name}: {n} specialisations, {own:.1f} s self; first called from {' | '.join(callers)}")
            for line in _differences(sigs):
                print("   ", line)
    sys.exit(rc)


if __name__ == "__main__":
    main()
