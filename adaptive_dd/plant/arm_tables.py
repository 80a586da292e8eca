"""The arm of a scenario's ``[arm]`` and ``[plant]`` tables: the one place that builds an arm
from a scenario.

:func:`arm_from_tables` reads the tables into an :class:`~adaptive_dd.plant.arm.Arm`: the paper's
two-link arm from its physical or base parameters (through their record,
:class:`~adaptive_dd.plant.two_link.ClosedFormTwoLink`), or any arm from a URDF
(:func:`urdf_arm_from_table`). An arm of the paper's geometry has the closed forms as its fast
path (:func:`~adaptive_dd.plant.two_link.closed_form_view`). Every error names the file, the key, the
value and the bound.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.errors import ParameterError, ScenarioError, UrdfError
from adaptive_dd.errors import is_finite_number as _is_num
from adaptive_dd.plant.arm_fields import MAX_CAPACITY
from adaptive_dd.plant.parameters import PhysicalParameters
from adaptive_dd.plant.two_link import FRICTION_LAWS, ClosedFormTwoLink, closed_form_view

if TYPE_CHECKING:
    from adaptive_dd.plant.arm import Arm  # imports Pinocchio: on first use only

__all__ = ["ARM_BOUNDS", "URDF_ARM_KEYS", "arm_from_tables", "scenario_file", "urdf_arm_from_table"]

Array = NDArray[np.float64]

# ------------------------------------------------------------ the paper's arm
_PHYSICAL_KEYS = ("l1", "l2", "m1", "m2", "a1", "a2", "I1", "I2", "b", "d")
_SIGMA_KEYS = ("sigma", "l1", "l2")
_ARM_OPTIONAL = ("payload_radius", "torque_limit")
_PLANT_KEYS = (
    "friction",
    "friction_velocity",
    "stribeck_ratio",
    "stribeck_velocity",
    "lugre_stiffness",
    "lugre_damping",
)

ARM_BOUNDS = {
    "arm.l1": 2.0,  # m: a direct-drive arm's link; beyond this no motor of the kind moves it
    "arm.l2": 2.0,
    "arm.a1": 3.0,  # m (PhysicalParameters further requires a_i <= 1.5 l_i)
    "arm.a2": 3.0,
    "arm.m1": 500.0,  # kg
    "arm.m2": 500.0,
    "arm.I1": 100.0,  # kg m^2
    "arm.I2": 100.0,
    "arm.sigma[0]": 1000.0,  # J1 [kg m^2]
    "arm.sigma[1]": 1000.0,  # J2
    "arm.sigma[2]": 1000.0,  # r
    "arm.sigma[3]": 1000.0,  # b1 [N m s/rad]
    "arm.sigma[4]": 1000.0,  # b2
    "arm.sigma[5]": 1000.0,  # d1 [N m]
    "arm.sigma[6]": 1000.0,  # d2
    "arm.b[0]": 1000.0,
    "arm.b[1]": 1000.0,
    "arm.d[0]": 1000.0,
    "arm.d[1]": 1000.0,
    "arm.payload_radius": 0.5,  # m, as the scenario's payload.radius
    "arm.torque_limit[0]": 1e4,  # N m
    "arm.torque_limit[1]": 1e4,
    "plant.friction_velocity": 10.0,  # rad/s
    "plant.stribeck_velocity": 10.0,
    "plant.stribeck_ratio": 100.0,
}
"""Upper bounds of the ``[arm]`` and ``[plant]`` numbers: physically plausible for a two-link
direct-drive arm, and far enough below overflow that every derived quantity (``m l^2``, the
mass matrix, its determinant) stays finite."""


def _table_number(src: str, key: str, v, *, lower: float | None = None, strict: bool = True) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise ScenarioError(f"{src}: key '{key}' must be a number, got {v!r}")
    if not math.isfinite(v):
        raise ScenarioError(f"{src}: key '{key}' must be finite, got {v!r}")
    if lower is not None and (v <= lower if strict else v < lower):
        raise ScenarioError(f"{src}: key '{key}' must be {'>' if strict else '>='} {lower:g}, got {v!r}")
    hi = ARM_BOUNDS.get(key)
    if hi is not None and v > hi:
        raise ScenarioError(f"{src}: key '{key}' must be <= {hi:g} (ARM_BOUNDS), got {v!r}")
    return float(v)


def _table_list(src: str, key: str, v, n: int, *, lower: float, strict: bool) -> tuple[float, ...]:
    if not isinstance(v, list) or len(v) != n:
        raise ScenarioError(f"{src}: key '{key}' must be a list of {n} numbers, got {v!r}")
    return tuple(_table_number(src, f"{key}[{i}]", x, lower=lower, strict=strict) for i, x in enumerate(v))


def _check_keys(src: str, table: str, data: dict, allowed: tuple[str, ...]) -> None:
    if not isinstance(data, dict):
        raise ScenarioError(f"{src}: [{table}] must be a table, got {data!r}")
    for key in data:
        if key not in allowed:
            from adaptive_dd.benchmark.key_hints import did_you_mean

            hint = did_you_mean(key, allowed)
            raise ScenarioError(f"{src}: unknown key '{table}.{key}'{hint}; allowed: {sorted(allowed)}")


def _arm_kwargs(src: str, arm: dict) -> dict:
    """Geometry, parameters and actuator of an ``[arm]`` table as ClosedFormTwoLink keyword arguments."""
    _check_keys(src, "arm", arm, tuple(dict.fromkeys(_PHYSICAL_KEYS + _SIGMA_KEYS + _ARM_OPTIONAL)))
    physical_only = [k for k in _PHYSICAL_KEYS if k in arm and k not in _SIGMA_KEYS]
    if "sigma" in arm and physical_only:
        raise ScenarioError(
            f"{src}: [arm] gives both 'sigma' and physical keys {physical_only}: use one form "
            f"(physical {list(_PHYSICAL_KEYS)} or 'sigma' with l1, l2)"
        )
    required = _SIGMA_KEYS if "sigma" in arm else _PHYSICAL_KEYS
    for key in required:
        if key not in arm:
            raise ScenarioError(f"{src}: key 'arm.{key}' is missing (required: {list(required)})")
    kw: dict = {}
    sice = ClosedFormTwoLink.sice()
    kw["payload_radius"] = _table_number(
        src, "arm.payload_radius", arm.get("payload_radius", sice.payload_radius), lower=0.0, strict=False
    )
    if "torque_limit" in arm:
        lim = _table_list(src, "arm.torque_limit", arm["torque_limit"], 2, lower=0.0, strict=True)
        kw["actuator"] = replace(sice.actuator, torque_limit=lim)
    l1 = _table_number(src, "arm.l1", arm["l1"], lower=0.0)
    l2 = _table_number(src, "arm.l2", arm["l2"], lower=0.0)
    if "sigma" in arm:
        kw["sigma"] = np.array(_table_list(src, "arm.sigma", arm["sigma"], 7, lower=0.0, strict=False))
        kw["l1"], kw["l2"] = l1, l2
        return kw
    num = {k: _table_number(src, f"arm.{k}", arm[k], lower=0.0) for k in ("m1", "m2", "I1", "I2")}
    num.update({k: _table_number(src, f"arm.{k}", arm[k], lower=0.0, strict=False) for k in ("a1", "a2")})
    b = _table_list(src, "arm.b", arm["b"], 2, lower=0.0, strict=False)
    d = _table_list(src, "arm.d", arm["d"], 2, lower=0.0, strict=False)
    try:
        phys = PhysicalParameters(b1=b[0], b2=b[1], d1=d[0], d2=d[1], l1=l1, l2=l2, **num)
    except (ParameterError, ArithmeticError) as exc:
        raise ScenarioError(f"{src}: [arm]: {exc}") from None
    kw.update(sigma=phys.to_sigma(), l1=l1, l2=l2, physical=phys)
    return kw


def _plant_kwargs(src: str, plant: dict) -> dict:
    _check_keys(src, "plant", plant, _PLANT_KEYS)
    kw: dict = {}
    if "friction" in plant:
        f = plant["friction"]
        if f not in FRICTION_LAWS:
            raise ScenarioError(
                f"{src}: key 'plant.friction' must be one of {list(FRICTION_LAWS)}, got {f!r}"
            )
        kw["friction"] = f
    for key in ("friction_velocity", "stribeck_velocity"):
        if key in plant:
            kw[key] = _table_number(src, f"plant.{key}", plant[key], lower=0.0)
    if "stribeck_ratio" in plant:
        kw["stribeck_ratio"] = _table_number(
            src, "plant.stribeck_ratio", plant["stribeck_ratio"], lower=1.0, strict=False
        )
    for key, strict in (("lugre_stiffness", True), ("lugre_damping", False)):
        if key in plant:  # one value for every joint, or one per joint (the arm checks how many)
            v = plant[key]
            if isinstance(v, list):
                kw[key] = _table_list(src, f"plant.{key}", v, len(v), lower=0.0, strict=strict)
            else:
                kw[key] = _table_number(src, f"plant.{key}", v, lower=0.0, strict=strict)
    return kw


def arm_from_tables(arm_table: dict | None, plant_table: dict | None, src: str = "<memory>") -> Arm:
    """The :class:`~adaptive_dd.plant.arm.Arm` of a scenario's ``[arm]`` and ``[plant]`` tables.

    An ``[arm]`` table with ``urdf`` or ``robot`` describes any serial arm
    (:func:`urdf_arm_from_table`); on an arm of the paper's geometry the closed forms are its
    fast path (:func:`closed_form_view`). Otherwise the paper's two-link arm by its numbers (an
    :class:`~adaptive_dd.plant.arm.Arm` made by :meth:`ClosedFormTwoLink.to_arm`, whose
    :func:`closed_form_view` is exactly those numbers' record):

    ``[arm]`` gives either the physical parameters (eq. 10)
    ``l1, l2, m1, m2, a1, a2, I1, I2, b = [b1, b2], d = [d1, d2]`` or the base
    parameters ``sigma = [J1, J2, r, b1, b2, d1, d2]`` with ``l1, l2``; both forms
    accept ``payload_radius`` [m] and ``torque_limit = [tau1, tau2]`` [N m]. Mixing
    the forms is an error. ``[plant]`` gives ``friction`` ("stick-slip", "tanh",
    "stribeck", "lugre"), ``friction_velocity``, ``stribeck_ratio``, ``stribeck_velocity``,
    ``lugre_stiffness`` [N m/rad] and ``lugre_damping`` [N m s/rad] (one number for every joint,
    or a list of one per joint).
    A missing table means the SICE arm's values (:meth:`ClosedFormTwoLink.sice`, stick-slip).

    Raises
    ------
    ScenarioError
        Naming ``src``, the key and the reason: unknown key, missing key, wrong
        type, non-finite value, value out of range, inconsistent arm.
    """
    plant_kw = _plant_kwargs(src, {} if plant_table is None else plant_table)
    if isinstance(arm_table, dict) and ("urdf" in arm_table or "robot" in arm_table):
        return _urdf_arm(src, arm_table, plant_kw)
    kw = ClosedFormTwoLink.sice().__dict__.copy() if arm_table is None else _arm_kwargs(src, arm_table)
    kw.update(_per_joint(src, plant_kw, 2))
    try:
        return ClosedFormTwoLink(**kw).to_arm()  # an Arm whose closed forms are exactly these
    except UrdfError as exc:  # the equivalent arm's URDF (written to the cache) refused: not the user's file
        reason = str(exc).split(": ", 1)[-1]
        raise ScenarioError(
            f"{src}: [arm]: the two-link arm that sigma, l1 and l2 describe: {reason}; check them together"
        ) from None
    except (ParameterError, ArithmeticError) as exc:
        raise ScenarioError(f"{src}: [arm]/[plant]: {type(exc).__name__}: {exc}") from None


def _urdf_arm(src: str, table: dict, plant_kw: dict):
    """The :class:`~adaptive_dd.plant.arm.Arm` of an ``[arm]`` table naming a URDF
    (:func:`urdf_arm_from_table`); ``general = true`` keeps the general kernels where the closed forms
    would apply (:func:`closed_form_view`). LuGre's bristles are checked against the arm's joints
    once the arm is read."""
    kw = dict(plant_kw)
    lugre = {k: kw.pop(k) for k in ("lugre_stiffness", "lugre_damping") if k in kw}
    general = table.get("general", False)
    if not isinstance(general, bool):
        raise ScenarioError(f"{src}: key 'arm.general' must be true or false, got {general!r}")
    arm = replace(urdf_arm_from_table(src, table, kw), general=general)
    try:
        closed_form_view(arm)
    except (ParameterError, ArithmeticError) as exc:  # the paper's geometry, parameters it cannot hold
        raise ScenarioError(
            f"{src}: [arm] urdf {arm.urdf}: as the paper's two-link arm: {exc} (`general = true` in [arm] "
            "runs it on the N-joint path)"
        ) from None
    return replace(arm, **_per_joint(src, lugre, arm.n_joints)) if lugre else arm


def _per_joint(src: str, kw: dict, n: int) -> dict:
    """``kw`` with LuGre's bristle stiffness and damping as ``n`` values each: one number given is
    every joint's; a list must have one per joint."""
    out = dict(kw)
    for key in ("lugre_stiffness", "lugre_damping"):
        v = out.get(key)
        if isinstance(v, tuple) and len(v) != n:
            raise ScenarioError(
                f"{src}: key 'plant.{key}' must be one number or a list of {n} (one per joint), got {list(v)}"
            )
        if v is not None and not isinstance(v, tuple):
            out[key] = (v,) * n
    return out


