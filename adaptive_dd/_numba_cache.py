"""Where numba caches the compiled kernels: one folder per state of the kernels' source.

numba's own cache (``cache=True``) is invalidated by the source file of the function it
compiled, not by the files of the functions that one calls: after an edit of, say, the
estimator kernel, the closed loop that inlines it would silently run the old code from
``__pycache__``. Keying the cache folder by a hash of every source file compiled code can
depend on rules that out (a changed file gives a fresh folder and one compilation). Those files
(:func:`kernel_sources`) are the modules that define compiled functions (``@njit``, ``@overload``,
...) or the ``NamedTuple`` records passed to them, every package module they import (at the top
or inside a function, directly or through another), the package's ``__init__.py`` and this file;
an edit elsewhere (the command line, the reports, the docs' examples) keeps the compiled kernels.
The folder is ``$XDG_CACHE_HOME/adaptive_dd/numba/<hash>`` (``~/.cache`` by default), or
``$NUMBA_CACHE_DIR/adaptive_dd/<hash>`` when that variable is set (keyed there too: a cache folder
shared across edits would otherwise serve stale kernels); the 8 newest are kept.
"""

from __future__ import annotations

import contextvars
import hashlib
import os
import re
import shutil
import time
from contextlib import contextmanager
from pathlib import Path

from numba.core import event

KEEP = 8

_COMPILES = re.compile(
    r"@(?:numba\.)?(?:njit|jit|overload\w*|register_jitable|intrinsic|vectorize|guvectorize|jitclass)\b"
    r"|\b(?:numba\.)?n?jit\("
)
"""Text of a module that defines compiled code: a decorator, or ``njit(...)`` called on a function
(the plug-ins' kernels and loop are compiled so)."""
_RECORDS = re.compile(r"\bNamedTuple\b|\bnamedtuple\(")
"""Text of a module that may define a record type compiled code receives (its fields are read by
position in the compiled code)."""
_IMPORT = re.compile(
    r"^[ \t]*(?:from[ \t]+(\.*[\w.]*)[ \t]+import[ \t]+(\([^)]*\)|[^\n]*)|import[ \t]+([^\n]*))", re.M
)


