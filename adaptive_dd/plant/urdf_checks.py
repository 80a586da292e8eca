"""Every number of a URDF checked for physical sense before Pinocchio reads it.

:func:`check_values` walks a parsed ``<robot>`` and refuses what no robot has, with an
:class:`~adaptive_dd.errors.UrdfError` naming the file, the element (link or joint name), the
attribute and the value: a number that does not parse or is not finite, a link of mass < 0, of
mass 0 with inertia, or above :data:`MAX_LINK_MASS`, an inertia with a moment larger than its mass at
:data:`MAX_OFFSET` from its centre could give, an origin or a centre of mass farther than
:data:`MAX_OFFSET` from its frame, a joint axis of zero length, an effort limit <= 0 or above
:data:`MAX_EFFORT`, a velocity limit <= 0 or above :data:`MAX_VELOCITY`, position limits with
lower >= upper or beyond :data:`MAX_POSITION`, negative or absurd damping or friction.
Where a vendor's file is merely unusual it is accepted with a note (:attr:`UrdfRobot.notes
<adaptive_dd.plant.urdf.UrdfRobot.notes>`, printed by ``adaptive-dd validate``): an axis that is
not of unit length (normalised, and raised as a :class:`UrdfWarning`), a link below
:data:`TINY_MASS`, a link of mass 0 and zero inertia (a massless frame, as the ROS-Industrial
UR descriptions write their tool frames).

Joints and links off the arm's chain (a gripper's fingers, a mobile base's sensors) are held to
the same finiteness and size checks, since Pinocchio reads them too; their limits are not
checked (they are locked at 0), and neither is their inertia's consistency
(:mod:`adaptive_dd.plant.urdf`).

The bounds are far outside any arm's values and far below overflow: they catch a typo of
units or a corrupted file, not an unusual robot.
"""

from __future__ import annotations

import math
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from adaptive_dd.errors import UrdfError

__all__ = [
    "GYRATION_NOTE",
    "HEAVY_LINK_MASS",
    "MAX_EFFORT",
    "MAX_FRICTION",
    "MAX_LINK_MASS",
    "MAX_OFFSET",
    "MAX_POSITION",
    "MAX_VELOCITY",
    "TINY_MASS",
    "UrdfWarning",
    "check_values",
    "massless_frame",
    "scalar",
]

MAX_LINK_MASS = 1e4  # kg: ten tonnes, beyond the heaviest industrial robot's heaviest link
TINY_MASS = 1e-6  # kg: a milligram, below any real link (a massless frame leaves <inertial> out)
HEAVY_LINK_MASS = 500.0  # kg: above an arm's links ([arm] bounds), a vendor's heavy base: a note
MAX_OFFSET = 10.0  # m: a joint origin, a centre of mass, a radius of gyration
GYRATION_NOTE = 1.0  # m: a link's radius of gyration beyond this is noted (an arm's links: < 0.5 m)
MAX_EFFORT = 1e5  # N m or N: as a scenario's [arm] torque_limit
MAX_VELOCITY = 1e3  # rad/s or m/s: about 10 000 rpm at the joint
MAX_POSITION = 1e3  # rad or m: a joint limit beyond this is no limit
MAX_FRICTION = 1e4  # N m s/rad and N m: as a scenario's [arm] viscous and coulomb
_AXIS_TOL = 1e-6


class UrdfWarning(UserWarning):
    """A URDF value that is unusual but usable (it is repaired or used as it is)."""


def _numbers(path: Path, where: str, el: ET.Element, attr: str, n: int) -> np.ndarray | None:
    """The ``n`` finite numbers of a vector attribute, or None when it is absent."""
    raw = el.get(attr)
    if raw is None:
        return None
    parts = raw.split()
    try:
        v = np.array([float(x) for x in parts])
    except ValueError:
        raise UrdfError(f"{path}: {where}: attribute '{attr}' = {raw!r} is not {n} numbers") from None
    if v.size != n:
        raise UrdfError(f"{path}: {where}: attribute '{attr}' = {raw!r} must be {n} numbers, got {v.size}")
    if not np.all(np.isfinite(v)):
        raise UrdfError(f"{path}: {where}: attribute '{attr}' = {raw!r} must be finite")
    return v


