"""A compiled plug-in's loop is cached like the built-ins' kernels, keyed by what it compiles.

:func:`~adaptive_dd.closed_loop.plugin_loop.plugin_key` must give the same key to the same
functions in any process and a new key after any edit the compiled loop would see (the plug-in's
file, a helper in another file, a value read from a global); what it cannot follow (a closure)
gives no key, and the loop is compiled in every process. The loop itself is written into the
cache folder and a later process loads it: a second module over the same file, whose plug-in
functions are left unset (compiling it would fail), finds the loop in numba's cache.
"""

import importlib.util
import os
import shutil
import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

import numba
import numpy as np
import pytest
from numba import njit

from adaptive_dd.closed_loop import plugin_loop
from adaptive_dd.closed_loop.plugin_loop import no_estimate, plugin_key

SCENARIO = Path(__file__).resolve().parent.parent / "examples" / "plugins" / "pd_gravity.toml"

HELPER = """
from numba import njit

@njit
def helper(a):
    return {body}
"""

VARIANT = """
import collections
import math

import numba
import numpy as np
from numba import njit

{head}


class Law:
    @staticmethod
    @njit
    def reset(p, x):
        pass

    @staticmethod
    @njit
    def command(p, x, q, qd, q_d, qd_d, qdd_d, terms, tau):
        for j in range(q.shape[0]):
            tau[j] = {body}

    @staticmethod
    @njit
    def observe(p, x, q, qd, tau):
        return 0
"""
"""A compiled plug-in's module: ``{head}`` its imports and globals, ``{body}`` its torque."""

LAW = VARIANT.format(head="import {helper}\n\nGAIN = 2.0", body="GAIN * {helper}.helper(q_d[j] - q[j])")
"""A law whose command calls a helper in another module (``{helper}``, filled per test)."""


@pytest.fixture(autouse=True)
def _no_stale_bytecode(monkeypatch):
    """These tests rewrite a module file and load it again within a second: a rewrite of the same
    size would load the bytecode Python cached of the file before it (a .pyc is checked against
    the source's whole-second time stamp and its size). No bytecode is written here, and
    :func:`_load` drops any a new process wrote."""
    monkeypatch.setattr(sys, "dont_write_bytecode", True)


def _load(path: Path, name: str):
    shutil.rmtree(path.parent / "__pycache__", ignore_errors=True)
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def _functions(module):
    law = module.Law
    return (law.reset, law.command, law.observe, no_estimate)


@pytest.fixture
def law(tmp_path, monkeypatch):
    """Write a law and its helper (another file) and load them afresh, as often as asked."""
    monkeypatch.syspath_prepend(str(tmp_path))
    helper = f"helper_{tmp_path.name}"

    def make(body="2.0 * a", law_text=LAW):
        (tmp_path / f"{helper}.py").write_text(HELPER.format(body=body))
        (tmp_path / "law.py").write_text(law_text.format(helper=helper))
        _load(tmp_path / f"{helper}.py", helper)
        return _load(tmp_path / "law.py", "law_under_test")

    yield make
    for name in [n for n in sys.modules if n.startswith(("helper_", "law_under_test"))]:
        del sys.modules[name]


def _key_in_a_new_process(tmp_path, seed: int = 0) -> str:
    """The key of ``law.py``'s Law (the ``law`` fixture's files) in a fresh Python process."""
    script = textwrap.dedent(f"""
        import importlib.util, sys
        sys.path.insert(0, {str(tmp_path)!r})
        import helper_{tmp_path.name}
        spec = importlib.util.spec_from_file_location("law_under_test", {str(tmp_path / "law.py")!r})
        m = importlib.util.module_from_spec(spec)
        sys.modules["law_under_test"] = m
        spec.loader.exec_module(m)
        from adaptive_dd.closed_loop.plugin_loop import no_estimate, plugin_key
        print(plugin_key((m.Law.reset, m.Law.command, m.Law.observe, no_estimate)))
    """)
    env = {**os.environ, "PYTHONHASHSEED": str(seed)}
    return subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=True, env=env
    ).stdout.strip()


def test_the_key_is_the_same_in_another_process(law, tmp_path):
    """Two new processes, as two runs of the command line: the same key. (This process may hold
    numba extensions other tests defined, which enter its keys.)"""
    law()
    key = _key_in_a_new_process(tmp_path, 1)
    assert len(key) == 16 and key != "None" and _key_in_a_new_process(tmp_path, 2) == key


