"""URDFs of `example-robot-data <https://github.com/Gepetto/example-robot-data>`_, named in a scenario.

Real arms' descriptions nobody here tuned for: ``[arm] urdf`` (and ``[plant] urdf``) take
``"example-robot-data:PATH"``, ``PATH`` a file below the package's ``robots`` folder, e.g.
``"example-robot-data:xarm_description/urdf/xarm7.urdf"``. The package is an optional dependency
(``pip install "adaptive-dd[robots]"``, or ``pip install example-robot-data``); its URDFs carry
kinematics, limits and inertials (the meshes they name are not read). State the rest as for any
URDF: the payload frame (a link; the chain stops there, so a gripper's joints beyond it are left
out), the rated payload (``payload_capacity``) and the drives' armature, from the data sheet.

Examples
--------
>>> from adaptive_dd.robots.example_robot_data import PREFIX, is_example_robot_data
>>> PREFIX
'example-robot-data:'
>>> is_example_robot_data("example-robot-data:z1_description/urdf/z1.urdf"), is_example_robot_data("arm.urdf")
(True, False)
"""

from __future__ import annotations

from pathlib import Path

from adaptive_dd.errors import ParameterError

__all__ = ["PREFIX", "is_example_robot_data", "robots_folder", "urdf_path"]

PREFIX = "example-robot-data:"
"""What starts a URDF path inside the example-robot-data package."""

_INSTALL = 'pip install "adaptive-dd[robots]" (or pip install example-robot-data)'


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
    """The file ``"example-robot-data:PATH"`` names (``PATH`` below :func:`robots_folder`).

    Raises
    ------
    ParameterError
        Not such a name, the package missing, or no such file: the message lists the package's URDFs
        in the folder named (or every one, when the folder is not there either).
    """
    if not is_example_robot_data(text):
        raise ParameterError(f"{text!r} does not start with {PREFIX!r}")
    rel = text[len(PREFIX) :].strip("/")
    root = robots_folder()
    path = root / rel
    if rel and ".." not in Path(rel).parts and path.is_file():
        return path
    top = Path(rel).parts[0] if rel else ""
    near = top and (root / top).is_dir()
    pool = sorted(root.glob(f"{top}/**/*.urdf") if near else root.glob("*/urdf/*.urdf"))
    names = ", ".join(str(p.relative_to(root)) for p in pool)
    raise ParameterError(f"{text!r}: no such URDF in example-robot-data ({root}); its URDFs: {names}")
