"""Arms nobody tuned for: a plausible fixed-base serial arm drawn from a seed.

:func:`random_arm` draws a 3-7 joint revolute arm of one of the kinematic kinds real arms have
(a yaw-pitch-pitch shoulder and elbow with a wrist of pitches and rolls, a UR-like offset wrist,
a seven-joint spherical-roll-spherical arm, a vertical planar arm), with link lengths, masses,
centres of mass and full inertias of a rigid body (a box of random proportions turned by a
random rotation, so that every inertia is positive definite and within the triangle
inequality), viscous and Coulomb friction, reflected rotor inertia (armature), a payload
capacity, a reference (two sines per joint, the form of a scenario's ``[reference]``), joint
position and velocity limits around that reference with a margin, and torque limits from the
task: the peak inverse-dynamics torque along the reference with the rated payload (its centre of
mass up to :data:`PAYLOAD_COM_REACH` from the flange) times a drawn margin.

Everything follows from ``numpy.random.default_rng(seed)``: the same seed, the same arm, on any
machine. In a scenario, ``[arm] robot = "random:SEED"`` names one (its capacity, armature and
reference are the defaults of ``[arm] payload_capacity``, ``[arm] armature`` and
``[reference]``); ``adaptive-dd benchmark FILE --arms N`` runs a scenario over N of them.
"""

from __future__ import annotations

import copy
import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from adaptive_dd.errors import ParameterError
from adaptive_dd.plant.two_link_urdf import cached_urdf

__all__ = [
    "PAYLOAD_COM_REACH",
    "RANDOM_PREFIX",
    "RandomArm",
    "parse_random_robot",
    "random_arm",
    "random_arm_joints",
    "with_random_arm",
]

RANDOM_PREFIX = "random:"
"""``[arm] robot = "random:SEED"`` names the arm :func:`random_arm` draws from ``SEED``."""

PAYLOAD_COM_REACH = 0.1
"""m: the torque limits hold the rated payload with its centre of mass this far from the flange
(0.05 m sideways and 0.1 m out), on top of the task."""

_AXES = {"yaw": "0 0 1", "roll": "0 0 1", "pitch": "0 1 0"}

# (axis kind, the segment after the joint) per kind of arm: S shoulder height, U upper arm,
# F forearm (U1/U2, F1/F2: the two parts when a roll joint splits it), W a wrist link
_KINDS: dict[str, tuple[tuple[str, str], ...]] = {
    "articulated": (
        ("yaw", "S"),
        ("pitch", "U"),
        ("pitch", "F1"),
        ("roll", "F2"),
        ("pitch", "W"),
        ("roll", "W"),
    ),
    "offset_wrist": (
        ("yaw", "S"),
        ("pitch", "U"),
        ("pitch", "F"),
        ("pitch", "W"),
        ("yaw", "W"),
        ("pitch", "W"),
    ),
    "palletizer": (("yaw", "S"), ("pitch", "U"), ("pitch", "F"), ("pitch", "W"), ("roll", "W")),
    "redundant": (
        ("yaw", "S"),
        ("pitch", "U1"),
        ("roll", "U2"),
        ("pitch", "F1"),
        ("roll", "F2"),
        ("pitch", "W"),
        ("roll", "W"),
    ),
    "planar_vertical": (("pitch", "U"), ("pitch", "F"), ("pitch", "W"), ("pitch", "W")),
}
_KIND_JOINTS = {
    "articulated": (3, 4, 5, 6),
    "offset_wrist": (5, 6),
    "palletizer": (3, 4, 5),
    "redundant": (7,),
    "planar_vertical": (3, 4),
}


