"""Reading a serial arm from a URDF file: checks first, then Pinocchio.

:func:`read_urdf` parses the file with :mod:`xml.etree.ElementTree`, checks what
an arm needs (one fixed root, a serial chain of revolute, continuous or prismatic
joints from the root to the payload frame, positive masses, physically consistent
inertias, effort limits), and only then builds the Pinocchio model, so that a bad
file gets an error naming the file, the element and the reason rather than a
Pinocchio traceback.

What the chain is
-----------------
The arm is the path of joints from the root link to the link that carries the
payload frame (``payload_frame``: a link name, default the single deepest link).
Fixed joints on it are merged into their parent bodies (Pinocchio does this).
Movable joints *off* that path (a gripper's fingers, say) are locked at 0: their
bodies are merged into the link they hang from and reported in
:attr:`UrdfRobot.locked`. A link with two parents (a closed chain), a floating or
planar joint, or a chain with no movable joint are errors.

Which values are checked
------------------------
Every number of the file, for physical sense (:mod:`adaptive_dd.plant.urdf_checks`): finite,
masses and inertias of a plausible size, axes of non-zero length (normalised when not of unit
length, noted), origins within 10 m, the chain joints' limits (effort and velocity > 0, lower
< upper), damping and friction >= 0; an error names the file, the element, the attribute and
the value.

Which inertias are checked
--------------------------
Only the links of the chain (from the first movable joint to the payload frame) must be
physically consistent on their own (inertia positive definite, principal moments obeying
the triangle inequality). Links off the chain (other branches, locked joints, links fixed
to the base before the first movable joint) are not checked one by one: they are merged
into the body they hang from (or into the fixed base, where they move nothing), and any
that would have failed is listed in :attr:`UrdfRobot.notes` (vendor URDFs carry such
links, e.g. a TIAGo's antennas at the 1e-8 kg m^2 level). A chain link that fails gets an
error naming the repair; with ``repair_inertia=True`` the repair is made (the smallest
change of its principal moments that makes it consistent, :func:`repair_inertia`) and
reported in :attr:`UrdfRobot.notes`.
"""

from __future__ import annotations

import contextlib
import math
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from adaptive_dd.errors import UrdfError
from adaptive_dd.plant.urdf_checks import check_values, massless_frame, scalar

__all__ = ["JointInfo", "UrdfRobot", "read_urdf", "repair_inertia"]

_MOVABLE = ("revolute", "continuous", "prismatic")
_KNOWN = (*_MOVABLE, "fixed", "floating", "planar")


@dataclass(frozen=True)
class JointInfo:
    """One movable joint of the chain as the URDF gives it.

    Attributes
    ----------
    name, kind : str
        URDF joint name and type (``revolute``, ``continuous``, ``prismatic``).
    effort, velocity : float
        Limits [N m or N; rad/s or m/s]; ``velocity`` is ``inf`` when not given.
    lower, upper : float
        Position limits [rad or m]; ``-inf, inf`` for continuous joints.
    damping, friction : float
        ``<dynamics damping friction>``: viscous and Coulomb friction (0 when absent).
    """

    name: str
    kind: str
    effort: float
    velocity: float
    lower: float
    upper: float
    damping: float
    friction: float


