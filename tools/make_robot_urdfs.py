"""Write the URDF files of ``adaptive_dd/robots/`` from their published parameter tables.

Run from the repository root::

    python tools/make_robot_urdfs.py          # rewrite the six files
    python tools/make_robot_urdfs.py --check  # exit 1 if a shipped file differs

Every number below is copied from the source named next to it; the only arithmetic
is the change of frame of the UR5's centres of mass and inertias (DH frame i to the
frame of joint i), the cylinder inertias of ``ur_description`` and the map of the
Panda's sigmoidal friction onto viscous + Coulomb (``panda_friction_fit``). The
shipped files are this script's output; ``tests/test_robots.py`` checks that they
still are.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parents[1] / "adaptive_dd" / "robots"
PI = math.pi

# ---------------------------------------------------------------------------- helpers


def _f(x: float) -> str:
    """A float as written in the URDF: shortest repr, -0 and round-off below 1e-15 cleaned."""
    x = float(x)
    if abs(x) < 1e-15:
        return "0"
    r = round(x, 15)
    return repr(r)


def _v(xs) -> str:
    return " ".join(_f(x) for x in xs)


def _link(name: str, mass: float | None = None, com=(0, 0, 0), inertia=None, visual: str = "") -> str:
    if mass is None:
        return f'  <link name="{name}"/>\n'
    i = np.asarray(inertia, dtype=float)
    return (
        f'  <link name="{name}">\n'
        f"    <inertial>\n"
        f'      <origin xyz="{_v(com)}" rpy="0 0 0"/>\n'
        f'      <mass value="{_f(mass)}"/>\n'
        f'      <inertia ixx="{_f(i[0, 0])}" ixy="{_f(i[0, 1])}" ixz="{_f(i[0, 2])}" '
        f'iyy="{_f(i[1, 1])}" iyz="{_f(i[1, 2])}" izz="{_f(i[2, 2])}"/>\n'
        f"    </inertial>\n"
        f"{visual}"
        f"  </link>\n"
    )


def _box_visual(size, xyz) -> str:
    return (
        f"    <visual>\n"
        f'      <origin xyz="{_v(xyz)}" rpy="0 0 0"/>\n'
        f'      <geometry><box size="{_v(size)}"/></geometry>\n'
        f"    </visual>\n"
    )


def _joint(
    name: str,
    parent: str,
    child: str,
    xyz=(0, 0, 0),
    rpy=(0, 0, 0),
    axis=None,
    limit=None,
    damping: float | None = None,
    friction: float | None = None,
) -> str:
    """A joint; ``limit = (lower, upper, effort, velocity)``, ``lower = upper = None`` a continuous joint."""
    kind = "fixed" if axis is None else "revolute" if limit[0] is not None else "continuous"
    s = f'  <joint name="{name}" type="{kind}">\n'
    s += f'    <parent link="{parent}"/>\n    <child link="{child}"/>\n'
    s += f'    <origin xyz="{_v(xyz)}" rpy="{_v(rpy)}"/>\n'
    if axis is not None:
        lo, hi, effort, vel = limit
        s += f'    <axis xyz="{_v(axis)}"/>\n'
        position = "" if lo is None else f'lower="{_f(lo)}" upper="{_f(hi)}" '
        s += f'    <limit {position}effort="{_f(effort)}" velocity="{_f(vel)}"/>\n'
        s += f'    <dynamics damping="{_f(damping)}" friction="{_f(friction)}"/>\n'
    return s + "  </joint>\n"


def _robot(name: str, comment: str, body: str) -> str:
    return f'<?xml version="1.0"?>\n<!--\n{comment.strip()}\n-->\n<robot name="{name}">\n{body}</robot>\n'


def _rx(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _cylinder(mass: float, radius: float, length: float, axis: str) -> np.ndarray:
    """ur_description's ``cylinder_inertial`` (ur_common.xacro) about the centre, axis along ``axis``."""
    side = 0.0833333 * mass * (3 * radius * radius + length * length)
    along = 0.5 * mass * radius * radius
    d = {"x": [along, side, side], "y": [side, along, side], "z": [side, side, along]}[axis]
    return np.diag(d)


# ---------------------------------------------------------------------------- SICE arm


