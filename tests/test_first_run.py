"""The first run says that it compiles, and the docs' getting-started scenario stays valid."""

from __future__ import annotations

import re
import shutil
from pathlib import Path
from types import SimpleNamespace

import numba
import pytest
from numba.core import event

from adaptive_dd import _numba_cache
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.benchmark.scenario_base import run_estimate
from adaptive_dd.plant.two_link import ClosedFormTwoLink

ROOT = Path(__file__).resolve().parents[1]


def _fake_kernel(index: Path):
    return SimpleNamespace(_cache=SimpleNamespace(_cache_file=SimpleNamespace(_index_path=str(index))))


def test_a_cold_cache_is_announced_and_counted_in_the_estimate(monkeypatch, tmp_path, capsys):
    index = tmp_path / "compiled.closed_loop_block-1.py311.nbi"
    monkeypatch.setattr(_numba_cache, "_closed_loop_kernel", lambda serial: _fake_kernel(index))
    cold = _numba_cache.compile_estimate(ClosedFormTwoLink.sice())
    assert cold == _numba_cache.COMPILE_SECONDS["two-link"] > 0
    sc = load_scenario()
    est = sc.estimate()
    assert est.compile_seconds == cold and est.seconds > cold
    assert "compiling the kernels, once" in str(est)
    with _numba_cache.announce_compilation(sc.closed_forms or sc.arm):  # as the CLI passes it
        pass
    err = capsys.readouterr().err
    assert err.startswith("compiling the closed-loop kernels for the two-link arm (once per source state;")
    assert str(numba.config.CACHE_DIR) in err
    index.write_bytes(b"")  # the kernel is in the cache now
    assert _numba_cache.compile_estimate(ClosedFormTwoLink.sice()) == 0.0
    assert sc.estimate().compile_seconds == 0.0 and "compiling" not in str(sc.estimate())
    with _numba_cache.announce_compilation(sc.closed_forms or sc.arm):  # as the CLI passes it
        pass
    assert capsys.readouterr().err == ""  # warm, nothing compiled: nothing said


def test_compile_time_is_the_wall_time_inside_any_compilation():
    def ev(kind):
        return event.Event("numba:compile", kind)

    start, end = event.EventStatus.START, event.EventStatus.END
    # an outer compilation 0-10 s compiling a callee 2-5 s, then another 20-23 s
    buffer = [(0.0, ev(start)), (2.0, ev(start)), (5.0, ev(end)), (10.0, ev(end)), (20.0, ev(start)),
              (23.0, ev(end))]  # fmt: skip
    assert _numba_cache._compile_split(buffer)[0] == 13.0
    assert _numba_cache._compile_split(list(reversed(buffer)))[0] == 13.0  # order of the records
    assert _numba_cache._compile_split([]) == (0.0, 0.0)


def test_compilations_of_uncached_functions_are_counted_apart():
    """The loop of a plug-in whose functions cannot be keyed is compiled with cache=False: every
    run compiles it again, and the run said "cached: later runs skip this" of it too."""
    from numba.core.caching import NullCache

    def ev(kind, cached=True):
        d = type("D", (), {"_cache": object() if cached else NullCache()})()
        return event.Event("numba:compile", kind, data={"dispatcher": d})

    start, end = event.EventStatus.START, event.EventStatus.END
    # a cached kernel 0-10 s (a callee 2-5 s inside), an uncached loop 20-23 s calling a cached one
    buffer = [(0.0, ev(start)), (2.0, ev(start)), (5.0, ev(end)), (10.0, ev(end)), (20.0, ev(start, False)),
              (21.0, ev(start)), (22.0, ev(end)), (23.0, ev(end, False))]  # fmt: skip
    assert _numba_cache._compile_split(buffer) == (13.0, 3.0)
    assert _numba_cache._compile_split(buffer[:4]) == (10.0, 0.0)


@pytest.mark.parametrize(
    ("split", "said"),
    [
        ((42.4, 0.0), "compiled the kernels in 42 s (cached: later runs skip this)"),
        ((42.4, 12.0), "compiled the kernels in 42 s (12 s of it plug-ins' loops that cannot be cached, "
         "compiled again by every run; the rest cached: later runs skip it)"),
        ((12.4, 12.0), "compiled the kernels in 12 s (plug-ins' loops that cannot be cached: every run "
         "compiles them again)"),
    ],
)  # fmt: skip
def test_the_compile_time_is_printed_after_a_compilation(monkeypatch, capsys, split, said):
    monkeypatch.setattr(_numba_cache, "compile_estimate", lambda arm: 0.0)
    monkeypatch.setattr(_numba_cache, "_compile_split", lambda buffer: split)
    with _numba_cache.announce_compilation(ClosedFormTwoLink.sice()):
        pass
    assert capsys.readouterr().err == said + "\n"


def test_run_estimate_adds_compilation():
    warm, cold = run_estimate(1000, 2, 3), run_estimate(1000, 2, 3, compile_seconds=50.0)
    assert cold.seconds == warm.seconds + 50.0 and "50 s compiling" in str(cold)