def _origin(path: Path, where: str, el: ET.Element | None, what: str) -> None:
    """``<origin xyz rpy>`` finite, ``xyz`` within :data:`MAX_OFFSET`, ``rpy`` within 100 rad."""
    o = el.find("origin") if el is not None else None
    if o is None:
        return
    xyz = _numbers(path, f"{where} <origin>", o, "xyz", 3)
    if xyz is not None and (np.abs(xyz).max() > MAX_OFFSET or np.linalg.norm(xyz) > MAX_OFFSET):
        raise UrdfError(
            f"{path}: {where} <origin>: xyz = {o.get('xyz')!r} puts the {what} more than {MAX_OFFSET:g} m "
            "away: a unit error (mm for m?)"
        )
    rpy = _numbers(path, f"{where} <origin>", o, "rpy", 3)
    if rpy is not None and np.abs(rpy).max() > 100.0:
        raise UrdfError(
            f"{path}: {where} <origin>: rpy = {o.get('rpy')!r} must be angles in rad (|x| <= 100)"
        )


def scalar(path: Path, where: str, el: ET.Element | None, attr: str) -> float | None:
    """Attribute ``attr`` of ``el`` as a finite float, None when absent; an error naming file,
    element, attribute and value when it is not a finite number."""
    raw = el.get(attr) if el is not None else None
    if raw is None:
        return None
    try:
        v = float(raw)
    except ValueError:
        raise UrdfError(f"{path}: {where}: attribute '{attr}' = {raw!r} is not a number") from None
    if not math.isfinite(v):
        raise UrdfError(f"{path}: {where}: attribute '{attr}' = {raw!r} must be finite")
    return v


_GEOMETRY = {
    "box": {"size": 3},
    "cylinder": {"radius": 1, "length": 1},
    "sphere": {"radius": 1},
    "mesh": {"scale": 3},
}


def _check_shapes(path: Path, link: ET.Element, notes: list[str]) -> None:
    """``<visual>`` and ``<collision>``: origins and geometry sizes finite (urdfdom reads them);
    a negative size is noted (no dynamics depends on it)."""
    name = link.get("name")
    for tag in ("visual", "collision"):
        for shape in link.findall(tag):
            where = f"link '{name}' <{tag}>"
            _origin(path, where, shape, f"{tag} shape")
            geometry = shape.find("geometry")
            for el in () if geometry is None else list(geometry):
                for attr, n in _GEOMETRY.get(el.tag, {}).items():
                    v = _numbers(path, f"{where} <{el.tag}>", el, attr, n)
                    if v is not None and np.any(v < 0):
                        notes.append(
                            f"link '{name}' <{tag}> <{el.tag}> {attr} = {el.get(attr)!r} is negative "
                            "(not used)"
                        )