def sice_arm() -> str:
    from adaptive_dd.plant.parameters import TABLE1_PHYSICAL as P
    from adaptive_dd.plant.parameters import TORQUE_LIMITS

    comment = """
The SICE standard direct-drive arm SR-402DD, as adaptive_dd.plant.Arm.sice().
Source: "Recursive simultaneous estimation of a two-link direct drive manipulator with
great variation of payload", Table 1 (base parameters J1 J2 r b1 b2 d1 d2), torque limits
70 and 15 N m (Section 1); the physical set is adaptive_dd.plant.parameters.TABLE1_PHYSICAL,
which maps exactly onto Table 1 (J1 = I1 + m1 a1^2 + m2 l1^2, J2 = I2 + m2 a2^2, r = m2 l1 a2,
eq. 3; docs/paper_reading.md).
Horizontal plane: joint axes along z, links along x, gravity (-z) gives no torque.
Izz of each link is I_i about its centre of mass; Ixx = Iyy = Izz (not seen by planar motion,
chosen so the inertia is positive definite and meets the triangle inequality).
<dynamics> damping = b_i [N m s/rad], friction = d_i [N m] of Table 1.
Position limits +-pi and velocity limits 2 pi rad/s are this project's choice, not the
paper's: the shipped scenario adaptive_dd/scenarios/payload_swap.toml asks of joints 1 / 2 at most
0.7 / 0.8 rad and 2.64 / 3.52 rad/s (sum of its sine amplitudes, and of amplitude * 2 pi f);
tests/test_robots.py checks these figures and the margin against the scenario file.
Frame `tip` (fixed, at l2 along link 2) is the payload frame: the paper's disk sits there.
"""
    vel = 2 * PI
    body = _link("base_link")
    body += _joint(
        "joint1",
        "base_link",
        "link1",
        axis=(0, 0, 1),
        limit=(-PI, PI, TORQUE_LIMITS[0], vel),
        damping=P.b1,
        friction=P.d1,
    )
    body += _link(
        "link1",
        P.m1,
        (P.a1, 0, 0),
        np.eye(3) * P.I1,
        _box_visual((P.l1, 0.04, 0.04), (P.l1 / 2, 0, 0)),
    )
    body += _joint(
        "joint2",
        "link1",
        "link2",
        xyz=(P.l1, 0, 0),
        axis=(0, 0, 1),
        limit=(-PI, PI, TORQUE_LIMITS[1], vel),
        damping=P.b2,
        friction=P.d2,
    )
    body += _link(
        "link2",
        P.m2,
        (P.a2, 0, 0),
        np.eye(3) * P.I2,
        _box_visual((P.l2, 0.04, 0.04), (P.l2 / 2, 0, 0)),
    )
    body += _joint("tip_joint", "link2", "tip", xyz=(P.l2, 0, 0))
    body += _link("tip")
    return _robot("sice_arm", comment, body)


# ---------------------------------------------------------------------------- vertical3

VERTICAL3 = {
    # length [m], mass [kg], b [N m s/rad], d [N m], effort [N m], velocity [rad/s]
    "lengths": (0.40, 0.35, 0.25),
    "masses": (4.0, 3.0, 1.5),
    "width": 0.06,
    "b": (0.8, 0.5, 0.2),
    "d": (1.5, 0.8, 0.3),
    "effort": (100.0, 40.0, 10.0),
    "velocity": (3.0, 4.0, 5.0),
}


def vertical3_static_gravity(g: float = 9.81) -> tuple[float, ...]:
    """Gravity torque [N m] of each joint of vertical3 at the stretched-out pose (q = 0), by hand.

    ``tau_j = g * sum_{k >= j} m_k (x_k - x_j)`` with ``x_k`` the centre of mass of link k and
    ``x_j`` joint j along the horizontal arm.
    """
    v = VERTICAL3
    joints = np.concatenate([[0.0], np.cumsum(v["lengths"])[:-1]])
    coms = joints + 0.5 * np.asarray(v["lengths"])
    m = np.asarray(v["masses"])
    return tuple(float(g * np.sum(m[j:] * (coms[j:] - joints[j]))) for j in range(3))