@dataclass(frozen=True)
class UrdfRobot:
    """A checked URDF: its chain, limits and friction; :meth:`model` builds the Pinocchio model.

    Attributes
    ----------
    path : Path
        The file.
    joints : tuple of JointInfo
        The movable joints of the chain, root to tip.
    payload_frame : str
        The link that carries the payload.
    locked : tuple of str
        Movable joints off the chain, locked at 0.
    notes : tuple of str
        What was not checked or was repaired (module docstring), one sentence each.
    xml : str or None
        The repaired URDF text (None: the file as it is).
    """

    path: Path
    joints: tuple[JointInfo, ...]
    payload_frame: str
    locked: tuple[str, ...]
    notes: tuple[str, ...] = ()
    xml: str | None = None

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(j.name for j in self.joints)

    def model(self, gravity=None):
        """The Pinocchio model of the chain (off-chain joints locked), gravity set if given."""
        import pinocchio as pin

        xml, locked = _locked_apart(self.path, self.xml, self.locked)
        try:
            with _quiet():
                if xml is None:
                    full = pin.buildModelFromUrdf(str(self.path))
                else:
                    full = pin.buildModelFromXML(xml)
        except Exception as exc:  # pragma: no cover - the XML checks catch what we know of
            raise UrdfError(f"{self.path}: Pinocchio cannot read it: {exc}") from None
        if locked:
            ids = [full.getJointId(n) for n in locked]
            try:
                full = pin.buildReducedModel(full, ids, pin.neutral(full))
            except Exception as exc:  # pragma: no cover - a clash of names is renamed above
                raise UrdfError(
                    f"{self.path}: Pinocchio cannot lock the joints off the chain {list(self.locked)}: {exc}"
                ) from None
        names = [full.names[i] for i in range(1, full.njoints)]
        if tuple(names) != self.joint_names:
            raise UrdfError(  # pragma: no cover - a guard against Pinocchio reordering joints
                f"{self.path}: Pinocchio's joint order {names} differs from the chain {self.joint_names}"
            )
        if gravity is not None:
            full.gravity.linear = np.asarray(gravity, dtype=float)
        return full


LOCKED_SUFFIX = "__locked"
"""Appended to the name of an off-chain joint that a link also carries, for Pinocchio only."""


def _locked_apart(path: Path, xml: str | None, locked: tuple[str, ...]) -> tuple[str | None, tuple[str, ...]]:
    """The URDF text and the locked joints' names to build the model from: an off-chain joint named
    as a link (the SO-100 of example-robot-data: joint and link ``gripper``) renamed with
    :data:`LOCKED_SUFFIX`, since Pinocchio's reduction looks the joint's frame up by name alone and
    stops at two frames of one name. The chain's joints and every link keep their names."""
    if not locked:
        return xml, locked
    root = ET.fromstring(xml) if xml is not None else ET.parse(path).getroot()
    links = {el.get("name") for el in root.findall("link")}
    clash = set(locked) & links
    if not clash:
        return xml, locked
    for el in root.findall("joint"):  # the robot's joints (a transmission's <joint> is not one)
        if el.get("name") in clash:
            el.set("name", el.get("name") + LOCKED_SUFFIX)
    return ET.tostring(root, encoding="unicode"), tuple(
        n + LOCKED_SUFFIX if n in clash else n for n in locked
    )


def frame_id(model, name: str) -> int:
    """The index of the frame ``name`` in a Pinocchio ``model``: the link's (a body frame) where a
    joint carries the same name too (Pinocchio's ``getFrameId(name)`` stops at two frames of one
    name), else the one frame of that name."""
    import pinocchio as pin

    for kind in (pin.FrameType.BODY, pin.FrameType.FIXED_JOINT, pin.FrameType.OP_FRAME, pin.FrameType.JOINT):
        if model.existFrame(name, kind):
            return int(model.getFrameId(name, kind))
    return int(model.getFrameId(name))  # (absent: Pinocchio's own error, after existFrame's check)


@contextlib.contextmanager
def _quiet():
    """Silence C++ writes to stdout/stderr (urdfdom warns on stderr)."""
    fds = []
    try:
        for fd in (1, 2):
            saved = os.dup(fd)
            null = os.open(os.devnull, os.O_WRONLY)
            os.dup2(null, fd)
            os.close(null)
            fds.append((fd, saved))
        yield
    finally:
        for fd, saved in fds:
            os.dup2(saved, fd)
            os.close(saved)


def _num(path, where: str, el, attr: str, default: float | None = None) -> float:
    """The attribute as a finite number (:func:`~adaptive_dd.plant.urdf_checks.scalar`); missing:
    ``default``, or an error naming it when there is none."""
    v = scalar(path, where, el, attr)
    if v is None:
        if default is None:
            raise UrdfError(f"{path}: {where}: attribute '{attr}' is missing")
        return default
    return v


