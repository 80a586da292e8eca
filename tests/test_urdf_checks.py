"""A URDF's values checked for physical sense (adaptive_dd.plant.urdf_checks), through read_urdf
and through a scenario, and the fuzzer over robot descriptions on planted mutations."""

from __future__ import annotations

import re
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.errors import ScenarioError, UrdfError
from adaptive_dd.plant.urdf import read_urdf
from adaptive_dd.plant.urdf_checks import UrdfWarning
from adaptive_dd.robots import ROBOTS, robot_urdf

ROOT = Path(__file__).resolve().parent.parent
UR5 = robot_urdf("ur5").read_text()


def _mutant(tmp_path, old: str, new: str, text: str = UR5) -> Path:
    assert text.count(old) >= 1, old
    path = tmp_path / "mutant.urdf"
    path.write_text(text.replace(old, new, 1))
    return path


def _first(pattern: str, text: str = UR5) -> str:
    return re.search(pattern, text).group(0)


@pytest.mark.parametrize("name", sorted(ROBOTS))
def test_shipped_robots_load_without_a_note(name):
    assert read_urdf(robot_urdf(name), ROBOTS[name].payload_frame).notes == ()


def test_tiago_vendor_file_still_loads():
    robot = read_urdf(ROOT / "examples" / "tiago" / "tiago_48_hey5.urdf", "arm_tool_link", repair=True)
    assert len(robot.joints) == 8


# (what is planted, the text replaced by, what the error must name: element, attribute, value)
PLANTED = [
    ('<axis xyz="0 0 1.0"', '<axis xyz="0 0 0"', ("joint 'shoulder_pan_joint'", "xyz", "'0 0 0'")),
    ('<axis xyz="0 0 1.0"', '<axis xyz="0 nan 1"', ("joint 'shoulder_pan_joint'", "xyz", "nan")),
    ('<axis xyz="0 0 1.0"', "<axis", ("joint 'shoulder_pan_joint'", "xyz", "missing")),
    ("MASS", "1e300", ("link", "value", "1e300")),
    ("MASS", "-2", ("link", "value", "-2")),
    ("EFFORT", "0", ("joint 'shoulder_pan_joint'", "effort", "'0'")),
    ("EFFORT", "1e300", ("joint 'shoulder_pan_joint'", "effort", "1e300")),
    ("VELOCITY", "0", ("joint 'shoulder_pan_joint'", "velocity", "'0'")),
    ("VELOCITY", "-1", ("joint 'shoulder_pan_joint'", "velocity", "'-1'")),
    ("ORIGIN", "0 0 inf", ("joint 'shoulder_pan_joint'", "xyz", "inf")),
    ("ORIGIN", "0 0 1e300", ("joint 'shoulder_pan_joint'", "xyz", "1e300")),
    ("ORIGIN", "0 0", ("joint 'shoulder_pan_joint'", "xyz", "3 numbers")),
    ("IXX", "1e300", ("link", "ixx", "1e300")),
    ("FRICTION", "-1", ("joint 'shoulder_pan_joint'", "friction", "'-1'")),
    ("LOWER", "1e300", ("joint 'shoulder_pan_joint'", "lower", "1e300")),
]


def _planted(old: str, new: str) -> tuple[str, str]:
    """The literal text of a planted mutation in the UR5's file."""
    patterns = {
        "MASS": (r'<mass value="[^"]*"', lambda m: f'<mass value="{new}"'),
        "EFFORT": (r'effort="[^"]*"', lambda m: f'effort="{new}"'),
        "VELOCITY": (r'velocity="[^"]*"', lambda m: f'velocity="{new}"'),
        "LOWER": (r'lower="[^"]*"', lambda m: f'lower="{new}"'),
        "FRICTION": (r'friction="[^"]*"', lambda m: f'friction="{new}"'),
        "IXX": (r'ixx="[^"]*"', lambda m: f'ixx="{new}"'),
        "ORIGIN": (
            r'<joint name="shoulder_pan_joint"[^>]*>\s*<parent[^>]*>\s*<child[^>]*>\s*<origin xyz="[^"]*"',
            None,
        ),
    }
    if old not in patterns:
        return old, new
    pattern, repl = patterns[old]
    found = _first(pattern)
    if repl is None:
        return found, re.sub(r'xyz="[^"]*"$', f'xyz="{new}"', found)
    return found, repl(found)