def vertical3() -> str:
    v = VERTICAL3
    tau = " / ".join(f"{t:.1f}" for t in vertical3_static_gravity())
    comment = f"""
vertical3: the project's own illustrative three-joint planar arm in a vertical plane; not a
product, no published source. Joint axes along y, links along x at q = 0 (the stretched-out,
horizontal pose, where gravity torque is largest), gravity along -z acts on every joint.
Each link is a uniform box (length L, square section 0.06 m), centre of mass at L/2, inertia
of the box about its centre: Ixx = m (w^2 + w^2)/12, Iyy = Izz = m (L^2 + w^2)/12.
Masses 4.0 / 3.0 / 1.5 kg; viscous 0.8 / 0.5 / 0.2 N m s/rad and Coulomb 1.5 / 0.8 / 0.3 N m
(plausible for geared joints of this size, assumed).
Effort limits 100 / 40 / 10 N m: the static gravity torque at the stretched-out pose is
{tau} N m (g = 9.81), below half of each (tests/test_robots.py checks it with pin.rnea).
Position limits +-pi, velocity limits 3 / 4 / 5 rad/s. Frame `tool` at the tip of link 3
is the payload frame.
"""
    w = v["width"]
    body = _link("base_link")
    parent, xyz = "base_link", (0, 0, 0)
    for k in range(3):
        length, m = v["lengths"][k], v["masses"][k]
        inertia = np.diag([m * (2 * w * w) / 12, m * (length**2 + w * w) / 12, m * (length**2 + w * w) / 12])
        link = f"link{k + 1}"
        body += _joint(
            f"joint{k + 1}",
            parent,
            link,
            xyz=xyz,
            axis=(0, 1, 0),
            limit=(-PI, PI, v["effort"][k], v["velocity"][k]),
            damping=v["b"][k],
            friction=v["d"][k],
        )
        body += _link(link, m, (length / 2, 0, 0), inertia, _box_visual((length, w, w), (length / 2, 0, 0)))
        parent, xyz = link, (length, 0, 0)
    body += _joint("tool_joint", parent, "tool", xyz=xyz)
    body += _link("tool")
    return _robot("vertical3", comment, body)


# ---------------------------------------------------------------------------- UR5

# Universal Robots' DH table of the UR5 (standard DH), as quoted "from urcontrol.conf" in
# ros-industrial/universal_robot ur_description/urdf/ur5.urdf.xacro and in
# ur_description/config/ur5/physical_parameters.yaml.
UR5_DH = {
    "a": (0.0, -0.425, -0.39225, 0.0, 0.0, 0.0),
    "d": (0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823),
    "alpha": (PI / 2, 0.0, 0.0, PI / 2, -PI / 2, 0.0),
}
# masses [kg] and centres of mass [m] in DH frame i, same source (the urcontrol.conf comment).
UR5_MASS = (3.7, 8.393, 2.275, 1.219, 1.219, 0.1879)
UR5_COM_DH = (
    (0.0, -0.02561, 0.00193),
    (0.2125, 0.0, 0.11336),
    (0.11993, 0.0, 0.0265),
    (0.0, -0.0018, 0.01634),
    (0.0, 0.0018, 0.01634),
    (0.0, 0.0, -0.001159),
)
# ur_description/config/ur5/physical_parameters.yaml, inertia_parameters.links (radius, length);
# wrist_1..3 appear twice there, and a YAML reader keeps the later entries, used here.
# Cylinder axis in the joint frame as in ur_description/urdf/inc/ur_macro.xacro: along the
# link (x) for the upper arm and forearm, along the joint axis z otherwise.
UR5_CYL = (
    (0.075, 0.178, "z"),
    (0.06, 0.425, "x"),
    (0.06, 0.39225, "x"),
    (0.06, 0.095, "z"),
    (0.06, 0.085, "z"),
    (0.0375, 0.0305, "z"),
)
UR5_NAMES = ("shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3")
UR5_LINKS = (
    "shoulder_link",
    "upper_arm_link",
    "forearm_link",
    "wrist_1_link",
    "wrist_2_link",
    "wrist_3_link",
)
UR5_EFFORT = (150.0, 150.0, 150.0, 28.0, 28.0, 28.0)
# assumed friction (see the file's comment)
UR5_B = (1.0, 1.0, 0.6, 0.2, 0.2, 0.2)
UR5_D = (6.0, 6.0, 4.0, 1.0, 1.0, 1.0)


