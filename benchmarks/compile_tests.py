"""Where a cold-cache test run's compilation goes: per compiled function and per test, in CPU seconds.

Usage (from the repository's root)::

    python benchmarks/compile_tests.py                  # the README's test line (pytest's addopts)
    python benchmarks/compile_tests.py -- tests/test_closed_loop.py -n 0 --top 20

Runs ``python -m pytest -q`` (arguments after ``--`` passed on) with ``NUMBA_CACHE_DIR`` set to a
fresh temporary folder (a cold cache, removed afterwards) and this file loaded as a pytest plug-in
in every process (``-p compile_tests``, xdist's workers included): a listener on numba's
``numba:compile`` events records each compilation (a cache miss: loads raise none) with its
argument types, the CPU seconds inside it with its callees (``incl``) and without them
(``self``), and the test that was running. Prints, over all processes: the run's wall time, the
CPU seconds of the processes and of compilation, one row per compiled function (count,
signatures, incl, self; largest self first), the tests whose compilations took the most CPU and
the tests and test files whose own CPU apart from those compilations (each test's process CPU
from its set-up to its tear-down, less the compilations it started) is the largest; a test run
in a subprocess (the CLI's, a script's) is not counted there.
CPU seconds (``time.process_time``), not wall time: other work on a shared machine stretches the
wall clock far more; read them beside the load printed. Asserts nothing: a measurement.
"""

from __future__ import annotations

import json
import os
import time

_OUT = os.environ.get("ADAPTIVE_DD_COMPILE_RECORD")
_test = ["(collection)"]
_cpu: list = []  # (test, CPU s of this process from its set-up to its tear-down)


def _listener():
    from numba.core import event

    class Recorder(event.Listener):
        def __init__(self) -> None:
            self.stack: list[list] = []
            self.done: list[dict] = []

        def on_start(self, ev) -> None:
            d = ev.data["dispatcher"]
            name = f"{d.py_func.__module__}.{d.py_func.__qualname__}"
            self.stack.append([name, [str(a) for a in ev.data["args"]], time.process_time(), 0.0])

        def on_end(self, ev) -> None:
            name, args, t0, nested = self.stack.pop()
            incl = time.process_time() - t0
            if self.stack:
                self.stack[-1][3] += incl
            row = {"name": name, "args": args, "incl": incl, "self": incl - nested}
            self.done.append({**row, "depth": len(self.stack), "test": _test[0]})

    rec = Recorder()
    event.register("numba:compile", rec)  # kept for the whole process (a context manager would end)
    return rec


_rec = _listener() if _OUT else None


def _protocol(item, nextitem):
    _test[0] = item.nodeid
    t0 = time.process_time()
    yield
    _cpu.append((item.nodeid, time.process_time() - t0))


try:  # a hook wrapper: pytest is importable wherever this plug-in is loaded
    import pytest

    pytest_runtest_protocol = pytest.hookimpl(hookwrapper=True)(_protocol)
except ImportError:  # pragma: no cover - the report alone
    pass


def pytest_sessionfinish(session):
    if _rec is not None:
        name = f"{os.environ.get('PYTEST_XDIST_WORKER', 'main')}-{os.getpid()}.json"
        with open(os.path.join(_OUT, name), "w") as f:
            json.dump({"done": _rec.done, "cpu": time.process_time(), "tests": _cpu}, f)


def _report(folder: str, top: int) -> None:
    from collections import defaultdict

    done, cpu, tests = [], 0.0, []
    for name in sorted(os.listdir(folder)):
        with open(os.path.join(folder, name)) as f:
            j = json.load(f)
        cpu += j["cpu"]
        done += j["done"]
        tests += j.get("tests", [])
    outer = [e for e in done if e["depth"] == 0]
    print(f"test processes' CPU {cpu:.1f} s, of which compiling {sum(e['incl'] for e in outer):.1f} s "
          f"({len(done)} compilations)")  # fmt: skip
    rows: dict = defaultdict(lambda: [0, set(), 0.0, 0.0])
    for e in done:
        r = rows[e["name"]]
        r[0] += 1
        r[1].add(tuple(e["args"]))
        r[2] += e["incl"]
        r[3] += e["self"]
    print(f"{'count':>5} {'sigs':>4} {'incl':>6} {'self':>6}  function (CPU s)")
    for name, (n, sigs, incl, own) in sorted(rows.items(), key=lambda kv: -kv[1][3])[:top]:
        print(f"{n:5d} {len(sigs):4d} {incl:6.1f} {own:6.1f}  {name}")
    per_test: dict = defaultdict(float)
    for e in outer:
        per_test[e["test"]] += e["incl"]
    print("\ntests by the CPU seconds of the compilations they started")
    for t, v in sorted(per_test.items(), key=lambda kv: -kv[1])[:top]:
        print(f"{v:6.1f}  {t}")
    own = [(t, c - per_test.get(t, 0.0)) for t, c in tests]
    print(f"\ntests by their own CPU seconds apart from compilation ({sum(v for _, v in own):.1f} s in all)")
    for t, v in sorted(own, key=lambda kv: -kv[1])[:top]:
        print(f"{v:6.1f}  {t}")
    per_file: dict = defaultdict(float)
    for t, v in own:
        per_file[t.split("::")[0]] += v
    print("\ntest files by their tests' own CPU seconds apart from compilation")
    for t, v in sorted(per_file.items(), key=lambda kv: -kv[1])[:top]:
        print(f"{v:6.1f}  {t}")


def main() -> None:
    import argparse
    import shutil
    import subprocess
    import sys
    import tempfile

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--top", type=int, default=30, help="rows of each table")
    p.add_argument("pytest_args", nargs="*", help="passed on to pytest (after --)")
    a = p.parse_args()
    cache, out = tempfile.mkdtemp(prefix="adaptive_dd_cold_"), tempfile.mkdtemp(prefix="adaptive_dd_rec_")
    here = os.path.dirname(os.path.abspath(__file__))
    path = os.pathsep.join(filter(None, (os.getcwd(), here, os.environ.get("PYTHONPATH"))))
    env = {**os.environ, "NUMBA_CACHE_DIR": cache, "ADAPTIVE_DD_COMPILE_RECORD": out, "PYTHONPATH": path}
    t0, c0 = time.perf_counter(), os.times()
    rc = subprocess.call(
        [sys.executable, "-m", "pytest", "-q", "-p", "compile_tests", *a.pytest_args], env=env
    )
    wall, c1 = time.perf_counter() - t0, os.times()
    children = (c1.children_user - c0.children_user) + (c1.children_system - c0.children_system)
    print(f"\npytest exit {rc}; wall {wall:.0f} s; CPU of pytest and its children {children:.1f} s; "
          f"load {os.getloadavg()[0]:.1f}")  # fmt: skip
    _report(out, a.top)
    shutil.rmtree(cache, ignore_errors=True)
    shutil.rmtree(out, ignore_errors=True)
    sys.exit(rc)


if __name__ == "__main__":
    main()
