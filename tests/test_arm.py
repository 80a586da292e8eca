"""Any serial arm from a URDF: checks of the file, base parameters, payload, the two-link fast path."""

from __future__ import annotations

import textwrap

import numpy as np
import pinocchio as pin
import pytest

from adaptive_dd.benchmark.scenario import parse_scenario
from adaptive_dd.errors import ScenarioError, UrdfError
from adaptive_dd.plant import ClosedFormTwoLink
from adaptive_dd.plant.arm import Arm, payload_parameters
from adaptive_dd.plant.dynamics import regressor as paper_regressor
from adaptive_dd.plant.two_link import as_two_link, closed_form_view
from adaptive_dd.plant.urdf import read_urdf
from adaptive_dd.robots import ROBOTS, robot_urdf


@pytest.fixture(scope="module")
def arms():
    return {name: Arm.from_urdf(robot_urdf(name), info.payload_frame) for name, info in ROBOTS.items()}


def _states(arm, rng, m=6):
    n = arm.n_joints
    return rng.uniform(-1.5, 1.5, (m, n)), rng.normal(size=(m, n)), rng.normal(size=(m, n)) * 3


def _pin_torque(arm, model, q, qd, qdd):
    data = model.createData()
    out = [pin.rnea(model, data, arm.pin_configuration(q[i]), qd[i], qdd[i]) for i in range(len(q))]
    return np.array(out) + arm.viscous * qd + arm.coulomb * np.sign(qd) + arm.armature * qdd


@pytest.mark.parametrize("name", list(ROBOTS))
def test_base_regressor_times_sigma_is_pinocchio_inverse_dynamics_with_friction(arms, name):
    n = arms[name].n_joints
    arm = Arm.from_urdf(robot_urdf(name), ROBOTS[name].payload_frame, armature=np.full(n, 0.01))
    q, qd, qdd = _states(arm, np.random.default_rng(1))
    ref = _pin_torque(arm, arm.model, q, qd, qdd)
    np.testing.assert_allclose(arm.inverse_dynamics(q, qd, qdd), ref, atol=1e-10)
    np.testing.assert_allclose(arm.standard_regressor(q, qd, qdd) @ arm.pi, ref, atol=1e-10)
    np.testing.assert_allclose(arm.regressor(q, qd, qdd) @ arm.sigma, ref, atol=1e-10)
    M = arm.mass_matrix(q)
    data = arm.model.createData()
    for i in range(len(q)):
        Mp = pin.crba(arm.model, data, arm.pin_configuration(q[i]))
        Mp = np.triu(Mp) + np.triu(Mp, 1).T + np.diag(arm.armature)
        np.testing.assert_allclose(M[i], Mp, atol=1e-10)


@pytest.mark.parametrize("name", list(ROBOTS))
def test_inverse_dynamics_and_mass_matrix_of_any_base_parameters_are_the_regressors(arms, name):
    """At base parameters that are no arm's (each scaled by 0.5-1.5, a batch of them too), the
    compiled RNEA and CRBA on the standard vector that :meth:`Arm._standard_of` builds give the
    base regressor's torques and their columns at unit accelerations; a batch of sigmas goes
    through the regressor."""
    arm, rng = arms[name], np.random.default_rng(4)
    n = arm.n_joints
    q, qd, qdd = _states(arm, rng)
    qd[0, 0] = 0.0  # sign(0): the Coulomb column's
    sigma = arm.sigma * rng.uniform(0.5, 1.5, arm.sigma.size)
    Y = arm.regressor(q, qd, qdd)
    np.testing.assert_allclose(arm.inverse_dynamics(q, qd, qdd, sigma), Y @ sigma, rtol=1e-12, atol=1e-10)
    batch = arm.sigma * rng.uniform(0.5, 1.5, (len(q), arm.sigma.size))
    np.testing.assert_allclose(
        arm.inverse_dynamics(q, qd, qdd, batch), np.einsum("sij,sj->si", Y, batch), atol=1e-10
    )
    zero = np.zeros_like(q)
    g = arm.regressor(q, zero, zero) @ sigma
    cols = [arm.regressor(q, zero, np.broadcast_to(np.eye(n)[k], q.shape)) @ sigma - g for k in range(n)]
    np.testing.assert_allclose(arm.mass_matrix(q, sigma), np.stack(cols, -1), rtol=1e-12, atol=1e-10)
    np.testing.assert_allclose(arm.mass_matrix(q, batch)[1], arm.mass_matrix(q[1], batch[1]), atol=1e-10)