# ------------------------------------------------------------ any arm from a URDF
URDF_ARM_KEYS = (
    "urdf",
    "robot",
    "payload_frame",
    "gravity",
    "viscous",
    "coulomb",
    "armature",
    "torque_limit",
    "encoder_counts",
    "dac_bits",
    "payload_radius",
    "payload_capacity",
    "payload_offset",
    "general",
    "repair_inertia",
)
"""Keys of an ``[arm]`` table that names a URDF (``urdf = "file"`` or ``robot = "ur5"``)."""


def urdf_arm_from_table(src: str, table: dict, plant_kw: dict):
    """The arm of an ``[arm]`` table with ``urdf`` (a path relative to the scenario file) or ``robot``.

    ``robot`` names a shipped robot (:data:`adaptive_dd.robots.ROBOTS`), with what its data sheet
    states beyond the URDF (:meth:`~adaptive_dd.robots.RobotInfo.stated`). Optional:
    ``payload_frame`` (a link), ``gravity = [x, y, z]`` (default ``[0, 0, -9.81]``),
    per-joint lists ``viscous``, ``coulomb``, ``armature``, ``torque_limit``,
    ``encoder_counts``, and ``dac_bits``, ``payload_radius``, ``repair_inertia`` (repair a
    chain link's inertia that is not a rigid body's, reported: :func:`adaptive_dd.plant.urdf.read_urdf`),
    ``payload_capacity`` (the rated payload [kg]: the size of the estimator's re-opening,
    :mod:`adaptive_dd.identification.online`), ``payload_offset`` (how far [m] a payload's centre
    of mass may lie from the payload frame: the length scale of the estimator's payload prior);
    ``general`` is read by :func:`arm_from_tables` (``general = true``: no closed-form fast path,
    :func:`~adaptive_dd.plant.two_link.closed_form_view`, on an arm of the paper's geometry).
    ``plant_kw``: the
    ``[plant]`` settings of the general model (LuGre's are the two-link arm's: not here).

    Raises
    ------
    ScenarioError
        Naming ``src``, the key and the reason (URDF problems name the URDF file too).
    """
    path, frame = _urdf_source(src, table)
    arm = _load_urdf_arm(src, table, path, frame)
    if "robot" in table:  # a shipped robot's data sheet, beyond its URDF (RobotInfo.stated)
        from adaptive_dd.robots import ROBOTS

        info = ROBOTS.get(table["robot"])
        arm = replace(arm, **info.stated(arm)) if info is not None else arm
    kw = _arm_overrides(src, table, arm, plant_kw)
    try:
        arm = replace(arm, **kw)
        _ = arm.sigma  # base parameters now, so that a singular model is reported here
    except (ParameterError, UrdfError) as exc:
        raise ScenarioError(f"{src}: [arm]/[plant]: {exc}") from None
    _refuse_inertialess_joints(src, arm)
    return arm


