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

__all__ = ["JointInfo", "UrdfRobot", "read_urdf"]

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
    """

    path: Path
    joints: tuple[JointInfo, ...]
    payload_frame: str
    locked: tuple[str, ...]

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(j.name for j in self.joints)

    def model(self, gravity=None):
        """The Pinocchio model of the chain (off-chain joints locked), gravity set if given."""
        import pinocchio as pin

        try:
            with _quiet():
                full = pin.buildModelFromUrdf(str(self.path))
        except Exception as exc:  # pragma: no cover - the XML checks catch what we know of
            raise UrdfError(f"{self.path}: Pinocchio cannot read it: {exc}") from None
        if self.locked:
            ids = [full.getJointId(n) for n in self.locked]
            full = pin.buildReducedModel(full, ids, pin.neutral(full))
        names = [full.names[i] for i in range(1, full.njoints)]
        if tuple(names) != self.joint_names:
            raise UrdfError(  # pragma: no cover - a guard against Pinocchio reordering joints
                f"{self.path}: Pinocchio's joint order {names} differs from the chain {self.joint_names}"
            )
        if gravity is not None:
            full.gravity.linear = np.asarray(gravity, dtype=float)
        return full


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
    raw = el.get(attr) if el is not None else None
    if raw is None:
        if default is None:
            raise UrdfError(f"{path}: {where}: attribute '{attr}' is missing")
        return default
    try:
        v = float(raw)
    except ValueError:
        raise UrdfError(f"{path}: {where}: attribute '{attr}' = {raw!r} is not a number") from None
    if not math.isfinite(v):
        raise UrdfError(f"{path}: {where}: attribute '{attr}' = {raw!r} must be finite")
    return v


def _check_inertial(path, link) -> None:
    name = link.get("name")
    inertial = link.find("inertial")
    if inertial is None:
        return
    where = f"link '{name}' <inertial>"
    mass = _num(path, f"{where} <mass>", inertial.find("mass"), "value")
    if mass <= 0:
        raise UrdfError(
            f"{path}: {where}: mass {mass} kg must be > 0 (leave <inertial> out for a massless frame)"
        )
    el = inertial.find("inertia")
    if el is None:
        raise UrdfError(f"{path}: {where}: <inertia> is missing")
    v = {k: _num(path, f"{where} <inertia>", el, k, 0.0) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
    inertia = np.array(
        [[v["ixx"], v["ixy"], v["ixz"]], [v["ixy"], v["iyy"], v["iyz"]], [v["ixz"], v["iyz"], v["izz"]]]
    )
    lam = np.linalg.eigvalsh(inertia)
    scale = max(abs(lam).max(), 1e-300)
    if lam[0] <= 1e-12 * scale:
        raise UrdfError(
            f"{path}: {where}: the inertia is not positive definite (principal moments {lam.tolist()})"
        )
    a, b, c = lam
    if c > a + b + 1e-9 * scale:
        raise UrdfError(
            f"{path}: {where}: the principal moments {lam.tolist()} violate the triangle inequality "
            f"({c:.6g} > {a:.6g} + {b:.6g}): no rigid body has this inertia"
        )


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


def read_urdf(path: str | Path, payload_frame: str | None = None) -> UrdfRobot:
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
        an inertia not positive definite or violating the triangle inequality, a
        missing effort limit.
    """
    path = Path(path)
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
    links = {el.get("name"): el for el in root.findall("link")}
    if not links:
        raise UrdfError(f"{path}: no <link> element")
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
    for el in links.values():
        _check_inertial(path, el)

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
        payload_frame = tips[0]
    elif payload_frame not in links:
        raise UrdfError(
            f"{path}: payload_frame {payload_frame!r} is not a link of this URDF; links: {sorted(links)}"
        )
    chain, name = [], payload_frame
    while name in parent_of:
        j = parent_of[name]
        chain.append(j)
        name = j.find("parent").get("link")
    chain.reverse()
    on_chain = {j.get("name") for j in chain}
    joints = tuple(_joint_info(path, j) for j in chain if j.get("type") in _MOVABLE)
    if not joints:
        raise UrdfError(f"{path}: no movable joint between the root and the payload frame '{payload_frame}'")
    locked = tuple(
        j.get("name")
        for j in root.findall("joint")
        if j.get("type") in _MOVABLE and j.get("name") not in on_chain
    )
    return UrdfRobot(path, joints, payload_frame, locked)