def test_the_key_follows_every_edit_the_loop_would_compile(law):
    module = law()
    key = plugin_key(_functions(module))
    assert plugin_key(_functions(law())) == key  # the same text again: the same key
    assert plugin_key(_functions(law(body="3.0 * a"))) != key  # the helper, in another file
    edited = LAW.replace("tau[j] = GAIN", "tau[j] = -GAIN")
    assert plugin_key(_functions(law(law_text=edited))) != key  # the law's own text
    module = law()
    module.GAIN = 2.5  # a global changed at run time: numba compiles its value in
    assert plugin_key(_functions(module)) != key
    checked = tuple(njit(boundscheck=True)(f.py_func) for f in _functions(module)[:3])
    assert plugin_key((*checked, no_estimate)) != plugin_key(_functions(module))  # the options


HELPERS = """
from numba import njit

INIT = 0.0
K = {k}


@njit
def term(e):
    return {body}
"""

THROUGH_MODULE = """
from numba import njit

import {helper}


class Law:
    @staticmethod
    @njit
    def reset(p, x):
        x[0] = {helper}.INIT

    @staticmethod
    @njit
    def command(p, x, q, qd, q_d, qd_d, qdd_d, terms, tau):
        for j in range(q.shape[0]):
            tau[j] = {helper}.K * {helper}.term(q_d[j] - q[j])

    @staticmethod
    @njit
    def observe(p, x, q, qd, tau):
        return 0
"""


def test_a_module_read_by_several_functions_is_keyed_by_what_each_reads(tmp_path, monkeypatch):
    """``import helpers`` then ``helpers.K``: every function's attributes of the module enter the
    key, not only those of the first function that reaches it (``reset`` reads ``INIT`` alone)."""
    monkeypatch.syspath_prepend(str(tmp_path))
    helper = f"helpers_{tmp_path.name}"

    def key(k="1.0", body="2.0 * e"):
        (tmp_path / f"{helper}.py").write_text(HELPERS.format(k=k, body=body))
        (tmp_path / "law_m.py").write_text(THROUGH_MODULE.format(helper=helper))
        _load(tmp_path / f"{helper}.py", helper)
        return plugin_key(_functions(_load(tmp_path / "law_m.py", "law_m_under_test")))

    try:
        first = key()
        assert key() == first
        assert key(k="1.1") != first  # read by command only
        assert key(body="3.0 * e") != first  # called by command only
    finally:
        for name in (helper, "law_m_under_test"):
            sys.modules.pop(name, None)


def test_what_the_key_cannot_follow_gives_no_key():
    def make(gain):
        @njit
        def command(p, x, q, qd, q_d, qd_d, qdd_d, terms, tau):
            tau[:] = gain * (q_d - q)

        return command

    noop = njit(lambda p, x: None)
    assert plugin_key((noop, make(1.0), noop, no_estimate)) is None  # a closure's cell: not in the code
    assert plugin_key((noop, noop, noop, no_estimate)) is not None


def _scenario(duration, seeds):
    """The plug-in example's arm and reference (its three-joint vertical arm), no payload."""
    from adaptive_dd.benchmark.scenario import parse_scenario

    data = tomllib.loads(SCENARIO.read_text())
    data["run"].update(controllers=["ct_nominal"], seeds=seeds, duration=duration)
    for table in ("controllers", "payload"):
        data.pop(table)
    return parse_scenario(data, str(SCENARIO), name="plugin_cache_test")


@pytest.fixture
def cache_folder(tmp_path, monkeypatch):
    """A cache folder of this test's for the plug-ins' loops: numba fixes a kernel's cache folder
    when it is decorated, so ``plugin_loop`` makes its module with numba's folder set to this one;
    the package's kernels keep theirs."""
    folder, make = tmp_path / "cache", plugin_loop.plugin_loop

    def in_folder(functions, runtime="chain"):
        with monkeypatch.context() as m:
            m.setattr(numba.config, "CACHE_DIR", str(folder))
            return make(functions, runtime)

    monkeypatch.setattr(plugin_loop, "plugin_loop", in_folder)
    monkeypatch.setattr(plugin_loop, "_LOOPS", {})
    return folder


