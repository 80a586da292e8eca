"""The N-joint change detector's level floor, derived from the arm's own noise (Detector.floor None):
on a light arm the constant 0.05 N m floor held every alarm back."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from adaptive_dd.benchmark.scenario import parse_scenario
from adaptive_dd.errors import ParameterError
from adaptive_dd.identification.online_config import FLOOR_MAX, Detector, detector_floor

SO101 = {  # LeRobot's SO-101 from example-robot-data: a hobby servo arm, 0.005 N m of row noise
    "arm": {
        "urdf": "example-robot-data:so_arm_description/urdf/so101.urdf",
        "payload_frame": "gripper_frame_link",
        "payload_capacity": 0.25,
        "armature": [0.012, 0.012, 0.012, 0.006, 0.006],
        "coulomb": [0.05, 0.05, 0.05, 0.03, 0.03],
        "viscous": [0.05, 0.05, 0.05, 0.03, 0.03],
        "torque_limit": [2.9] * 5,
    },
    "run": {"duration": 3.0, "seeds": 2, "controllers": ["ct_oracle", "adaptive_ct"]},
    "reference": {
        "ramp": 1.0,
        **{
            f"joint{j + 1}": {
                "offset": o,
                "amplitude": [0.4, 0.1],
                "frequency": [0.3 + 0.05 * j, 0.9 + 0.1 * j],
            }
            for j, o in enumerate([0.0, -0.5, 0.6, 0.3, 0.0])
        },
    },
    "payload": [{"at": 2.0, "mass": 0.2, "com": [0.0, 0.0, 0.02]}],
}


def test_the_floor_is_at_most_the_heaviest_rows_noise_over_the_threshold():
    d = Detector()
    assert d.floor is None and detector_floor(d) == FLOOR_MAX  # no task: the constant
    assert detector_floor(d, 0.6) == FLOOR_MAX  # a UR5's heaviest row: 0.58 N m
    assert detector_floor(d, 0.02) == pytest.approx(0.02 / d.threshold)
    assert detector_floor(dataclasses.replace(d, floor=0.3), 0.02) == 0.3  # given: as given
    with pytest.raises(ParameterError, match="floor"):
        Detector(floor=-1.0)


def _robots():
    from adaptive_dd.robots.example_robot_data import robots_folder

    try:
        robots_folder()
    except ParameterError as exc:
        pytest.skip(str(exc))


def test_a_light_arm_gets_its_own_floor():
    _robots()
    from adaptive_dd.controllers.registry import scenario_controller

    sc = parse_scenario(SO101, "so101.toml")
    floor = scenario_controller(sc, "adaptive_ct")[1].online.detector.floor
    assert 0 < floor < 0.1 * FLOOR_MAX  # its heaviest row carries about 0.005 N m of noise


@pytest.mark.slow
def test_on_a_light_arm_the_swap_is_found_within_the_filters_time():
    """The 0.2 kg pick-up on the SO-101 here was found 22 ms after it with the 0.05 N m floor, 3 ms
    with its own (and 34-39 ms against 5-7 on a user's 15-s scenario of the arm)."""
    _robots()
    from adaptive_dd.benchmark.runner import run_benchmark

    res = run_benchmark(parse_scenario(SO101, "so101.toml"), progress=False, keep_trajectories=0)
    delays = [
        min((t for t in a if t >= 2.0), default=np.inf) - 2.0 for a in res.runs["adaptive_ct"].alarm_times
    ]
    assert max(delays) <= 0.015, delays
    assert all(t >= 2.0 for a in res.runs["adaptive_ct"].alarm_times for t in a)  # no false alarm
