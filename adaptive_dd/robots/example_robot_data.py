"""URDFs of `example-robot-data <https://github.com/Gepetto/example-robot-data>`_, named in a scenario.

Real arms' descriptions nobody here tuned for: ``[arm] urdf``, ``[plant] urdf`` and ``[model] from``
take ``"example-robot-data:PATH"``, ``PATH`` a file below the package's ``robots`` folder, e.g.
``"example-robot-data:xarm_description/urdf/xarm7.urdf"``. The package is an optional dependency
(``pip install example-robot-data``; in a checkout of this repository ``pip install -e ".[robots]"``);
its URDFs carry kinematics, limits and inertials (the meshes they name are not read). State the
rest as for any URDF: the payload frame (a link; the chain stops there, so a gripper's joints
beyond it are left out), the rated payload (``payload_capacity``) and the drives' armature, from
the data sheet.

Examples
--------
>>> from adaptive_dd.robots.example_robot_data import PREFIX, is_example_robot_data
>>> PREFIX
'example-robot-data:'
>>> is_example_robot_data("example-robot-data:z1_description/urdf/z1.urdf"), is_example_robot_data("arm.urdf")
(True, False)
"""

from __future__ import annotations

from pathlib import Path, PurePosixPath

from adaptive_dd.errors import ParameterError

__all__ = ["PREFIX", "is_example_robot_data", "robots_folder", "urdf_path"]

PREFIX = "example-robot-data:"
"""What starts a URDF path inside the example-robot-data package."""

_INSTALL = 'pip install example-robot-data (in a checkout of adaptive_dd: pip install -e ".[robots]")'


def is_example_robot_data(text) -> bool:
    """Whether a scenario's URDF value names a file of example-robot-data (starts with :data:`PREFIX`)."""
    return isinstance(text, str) and text.startswith(PREFIX)


def robots_folder() -> Path:
    """The installed package's ``robots`` folder (the wheel's
    ``cmeel.prefix/share/example-robot-data/robots``, or where an older release's
    ``example_robot_data.getModelPath`` puts it).

    Raises
    ------
    ParameterError
        The package is not installed, or holds no ``robots`` folder (the message says how to install it).
    """
    from importlib.metadata import PackageNotFoundError, distribution

    try:
        dist = distribution("example-robot-data")
    except PackageNotFoundError:
        dist = None
    if dist is not None:
        path = Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots")))
        if path.is_dir():
            return path
    try:  # releases before 5 shipped a module that knows the folder
        import example_robot_data as erd

        path = Path(erd.getModelPath("ur_description/urdf/ur5_robot.urdf"))
        if path.is_dir():
            return path
    except (ImportError, OSError, ValueError, AttributeError):
        pass
    found = "is not installed" if dist is None else f"{dist.version} holds no robots folder"
    raise ParameterError(f"example-robot-data {found}: {_INSTALL}")


def urdf_path(text: str) -> Path:
    """The file ``"example-robot-data:PATH"`` names (``PATH``, with ``/`` between its parts, below
    :func:`robots_folder`; never outside it).

    Raises
    ------
    ParameterError
        Not such a name, the package missing, or no such file: the message lists the URDFs in the
        description folder named (``PATH``'s first part), or the folders when that one is not there.
    """
    if not is_example_robot_data(text):
        raise ParameterError(f"{text!r} does not start with {PREFIX!r}")
    rel = PurePosixPath(text[len(PREFIX) :].replace("\\", "/"))
    root = robots_folder()
    inside = bool(rel.parts) and not rel.is_absolute() and ".." not in rel.parts and ":" not in rel.parts[0]
    path = root.joinpath(*rel.parts)
    if inside and path.is_file() and path.resolve().is_relative_to(root.resolve()):
        return path
    top = rel.parts[0] if inside else ""
    if top and (root / top).is_dir():
        names = sorted(p.relative_to(root).as_posix() for p in (root / top).rglob("*.urdf"))
        what = f"the URDFs of {top}: {', '.join(names)}"
    else:
        folders = sorted(p.name for p in root.iterdir() if p.is_dir() and any(p.rglob("*.urdf")))
        what = f"its description folders: {', '.join(folders)}"
    raise ParameterError(f"{text!r}: no such URDF in example-robot-data ({root}); {what}")