@dataclass(frozen=True)
class RandomArm:
    """One drawn arm.

    Attributes
    ----------
    seed : int
        The seed it was drawn from.
    kind : str
        The kinematic kind (a key of the module's kinds: ``articulated``, ``offset_wrist``,
        ``palletizer``, ``redundant``, ``planar_vertical``).
    urdf : str
        The URDF text (links ``base_link``, ``link1`` .. ``linkN``, ``tool``; joints
        ``joint1`` .. ``jointN``, revolute, with limits and ``<dynamics>``).
    payload_frame : str
        ``"tool"``: the flange, where a payload is attached.
    payload_capacity : float
        The rated payload [kg].
    armature : tuple of float
        Reflected rotor inertia per joint [kg m^2].
    reference : dict
        A scenario's ``[reference]`` table: ``ramp`` and ``joint1`` .. ``jointN`` with
        ``offset``, ``amplitude``, ``frequency``, ``phase`` (rad, Hz, rad).
    task_torque : tuple of float
        The peak |torque| per joint along the reference with the rated payload [N m], from
        which the effort limits were set.
    """

    seed: int
    kind: str
    urdf: str
    payload_frame: str
    payload_capacity: float
    armature: tuple[float, ...]
    reference: dict
    task_torque: tuple[float, ...]

    @property
    def n_joints(self) -> int:
        return len(self.armature)

    def path(self) -> Path:
        """The URDF as a file in the user's cache folder, named by seed and content hash."""
        return cached_urdf(self.urdf, f"random_arm-{self.seed}")

    def arm_table(self) -> dict:
        """The ``[arm]`` keys this arm brings to a scenario (robot, capacity, armature)."""
        return {
            "robot": f"{RANDOM_PREFIX}{self.seed}",
            "payload_capacity": self.payload_capacity,
            "armature": list(self.armature),
        }


def parse_random_robot(name: str) -> int | None:
    """The seed of a ``"random:SEED"`` robot name, None for any other name.

    Raises
    ------
    ParameterError
        The name starts with ``random:`` but ``SEED`` is not an integer in [0, 2**63).
    """
    if not isinstance(name, str) or not name.startswith(RANDOM_PREFIX):
        return None
    raw = name[len(RANDOM_PREFIX) :].strip()
    if not raw.isdigit() or int(raw) >= 2**63:
        raise ParameterError(
            f"robot {name!r}: the seed after 'random:' must be an integer in [0, 2**63), e.g. 'random:7'"
        )
    return int(raw)


def random_arm(seed: int, joints: int | None = None) -> RandomArm:
    """Draw a plausible fixed-base serial arm (module docstring) from ``seed``.

    Parameters
    ----------
    seed : int
        Seed of ``numpy.random.default_rng``, >= 0.
    joints : int, optional
        Number of revolute joints, 3 .. 7 (default: drawn).

    Returns
    -------
    RandomArm
        The drawn arm: its URDF, payload capacity and reference; the same seed gives the same arm.

    Raises
    ------
    ParameterError
        ``seed`` negative or not an integer; ``joints`` not in 3 .. 7.

    Examples
    --------
    >>> from adaptive_dd.robots.random_arm import random_arm
    >>> arm = random_arm(7, joints=5)
    >>> arm.n_joints
    5
    >>> random_arm(7, joints=5) is arm
    True
    >>> random_arm(-1)
    Traceback (most recent call last):
    ...
    adaptive_dd.errors.ParameterError: random_arm: seed must be an integer >= 0, got -1
    """
    _check_seed(seed)
    if joints is not None and (
        isinstance(joints, bool) or not isinstance(joints, int | np.integer) or joints not in range(3, 8)
    ):
        raise ParameterError(f"random_arm: joints must be an integer in 3 .. 7, got {joints!r}")
    return _draw(int(seed), None if joints is None else int(joints))


def random_arm_joints(seed: int) -> int:
    """The number of joints of ``random_arm(seed)``, its first draw, without drawing the rest
    (a scheduler that orders arms by size: the whole arm is about 70 ms).

    Examples
    --------
    >>> from adaptive_dd.robots.random_arm import random_arm, random_arm_joints
    >>> random_arm_joints(1) == random_arm(1).n_joints
    True
    """
    _check_seed(seed)
    return _joints(np.random.default_rng([int(seed), 42]))


def _check_seed(seed) -> None:
    """A drawn arm's seed: an integer >= 0 (a ``ParameterError`` naming it otherwise)."""
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ParameterError(f"random_arm: seed must be an integer >= 0, got {seed!r}")


