"""The tool frame's error: forward kinematics held to Pinocchio, the per-segment figures to a
hand computation, and the benchmark's results carrying them."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from adaptive_dd.benchmark.end_effector import end_effector_errors, frame_placements, rotation_angle
from adaptive_dd.errors import ParameterError
from adaptive_dd.plant.arm import Arm

ROOT = Path(__file__).resolve().parent.parent
ROBOTS = ROOT / "adaptive_dd" / "robots"
ARMS = {
    "ur5": ("ur5.urdf", "tool0"),
    "panda": ("panda.urdf", "panda_link8"),
    "gen3": ("gen3.urdf", "end_effector_link"),  # continuous joints: Pinocchio's (cos, sin)
    "vertical3": ("vertical3.urdf", "tool"),
}


UNALIGNED = """<robot name="unaligned">
  <link name="base"/>
  <joint name="j1" type="continuous"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.1" rpy="0.1 0.2 0.3"/><axis xyz="0 0.6 0.8"/><limit effort="20" velocity="3"/></joint>
  <link name="l1"><inertial><mass value="1"/><origin xyz="0.1 0 0"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.2 0 0"/>
    <axis xyz="0.8 0 0.6"/><limit effort="10" velocity="3" lower="-3" upper="3"/></joint>
  <link name="l2"><inertial><mass value="0.5"/><origin xyz="0.05 0 0"/>
    <inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j3" type="prismatic"><parent link="l2"/><child link="tool"/><origin xyz="0.1 0 0"/>
    <axis xyz="0.6 0 0.8"/><limit effort="10" velocity="1" lower="-0.1" upper="0.1"/></joint>
  <link name="tool"><inertial><mass value="0.2"/><origin xyz="0.02 0 0"/>
    <inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
</robot>
"""
"""An arm of the joint types no shipped robot has: an unaligned continuous joint (Pinocchio's
RevoluteUnboundedUnaligned, whose model has no ``axis`` attribute), an unaligned revolute and an
unaligned prismatic one."""


def _arm(name: str, tmp_path: Path | None = None) -> Arm:
    if name == "unaligned":
        path = (tmp_path or Path(".")) / "unaligned.urdf"
        path.write_text(UNALIGNED)
        return Arm.from_urdf(path, payload_frame="tool")
    urdf, frame = ARMS[name]
    return Arm.from_urdf(ROBOTS / urdf, payload_frame=frame)


@pytest.mark.parametrize("name", [*ARMS, "sice", "unaligned"])
def test_forward_kinematics_is_pinocchios(name, tmp_path):
    """The vectorised product of joint placements equals Pinocchio's framePlacement on 20 random
    configurations, for the tool frame and for every other frame of the model."""
    arm = Arm.sice() if name == "sice" else _arm(name, tmp_path)
    model = arm.model
    data = model.createData()
    rng = np.random.default_rng(44)
    q = rng.uniform(-np.pi, np.pi, (20, arm.n_joints))
    names = [f.name for f in model.frames][1:]
    for frame in [arm.payload_frame, *names[::3]]:
        p, r = frame_placements(arm, q, frame)
        fid = model.getFrameId(frame)
        for k in range(q.shape[0]):
            pin.forwardKinematics(model, data, arm.pin_configuration(q[k]))
            m = pin.updateFramePlacement(model, data, fid)
            np.testing.assert_allclose(p[k], m.translation, atol=1e-12, err_msg=f"{name} {frame}")
            np.testing.assert_allclose(r[k], m.rotation, atol=1e-12, err_msg=f"{name} {frame}")


def test_unknown_frame_and_bad_shape_are_named():
    arm = _arm("ur5")
    with pytest.raises(ParameterError, match="'nowhere'"):
        frame_placements(arm, np.zeros(6), "nowhere")
    with pytest.raises(ParameterError, match=r"\(\.\.\., 6\)"):
        frame_placements(arm, np.zeros(5))


def test_rotation_angle_small_and_large():
    """The geodesic angle is exact near 0 (where arccos of the trace loses it) and near pi."""
    axis = np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5])
    for th in (1e-9, 1e-4, 0.3, 3.1):
        r = pin.exp3(axis * th)
        assert rotation_angle(np.eye(3), r) == pytest.approx(th, rel=1e-9)
        assert rotation_angle(r, np.eye(3)) == pytest.approx(th, rel=1e-9)


def test_planar_two_link_tip():
    """The paper's arm: the tip lies at (l1 c1 + l2 c12, l1 s1 + l2 s12) and turns by q1 + q2."""
    arm = Arm.sice()
    q = np.array([[0.3, -0.7], [1.2, 0.4]])
    p, r = frame_placements(arm, q)
    p0, _ = frame_placements(arm, np.zeros(2))
    l_tot = np.linalg.norm(p0[:2])
    # the two links' lengths from two configurations: elbow at 0 and at pi/2
    p90, _ = frame_placements(arm, np.array([0.0, np.pi / 2]))
    l1 = p90[0]
    l2 = l_tot - l1
    for k in range(2):
        c1, s1 = np.cos(q[k, 0]), np.sin(q[k, 0])
        c12, s12 = np.cos(q[k].sum()), np.sin(q[k].sum())
        np.testing.assert_allclose(p[k, :2], [l1 * c1 + l2 * c12, l1 * s1 + l2 * s12], atol=1e-12)
    assert rotation_angle(r[0], r[1]) == pytest.approx(abs(q[1].sum() - q[0].sum()), rel=1e-12)