@pytest.mark.parametrize("name", list(ROBOTS))
def test_base_parameter_count_is_the_rank_of_pinocchios_regressor(arms, name):
    """Independent of our QR: the numerical rank (SVD) of stacked Pinocchio regressors plus
    friction and armature columns, on states of another seed."""
    arm = arms[name]
    n = arm.n_joints
    rng = np.random.default_rng(11)
    q, qd, qdd = rng.uniform(-2, 2, (3, 80, n))
    data = arm.model.createData()
    rows = []
    for i in range(80):
        Y = pin.computeJointTorqueRegressor(arm.model, data, arm.pin_configuration(q[i]), qd[i], qdd[i])
        rows.append(np.hstack([Y, np.diag(qd[i]), np.diag(np.sign(qd[i])), np.diag(qdd[i])]))
    W = np.vstack(rows)
    norms = np.linalg.norm(W, axis=0)
    W = W[:, norms > 1e-9 * norms.max()]  # columns no torque depends on (rounding noise only)
    s = np.linalg.svd(W / np.linalg.norm(W, axis=0), compute_uv=False)
    assert arm.base.count == int(np.sum(s > 1e-8 * s[0]))


@pytest.mark.parametrize(("name", "inertial"), [("ur5", 36), ("vertical3", 9), ("sice_arm", 4)])
def test_inertial_base_parameter_counts_known_from_the_literature(arms, name, inertial):
    """UR5: 36 (Gautier-Khalil grouping, as FIGAROH and the notes count); planar nR with
    gravity in the plane: 3n; planar 2R horizontal with centres of mass anywhere: 4."""
    arm = arms[name]
    inert = [s for s in arm.sigma_names if not s.startswith(("fv", "fc", "Ia"))]
    assert len(inert) == inertial


def test_sice_urdf_spans_the_papers_regressor(arms):
    """A fixed map T with W_base T = Phi_paper (eq. 8) at every state, and sigma_paper from it."""
    arm = arms["sice_arm"]
    rng = np.random.default_rng(2)
    q, qd, qdd = (rng.normal(size=(40, 2)) for _ in range(3))
    Wb = arm.regressor(q, qd, qdd).reshape(-1, arm.base.count)
    phi = paper_regressor(q, qd, qdd).reshape(-1, 7)
    T, *_ = np.linalg.lstsq(Wb, phi, rcond=None)
    np.testing.assert_allclose(Wb @ T, phi, atol=1e-10)
    # centres of mass on the link axes: the general base parameters carry the paper's sigma
    sigma = arm.sigma
    names = arm.sigma_names
    got = {n: v for n, v in zip(names, sigma, strict=True)}
    sice = ClosedFormTwoLink.sice().sigma
    assert got["Izz1 + 0.04*m2 + Ia1"] == pytest.approx(sice[0])
    assert got["Izz2"] == pytest.approx(sice[1])
    assert 0.2 * got["mx2"] == pytest.approx(sice[2])
    assert got["my2"] == 0.0


def test_sice_urdf_is_the_sice_arm_through_the_fast_path(arms):
    two = as_two_link(arms["sice_arm"])
    assert isinstance(two, ClosedFormTwoLink)
    np.testing.assert_allclose(two.sigma, ClosedFormTwoLink.sice().sigma, rtol=1e-14, atol=1e-15)
    assert (two.l1, two.l2) == (0.2, 0.2)
    np.testing.assert_allclose(
        as_two_link(Arm.sice()).sigma, ClosedFormTwoLink.sice().sigma, rtol=1e-14, atol=1e-15
    )
    assert Arm.sice().payload_frame == "tip" and Arm.sice().n_joints == 2
    assert as_two_link(arms["ur5"]) is None and as_two_link(arms["vertical3"]) is None
    assert closed_form_view(Arm.from_urdf(robot_urdf("sice_arm"), "tip")) == two
    assert closed_form_view(Arm.from_urdf(robot_urdf("vertical3"), "tool")) is None
    # the general kernels and the closed forms agree on the SICE arm, payload included
    rng = np.random.default_rng(3)
    q, qd, qdd = _states(arms["sice_arm"], rng)
    general = arms["sice_arm"].inverse_dynamics(q, qd, qdd, arms["sice_arm"].sigma_with_payload(3.0))
    closed = paper_regressor(q, qd, qdd) @ two.sigma_with_payload(3.0)
    np.testing.assert_allclose(general, closed, atol=1e-11)


