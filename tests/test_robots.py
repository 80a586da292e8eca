"""The shipped URDF robots (adaptive_dd/robots): they load, are physically consistent, and match
their published tables (SICE arm = Arm.sice(); UR5 and Panda forward kinematics = their DH tables).
"""

from __future__ import annotations

import math
import tomllib
import warnings
from importlib import resources
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from adaptive_dd.plant import ClosedFormTwoLink
from adaptive_dd.plant.dynamics import mass_matrix
from adaptive_dd.plant.parameters import L1, L2, TORQUE_LIMITS
from adaptive_dd.robots import ROBOTS, RobotInfo, UnknownRobotError, robot_urdf

ROOT = Path(__file__).resolve().parents[1]
N_JOINTS = {"sice_arm": 2, "vertical3": 3, "ur5": 6, "panda": 7, "iiwa14": 7, "gen3": 7}
CONTINUOUS = {"gen3": 4}  # joints of type "continuous": (cos, sin) in Pinocchio's q
PI = math.pi


def _load(name: str) -> pin.Model:
    return pin.buildModelFromUrdf(str(robot_urdf(name)))


def _frame(model: pin.Model, q: np.ndarray, frame: str) -> pin.SE3:
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    return data.oMf[model.getFrameId(frame)]


# ------------------------------------------------------------------------------------ registry


def test_registry_lists_every_shipped_file():
    assert set(ROBOTS) == set(N_JOINTS)
    shipped = {p.name for p in (ROOT / "adaptive_dd" / "robots").glob("*.urdf")}
    assert shipped == {info.file for info in ROBOTS.values()}
    for name, info in ROBOTS.items():
        assert isinstance(info, RobotInfo) and info.description
        assert robot_urdf(name).is_file()


def test_unknown_robot_names_the_known_ones():
    with pytest.raises(UnknownRobotError) as err:
        robot_urdf("ur10")
    assert isinstance(err.value, KeyError)
    msg = str(err.value)
    assert "'ur10'" in msg and all(name in msg for name in ROBOTS)


def test_urdfs_are_package_data():
    # pyproject ships them: the files must be reachable as package resources
    files = {p.name for p in resources.files("adaptive_dd.robots").iterdir()}
    assert {info.file for info in ROBOTS.values()} <= files
    text = (ROOT / "pyproject.toml").read_text()
    assert '"adaptive_dd.robots" = ["*.urdf"]' in text


def test_files_are_the_generator_output():
    """The generator's ``--check`` (run as a user runs it, not imported by path: issue 27) finds the
    shipped files equal to what it writes."""
    import subprocess
    import sys

    gen = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "make_robot_urdfs.py"), "--check"],
        capture_output=True, text=True, timeout=300, check=False,
    )  # fmt: skip
    assert gen.returncode == 0, gen.stdout + gen.stderr


# ------------------------------------------------------------------------------- every robot


@pytest.mark.parametrize("name", sorted(N_JOINTS))
def test_loads_without_warnings(name, capfd):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model = _load(name)
    out, err = capfd.readouterr()
    assert out == "" and err == ""
    assert model.nv == N_JOINTS[name]
    assert model.nq == N_JOINTS[name] + CONTINUOUS.get(name, 0)
    assert model.njoints == N_JOINTS[name] + 1  # + the universe
    assert all(j.shortname().startswith("JointModelR") for j in model.joints[1:])  # revolute
    assert model.existFrame(ROBOTS[name].payload_frame)


@pytest.mark.parametrize("name", sorted(N_JOINTS))
def test_limits_present_and_positive(name):
    model = _load(name)
    for arr in (model.effortLimit, model.velocityLimit):
        assert arr.shape == (model.nv,) and np.all(np.isfinite(arr))
    for arr in (model.lowerPositionLimit, model.upperPositionLimit):
        assert arr.shape == (model.nq,) and np.all(np.isfinite(arr))
    assert np.all(model.effortLimit > 0)
    assert np.all(model.velocityLimit > 0)
    assert np.all(model.upperPositionLimit > model.lowerPositionLimit)
    assert np.all(model.damping >= 0) and np.all(model.friction >= 0)


