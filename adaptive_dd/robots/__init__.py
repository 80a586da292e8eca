"""The robots adaptive_dd ships, as URDF files written from published parameter tables, and
arms drawn from a seed (:func:`random_arm`: ``robot = "random:SEED"`` in a scenario).

Each file has no meshes; its header comment names the source of every number.
The files are the output of ``tools/make_robot_urdfs.py`` (``--check`` compares).

>>> import pinocchio as pin
>>> model = pin.buildModelFromUrdf(str(robot_urdf("sice_arm")))
>>> model.nq
2
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

from adaptive_dd.plant.devices import SICE_SENSOR, SensorConfig
from adaptive_dd.robots.random_arm import RandomArm, random_arm

__all__ = ["ROBOTS", "RandomArm", "RobotInfo", "UnknownRobotError", "random_arm", "robot_urdf"]

_HERE = Path(__file__).resolve().parent


@dataclass(frozen=True)
class RobotInfo:
    """One shipped robot.

    Attributes
    ----------
    file : str
        File name in ``adaptive_dd/robots/``.
    payload_frame : str
        Name of the frame where a payload is attached (a fixed frame at the flange or tip).
    description : str
        One line: what it is and where its numbers come from.
    sensor, dac_bits, payload_offset
        What its data sheet states that a URDF has no place for (:meth:`stated`): the encoders'
        counts and the sensors' noise variances, the D/A's bits, the payload's centre-of-mass
        offset [m]; None: not stated (a URDF arm's defaults). A scenario's ``[arm]`` and
        ``[noise]`` keys override them.

    Examples
    --------
    >>> from adaptive_dd.robots import ROBOTS
    >>> {"sice_arm", "ur5", "panda", "iiwa14"} <= set(ROBOTS)
    True
    >>> ROBOTS["ur5"].file
    'ur5.urdf'
    """

    file: str
    payload_frame: str
    description: str
    sensor: SensorConfig | None = None
    dac_bits: int | None = None
    payload_offset: float | None = None

    def stated(self, arm) -> dict:
        """What the robot's data sheet states beyond its URDF, as :func:`dataclasses.replace`'s
        keywords for an :class:`~adaptive_dd.plant.arm.Arm` read from it: the encoders and sensor
        noise (``sensor``), the D/A's bits (``dac_bits``) and how far a payload's centre of mass
        lies from the payload frame (``payload_offset``); the ones not stated keep the URDF arm's
        defaults."""
        kw: dict = {} if self.sensor is None else {"sensor": self.sensor}
        if self.dac_bits is not None:
            kw["actuator"] = replace(arm.actuator, dac_bits=self.dac_bits)
        if self.payload_offset is not None:
            kw["payload_offset"] = self.payload_offset
        return kw


ROBOTS: dict[str, RobotInfo] = {
    "sice_arm": RobotInfo(
        "sice_arm.urdf",
        "tip",
        "SICE SR-402DD two-link direct-drive arm, horizontal (Arm.sice()); Table 1 of 'Recursive "
        "simultaneous estimation of a two-link direct drive manipulator with great variation of payload'",
        sensor=SICE_SENSOR,  # its encoders and noise (Tables 2 and 4)
        dac_bits=12,  # its D/A
        payload_offset=0.0,  # its payloads: disks centred on the tip (eq. 9)
    ),
    "vertical3": RobotInfo(
        "vertical3.urdf",
        "tool",
        "three-joint planar arm in a vertical plane, gravity acting; the project's own illustrative "
        "arm, not a product",
    ),
    "ur5": RobotInfo(
        "ur5.urdf",
        "tool0",
        "Universal Robots UR5: UR's DH table, masses and centres of mass, cylinder inertias of "
        "ros-industrial/universal_robot ur_description; friction assumed",
    ),
    "panda": RobotInfo(
        "panda.urdf",
        "panda_link8",
        "Franka Emika Panda (7 joints, no hand): inertial parameters and friction identified by Gaz "
        "et al., IEEE RA-L 4(4) 2019; Franka's modified DH and joint limits",
    ),
    "iiwa14": RobotInfo(
        "iiwa14.urdf",
        "iiwa_link_ee_kuka",
        "KUKA LBR iiwa 14 R820 (7 joints): kinematics, limits and inertials of Drake's "
        "iiwa14_no_collision.urdf (BSD-3-Clause)",
    ),
    "gen3": RobotInfo(
        "gen3.urdf",
        "end_effector_link",
        "Kinova Gen3 (7 joints, four continuous; no vision module): kinematics, limits and inertials "
        "of Kinova's ros_kortex gen3_macro.xacro (BSD-3-Clause); friction assumed",
    ),
}
"""Name -> :class:`RobotInfo` of every robot shipped in ``adaptive_dd/robots/``."""


class UnknownRobotError(KeyError):
    """A robot name that is not in :data:`ROBOTS`; the message lists the known names.

    Examples
    --------
    >>> from adaptive_dd.robots import robot_urdf
    >>> robot_urdf("r2d2")
    Traceback (most recent call last):
    ...
    adaptive_dd.robots.UnknownRobotError: unknown robot 'r2d2'; known robots: ...
    """

    def __str__(self) -> str:  # KeyError's str() would quote the whole message
        return str(self.args[0]) if self.args else ""


def robot_urdf(name: str) -> Path:
    """Path of a shipped robot's URDF file.

    Parameters
    ----------
    name : str
        A key of :data:`ROBOTS` (``"sice_arm"``, ``"vertical3"``, ``"ur5"``, ``"panda"``,
        ``"iiwa14"``, ``"gen3"``).

    Returns
    -------
    pathlib.Path
        Absolute path of the ``.urdf`` file, which exists.

    Raises
    ------
    UnknownRobotError
        ``name`` is not a known robot (a ``KeyError``); the message lists the known ones.
    FileNotFoundError
        The package was installed without its ``*.urdf`` data files.

    Examples
    --------
    >>> from adaptive_dd.robots import robot_urdf
    >>> path = robot_urdf("panda")
    >>> path.name, path.is_file()
    ('panda.urdf', True)
    """
    try:
        info = ROBOTS[name]
    except (KeyError, TypeError):
        known = ", ".join(sorted(ROBOTS))
        raise UnknownRobotError(f"unknown robot {name!r}; known robots: {known}") from None
    path = _HERE / info.file
    if not path.is_file():
        raise FileNotFoundError(f"robot {name!r}: {path} is missing (package data not installed?)")
    return path