def _joints(rng: np.random.Generator) -> int:
    """An arm's number of joints: the first draw of its generator."""
    return int(rng.integers(3, 8))


@functools.lru_cache(maxsize=256)
def _draw(seed: int, joints: int | None) -> RandomArm:
    """:func:`random_arm` after its checks (cached: a population reads each arm several times)."""
    rng = np.random.default_rng([seed, 42])
    n = joints if joints is not None else _joints(rng)
    kinds = sorted(k for k, ns in _KIND_JOINTS.items() if n in ns)
    kind = kinds[int(rng.integers(len(kinds)))]
    layout = _KINDS[kind][:n]
    geo = _geometry(rng, layout)
    ref = _reference(rng, layout)
    lower, upper, vel = _limits(rng, ref)
    capacity = float(np.round(rng.uniform(0.12, 0.35) * geo["mass"].sum(), 2))
    fric = rng.uniform(0.01, 0.04, n), rng.uniform(0.02, 0.06, n)  # Coulomb, viscous per peak torque
    armature = geo["rotor"]
    body = _urdf(seed, kind, geo, layout, lower, upper, vel, np.ones(n), np.zeros(n), np.zeros(n))
    peak = _task_torque(body, ref, capacity, armature, np.zeros(n), np.zeros(n))
    coulomb = np.round(fric[0] * peak, 4)
    viscous = np.round(fric[1] * peak / np.maximum(_peak_speed(ref), 0.1), 4)
    body = _urdf(seed, kind, geo, layout, lower, upper, vel, np.ones(n), viscous, coulomb)
    peak = _task_torque(body, ref, capacity, armature, viscous, coulomb)
    effort = np.round(rng.uniform(1.6, 2.5, n) * peak, 2)
    text = _urdf(seed, kind, geo, layout, lower, upper, vel, effort, viscous, coulomb)
    return RandomArm(
        seed=seed,
        kind=kind,
        urdf=text,
        payload_frame="tool",
        payload_capacity=capacity,
        armature=tuple(float(a) for a in armature),
        reference=ref,
        task_torque=tuple(float(p) for p in peak),
    )


def _geometry(rng, layout) -> dict:
    """Segment vectors, masses, centres of mass, inertias (about the centres) and rotor inertias."""
    n = len(layout)
    size = rng.uniform(0.6, 1.4)  # overall scale: a small cobot to a mid-size industrial arm
    upper = size * rng.uniform(0.3, 0.5)
    fore = upper * rng.uniform(0.7, 1.1)
    split = rng.uniform(0.3, 0.6)
    length = {
        "S": size * rng.uniform(0.05, 0.15),
        "U": upper,
        "U1": upper * split,
        "U2": upper * (1 - split),
        "F": fore,
        "F1": fore * split,
        "F2": fore * (1 - split),
    }
    density = rng.uniform(6.0, 14.0) * size  # kg per m of link tube
    seg, mass, com, inertia, rotor = [], [], [], [], []
    for i, (_, part) in enumerate(layout):
        ell = length.get(part, size * rng.uniform(0.04, 0.12))
        side = rng.uniform(-0.08, 0.08) * size if rng.random() < 0.3 else 0.0
        d = np.array([0.0, side, ell])
        distal = 1.0 - 0.6 * i / max(n - 1, 1)  # motors shrink toward the wrist
        m = density * ell + size * distal * rng.uniform(0.8, 2.5)
        c = d * rng.uniform(0.3, 0.6) + rng.uniform(-0.01, 0.01, 3)
        dims = np.array([*rng.uniform(0.05, 0.14, 2) * size**0.5, max(ell, 0.05)])
        moments = (
            m
            / 12.0
            * np.array(
                [dims[1] ** 2 + dims[2] ** 2, dims[0] ** 2 + dims[2] ** 2, dims[0] ** 2 + dims[1] ** 2]
            )
        )
        R = _rotation(rng, 0.3)
        seg.append(d)
        mass.append(m)
        com.append(c)
        inertia.append(R @ np.diag(moments) @ R.T)
        rotor.append(size**2 * distal * rng.uniform(0.1, 0.5))  # kg m^2 reflected by a gear of ~100
    return {
        "base": size * rng.uniform(0.1, 0.3),
        "tool": size * rng.uniform(0.03, 0.1),
        "seg": seg,
        "mass": np.array(mass),
        "com": com,
        "inertia": inertia,
        "rotor": np.round(np.array(rotor), 4),
    }


