"""Where one closed-loop trial's time goes, by compiled function: a sampling profile with names.

    python benchmarks/profile_loop.py                      # the UR5 tool swap, adaptive_ct
    python benchmarks/profile_loop.py FILE --controller ct_oracle --top 20
    python benchmarks/profile_loop.py --annotate adaptive_dd.plant.chain_rk4._rk4

``--annotate NAME`` (a compiled function's name as the profile prints it) also bins the samples
that land in that function by instruction: its code is read from the process
(``ctypes.string_at``) and disassembled by ``objdump``, and the shares of its own time per
mnemonic and its hottest instructions are printed (a sample on a ``call`` is mostly the call
itself; ``mov`` around it, its arguments). That is how the estimator step's reference counts
were found: 45 % of its time on 2293 indirect calls to them (``docs/changelog.md``).

Needs Linux ``perf``. numba's compiled code carries no symbols ``perf`` can read, so the script
compiles the kernels afresh (a temporary ``NUMBA_CACHE_DIR``: a library loaded from the cache has
no module to list its functions; about 2-3 minutes), writes ``/tmp/perf-PID.map`` (each compiled
function's address from ``library.get_pointer_to_function``), then records the process with
``perf record -p PID`` while it runs three trials of one seed (compilation excluded), and prints
the functions' shares of the samples, with their module-qualified names
(``adaptive_dd.plant.chain_rk4._rk4``), and the share of numba's reference counting
(``NRT_incref`` / ``NRT_decref``). Self time only: numba's code keeps no frame pointers.

A sampling profile's shares are where the samples land, not what removing a function would save:
the reference counts' 25 % of a UR5 ``adaptive_ct`` trial, taken to 2.5 % by borrowed views, left
its time unchanged (docs/changelog.md). Asserts nothing.
"""

from __future__ import annotations

import argparse
import dataclasses
import gc
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from importlib import resources

_FRESH = "ADAPTIVE_DD_PROFILE_FRESH_CACHE"


def short_name(mangled: str) -> str:
    """``adaptive_dd.plant.chain_rk4._rk4`` for numba's ``_ZN11adaptive_dd5plant9chain_rk44_rk4B...``
    (the Itanium-style length-prefixed parts up to the ABI tag); other names as they are."""
    if not mangled.startswith("_ZN"):
        return mangled
    parts, k = [], 3
    while k < len(mangled) and mangled[k].isdigit():
        m = re.match(r"\d+", mangled[k:])
        n = int(m.group(0))
        k += len(m.group(0))
        parts.append(mangled[k : k + n])
        k += n
    return ".".join(parts) if parts else mangled


def compiled_symbols() -> list[tuple[int, str]]:
    """``(address, name)`` of every function of every compiled library in this process that has
    its module (those compiled in it, not loaded from the cache), sorted by address."""
    from numba.core.dispatcher import Dispatcher

    seen, out = set(), set()
    for obj in gc.get_objects():
        try:
            if not isinstance(obj, Dispatcher):
                continue
        except ReferenceError:  # a weak proxy whose object is gone
            continue
        for cres in obj.overloads.values():
            lib = cres.library
            if id(lib) in seen:
                continue
            seen.add(id(lib))
            try:
                functions = list(lib._final_module.functions)
            except Exception:  # loaded from the cache: no module
                continue
            for f in functions:
                if f.is_declaration:
                    continue
                addr = lib.get_pointer_to_function(f.name)
                if addr:
                    out.add((int(addr), f.name))
    return sorted(out)


def write_perf_map(symbols: list[tuple[int, str]], path: str) -> int:
    """Write ``perf``'s JIT map (``START SIZE NAME`` in hex); each function runs to the next one's
    start (at most 1 MiB). Returns the number of lines."""
    with open(path, "w") as fh:
        for (a, name), nxt in zip(symbols, [*symbols[1:], (symbols[-1][0] + 4096, "")], strict=True):
            fh.write(f"{a:x} {min(nxt[0] - a, 1 << 20):x} {short_name(name)}\n")
    return len(symbols)


def _trial(scenario_path: str, name: str):
    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.closed_loop.runner import run_closed_loop

    sc = load_scenario(scenario_path)
    opts = tuple(o for o in sc.controller_options if o[0] == name)
    one = dataclasses.replace(sc, seeds=1, controllers=(name,), controller_options=opts)
    warm = tuple(0.05 * (k + 1) for k in range(len(sc.swap_times)))
    run_closed_loop(dataclasses.replace(one, duration=0.05 * (len(warm) + 1), swap_times=warm))
    return lambda: run_closed_loop(one)


def instruction_shares(asm: str, offsets: list[int], top: int = 10) -> tuple[list, list]:
    """From ``objdump -D`` text of one function (addresses from 0) and the offsets of the samples
    that landed in it: ``(mnemonic, share)`` sorted by share, and the ``top`` hottest
    ``(offset, instruction, share)``. Shares of the samples in the function."""
    counts: dict[int, int] = {}
    for off in offsets:
        counts[off] = counts.get(off, 0) + 1
    total = max(sum(counts.values()), 1)
    by_mn: dict[str, int] = {}
    hot = []
    for line in asm.splitlines():
        m = re.match(r"\s*([0-9a-f]+):\s+(?:[0-9a-f]{2} )+\s*(\S.*)", line)
        if not m:
            continue
        off, text = int(m.group(1), 16), m.group(2).strip()
        c = counts.get(off, 0)
        if c:
            by_mn[text.split()[0]] = by_mn.get(text.split()[0], 0) + c
            hot.append((off, text, c / total))
    shares = sorted(((k, v / total) for k, v in by_mn.items()), key=lambda kv: -kv[1])
    return shares, sorted(hot, key=lambda h: -h[2])[:top]


