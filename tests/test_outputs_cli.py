"""Faults at the command line and in writing outputs (issue 13): exit 2 with one line, nothing lost."""

import os

import numpy as np
import pytest

import adaptive_dd
from adaptive_dd.cli import EXIT_INTERNAL, EXIT_INTERRUPTED, main
from adaptive_dd.outputs import PARTIAL_MARKER, OutputSet, atomic_write, check_output_dir

TINY = """
[run]
duration = 0.3
sample_period = 0.001
seeds = 1
controllers = ["pd", "ct_oracle"]
[[payload]]
at = 0.15
mass = 1.0
"""


@pytest.fixture
def tiny(tmp_path):
    p = tmp_path / "tiny.toml"
    p.write_text(TINY)
    return p


def old_set(folder):
    folder.mkdir(parents=True, exist_ok=True)
    for name in ("metrics.csv", "metrics.json", "tracking_error.png"):
        (folder / name).write_text("old")


def assert_old_set_intact(folder):
    assert sorted(p.name for p in folder.iterdir()) == ["metrics.csv", "metrics.json", "tracking_error.png"]
    assert all((folder / n).read_text() == "old" for n in ("metrics.csv", "metrics.json"))


def test_file_in_the_way_is_refused_before_the_run(tmp_path, tiny, monkeypatch, capsys):
    import adaptive_dd.benchmark.runner as runner

    monkeypatch.setattr(runner, "run_benchmark", lambda *a, **k: pytest.fail("ran before checking"))
    (tmp_path / "file").write_text("x")
    assert main(["benchmark", str(tiny), "--out", str(tmp_path / "file" / "out")]) == 2
    # one line of error (a cold kernel cache adds the run's time estimate before it)
    err = [ln for ln in capsys.readouterr().err.strip().splitlines() if not ln.startswith("estimate:")]
    assert len(err) == 1 and f"{tmp_path / 'file'} is a file" in err[0]
    assert main(["benchmark", str(tiny), "--json", str(tmp_path / "file" / "m.json")]) == 2
    assert main(["benchmark", str(tiny), "--json", str(tmp_path), "--out", str(tmp_path / "o")]) == 2
    assert "is a folder" in capsys.readouterr().err


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_read_only_folder_is_refused(tmp_path, tiny):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        assert main(["benchmark", str(tiny), "--out", str(ro / "out")]) == 2
    finally:
        ro.chmod(0o700)


def test_unwritable_folder_is_refused(tmp_path, monkeypatch):
    from pathlib import Path

    real = Path.write_bytes

    def denied(self, data):
        if self.name.startswith(".write-test"):
            raise PermissionError(13, "Permission denied", str(self))
        return real(self, data)

    monkeypatch.setattr(Path, "write_bytes", denied)
    with pytest.raises(ValueError, match="output folder is not writable: Permission denied"):
        check_output_dir(tmp_path / "x")


