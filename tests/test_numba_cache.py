"""The compiled-kernel cache is keyed by the source compiled code can depend on (stale kernels cannot run)."""

from __future__ import annotations

import numba

from adaptive_dd import _numba_cache


def _package(root):
    """A package with a kernel module, what it imports (at the top, relatively, inside a function),
    a record type, and a command line that imports the kernel."""
    files = {
        "__init__.py": "",
        "_numba_cache.py": "",
        "kern.py": (
            "from numba import njit\nfrom pkg.consts import K\nfrom . import helpers\n\n\n"
            "@njit\ndef f(x):\n    return x + K + helpers.H\n\n\ndef lazy():\n"
            "    from pkg.sub.late import L\n    return L\n"
        ),
        "consts.py": "K = 1\n",
        "helpers.py": "H = 2\n",
        "records.py": "from typing import NamedTuple\n\n\nclass R(NamedTuple):\n    a: float\n    b: float\n",
        "sub/__init__.py": "",
        "sub/late.py": "L = 3\n",
        "cli.py": "from pkg.kern import f\n\nprint(f(1))\n",
        "report.py": "import pkg.cli\n",
    }
    for name, text in files.items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text(text)
    return root


def test_a_change_that_compiled_code_can_see_gives_another_cache_folder(tmp_path):
    pkg = _package(tmp_path / "pkg")
    h0 = _numba_cache.source_hash(pkg)
    assert _numba_cache.source_hash(pkg) == h0
    seen = {h0}
    # the kernel, what it imports (absolute, relative, inside a function), a record type, the
    # package's __init__: each edit is a new folder (a callee's file, not the caller's)
    for name in ("kern.py", "consts.py", "helpers.py", "sub/late.py", "records.py", "__init__.py"):
        f = pkg / name
        f.write_text(f.read_text() + "\n# edited\n")
        h = _numba_cache.source_hash(pkg)
        assert h not in seen, name
        seen.add(h)
    (pkg / "consts.py").rename(pkg / "consts2.py")  # same bytes, another module
    assert _numba_cache.source_hash(pkg) not in seen


def test_a_change_no_compiled_code_can_see_keeps_the_cache_folder(tmp_path):
    pkg = _package(tmp_path / "pkg")
    h0 = _numba_cache.source_hash(pkg)
    (pkg / "cli.py").write_text("from pkg.kern import f\n\nprint(f(2))\n")
    (pkg / "report.py").write_text("import pkg.cli  # the report\n")
    (pkg / "docs_example.py").write_text("import pkg.kern\n")
    assert _numba_cache.source_hash(pkg) == h0
    names = {f.relative_to(pkg).as_posix() for f in _numba_cache.kernel_sources(pkg)}
    assert names == {"__init__.py", "_numba_cache.py", "kern.py", "consts.py", "helpers.py", "sub/late.py",
                     "records.py"}  # fmt: skip


def test_the_key_covers_every_module_of_compiled_code_in_the_package():
    """Every module that compiles, and every package module it imports, is in the key; the
    command line and the reports are not (an edit there does not recompile)."""
    import re
    from pathlib import Path

    import adaptive_dd

    pkg = Path(adaptive_dd.__file__).resolve().parent
    keyed = set(_numba_cache.kernel_sources(pkg))
    for f in pkg.rglob("*.py"):
        text = f.read_text()
        if re.search(r"^\s*@(njit|overload)", text, re.M) or re.search(r"(?<![\w.])njit\(", text):
            assert f in keyed, f  # decorated, or compiled by a call (controllers/kernels.py)
    assert pkg / "plant" / "chain.py" in keyed and pkg / "closed_loop" / "types.py" in keyed
    assert pkg / "controllers" / "kernels.py" in keyed and pkg / "closed_loop" / "plugin_loop.py" in keyed
    cli = [f for f in pkg.rglob("*.py") if f.relative_to(pkg).parts[0] in ("cli", "cli.py")]
    assert cli and not keyed & set(cli)
    assert pkg / "benchmark" / "report.py" not in keyed


def test_the_package_keys_its_folder_also_inside_the_users(monkeypatch, tmp_path):
    from pathlib import Path

    import adaptive_dd

    expected = _numba_cache.source_hash(Path(adaptive_dd.__file__).parent)
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    before = numba.config.CACHE_DIR
    try:
        folder = _numba_cache.configure()
        assert folder == str(tmp_path / "adaptive_dd" / "numba" / expected)
        assert numba.config.CACHE_DIR == folder
        # a NUMBA_CACHE_DIR of the user's own is keyed too (shared across edits it would serve
        # kernels compiled from another state of the source)
        monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "mine"))
        assert _numba_cache.configure() == str(tmp_path / "mine" / "adaptive_dd" / expected)
        assert numba.config.CACHE_DIR == str(tmp_path / "mine" / "adaptive_dd" / expected)
    finally:
        numba.config.CACHE_DIR = before


_SAVER = """
import sys
import adaptive_dd  # installs the lock on numba's cache writes
from numba.core.caching import IndexDataCacheFile

f = IndexDataCacheFile(sys.argv[1], "kernel", ("stamp", 1))
for i in range(int(sys.argv[3])):
    f.save((sys.argv[2], i), b"x")
"""