@pytest.mark.parametrize("name", ["ur5", "panda", "vertical3"])
def test_payload_enters_sigma_linearly_as_pinocchio_says(arms, name):
    from adaptive_dd.plant.pinocchio_check import loaded_model

    arm = arms[name]
    body = {"mass": 2.5, "com": [0.01, -0.02, 0.06], "inertia": [0.011, 0.009, 0.006, 0.001, 0.0, -0.0005]}
    q, qd, qdd = _states(arm, np.random.default_rng(4))
    ref = _pin_torque(arm, loaded_model(arm, body), q, qd, qdd)
    np.testing.assert_allclose(
        arm.inverse_dynamics(q, qd, qdd, arm.sigma_with_payload(**body)), ref, atol=1e-10
    )
    est = arm.payload_from_sigma(arm.sigma_with_payload(**body))
    assert est.mass == pytest.approx(2.5, abs=1e-10)
    ok = est.identifiable[1:4]
    np.testing.assert_allclose(est.com[ok], np.array(body["com"])[ok], atol=1e-10)
    assert np.all(np.isnan(est.com[~ok]))


def test_payload_parameters_of_a_disk_and_bad_bodies():
    p = payload_parameters(2.0, radius=0.1)
    assert p[0] == 2.0 and np.all(p[1:4] == 0)
    assert p[9] == pytest.approx(2.0 * 0.01 / 2) and p[4] == pytest.approx(2.0 * 0.01 / 4)
    p = payload_parameters(1.0, [0.0, 0.0, 0.1], [0.0, 0.0, 0.0, 0, 0, 0])
    assert p[4] == pytest.approx(0.01) and p[9] == 0.0  # parallel axis: Ixx about the frame origin
    with pytest.raises(ValueError, match=r"triangle|rigid body"):
        payload_parameters(1.0, None, [1.0, 1.0, 3.0, 0, 0, 0])
    with pytest.raises(ValueError, match="mass"):
        payload_parameters(-1.0)


URDF_OK = """
<robot name="r">
  <link name="base"/>
  <link name="l1"><inertial><mass value="{m}"/><origin xyz="0.1 0 0"/>
    <inertia ixx="{ixx}" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="tip"/>
  <joint name="j1" type="{kind}"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
    {limit}</joint>
  <joint name="jt" type="fixed"><parent link="l1"/><child link="tip"/><origin xyz="0.2 0 0"/></joint>
</robot>
"""
LIMIT = '<limit effort="10" velocity="2" lower="-3" upper="3"/>'


def _write(tmp_path, text, name="r.urdf"):
    p = tmp_path / name
    p.write_text(textwrap.dedent(text))
    return p


@pytest.mark.parametrize(
    ("fields", "match"),
    [
        ({"m": "0"}, r"link 'l1'.*mass 0.0 kg must be > 0"),
        ({"m": "-1"}, r"mass -1.0 kg must be > 0"),
        ({"ixx": "0.05"}, r"link 'l1'.*triangle inequality"),
        ({"ixx": "-0.01"}, r"link 'l1'.*not positive definite"),
        ({"kind": "floating"}, r"joint 'j1'.*'floating' is not supported"),
        ({"kind": "planar"}, r"joint 'j1'.*'planar'"),
        ({"kind": "ball"}, r"joint 'j1': unknown type 'ball'"),
        ({"limit": '<limit velocity="2" lower="-3" upper="3"/>'}, r"joint 'j1'.*effort"),
        ({"limit": ""}, r"joint 'j1'.*effort"),
    ],
)
def test_bad_urdf_names_file_element_and_reason(tmp_path, fields, match):
    kw = {"m": "1.0", "ixx": "0.01", "kind": "revolute", "limit": LIMIT, **fields}
    p = _write(tmp_path, URDF_OK.format(**kw))
    with pytest.raises(UrdfError, match=match) as exc:
        Arm.from_urdf(p)
    assert str(p) in str(exc.value)


