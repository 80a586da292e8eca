"""A reference given as a path of the tool frame: solved to joints by damped least squares, held to
the path by Pinocchio's forward kinematics, and checked against the joint limits by ``validate``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from adaptive_dd.benchmark.end_effector import frame_placements, rotation_angle
from adaptive_dd.benchmark.preflight import reference_problems
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.errors import ScenarioError

ROOT = Path(__file__).resolve().parent.parent
UR5_Q0 = "[0.0, -1.3, 1.5, -1.8, -1.57, 0.0]"


def _scenario(tmp_path, robot: str, cartesian: str, ramp: float = 1.0, duration: float = 6.0):
    text = f"""
[arm]
robot = "{robot}"
[run]
duration = {duration}
seeds = 1
controllers = ["ct_oracle"]
[reference]
ramp = {ramp}
cartesian = {cartesian}
[[payload]]
at = 3.0
mass = 1.0
"""
    path = tmp_path / f"{robot}_path.toml"
    path.write_text(text)
    return load_scenario(path)


def _tool(sc, t):
    """The tool frame's position and rotation along the scenario's joint reference at times t,
    by Pinocchio's framePlacement (not the project's forward kinematics)."""
    arm = sc.arm
    q = sc.reference.sample(t)[0]
    model, data = arm.model, arm.model.createData()
    fid = model.getFrameId(arm.payload_frame)
    p, r = [], []
    for qk in q:
        pin.forwardKinematics(model, data, arm.pin_configuration(qk))
        m = pin.updateFramePlacement(model, data, fid)
        p.append(m.translation.copy())
        r.append(m.rotation.copy())
    return np.array(p), np.array(r)


def test_a_circle_of_the_ur5s_tool(tmp_path):
    """After the ramp the UR5's tool runs on the circle asked for (radius 0.1 m, in the
    horizontal plane through its position at q0, once per 4 s) to the stated tolerance, its
    orientation held at q0's; the reference is an ordinary multi-sine one (validate: no problem)."""
    sc = _scenario(tmp_path, "ur5", f"{{ circle = 0.1, normal = [0, 0, 1], period = 4.0, q0 = {UR5_Q0} }}")
    ref = sc.reference
    assert ref.path.circle == 0.1 and ref.path_error <= 1e-4
    assert all(len(a) <= 50 for a in ref.amplitude)
    p0, r0 = frame_placements(sc.arm, np.array([0.0, -1.3, 1.5, -1.8, -1.57, 0.0]))
    t = np.linspace(1.0, 5.0, 96, endpoint=False)  # one period, evenly: the mean is the centre
    p, r = _tool(sc, t)
    radius = np.linalg.norm(p[:, :2] - p[:, :2].mean(axis=0), axis=1)
    np.testing.assert_allclose(radius, 0.1, atol=2e-4)
    np.testing.assert_allclose(p[:, 2], p0[2], atol=2e-4)  # in the horizontal plane through p0
    assert np.min(np.linalg.norm(p - p0, axis=1)) < 2e-4  # it passes through p0 (at t = 1 + 4 k s)
    assert np.max(np.linalg.norm(p - p0, axis=1)) == pytest.approx(0.2, abs=4e-4)  # the diameter
    assert np.degrees(rotation_angle(r0, r)).max() < 0.05
    assert reference_problems(sc) == []


def test_waypoints_on_a_redundant_arm_and_position_only_on_three_joints(tmp_path):
    """The Panda (7 joints: its null space pulled to q0 so that the loop closes) passes through
    each waypoint at its time; the 3-joint arm follows the waypoints' positions."""
    w = [[0.0, 0.0, 0.0], [0.06, 0.0, 0.0], [0.06, 0.06, 0.03], [0.0, 0.06, 0.0]]
    q0 = "[0.0, 0.2, 0.0, -1.8, 0.0, 1.8, 0.8]"
    sc = _scenario(tmp_path, "panda", f"{{ waypoints = {w}, period = 4.0, q0 = {q0} }}")
    p0, _ = frame_placements(sc.arm, np.array([0.0, 0.2, 0.0, -1.8, 0.0, 1.8, 0.8]))
    p, _ = _tool(sc, 4.0 + np.arange(4) * 1.0)  # waypoint i at t = i P / 4 (mod P)
    np.testing.assert_allclose(p - p0, w, atol=2e-4)
    w3 = [[0.0, 0.0, 0.0], [-0.1, 0.0, 0.0], [-0.1, 0.0, 0.1]]  # in the planar arm's x-z plane
    sc3 = _scenario(tmp_path, "vertical3", f"{{ waypoints = {w3}, period = 3.0, q0 = [0.3, -0.6, 0.4] }}")
    p0, _ = frame_placements(sc3.arm, np.array([0.3, -0.6, 0.4]))
    p, _ = _tool(sc3, 3.0 + np.arange(3) * 1.0)
    np.testing.assert_allclose(p - p0, w3, atol=2e-4)