def _annotate(name: str, symbols: list[tuple[int, str]], data: str) -> None:
    """Print :func:`instruction_shares` of the compiled function ``name`` from ``perf.data``."""
    import ctypes

    starts = sorted(a for a, _ in symbols)
    mine = [a for a, n in symbols if short_name(n) == name]
    if not mine:
        print(f"--annotate: no compiled function named {name} (names as the profile prints them)")
        return
    a0 = mine[0]
    size = min((a for a in starts if a > a0), default=a0 + 4096) - a0
    out = subprocess.run(
        ["perf", "script", "-i", data, "-F", "ip"], capture_output=True, text=True, check=False
    )
    offsets = [int(x, 16) - a0 for x in out.stdout.split() if a0 <= int(x, 16) < a0 + size]
    with tempfile.NamedTemporaryFile(suffix=".bin") as fh:
        fh.write(ctypes.string_at(a0, size))
        fh.flush()
        asm = subprocess.run(
            ["objdump", "-D", "-b", "binary", "-m", "i386:x86-64", fh.name],
            capture_output=True,
            text=True,
            check=False,
        ).stdout
    shares, hot = instruction_shares(asm, offsets)
    print(f"{name}: {len(offsets)} samples in its {size} bytes; share of its own time by mnemonic:")
    print("  " + ", ".join(f"{k} {100 * v:.1f} %" for k, v in shares[:10]))
    print("  hottest instructions:")
    for off, text, v in hot:
        print(f"    {100 * v:5.1f} %  +{off:x}  {text}")


def _record(run, annotate: str | None = None, symbols=None) -> tuple[str, float]:
    """``perf report``'s text of three runs of ``run`` recorded on this process, and one run's wall
    time [s]; with ``annotate``, :func:`_annotate` of that function first (sampled 10x as often)."""
    with tempfile.TemporaryDirectory() as tmp:
        data = os.path.join(tmp, "perf.data")
        rec = subprocess.Popen(
            ["perf", "record", "-F", "20000" if annotate else "2000", "-p", str(os.getpid()), "-o", data],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        time.sleep(1.0)
        t0 = time.perf_counter()
        for _ in range(3):
            run()
        wall = (time.perf_counter() - t0) / 3
        rec.send_signal(signal.SIGINT)
        rec.wait()
        if annotate:
            _annotate(annotate, symbols, data)
        rep = subprocess.run(
            ["perf", "report", "-i", data, "--no-children", "--sort", "sym", "--stdio"],
            capture_output=True,
            text=True,
            check=False,
        )
    return rep.stdout, wall


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scenario", nargs="?", default=None, help="scenario file (default: the UR5 tool swap)")
    ap.add_argument("--controller", default="adaptive_ct")
    ap.add_argument("--top", type=int, default=15, help="functions printed")
    ap.add_argument(
        "--annotate",
        metavar="NAME",
        help="also bin one compiled function's samples by instruction (its name as printed)",
    )
    args = ap.parse_args()
    if shutil.which("perf") is None:
        sys.exit("profile_loop: needs Linux perf (apt install linux-perf); not found on PATH")
    if os.environ.get(_FRESH) != "1":  # compile afresh in a child process, the cache removed after
        with tempfile.TemporaryDirectory() as tmp:
            env = {**os.environ, "NUMBA_CACHE_DIR": tmp, _FRESH: "1"}
            sys.exit(subprocess.call([sys.executable, *sys.argv], env=env))
    path = args.scenario or str(resources.files("adaptive_dd.scenarios").joinpath("ur5_tool_swap_exact.toml"))
    print(f"compiling {args.controller} on {path} afresh (a minute or three) ...", flush=True)
    run = _trial(path, args.controller)
    run()
    symbols = compiled_symbols()
    if not symbols:
        sys.exit("profile_loop: no compiled function to map (is NUMBA_DISABLE_JIT set?)")
    pmap = f"/tmp/perf-{os.getpid()}.map"
    n = write_perf_map(symbols, pmap)
    try:
        rep, wall = _record(run, args.annotate, symbols)
    finally:
        os.remove(pmap)
    rows = [ln for ln in rep.splitlines() if ln.strip() and not ln.startswith("#")]
    print(f"{n} compiled functions mapped; one trial {wall:.3f} s wall; self time by function:")
    nrt = 0.0
    for ln in rows:
        m = re.match(r"\s*([\d.]+)%\s+\[\S+\]\s+(.*)", ln)
        if m and m.group(2).startswith("NRT_"):
            nrt += float(m.group(1))
    for ln in rows[: args.top]:
        print("  " + ln.strip())
    print(f"  numba's reference counting (NRT_incref, NRT_decref): {nrt:.1f} %")


if __name__ == "__main__":
    main()
