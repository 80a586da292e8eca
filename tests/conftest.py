import numpy as np
import pytest


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


# ---- a parallel run of the whole suite compiles the two closed loops at its start -----------


def _whole_suite_in_parallel(config) -> bool:
    """The xdist controller of a run of the default test paths (no file, node or ``-k`` given)."""
    return (
        not hasattr(config, "workerinput")
        and bool(getattr(config.option, "numprocesses", None))
        and config.args_source == pytest.Config.ArgsSource.TESTPATHS
        and not config.option.keyword
    )


def pytest_configure(config):
    """Start ``tests/precompile_loops.py`` for each kind of arm (it does nothing on a warm cache):
    the workers then wait for no long compilation of a closed loop (its docstring)."""
    if not _whole_suite_in_parallel(config):
        return
    import os
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    path = os.pathsep.join(p for p in (str(root), os.environ.get("PYTHONPATH")) if p)
    env = {**os.environ, "PYTHONPATH": path}
    quiet = {"stdin": subprocess.DEVNULL, "stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
    script = str(root / "tests" / "precompile_loops.py")
    # each in its own process group: stopped with the second process it may start
    config._precompile = [
        subprocess.Popen([sys.executable, script, kind], env=env, cwd=root, start_new_session=True, **quiet)
        for kind in ("n-joint", "two-link")
    ]


def pytest_unconfigure(config):
    import os
    import signal

    for p in getattr(config, "_precompile", ()):
        if p.poll() is None:  # the run ended first (an error, -x, an interrupt)
            os.killpg(p.pid, signal.SIGTERM)
        p.wait()
