"""The excitation phase's option ``reach`` (``REACH_TASK``, off by default): each joint's
acceleration limit raised to the largest the scenario's ``[reference]`` asks (never lowered below
the arm's 5 rad/s^2), so the record informs the inertia and armature the task's fast joints need
(docs/learning_the_arm.md, "The excitation reaches the task's accelerations")."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop.excitation_phase import excitation_limits, excitation_reference
from adaptive_dd.identification.excitation import ExcitationLimits


def _scenario(name: str, **run):
    src = Path(str(resources.files("adaptive_dd.scenarios").joinpath(f"{name}.toml")))
    data = read_toml(src)
    data["run"].update(run)
    return parse_scenario(data, str(src), name)


@pytest.fixture(scope="module")
def vertical3():
    return _scenario("vertical3_payload_exact", excite=20.0)


def _task_peak(scenario):
    t = np.arange(0.0, scenario.duration, 0.001)
    return np.abs(scenario.reference.sample(t)[2]).max(axis=0)


def test_the_acceleration_limit_reaches_the_tasks_per_joint(vertical3):
    """vertical3's task asks 4.1 / 10.3 / 19.6 rad/s^2: the limits become 5 / 10.3 / 19.6 (the
    first joint keeps the arm's 5); positions, speeds and torques keep the arm's limits."""
    peak = _task_peak(vertical3)
    arm = ExcitationLimits.of_arm(vertical3.arm)
    lim = excitation_limits(vertical3, reach=True)
    assert peak[0] < 5.0 < peak[1] < peak[2]
    assert lim.acceleration[0] == pytest.approx(arm.acceleration[0])
    assert np.allclose(lim.acceleration[1:], peak[1:], rtol=2e-3)
    for key in ("lower", "upper", "velocity", "torque"):
        assert np.array_equal(getattr(lim, key), getattr(arm, key)), key
    assert np.array_equal(excitation_limits(vertical3, reach=False).acceleration, arm.acceleration)
    assert np.array_equal(excitation_limits(vertical3).acceleration, arm.acceleration)  # the default
    task = excitation_limits(vertical3, "task", reach=True)
    assert np.allclose(task.acceleration, lim.acceleration) and np.all(task.upper <= arm.upper)


def test_the_phases_design_moves_faster_than_the_arms_one_limit_and_within_the_raised_ones(vertical3):
    """The phase's design with ``reach`` uses the raised limits: some joint accelerates beyond the
    arm's 5 rad/s^2 (after the 1 s ramp, on a fine grid) and none beyond its raised limit."""
    lim = excitation_limits(vertical3, reach=True)
    _, qd, qdd = excitation_reference(vertical3, reach=True).sample(np.arange(1.0, 20.0, 0.002))
    top = np.abs(qdd).max(axis=0)
    assert top.max() > 1.2 * 5.0, top
    assert np.all(top <= lim.acceleration * 1.01), (top, lim.acceleration)
    assert np.all(np.abs(qd).max(axis=0) <= lim.velocity * 1.01)