def ur5() -> str:
    comment = """
Universal Robots UR5 (CB-series), 6 revolute joints, no meshes.
Sources (ros-industrial/universal_robot, ur_description):
- kinematics: UR's standard DH table d1 = 0.089159, a2 = -0.425, a3 = -0.39225, d4 = 0.10915,
  d5 = 0.09465, d6 = 0.0823, alpha = (pi/2, 0, 0, pi/2, -pi/2, 0)
  (urdf/ur5.urdf.xacro, comment "Properties from urcontrol.conf"; config/ur5/physical_parameters.yaml);
- masses 3.7 / 8.393 / 2.275 / 1.219 / 1.219 / 0.1879 kg and centres of mass in DH frame i
  (0, -0.02561, 0.00193), (0.2125, 0, 0.11336), (0.11993, 0, 0.0265), (0, -0.0018, 0.01634),
  (0, 0.0018, 0.01634), (0, 0, -0.001159): the same urcontrol.conf comment in urdf/ur5.urdf.xacro;
- inertias about the centre of mass: ur_description's cylinder_inertial macro
  (urdf/inc/ur_common.xacro: Ixx = Iyy = m (3 r^2 + l^2)/12, Izz = m r^2/2 about the cylinder axis)
  with the radius/length of config/ur5/physical_parameters.yaml (shoulder 0.075/0.178,
  upper arm 0.06/0.425, forearm 0.06/0.39225, wrists 0.06/0.095, 0.06/0.085, 0.0375/0.0305),
  the axis along the link for upper arm and forearm as in urdf/inc/ur_macro.xacro.
  ur_description centres these cylinders at its own offsets; here they sit at UR's centres of mass.
- limits: effort 150 150 150 28 28 28 N m, velocity pi rad/s, position +-2 pi.
Frames: link i's frame is on joint i's axis (z) and turns with it, as in ur_macro.xacro;
`base_link` here is UR's DH base frame, which is ur_description's `base` frame: ur_description's
REP-103 `base_link` is this frame turned by pi about z. `tool0` is the flange (DH frame 6),
the payload frame. Generated by tools/make_robot_urdfs.py.
Friction: the published URDF has none. Viscous 1.0 1.0 0.6 0.2 0.2 0.2 N m s/rad and Coulomb
6 6 4 1 1 1 N m are ASSUMED (order of magnitude of harmonic-drive joints: Coulomb about 4 % of
the effort limit), not identified values.
"""
    a, d, alpha = UR5_DH["a"], UR5_DH["d"], UR5_DH["alpha"]
    body = _link("base_link")
    parent = "base_link"
    # joint i's origin in link (i-1)'s frame: Tx(a_{i-1}) Rx(alpha_{i-1}) Tz(d_i)
    prev_a, prev_alpha = 0.0, 0.0
    for i in range(6):
        r = _rx(prev_alpha)
        xyz = np.array([prev_a, 0.0, 0.0]) + r @ np.array([0.0, 0.0, d[i]])
        body += _joint(
            f"{UR5_NAMES[i]}_joint",
            parent,
            UR5_LINKS[i],
            xyz=xyz,
            rpy=(prev_alpha, 0, 0),
            axis=(0, 0, 1),
            limit=(-2 * PI, 2 * PI, UR5_EFFORT[i], PI),
            damping=UR5_B[i],
            friction=UR5_D[i],
        )
        # DH frame i = link frame * Tx(a_i) Rx(alpha_i)
        ri = _rx(alpha[i])
        com = np.array([a[i], 0.0, 0.0]) + ri @ np.array(UR5_COM_DH[i])
        rad, length, ax = UR5_CYL[i]
        # the cylinder axis is given in the link (joint) frame, as in ur_macro.xacro
        inertia = _cylinder(UR5_MASS[i], rad, length, ax)
        body += _link(UR5_LINKS[i], UR5_MASS[i], com, inertia)
        parent = UR5_LINKS[i]
        prev_a, prev_alpha = a[i], alpha[i]
    body += _joint(
        "wrist_3_link-tool0_fixed_joint", parent, "tool0", xyz=(prev_a, 0, 0), rpy=(prev_alpha, 0, 0)
    )
    body += _link("tool0")
    return _robot("ur5", comment, body)


# ---------------------------------------------------------------------------- Panda

# Franka's documented kinematics (modified DH, Craig): per joint (a_{i-1}, d_i, alpha_{i-1}).
PANDA_MDH = {
    "a": (0.0, 0.0, 0.0, 0.0825, -0.0825, 0.0, 0.088),
    "d": (0.333, 0.0, 0.316, 0.0, 0.384, 0.0, 0.0),
    "alpha": (0.0, -PI / 2, PI / 2, PI / 2, -PI / 2, PI / 2, PI / 2),
    "flange_d": 0.107,
}
# frankaemika/franka_ros franka_description/robots/panda/joint_limits.yaml
PANDA_Q_MIN = (-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973)
PANDA_Q_MAX = (2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973)
PANDA_DQ_MAX = (2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61)
PANDA_TAU_MAX = (87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0)
# Gaz et al. 2019, Tables VIII-IX of the supplementary material, as typed in
# marcocognetti/FrankaEmikaPandaDynModel matlab/ConvertDynPars2VREP/DynPars2VREP.m:
PANDA_MASS = (4.970684, 0.646926, 3.228604, 3.587895, 1.225946, 1.666555, 7.35522e-01)
PANDA_COM = (
    (3.875e-03, 2.081e-03, 0.0),
    (-3.141e-03, -2.872e-02, 3.495e-03),
    (2.7518e-02, 3.9252e-02, -6.6502e-02),
    (-5.317e-02, 1.04419e-01, 2.7454e-02),
    (-1.1953e-02, 4.1065e-02, -3.8437e-02),
    (6.0149e-02, -1.4117e-02, -1.0517e-02),
    (1.0517e-02, -4.252e-03, 6.1597e-02),
)
# barycentric inertia in the link frame: Ixx Ixy Ixz Iyy Iyz Izz [kg m^2]
PANDA_INERTIA = (
    (7.0337e-01, -1.3900e-04, 6.7720e-03, 7.0661e-01, 1.9169e-02, 9.1170e-03),
    (7.9620e-03, -3.9250e-03, 1.0254e-02, 2.8110e-02, 7.0400e-04, 2.5995e-02),
    (3.7242e-02, -4.7610e-03, -1.1396e-02, 3.6155e-02, -1.2805e-02, 1.0830e-02),
    (2.5853e-02, 7.7960e-03, -1.3320e-03, 1.9552e-02, 8.6410e-03, 2.8323e-02),
    (3.5549e-02, -2.1170e-03, -4.0370e-03, 2.9474e-02, 2.2900e-04, 8.6270e-03),
    (1.9640e-03, 1.0900e-04, -1.1580e-03, 4.3540e-03, 3.4100e-04, 5.4330e-03),
    (1.2516e-02, -4.2800e-04, -1.1960e-03, 1.0027e-02, -7.4100e-04, 4.8150e-03),
)
# sigmoidal friction, matlab/dyn_model_panda/get_FrictionTorque.m of the same repository:
# tau_f = -A / (1 + exp(-alpha phi)) + A / (1 + exp(-alpha (qd + phi)))
PANDA_FRICTION_A = (0.54615, 0.87224, 0.64068, 1.2794, 0.83904, 0.30301, 0.56489)
PANDA_FRICTION_PHI = (0.039533, 0.025882, -0.04607, 0.036194, 0.026226, -0.021047, 0.0035526)
PANDA_FRICTION_ALPHA = (5.1181, 9.0657, 10.136, 5.5903, 8.3469, 17.133, 10.336)
FIT_POINTS = 2001


