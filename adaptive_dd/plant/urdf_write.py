"""Writing an arm's URDF back with other link inertials (an identified or drawn model).

The arm's own URDF is copied with every movable chain joint's child link given the link's
ten parameters (about its joint frame, :attr:`Arm.pi_links
<adaptive_dd.plant.arm.Arm.pi_links>`'s layout) as its ``<inertial>``, and
every body Pinocchio merges into that link (fixed children, locked joints' subtrees) left
without one, so that reading the file back gives exactly those parameters. Kinematics, limits,
friction and every other element are the original's.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from adaptive_dd.errors import ParameterError
from adaptive_dd.outputs import atomic_write

__all__ = ["write_fitted_urdf", "write_urdf_links"]


def _f(x: float) -> str:
    return repr(float(x))


def write_urdf_links(
    arm, pi_links: ArrayLike, path: str | Path, comment: str = "", friction: tuple | None = None
) -> Path:
    """Write ``arm``'s URDF with links ``pi_links (10 n,)`` to ``path``; returns the path.

    The URDF read is the arm's as repaired (``repair_inertia``), if it was. ``friction = (fv, fc)``
    (each ``(n,)``) also writes the chain joints' ``<dynamics damping friction>``. The file is
    written atomically.

    Raises
    ------
    ParameterError
        ``pi_links`` of the wrong size, or a link that is not a rigid body's
        (:func:`~adaptive_dd.plant.uncertainty.check_link`).
    """
    from adaptive_dd.plant.uncertainty import check_link

    pi = np.asarray(pi_links, dtype=float).reshape(-1)
    n = arm.n_joints
    if pi.shape != (10 * n,):
        raise ParameterError(f"pi_links must have {10 * n} values (10 per link), got {pi.shape}")
    xml = arm._robot.xml
    root = ET.fromstring(xml) if xml is not None else ET.parse(arm.urdf).getroot()
    links = {el.get("name"): el for el in root.findall("link")}
    joints = {el.get("name"): el for el in root.findall("joint")}
    children: dict[str, list] = {}
    for j in joints.values():
        children.setdefault(j.find("parent").get("link"), []).append(j)
    chain = set(arm.joint_names)
    for k, name in enumerate(arm.joint_names):
        child = joints[name].find("child").get("link")
        _remove_inertials_below(links, children, child, chain)
        if friction is not None:
            _set_dynamics(joints[name], friction[0][k], friction[1][k])
        p = pi[10 * k : 10 * k + 10]
        check_link(p, f"link {k + 1} ({child})")
        _add_inertial(links[child], p)
    if comment:
        root.insert(0, ET.Comment(f" {comment} "))
    path = Path(path)
    with atomic_write(path, encoding="utf-8") as fh:
        fh.write('<?xml version="1.0" encoding="utf-8"?>\n')
        fh.write(ET.tostring(root, encoding="unicode"))
    return path


def _remove_inertials_below(links: dict, children: dict, link_name: str, chain: set) -> None:
    """Remove the ``<inertial>`` of a chain link and of every body merged into it: everything
    below it up to the next chain joint."""
    stack = [link_name]
    while stack:
        link = links[stack.pop()]
        for el in link.findall("inertial"):
            link.remove(el)
        stack += [
            j.find("child").get("link")
            for j in children.get(link.get("name"), ())
            if j.get("name") not in chain
        ]


def _set_dynamics(joint: ET.Element, damping: float, friction: float) -> None:
    """Set (or add) the joint's ``<dynamics damping friction>``."""
    dyn = joint.find("dynamics")
    if dyn is None:
        dyn = ET.SubElement(joint, "dynamics")
    dyn.set("damping", _f(damping))
    dyn.set("friction", _f(friction))


def _add_inertial(link: ET.Element, p) -> None:
    """Give the link an ``<inertial>`` of the ten parameters ``p`` (none when the mass is 0)."""
    from adaptive_dd.plant.uncertainty import link_parts

    m, c, Ic = link_parts(p)
    if m <= 0:
        return
    inertial = ET.SubElement(link, "inertial")
    ET.SubElement(inertial, "origin", {"xyz": " ".join(_f(x) for x in c), "rpy": "0 0 0"})
    ET.SubElement(inertial, "mass", {"value": _f(m)})
    names = {"ixx": (0, 0), "ixy": (0, 1), "ixz": (0, 2), "iyy": (1, 1), "iyz": (1, 2), "izz": (2, 2)}
    ET.SubElement(inertial, "inertia", {k: _f(Ic[a, b]) for k, (a, b) in names.items()})


def write_fitted_urdf(arm, pi, path: str | Path) -> Path:
    """The arm's URDF with the standard parameters ``pi (13 n,)`` written in.

    Each chain joint's child link gets the inertia of its whole body (Pinocchio merges the
    links fixed to it and the locked branches hanging from it: their ``<inertial>`` are
    removed, their mass now in the body); ``<dynamics damping friction>`` of the chain
    joints get ``fv, fc``. The armature is not a URDF quantity (it stays in model.json).
    """
    n = arm.n_joints
    pi = np.asarray(pi, dtype=float)
    return write_urdf_links(
        arm,
        pi[: 10 * n],
        path,
        f"written by adaptive-dd identify: a physically consistent fit on {arm.urdf}",
        friction=(pi[10 * n : 11 * n], pi[11 * n : 12 * n]),
    )