def test_segment_figures_by_hand():
    """A trial off the reference by a constant offset on one joint: the RMS, peak and angle are
    those of that offset, segment by segment, and a non-finite sample blanks its segment."""
    arm = _arm("ur5")
    N = 40
    q_d = np.tile([0.1, -1.3, 1.5, -1.8, -1.57, 0.0], (N, 1))
    q = np.repeat(q_d[None], 2, axis=0).copy()
    q[0, 20:, 5] += 0.01  # the last joint turns the flange about its axis: no position error
    q[1, 20:, 0] += 0.02  # the base joint swings the tool
    q[1, 35, 2] = np.nan
    out = end_effector_errors(arm, q, q_d, [0, 20], [20, 40])
    assert out["ee_position_rms"][:, 0] == pytest.approx([0, 0], abs=1e-9)
    assert out["ee_orientation_rms"][0, 1] == pytest.approx(np.degrees(0.01), rel=1e-9)
    assert out["ee_position_rms"][0, 1] == pytest.approx(0.0, abs=1e-9)
    p, _ = frame_placements(arm, q_d[0])
    radius = np.hypot(p[0], p[1]) * 1e3
    assert out["ee_position_max"][1, 0] == pytest.approx(0.0, abs=1e-9)
    assert np.isnan(out["ee_position_rms"][1, 1])  # the NaN sample's segment
    q[1, 35, 2] = q_d[35, 2]
    out = end_effector_errors(arm, q, q_d, [0, 20], [20, 40])
    chord = 2 * radius * np.sin(0.01)
    assert out["ee_position_rms"][1, 1] == pytest.approx(chord, rel=1e-9)
    assert out["ee_position_max"][1, 1] == pytest.approx(chord, rel=1e-9)
    assert out["ee_orientation_rms"][1, 1] == pytest.approx(np.degrees(0.02), rel=1e-9)


def _short(arm: str, seeds: int):
    """The arm's shipped scenario cut to 1.5 s, swaps at 0.5 s (2 kg) and 1.0 s (off)."""
    import dataclasses

    from adaptive_dd.benchmark.scenario import load_scenario

    file = {"ur5": ROOT / "adaptive_dd" / "scenarios" / "ur5_tool_swap.toml", "sice": None}[arm]
    sc = load_scenario(file)
    return dataclasses.replace(
        sc, seeds=seeds, duration=1.5, swap_times=(0.5, 1.0), swap_masses=(2.0, 0.0), swap_com=(),
        swap_inertia=(),
    )  # fmt: skip