def _module_name(package: Path, f: Path) -> str:
    parts = list(f.relative_to(package.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imported(name: str, is_package: bool, text: str, modules: dict) -> set[str]:
    """The package's modules that module ``name`` imports anywhere in its text (at the top, in a
    function, or in a docstring's example: too many is safe, too few would not be)."""
    here = name.split(".") if is_package else name.split(".")[:-1]
    found = set()
    for base, what, plain in _IMPORT.findall(text):
        if plain:
            names = [w.split(" as ")[0].strip() for w in plain.split("#")[0].split(",")]
        else:
            if base.startswith("."):
                level = len(base) - len(base.lstrip("."))
                rest = base[level:]
                base = ".".join([*here[: len(here) - level + 1], *([rest] if rest else [])])
            items = what.split("#")[0].strip("()").replace("\n", " ").split(",")
            names = [base, *(f"{base}.{w.split(' as ')[0].strip()}" for w in items if w.strip())]
        # the module named (``from a.b import c``: a.b, and a.b.c if c is a module); not the
        # packages above it, whose __init__ runs but whose names the importer does not read
        found |= set(names) & modules.keys()
    return found


def kernel_sources(package: Path) -> list[Path]:
    """The package's ``.py`` files that compiled code can depend on (module docstring), sorted:
    the modules defining compiled code and, recursively, the package modules they import; the
    modules defining records (``NamedTuple``); the package's ``__init__.py`` and this file."""
    modules = {_module_name(package, f): f for f in package.rglob("*.py")}
    texts = {m: f.read_text(encoding="utf-8", errors="replace") for m, f in modules.items()}
    names = ("__init__.py", Path(__file__).name)
    setup = {m for m, f in modules.items() if f.parent == package and f.name in names}
    keep = setup | {m for m, t in texts.items() if _RECORDS.search(t)}
    todo = [m for m, t in texts.items() if _COMPILES.search(t) and m not in setup]
    seen: set[str] = set()
    while todo:
        m = todo.pop()
        if m not in seen:
            seen.add(m)
            todo.extend(_imported(m, modules[m].name == "__init__.py", texts[m], modules) - seen)
    return sorted(modules[m] for m in seen | keep)


def source_hash(package: Path) -> str:
    """SHA-1 of the files of :func:`kernel_sources` (names and contents), 16 hex digits."""
    h = hashlib.sha1()
    for f in kernel_sources(package):
        h.update(f.relative_to(package).as_posix().encode())
        h.update(f.read_bytes())
    return h.hexdigest()[:16]


def configure() -> str | None:
    """Point numba's cache at the folder of this source state; returns it (None if left alone: the
    folder cannot be written)."""
    _inline_fresh_ir_in_place()
    package = Path(__file__).resolve().parent
    if os.environ.get("NUMBA_CACHE_DIR"):  # the user's folder, keyed inside it
        base = Path(os.environ["NUMBA_CACHE_DIR"]) / "adaptive_dd"
    else:
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "adaptive_dd" / "numba"
    folder = base / source_hash(package)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        if not os.access(folder, os.W_OK):
            return None
    except OSError:
        return None
    import numba

    numba.config.CACHE_DIR = str(folder)
    _lock_index_writes()
    _lock_compilations()
    try:
        old = sorted((p for p in base.iterdir() if p.is_dir()), key=lambda p: p.stat().st_mtime)
        for p in old[:-KEEP]:
            if p != folder:
                shutil.rmtree(p, ignore_errors=True)
    except OSError:
        pass
    return str(folder)


def _lock_index_writes() -> None:
    """Make numba's cache writes safe between processes: each write of a kernel's index reads
    the index, adds its entry and writes it back, so two processes adding different
    specialisations of one kernel at once could lose one of them (or give both the same data
    file). Each write is done holding an exclusive lock on ``.lock`` in the cache folder
    (``fcntl.flock``; where it is missing, as on Windows, numba's own writes are left alone)."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows
        return
    from numba.core.caching import IndexDataCacheFile

    save = IndexDataCacheFile.save
    if getattr(save, "_adaptive_dd_locked", False):
        return

    def locked_save(self, key, data):
        with open(os.path.join(self._cache_path, ".lock"), "a") as f:
            fcntl.flock(f, fcntl.LOCK_EX)
            try:
                save(self, key, data)
            finally:
                fcntl.flock(f, fcntl.LOCK_UN)

    locked_save._adaptive_dd_locked = True
    IndexDataCacheFile.save = locked_save


COMPILE_WAIT = 900.0
"""[s] The longest a process waits for another's compilation of a kernel before compiling it itself."""

_held: dict[str, int] = {}  # compile locks this process holds (index path -> depth)


def _lock_compilations() -> None:
    """One compilation of a cached kernel at a time across processes: a process about to compile
    a kernel (numba's cache missed) takes an exclusive lock on ``<its index>.compiling`` in the
    cache folder, then asks the cache again, so that a second process asking for the same kernel
    meanwhile (the test run's workers, the benchmark's second process) waits for the first and
    loads its result instead of compiling it too: the cold default test run compiled about 45
    CPU s of kernels twice, once per worker, without it. Locks follow the call graph (a kernel
    is compiled before its callers finish), which has no cycle; a lock this process holds
    already is not taken again, and a wait gives up after :data:`COMPILE_WAIT` (the kernel is
    then compiled here). Where ``fcntl`` is missing (Windows), compilation is left alone."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows
        return
    from numba.core.dispatcher import Dispatcher

    compile_ = Dispatcher.compile
    if getattr(compile_, "_adaptive_dd_locked", False):
        return
    from numba.core import sigutils

    def locked_compile(self, sig):
        index = getattr(getattr(self._cache, "_cache_file", None), "_index_path", None)
        if index is None or _held.get(index) or tuple(sigutils.normalize_signature(sig)[0]) in self.overloads:
            return compile_(self, sig)
        try:
            f = open(index + ".compiling", "a")
        except OSError:
            return compile_(self, sig)
        with f:
            deadline = time.monotonic() + COMPILE_WAIT
            locked = False
            while not locked:
                try:
                    fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
                    locked = True
                except OSError:
                    if time.monotonic() > deadline:
                        break
                    time.sleep(0.05)
            _held[index] = _held.get(index, 0) + 1
            try:
                return compile_(self, sig)  # loads the kernel if another process compiled it
            finally:
                _held[index] -= 1
                if locked:
                    fcntl.flock(f, fcntl.LOCK_UN)

    locked_compile._adaptive_dd_locked = True
    Dispatcher.compile = locked_compile


_FRESH_IR = contextvars.ContextVar("adaptive_dd_fresh_inline_ir", default=False)


def _inline_fresh_ir_in_place() -> bool:
    """Let numba inline a function compiled with ``inline="always"`` without deep-copying its IR.

    numba's ``InlineWorker.inline_function`` runs the untyped pipeline on the callee for each
    call site, which gives IR nothing else holds, then ``inline_ir`` deep-copies it twice, block by
    block (each block's copy copies the function's whole variable scope again), to protect a
    caller's IR it was never shared with (numba/numba#8989; NVIDIA/numba-cuda#688 and
    NVIDIA/numba-cuda-mlir#196 measure the same cost). With our kernels those copies were about
    a fifth of a cold compilation, and skipping them leaves the compiled code the same
    (``benchmarks/cold_compile.py`` prints the same error; ``tests/test_numba_cache.py``; the
    figures in the changelog). Here the copies are skipped inside ``inline_function`` only;
    ``inline_ir`` called with IR that is kept (numba's ``overload(inline="always")``: the
    template's cached IR) copies it as before. Applied only where numba's inliner has the shape
    this was written against (its module's ``copy.deepcopy`` of each block inside
    ``inline_function``'s call of ``inline_ir``); returns whether it is in place."""
    import copy
    import inspect
    import types

    from numba.core import inline_closurecall as icc

    worker = icc.InlineWorker
    if getattr(worker.inline_function, "_adaptive_dd_fresh", False):
        return True
    try:
        ir_source = inspect.getsource(worker.inline_ir)
        fn_source = inspect.getsource(worker.inline_function)
    except (OSError, TypeError):  # pragma: no cover - numba installed without sources
        return False
    if (
        getattr(icc, "copy", None) is not copy
        or "copy.deepcopy(the_ir.blocks[block_label])" not in ir_source
        or "self.run_untyped_passes(function)" not in fn_source
        or "self.inline_ir(" not in fn_source
    ):
        return False  # another numba: its inliner is left as it is
    inline_function = worker.inline_function

    def deepcopy(x, memo=None):
        return x if _FRESH_IR.get() else copy.deepcopy(x, memo)

    def fresh_inline_function(self, *args, **kwargs):
        token = _FRESH_IR.set(True)
        try:
            return inline_function(self, *args, **kwargs)
        finally:
            _FRESH_IR.reset(token)

    fresh_inline_function._adaptive_dd_fresh = True
    icc.copy = types.SimpleNamespace(deepcopy=deepcopy)
    worker.inline_function = fresh_inline_function
    return True


# ------------------------------------------------------------ telling the user about compilation
COMPILE_SECONDS = {"two-link": 28.0, "serial": 60.0, "plug-in": 9.0}
"""One-time compilation of a benchmark's kernels with a cold cache, on 2 idle cores: a guide for
the message and ``validate``'s estimate, not a promise (a busy machine stretches it; numba
compiles each kernel on one core). Measured from a fresh clone with an empty cache
(``XDG_CACHE_HOME`` a fresh folder): ``adaptive-dd benchmark --seeds 1`` printed ``compiled the
kernels in 26 s`` on the paper's arm and 54-59 s on ``ur5_tool_swap.toml`` (about 110 CPU s of
both processes), where an N-joint arm (any compiles the same kernels) compiles in two processes at
once (:class:`Compiling`); a compiled plug-in's loop, each, after them: ``pd_gravity_plugin:
PDGravityPlugin`` of ``examples/plugins/pd_gravity.toml`` printed ``compiled the plug-in into the
closed loop in 8.7 s``. ``benchmarks/compile_profile.py`` gives each kernel's CPU seconds;
earlier figures are in the changelog."""


def _closed_loop_kernel(serial: bool):
    """The closed loop's kernel of a kind of arm: ``chain_loop_block`` (N joints) or
    ``closed_loop_block`` (the two-link arm), each compiled once for every law."""
    import adaptive_dd.benchmark.compiled  # noqa: F401  (the two-link arm's choices)
    from adaptive_dd.closed_loop.glue import chain_loop_block, closed_loop_block

    return chain_loop_block if serial else closed_loop_block


def _holds(cache, serial: bool) -> bool:
    """Whether the kernel's cache index holds a specialisation for this kind of arm (the two-link
    arm's signature names its ``TwoLinkPlant``); True when the index cannot be read."""
    load = getattr(getattr(cache, "_cache_file", None), "_load_index", None)
    if load is None:
        return True
    try:
        keys = load()
    except Exception:  # an index numba cannot read: it recompiles and says so after the run
        return True
    return any(("TwoLinkPlant" in str(key)) != serial for key in keys)


def cache_index(dispatcher) -> str | None:
    """The path of a ``cache=True`` kernel's index in numba's cache (it exists once the kernel has
    been compiled and saved for this state of the source), or None for a kernel numba does not cache."""
    return getattr(getattr(getattr(dispatcher, "_cache", None), "_cache_file", None), "_index_path", None)


def compile_estimate(arm, plugins=()) -> float:
    """Seconds of one-time compilation a benchmark on ``arm`` would spend now (0 when cached),
    with each compiled plug-in's loop of ``plugins`` (their ``(reset, command, observe,
    estimate)``) numba's cache does not hold.

    Cold means numba's cache holds no compiled form of the closed-loop kernel for this state of
    the source (:func:`configure`); a cached kernel with a new specialisation (another law)
    still compiles, and the message after the run says so.
    """
    from adaptive_dd.closed_loop.plugin_loop import loop_cached
    from adaptive_dd.plant.kind import is_chain

    serial = is_chain(arm)
    runtime = "chain" if serial else "two-link"
    own = sum(COMPILE_SECONDS["plug-in"] for f in plugins if not loop_cached(f, runtime))
    kernel = _closed_loop_kernel(serial)
    index = cache_index(kernel)
    if index is None or (os.path.exists(index) and _holds(kernel._cache, serial)):
        return own
    return COMPILE_SECONDS["serial" if serial else "two-link"] + own


def _compile_split(buffer) -> tuple[float, float]:
    """``(total, uncached)`` from a recorder's ``(time, event)`` pairs: the wall time inside at least
    one numba compilation, and the part of it
    in compilations started from Python of functions numba does not cache (``cache=False``: the
    loop of a plug-in whose functions cannot be keyed,
    :func:`adaptive_dd.closed_loop.plugin_loop.plugin_key`), which every run compiles again."""
    total, uncached, depth, start, cached = 0.0, 0.0, 0, 0.0, True
    for t, ev in sorted(buffer, key=lambda x: x[0]):
        if ev.is_start:
            if depth == 0:
                start = t
                cache = getattr((ev.data or {}).get("dispatcher"), "_cache", None)
                cached = cache is None or type(cache).__name__ != "NullCache"
            depth += 1
        elif depth > 0:
            depth -= 1
            if depth == 0:
                total += t - start
                uncached += 0.0 if cached else t - start
    return total, uncached


def _arm_label(arm) -> str:
    urdf = getattr(arm, "urdf", None)
    if urdf is not None:
        return f"{Path(str(urdf)).stem} ({arm.n_joints} joints)"
    return "the two-link arm"


def _kernel_label(dispatcher, args) -> str:
    """What a kernel compiled from Python is, for the user: ``the N-joint closed loop``, ``the
    two-link closed loop``, ``a plug-in's closed loop``, else ``module.function``."""
    f = dispatcher.py_func
    if f.__name__ == "chain_loop_block":
        return "the N-joint closed loop"
    if f.__module__.startswith("adaptive_dd_plugin_loop_"):  # closed_loop.plugin_loop.plugin_loop
        return "a plug-in's closed loop"
    if f.__name__ != "closed_loop_block":
        return f"{f.__module__.split('.')[-1]}.{f.__name__}"
    return "the two-link closed loop"


class _Progress(event.Listener):
    """A ``numba:compile`` listener printing each kernel compiled from Python (a compilation at
    depth 0, its callees included) that took over a second: the user sees the work advance."""

    def __init__(self, stream) -> None:
        self.stream, self.depth, self.start = stream, 0, 0.0

    def on_start(self, ev) -> None:
        if self.depth == 0:
            self.start = time.perf_counter()
        self.depth += 1

    def on_end(self, ev) -> None:
        self.depth = max(0, self.depth - 1)
        if self.depth == 0 and (spent := time.perf_counter() - self.start) > 1.0:
            label = _kernel_label(ev.data["dispatcher"], ev.data["args"])
            _say(self.stream, f"  {label}: {spent:.0f} s")


def _say(stream, msg: str) -> None:
    """Print ``msg`` on its own line: on a terminal over a progress bar's line first (the bar
    redraws below), so that a compilation's message does not break into it."""
    tty = getattr(stream, "isatty", lambda: False)()
    print(("\r\x1b[K" if tty else "") + msg, file=stream, flush=True)


READY = "ready"
"""What the second process prints when the plant's step and the law's pieces are in the cache."""


class Compiling:
    """Two processes compiling at once on a cold cache (an arm read from a scenario file). On an
    N-joint arm this one compiles the estimator's step
    (:func:`~adaptive_dd.closed_loop.chain_choices.compile_estimator`) while a second
    (:func:`adaptive_dd.closed_loop.precompile.second_process`) compiles the plant's step and the
    law's pieces; this one then compiles the closed loop, loading those from the cache, while the
    second compiles the report's kernels. On the paper's arm (its closed forms) this one compiles
    the closed loop at once while the second
    (:func:`~adaptive_dd.closed_loop.precompile.second_process_two_link`) compiles the estimator's
    step it calls and the report's regressor: this one loads the step when it reaches it, or waits
    for it (:func:`_lock_compilations`). numba's cache is shared by processes (each index write
    locked: :func:`_lock_index_writes`). ``ADAPTIVE_DD_COMPILE_HELPER=0``: one process."""

    def __init__(self, stream, helper=None, errors=None) -> None:
        self.stream, self.helper, self.start = stream, helper, time.perf_counter()
        self.errors = errors  # the second process's stderr (a temporary file), told if it fails
        self.waited = 0.0  # seconds this process waited for the second (counted as compiling)
        self.done = "compiled the report's kernels"  # what the second process's end is told as

    @classmethod
    def begin(cls, arm, source, stream) -> Compiling:
        import subprocess
        import sys
        import tempfile

        from adaptive_dd.plant.kind import is_chain, is_two_link

        chain = is_chain(arm)
        ok = source and os.path.isfile(str(source)) and (chain or is_two_link(arm))
        if not ok or os.environ.get("ADAPTIVE_DD_COMPILE_HELPER", "1") == "0":
            return cls(stream)
        helper_name = "second_process" if chain else "second_process_two_link"
        code = (
            f"import sys; from adaptive_dd.closed_loop.precompile import {helper_name} as f; f(sys.argv[1])"
        )
        here = str(Path(__file__).resolve().parents[1])  # this copy of the package, not another
        path = os.pathsep.join(p for p in (here, os.environ.get("PYTHONPATH")) if p)
        errors = tempfile.TemporaryFile(mode="w+")
        try:
            helper = subprocess.Popen(
                [sys.executable, "-c", code, str(source)], env={**os.environ, "PYTHONPATH": path},
                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=errors, text=True,
            )  # fmt: skip
        except OSError:
            errors.close()
            return cls(stream)
        what = (
            "the plant's step, the law's pieces and the report's kernels"
            if chain
            else "the estimator's step and the report's regressor"
        )
        print(f"  a second process (pid {helper.pid}) compiles {what} meanwhile", file=stream, flush=True)
        self = cls(stream, helper, errors)
        self.done = "compiled the report's kernels" if chain else f"compiled {what}"
        if chain:  # the estimator's step here, then the loop once the plant and the law are cached
            from adaptive_dd.closed_loop.glue import compile_estimator

            compile_estimator(arm)
            self._wait_ready()
        return self

    def _wait_ready(self, timeout: float = 600.0) -> None:
        """Wait until the second process has the plant and the law in the cache (or has ended)."""
        import select

        t0 = time.perf_counter()
        ready = select.select([self.helper.stdout], [], [], timeout)[0]
        self.waited += time.perf_counter() - t0
        if ready:
            if self.helper.stdout.readline().strip() == READY:
                spent = time.perf_counter() - self.start
                _say(
                    self.stream,
                    f"  the second process compiled the plant's step and the law's pieces ({spent:.0f} s)",
                )

    def join(self) -> None:
        """Wait for the second process (the report's kernels are then in the cache), say how it ended."""
        if self.helper is None:
            return
        t0 = time.perf_counter()
        rc, self.helper = self.helper.wait(), None
        self.waited += time.perf_counter() - t0
        spent = time.perf_counter() - self.start
        what = self.done if rc == 0 else f"failed (exit {rc}): what it left compiles here"
        _say(self.stream, f"  the second process {what} ({spent:.0f} s after the start)")
        if rc != 0 and self.errors is not None:
            self.errors.seek(0)
            last = [line for line in self.errors.read().splitlines() if line.strip()][-1:]
            if last:
                _say(self.stream, f"  its error: {last[0].strip()}")
        self._close_errors()

    def _close_errors(self) -> None:
        if self.errors is not None:
            self.errors.close()
            self.errors = None

    def stop(self) -> None:
        if self.helper is not None and self.helper.poll() is None:
            self.helper.terminate()
            self.helper.wait()
        self.helper = None
        self._close_errors()


@contextmanager
def announce_compilation(arm, stream=None, source=None):
    """Say before a run that numba compiles (cold cache), as it goes which kernels it compiled,
    and after it how long compilation took (this process's time inside numba's compilations and
    waiting for the second process, which held the run up as much).

    Prints to ``stream`` (default ``sys.stderr``) a line before, when :func:`compile_estimate`
    finds the cache cold, a line per kernel compiled from Python that took over a second
    (:class:`_Progress`) and a line after whenever compilation took more than a second. On a cold
    cache with an arm read from the scenario file ``source``, two processes compile at once
    (:class:`Compiling`, yielded: its ``join`` waits for the second before the report).
    """
    import sys

    stream = stream or sys.stderr
    guess = compile_estimate(arm)
    if guess:
        import numba

        print(
            f"compiling the closed-loop kernels for {_arm_label(arm)} (once per source state; about "
            f"{guess:.0f} s on 2 cores; cached in {numba.config.CACHE_DIR})",
            file=stream,
            flush=True,
        )
    progress = _Progress(stream)
    compiling = Compiling(stream)
    try:
        with (
            event.install_recorder("numba:compile") as rec,
            event.install_listener("numba:compile", progress),
        ):
            if guess:
                compiling = Compiling.begin(arm, source, stream)
            yield compiling
            compiling.join()
    finally:
        compiling.stop()
    compiled, uncached = _compile_split(rec.buffer)
    spent = compiled + compiling.waited  # the run held up either way
    if spent > 1.0:
        waited = (
            f", {compiling.waited:.0f} s of it waiting for the second process"
            if compiling.waited > 1.0
            else ""
        )
        if uncached > 1.0 and spent - uncached > 1.0:
            said = (
                f"{uncached:.0f} s of it plug-ins' loops that cannot be cached, compiled again by every "
                f"run; the rest cached: later runs skip it{waited}"
            )
        elif uncached > 1.0:
            said = f"plug-ins' loops that cannot be cached: every run compiles them again{waited}"
        else:
            said = f"cached: later runs skip this{waited}"
        _say(stream, f"compiled the kernels in {spent:.0f} s ({said})")