def _rotation(rng, angle: float) -> np.ndarray:
    """A rotation by a uniform angle in [-angle, angle] about a random axis (Rodrigues)."""
    k = rng.normal(size=3)
    k /= np.linalg.norm(k)
    t = rng.uniform(-angle, angle)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(t) * K + (1 - np.cos(t)) * K @ K


def _reference(rng, layout) -> dict:
    """Two sines per joint, proximal joints moving less, pitches held off the upright pose."""
    n = len(layout)
    ref: dict = {"ramp": 1.0}
    for i, (axis, _) in enumerate(layout):
        if axis == "pitch":
            offset = rng.choice([-1.0, 1.0]) * rng.uniform(0.4, 1.2)
        else:
            offset = rng.uniform(-0.5, 0.5)
        scale = 0.6 + 0.6 * i / max(n - 1, 1)
        ref[f"joint{i + 1}"] = {
            "offset": round(float(offset), 3),
            "amplitude": [
                round(float(scale * rng.uniform(0.2, 0.45)), 3),
                round(float(scale * rng.uniform(0.05, 0.15)), 3),
            ],
            "frequency": [round(float(rng.uniform(0.2, 0.45)), 3), round(float(rng.uniform(0.6, 1.3)), 3)],
            "phase": [round(float(rng.uniform(0, 2 * np.pi)), 3), round(float(rng.uniform(0, 2 * np.pi)), 3)],
        }
    return ref


def _ref_arrays(ref: dict) -> tuple[np.ndarray, ...]:
    n = sum(1 for k in ref if k.startswith("joint"))
    rows = [ref[f"joint{i + 1}"] for i in range(n)]
    off = np.array([r["offset"] for r in rows])
    amp = np.array([r["amplitude"] for r in rows])
    w = 2 * np.pi * np.array([r["frequency"] for r in rows])
    ph = np.array([r["phase"] for r in rows])
    return off, amp, w, ph


def _peak_speed(ref: dict) -> np.ndarray:
    _, amp, w, _ = _ref_arrays(ref)
    return (amp * w).sum(axis=1)


def _limits(rng, ref: dict):
    """Position limits: the reference's range widened by 0.3-1 rad each side; velocity limits:
    1.5-3 times its peak speed (the ramp adds at most a few percent)."""
    off, amp, _, _ = _ref_arrays(ref)
    reach = amp.sum(axis=1)
    lower = np.round(off - reach - rng.uniform(0.3, 1.0, off.size), 3)
    upper = np.round(off + reach + rng.uniform(0.3, 1.0, off.size), 3)
    vel = np.round(np.maximum(rng.uniform(1.5, 3.0, off.size) * _peak_speed(ref), 1.0), 3)
    return lower, upper, vel


def _task_torque(text: str, ref: dict, capacity: float, armature, viscous, coulomb) -> np.ndarray:
    """Peak |tau| per joint along 40 s of the reference (the ramp left out: sums of sines
    repeat their peaks), with the rated payload at the flange, its centre of mass
    :data:`PAYLOAD_COM_REACH` out, and the friction."""
    import pinocchio as pin

    from adaptive_dd.plant.urdf import _quiet

    with _quiet():
        model = pin.buildModelFromXML(text)
    fid = model.getFrameId("tool")
    frame = model.frames[fid]
    load = pin.Inertia(capacity, np.array([0.05, 0.0, PAYLOAD_COM_REACH]), np.eye(3) * 1e-3 * capacity)
    model.inertias[frame.parentJoint] += frame.placement.act(load)
    data = model.createData()
    off, amp, w, ph = _ref_arrays(ref)
    peak = np.zeros(off.size)
    arm = np.asarray(armature)
    for t in np.arange(0.0, 40.0, 0.02):
        s = np.sin(w * t + ph)
        c = np.cos(w * t + ph)
        q = off + (amp * s).sum(axis=1)
        v = (amp * w * c).sum(axis=1)
        a = -(amp * w**2 * s).sum(axis=1)
        tau = pin.rnea(model, data, q, v, a) + arm * a + viscous * v + coulomb * np.sign(v)
        peak = np.maximum(peak, np.abs(tau))
    return peak


