"""The arm a command works on: a scenario file's ``[arm]``, ``[plant]`` and ``[model]``
(:func:`load_arm`), and what ``validate`` and ``identify`` print of a URDF arm
(:func:`describe_arm`). Shared by :mod:`adaptive_dd.cli` and :mod:`adaptive_dd.cli_log`
(apart from both, so that neither imports the other)."""

from __future__ import annotations

from pathlib import Path

__all__ = ["describe_arm", "load_arm"]


def load_arm(path: str | None, repair_inertia: bool = False):
    """The arm of a scenario file's ``[arm]`` and ``[plant]`` tables (SICE arm if ``path`` is None):
    the model its controllers are given (``[model] from`` when there is one); ``repair_inertia``
    sets ``arm.repair_inertia = true`` (identify's --repair-inertia)."""
    from adaptive_dd.benchmark.scenario import model_and_plant, read_toml
    from adaptive_dd.errors import ScenarioError
    from adaptive_dd.plant.arm_tables import arm_from_tables
    from adaptive_dd.plant.two_link import TwoLinkArm
    from adaptive_dd.plant.uncertainty import PLANT_TRUTH_KEYS

    if path is None:
        return TwoLinkArm.sice()
    if not Path(path).is_file():
        raise ScenarioError(f"{path}: no such scenario file")
    data = read_toml(Path(path))
    table = data.get("arm")
    if repair_inertia and isinstance(table, dict):
        table = {**table, "repair_inertia": True}
    plant = data.get("plant")
    law = {k: v for k, v in plant.items() if k not in PLANT_TRUTH_KEYS} if isinstance(plant, dict) else plant
    arm = arm_from_tables(table, law, str(path))
    return model_and_plant(str(path), arm, plant if isinstance(plant, dict) else None, data.get("model"))[0]


def describe_arm(arm) -> str:
    """What ``validate`` prints of a URDF arm: joints, base parameters, payload subspace."""
    lines = [f"# arm: {arm.urdf} ({arm.n_joints} joints, payload frame '{arm.payload_frame}')"]
    lim = arm.position_limits
    for j, name in enumerate(arm.joint_names):
        lines.append(
            f"#   joint{j + 1} {name}: limits [{lim[j, 0]:.4g}, {lim[j, 1]:.4g}], velocity "
            f"{arm.velocity_limits[j]:.4g}, effort {arm.actuator.torque_limit[j]:.4g}, viscous "
            f"{arm.viscous[j]:.4g}, Coulomb {arm.coulomb[j]:.4g}, armature {arm.armature[j]:.4g}"
        )
    if arm.locked:
        lines.append(f"#   locked at 0 (off the chain): {', '.join(arm.locked)}")
    lines.append(f"# base parameters: {arm.base.count} of {13 * arm.n_joints} standard")
    for k, (name, v) in enumerate(zip(arm.sigma_names, arm.sigma, strict=True)):
        lines.append(f"#   sigma[{k}] = {v:.6g}: {name}")
    if arm.base.unidentifiable:
        lines.append(f"# no torque depends on: {', '.join(arm.base.unidentifiable)}")
    names = ("m", "mx", "my", "mz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
    seen = [n for n, ok in zip(names, arm.payload_identifiable, strict=True) if ok]
    lines.append(
        f"# payload subspace: rank {arm.payload_rank} of 10; determined by the base parameters: "
        f"{', '.join(seen)}"
    )
    return "\n".join(lines)