def panda_friction_fit(a: float, phi: float, alpha: float, v_max: float) -> tuple[float, float]:
    """Viscous ``b`` and Coulomb ``d`` fitting the odd part of Gaz et al.'s sigmoid on ``(0, v_max]``.

    The odd part ``g(v) = (tau_f(v) - tau_f(-v)) / 2`` is fitted by least squares with
    ``b v + d`` on ``FIT_POINTS`` equally spaced velocities in ``(0, v_max]``; the even part
    (a constant offset ``A (1/2 - s(alpha phi))`` at speed) is not friction and is dropped.
    """

    def tau(v):
        return -a / (1 + np.exp(-alpha * phi)) + a / (1 + np.exp(-alpha * (v + phi)))

    v = np.linspace(v_max / FIT_POINTS, v_max, FIT_POINTS)
    g = 0.5 * (tau(v) - tau(-v))
    design = np.stack([v, np.ones_like(v)], axis=1)
    (b, d), *_ = np.linalg.lstsq(design, g, rcond=None)
    return float(b), float(d)


def panda() -> str:
    fits = [
        panda_friction_fit(
            PANDA_FRICTION_A[i], PANDA_FRICTION_PHI[i], PANDA_FRICTION_ALPHA[i], PANDA_DQ_MAX[i]
        )
        for i in range(7)
    ]
    b_txt = " ".join(f"{b:.4g}" for b, _ in fits)
    d_txt = " ".join(f"{d:.4g}" for _, d in fits)
    comment = f"""
Franka Emika Panda, 7 revolute joints, no hand; `panda_link8` is the flange (payload frame).
Inertial parameters: C. Gaz, M. Cognetti, A. Oliva, P. Robuffo Giordano, A. De Luca, "Dynamic
identification of the Franka Emika Panda robot with retrieval of feasible parameters using
penalty-based optimization", IEEE RA-L 4(4), 2019: masses, centres of mass (link frame) and
barycentric inertias (link-frame axes) of Tables VIII and IX of its supplementary material, as
typed in marcocognetti/FrankaEmikaPandaDynModel matlab/ConvertDynPars2VREP/DynPars2VREP.m.
Kinematics: Franka's documented modified DH table (a = 0 0 0 0.0825 -0.0825 0 0.088,
d = 0.333 0 0.316 0 0.384 0 0, alpha = 0 -pi/2 pi/2 pi/2 -pi/2 pi/2 pi/2, flange d = 0.107);
link i's frame is DH frame i. Limits: Franka's joint limits (position, velocity 2.175 x4 /
2.61 x3 rad/s, effort 87 x4 / 12 x3 N m), frankaemika/franka_ros
franka_description/robots/panda/joint_limits.yaml.
Friction: Gaz et al.'s model (FrankaEmikaPandaDynModel matlab/dyn_model_panda/get_FrictionTorque.m)
is tau_f = -A/(1+exp(-alpha phi)) + A/(1+exp(-alpha (qd+phi))). Its odd part is fitted by least
squares with b qd + d sign(qd) on 0 < qd <= the joint's velocity limit (tools/make_robot_urdfs.py,
panda_friction_fit); its even part, a constant offset A (1/2 - 1/(1+exp(-alpha phi))) at speed,
is not friction and is dropped. Result: damping b = {b_txt} N m s/rad,
friction d = {d_txt} N m.
Generated by tools/make_robot_urdfs.py.
"""
    m = PANDA_MDH
    body = _link("panda_link0")
    parent = "panda_link0"
    for i in range(7):
        al, a, d = m["alpha"][i], m["a"][i], m["d"][i]
        xyz = np.array([a, 0.0, 0.0]) + _rx(al) @ np.array([0.0, 0.0, d])
        b, dc = fits[i]
        child = f"panda_link{i + 1}"
        body += _joint(
            f"panda_joint{i + 1}",
            parent,
            child,
            xyz=xyz,
            rpy=(al, 0, 0),
            axis=(0, 0, 1),
            limit=(PANDA_Q_MIN[i], PANDA_Q_MAX[i], PANDA_TAU_MAX[i], PANDA_DQ_MAX[i]),
            damping=round(b, 6),
            friction=round(dc, 6),
        )
        ixx, ixy, ixz, iyy, iyz, izz = PANDA_INERTIA[i]
        inertia = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
        body += _link(child, PANDA_MASS[i], PANDA_COM[i], inertia)
        parent = child
    body += _joint("panda_joint8", parent, "panda_link8", xyz=(0, 0, m["flange_d"]))
    body += _link("panda_link8")
    return _robot("panda", comment, body)