def test_interrupted_run_leaves_the_old_set(tmp_path, tiny, monkeypatch, capsys):
    import adaptive_dd.plotting as plotting

    out = tmp_path / "out"
    old_set(out)

    def interrupt(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(plotting, "plot_tracking_errors", interrupt)  # after the CSV and JSON
    assert main(["benchmark", str(tiny), "--out", str(out), "--no-progress"]) == EXIT_INTERRUPTED
    assert_old_set_intact(out)  # no new CSV/JSON, no staging folder, no marker
    monkeypatch.undo()
    assert main(["benchmark", str(tiny), "--out", str(out), "--no-progress"]) == 0
    assert (out / "metrics.csv").read_text().startswith("controller,")
    assert not any(p.name.startswith(".") or p.name == PARTIAL_MARKER for p in out.iterdir())


def test_interrupted_commit_is_marked_partial(tmp_path, monkeypatch):
    out = tmp_path / "out"
    old_set(out)
    s = OutputSet(out)
    for name in ("metrics.csv", "metrics.json"):
        s.path(name).write_text("new")
    real, calls = os.replace, []

    def replace(a, b):
        calls.append(b)
        if len(calls) == 3:  # marker, first file, then the interruption
            raise KeyboardInterrupt
        real(a, b)

    monkeypatch.setattr(os, "replace", replace)
    with pytest.raises(KeyboardInterrupt):
        s.commit()
    assert (out / PARTIAL_MARKER).is_file()  # a mix, but marked
    assert "partly updated" in (out / PARTIAL_MARKER).read_text()


def test_atomic_write_keeps_the_old_file_on_failure(tmp_path):
    p = tmp_path / "a.json"
    p.write_text("old")
    with pytest.raises(KeyboardInterrupt), atomic_write(p) as fh:
        fh.write("new, half")
        raise KeyboardInterrupt
    assert p.read_text() == "old" and sorted(x.name for x in tmp_path.iterdir()) == ["a.json"]


def test_output_set_discards_on_error(tmp_path):
    out = tmp_path / "o"
    old_set(out)
    with pytest.raises(RuntimeError), OutputSet(out) as s:
        s.path("metrics.csv").write_text("new")
        raise RuntimeError("boom")
    assert_old_set_intact(out)


def test_internal_error_short_message_and_debug_traceback(monkeypatch, capsys):
    import adaptive_dd.cli.validate as cli_validate

    def boom(args):
        raise RuntimeError("something broke")

    monkeypatch.setattr(cli_validate, "run", boom)
    assert main(["validate"]) == EXIT_INTERNAL
    err = capsys.readouterr().err
    assert "internal error: RuntimeError: something broke" in err
    assert "adaptive_dd issue tracker" in err and "--debug" in err and "Traceback" not in err
    assert main(["--debug", "validate"]) == EXIT_INTERNAL
    assert "Traceback" in capsys.readouterr().err


def test_plain_value_error_outside_our_code_is_internal(monkeypatch, capsys):
    import adaptive_dd.cli.validate as cli_validate

    monkeypatch.setattr(cli_validate, "run", lambda args: np.zeros(0).max())
    assert main(["validate"]) == EXIT_INTERNAL


def test_version_and_no_abbreviations(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0 and f"adaptive-dd {adaptive_dd.__version__}" in capsys.readouterr().out
    with pytest.raises(SystemExit) as e:
        main(["benchmark", "--controller", "pd"])  # a prefix of --controllers: no abbreviation
    err = capsys.readouterr().err
    assert e.value.code == 2 and "unrecognized arguments: --controller" in err
    # the command's own usage and the option meant
    assert "usage: adaptive-dd benchmark" in err and "(--controller: did you mean --controllers?)" in err
    with pytest.raises(SystemExit) as e:
        main(["validate", "--zzzz"])
    err = capsys.readouterr().err
    assert e.value.code == 2 and "unrecognized arguments: --zzzz" in err and "did you mean" not in err


@pytest.mark.parametrize(
    "argv, match",
    [
        (["simulate", "--sample-period", "0"], "--sample-period: 0 is outside"),
        (["simulate", "--duration", "nan"], "--duration: nan is outside"),
        (["simulate", "--seeds", "0"], "--seeds: 0 is outside"),
        (["simulate", "--payload", "-1"], "--payload: -1 is outside"),
        (["check", "--states", "x"], "--states: not an integer"),
        (["benchmark", "--seeds", "18446744073709551616"], "--seeds: 18446744073709551616 is outside"),
        (["identify", "x.csv", "--tau-f", "0"], "--tau-f: 0 is outside"),
    ],
)
def test_bad_numeric_options_exit_2(argv, match, capsys):
    with pytest.raises(SystemExit) as e:
        main(argv)
    assert e.value.code == 2 and match in capsys.readouterr().err


def test_absurd_run_is_refused_with_the_estimate(tmp_path, capsys):
    assert main(["simulate", "--duration", "1e9", "--out", str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err
    assert "too large" in err and "4.55 TiB" in err and " h" in err  # the unit that reads
    assert not (tmp_path / "s").exists()


def test_validate_prints_defaults_or_all_errors(tmp_path, capsys):
    assert main(["validate"]) == 0
    assert "run.substeps = 2   (default)" in capsys.readouterr().out
    bad = tmp_path / "bad.toml"
    bad.write_text("[run]\nseeds = 0\nduration = nan\n")
    assert main(["validate", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "2 errors" in err and "bad.toml: run.seeds:" in err and "bad.toml: run.duration:" in err


def write_csv(path, q):
    t = np.arange(len(q)) * 1e-3
    tau = q + 0.1 * t[:, None]  # a torque that varies (a constant channel is refused first)
    from adaptive_dd.io import write_recording

    return write_recording(path, t, q, q * 0, tau)


def test_identify_refuses_a_record_without_motion(tmp_path, capsys):
    p = write_csv(tmp_path / "zeros.csv", np.zeros((2000, 2)))
    assert main(["identify", str(p), "--out", str(tmp_path / "id")]) == 2
    assert "does not move" in capsys.readouterr().err
    assert not (tmp_path / "id" / "convergence.png").exists()


def test_identify_refuses_long_filters_and_too_few_equations(tmp_path, monkeypatch, capsys):
    q = np.sin(np.arange(2000)[:, None] * 1e-2 * np.array([1.0, 1.3]))
    p = write_csv(tmp_path / "rec.csv", q)
    assert main(["identify", str(p), "--tau-f", "100", "--out", str(tmp_path / "id")]) == 2
    assert "tau_f / T = 1e+05" in capsys.readouterr().err
    assert main(["identify", str(p), "--tau-f", "0.5", "--out", str(tmp_path / "id")]) == 2
    assert "shorter than 10 tau_f" in capsys.readouterr().err

    import adaptive_dd.identification.estimators as est

    class Few:
        n_used, split, final, std, theta = 12, "full", np.ones(7), np.ones(7), np.ones((2000, 7))

    monkeypatch.setattr(est, "estimate", lambda *a, **k: Few())
    assert main(["identify", str(p), "--out", str(tmp_path / "id")]) == 2
    err = capsys.readouterr().err
    assert "only 12 usable equations" in err and "at least 70" in err


def test_plain_value_error_from_our_code_is_a_user_error(monkeypatch, capsys):
    import adaptive_dd.cli.validate as cli_validate
    from adaptive_dd.controllers import make_controller

    monkeypatch.setattr(cli_validate, "run", lambda args: make_controller("nope"))
    assert main(["validate"]) == 2
    assert "error: unknown controller 'nope'" in capsys.readouterr().err


def test_large_run_prints_its_estimate_first(tiny, tmp_path, monkeypatch, capsys):
    import adaptive_dd.benchmark.runner as runner
    from adaptive_dd.benchmark.scenario import LIMITS

    def interrupt(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setitem(LIMITS, "large_seconds", 0.0)
    monkeypatch.setattr(runner, "run_benchmark", interrupt)
    assert main(["benchmark", str(tiny), "--out", str(tmp_path / "o")]) == EXIT_INTERRUPTED
    assert "estimate: 300 samples x 2 trials: about" in capsys.readouterr().err
    assert list((tmp_path / "o").iterdir()) == []  # the staging folder is gone


def test_figures_in_the_formats_asked_for(tiny, tmp_path):
    """``--figure-formats svg pdf`` wrote svg and pdf files that were never announced to the output
    set, so the run failed at its end ("output files announced but not written: ...png")."""
    out = tmp_path / "o"
    argv = ["benchmark", str(tiny), "--out", str(out), "--no-progress", "--figure-formats", "svg", "pdf"]
    assert main(argv) == 0
    assert {p.suffix for p in out.glob("tracking_error.*")} == {".svg", ".pdf"}
    assert not list(out.glob("*.png"))


def _command(*args, **kw):
    """``python -m adaptive_dd.cli ARGS`` (the console entry, :func:`adaptive_dd.cli.console`) in a
    child process."""
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-m", "adaptive_dd.cli", *args], text=True, check=False, **kw)


def test_the_command_ends_with_every_output_whole_and_its_exit_code(tmp_path, tiny):
    """The console entry ends the process without the interpreter's teardown: what the run wrote is
    complete (the JSON parses, the CSV has its rows, the figure is a whole PNG), the report reached
    stdout, and the exit code is the command's."""
    import json

    out = tmp_path / "out"
    p = _command("benchmark", str(tiny), "--out", str(out), "--no-progress", capture_output=True)
    assert p.returncode == 0, p.stderr
    assert "wrote " in p.stdout.splitlines()[-1]
    assert json.loads((out / "metrics.json").read_text())
    assert len((out / "per_seed.csv").read_text().splitlines()) > 1
    png = (out / "tracking_error.png").read_bytes()
    assert png.startswith(b"\x89PNG") and png.endswith(b"IEND\xaeB`\x82")
    bad = _command("benchmark", str(tmp_path / "missing.toml"), "--out", str(out), capture_output=True)
    assert bad.returncode == 2 and "no such scenario file" in bad.stderr


def test_a_reader_that_stops_early_ends_the_command_quietly(tmp_path):
    """``adaptive-dd validate | head -1``: the pipe closed under the command is not reported as an
    error of the user's; exit 141, as a command killed by SIGPIPE (here the reader is gone before
    the command's first write)."""
    import subprocess
    import sys

    from adaptive_dd.cli import EXIT_PIPE

    p = subprocess.Popen(
        [sys.executable, "-m", "adaptive_dd.cli", "validate"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    p.stdout.close()  # before the command writes: its every write, or its last flush, finds no reader
    err = p.stderr.read()
    assert p.wait() == EXIT_PIPE, err
    assert "error" not in err


def test_a_controller_without_its_floor_gets_it_in_the_cli_and_a_warning_in_the_library(tmp_path, capsys):
    """A scenario listing ``adaptive_ct`` alone: the command adds ``ct_oracle`` and says so (its
    ratios and limits need it); ``run_benchmark`` given the same scenario warns instead."""
    import json

    from adaptive_dd.benchmark.runner import run_benchmark
    from adaptive_dd.benchmark.scenario import load_scenario

    p = tmp_path / "alone.toml"
    p.write_text(TINY.replace('controllers = ["pd", "ct_oracle"]', 'controllers = ["adaptive_ct"]'))
    assert 'controllers = ["adaptive_ct"]' in p.read_text()
    assert main(["benchmark", str(p), "--out", str(tmp_path / "o"), "--no-progress"]) == 0
    assert "run.controllers: ct_oracle added (the floor of adaptive_ct" in capsys.readouterr().err
    m = json.loads((tmp_path / "o" / "metrics.json").read_text())
    assert set(m["controllers"]) == {"adaptive_ct", "ct_oracle"}
    with pytest.warns(UserWarning, match="adaptive_ct's floor ct_oracle did not run"):
        run_benchmark(load_scenario(p), progress=False)


def test_sigterm_stops_a_run_as_ctrl_c_does(tmp_path, tiny, monkeypatch, capsys):
    """SIGTERM (timeout, CI, systemd) exited 143 and left an empty .partial-PID folder behind; it now
    stops the run as Ctrl-C does: the old set intact, no staging folder, and the handler restored."""
    import signal

    import adaptive_dd.plotting as plotting

    out = tmp_path / "out"
    old_set(out)
    before = signal.getsignal(signal.SIGTERM)

    def terminate(*a, **k):
        os.kill(os.getpid(), signal.SIGTERM)  # delivered to this (the main) thread: the handler raises

    monkeypatch.setattr(plotting, "plot_tracking_errors", terminate)
    assert main(["benchmark", str(tiny), "--out", str(out), "--no-progress"]) == EXIT_INTERRUPTED
    assert_old_set_intact(out)
    assert "interrupted; outputs left as before" in capsys.readouterr().err
    assert signal.getsignal(signal.SIGTERM) is before


def test_identify_without_arm_refuses_what_the_arm_path_refuses(tmp_path, capsys):
    """The paper's-arm path (no --arm) accepted a record whose torques are all zero (every estimate 0,
    CRB inf, exit 0), a corrupt 1e300 cell (J1 0.452 -> 0.785, exit 0), a time column in ms (T read as
    1 s), --tau-f below a sample (a negative viscous friction) and --split beside another estimator."""
    from adaptive_dd.io import write_recording

    t = np.arange(3000) * 1e-3
    q = np.column_stack([np.sin(2 * t), np.cos(3 * t)])
    tau = np.column_stack([np.sin(5 * t), np.cos(7 * t)])
    cases = {
        "zero torque": (write_recording(tmp_path / "z.csv", t, q, q * 0, 0 * tau), "column tau1 holds 0"),
        "a corrupt cell": (
            write_recording(tmp_path / "b.csv", t, np.where(t[:, None] == t[100], 1e300, q), q * 0, tau),
            "a value beyond 1e+06 at row 101",
        ),
        "ms": (write_recording(tmp_path / "ms.csv", t * 1e3, q, q * 0, tau), "a time column in ms or ns"),
    }
    for what, (path, needle) in cases.items():
        assert main(["identify", str(path), "--out", str(tmp_path / "id")]) == 2, what
        assert needle in capsys.readouterr().err, what
    good = write_recording(tmp_path / "g.csv", t, q, q * 0, tau)
    assert main(["identify", str(good), "--tau-f", "1e-5", "--out", str(tmp_path / "id")]) == 2
    assert "--tau-f 1e-05 s is below the sample period" in capsys.readouterr().err
    assert main(["identify", str(good), "--split", "16", "--out", str(tmp_path / "id")]) == 2
    assert "--split: a split of the paper's estimator; --estimator exact" in capsys.readouterr().err


def test_excite_refuses_a_ramp_as_long_as_the_record(tmp_path, capsys):
    """--ramp 100 --duration 1 ran the whole design, then ended in an internal error (a singular
    information matrix of a record inside the ramp)."""
    root = os.path.dirname(os.path.dirname(adaptive_dd.__file__))
    arm = os.path.join(root, "benchmarks", "scenarios", "sice_general.toml")
    out = str(tmp_path / "x.toml")
    assert main(["excite", "--arm", arm, "--ramp", "100", "--duration", "1", "--out", out]) == 2
    assert "--ramp 100 s is longer than --duration 1 s" in capsys.readouterr().err


EMPTY = [["benchmark", "--out", ""], ["benchmark", "--json="], ["simulate", "--out", ""]]


@pytest.mark.parametrize("argv", EMPTY)
def test_an_empty_path_is_refused_not_read_as_not_given(argv, capsys):
    """--out "" wrote the results into the working folder; --json "" wrote OUT/metrics.json."""
    assert main(argv) == 2
    assert ": an empty value; give one" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["benchmark", "--seeds", "5", "--seeds", "10"], "--seeds given 2 times"),
        (["benchmark", "--seeds=5", "--seeds", "10"], "--seeds given 2 times"),
        (["benchmark", "--controllers", "pd", "--controllers", "adaptive_ct"], "--controllers given 2 times"),
        (["sweep", "x.toml", "--no-progress", "--no-progress"], "--no-progress given 2 times"),
    ],
)
def test_an_option_given_twice_is_refused_not_the_last_taken(capsys, argv, says):
    """``--seeds 5 --seeds 10`` ran 10 seeds without a word."""
    with pytest.raises(SystemExit) as e:
        main(argv)
    err = capsys.readouterr().err
    assert e.value.code == 2 and says in err and f"usage: adaptive-dd {argv[0]}" in err


def test_a_progress_bar_only_on_a_terminal(monkeypatch):
    """stderr to a file (a log) gets no bar: its carriage returns ran into the messages beside it."""
    import argparse
    import io
    import sys

    from adaptive_dd.cli._common import show_progress

    class Tty(io.StringIO):
        def isatty(self):
            return True

    on, off = argparse.Namespace(no_progress=False), argparse.Namespace(no_progress=True)
    monkeypatch.setattr(sys, "stderr", io.StringIO())
    assert not show_progress(on)
    monkeypatch.setattr(sys, "stderr", Tty())
    assert show_progress(on) and not show_progress(off)