@pytest.mark.slow  # two processes compiling a plug-in loop: 10 s of the default run
def test_a_plugins_loop_is_written_once_and_loaded_by_a_later_process(cache_folder, capsys, monkeypatch):
    from adaptive_dd.closed_loop.runner import run_closed_loop
    from adaptive_dd.controllers.plugins import compiled_form

    class Proportional:
        needs = ("gravity",)

        def __init__(self, gain):
            self.gain = gain

        def parameters(self, sample_period):
            return (self.gain,)

        @staticmethod
        @njit
        def reset(p, x):
            pass

        @staticmethod
        @njit
        def command(p, x, q, qd, q_d, qd_d, qdd_d, terms, tau):
            for j in range(q.shape[0]):
                tau[j] = p[0] * (q_d[j] - q[j]) + terms[0][j]

        @staticmethod
        @njit
        def observe(p, x, q, qd, tau):
            return 0

    sc = _scenario(0.05, 2)
    form = compiled_form("p", Proportional(200.0), 1, sc.sample_period)  # as the run builds it
    functions = (form.reset, form.command, form.observe, form.estimate)
    with monkeypatch.context() as m:  # validate's estimate: this loop is to be compiled
        m.setattr(numba.config, "CACHE_DIR", str(cache_folder))
        assert not plugin_loop.loop_cached(functions)
    runs = run_closed_loop(sc, {"p": Proportional(200.0)}).runs
    assert runs["p"].engine == "compiled" and not runs["p"].failed.any()
    with monkeypatch.context() as m:  # and now it is found
        m.setattr(numba.config, "CACHE_DIR", str(cache_folder))
        assert plugin_loop.loop_cached(functions)
        assert not plugin_loop.loop_cached(functions, "two-link")  # another runtime's loop
    assert "p: compiled the plug-in into the closed loop" in capsys.readouterr().err
    (written,) = (cache_folder / "plugin_loops").glob("loop_*.py")
    key = written.stem.removeprefix("loop_")
    loop = sys.modules[f"adaptive_dd_plugin_loop_{key}"].plugin_block
    assert len(loop.signatures) == 1 and sum(loop.stats.cache_misses.values()) == 1
    stamp = written.stat().st_mtime_ns

    # a later run in a new process: no loop in memory; the same functions, other parameters
    monkeypatch.setattr(plugin_loop, "_LOOPS", {})
    monkeypatch.delitem(sys.modules, f"adaptive_dd_plugin_loop_{key}")
    again = run_closed_loop(sc, {"p": Proportional(100.0)}).runs["p"]
    err = capsys.readouterr().err
    assert "compiled the plug-in" not in err and not again.failed.any()
    assert "p: a compiled plug-in, in the compiled closed loop (compiled before)" in err
    run_closed_loop(sc, {"p": Proportional(100.0)})
    assert "compiled" not in capsys.readouterr().err  # said once in a process
    reloaded = sys.modules[f"adaptive_dd_plugin_loop_{key}"].plugin_block
    assert reloaded is not loop and sum(reloaded.stats.cache_hits.values()) == 1
    assert written.stat().st_mtime_ns == stamp and list(written.parent.glob("loop_*.py")) == [written]
    assert np.abs(again.tau).max() < np.abs(runs["p"].tau).max()  # its own parameters, not the first's

    # a later process: a second module over the same file, its plug-in functions unset (None)
    with pytest.MonkeyPatch.context() as m:
        m.setattr(numba.config, "CACHE_DIR", str(cache_folder))
        later = _load(written, f"later_{key}")
    try:
        assert later.command is None
        later.plugin_block.compile(loop.signatures[0])  # would fail to type a call of None
        assert sum(later.plugin_block.stats.cache_hits.values()) == 1
        assert not later.plugin_block.stats.cache_misses
    finally:
        del sys.modules[f"later_{key}"]


@pytest.mark.slow  # compiles a loop (about 9 s) that no cache holds
def test_a_closure_plugin_still_runs_and_says_it_is_compiled_every_run(cache_folder, capsys):
    from adaptive_dd.closed_loop.runner import run_closed_loop

    gain = np.float64(150.0)

    @njit
    def command(p, x, q, qd, q_d, qd_d, qdd_d, terms, tau):
        for j in range(q.shape[0]):
            tau[j] = gain * (q_d[j] - q[j]) + terms[0][j]

    class Closure:
        needs = ("gravity",)
        reset = staticmethod(njit(lambda p, x: None))
        observe = staticmethod(njit(lambda p, x, q, qd, tau: 0))

    Closure.command = staticmethod(command)
    runs = run_closed_loop(_scenario(0.02, 1), {"c": Closure()}).runs
    assert runs["c"].engine == "compiled" and not runs["c"].failed.any()
    assert "compiled again by every run" in capsys.readouterr().err
    assert not (cache_folder / "plugin_loops").exists()