# ---------------------------------------------------------------------------- KUKA iiwa 14

IIWA_SOURCE = (
    "RobotLocomotion/drake, manipulation/models/iiwa_description/urdf/iiwa14_no_collision.urdf\n"
    "(commit 0b6a9c384d8cd7200a2015c7c36b52fca21d8635)"
)
# Per joint i = 1..7, Drake's <joint iiwa_joint_i>: origin xyz, rpy, then <limit lower upper effort velocity>
IIWA_JOINTS = (
    ((0, 0, 0.1575), (0, 0, 0), (-2.96705972839, 2.96705972839, 320, 1.4835298641951802)),
    ((0, 0, 0.2025), (PI / 2, 0, PI), (-2.09439510239, 2.09439510239, 320, 1.4835298641951802)),
    ((0, 0.2045, 0), (PI / 2, 0, PI), (-2.96705972839, 2.96705972839, 176, 1.7453292519943295)),
    ((0, 0, 0.2155), (PI / 2, 0, 0), (-2.09439510239, 2.09439510239, 176, 1.3089969389957472)),
    ((0, 0.1845, 0), (-PI / 2, PI, 0), (-2.96705972839, 2.96705972839, 110, 2.2689280275926285)),
    ((0, 0, 0.2155), (PI / 2, 0, 0), (-2.09439510239, 2.09439510239, 40, 2.356194490192345)),
    ((0, 0.081, 0), (-PI / 2, PI, 0), (-3.05432619099, 3.05432619099, 40, 2.356194490192345)),
)
# Per link 0..7, Drake's <inertial>: mass [kg], origin xyz (centre of mass) [m], ixx iyy izz [kg m^2]
# (ixy = ixz = iyz = 0 and rpy = 0 in every link)
IIWA_LINKS = (
    (5.0, (-0.1, 0, 0.07), (0.05, 0.06, 0.03)),
    (5.76, (0, -0.03, 0.12), (0.033, 0.0333, 0.0123)),
    (6.35, (0.0003, 0.059, 0.042), (0.0305, 0.0304, 0.011)),
    (3.5, (0, 0.03, 0.13), (0.025, 0.0238, 0.0076)),
    (3.5, (0, 0.067, 0.034), (0.017, 0.0164, 0.006)),
    (3.5, (0.0001, 0.021, 0.076), (0.01, 0.0087, 0.00449)),
    (1.8, (0, 0.0006, 0.0004), (0.0049, 0.0047, 0.0036)),
    (1.2, (0, 0, 0.02), (0.001, 0.001, 0.001)),
)
IIWA_DAMPING = 0.5  # N m s/rad, Drake's <dynamics damping> of every joint (no Coulomb friction given)
IIWA_FLANGE = 0.045  # m, Drake's fixed joint iiwa_joint_ee to iiwa_link_ee_kuka along link 7's z