def _f(x) -> str:
    return f"{float(x):.6g}"


def _v(x) -> str:
    return " ".join(_f(v) for v in x)


def _urdf(seed, kind, geo, layout, lower, upper, vel, effort, viscous, coulomb) -> str:
    """The URDF text of the drawn arm (all frames aligned with the base at q = 0)."""
    n = len(layout)
    out = [
        '<?xml version="1.0"?>',
        f"<!-- drawn by adaptive_dd.robots.random_arm({seed}): a {n}-joint {kind} arm; not a product -->",
        f'<robot name="random_arm_{seed}">',
        '  <link name="base_link"/>',
    ]
    parent, origin = "base_link", np.array([0.0, 0.0, geo["base"]])
    for i, (axis, _) in enumerate(layout):
        inertia = geo["inertia"][i]
        out += [
            f'  <joint name="joint{i + 1}" type="revolute">',
            f'    <parent link="{parent}"/>',
            f'    <child link="link{i + 1}"/>',
            f'    <origin xyz="{_v(origin)}" rpy="0 0 0"/>',
            f'    <axis xyz="{_AXES[axis]}"/>',
            f'    <limit lower="{_f(lower[i])}" upper="{_f(upper[i])}" effort="{_f(effort[i])}" '
            f'velocity="{_f(vel[i])}"/>',
            f'    <dynamics damping="{_f(viscous[i])}" friction="{_f(coulomb[i])}"/>',
            "  </joint>",
            f'  <link name="link{i + 1}">',
            "    <inertial>",
            f'      <origin xyz="{_v(geo["com"][i])}" rpy="0 0 0"/>',
            f'      <mass value="{_f(geo["mass"][i])}"/>',
            f'      <inertia ixx="{_f(inertia[0, 0])}" ixy="{_f(inertia[0, 1])}" ixz="{_f(inertia[0, 2])}" '
            f'iyy="{_f(inertia[1, 1])}" iyz="{_f(inertia[1, 2])}" izz="{_f(inertia[2, 2])}"/>',
            "    </inertial>",
            "  </link>",
        ]
        parent, origin = f"link{i + 1}", geo["seg"][i]
    origin = origin + np.array([0.0, 0.0, geo["tool"]])
    out += [
        '  <joint name="tool_joint" type="fixed">',
        f'    <parent link="{parent}"/>',
        '    <child link="tool"/>',
        f'    <origin xyz="{_v(origin)}" rpy="0 0 0"/>',
        "  </joint>",
        '  <link name="tool"/>',
        "</robot>",
    ]
    return "\n".join(out) + "\n"


def with_random_arm(data: dict, src: str = "<memory>") -> dict:
    """A scenario's parsed TOML with a ``"random:SEED"`` robot's defaults filled in.

    Where ``[arm] robot = "random:SEED"``, the drawn arm's ``payload_capacity`` and ``armature``
    become the ``[arm]`` keys' defaults and its reference the ``[reference]`` table's (a table
    given in the file wins). Any other scenario is returned as it is (the same object).

    Raises
    ------
    ScenarioError
        ``robot`` starts with ``random:`` but the seed is not an integer in [0, 2**63)
        (naming ``src``, the key and the value).
    """
    from adaptive_dd.errors import ScenarioError

    arm = data.get("arm") if isinstance(data, dict) else None
    if not isinstance(arm, dict):
        return data
    try:
        seed = parse_random_robot(arm.get("robot"))
    except ParameterError as exc:
        raise ScenarioError(f"{src}: key 'arm.robot': {exc}") from None
    if seed is None:
        return data
    drawn = random_arm(seed)
    out = dict(data)
    out["arm"] = {**{k: v for k, v in drawn.arm_table().items() if k != "robot"}, **arm}
    out.setdefault("reference", copy.deepcopy(drawn.reference))
    return out