def _refuse_inertialess_joints(src: str, arm) -> None:
    """A joint of the arm that moves no inertia (:func:`inertialess_joints`): the mass matrix is
    singular and no controller or plant can run the arm."""
    for j, d in inertialess_joints(arm, arm.pi_links, arm.armature):
        raise ScenarioError(
            f"{src}: [arm] urdf: {arm.urdf}: joint {arm.joint_names[j]!r} moves no inertia about its axis "
            f"(mass matrix diagonal {d:.3g}: the links beyond it have no <inertial>, or point masses "
            "on its axis): the arm cannot be simulated or controlled. Give those links their <inertial>, "
            "or state the drive's rotor inertia in [arm] armature"
        )


def inertialess_joints(arm, pi_links, armature) -> list[tuple[int, float]]:
    """``(joint, largest diagonal)`` of the joints whose mass-matrix diagonal (links ``pi_links``,
    ``armature`` added) is 0 at three postures within the limits (0, 30 % and 70 % of the range,
    an unbounded joint's taken as +-pi): the links beyond them without ``<inertial>`` or point
    masses on their axis, and no armature."""
    from adaptive_dd.plant.chain import mass_matrix_batch

    lim = np.clip(np.asarray(arm.position_limits, dtype=float), -np.pi, np.pi)
    q = np.stack([np.zeros(arm.n_joints)] + [lim[:, 0] + f * (lim[:, 1] - lim[:, 0]) for f in (0.3, 0.7)])
    m = mass_matrix_batch(arm.chain, np.asarray(pi_links, dtype=float), q)
    diag = np.diagonal(m, axis1=-2, axis2=-1).max(axis=0) + np.asarray(armature, dtype=float)
    top = max(1.0, float(np.nanmax(diag)))
    return [(int(j), float(diag[j])) for j in np.flatnonzero(~(diag > 1e-12 * top))]