@pytest.mark.parametrize("name", sorted(N_JOINTS))
def test_inertias_physically_consistent(name):
    model = _load(name)
    for i in range(1, model.njoints):
        inertia = model.inertias[i]
        assert inertia.mass > 0, model.names[i]
        rot = inertia.inertia  # about the centre of mass
        np.testing.assert_allclose(rot, rot.T, atol=0)
        ev = np.linalg.eigvalsh(rot)
        assert ev[0] > 0, (model.names[i], ev)
        # triangle inequality of the principal moments: each <= the sum of the other two
        assert 2 * ev[-1] <= ev.sum() * (1 + 1e-12), (model.names[i], ev)


# ---------------------------------------------------------------------------------- SICE arm


def test_sice_mass_matrix_equals_arm_sice():
    model, arm = _load("sice_arm"), ClosedFormTwoLink.sice()
    data = model.createData()
    rng = np.random.default_rng(20261124)
    for q in rng.uniform(-PI, PI, size=(20, 2)):
        m_pin = pin.crba(model, data, q)
        m_pin = np.triu(m_pin) + np.triu(m_pin, 1).T
        np.testing.assert_allclose(m_pin, mass_matrix(q, arm.sigma), rtol=0, atol=1e-12)


def test_sice_friction_limits_and_no_gravity():
    model, arm = _load("sice_arm"), ClosedFormTwoLink.sice()
    np.testing.assert_array_equal(model.damping, arm.sigma[3:5])
    np.testing.assert_array_equal(model.friction, arm.sigma[5:7])
    np.testing.assert_array_equal(model.effortLimit, TORQUE_LIMITS)
    # horizontal plane: gravity gives no torque about the vertical axes
    data = model.createData()
    g = pin.computeGeneralizedGravity(model, data, np.array([0.3, -1.2]))
    np.testing.assert_allclose(g, 0.0, atol=1e-12)


def test_a_shipped_robot_brings_its_data_sheet_and_a_scenario_overrides_it():
    """``robot = "sice_arm"`` is the paper's arm whichever runtime runs it: its data sheet (the
    encoders and noise of Tables 2 and 4, the 12-bit D/A, payloads centred on the tip) as
    ``Arm.sice()`` and the closed forms' record have it; a scenario's ``[arm]`` and ``[noise]`` keys
    still override each of them, and a robot whose sheet states nothing keeps a URDF arm's defaults."""
    from adaptive_dd.benchmark.scenario import parse_scenario
    from adaptive_dd.plant import Arm

    closed = ClosedFormTwoLink.sice()
    for general in (False, True):
        arm = parse_scenario({"arm": {"robot": "sice_arm", "general": general}}).arm
        assert arm.sensor == closed.sensor == Arm.sice().sensor
        assert arm.actuator.dac_bits == closed.actuator.dac_bits == 12
        assert arm.payload_offset == Arm.sice().payload_offset == 0.0
    table = {"robot": "sice_arm", "general": True, "encoder_counts": [4096, 4096], "dac_bits": 16}
    sc = parse_scenario(
        {"arm": {**table, "payload_offset": 0.02}, "noise": {"velocity_variance": [1e-6, 1e-6]}}
    )
    assert sc.arm.sensor.encoder_counts == (4096, 4096) and sc.arm.actuator.dac_bits == 16
    assert sc.arm.payload_offset == 0.02
    assert tuple(sc.arm.sensor.velocity_variance) == (1e-6, 1e-6)
    assert tuple(sc.arm.sensor.position_variance) == closed.sensor.position_variance
    ur5 = Arm.from_urdf(robot_urdf("ur5"), "tool0")
    assert ROBOTS["ur5"].stated(ur5) == {}


def test_sice_tip_frame():
    model = _load("sice_arm")
    np.testing.assert_allclose(_frame(model, np.zeros(2), "tip").translation, [L1 + L2, 0, 0], atol=1e-15)
    q = np.array([0.7, -1.9])
    expected = [L1 * math.cos(q[0]) + L2 * math.cos(q.sum()), L1 * math.sin(q[0]) + L2 * math.sin(q.sum()), 0]
    np.testing.assert_allclose(_frame(model, q, "tip").translation, expected, atol=1e-15)