@pytest.mark.parametrize(("arm", "engine"), [("ur5", "auto"), ("ur5", "python"), ("sice", "auto")])
def test_streamed_figures_equal_a_kept_trajectorys(arm, engine):
    """The tool frame's error the loop streams for every seed (no trajectory kept) equals
    :func:`end_effector_errors` on the trajectory of the same trial kept in full, seed by seed and
    segment by segment, on the compiled and the Python path and on the paper's arm; the seeds past
    ``keep_trajectories`` have it too."""
    from adaptive_dd.benchmark.metrics import per_seed_segment_metrics
    from adaptive_dd.benchmark.runner import run_benchmark, scenario_controller
    from adaptive_dd.closed_loop.types import run_constants

    sc = _short(arm, seeds=3)
    ctrls = dict(scenario_controller(sc, name) for name in ("pd", "ct_oracle"))
    kept = run_benchmark(sc, progress=False, controllers=ctrls, engine=engine, keep_trajectories=3)
    streamed = run_benchmark(sc, progress=False, controllers=ctrls, engine=engine, keep_trajectories=1)
    rc = run_constants(sc)
    for name in ctrls:
        run = kept.runs[name]
        ref = end_effector_errors(sc.arm, run.q, kept.q_d, rc.seg_start, rc.seg_end)
        got = per_seed_segment_metrics(streamed, streamed.runs[name], settling=False)
        for k in ref:
            assert np.all(np.isfinite(got[k])), (name, k)
            np.testing.assert_allclose(got[k], ref[k], rtol=1e-9, atol=1e-12, err_msg=f"{name} {k}")
        assert np.all(got["ee_position_rms"] > 0) and np.all(got["ee_orientation_rms"] > 0)


@pytest.mark.parametrize("name", [*ARMS, "sice", "unaligned"])
def test_streamed_kinematics_are_pinocchios(name, tmp_path):
    """The loop's per-sample kernel (:func:`~adaptive_dd.closed_loop.tool_frame.accumulate_tool`,
    run here as Python on its tables) adds, for 20 random pairs of configurations, the squared
    distance and the squared angle between the tool frame's placements by Pinocchio's
    ``framePlacement`` (``log3`` for the angle), and keeps the peak distance."""
    from adaptive_dd.closed_loop.tool_frame import accumulate_tool, tool_tables

    arm = Arm.sice() if name == "sice" else _arm(name, tmp_path)
    model, data = arm.model, arm.model.createData()
    fid = model.getFrameId(arm.payload_frame)
    rng = np.random.default_rng(7)
    q_d = rng.uniform(-np.pi, np.pi, (20, arm.n_joints))
    q = q_d + rng.normal(0.0, 0.05, q_d.shape)
    tab = tool_tables(arm, q_d)
    sums = np.zeros((3, 1, 20))
    w, r0 = np.zeros((tab.index.shape[0], 12)), np.zeros(9)
    for k in range(20):
        accumulate_tool(*tab, sums[0], sums[1], sums[2], 0, k, k, q[k], w, r0)

    def place(x):
        pin.forwardKinematics(model, data, arm.pin_configuration(x))
        return pin.updateFramePlacement(model, data, fid).copy()

    for k in range(20):
        a, b = place(q_d[k]), place(q[k])
        d2 = np.sum((a.translation - b.translation) ** 2)
        th = np.linalg.norm(pin.log3(a.rotation.T @ b.rotation))
        assert sums[0, 0, k] == pytest.approx(d2, rel=1e-9, abs=1e-18), (name, k)
        assert sums[1, 0, k] == pytest.approx(np.sqrt(d2), rel=1e-9, abs=1e-12)
        assert sums[2, 0, k] == pytest.approx(th**2, rel=1e-8, abs=1e-18), (name, k)
    # the reference's placements come from the same compiled kinematics: on the reference itself
    # the loop adds exactly nothing
    at_ref = np.zeros((3, 1, 20))
    for k in range(20):
        accumulate_tool(*tab, at_ref[0], at_ref[1], at_ref[2], 0, k, k, q_d[k], w, r0)
    assert not at_ref.any(), (name, at_ref)