def iiwa14() -> str:
    comment = f"""
KUKA LBR iiwa 14 R820, 7 revolute joints, no meshes; `iiwa_link_ee_kuka` is the flange
(the payload frame). Source of every number:
{IIWA_SOURCE}:
the joints' origins, axes (z) and <limit> (position, effort 320 320 176 176 110 40 40 N m,
velocity), the links' <inertial> (masses, centres of mass, inertias about them; Drake notes
that several masses were changed from KUKA's CAD values) and <dynamics damping="0.5">.
Licence: Drake's iiwa_description folder is BSD-3-Clause (Drake's licence); its files were first
taken from SalvoVirga/iiwa_stack (BSD licence, iiwa_stack.LICENSE.txt there) and substantially
modified by Drake. Left out: visuals, collision, Gazebo and transmission tags, Drake's
drake:acceleration limit attributes and its tool0 frame. The flange's fixed joint has rpy = 0
here: Drake writes rpy = (pi, pi, pi), the same rotation (the identity).
Friction: viscous 0.5 N m s/rad per joint as Drake gives; no Coulomb friction or armature (a
scenario may add them).
Generated by tools/make_robot_urdfs.py.
"""
    body = _link("base")
    body += _joint("iiwa_base_joint", "base", "iiwa_link_0")
    m, com, diag = IIWA_LINKS[0]
    body += _link("iiwa_link_0", m, com, np.diag(diag))
    parent = "iiwa_link_0"
    for i, (xyz, rpy, limit) in enumerate(IIWA_JOINTS):
        child = f"iiwa_link_{i + 1}"
        body += _joint(
            f"iiwa_joint_{i + 1}", parent, child, xyz=xyz, rpy=rpy, axis=(0, 0, 1), limit=limit,
            damping=IIWA_DAMPING, friction=0.0,
        )  # fmt: skip
        m, com, diag = IIWA_LINKS[i + 1]
        body += _link(child, m, com, np.diag(diag))
        parent = child
    body += _joint("iiwa_joint_ee", parent, "iiwa_link_ee_kuka", xyz=(0, 0, IIWA_FLANGE))
    body += _link("iiwa_link_ee_kuka")
    return _robot("iiwa14", comment, body)


# ---------------------------------------------------------------------------- Kinova Gen3

GEN3_SOURCE = (
    "Kinovarobotics/ros_kortex, kortex_description/arms/gen3/7dof/urdf/gen3_macro.xacro\n"
    "(commit 5fce8b7ab9b957834696d02c725f44efc931392b)"
)
GEN3_LINKS_NAMES = (
    "base_link",
    "shoulder_link",
    "half_arm_1_link",
    "half_arm_2_link",
    "forearm_link",
    "spherical_wrist_1_link",
    "spherical_wrist_2_link",
    "bracelet_link",
)
# Per joint i = 1..7, the macro's <joint joint_i>: origin xyz, rpy (as Kinova writes them, 3.1416
# and 1.5708 included), then <limit lower upper effort velocity> (None, None: type "continuous").
GEN3_JOINTS = (
    ((0, 0, 0.15643), (3.1416, 2.7629e-18, -4.9305e-36), (None, None, 39, 1.3963)),
    ((0, 0.005375, -0.12838), (1.5708, 2.1343e-17, -1.1102e-16), (-2.41, 2.41, 39, 1.3963)),
    ((0, -0.21038, -0.006375), (-1.5708, 1.2326e-32, -2.9122e-16), (None, None, 39, 1.3963)),
    ((0, 0.006375, -0.21038), (1.5708, -6.6954e-17, -1.6653e-16), (-2.66, 2.66, 39, 1.3963)),
    ((0, -0.20843, -0.006375), (-1.5708, 2.2204e-16, -6.373e-17), (None, None, 9, 1.2218)),
    ((0, 0.00017505, -0.10593), (1.5708, 9.2076e-28, -8.2157e-15), (-2.23, 2.23, 9, 1.2218)),
    ((0, -0.10593, -0.00017505), (-1.5708, -5.5511e-17, 9.6396e-17), (None, None, 9, 1.2218)),
)
# Per link 0..7, the macro's <inertial>: mass [kg], origin xyz (centre of mass) [m],
# ixx ixy ixz iyy iyz izz [kg m^2] about it (rpy = 0 in every link); the bracelet is the
# `vision = false` branch (bracelet_no_vision_link).
GEN3_INERTIALS = (
    (1.697, (-0.000648, -0.000166, 0.084487), (0.004622, 9e-06, 6e-05, 0.004495, 9e-06, 0.002079)),
    (1.3773, (-2.3e-05, -0.010364, -0.07336), (0.00457, 1e-06, 2e-06, 0.004831, 0.000448, 0.001409)),
    (1.1636, (-4.4e-05, -0.09958, -0.013278), (0.011088, 5e-06, 0, 0.001072, -0.000691, 0.011255)),
    (1.1636, (-4.4e-05, -0.006641, -0.117892), (0.010932, 0, -7e-06, 0.011127, 0.000606, 0.001043)),
    (0.9302, (-1.8e-05, -0.075478, -0.015006), (0.008147, -1e-06, 0, 0.000631, -0.0005, 0.008316)),
    (0.6781, (1e-06, -0.009432, -0.063883), (0.001596, 0, 0, 0.001607, 0.000256, 0.000399)),
    (0.6781, (1e-06, -0.045483, -0.00965), (0.001641, 0, 0, 0.00041, -0.000278, 0.001641)),
    (0.364, (-9.3e-05, 0.000132, -0.022905), (0.000214, 0, 1e-06, 0.000223, -2e-06, 0.00024)),
)
# the macro's fixed joint end_effector (bracelet_link to end_effector_link): xyz, rpy
GEN3_FLANGE = ((0, 0, -0.0615250000000001), (3.14159265358979, 1.09937075168372e-32, 0))
# assumed friction (see the file's comment): large actuators (joints 1-4), small ones (5-7)
GEN3_B = (0.3, 0.3, 0.3, 0.3, 0.1, 0.1, 0.1)
GEN3_D = (1.0, 1.0, 1.0, 1.0, 0.25, 0.25, 0.25)