def test_sice_limits_not_reached_by_shipped_scenario():
    model = _load("sice_arm")
    scen = tomllib.loads((ROOT / "adaptive_dd" / "scenarios" / "payload_swap.toml").read_text())
    peaks = []
    for k in range(2):
        ref = scen["reference"][f"joint{k + 1}"]
        amp, freq = np.asarray(ref["amplitude"]), np.asarray(ref["frequency"])
        q_max = abs(ref["offset"]) + amp.sum()
        qd_max = float(np.sum(amp * 2 * PI * freq))
        assert q_max < 0.5 * model.upperPositionLimit[k] and -q_max > 0.5 * model.lowerPositionLimit[k]
        assert qd_max < 0.6 * model.velocityLimit[k]
        peaks.append((q_max, qd_max))
    # the figures the file's comment gives
    (q1, qd1), (q2, qd2) = peaks
    assert f"{q1:.1f} / {q2:.1f} rad and {qd1:.2f} / {qd2:.2f} rad/s" in robot_urdf("sice_arm").read_text()


# --------------------------------------------------------------------------------- vertical3


def test_vertical3_gravity_below_half_the_effort():
    model = _load("vertical3")
    data = model.createData()
    np.testing.assert_allclose(model.gravity.linear, [0, 0, -9.81])
    stretched = pin.rnea(model, data, np.zeros(3), np.zeros(3), np.zeros(3))
    assert np.all(np.abs(stretched) > 0.1)
    # the stretched-out pose is the worst one for every joint: check it over many poses
    rng = np.random.default_rng(7)
    worst = np.abs(stretched)
    for q in rng.uniform(model.lowerPositionLimit, model.upperPositionLimit, size=(500, 3)):
        worst = np.maximum(worst, np.abs(pin.computeGeneralizedGravity(model, data, q)))
    np.testing.assert_allclose(worst, np.abs(stretched), rtol=0.02)
    assert np.all(worst < 0.5 * model.effortLimit), (worst, model.effortLimit)
    # by hand (masses 4, 3, 1.5 kg at the middle of links 0.4, 0.35, 0.25 m), as the file's comment says
    by_hand = 9.81 * np.array([4 * 0.2 + 3 * 0.575 + 1.5 * 0.875, 3 * 0.175 + 1.5 * 0.475, 1.5 * 0.125])
    np.testing.assert_allclose(np.abs(stretched), by_hand, rtol=1e-12)
    text = robot_urdf("vertical3").read_text()
    assert " / ".join(f"{t:.1f}" for t in by_hand) + " N m" in text


# ---------------------------------------------------------------------------------- UR5