@pytest.mark.parametrize(("old", "new", "named"), PLANTED)
def test_planted_fault_is_an_error_naming_element_attribute_value(tmp_path, old, new, named):
    old, new = _planted(old, new)
    path = _mutant(tmp_path, old, new)
    with pytest.raises(UrdfError) as err:
        read_urdf(path, "tool0")
    msg = str(err.value)
    assert str(path) in msg
    for part in named:
        assert part in msg, (part, msg)


def test_planted_fault_through_a_scenario_names_file_and_key(tmp_path):
    from adaptive_dd.benchmark.scenario import parse_scenario

    path = _mutant(tmp_path, '<axis xyz="0 0 1.0"', '<axis xyz="0 0 0"')
    data = {
        "arm": {"urdf": str(path), "payload_frame": "tool0"},
        "reference": {
            f"joint{j + 1}": {"offset": 0.0, "amplitude": [0.01], "frequency": [0.5]} for j in range(6)
        },
        "payload": [{"at": 1.0, "mass": 1.0}],
    }
    with pytest.raises(
        ScenarioError, match=r"s\.toml: \[arm\] urdf: .*mutant\.urdf: joint 'shoulder_pan_joint'"
    ):
        parse_scenario(data, "s.toml")


def test_axis_not_of_unit_length_is_normalised_with_a_note(tmp_path):
    path = _mutant(tmp_path, '<axis xyz="0 0 1.0"', '<axis xyz="0 0 2.5"')
    with pytest.warns(UrdfWarning, match="shoulder_pan_joint.*2.5"):
        robot = read_urdf(path, "tool0")
    assert any("normalised joint 'shoulder_pan_joint'" in n for n in robot.notes)
    model = robot.model()
    axis = model.joints[1].extract()
    # Pinocchio reads the normalised file: the joint is the same as the original's
    ref = read_urdf(robot_urdf("ur5"), "tool0").model()
    q = np.linspace(-0.3, 0.4, model.nq)
    import pinocchio as pin

    d1, d2 = model.createData(), ref.createData()
    pin.forwardKinematics(model, d1, q)
    pin.forwardKinematics(ref, d2, q)
    np.testing.assert_allclose(d1.oMi[-1].translation, d2.oMi[-1].translation, atol=1e-12)
    assert axis is not None


def test_geometry_size_nan_is_an_error_negative_a_note(tmp_path):
    text = robot_urdf("vertical3").read_text()
    box = _first(r'<box size="[^"]*"', text)
    path = _mutant(tmp_path, box, '<box size="0.3 nan 0.06"', text)
    with pytest.raises(UrdfError, match="<visual> <box>: attribute 'size'"):
        read_urdf(path, "tool")
    path = _mutant(tmp_path, box, '<box size="0.3 -0.06 0.06"', text)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        robot = read_urdf(path, "tool")
    assert any("is negative (not used)" in n for n in robot.notes)