def _urdf_source(src: str, table: dict) -> tuple[Path, str | None]:
    """The URDF file (``urdf`` relative to the scenario file, or a shipped ``robot``'s) and the
    payload frame named in the table (a shipped robot's own when not named); checks the keys."""
    unknown = [k for k in table if k not in URDF_ARM_KEYS]
    if unknown:
        from adaptive_dd.benchmark.key_hints import did_you_mean

        hint = did_you_mean(unknown[0], URDF_ARM_KEYS)
        raise ScenarioError(
            f"{src}: unknown key 'arm.{unknown[0]}'{hint}; allowed with a URDF: {sorted(URDF_ARM_KEYS)}"
        )
    if ("urdf" in table) == ("robot" in table):
        raise ScenarioError(
            f"{src}: [arm] needs exactly one of 'urdf' (a file) and 'robot' (a shipped robot)"
        )
    frame = table.get("payload_frame")
    if frame is not None and not isinstance(frame, str):
        raise ScenarioError(f"{src}: key 'arm.payload_frame' must be a link name, got {frame!r}")
    if "robot" in table:
        from adaptive_dd.robots import ROBOTS, robot_urdf
        from adaptive_dd.robots.random_arm import parse_random_robot, random_arm

        name = table["robot"]
        try:
            seed = parse_random_robot(name)
        except ParameterError as exc:
            raise ScenarioError(f"{src}: key 'arm.robot': {exc}") from None
        if seed is not None:  # a drawn arm (adaptive_dd.robots.random_arm)
            drawn = random_arm(seed)
            return drawn.path(), frame or drawn.payload_frame
        if not isinstance(name, str) or name not in ROBOTS:
            raise ScenarioError(
                f"{src}: key 'arm.robot' = {name!r} is not a shipped robot; known: {sorted(ROBOTS)}, "
                "or 'random:SEED' (an arm drawn from SEED)"
            )
        return robot_urdf(name), frame or ROBOTS[name].payload_frame
    if not isinstance(table["urdf"], str) or not table["urdf"]:
        raise ScenarioError(f"{src}: key 'arm.urdf' must be a file path, got {table['urdf']!r}")
    return scenario_file(src, "arm.urdf", table["urdf"]), frame