def test_bad_urdf_structure(tmp_path):
    with pytest.raises(UrdfError, match="no such URDF file"):
        read_urdf(tmp_path / "missing.urdf")
    with pytest.raises(UrdfError, match="not valid XML"):
        read_urdf(_write(tmp_path, "<robot><link name='a'></robot>"))
    ok = URDF_OK.format(m="1", ixx="0.01", kind="revolute", limit=LIMIT)
    with pytest.raises(UrdfError, match="payload_frame 'nope' is not a link"):
        read_urdf(_write(tmp_path, ok), payload_frame="nope")
    closed = ok.replace(
        "</robot>",
        '<joint name="j2" type="fixed"><parent link="base"/><child link="tip"/></joint></robot>',
    )
    with pytest.raises(UrdfError, match=r"link 'tip' has two parent joints.*closed chain"):
        read_urdf(_write(tmp_path, closed))
    with pytest.raises(UrdfError, match="no movable joint"):
        read_urdf(_write(tmp_path, ok), payload_frame="base")
    branched = ok.replace(
        "</robot>",
        '<link name="tip2"/><joint name="jx" type="fixed"><parent link="l1"/>'
        '<child link="tip2"/></joint></robot>',
    )
    with pytest.raises(UrdfError, match=r"deepest links.*name the payload frame"):
        read_urdf(_write(tmp_path, branched))
    robot = read_urdf(_write(tmp_path, branched), payload_frame="tip2")
    assert robot.joint_names == ("j1",)


def test_off_chain_joints_are_locked_and_their_mass_merged(tmp_path):
    text = URDF_OK.format(m="1", ixx="0.01", kind="revolute", limit=LIMIT).replace(
        "</robot>",
        '<link name="finger"><inertial><mass value="0.5"/><inertia ixx="0.001" iyy="0.001" izz="0.001"'
        ' ixy="0" ixz="0" iyz="0"/></inertial></link>'
        '<joint name="jf" type="prismatic"><parent link="l1"/><child link="finger"/><origin xyz="0.1 0 0"/>'
        '<axis xyz="1 0 0"/><limit effort="5" velocity="1" lower="0" upper="0.04"/></joint></robot>',
    )
    arm = Arm.from_urdf(_write(tmp_path, text), payload_frame="tip")
    assert arm.locked == ("jf",) and arm.n_joints == 1
    assert arm.model.inertias[1].mass == pytest.approx(1.5)


UR5_SCENARIO = """
[run]
duration = 2.0
controllers = ["pd"]
[arm]
robot = "ur5"
{arm_extra}
[reference]
joint1 = {{ amplitude = [0.5], frequency = [0.3] }}
joint2 = {{ offset = -1.0, amplitude = [0.4], frequency = [0.25] }}
joint3 = {{ offset = 1.0, amplitude = [0.4], frequency = [0.35] }}
joint4 = {{ amplitude = [0.5], frequency = [0.4] }}
wrist_2_joint = {{ amplitude = [0.5], frequency = [0.45] }}
{last}
[[payload]]
at = 1.0
mass = 2.0
com = [0.0, 0.0, 0.05]
{inertia}
"""


def _ur5(arm_extra="", last="joint6 = { amplitude = [0.5], frequency = [0.5] }", inertia=""):
    import tomllib

    text = UR5_SCENARIO.format(arm_extra=arm_extra, last=last, inertia=inertia)
    return parse_scenario(tomllib.loads(text), "ur5.toml")


def test_scenario_with_a_shipped_robot():
    sc = _ur5(
        arm_extra="viscous = [1, 1, 1, 0.5, 0.5, 0.5]", inertia="inertia = [0.004, 0.004, 0.002, 0, 0, 0]"
    )
    assert sc.n_joints == 6 and isinstance(sc.arm, Arm)
    assert sc.arm.viscous.tolist() == [1, 1, 1, 0.5, 0.5, 0.5]
    assert sc.reference.sample(np.array([0.5]))[0].shape == (1, 6)
    sig = sc.segment_sigmas()
    assert sig.shape == (2, sc.arm.base.count)
    assert sc.arm.payload_from_sigma(sig[1]).mass == pytest.approx(2.0)
    np.testing.assert_allclose(sc.arm.payload_from_sigma(sig[1]).com, [0, 0, 0.05], atol=1e-10)
    assert len(sc.position_variance) == 6


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"last": ""}, r"reference.joint6: missing"),
        ({"last": "joint7 = { amplitude = [0.1], frequency = [0.1] }"}, r"reference.joint7: not a joint"),
        (
            {"arm_extra": "viscous = [1, 1]"},
            r"arm.viscous' has 2 numbers; the arm has 6 joints, from the root to the payload frame "
            r"'tool0': shoulder_pan_joint, ",
        ),
        ({"arm_extra": 'payload_frame = "nowhere"'}, r"payload_frame 'nowhere' is not a link"),
        ({"arm_extra": "gravity = [0, 0]"}, r"arm.gravity"),
        ({"arm_extra": "torque_limit = [1, 1, 1, 1, 1, -1]"}, r"arm.torque_limit' must be > 0"),
        ({"inertia": "inertia = [1, 1, 3, 0, 0, 0]"}, r"payload\[0\].inertia:.*rigid body"),
        ({"arm_extra": "wheels = 4"}, r"unknown key 'arm.wheels'; allowed with a URDF"),
        ({"arm_extra": "payload_capacty = 4"}, r"'arm.payload_capacty' \(did you mean 'payload_capacity'"),
    ],
)
def test_bad_urdf_scenarios_name_the_key(kw, match):
    with pytest.raises(ScenarioError, match=match):
        _ur5(**kw)