def test_fuzzer_regressions():
    """The fuzzer's judgement on mutations it once found unjudged (internal errors, silence)."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        import fuzz_urdf
    finally:
        sys.path.pop(0)
    import tempfile

    cases = [
        ("sice_arm", "tip", 2, '<inertia ixx="', '<inertia iyz="0.3" ixx="'),  # not a rigid body's
        ("iiwa14", "iiwa_link_ee_kuka", 7, '<axis xyz="0 0 1.0"/>', "<axis/>"),  # axis without xyz
        ("sice_arm", "tip", 2, 'velocity="', 'velocityx="'),  # urdfdom requires velocity
        ("vertical3", "tool", 3, '<box size="', '<box size="-inf '),  # a visual's size
    ]
    with tempfile.TemporaryDirectory() as tmp:
        for name, frame, n, old, new in cases:
            text = robot_urdf(name).read_text()
            assert old in text, old
            got = fuzz_urdf.load(text.replace(old, new, 1), Path(tmp) / f"{name}.urdf", frame, n)
            assert isinstance(got, ScenarioError), (name, new, got)
            assert str(Path(tmp) / f"{name}.urdf") in str(got)
        # a legal mutation is accepted and judged sane
        text = robot_urdf("ur5").read_text()
        got = fuzz_urdf.load(text, Path(tmp) / "ur5.urdf", "tool0", 6)
        assert fuzz_urdf.meaningless(got) is None


MASSLESS = (
    '<link name="tool0"><inertial><origin xyz="0 0 0"/><mass value="0.0"/>'
    '<inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="{izz}"/></inertial></link>'
)


def test_a_vendors_massless_frame_is_kept_with_a_note(tmp_path):
    """The ROS-Industrial UR descriptions write their tool frames as mass 0 with zero inertia."""
    path = _mutant(tmp_path, '<link name="tool0"/>', MASSLESS.format(izz="0"))
    robot = read_urdf(path, "tool0")
    assert any("'tool0'" in n and "massless frame" in n for n in robot.notes), robot.notes
    ref = read_urdf(robot_urdf("ur5"), "tool0")
    np.testing.assert_array_equal(robot.model().inertias[-1].mass, ref.model().inertias[-1].mass)


def test_mass_zero_with_inertia_is_an_error(tmp_path):
    path = _mutant(tmp_path, '<link name="tool0"/>', MASSLESS.format(izz="0.001"))
    with pytest.raises(UrdfError, match=r"link 'tool0' <inertial> <mass>: value = '0.0'.*must be > 0"):
        read_urdf(path, "tool0")


def test_a_point_mass_on_the_chain_is_kept_with_a_note(tmp_path):
    """The SO-101's gripper_frame_link: mass 1e-9 kg, zero inertia (it was refused as 'not positive
    definite', and its 'repair' changed nothing)."""
    text = MASSLESS.format(izz="0").replace('<mass value="0.0"/>', '<mass value="1e-9"/>')
    robot = read_urdf(_mutant(tmp_path, '<link name="tool0"/>', text), "tool0")
    assert any("'tool0': a point mass (1e-09 kg, no rotational inertia), kept" in n for n in robot.notes)
    assert robot.model().inertias[-1].mass > 0


def test_a_massless_frame_without_inertia_is_kept_too(tmp_path):
    """Mass 0 and no <inertia> element: the checks noted it, then reading it failed ("<inertia> is
    missing")."""
    text = '<link name="tool0"><inertial><origin xyz="0 0 0"/><mass value="0"/></inertial></link>'
    robot = read_urdf(_mutant(tmp_path, '<link name="tool0"/>', text), "tool0")
    assert any("'tool0': mass 0 kg and no inertia: a massless frame" in n for n in robot.notes)


def test_a_limit_without_stops_and_a_very_heavy_link_are_kept_with_a_note(tmp_path):
    """A revolute joint's <limit> without lower and upper was read as unlimited without a word (the
    URDF format's default is 0, as Pinocchio reads it); a 2500 kg link passed without a note, which
    the errors page promised."""
    old = '<limit lower="-6.283185307179586" upper="6.283185307179586" effort="150.0"'
    robot = read_urdf(_mutant(tmp_path, old, '<limit effort="150.0"'), "tool0")
    assert any("<limit> without lower and upper: read as no position limits" in n for n in robot.notes)
    heavy = read_urdf(_mutant(tmp_path, '<mass value="3.7"/>', '<mass value="2500"/>'), "tool0")
    assert any("mass '2500' kg is above 500 kg: a heavy base, or a unit error?" in n for n in heavy.notes)