def test_the_readme_test_line_is_the_one_ci_runs():
    ci = (ROOT / ".ci" / "run").read_text()
    line = 'python3 -m venv .venv && .venv/bin/pip install -e ".[test]" && .venv/bin/python -m pytest'
    assert line in (ROOT / "README.md").read_text() and line in ci


def test_the_getting_started_scenario_is_valid(tmp_path):
    text = (ROOT / "docs" / "getting_started.md").read_text()
    toml = re.search(r"```toml\n(# my_arm\.toml\n.*?)```", text, re.S).group(1)
    (tmp_path / "my_arm.toml").write_text(toml)
    shutil.copy(ROOT / "adaptive_dd" / "robots" / "vertical3.urdf", tmp_path / "my_arm.urdf")
    sc = load_scenario(tmp_path / "my_arm.toml")
    assert sc.n_joints == 3 and sc.arm.payload_frame == "tool"


def test_the_scenario_keys_page_lists_every_key_and_stops_on_drift(monkeypatch):
    import sys

    import pytest

    pytest.importorskip("sphinx")
    sys.path.insert(0, str(ROOT / "docs" / "_ext"))
    try:
        import scenario_keys
    finally:
        sys.path.remove(str(ROOT / "docs" / "_ext"))
    from sphinx.errors import ExtensionError

    from adaptive_dd.benchmark.scenario_base import KEYS

    page = scenario_keys.page()
    # the page is in the repository (its links work in a clone, not only in the built site), as
    # the generator writes it: `python docs/_ext/scenario_keys.py --write` after a key changes
    committed = (ROOT / "docs" / "guide" / "scenario_keys.md").read_text()
    assert committed == page, "stale: python docs/_ext/scenario_keys.py --write"
    for table, keys in KEYS.items():
        assert f"`[{table}]`" in page or f"`[[{table}]]`" in page or f"`[{table}.NAME]`" in page
        for k in keys or ():
            assert f"| `{k}` |" in page, f"{table}.{k}"
    meaning = dict(scenario_keys.MEANING)
    del meaning["noise.dropout"]  # a key of the checks without a meaning on the page
    monkeypatch.setattr(scenario_keys, "MEANING", meaning)
    with pytest.raises(ExtensionError, match=r"noise\.dropout"):
        scenario_keys.page()
    monkeypatch.setattr(scenario_keys, "MEANING", {**scenario_keys.MEANING, "run.gone": "a removed key"})
    with pytest.raises(ExtensionError, match=r"run\.gone"):
        scenario_keys.page()


def test_each_kernel_compiled_from_python_is_named_as_it_ends(monkeypatch):
    """One line per compilation at depth 0 over a second (its callees' time inside, not listed)."""
    import io

    from adaptive_dd.closed_loop import glue

    class Typ:
        def __init__(self, text):
            self.text = text

        def __str__(self):
            return self.text

    clock = iter([0.0, 40.0, 41.0, 70.0, 100.0, 100.5])  # perf_counter at each start/end of depth 0
    monkeypatch.setattr(_numba_cache.time, "perf_counter", lambda: next(clock))
    out = io.StringIO()
    progress = _numba_cache._Progress(out)
    chain, two_link, callee = glue.chain_loop_block, glue.closed_loop_block, glue.segment_of

    def ev(kernel, *args):
        return SimpleNamespace(data={"dispatcher": kernel, "args": args})

    progress.on_start(ev(chain, Typ("int64"), Typ("ChainEstimator(EstCfg(Chain(...")))
    progress.on_start(ev(callee))
    progress.on_end(ev(callee))  # nested: not a line of its own
    progress.on_end(ev(chain, Typ("int64"), Typ("ChainEstimator(EstCfg(Chain(...")))
    progress.on_start(ev(two_link, Typ("TwoLinkPlant(...)")))
    progress.on_end(ev(two_link, Typ("TwoLinkPlant(...)")))
    progress.on_start(ev(callee))
    progress.on_end(ev(callee))  # half a second: not worth a line
    assert out.getvalue() == ("  the N-joint closed loop: 40 s\n  the two-link closed loop: 29 s\n")


def test_the_second_process_is_started_only_where_it_helps(monkeypatch, tmp_path):
    """No second process for a scenario not read from a file (either arm), or when turned off."""
    import io

    from adaptive_dd.benchmark.scenario import load_scenario as load

    ur5 = load(str(ROOT / "adaptive_dd" / "scenarios" / "ur5_tool_swap.toml"))
    out = io.StringIO()
    assert _numba_cache.Compiling.begin(ClosedFormTwoLink.sice(), "<memory>", out).helper is None
    assert _numba_cache.Compiling.begin(ur5.arm, "<memory>", out).helper is None
    monkeypatch.setenv("ADAPTIVE_DD_COMPILE_HELPER", "0")
    assert _numba_cache.Compiling.begin(ur5.arm, ur5.source, out).helper is None
    assert out.getvalue() == ""