@pytest.mark.parametrize(
    ("cartesian", "needle"),
    [
        (f"{{ circle = 3.0, period = 4.0, q0 = {UR5_Q0} }}", "the circle at"),
        (
            f"{{ circle = 0.1, period = 4.0, q0 = {UR5_Q0}, speed = 1 }}",
            "reference.cartesian.speed: unknown key",
        ),
        (f"{{ period = 4.0, q0 = {UR5_Q0} }}", "exactly one of circle"),
        ("{ circle = 0.1, period = 4.0, q0 = [0.0, 1.0] }", "reference.cartesian.q0: must be a list of 6"),
        (f"{{ waypoints = [[0, 0, 0], [0.1, 0]], period = 4.0, q0 = {UR5_Q0} }}", "waypoints[2]"),
        (f"{{ waypoints = [[0, 0, 0], [true, 0, 0]], period = 4.0, q0 = {UR5_Q0} }}", "waypoints[2]"),
        (f"{{ circle = inf, period = 4.0, q0 = {UR5_Q0} }}", "cartesian.circle: must be a number"),
        (f"{{ circle = 0.1, period = 4.0, q0 = {UR5_Q0}, normal = [0, 0, 0] }}", "normal: must not be zero"),
        (f"{{ circle = 0.1, period = 4.0, q0 = {UR5_Q0}, tolerance = 1e-14 }}", "beyond tolerance"),
        ("[1, 2]", "must be an inline table"),
    ],
)
def test_a_bad_path_names_the_key(tmp_path, cartesian, needle):
    with pytest.raises(ScenarioError, match=r"reference\.cartesian") as exc:
        _scenario(tmp_path, "ur5", cartesian)
    assert needle in str(exc.value)


def test_joints_beside_a_path_and_a_bad_ramp_are_named(tmp_path):
    """Joints given beside the path are refused; a bad ramp is named as the ramp, not the path."""
    both = f"{{ circle = 0.1, period = 4.0, q0 = {UR5_Q0} }}\njoint1 = {{ offset = 0.0 }}"
    with pytest.raises(ScenarioError, match="give the path or the joints, not both"):
        _scenario(tmp_path, "ur5", both)
    with pytest.raises(ScenarioError) as exc:
        _scenario(tmp_path, "ur5", f"{{ circle = 0.1, period = 4.0, q0 = {UR5_Q0} }}", ramp=-1.0)
    assert "reference.ramp" in str(exc.value) and "reference.cartesian" not in str(exc.value)


def test_validate_names_the_waypoint_and_the_joint_beyond_a_limit(tmp_path):
    """A path whose joints leave the joint's range, or outrun its velocity limit, is named by
    validate's check: the key, the waypoint and the joint (by its URDF name)."""
    q0 = "[6.2, -1.3, 1.5, -1.8, -1.57, 0.0]"  # the base joint 0.08 rad from its limit (2 pi)
    w = "[[0, 0, 0], [0, -0.15, 0], [0.1, -0.15, 0], [0.1, 0, 0]]"  # turns the base joint up
    sc = _scenario(tmp_path, "ur5", f"{{ waypoints = {w}, period = 4.0, q0 = {q0} }}")
    (problem,) = reference_problems(sc)
    assert problem.startswith("reference.cartesian: at waypoint ")
    assert "joint 'shoulder_pan_joint' (joint1)" in problem and "upper limit 6.283" in problem
    fast = _scenario(tmp_path, "ur5", f"{{ circle = 0.1, period = 0.3, q0 = {UR5_Q0} }}")
    problems = reference_problems(fast)
    assert problems and all(p.startswith("reference.cartesian: at the circle at ") for p in problems)
    assert any("velocity limit 3.142 rad/s" in p and "slow the path" in p for p in problems)