def test_a_joint_named_as_a_link_loads(tmp_path):
    """The SO-100 of example-robot-data names an off-chain joint as its parent link (``gripper``):
    Pinocchio's reduction then stopped at "Several frames match the filter", printed bare. The
    locked joint is renamed for Pinocchio only, and a chain joint named as its child link leaves
    the link's frame the payload frame."""
    from adaptive_dd.plant.arm import Arm
    from adaptive_dd.robots import robot_urdf

    text = Path(robot_urdf("vertical3")).read_text()
    jaw = (
        '<link name="grip"><inertial><mass value="0.1"/><inertia ixx="1e-4" iyy="1e-4" izz="1e-4" '
        'ixy="0" ixz="0" iyz="0"/></inertial></link>'
        '<joint name="grip_fix" type="fixed"><parent link="tool"/><child link="grip"/></joint>'
        '<link name="jaw"><inertial><mass value="0.05"/><inertia ixx="1e-5" iyy="1e-5" izz="1e-5" '
        'ixy="0" ixz="0" iyz="0"/></inertial></link>'
        '<joint name="grip" type="revolute"><parent link="grip"/><child link="jaw"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
    )
    path = tmp_path / "gripper.urdf"
    path.write_text(text.replace("</robot>", jaw + "</robot>"))
    arm = Arm.from_urdf(path, payload_frame="grip")
    assert arm.joint_names == ("joint1", "joint2", "joint3")
    q = np.array([0.3, -0.2, 0.5])
    plain = Arm.from_urdf(robot_urdf("vertical3"), payload_frame="tool")
    np.testing.assert_allclose(arm.mass_matrix(q)[:2, :2] > plain.mass_matrix(q)[:2, :2], True)
    # a chain joint named as its child link: the payload frame is the link's
    named = tmp_path / "named.urdf"
    named.write_text(text.replace('"joint3"', '"link3"'))
    arm3 = Arm.from_urdf(named, payload_frame="link3")
    ref = Arm.from_urdf(robot_urdf("vertical3"), payload_frame="link3")
    assert arm3.payload_joint == ref.payload_joint


V3 = Path(robot_urdf("vertical3")).read_text()
LINK3_INERTIAL = re.search(r'(?s)(<link name="link3">\s*)(<inertial>.*?</inertial>)', V3).group(2)


def test_a_mimic_joint_on_the_chain_is_refused_naming_it(tmp_path):
    """A joint coupled to another by <mimic> was read as a joint of its own (simulated and
    controlled independently) without a word."""
    old = '<dynamics damping="0.2" friction="0.3"/>\n  </joint>\n  <link name="link3">'
    new = old.replace("<dynamics", '<mimic joint="joint2" multiplier="1.0" offset="0"/><dynamics')
    with pytest.raises(UrdfError, match=r"joint 'joint3' <mimic joint='joint2'>: a joint coupled"):
        read_urdf(_mutant(tmp_path, old, new, V3), "tool")


def test_names_twice_and_an_off_chain_joint_without_limit_are_named(tmp_path):
    """Pinocchio refused both files with 'does not contain a valid URDF model', naming nothing."""
    twice = _mutant(tmp_path, '<joint name="joint3"', '<joint name="joint2"', V3)
    with pytest.raises(UrdfError, match=r"two <joint> elements named 'joint2'"):
        read_urdf(twice, "tool")
    finger = (
        '<link name="tool"/><link name="finger"/><joint name="finger_joint" type="revolute">'
        '<parent link="tool"/><child link="finger"/><axis xyz="0 0 1"/></joint>'
    )
    path = _mutant(tmp_path, '<link name="tool"/>', finger, V3)
    missing = r"joint 'finger_joint' \(revolute\): <limit> is missing.*off the arm"
    with pytest.raises(UrdfError, match=missing):
        read_urdf(path, "tool")


