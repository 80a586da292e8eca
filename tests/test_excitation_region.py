"""The excitation phase's coverage check of the task's region (``[run] excite`` prints it): an
excitation off that region is caught, the default design over the arm's whole limits among them."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop.excitation_phase import _task_path, excitation_coverage, excitation_reference
from adaptive_dd.identification.excitation import coverage, moving_joints
from adaptive_dd.identification.model import arm_model


def _scenario(name: str, **run):
    src = Path(str(resources.files("adaptive_dd.scenarios").joinpath(f"{name}.toml")))
    data = read_toml(src)
    data["run"].update(run)
    return parse_scenario(data, str(src), name)


@pytest.fixture(scope="module")
def vertical3():
    return _scenario("vertical3_payload_exact", excite=20.0)


def test_the_default_design_over_the_arms_limits_is_reported_off_the_tasks_region(vertical3):
    """vertical3: the phase's default excitation (the arm's whole limits) visits the task's range on
    every joint but spends 14 % of its time in the task's region: reported, not covered."""
    cov = excitation_coverage(vertical3, excitation_reference(vertical3), 20.0)
    assert cov.span.min() >= 0.9 and cov.inside < 0.3 and not cov.ok, cov.line()


def test_an_excitation_over_the_arms_whole_limits_is_not_on_the_tasks_region():
    """Synthetic: an excitation sweeping the whole of +-pi visits the task's range on every joint but
    spends most of its time off the task's region: caught (``inside``); one sweeping the region is
    covered."""
    t = np.linspace(0.0, 20.0, 1000)[:, None]
    task = (
        0.3 * np.sin(2 * np.pi * 0.3 * t + [0.0, 1.0, 2.0]),
        0.6 * np.cos(2 * np.pi * 0.3 * t + [0, 1, 2]),
    )
    wide = (np.pi * np.sin(2 * np.pi * np.array([0.11, 0.13, 0.17]) * t), np.ones((1000, 3)))
    near = (0.45 * np.sin(2 * np.pi * np.array([0.11, 0.13, 0.17]) * t), np.ones((1000, 3)))
    off = coverage(task, wide)
    assert off.span.min() == pytest.approx(1.0) and off.inside < 0.1 and not off.ok
    on = coverage(task, near)
    assert on.ok and on.distance[0] < off.distance[0]
    # wider than the region but through the task's own poses (a two-joint arm's case): covered
    through = (np.concatenate([task[0][::2], wide[0]]), np.concatenate([task[1][::2], wide[1]]))
    both = coverage(task, through)
    assert both.inside < 0.5 and both.distance[0] == 0.0 and both.ok, both.line()


def test_a_base_joint_about_the_vertical_is_not_judged():
    """The iiwa's first joint turns about gravity: its position does not enter the dynamics, so the
    coverage check does not ask the excitation to visit its range; every other joint's it does."""
    sc = _scenario("iiwa14_payload_exact")
    tq = _task_path(sc)[0][::25]
    moves = moving_joints(arm_model(sc.arm), tq, np.random.default_rng(0))
    assert not moves[0] and moves[1:].all()
