"""The URDF of a two-link arm of the paper's geometry from its physical parameters (eq. 10):
:func:`two_link_urdf`, kept in the user's cache folder by :func:`cached_urdf`
(:meth:`ClosedFormTwoLink.to_arm <adaptive_dd.plant.two_link.ClosedFormTwoLink.to_arm>`)."""

from __future__ import annotations

import hashlib
import math
import os
from pathlib import Path

__all__ = ["cached_urdf", "two_link_urdf"]


def two_link_urdf(p, torque_limit=(70.0, 15.0)) -> str:
    """The URDF text of a two-link arm of the paper's geometry with physical parameters ``p`` (eq. 10).

    Each link's ``izz`` is its ``I_i`` about the centre of mass, ``ixx = iyy = izz`` (unseen by
    planar motion; a rigid body's); ``<dynamics damping friction>`` are ``b_i``, ``d_i``.
    """

    def f(x) -> str:
        return repr(float(x))

    def joint(i, parent, xyz, b, d, effort) -> str:
        return (
            f'  <joint name="joint{i}" type="revolute">\n    <parent link="{parent}"/>\n'
            f'    <child link="link{i}"/>\n    <origin xyz="{xyz} 0 0" rpy="0 0 0"/>\n'
            '    <axis xyz="0 0 1.0"/>\n'
            f'    <limit lower="{f(-math.pi)}" upper="{f(math.pi)}" effort="{f(effort)}" '
            f'velocity="{f(2 * math.pi)}"/>\n'
            f'    <dynamics damping="{f(b)}" friction="{f(d)}"/>\n  </joint>\n'
        )

    def link(i, m, a, inertia) -> str:
        ii = f(inertia)
        return (
            f'  <link name="link{i}">\n    <inertial>\n      <origin xyz="{f(a)} 0 0" rpy="0 0 0"/>\n'
            f'      <mass value="{f(m)}"/>\n'
            f'      <inertia ixx="{ii}" ixy="0" ixz="0" iyy="{ii}" iyz="0" izz="{ii}"/>\n'
            "    </inertial>\n  </link>\n"
        )

    return (
        '<?xml version="1.0"?>\n<!-- A two-link arm of the paper\'s geometry '
        "(adaptive_dd.plant.two_link.two_link_urdf) -->\n"
        '<robot name="two_link">\n  <link name="base_link"/>\n'
        + joint(1, "base_link", "0", p.b1, p.d1, torque_limit[0])
        + link(1, p.m1, p.a1, p.I1)
        + joint(2, "link1", f(p.l1), p.b2, p.d2, torque_limit[1])
        + link(2, p.m2, p.a2, p.I2)
        + '  <joint name="tip_joint" type="fixed">\n    <parent link="link2"/>\n    <child link="tip"/>\n'
        f'    <origin xyz="{f(p.l2)} 0 0" rpy="0 0 0"/>\n  </joint>\n  <link name="tip"/>\n</robot>\n'
    )


def cached_urdf(text: str, stem: str = "two_link") -> Path:
    """``text`` as a file in ``$XDG_CACHE_HOME/adaptive_dd/urdf`` (default ``~/.cache``; the
    temporary folder when that cannot be written), named ``STEM-HASH.urdf`` by its hash: the same
    arm, the same file (an :class:`~adaptive_dd.plant.arm.Arm` reads it again in a worker
    process). Generated arms (the two-link arm's, a random arm's) are written here."""
    import tempfile

    from adaptive_dd.outputs import atomic_write

    name = f"{stem}-{hashlib.sha256(text.encode()).hexdigest()[:16]}.urdf"
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "adaptive_dd" / "urdf"
    # a cache folder that cannot be written (a read-only home): the temporary folder instead, so
    # that loading a scenario never fails on it
    for root in (cache, Path(tempfile.gettempdir()) / f"adaptive_dd-urdf-{os.getuid()}"):
        path = root / name
        if path.is_file():
            return path
        try:
            root.mkdir(parents=True, exist_ok=True)
            with atomic_write(path) as fh:
                fh.write(text)
            return path
        except OSError:
            continue
    raise OSError(f"cannot write the URDF {name} to {cache} nor to the temporary folder")