def _inertia_of(path, link):
    """``(mass, inertia (3, 3), <inertia> element)`` of a link, or None without ``<inertial>``."""
    name = link.get("name")
    inertial = link.find("inertial")
    if inertial is None:
        return None
    where = f"link '{name}' <inertial>"
    if massless_frame(path, where, inertial):  # a vendor's massless frame (urdf_checks notes it)
        return None
    mass = _num(path, f"{where} <mass>", inertial.find("mass"), "value")
    el = inertial.find("inertia")
    if el is None:
        raise UrdfError(f"{path}: {where}: <inertia> is missing")
    v = {k: _num(path, f"{where} <inertia>", el, k, 0.0) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
    if mass <= 0:
        raise UrdfError(
            f"{path}: {where}: mass {mass} kg must be > 0 (a massless frame: leave <inertial> out, or "
            "give it zero inertia)"
        )
    inertia = np.array(
        [[v["ixx"], v["ixy"], v["ixz"]], [v["ixy"], v["iyy"], v["iyz"]], [v["ixz"], v["iyz"], v["izz"]]]
    )
    return mass, inertia, el


def _inertia_fault(inertia) -> str | None:
    """Why a rotational inertia is not a rigid body's, or None."""
    lam = np.linalg.eigvalsh(inertia)
    scale = max(abs(lam).max(), 1e-300)
    if lam[0] <= 1e-12 * scale:
        return f"the inertia is not positive definite (principal moments {lam.tolist()})"
    a, b, c = lam
    if c > a + b + 1e-9 * scale:
        return (
            f"the principal moments {lam.tolist()} violate the triangle inequality "
            f"({c:.6g} > {a:.6g} + {b:.6g}, by {c - a - b:.3g} kg m^2): no rigid body has this inertia"
        )
    return None


def repair_inertia(inertia, margin: float = 1e-6):
    """The nearest rigid-body inertia in the principal frame: raise the smallest moments.

    Principal moments below ``margin * max`` are raised to it; then, if the largest exceeds
    the sum of the other two, both of those are raised by half the excess (plus the margin),
    which is the least change (in the largest moment change) restoring the triangle
    inequality. The principal axes are kept.

    Returns
    -------
    ndarray (3, 3)
        The repaired inertia [kg m^2].
    """
    lam, R = np.linalg.eigh(np.asarray(inertia, dtype=float))
    eps = margin * max(abs(lam).max(), 1e-300)
    lam = np.maximum(lam, eps)
    excess = lam[2] - lam[0] - lam[1]
    if excess > -eps:
        lam[:2] += 0.5 * excess + eps
    return (R * lam) @ R.T


def _joint_info(path, j) -> JointInfo:
    name, kind = j.get("name"), j.get("type")
    where = f"joint '{name}' ({kind})"
    lim = j.find("limit")
    if lim is None or lim.get("effort") is None:
        raise UrdfError(f"{path}: {where}: <limit effort=...> is missing (the actuator's torque limit)")
    effort = _num(path, f"{where} <limit>", lim, "effort")
    if effort <= 0:
        raise UrdfError(f"{path}: {where} <limit>: effort {effort} must be > 0")
    vel = _num(path, f"{where} <limit>", lim, "velocity", math.inf)
    vel = math.inf if vel <= 0 else vel
    if kind == "continuous":
        lo, hi = -math.inf, math.inf
    else:
        lo = _num(path, f"{where} <limit>", lim, "lower", -math.inf)
        hi = _num(path, f"{where} <limit>", lim, "upper", math.inf)
        if not lo < hi:
            raise UrdfError(f"{path}: {where} <limit>: lower {lo} must be below upper {hi}")
    dyn = j.find("dynamics")
    damping = _num(path, f"{where} <dynamics>", dyn, "damping", 0.0)
    friction = _num(path, f"{where} <dynamics>", dyn, "friction", 0.0)
    if damping < 0 or friction < 0:
        raise UrdfError(f"{path}: {where} <dynamics>: damping and friction must be >= 0")
    return JointInfo(name, kind, effort, vel, lo, hi, damping, friction)


def read_urdf(path: str | Path, payload_frame: str | None = None, repair: bool = False) -> UrdfRobot:
    """Read and check a URDF file describing a fixed-base serial arm (module docstring).

    Parameters
    ----------
    path : str or Path
        The URDF file.
    payload_frame : str, optional
        Name of the link that carries the payload; default the single deepest link
        of the tree (an error if there are several: name one).

    Raises
    ------
    UrdfError
        Naming the file, the element and the reason: missing or unreadable file,
        XML that does not parse, no or several root links, a link with two parents
        (closed chain), an unsupported joint type (floating, planar), an unknown
        ``payload_frame``, a chain without movable joints, zero or negative mass,
        an inertia of a chain link not positive definite or violating the triangle
        inequality (unless ``repair``), a missing effort limit.
    repair : bool
        Repair the chain links' inconsistent inertias (:func:`repair_inertia`) instead of
        refusing them; each repair is reported in :attr:`UrdfRobot.notes`.
    """
    path = Path(path)
    root = _parse_robot(path)
    _unique_names(path, root)
    links = {el.get("name"): el for el in root.findall("link")}
    if not links:
        raise UrdfError(f"{path}: no <link> element")
    parent_of, children = _joint_tree(path, root, links)
    payload_frame = _payload_frame(path, links, parent_of, children, payload_frame)
    chain, name = [], payload_frame
    while name in parent_of:
        j = parent_of[name]
        chain.append(j)
        name = j.find("parent").get("link")
    chain.reverse()
    on_chain = {j.get("name") for j in chain}
    for j in chain:
        mimic = j.find("mimic")
        if j.get("type") in _MOVABLE and mimic is not None:
            raise UrdfError(
                f"{path}: joint '{j.get('name')}' <mimic joint={mimic.get('joint')!r}>: a joint coupled to "
                "another is not supported between the root and the payload frame (it would be simulated "
                "and controlled as a joint of its own): make it fixed, or name another payload_frame"
            )
    value_notes, changed = check_values(path, root, on_chain)  # every number's physical sense
    joints = tuple(_joint_info(path, j) for j in chain if j.get("type") in _MOVABLE)
    if not joints:
        raise UrdfError(f"{path}: no movable joint between the root and the payload frame '{payload_frame}'")
    first = next(i for i, j in enumerate(chain) if j.get("type") in _MOVABLE)
    chain_links = [j.find("child").get("link") for j in chain[first:]]
    notes = value_notes + _check_inertias(path, links, chain_links, parent_of, repair)
    notes += tuple(
        f"link '{name}' has a shape but no <inertial>: read as massless (a forgotten <inertial>?)"
        for name in chain_links
        if links[name].find("inertial") is None
        and (links[name].find("visual") is not None or links[name].find("collision") is not None)
    )
    locked = tuple(
        j.get("name")
        for j in root.findall("joint")
        if j.get("type") in _MOVABLE and j.get("name") not in on_chain
    )
    changed = changed or any(n.startswith("repaired") for n in notes)
    xml = ET.tostring(root, encoding="unicode") if changed else None
    return UrdfRobot(path, joints, payload_frame, locked, notes, xml)


def _unique_names(path: Path, root: ET.Element) -> None:
    """Every link and joint named, each name once (Pinocchio refuses the file without saying why)."""
    for tag in ("link", "joint"):
        seen: set[str] = set()
        for el in root.findall(tag):
            name = el.get("name")
            if not name:
                raise UrdfError(f"{path}: a <{tag}> without a name: give it one (attribute 'name')")
            if name in seen:
                raise UrdfError(f"{path}: two <{tag}> elements named '{name}': a {tag}'s name must be unique")
            seen.add(name)


def _parse_robot(path: Path) -> ET.Element:
    """The ``<robot>`` element of the file, or an error naming the file and why it cannot be read."""
    if not path.is_file():
        raise UrdfError(f"{path}: no such URDF file")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise UrdfError(f"{path}: not valid XML: {exc}") from None
    except OSError as exc:
        raise UrdfError(f"{path}: cannot be read: {exc.strerror}") from None
    if root.tag != "robot":
        raise UrdfError(f"{path}: the root element is <{root.tag}>, not <robot>")
    return root


def _joint_tree(path: Path, root: ET.Element, links: dict) -> tuple[dict, dict]:
    """``parent_of`` (link name to the joint above it) and ``children`` (link name to the joints
    below it), checking the joint types, their links, and that the links form one tree."""
    parent_of: dict[str, object] = {}
    children: dict[str, list] = {name: [] for name in links}
    for j in root.findall("joint"):
        name, kind = j.get("name"), j.get("type")
        if kind not in _KNOWN:
            raise UrdfError(f"{path}: joint '{name}': unknown type {kind!r}")
        if kind in ("floating", "planar"):
            raise UrdfError(
                f"{path}: joint '{name}': type '{kind}' is not supported (a floating base or a planar "
                "joint); adaptive_dd handles fixed-base arms of revolute, continuous and prismatic joints"
            )
        p, c = j.find("parent"), j.find("child")
        if p is None or c is None:
            raise UrdfError(f"{path}: joint '{name}': <parent link> and <child link> are required")
        pl, cl = p.get("link"), c.get("link")
        for ln in (pl, cl):
            if ln not in links:
                raise UrdfError(f"{path}: joint '{name}': link {ln!r} is not defined")
        if cl in parent_of:
            raise UrdfError(
                f"{path}: link '{cl}' has two parent joints ('{parent_of[cl].get('name')}' and '{name}'): "
                "a closed chain; adaptive_dd handles serial (open) chains"
            )
        parent_of[cl] = j
        children[pl].append(j)
    roots = [n for n in links if n not in parent_of]
    if len(roots) != 1:
        raise UrdfError(f"{path}: {len(roots)} root links {roots}; a URDF tree has exactly one")
    return parent_of, children


def _payload_frame(
    path: Path, links: dict, parent_of: dict, children: dict, payload_frame: str | None
) -> str:
    """The named payload frame, checked, or the single deepest link of the tree."""

    def depth(name: str) -> int:
        d = 0
        while name in parent_of:
            name = parent_of[name].find("parent").get("link")
            d += 1
        return d

    if payload_frame is None:
        leaves = [n for n, ch in children.items() if not ch]
        deepest = max(depth(n) for n in leaves)
        tips = [n for n in leaves if depth(n) == deepest]
        if len(tips) > 1:
            raise UrdfError(
                f"{path}: the tree has {len(tips)} deepest links {tips}: name the payload frame "
                "(payload_frame = one of the links)"
            )
        return tips[0]
    if payload_frame not in links:
        raise UrdfError(
            f"{path}: payload_frame {payload_frame!r} is not a link of this URDF; links: {sorted(links)}"
        )
    return payload_frame


def _check_inertias(path, links: dict, chain_links: list, parent_of: dict, repair: bool) -> tuple[str, ...]:
    """Check the chain links' inertias (repair them if asked); note the others that would fail."""
    notes, off = [], []
    for name, el in links.items():
        got = _inertia_of(path, el)
        if got is not None and not np.any(got[1]):  # a point mass: a rigid body, at the limit
            notes.append(f"link '{name}': a point mass ({got[0]:g} kg, no rotational inertia), kept")
            continue
        fault = None if got is None else _inertia_fault(got[1])
        if fault is None:
            continue
        if name not in chain_links:
            host = name
            while host in parent_of and host not in chain_links:
                host = parent_of[host].find("parent").get("link")
            off.append(
                f"'{name}' ({'merged into ' + repr(host) if host in chain_links else 'fixed to the base'})"
            )
            continue
        if not repair:
            raise UrdfError(
                f"{path}: link '{name}' <inertial>: {fault}. It is on the identified chain: fix the "
                "URDF, or let adaptive_dd raise its smallest principal moments to the nearest rigid "
                "body (repair_inertia = true in the scenario's [arm], or --repair-inertia)"
            )
        fixed = repair_inertia(got[1])
        for key, (r, c) in {
            "ixx": (0, 0),
            "ixy": (0, 1),
            "ixz": (0, 2),
            "iyy": (1, 1),
            "iyz": (1, 2),
            "izz": (2, 2),
        }.items():
            got[2].set(key, repr(float(fixed[r, c])))
        old, new = np.linalg.eigvalsh(got[1]), np.linalg.eigvalsh(fixed)
        notes.append(
            f"repaired link '{name}' inertia: principal moments {np.round(old, 8).tolist()} -> "
            f"{np.round(new, 8).tolist()} kg m^2 (largest change {np.abs(new - old).max():.3g})"
        )
    if off:
        notes.append(
            f"{len(off)} link(s) off the chain with inertias that are not a rigid body's, not checked "
            "(merged with locked joints at 0, or fixed to the base): " + ", ".join(off)
        )
    return tuple(notes)