def _check_link(path: Path, link: ET.Element, notes: list[str]) -> None:
    name = link.get("name")
    _check_shapes(path, link, notes)
    inertial = link.find("inertial")
    if inertial is None:
        return
    where = f"link '{name}' <inertial>"
    _origin(path, where, inertial, "centre of mass")
    mass = scalar(path, f"{where} <mass>", inertial.find("mass"), "value")
    raw = inertial.find("mass").get("value") if mass is not None else None
    if mass is None:
        raise UrdfError(f"{path}: {where} <mass>: attribute 'value' is missing")
    if massless_frame(path, where, inertial):
        notes.append(f"link '{name}': mass 0 kg and no inertia: a massless frame (kept)")
        return
    if mass <= 0:
        raise UrdfError(
            f"{path}: {where} <mass>: value = {raw!r}: mass {mass} kg must be > 0 "
            "(a massless frame: leave <inertial> out, or give it zero inertia)"
        )
    if mass > MAX_LINK_MASS:
        raise UrdfError(
            f"{path}: {where} <mass>: value = {raw!r} kg is above {MAX_LINK_MASS:g} kg: "
            "a unit error (g for kg?)"
        )
    if mass < TINY_MASS:
        notes.append(f"link '{name}': mass {raw!r} kg is below {TINY_MASS:g} kg (kept)")
    elif mass > HEAVY_LINK_MASS:
        notes.append(
            f"link '{name}': mass {raw!r} kg is above {HEAVY_LINK_MASS:g} kg: a heavy base, or a unit error? "
            "(kept)"
        )
    el = inertial.find("inertia")
    if el is None:
        return  # read_urdf names it
    moments = {
        k: scalar(path, f"{where} <inertia>", el, k) for k in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")
    }
    biggest = max(abs(v) for v in moments.values() if v is not None) if any(moments.values()) else 0.0
    if mass >= 1e-3 and mass * GYRATION_NOTE**2 < biggest <= mass * MAX_OFFSET**2:  # a gram: no dummy link
        notes.append(
            f"link '{name}': a moment of {biggest:.4g} kg m^2 for {mass:g} kg is a radius of gyration of "
            f"{math.sqrt(biggest / mass):.3g} m, beyond {GYRATION_NOTE:g} m: a unit error? (kept)"
        )
    if biggest > mass * MAX_OFFSET**2:
        key = max((k for k in moments if moments[k] is not None), key=lambda k: abs(moments[k]))
        raise UrdfError(
            f"{path}: {where} <inertia>: {key} = {el.get(key)!r} kg m^2 is more than {mass:g} kg at "
            f"{MAX_OFFSET:g} m could give (radius of gyration {math.sqrt(biggest / mass):.3g} m): "
            "a unit error?"
        )


def massless_frame(path: Path, where: str, inertial: ET.Element) -> bool:
    """Whether an ``<inertial>`` is a vendor's massless frame: mass 0 and its ``<inertia>`` absent or
    all 0 (each number checked); :mod:`adaptive_dd.plant.urdf` then reads the link as having none."""
    if scalar(path, f"{where} <mass>", inertial.find("mass"), "value") != 0.0:
        return False
    el = inertial.find("inertia")
    keys = ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")
    return el is None or all(scalar(path, f"{where} <inertia>", el, k) in (None, 0.0) for k in keys)


def _check_axis(path: Path, where: str, joint: ET.Element, notes: list[str]) -> bool:
    """Axis finite and non-zero; normalised (with a note) when it is not of unit length.
    Returns True when the element was changed."""
    ax_el = joint.find("axis")
    if ax_el is None:
        return False
    ax = _numbers(path, f"{where} <axis>", ax_el, "xyz", 3)
    if ax is None:
        raise UrdfError(
            f"{path}: {where} <axis>: attribute 'xyz' is missing (give the axis, or leave <axis> out for "
            "the default 1 0 0)"
        )
    big = float(np.abs(ax).max())
    norm = big * float(np.linalg.norm(ax / big)) if big > 0 else 0.0  # no overflow at 1e300
    if not norm > 1e-9:
        raise UrdfError(
            f"{path}: {where} <axis>: xyz = {ax_el.get('xyz')!r} has no direction: give the joint's axis, "
            'e.g. xyz="0 0 1"'
        )
    if abs(norm - 1.0) > _AXIS_TOL:
        unit = (ax / big) / float(np.linalg.norm(ax / big))
        ax_el.set("xyz", " ".join(repr(float(x)) for x in unit))
        notes.append(
            f"normalised {where} <axis> xyz = {' '.join(f'{x:g}' for x in ax)} (length {norm:.6g}) "
            "to unit length"
        )
        warnings.warn(f"{path}: {where}: axis of length {norm:.6g} normalised", UrdfWarning, stacklevel=4)
        return True
    return False