def test_unknown_robot_and_urdf_path_relative_to_the_scenario(tmp_path):
    import tomllib

    with pytest.raises(ScenarioError, match="not a shipped robot"):
        parse_scenario(tomllib.loads('[arm]\nrobot = "r2d2"\n'), "x.toml")
    p = _write(tmp_path, URDF_OK.format(m="1", ixx="0.01", kind="revolute", limit=LIMIT), "one.urdf")
    sc_file = tmp_path / "s.toml"
    sc_file.write_text(
        '[run]\nduration = 1.0\ncontrollers = ["pd"]\n[arm]\nurdf = "one.urdf"\n'
        "[reference]\njoint1 = { amplitude = [0.2], frequency = [0.5] }\n"
    )
    from adaptive_dd.benchmark.scenario import load_scenario

    sc = load_scenario(sc_file)
    assert sc.arm.urdf == p and sc.n_joints == 1


def test_example_robot_data_urdfs_load_and_pass_the_check():
    from adaptive_dd.errors import ParameterError
    from adaptive_dd.plant.pinocchio_check import cross_check
    from adaptive_dd.robots.example_robot_data import urdf_path

    try:
        path = urdf_path("example-robot-data:ur_description/urdf/ur5_robot.urdf")
    except ParameterError as exc:  # the optional package (the robots and test extras)
        pytest.skip(str(exc))
    arm = Arm.from_urdf(path, "tool0")  # its ee_link, base and tool0: mass 0, zero inertia (kept)
    assert arm.n_joints == 6
    assert all(r.passed for r in cross_check(arm, {"mass": 2.0}, n_states=10))


@pytest.mark.parametrize("name", ["vertical3", "ur5", "panda"])
def test_every_shipped_robot_passes_the_pinocchio_check(arms, name):
    from adaptive_dd.plant.pinocchio_check import cross_check

    for payload in (None, {"mass": 2.0, "com": [0.01, 0.0, 0.03]}):
        results = cross_check(arms[name], payload, n_states=8, rng=np.random.default_rng(5))
        assert all(r.passed for r in results), [str(r) for r in results if not r.passed]


def test_sice_from_urdf_gives_the_default_benchmark_numbers():
    """Issue target: per-seed RMS within 1e-6 relative of ClosedFormTwoLink.sice()'s (a short run, all
    controllers)."""
    import dataclasses
    from pathlib import Path

    from adaptive_dd.benchmark.runner import run_benchmark
    from adaptive_dd.benchmark.scenario import load_scenario

    here = Path(__file__).resolve().parents[1] / "benchmarks" / "scenarios" / "sice_urdf.toml"
    urdf = load_scenario(here)
    default = load_scenario()
    assert isinstance(urdf.arm, Arm) and isinstance(default.arm, Arm)  # one arm type (issue 27)
    assert isinstance(urdf.closed_forms, ClosedFormTwoLink)
    assert default.closed_forms == ClosedFormTwoLink.sice()
    short = {"duration": 6.0, "seeds": 2, "swap_times": (5.0,), "swap_masses": (3.0,)}
    a = run_benchmark(dataclasses.replace(urdf, **short), progress=False)
    b = run_benchmark(dataclasses.replace(default, **short), progress=False)
    for name, run in b.runs.items():
        for f, x, y in zip(run.acc._fields[:-1], a.runs[name].acc, run.acc, strict=False):  # not e_norm
            np.testing.assert_allclose(x, y, rtol=1e-6, atol=1e-12, err_msg=f"{name} {f}")