def gen3() -> str:
    comment = f"""
Kinova Gen3 (7 DoF, no vision module), 7 revolute joints (1, 3, 5, 7 continuous, as Kinova
writes them), no meshes; `end_effector_link` is the flange (the payload frame). Source of every
number but the friction:
{GEN3_SOURCE},
the `load_arm` macro with dof = 7, vision = false, no prefix: the joints' origins (rpy as Kinova
writes them: 3.1416 and 1.5708, not pi and pi/2; the rounding tilts the axes by up to 7e-6 rad, which
leaves 65 base parameters where exact right angles give 62: mx1, my1's group and Ia2 are seen
only through it, and a record cannot identify them; docs/any_arm.md), axes (z) and <limit>
(position +-2.41 / +-2.66 / +-2.23 rad on joints 2 / 4 / 6, effort 39 N m on joints 1-4 and
9 N m on 5-7, velocity 1.3963 and 1.2218 rad/s), the links' <inertial> (masses, centres of
mass, inertias about them; the bracelet without the vision module, 0.364 kg) and the fixed
joint end_effector.
Licence: ros_kortex is BSD-3-Clause ("Copyright (c) 2018, Kinova Robotics", its LICENSE).
Left out: visuals, collision, transmissions.
Kinova's data sheet (Gen3 user guide, "Normal use definition"): 4 kg mid-range continuous
payload, 1.1 kg at full reach.
Friction: the published URDF has none. Viscous 0.3 (joints 1-4) / 0.1 (5-7) N m s/rad and
Coulomb 1.0 / 0.25 N m are ASSUMED (harmonic drives; Coulomb about 2.5-3 % of the effort limit,
as assumed for the UR5 and the iiwa), not identified values; no armature (a scenario adds it).
Generated by tools/make_robot_urdfs.py.
"""
    names = GEN3_LINKS_NAMES
    m, com, (ixx, ixy, ixz, iyy, iyz, izz) = GEN3_INERTIALS[0]
    body = _link(names[0], m, com, np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]))
    for i, (xyz, rpy, limit) in enumerate(GEN3_JOINTS):
        body += _joint(
            f"joint_{i + 1}", names[i], names[i + 1], xyz=xyz, rpy=rpy, axis=(0, 0, 1), limit=limit,
            damping=GEN3_B[i], friction=GEN3_D[i],
        )  # fmt: skip
        m, com, (ixx, ixy, ixz, iyy, iyz, izz) = GEN3_INERTIALS[i + 1]
        inertia = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
        body += _link(names[i + 1], m, com, inertia)
    xyz, rpy = GEN3_FLANGE
    body += _joint("end_effector", names[-1], "end_effector_link", xyz=xyz, rpy=rpy)
    body += _link("end_effector_link")
    return _robot("gen3", comment, body)


FILES = {
    "sice_arm.urdf": sice_arm,
    "vertical3.urdf": vertical3,
    "ur5.urdf": ur5,
    "panda.urdf": panda,
    "iiwa14.urdf": iiwa14,
    "gen3.urdf": gen3,
}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="compare with the shipped files, write nothing")
    args = parser.parse_args(argv)
    stale = []
    for name, make in FILES.items():
        text = make()
        path = OUT / name
        if args.check:
            if not path.exists() or path.read_text() != text:
                stale.append(name)
        else:
            path.write_text(text)
            print(f"wrote {path}")
    if stale:
        print("differ from tools/make_robot_urdfs.py:", ", ".join(stale))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