def test_a_chain_link_with_a_shape_and_no_inertial_and_a_huge_gyration_are_noted(tmp_path):
    robot = read_urdf(_mutant(tmp_path, LINK3_INERTIAL, "", V3), "tool")
    assert any("link 'link3' has a shape but no <inertial>: read as massless" in n for n in robot.notes)
    moments = r'ixx="[^"]*" ixy="0" ixz="0" iyy="[^"]*" iyz="0" izz="[^"]*"'
    huge = re.sub(moments, 'ixx="3" ixy="0" ixz="0" iyy="6" iyz="0" izz="6"', LINK3_INERTIAL)
    assert huge != LINK3_INERTIAL
    robot = read_urdf(_mutant(tmp_path, LINK3_INERTIAL, huge, V3), "tool")
    note = "link 'link3': a moment of 6 kg m^2 for 1.5 kg is a radius of gyration of 2 m"
    assert any(note in n for n in robot.notes), robot.notes


def test_negative_damping_and_friction_are_both_named(tmp_path):
    path = _mutant(tmp_path, 'damping="0.2" friction="0.3"', 'damping="-1" friction="-2"', V3)
    with pytest.raises(UrdfError, match=r"damping = '-1' and friction = '-2' must be in \[0"):
        read_urdf(path, "tool")


def _vertical3_scenario(urdf: Path, **arm) -> dict:
    return {
        "arm": {"urdf": str(urdf), "payload_frame": "tool", **arm},
        "reference": {
            f"joint{j + 1}": {"offset": 0.0, "amplitude": [0.2], "frequency": [0.5]} for j in range(3)
        },
        "payload": [{"at": 1.0, "mass": 0.5}],
        "run": {"duration": 2.0},
    }


def test_a_joint_that_moves_no_inertia_is_refused_unless_armature_is_stated(tmp_path):
    """vertical3 without link3's <inertial>: joint3 moves nothing (the tool frame is massless), so
    the mass matrix is singular; validate passed it with divide-by-zero warnings and every trial
    then failed, differently from run to run."""
    from adaptive_dd.benchmark.scenario import parse_scenario

    path = _mutant(tmp_path, LINK3_INERTIAL, "", V3)
    refused = r"joint 'joint3' moves no inertia about its axis.*\[arm\] armature"
    with pytest.raises(ScenarioError, match=refused):
        parse_scenario(_vertical3_scenario(path), "s.toml")
    sc = parse_scenario(_vertical3_scenario(path, armature=[0.05, 0.05, 0.02]), "s.toml")
    assert sc.arm.n_joints == 3


def test_a_plant_urdf_whose_joint_moves_no_inertia_is_refused_too(tmp_path):
    """The [arm] URDF was checked, a [plant] urdf not: every trial then failed at t = 0."""
    from adaptive_dd.benchmark.scenario import parse_scenario

    plant = _mutant(tmp_path, LINK3_INERTIAL, "", V3)
    data = _vertical3_scenario(Path(robot_urdf("vertical3")))
    data["plant"] = {"urdf": str(plant)}
    with pytest.raises(
        ScenarioError, match=r"\[plant\]: joint 'joint3' of the plant moves no inertia.*plant.armature"
    ):
        parse_scenario(data, str(tmp_path / "s.toml"))
    data["plant"]["armature"] = [0.05, 0.05, 0.02]
    assert parse_scenario(data, str(tmp_path / "s.toml")).plant is not None


def test_a_dummy_links_gyration_is_not_noted(tmp_path):
    """iCub's root link (1e-6 kg, 1.3e-6 kg m^2) was noted as a unit error on every load."""
    tiny = re.sub(r'<mass value="[^"]*"/>', '<mass value="1e-6"/>', LINK3_INERTIAL)
    tiny = re.sub(
        r'(i[xyz]{2})="[^"]*"',
        lambda m: f'{m.group(1)}="1.3e-6"' if m.group(1)[1] == m.group(1)[2] else f'{m.group(1)}="0"',
        tiny,
    )
    robot = read_urdf(_mutant(tmp_path, LINK3_INERTIAL, tiny, V3), "tool")
    assert not any("radius of gyration" in n for n in robot.notes), robot.notes