def scenario_file(src: str, key: str, value: str) -> Path:
    """The file a scenario's ``key = value`` names: relative to the scenario file's folder (or the
    working folder), or ``"example-robot-data:PATH"`` (a URDF of that package:
    :mod:`adaptive_dd.robots.example_robot_data`)."""
    from adaptive_dd.robots.example_robot_data import is_example_robot_data, urdf_path

    if is_example_robot_data(value):
        try:
            return urdf_path(value)
        except ParameterError as exc:
            raise ScenarioError(f"{src}: key '{key}': {exc}") from None
    path = Path(value)
    if not path.is_absolute():
        path = (Path(src).parent if Path(src).is_file() else Path.cwd()) / path
    head = value.split(":")[0].split("/")[0].lower().replace("_", "-")
    if head == "example-robot-data" and not path.exists():
        raise ScenarioError(
            f"{src}: key '{key}' = {value!r}: no such file; a URDF of the example-robot-data package is "
            f'named "example-robot-data:PATH" (a hyphenated name and a colon), e.g. '
            f'"example-robot-data:ur_description/urdf/ur5_robot.urdf"'
        )
    return path


def _load_urdf_arm(src: str, table: dict, path: Path, frame: str | None):
    """:meth:`Arm.from_urdf` with the table's ``gravity`` and ``repair_inertia``; a URDF or
    parameter problem becomes a ScenarioError naming ``src``."""
    from adaptive_dd.plant.arm import DEFAULT_GRAVITY, Arm  # imports Pinocchio: on first use

    gravity = table.get("gravity", list(DEFAULT_GRAVITY))
    if not (isinstance(gravity, list) and len(gravity) == 3 and all(_is_num(x) for x in gravity)):
        raise ScenarioError(f"{src}: key 'arm.gravity' must be [x, y, z] in m/s^2, got {gravity!r}")
    try:
        repair = table.get("repair_inertia", False)
        if not isinstance(repair, bool):
            raise ScenarioError(f"{src}: key 'arm.repair_inertia' must be true or false, got {repair!r}")
        return Arm.from_urdf(path, frame, gravity=[float(x) for x in gravity], repair_inertia=repair)
    except UrdfError as exc:
        raise ScenarioError(f"{src}: [arm] urdf: {exc}") from None
    except ParameterError as exc:
        raise ScenarioError(f"{src}: [arm]: {exc}") from None


