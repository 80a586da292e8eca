"""A run whose trials fail still writes its outputs and says so: every trial failed exits 1, a
failed trial's saturation stops counting where it failed, a plug-in's floor and settings are read
as the docs say (found by a plug-in author's walk-through)."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from adaptive_dd.cli import main
from adaptive_dd.errors import ParameterError

NAN_LAW = """
import numpy as np

class NaNLaw:
    floor = False  # as a table's floor = false: no floor

    def __init__(self, kp=10.0, adapt=True, kd=np.array([1.0, 1.0, 1.0])):
        self.kp, self.adapt = kp, adapt

    def reset(self, n, T):
        pass

    def command(self, q, qd, q_d, qd_d, qdd_d):
        return np.full_like(q, np.nan)

    def observe(self, q, qd, tau):
        pass


class PushLaw(NaNLaw):
    floor = None

    def command(self, q, qd, q_d, qd_d, qdd_d):
        return np.full_like(q, 1e6)  # every joint at its limit: the arm runs away


class BadFloor(NaNLaw):
    floor = 3
"""

SCENARIO = """
[arm]
robot = "vertical3"

[run]
duration = 1.0
seeds = 2
controllers = ["{spec}"]

[reference]
joint1 = {{ offset = 0.3, amplitude = [0.2], frequency = [0.5] }}
joint2 = {{ offset = -0.6, amplitude = [0.2], frequency = [0.5] }}
joint3 = {{ offset = 0.4, amplitude = [0.2], frequency = [0.5] }}

[[payload]]
at = 0.5
mass = 0.5
"""


@pytest.fixture
def folder(tmp_path):
    (tmp_path / "failing_laws.py").write_text(NAN_LAW)
    sys.modules.pop("failing_laws", None)
    yield tmp_path
    sys.modules.pop("failing_laws", None)


def _scenario_file(folder, spec: str, table: str = "") -> str:
    path = folder / "s.toml"
    path.write_text(SCENARIO.format(spec=spec) + table)
    return str(path)


def test_a_run_whose_every_trial_failed_writes_its_outputs_and_exits_1(folder, capsys):
    """It ended in an internal error (a legend of no line, exit 3) and wrote nothing; without that
    it exited 0."""
    path = _scenario_file(folder, "failing_laws:NaNLaw")
    out = folder / "out"
    assert main(["benchmark", path, "--out", str(out), "--no-progress"]) == 1
    captured = capsys.readouterr()
    assert "every trial of every controller failed" in captured.err
    for name in ("metrics.csv", "metrics.json", "per_seed.csv", "tracking_error.png", "joint_errors.png"):
        assert (out / name).is_file(), name


def test_a_failed_trials_saturation_stops_where_it_failed(folder):
    """The saturation count went on after the failure (the flag read 548 % of the samples run)."""
    from adaptive_dd.benchmark.runner import run_benchmark
    from adaptive_dd.benchmark.scenario import load_scenario

    sc = load_scenario(_scenario_file(folder, "failing_laws:PushLaw"))
    run = run_benchmark(sc, progress=False).runs["PushLaw"]
    assert run.failed.all()
    ran = run.failed_at + 1  # the samples up to the failure, the failed one included
    assert np.all(run.acc.n_saturated.sum(axis=1) <= ran), (run.acc.n_saturated, run.failed_at)
    assert np.all(run.acc.n_saturated.sum(axis=1) >= 1)


def test_floor_false_on_the_class_is_no_floor_and_another_value_is_named(folder):
    from adaptive_dd.benchmark.preflight import missing_floors
    from adaptive_dd.benchmark.scenario import load_scenario

    sc = load_scenario(_scenario_file(folder, "failing_laws:NaNLaw"))
    assert missing_floors(sc) == ({}, {})  # it read False as a controller named "False"
    from adaptive_dd.benchmark.preflight import controller_problems
    from adaptive_dd.controllers.plugins import floor_of

    (problem,) = controller_problems(load_scenario(_scenario_file(folder, "failing_laws:BadFloor")))
    assert "controllers.BadFloor: BadFloor.floor = 3: the name of one of the run's controllers" in problem
    with pytest.raises(ParameterError, match=r"BadFloor\.floor = 3"):
        floor_of(sys.modules["failing_laws"].BadFloor())


@pytest.mark.parametrize(
    ("table", "needle"),
    [
        (
            'kp = "fast"',
            "controllers.NaNLaw.kp = 'fast': a number (or a list of numbers) (the class's default",
        ),
        ("kp = true", "controllers.NaNLaw.kp = True: a number"),
        ("adapt = 1", "controllers.NaNLaw.adapt = 1: true or false (the class's default is True)"),
        ("kd = true", "controllers.NaNLaw.kd = True: a number (or a list of numbers)"),  # a per-joint default
    ],
)
def test_a_setting_of_the_wrong_kind_names_its_key(folder, table, needle):
    """kp = "fast" read "controllers.NaNLaw: ValueError: could not convert string to float", and
    kp = true ran as 1.0."""
    from adaptive_dd.benchmark.preflight import controller_problems
    from adaptive_dd.benchmark.scenario import load_scenario

    sc = load_scenario(_scenario_file(folder, "failing_laws:NaNLaw", f"\n[controllers.NaNLaw]\n{table}\n"))
    (problem,) = controller_problems(sc)
    assert needle in problem, problem