def test_the_second_process_is_waited_for_and_its_end_told(capsys):
    """It says when the plant and the law are ready, and how it ended (a failure: the first
    process compiles what was left; the failure's last line, so that it is not silent)."""
    import subprocess
    import sys
    import tempfile

    crash = "raise TypeError('law_trial: 14 arguments, got 13')"
    told = "  its error: TypeError: law_trial: 14 arguments, got 13"
    ready = _numba_cache.READY
    for code, end, error in (
        ("", "compiled the report's kernels", None),
        ("raise SystemExit(3)", "failed (exit 3)", None),
        (crash, "failed (exit 1)", told),
    ):
        errors = tempfile.TemporaryFile(mode="w+")
        helper = subprocess.Popen(
            [sys.executable, "-c", f"import time\ntime.sleep(1.5)\nprint({ready!r}, flush=True)\n"
             f"time.sleep(0.5)\n{code}"],
            stdout=subprocess.PIPE, stderr=errors, text=True,
        )  # fmt: skip
        c = _numba_cache.Compiling(sys.stderr, helper, errors)
        c._wait_ready(timeout=60)
        assert c.waited >= 1.0  # the wait holds the run up: counted in "compiled the kernels in"
        before = c.waited
        c.join()
        assert c.waited >= before + 0.3  # and the wait at the end
        err = capsys.readouterr().err
        assert "the second process compiled the plant's step and the law's pieces" in err
        assert f"the second process {end}" in err
        assert (error in err) if error else ("its error" not in err)
        assert c.helper is None and c.errors is None


@pytest.mark.slow
def test_the_second_process_compiles_the_estimator_step_the_two_link_loop_calls(tmp_path):
    """On the paper's arm the second process compiles the estimator's step with the argument types
    the closed loop calls it with. In a fresh cache: the second process's work, then (another
    process) a closed-loop run, which loads the step from the cache and compiles no specialisation
    of it (a second process that compiled another, say with a 32-bit trial index, fails here: the
    loop compiles its own). About 50 CPU s: the loop compiles from nothing."""
    import os
    import subprocess
    import sys

    source = str(ROOT / "adaptive_dd" / "scenarios" / "payload_swap.toml")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path), "PYTHONPATH": str(ROOT)}
    helper = (
        "import sys; from adaptive_dd.closed_loop.precompile import second_process_two_link as f; "
        "f(sys.argv[1])"
    )
    out = subprocess.run([sys.executable, "-c", helper, source], env=env, capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout.splitlines()[0] == _numba_cache.READY, out.stderr
    run = (
        "import dataclasses, sys\n"
        "from adaptive_dd.benchmark.runner import run_benchmark\n"
        "from adaptive_dd.benchmark.scenario import load_scenario\n"
        "from adaptive_dd.identification.two_link_online_kernel import online_step_trial\n"
        "sc = load_scenario(sys.argv[1])\n"
        "sc = dataclasses.replace(sc, seeds=1, controllers=('ct_oracle', 'adaptive_ct'))\n"
        "run_benchmark(sc, progress=False)\n"
        "s = online_step_trial.stats\n"
        "print(sum(s.cache_hits.values()), sum(s.cache_misses.values()))\n"
    )
    out = subprocess.run([sys.executable, "-c", run, source], env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    hits, misses = (int(x) for x in out.stdout.split()[-2:])
    assert (hits, misses) == (1, 0)


def test_the_second_process_compiles_what_the_closed_loop_calls(capsys):
    """The second process's own work, run here in this process on a shipped N-joint scenario: it
    calls the plant's step, the law and the report's kernels with the closed loop's argument types,
    and says it is ready. A law whose signature changed (a new state argument) fails it here, where
    the benchmark would only have said that the second process failed."""
    from adaptive_dd.closed_loop.precompile import second_process

    second_process(str(ROOT / "adaptive_dd" / "scenarios" / "vertical3_payload_exact.toml"))
    assert capsys.readouterr().out.splitlines()[0] == _numba_cache.READY


def test_the_key_count_counts_every_key_the_page_documents_and_no_other():
    """``python docs/_ext/scenario_keys.py`` counts the keys a scenario may set: each counted key is
    on the generated page, and each key the page gives a meaning is counted."""
    import sys

    import pytest

    pytest.importorskip("sphinx")
    sys.path.insert(0, str(ROOT / "docs" / "_ext"))
    try:
        import scenario_keys
    finally:
        sys.path.remove(str(ROOT / "docs" / "_ext"))
    keys = scenario_keys.every_key()
    page = scenario_keys.page()
    for where, names in keys.items():
        for k in names:
            assert f"`{k}`" in page, f"{where}.{k} counted, not on the page"
    for key in [*scenario_keys.MEANING, *scenario_keys.ARRIVING]:
        where, _, k = key.rpartition(".")
        where = {"setting": "controllers.NAME"}.get(where, where)
        if where in ("arm", "plant") or where in keys:
            assert k in keys[where], f"{key} has a meaning on the page but is not counted"
    assert sum(len(v) for v in keys.values()) == len({(w, k) for w, v in keys.items() for k in v})