EXTENSION = """
from numba.core import types
from numba.extending import overload_method


@overload_method(types.Array, "gain_{tag}")
def _gain(a):
    def impl(a):
        return {k} * a[0]

    return impl
"""


@pytest.mark.parametrize(
    ("head", "body", "edited"),
    [
        ("from math import sin as f", "f(q[j])", "from math import cos as f"),
        ("SAT = np.tanh", "SAT(q[j])", "SAT = np.arctan"),
        ("DT = np.float64", "DT(q[j])", "DT = np.float32"),
        (
            "@njit(locals={'e': numba.float64})\ndef h(a):\n    e = a * 1.5\n    return e",
            "h(q[j])",
            "@njit(locals={'e': numba.int64})\ndef h(a):\n    e = a * 1.5\n    return e",
        ),
        (
            "@njit('float64(float64)')\ndef h(a):\n    return a / 3",
            "h(q[j])",
            "@njit('float32(float32)')\ndef h(a):\n    return a / 3",
        ),
        (
            "@njit\ndef h(a):\n    return len(a)",
            "h((q[j], 1.0))",
            "@njit\ndef h(*a):\n    return len(a)",  # the same bytecode and names: its flags
        ),
        (
            "G = collections.namedtuple('G', 'kp kd')(2.0, 3.0)",
            "G.kp * q[j]",
            "G = collections.namedtuple('G', 'kd kp')(2.0, 3.0)",
        ),
    ],
)  # fmt: skip
def test_the_key_follows_what_numba_freezes(tmp_path, monkeypatch, head, body, edited):
    """A global naming another numpy or math function or type, a helper's locals, signature or
    argument counts, a named tuple's fields: each changes the compiled loop, so its key."""
    monkeypatch.syspath_prepend(str(tmp_path))

    def key(head):
        (tmp_path / "law_variant.py").write_text(VARIANT.format(head=head, body=body))
        return plugin_key(_functions(_load(tmp_path / "law_variant.py", "law_variant")))

    try:
        first = key(head)
        assert first is not None and key(head) == first
        assert key(edited) != first
    finally:
        sys.modules.pop("law_variant", None)


def test_the_key_follows_a_numba_extension_reached_by_an_attribute(tmp_path, monkeypatch):
    """``a.gain_x()`` reaches an ``@overload_method`` by its name alone: the key holds every
    extension defined outside numba, numpy and the package."""
    monkeypatch.syspath_prepend(str(tmp_path))
    tag = tmp_path.name.replace("-", "_")  # numba keeps every registered method: one name per test

    def key(k):
        (tmp_path / "ext_variant.py").write_text(EXTENSION.format(tag=tag, k=k))
        _load(tmp_path / "ext_variant.py", "ext_variant")
        (tmp_path / "law_variant.py").write_text(VARIANT.format(head="", body=f"q.gain_{tag}()"))
        return plugin_key(_functions(_load(tmp_path / "law_variant.py", "law_variant")))

    try:
        assert key("2.0") != key("3.0")
    finally:
        for name in ("law_variant", "ext_variant"):
            sys.modules.pop(name, None)


def test_the_key_is_the_same_whatever_the_hash_seed(law, tmp_path):
    """Options holding a set (``fastmath={...}``) print in hash-seed order: keyed sorted."""
    law(
        law_text=LAW.replace(
            "    @staticmethod\n    @njit\n    def command",
            "    @staticmethod\n    @njit(fastmath={{'nnan', 'ninf', 'nsz', 'arcp'}})\n    def command",
        )
    )
    keys = {_key_in_a_new_process(tmp_path, seed) for seed in (1, 2, 3)}
    assert len(keys) == 1 and "None" not in keys