def _arm_overrides(src: str, table: dict, arm, plant_kw: dict) -> dict:
    """The ``[plant]`` settings plus the table's overrides of the URDF arm (friction, armature,
    actuator, sensor, payload radius and capacity), checked: keyword arguments of ``replace``."""
    n = arm.n_joints
    joints = chain_joints(arm)
    kw: dict = dict(plant_kw)
    for key in ("viscous", "coulomb", "armature"):
        if key in table:
            hi = URDF_TABLE_BOUNDS[key]
            kw[key] = _table_vector(src, key, table[key], n, 0.0, strict=False, hi=hi, joints=joints)
    if "torque_limit" in table:
        hi = URDF_TABLE_BOUNDS["torque_limit"]
        lim = _table_vector(
            src, "torque_limit", table["torque_limit"], n, 0.0, strict=True, hi=hi, joints=joints
        )
        kw["actuator"] = replace(arm.actuator, torque_limit=tuple(lim))
    if "dac_bits" in table:
        bits = table["dac_bits"]
        if isinstance(bits, bool) or not isinstance(bits, int) or not 1 <= bits <= 32:
            raise ScenarioError(f"{src}: key 'arm.dac_bits' must be an integer in [1, 32], got {bits!r}")
        kw["actuator"] = replace(kw.get("actuator", arm.actuator), dac_bits=bits)
    if "encoder_counts" in table:
        counts = _table_vector(
            src, "encoder_counts", table["encoder_counts"], n, 0.0, strict=True, joints=joints
        )
        if np.any(counts != np.round(counts)) or np.any(counts > 2**40):
            raise ScenarioError(
                f"{src}: key 'arm.encoder_counts' must be integers in [1, 2^40], got {counts}"
            )
        kw["sensor"] = replace(arm.sensor, encoder_counts=tuple(int(c) for c in counts))
    if "payload_radius" in table:
        r = table["payload_radius"]
        if not _is_num(r) or not 0 <= r <= 0.5:
            raise ScenarioError(f"{src}: key 'arm.payload_radius' must be in [0, 0.5] m, got {r!r}")
        kw["payload_radius"] = float(r)
    if "payload_capacity" in table:
        cap = table["payload_capacity"]
        if not _is_num(cap) or not 0 < cap <= MAX_CAPACITY:
            raise ScenarioError(
                f"{src}: key 'arm.payload_capacity' must be the rated payload in (0, {MAX_CAPACITY:g}] kg "
                f"(a payload's mass is at most that too), got {cap!r}"
                + (": a capacity in g? give it in kg" if _is_num(cap) and cap >= 1000 else "")
            )
        kw["payload_capacity"] = float(cap)
    if "payload_offset" in table:
        off = table["payload_offset"]
        if not _is_num(off) or not 0 <= off <= 1:
            raise ScenarioError(
                f"{src}: key 'arm.payload_offset' must be how far [m] a payload's centre of mass may lie "
                f"from the payload frame, in [0, 1] m, got {off!r}"
            )
        kw["payload_offset"] = float(off)
    return kw