def _check_joint(path: Path, joint: ET.Element, on_chain: bool, notes: list[str]) -> bool:
    name, kind = joint.get("name"), joint.get("type")
    where = f"joint '{name}' ({kind})"
    _origin(path, where, joint, "joint")
    changed = _check_axis(path, where, joint, notes) if kind != "fixed" else False
    lim, dyn = joint.find("limit"), joint.find("dynamics")
    values = {k: scalar(path, f"{where} <limit>", lim, k) for k in ("effort", "velocity", "lower", "upper")}
    values |= {k: scalar(path, f"{where} <dynamics>", dyn, k) for k in ("damping", "friction")}
    bad = [k for k in ("damping", "friction") if values[k] is not None and not 0 <= values[k] <= MAX_FRICTION]
    if bad:
        units = (
            {"damping": "N s/m", "friction": "N"}
            if kind == "prismatic"
            else {"damping": "N m s/rad", "friction": "N m"}
        )
        raise UrdfError(
            f"{path}: {where} <dynamics>: "
            + " and ".join(f"{k} = {dyn.get(k)!r}" for k in bad)
            + f" must be in [0, {MAX_FRICTION:g}] ({', '.join(units[k] for k in bad)})"
        )
    if lim is None and kind in ("revolute", "prismatic"):  # Pinocchio refuses the file without a word
        raise UrdfError(
            f"{path}: {where}: <limit> is missing (URDF requires it on a {kind} joint: effort, velocity, "
            "lower, upper)" + ("" if on_chain else "; the joint is off the arm's chain, locked at 0")
        )
    if lim is not None and kind in ("revolute", "prismatic"):
        for k in ("effort", "velocity"):  # urdfdom refuses a limit without them
            if values[k] is None:
                raise UrdfError(
                    f"{path}: {where} <limit>: attribute '{k}' is missing (URDF requires it; "
                    f"{'the torque limit' if k == 'effort' else 'the speed limit, rad/s or m/s'})"
                )
    if not on_chain or kind == "fixed":
        return changed
    effort, vel = values["effort"], values["velocity"]
    if effort is not None and not 0 < effort <= MAX_EFFORT:
        raise UrdfError(
            f"{path}: {where} <limit>: effort = {lim.get('effort')!r} must be in (0, {MAX_EFFORT:g}] N m "
            "(the actuator's torque limit)"
        )
    if vel is not None and not 0 < vel <= MAX_VELOCITY:
        raise UrdfError(
            f"{path}: {where} <limit>: velocity = {lim.get('velocity')!r} must be in (0, {MAX_VELOCITY:g}] "
            "(rad/s or m/s: the data sheet's joint speed)"
        )
    if kind == "revolute" and lim is not None and values["lower"] is None and values["upper"] is None:
        notes.append(  # the URDF's default is 0 (Pinocchio reads [0, 0]); a joint without stops is continuous
            f"joint '{name}': <limit> without lower and upper: read as no position limits (the URDF format's "
            "default is 0 for both); give the stops, or make the joint continuous"
        )
    for k in ("lower", "upper"):
        v = values[k]
        if v is not None and abs(v) > MAX_POSITION:
            raise UrdfError(
                f"{path}: {where} <limit>: {k} = {lim.get(k)!r} is beyond {MAX_POSITION:g} (rad or m): "
                "leave it out (or make the joint continuous) for a joint without stops"
            )
    return changed


def check_values(path: str | Path, root: ET.Element, chain_joints: set[str]) -> tuple[tuple[str, ...], bool]:
    """Check every link and joint of ``root`` (module docstring); normalise non-unit axes in place.

    Parameters
    ----------
    path : str or Path
        The file, for the messages.
    root : xml.etree.ElementTree.Element
        The ``<robot>`` element (changed in place where an axis is normalised).
    chain_joints : set of str
        Names of the joints between the root and the payload frame: their limits are checked.

    Returns
    -------
    notes : tuple of str
        What was unusual and kept or repaired, one sentence each.
    changed : bool
        True when ``root`` was changed (an axis normalised): Pinocchio must read the changed text.

    Raises
    ------
    UrdfError
        Naming the file, the element, the attribute and the value.
    """
    path = Path(path)
    notes: list[str] = []
    for link in root.findall("link"):
        _check_link(path, link, notes)
    changed = False
    for joint in root.findall("joint"):
        changed |= _check_joint(path, joint, joint.get("name") in chain_joints, notes)
    return tuple(notes), changed
