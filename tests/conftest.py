import os

# One BLAS thread in every process of the run (the workers, the precompile helper, the CLI and the
# scripts the tests start inherit it), as the leaderboard and ``benchmark --arms`` run: the suite's
# two workers and the precompile helper on 2 cores leave OpenBLAS's second thread no core, and its
# threads spin waiting for each other (an arm's base parameters, a 360 x 78 QR: 0.48 CPU s with two
# threads at load 8, 0.003 with one). Set before numpy is imported here; a value the caller set is
# kept.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
os.environ.setdefault("MPLBACKEND", "Agg")  # figures to files, on a machine with a display too

import numpy as np  # noqa: E402
import pytest  # noqa: E402


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


# ---- a parallel run of the whole suite compiles the N-joint closed loop at its start ---------


def _whole_suite_in_parallel(config) -> bool:
    """The xdist controller of a run of the default test paths (no file, node or ``-k`` given, not
    ``--collect-only``)."""
    return (
        not hasattr(config, "workerinput")
        and bool(getattr(config.option, "numprocesses", None))
        and config.args_source == pytest.Config.ArgsSource.TESTPATHS
        and not config.option.keyword
        and not config.option.collectonly
    )


def pytest_configure(config):
    """Start ``tests/precompile_n_joint_loop.py`` (it does nothing on a warm cache): the workers
    wait less for the N-joint closed loop's compilation (its docstring)."""
    if not _whole_suite_in_parallel(config):
        return
    import os
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    path = os.pathsep.join(p for p in (str(root), os.environ.get("PYTHONPATH")) if p)
    quiet = {"stdin": subprocess.DEVNULL, "stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
    config._precompile = subprocess.Popen(
        [sys.executable, str(root / "tests" / "precompile_n_joint_loop.py")],
        env={**os.environ, "PYTHONPATH": path},  # this copy of the package, not an installed one
        cwd=root,
        start_new_session=True,  # its own process group: stopped with the second process it starts
        **quiet,
    )


def pytest_unconfigure(config):
    import os
    import signal

    p = getattr(config, "_precompile", None)
    if p is not None:
        if p.poll() is None:  # the run ended first (an error, -x, an interrupt)
            if hasattr(os, "killpg"):
                os.killpg(p.pid, signal.SIGTERM)
            else:  # pragma: no cover - Windows: no process groups
                p.terminate()
        p.wait()


@pytest.fixture
def assert_on_the_page():
    """A check that nothing drawn falls off a figure's page (a tick label, an axis label, the
    title): the benchmark's figures have fixed margins and no cropping pass."""

    def check(fig) -> None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        canvas = FigureCanvasAgg(fig)
        canvas.draw()
        drawn = fig.get_tightbbox(canvas.get_renderer())  # [in]
        w, h = fig.get_size_inches()
        assert drawn.x0 >= 0 and drawn.y0 >= 0 and drawn.x1 <= w and drawn.y1 <= h, (drawn, w, h)

    return check