def _dh(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    """Standard DH: Rz(theta) Tz(d) Tx(a) Rx(alpha)."""
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array(
        [[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, d], [0, 0, 0, 1]]
    )


def _mdh(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    """Modified DH (Craig): Rx(alpha) Tx(a) Rz(theta) Tz(d)."""
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array(
        [[ct, -st, 0, a], [st * ca, ct * ca, -sa, -d * sa], [st * sa, ct * sa, ca, d * ca], [0, 0, 0, 1]]
    )


# Universal Robots' published UR5 DH table
UR5_D = (0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823)
UR5_A = (0.0, -0.425, -0.39225, 0.0, 0.0, 0.0)
UR5_ALPHA = (PI / 2, 0.0, 0.0, PI / 2, -PI / 2, 0.0)


def test_ur5_forward_kinematics_equals_dh_table():
    """tool0 is DH frame 6; base_link is the DH base frame (base rotation: identity).

    ur_description's REP-103 ``base_link`` would be this base turned by pi about z.
    """
    model = _load("ur5")
    rng = np.random.default_rng(5)
    qs = np.vstack([np.zeros(6), rng.uniform(-PI, PI, size=(6, 6))])
    for q in qs:
        t = np.eye(4)
        for i in range(6):
            t = t @ _dh(q[i], UR5_D[i], UR5_A[i], UR5_ALPHA[i])
        placement = _frame(model, q, "tool0")
        np.testing.assert_allclose(placement.translation, t[:3, 3], atol=1e-9)
        np.testing.assert_allclose(placement.rotation, t[:3, :3], atol=1e-9)
    # q = 0 by hand: x = a2 + a3, y = -(d4 + d6), z = d1 - d5
    np.testing.assert_allclose(
        _frame(model, np.zeros(6), "tool0").translation, [-0.81725, -0.19145, -0.005491], atol=1e-12
    )


def test_ur5_published_masses_and_limits():
    model = _load("ur5")
    masses = [model.inertias[i].mass for i in range(1, 7)]
    # UR's published link masses (ur_description/urdf/ur5.urdf.xacro, urcontrol.conf)
    np.testing.assert_array_equal(masses, [3.7, 8.393, 2.275, 1.219, 1.219, 0.1879])
    np.testing.assert_array_equal(model.effortLimit, [150, 150, 150, 28, 28, 28])
    np.testing.assert_allclose(model.velocityLimit, PI, rtol=1e-15)
    np.testing.assert_allclose(model.upperPositionLimit, 2 * PI, rtol=1e-15)
    np.testing.assert_allclose(model.lowerPositionLimit, -2 * PI, rtol=1e-15)


# -------------------------------------------------------------------------------- Panda

# Franka's documented modified DH table: (a_{i-1}, d_i, alpha_{i-1}); flange d = 0.107
PANDA_A = (0.0, 0.0, 0.0, 0.0825, -0.0825, 0.0, 0.088)
PANDA_D = (0.333, 0.0, 0.316, 0.0, 0.384, 0.0, 0.0)
PANDA_ALPHA = (0.0, -PI / 2, PI / 2, PI / 2, -PI / 2, PI / 2, PI / 2)


def test_panda_forward_kinematics_equals_modified_dh():
    model = _load("panda")
    rng = np.random.default_rng(11)
    lo, hi = model.lowerPositionLimit, model.upperPositionLimit
    qs = np.vstack([np.zeros(7), rng.uniform(lo, hi, size=(6, 7))])
    for q in qs:
        t = np.eye(4)
        for i in range(7):
            t = t @ _mdh(q[i], PANDA_D[i], PANDA_A[i], PANDA_ALPHA[i])
        t = t @ _mdh(0.0, 0.107, 0.0, 0.0)
        placement = _frame(model, q, "panda_link8")
        np.testing.assert_allclose(placement.translation, t[:3, 3], atol=1e-9)
        np.testing.assert_allclose(placement.rotation, t[:3, :3], atol=1e-9)
    # q = 0 by hand: x = 0.0825 - 0.0825 + 0.088, z = 0.333 + 0.316 + 0.384 - 0.107
    np.testing.assert_allclose(
        _frame(model, np.zeros(7), "panda_link8").translation, [0.088, 0, 0.926], atol=1e-12
    )


def test_panda_gaz_parameters_and_limits():
    model = _load("panda")
    masses = [model.inertias[i].mass for i in range(1, 8)]
    # Gaz et al. 2019, supplementary Tables VIII-IX (FrankaEmikaPandaDynModel DynPars2VREP.m)
    np.testing.assert_array_equal(
        masses, [4.970684, 0.646926, 3.228604, 3.587895, 1.225946, 1.666555, 0.735522]
    )
    np.testing.assert_array_equal(model.effortLimit, [87, 87, 87, 87, 12, 12, 12])
    np.testing.assert_array_equal(model.velocityLimit, [2.175] * 4 + [2.61] * 3)
    np.testing.assert_array_equal(
        model.upperPositionLimit, [2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973]
    )
    np.testing.assert_array_equal(
        model.lowerPositionLimit, [-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973]
    )


def test_panda_friction_is_the_fit_of_the_gaz_sigmoid():
    """damping, friction = least-squares line through the odd part of the identified sigmoid."""
    model = _load("panda")
    # matlab/dyn_model_panda/get_FrictionTorque.m of FrankaEmikaPandaDynModel
    a = np.array([0.54615, 0.87224, 0.64068, 1.2794, 0.83904, 0.30301, 0.56489])
    phi = np.array([0.039533, 0.025882, -0.04607, 0.036194, 0.026226, -0.021047, 0.0035526])
    alpha = np.array([5.1181, 9.0657, 10.136, 5.5903, 8.3469, 17.133, 10.336])

    def tau_f(v, k):
        return -a[k] / (1 + np.exp(-alpha[k] * phi[k])) + a[k] / (1 + np.exp(-alpha[k] * (v + phi[k])))

    for k in range(7):
        v = np.linspace(0, model.velocityLimit[k], 2002)[1:]
        odd = 0.5 * (tau_f(v, k) - tau_f(-v, k))
        slope, intercept = np.polyfit(v, odd, 1)
        np.testing.assert_allclose([model.damping[k], model.friction[k]], [slope, intercept], atol=1e-6)
        # Coulomb below the sigmoid's half-range A/2; past its rise (|qd| >= 0.5 rad/s) the
        # line b qd + d stays within 15 % of A of the identified curve
        assert 0 < model.friction[k] < a[k] / 2
        fast = v >= 0.5
        assert np.max(np.abs(slope * v[fast] + intercept - odd[fast])) < 0.15 * a[k]


def test_panda_gravity_near_gaz_symbolic_model():
    """Joint-2 gravity torque against Gaz et al.'s own model (get_GravityVector.m), by hand.

    Their symbolic g(q) (FrankaEmikaPandaDynModel matlab/dyn_model_panda/get_GravityVector.m,
    g0 = 9.80665) at q = 0: g2 = g0 (5.3688e-3 - 0.68735 + 0.48884 + 1.0004e-2 - 0.16568 - 6.2308e-3)
    = -0.3550563 g0; at q2 = pi/2, the rest 0: g2 = g0 (-3.1025757 - 1.7184882 + 0.0677117)
    = -4.7533522 g0. Its coefficients come from their regression, not exactly from the retrieved
    parameters this file holds, hence 2 %: a wrong frame or centre of mass is off by far more.
    """
    model = _load("panda")
    model.gravity.linear[:] = [0.0, 0.0, -9.80665]
    data = model.createData()
    q = np.zeros(7)
    np.testing.assert_allclose(
        pin.computeGeneralizedGravity(model, data, q)[1], -0.3550563 * 9.80665, rtol=0.02
    )
    q[1] = PI / 2
    np.testing.assert_allclose(
        pin.computeGeneralizedGravity(model, data, q)[1], -4.7533522 * 9.80665, rtol=0.02
    )


# ---------------------------------------------------------------------------- Kinova Gen3


def test_gen3_published_masses_limits_and_joint_types():
    """Kinova's ros_kortex gen3_macro.xacro (dof 7, no vision): masses, limits, continuous joints."""
    model = _load("gen3")
    masses = [model.inertias[i].mass for i in range(1, 8)]
    np.testing.assert_array_equal(masses, [1.3773, 1.1636, 1.1636, 0.9302, 0.6781, 0.6781, 0.364])
    np.testing.assert_array_equal(model.effortLimit, [39] * 4 + [9] * 3)
    np.testing.assert_array_equal(model.velocityLimit, [1.3963] * 4 + [1.2218] * 3)
    kinds = [j.shortname() for j in model.joints[1:]]
    assert kinds == ["JointModelRUBZ", "JointModelRZ"] * 3 + ["JointModelRUBZ"]
    # the revolute joints 2, 4, 6: Kinova's position limits (idx_q of each)
    rev = [model.joints[k].idx_q for k in (2, 4, 6)]
    np.testing.assert_array_equal(model.upperPositionLimit[rev], [2.41, 2.66, 2.23])
    np.testing.assert_array_equal(model.lowerPositionLimit[rev], [-2.41, -2.66, -2.23])


def test_gen3_stretched_upright_height():
    """At q = 0 the Gen3 stands straight up: the flange's height is the sum of the macro's joint
    offsets along the chain (0.15643 + 0.12838 + 0.21038 + 0.21038 + 0.20843 + 0.10593 + 0.10593
    + 0.061525 = 1.187385 m), off the base's axis by the sideways offsets (0.005375 + 3 x 0.006375
    + 2 x 0.00017505 = 0.02485 m); Kinova writes 3.1416 and 1.5708 for pi and pi/2, which moves
    the flange by some micrometres."""
    model = _load("gen3")
    flange = _frame(model, pin.neutral(model), "end_effector_link").translation
    np.testing.assert_allclose(flange[2], 1.187385, atol=2e-5)
    np.testing.assert_allclose(np.hypot(flange[0], flange[1]), 0.0248501, atol=2e-5)