def test_two_processes_adding_specialisations_of_one_kernel_lose_none(tmp_path):
    """numba's cache index is read, extended and written back on each save: two processes
    compiling different specialisations of one kernel at once (the benchmark's second process)
    would lose entries without the lock of :func:`_numba_cache._lock_index_writes`."""
    import subprocess
    import sys

    from numba.core.caching import IndexDataCacheFile

    n = 60
    procs = [
        subprocess.Popen([sys.executable, "-c", _SAVER, str(tmp_path), tag, str(n)]) for tag in ("a", "b")
    ]
    assert [p.wait(timeout=120) for p in procs] == [0, 0]
    index = IndexDataCacheFile(str(tmp_path), "kernel", ("stamp", 1))._load_index()
    assert len(index) == 2 * n, f"{2 * n - len(index)} entries lost"
    assert len(set(index.values())) == 2 * n  # one data file per entry, none shared


_KERNEL = """
import numba
import numpy as np


@numba.njit(cache=True)
def f(x):  # compiles in a few tenths of a second: both processes are inside numba meanwhile
    a = np.arange(20.0) * x
    return np.sort(a)[::-1].sum()
"""

_COMPILER = """
import os
import sys
import time

import adaptive_dd  # installs the lock on numba's compilations
import numba

numba.config.CACHE_DIR = sys.argv[1]
sys.path.insert(0, sys.argv[2])
import kernel

open(os.path.join(sys.argv[2], sys.argv[3]), "w").close()
while not all(os.path.exists(os.path.join(sys.argv[2], t)) for t in ("a", "b")):
    time.sleep(0.01)  # both processes ask for the kernel at the same moment
kernel.f(1.0)
print(sum(kernel.f.stats.cache_misses.values()))
"""


def test_two_processes_asking_for_one_kernel_compile_it_once(tmp_path):
    """Two processes asking at once for a kernel the cache lacks (the test run's two workers):
    one compiles it, the other waits for it and loads it from the cache
    (:func:`_numba_cache._lock_compilations`); without the lock both compiled it."""
    import subprocess
    import sys

    (tmp_path / "kernel.py").write_text(_KERNEL)
    cache = tmp_path / "cache"
    cache.mkdir()
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", _COMPILER, str(cache), str(tmp_path), tag],
            stdout=subprocess.PIPE,
            text=True,
        )
        for tag in ("a", "b")
    ]
    misses = sorted(int(p.communicate(timeout=300)[0].split()[-1]) for p in procs)
    assert [p.returncode for p in procs] == [0, 0]
    assert misses == [0, 1], f"cache misses per process {misses}: the kernel was compiled twice"


# ------------------------------------------------------------ inlining without copies of fresh IR
@numba.njit(inline="always")
def _leaf(a, k):
    s = 0.0
    for i in range(a.size):
        s += a[i] * k if a[i] > k else -a[i]
    return s


@numba.njit(inline="always")
def _mid(a, k):
    return _leaf(a, k) + 2.0 * _leaf(a, k + 1.0)


def _over(a, k):
    """Python's meaning of the overload below."""
    return sum(x if x < k else -k for x in a)


@numba.extending.overload(_over, inline="always")
def _over_impl(a, k):
    def impl(a, k):
        t = 0.0
        for i in range(a.size):
            t += a[i] if a[i] < k else -k
        return t

    return impl


def _py_mid(a, k):
    leaf = lambda k: sum(x * k if x > k else -x for x in a)  # noqa: E731
    return leaf(k) + 2.0 * leaf(k + 1.0)


def test_inlining_copies_no_fresh_ir_and_still_copies_the_ir_an_overload_keeps(monkeypatch):
    """Functions compiled with ``inline="always"`` are inlined at each call site (two sites, each
    inlining two more) without a deep copy of their IR, with the same results as Python's; an
    ``overload(inline="always")``, whose template keeps one IR for every site, is still copied
    at each (skipping those copies too breaks its second site: numba fails on the mutated IR)."""
    import copy

    import numpy as np
    import pytest

    if not _numba_cache._inline_fresh_ir_in_place():
        pytest.skip(f"numba {numba.__version__}'s inliner is not the shape the shortcut was written for")
    blocks = []
    deepcopy = copy.deepcopy

    def counting(x, memo=None):
        if type(x).__name__ == "Block":
            blocks.append(x)
        return deepcopy(x, memo)

    monkeypatch.setattr(copy, "deepcopy", counting)
    top = numba.njit(lambda a: _mid(a, 0.5) + 3.0 * _mid(a, -0.25))
    over = numba.njit(lambda a: _over(a, 0.5) + 3.0 * _over(a, -0.25))
    a = np.linspace(-1.0, 2.0, 17)
    assert top(a) == _py_mid(a, 0.5) + 3.0 * _py_mid(a, -0.25)
    assert blocks == []  # six inlined sites, no block copied
    assert over(a) == _over(a, 0.5) + 3.0 * _over(a, -0.25)
    assert len(blocks) >= 4  # two sites, each copy of the kept IR (and numba's second copy)


def test_compilation_messages_clear_a_progress_bars_line_on_a_terminal():
    """The second process's lines broke into the progress bar (only the per-kernel line cleared it)."""
    import io

    from adaptive_dd._numba_cache import _say

    class Tty(io.StringIO):
        def isatty(self):
            return True

    tty, pipe = Tty(), io.StringIO()
    _say(tty, "  the second process compiled the plant's step (41 s)")
    _say(pipe, "compiled the kernels in 9 s")
    assert tty.getvalue() == "\r\x1b[K  the second process compiled the plant's step (41 s)\n"
    assert pipe.getvalue() == "compiled the kernels in 9 s\n"  # a log file gets no escape codes