URDF_TABLE_BOUNDS = {"viscous": 1e4, "coulomb": 1e4, "armature": 1e3, "torque_limit": 1e5}
"""Upper bounds of the per-joint overrides of a URDF arm (N m s, N m, kg m^2, N m): beyond
them no actuator of an arm is meant."""


def chain_joints(arm) -> str:
    """What a per-joint list's wrong length is told: the arm's joints, which its payload frame sets."""
    names, frame = ", ".join(arm.joint_names), arm.payload_frame
    return f"the arm has {arm.n_joints} joints, from the root to the payload frame '{frame}': {names}"


def _table_vector(
    src: str, key: str, v, n: int, lo: float, strict: bool, hi: float = math.inf, joints: str = ""
) -> Array:
    """``v`` as n finite numbers within ``lo`` (``strict``: above it) and ``hi``; ``joints``
    (:func:`chain_joints`) names the arm's joints when the length is wrong."""
    if joints and isinstance(v, list) and len(v) != n:
        raise ScenarioError(f"{src}: key 'arm.{key}' has {len(v)} numbers; {joints}")
    if not isinstance(v, list) or len(v) != n or not all(_is_num(x) for x in v):
        raise ScenarioError(
            f"{src}: key 'arm.{key}' must be a list of {n} finite numbers (one per joint), got {v!r}"
        )
    a = np.array(v, dtype=float)
    if np.any(a <= lo if strict else a < lo):
        raise ScenarioError(f"{src}: key 'arm.{key}' must be {'>' if strict else '>='} {lo:g}, got {v!r}")
    if np.any(a > hi):
        raise ScenarioError(f"{src}: key 'arm.{key}' must be <= {hi:g}, got {v!r}")
    return a