def test_a_module_serving_attributes_through_getattr_gives_no_key(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(tmp_path))
    (tmp_path / "lazy_helpers.py").write_text(
        "from numba import njit\n\n\ndef __getattr__(name):\n    return njit(lambda a: 2.0 * a)\n"
    )
    try:
        _load(tmp_path / "lazy_helpers.py", "lazy_helpers")
        (tmp_path / "law_variant.py").write_text(
            VARIANT.format(head="import lazy_helpers", body="lazy_helpers.h(q[j])")
        )
        assert plugin_key(_functions(_load(tmp_path / "law_variant.py", "law_variant"))) is None
    finally:
        for name in ("law_variant", "lazy_helpers"):
            sys.modules.pop(name, None)


def test_a_loop_that_cannot_be_written_says_why_not_a_closure(cache_folder, monkeypatch):
    def no_links(src, dst):
        raise PermissionError(1, "Operation not permitted")

    noop = njit(lambda p, x: None)
    with monkeypatch.context() as m:
        m.setattr(plugin_loop.os, "link", no_links)
        why = plugin_loop.plugin_loop((noop, noop, noop, no_estimate)).adaptive_dd_uncached
    assert "could not be written" in why and "Operation not permitted" in why
    assert not list((cache_folder / "plugin_loops").glob("*"))  # its temporary file removed
    closure = (noop, _closure_command(2.0), noop, no_estimate)
    assert "closure" in plugin_loop.plugin_loop(closure).adaptive_dd_uncached


def _closure_command(gain):
    @njit
    def command(p, x, q, qd, q_d, qd_d, qdd_d, terms, tau):
        tau[:] = gain * (q_d - q)

    return command


def test_old_plugin_loops_are_pruned_with_their_compiled_code(tmp_path):
    """Each edit of a plug-in is a new loop in the cache: beyond the KEEP_LOOPS last used, the loops
    not used for a day go, with numba's files of them; the recent ones stay, however many."""
    folder = tmp_path / "plugin_loops"
    compiled = tmp_path / "plugin_loops_0123abcd"
    folder.mkdir()
    compiled.mkdir()
    now = 1_000_000.0
    day = plugin_loop.KEEP_AGE
    for i in range(20):  # loop 0 used last; 19 first; 18 and 19 used long ago, 16 and 17 an hour ago
        stem = f"loop_{i:016x}"
        (folder / f"{stem}.py").write_text("")
        (compiled / f"{stem}._plugin_block-12.py311.nbi").write_text("")
        (compiled / f"{stem}._plugin_block-12.py311.1.nbc").write_text("")
        when = now - (2 * day if i >= 18 else 3600.0 * i)
        (folder / f"{stem}.used").touch()
        os.utime(folder / f"{stem}.used", (when, when))
    other = compiled / "unrelated.nbi"
    other.write_text("")
    gone = plugin_loop.prune_loops(folder, keep=16, now=now)
    assert sorted(gone) == [f"{18:016x}", f"{19:016x}"]
    left = sorted(p.name for p in folder.glob("*.py"))
    assert len(left) == 18 and "loop_0000000000000012.py" not in left
    assert not list(compiled.glob("loop_0000000000000013.*"))
    assert len(list(compiled.glob("loop_0000000000000011.*"))) == 2
    assert other.exists()
    assert plugin_loop.prune_loops(folder, keep=16, now=now) == []  # nothing more to prune


def test_validates_estimate_counts_each_plug_in_loop_the_cache_lacks(monkeypatch):
    """``validate``'s estimate left out a compiled plug-in's loop (about 9 s a plug-in): it counts
    each one numba's cache does not hold, and none it holds (the example's compiled PD plus gravity;
    its plain-Python twin compiles nothing of its own)."""
    from adaptive_dd import _numba_cache as cache
    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.controllers.registry import plugin_functions

    sc = load_scenario(Path(__file__).parents[1] / "examples" / "plugins" / "pd_gravity.toml")
    (functions,) = plugin_functions(sc)  # pd_gravity_plugin:PDGravityPlugin only
    assert functions[1].__name__ == "command" and all(
        isinstance(f, numba.core.dispatcher.Dispatcher) for f in functions
    )
    held = set()
    monkeypatch.setattr(plugin_loop, "loop_cached", lambda f, runtime="chain": (f, runtime) in held)
    monkeypatch.setattr(cache, "cache_index", lambda kernel: None)  # the built-in kernels cached
    assert cache.compile_estimate(sc.arm, [functions]) == cache.COMPILE_SECONDS["plug-in"]
    held.add((functions, "chain"))
    assert cache.compile_estimate(sc.arm, [functions]) == 0.0
    assert sc.estimate().compile_seconds == 0.0
